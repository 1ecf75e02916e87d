#pragma once
// What the C API's entry points (c_api_*.cpp) share, inside the library only: the handles behind
// haptic_c.h's opaque types, errors (every entry point catches every exception and reports it as a
// code and message, so nothing unwinds into C), callers' sized structs (read and written no
// further than their `size`), and each spec kind's one pair of conversions (CSpec <-> the C++
// spec) that init, add, update, scenes and read-back share.

#include "haptic/haptic_c.h"

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <cstring>
#include <exception>
#include <new>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include "haptic/haptic.hpp"
#include "haptic/motion.hpp"
#include "haptic/recorder.hpp"

struct haptic_client {
  haptic::Client client;
};

struct haptic_object {
  haptic::ObjectHandle handle;
};

struct haptic_field {
  haptic::FieldHandle handle;
};

struct haptic_applied_scene {
  std::vector<std::optional<haptic::ObjectHandle>> objects;
  std::vector<std::optional<haptic::FieldHandle>> fields;
  std::vector<haptic::StabilityReport> stability;
};

struct haptic_registered_scene {
  haptic::RegisteredScene scene;
};

struct haptic_recorder {
  haptic::Recorder recorder;
};


namespace haptic::c_api {


using haptic::InvalidArgumentError;

// ---- errors ----

/// Copies `text` into a fixed buffer, truncated to fit and NUL-terminated (only what it needs:
/// a success's empty message writes one byte).
inline void copy_text(char* out, std::size_t capacity, const std::string& text) {
  const std::size_t n = std::min(capacity - 1, text.size());
  std::memcpy(out, text.data(), n);
  out[n] = '\0';
}

inline void set_error(haptic_error* err, int code, const std::string& message) {
  if (err == nullptr) return;
  err->code = code;
  copy_text(err->message, sizeof(err->message), message);
}

inline int code_of(haptic::ErrorCode code) {
  switch (code) {
    case haptic::ErrorCode::kConnection: return HAPTIC_ERROR_CONNECTION;
    case haptic::ErrorCode::kInvalidArgument: return HAPTIC_ERROR_INVALID_ARGUMENT;
    case haptic::ErrorCode::kNotFound: return HAPTIC_ERROR_NOT_FOUND;
    case haptic::ErrorCode::kPermissionDenied: return HAPTIC_ERROR_PERMISSION_DENIED;
    case haptic::ErrorCode::kResourceExhausted: return HAPTIC_ERROR_RESOURCE_EXHAUSTED;
    case haptic::ErrorCode::kFailedPrecondition: return HAPTIC_ERROR_FAILED_PRECONDITION;
    case haptic::ErrorCode::kVersionMismatch: return HAPTIC_ERROR_VERSION_MISMATCH;
    case haptic::ErrorCode::kInternal: return HAPTIC_ERROR_INTERNAL;
    case haptic::ErrorCode::kUnauthenticated: return HAPTIC_ERROR_UNAUTHENTICATED;
  }
  return HAPTIC_ERROR_INTERNAL;
}

// Runs `body` (which returns a status), mapping whatever it throws onto `err`.
template <typename Body>
int guarded(haptic_error* err, Body&& body) noexcept {
  try {
    set_error(err, HAPTIC_OK, "");
    return body();
  } catch (const haptic::Error& e) {
    set_error(err, code_of(e.code()), e.what());
    return code_of(e.code());
  } catch (const std::bad_alloc&) {
    set_error(err, HAPTIC_ERROR_INTERNAL, "out of memory");
    return HAPTIC_ERROR_INTERNAL;
  } catch (const std::exception& e) {
    set_error(err, HAPTIC_ERROR_INTERNAL, e.what());
    return HAPTIC_ERROR_INTERNAL;
  } catch (...) {
    set_error(err, HAPTIC_ERROR_INTERNAL, "unknown error");
    return HAPTIC_ERROR_INTERNAL;
  }
}

/// Throws InvalidArgumentError "<call>: <field>: is NULL" when `pointer` is.
inline void require(const void* pointer, const char* call, const char* field) {
  if (pointer == nullptr) throw InvalidArgumentError(std::string(call) + ": " + field + ": is NULL");
}

/// How much of a struct that starts with `size` version 1 of this header holds: today all of it.
/// Fields are only appended; when one is, this becomes offsetof(that struct, its first appended
/// field) for it, as the driver ABI's driver_struct_sizes does, so that a program built against
/// version 1 keeps working. The growth test builds the library with a field appended to every
/// such struct (HAPTIC_C_TEST_GROWN: tests/integration/grow_c_header.py) and runs a version 1
/// program against it.
template <typename CStruct>
constexpr std::uint32_t version1_size() {
#ifdef HAPTIC_C_TEST_GROWN
  return static_cast<std::uint32_t>(offsetof(CStruct, grown_by_test));
#else
  return static_cast<std::uint32_t>(sizeof(CStruct));
#endif
}

/// A caller's struct that starts with a size, as this library's struct: its first min(size,
/// sizeof) bytes, the fields it predates zero (an appended field takes 0 as "not given"). NULL, or
/// smaller than version 1's, is refused. Never reads past the caller's `size`.
template <typename CStruct>
CStruct sized(const void* pointer, const char* call, const char* field) {
  require(pointer, call, field);
  std::uint32_t size = 0;
  std::memcpy(&size, pointer, sizeof(size));
  if (size < version1_size<CStruct>()) {
    throw InvalidArgumentError(std::string(call) + ": " + field + ": size " + std::to_string(size) +
                               " is smaller than version 1's " + std::to_string(version1_size<CStruct>()));
  }
  CStruct value{};
  std::memcpy(&value, pointer, std::min<std::size_t>(size, sizeof(CStruct)));
  return value;
}

/// Writes `value`, a struct the library filled, as the caller's struct of `size` bytes: its first
/// min(size, sizeof) bytes, with `size` as the caller's.
template <typename CStruct>
void write_as_callers(void* out, CStruct value, std::uint32_t size) {
  value.size = size;
  std::memcpy(out, &value, std::min<std::size_t>(size, sizeof(CStruct)));
}

/// A caller's struct the library fills: checked as sized() checks it, filled here (`*out`), and
/// written back when this ends, its first min(size, sizeof) bytes with the caller's own `size`:
/// never past what the caller has.
template <typename CStruct>
class SizedOut {
 public:
  SizedOut(void* pointer, const char* call, const char* field)
      : pointer_(pointer), value_(sized<CStruct>(pointer, call, field)), size_(value_.size) {}
  SizedOut(const SizedOut&) = delete;
  SizedOut& operator=(const SizedOut&) = delete;
  ~SizedOut() { write_as_callers(pointer_, value_, size_); }
  CStruct& operator*() { return value_; }

 private:
  void* pointer_;
  CStruct value_;
  std::uint32_t size_;
};

// Each *_init twice (haptic_c.h): _init_sized writes the defaults as far as the caller's `size`
// and keeps that size; the plain function, for callers without the header's macro, writes version
// 1's fields and size. The parentheses keep the header's macro of the same name from expanding.
#define HAPTIC_C_INIT(Struct, defaults)                                          \
  void Struct##_init_sized(Struct* out, uint32_t size) {                         \
    if (out != nullptr) write_as_callers(out, defaults, size);                   \
  }                                                                              \
  void(Struct##_init)(Struct * out) {                                            \
    if (out != nullptr) write_as_callers(out, defaults, version1_size<Struct>()); \
  }

/// A problem with one field of a C struct, found while converting it; the call that read the
/// struct turns it into InvalidArgumentError "<call>: <struct>.<field>: <problem>".
struct FieldProblem {
  std::string field;
  std::string problem;
};

template <typename Convert>
auto converting(const char* call, const char* name, Convert&& convert) {
  try {
    return convert();
  } catch (const FieldProblem& p) {
    throw InvalidArgumentError(std::string(call) + ": " + name + "." + p.field + ": " + p.problem);
  }
}

/// A C enum's value as the C++ enum; out of range is a FieldProblem.
template <typename Enum>
Enum enum_from(std::int32_t value, std::int32_t last, const char* field) {
  if (value < 0 || value > last) {
    throw FieldProblem{field, std::to_string(value) + " is not one of 0.." + std::to_string(last)};
  }
  return static_cast<Enum>(value);
}

inline std::int64_t steady_ns(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(t.time_since_epoch()).count();
}

// ---- value types and specs: each struct's fields listed once, walked in either direction ----

inline haptic_vec3 to_c(const haptic::Vec3& v) { return {v.x, v.y, v.z}; }
inline haptic::Vec3 to_cpp(const haptic_vec3& v) { return {v.x, v.y, v.z}; }
inline haptic_quaternion to_c(const haptic::Quaternion& q) { return {q.w, q.x, q.y, q.z}; }
inline haptic::Quaternion to_cpp(const haptic_quaternion& q) { return {q.w, q.x, q.y, q.z}; }

/// The last value of each C++ enum a C struct carries as an int32_t (values 0..last).
template <typename Enum> constexpr std::int32_t kLastValue = 0;
template <> inline constexpr std::int32_t kLastValue<haptic::ImpedanceLaw> = HAPTIC_LAW_TUSTIN;
template <> inline constexpr std::int32_t kLastValue<haptic::Distance::Kind> = HAPTIC_DISTANCE_SPHERE;
template <> inline constexpr std::int32_t kLastValue<haptic::PotentialFieldSpec::Kind> = HAPTIC_POTENTIAL_KHATIB;

// each_field(c, cpp, visit): calls visit(c.field, cpp.field, "name") for every field of a C struct
// and its C++ twin, in the header's order. One list per struct serves both directions (ToCpp,
// ToC below) and names the field in a refusal.
template <typename V> void each_field(haptic_pose& c, haptic::Pose& s, V&& v) {
  v(c.position, s.position, "position");
  v(c.orientation, s.orientation, "orientation");
}
template <typename V> void each_field(haptic_dynamics& c, haptic::Dynamics& s, V&& v) {
  v(c.mass, s.mass, "mass");
  v(c.damping, s.damping, "damping");
}
template <typename V> void each_field(haptic_impedance& c, haptic::Impedance& s, V&& v) {
  v(c.stiffness, s.stiffness, "stiffness");
  v(c.damping, s.damping, "damping");
  v(c.static_friction, s.static_friction, "static_friction");
  v(c.dynamic_friction, s.dynamic_friction, "dynamic_friction");
  v(c.mass, s.mass, "mass");
  v(c.law, s.law, "law");
  v(c.transparency_optimal_damping, s.transparency_optimal_damping, "transparency_optimal_damping");
  v(c.virtual_coupling, s.virtual_coupling, "virtual_coupling");
}
template <typename V> void each_field(haptic_distance& c, haptic::Distance& s, V&& v) {
  v(c.kind, s.kind, "kind");
  v(c.origin, s.origin, "origin");
  v(c.axis, s.axis, "axis");
  v(c.radius, s.radius, "radius");
}
template <typename V> void each_field(haptic_wall_spec& c, haptic::WallSpec& s, V&& v) {
  v(c.point, s.point, "point");
  v(c.normal, s.normal, "normal");
  v(c.impedance, s.impedance, "impedance");
  v(c.shared, s.shared, "shared");
  v(c.across_sites, s.across_sites, "across_sites");
}
template <typename V> void each_field(haptic_sphere_spec& c, haptic::SphereSpec& s, V&& v) {
  v(c.center, s.center, "center");
  v(c.radius, s.radius, "radius");
  v(c.impedance, s.impedance, "impedance");
  v(c.dynamics, s.dynamics, "dynamics");
  v(c.shared, s.shared, "shared");
  v(c.across_sites, s.across_sites, "across_sites");
}
template <typename V> void each_field(haptic_box_spec& c, haptic::BoxSpec& s, V&& v) {
  v(c.pose, s.pose, "pose");
  v(c.half_extents, s.half_extents, "half_extents");
  v(c.impedance, s.impedance, "impedance");
  v(c.dynamics, s.dynamics, "dynamics");
  v(c.shared, s.shared, "shared");
  v(c.across_sites, s.across_sites, "across_sites");
}
template <typename V> void each_field(haptic_capsule_spec& c, haptic::CapsuleSpec& s, V&& v) {
  v(c.pose, s.pose, "pose");
  v(c.radius, s.radius, "radius");
  v(c.half_length, s.half_length, "half_length");
  v(c.impedance, s.impedance, "impedance");
  v(c.dynamics, s.dynamics, "dynamics");
  v(c.shared, s.shared, "shared");
  v(c.across_sites, s.across_sites, "across_sites");
}
template <typename V> void each_field(haptic_tangent_plane_spec& c, haptic::TangentPlaneSpec& s, V&& v) {
  v(c.pose, s.pose, "pose");
  v(c.normal, s.normal, "normal");
  v(c.reference, s.reference, "reference");
  v(c.tangential_stiffness, s.tangential_stiffness, "tangential_stiffness");
  v(c.tangential_damping, s.tangential_damping, "tangential_damping");
  v(c.impedance, s.impedance, "impedance");
  v(c.across_sites, s.across_sites, "across_sites");
}
/// A mesh's fields but its arrays (to_c and to_cpp below carry those).
template <typename V> void each_field(haptic_mesh_spec& c, haptic::MeshSpec& s, V&& v) {
  v(c.pose, s.pose, "pose");
  v(c.impedance, s.impedance, "impedance");
  v(c.shared, s.shared, "shared");
  v(c.across_sites, s.across_sites, "across_sites");
}
template <typename V> void each_field(haptic_spring_field_spec& c, haptic::SpringFieldSpec& s, V&& v) {
  v(c.anchor, s.anchor, "anchor");
  v(c.stiffness, s.stiffness, "stiffness");
  v(c.damping, s.damping, "damping");
  v(c.max_force, s.max_force, "max_force");
  v(c.across_sites, s.across_sites, "across_sites");
}
template <typename V> void each_field(haptic_distance_spring_spec& c, haptic::DistanceSpringSpec& s, V&& v) {
  v(c.anchor, s.anchor, "anchor");
  v(c.stiffness, s.stiffness, "stiffness");
  v(c.damping, s.damping, "damping");
  v(c.max_force, s.max_force, "max_force");
  v(c.across_sites, s.across_sites, "across_sites");
}
template <typename V> void each_field(haptic_potential_field_spec& c, haptic::PotentialFieldSpec& s, V&& v) {
  v(c.distance, s.distance, "distance");
  v(c.kind, s.kind, "kind");
  v(c.order, s.order, "order");
  v(c.gain, s.gain, "gain");
  v(c.offset, s.offset, "offset");
  v(c.influence_distance, s.influence_distance, "influence_distance");
  v(c.min_distance, s.min_distance, "min_distance");
  v(c.central_differences, s.central_differences, "central_differences");
  v(c.across_sites, s.across_sites, "across_sites");
}
template <typename V> void each_field(haptic_linear_field_spec& c, haptic::LinearFieldSpec& s, V&& v) {
  v(c.origin, s.origin, "origin");
  v(c.force, s.force, "force");
  v(c.jacobian, s.jacobian, "jacobian");
  v(c.radius, s.radius, "radius");
  v(c.fade_width, s.fade_width, "fade_width");
  v(c.across_sites, s.across_sites, "across_sites");
}
template <typename V> void each_field(haptic_viscous_field_spec& c, haptic::ViscousFieldSpec& s, V&& v) {
  v(c.damping, s.damping, "damping");
  v(c.center, s.center, "center");
  v(c.radius, s.radius, "radius");
  v(c.fade_width, s.fade_width, "fade_width");
  v(c.across_sites, s.across_sites, "across_sites");
}
template <typename V> void each_field(haptic_detent_field_spec& c, haptic::DetentFieldSpec& s, V&& v) {
  v(c.distance, s.distance, "distance");
  v(c.depth, s.depth, "depth");
  v(c.radius, s.radius, "radius");
  v(c.rim_height, s.rim_height, "rim_height");
  v(c.rim_width, s.rim_width, "rim_width");
  v(c.across_sites, s.across_sites, "across_sites");
}
template <typename V> void each_field(haptic_orientation_spring_spec& c, haptic::OrientationSpringSpec& s, V&& v) {
  v(c.target, s.target, "target");
  v(c.stiffness, s.stiffness, "stiffness");
  v(c.damping, s.damping, "damping");
  v(c.max_torque, s.max_torque, "max_torque");
  v(c.law, s.law, "law");
  v(c.across_sites, s.across_sites, "across_sites");
}
template <typename V> void each_field(haptic_orientation_detent_spec& c, haptic::OrientationDetentSpec& s, V&& v) {
  v(c.target, s.target, "target");
  v(c.depth, s.depth, "depth");
  v(c.radius, s.radius, "radius");
  v(c.rim_height, s.rim_height, "rim_height");
  v(c.rim_width, s.rim_width, "rim_width");
  v(c.damping, s.damping, "damping");
  v(c.across_sites, s.across_sites, "across_sites");
}

template <typename C, typename Cpp>
concept HasFields = requires(C& c, Cpp& s) { each_field(c, s, [](auto&, auto&, const char*) {}); };

/// Copies a C struct's fields into the C++ one; a nested struct's problem is named by its path.
struct ToCpp {
  void operator()(const double& c, double& s, const char*) const { s = c; }
  void operator()(const std::uint32_t& c, std::uint32_t& s, const char*) const { s = c; }
  void operator()(const std::int32_t& c, bool& s, const char*) const { s = c != 0; }
  template <typename Enum>
    requires std::is_enum_v<Enum>
  void operator()(const std::int32_t& c, Enum& s, const char* name) const {
    s = enum_from<Enum>(c, kLastValue<Enum>, name);
  }
  void operator()(const haptic_vec3& c, haptic::Vec3& s, const char*) const { s = to_cpp(c); }
  void operator()(const haptic_quaternion& c, haptic::Quaternion& s, const char*) const { s = to_cpp(c); }
  void operator()(const haptic_vec3 (&c)[3], haptic::Vec3 (&s)[3], const char*) const {
    for (int i = 0; i < 3; ++i) s[i] = to_cpp(c[i]);
  }
  template <typename C, typename Cpp>
    requires HasFields<C, Cpp>
  void operator()(const C& c, Cpp& s, const char* name) const {
    C copy = c;
    try {
      each_field(copy, s, *this);
    } catch (FieldProblem& problem) {
      problem.field = std::string(name) + "." + problem.field;
      throw;
    }
  }
};

/// Copies a C++ struct's fields into the C one.
struct ToC {
  void operator()(double& c, const double& s, const char*) const { c = s; }
  void operator()(std::uint32_t& c, const std::uint32_t& s, const char*) const { c = s; }
  void operator()(std::int32_t& c, const bool& s, const char*) const { c = s ? 1 : 0; }
  template <typename Enum>
    requires std::is_enum_v<Enum>
  void operator()(std::int32_t& c, const Enum& s, const char*) const { c = static_cast<std::int32_t>(s); }
  void operator()(haptic_vec3& c, const haptic::Vec3& s, const char*) const { c = to_c(s); }
  void operator()(haptic_quaternion& c, const haptic::Quaternion& s, const char*) const { c = to_c(s); }
  void operator()(haptic_vec3 (&c)[3], const haptic::Vec3 (&s)[3], const char*) const {
    for (int i = 0; i < 3; ++i) c[i] = to_c(s[i]);
  }
  template <typename C, typename Cpp>
    requires HasFields<C, Cpp>
  void operator()(C& c, const Cpp& s, const char*) const {
    Cpp copy = s;
    each_field(c, copy, *this);
  }
};

/// The C twin of each C++ struct, by type: the nested ones here, the specs with their traits below.
template <typename Cpp> struct CTwin;
#define HAPTIC_C_TWIN(C, CPP) \
  template <> struct CTwin<haptic::CPP> { using type = C; };
HAPTIC_C_TWIN(haptic_pose, Pose)
HAPTIC_C_TWIN(haptic_dynamics, Dynamics)
HAPTIC_C_TWIN(haptic_impedance, Impedance)
HAPTIC_C_TWIN(haptic_distance, Distance)

/// Each C spec's kind, the C++ spec it converts to (and back: its CTwin), and the name the
/// server's messages give it.
template <typename CSpec> struct SpecTraits;
#define HAPTIC_C_SPEC(CSPEC, CPP, KIND, NAME)      \
  template <> struct SpecTraits<CSPEC> {           \
    using Cpp = haptic::CPP;                       \
    static constexpr std::int32_t kind = KIND;     \
    static constexpr const char* name = NAME;      \
  };                                               \
  HAPTIC_C_TWIN(CSPEC, CPP)
HAPTIC_C_SPEC(haptic_wall_spec, WallSpec, HAPTIC_KIND_WALL, "object.wall")
HAPTIC_C_SPEC(haptic_sphere_spec, SphereSpec, HAPTIC_KIND_SPHERE, "object.sphere")
HAPTIC_C_SPEC(haptic_box_spec, BoxSpec, HAPTIC_KIND_BOX, "object.box")
HAPTIC_C_SPEC(haptic_capsule_spec, CapsuleSpec, HAPTIC_KIND_CAPSULE, "object.capsule")
HAPTIC_C_SPEC(haptic_tangent_plane_spec, TangentPlaneSpec, HAPTIC_KIND_TANGENT_PLANE, "object.tangent_plane")
HAPTIC_C_SPEC(haptic_mesh_spec, MeshSpec, HAPTIC_KIND_MESH, "object.mesh")
HAPTIC_C_SPEC(haptic_spring_field_spec, SpringFieldSpec, HAPTIC_KIND_SPRING_FIELD, "field.spring")
HAPTIC_C_SPEC(haptic_distance_spring_spec, DistanceSpringSpec, HAPTIC_KIND_DISTANCE_SPRING, "field.distance_spring")
HAPTIC_C_SPEC(haptic_potential_field_spec, PotentialFieldSpec, HAPTIC_KIND_POTENTIAL_FIELD, "field.potential")
HAPTIC_C_SPEC(haptic_linear_field_spec, LinearFieldSpec, HAPTIC_KIND_LINEAR_FIELD, "field.linear")
HAPTIC_C_SPEC(haptic_viscous_field_spec, ViscousFieldSpec, HAPTIC_KIND_VISCOUS_FIELD, "field.viscous")
HAPTIC_C_SPEC(haptic_detent_field_spec, DetentFieldSpec, HAPTIC_KIND_DETENT_FIELD, "field.detent")
HAPTIC_C_SPEC(haptic_orientation_spring_spec, OrientationSpringSpec, HAPTIC_KIND_ORIENTATION_SPRING, "field.orientation_spring")
HAPTIC_C_SPEC(haptic_orientation_detent_spec, OrientationDetentSpec, HAPTIC_KIND_ORIENTATION_DETENT, "field.orientation_detent")
#undef HAPTIC_C_SPEC
#undef HAPTIC_C_TWIN

/// A C++ struct as its C twin; a spec's size is set to its sizeof.
template <typename Cpp>
typename CTwin<Cpp>::type to_c(const Cpp& s) {
  using C = typename CTwin<Cpp>::type;
  C c{};
  if constexpr (requires { c.size; }) c.size = sizeof(C);
  Cpp copy = s;
  each_field(c, copy, ToC{});
  return c;
}

/// A C struct as its C++ twin; a field out of range is a FieldProblem naming it.
template <typename C, typename Cpp>
Cpp to_cpp_as(const C& c) {
  Cpp s{};
  C copy = c;
  each_field(copy, s, ToCpp{});
  return s;
}

// A mesh's arrays: the C struct points into the C++ spec's vectors (which must outlive it).
inline haptic_mesh_spec mesh_to_c(const haptic::MeshSpec& s) {
  static_assert(sizeof(haptic_vec3) == sizeof(haptic::Vec3) && std::is_standard_layout_v<haptic::Vec3>);
  haptic_mesh_spec c = to_c(s);
  c.vertices = s.vertices.empty() ? nullptr : reinterpret_cast<const haptic_vec3*>(s.vertices.data());
  c.vertex_count = static_cast<std::uint32_t>(s.vertices.size());
  c.indices = s.indices.empty() ? nullptr : s.indices.data();
  c.index_count = static_cast<std::uint32_t>(s.indices.size());
  return c;
}
inline haptic::MeshSpec mesh_to_cpp(const haptic_mesh_spec& c) {
  haptic::MeshSpec s = to_cpp_as<haptic_mesh_spec, haptic::MeshSpec>(c);
  if (c.vertex_count > 0 && c.vertices == nullptr) throw FieldProblem{"vertices", "is NULL with vertex_count > 0"};
  if (c.index_count > 0 && c.indices == nullptr) throw FieldProblem{"indices", "is NULL with index_count > 0"};
  s.vertices.reserve(c.vertex_count);
  for (std::uint32_t i = 0; i < c.vertex_count; ++i) s.vertices.push_back(to_cpp(c.vertices[i]));
  if (c.index_count > 0) s.indices.assign(c.indices, c.indices + c.index_count);
  return s;
}


/// A C spec from the C++ one (a mesh's arrays pointing into it).
template <typename Cpp>
typename CTwin<Cpp>::type spec_to_c(const Cpp& s) {
  if constexpr (std::is_same_v<Cpp, haptic::MeshSpec>) return mesh_to_c(s);
  else return to_c(s);
}

template <typename CSpec>
CSpec spec_defaults() {
  return spec_to_c(typename SpecTraits<CSpec>::Cpp{});
}

template <typename CSpec>
typename SpecTraits<CSpec>::Cpp read_spec(const void* spec, const char* call) {
  using Cpp = typename SpecTraits<CSpec>::Cpp;
  const CSpec& c = sized<CSpec>(spec, call, SpecTraits<CSpec>::name);
  return converting(call, SpecTraits<CSpec>::name, [&] {
    if constexpr (std::is_same_v<CSpec, haptic_mesh_spec>) return mesh_to_cpp(c);
    else return to_cpp_as<CSpec, Cpp>(c);
  });
}

template <typename CSpec>
int add_object(haptic_client* client, const CSpec* spec, haptic_object** out, haptic_error* err) {
  return guarded(err, [&] {
    require(out, "CreateObject", "out");
    *out = nullptr;
    require(client, "CreateObject", "client");
    const auto cpp = read_spec<CSpec>(spec, "CreateObject");
    haptic::ObjectHandle handle;
    if constexpr (std::is_same_v<CSpec, haptic_wall_spec>) handle = client->client.add_wall(cpp);
    else if constexpr (std::is_same_v<CSpec, haptic_sphere_spec>) handle = client->client.add_sphere(cpp);
    else if constexpr (std::is_same_v<CSpec, haptic_box_spec>) handle = client->client.add_box(cpp);
    else if constexpr (std::is_same_v<CSpec, haptic_capsule_spec>) handle = client->client.add_capsule(cpp);
    else if constexpr (std::is_same_v<CSpec, haptic_tangent_plane_spec>) handle = client->client.add_tangent_plane(cpp);
    else handle = client->client.add_mesh(cpp);
    *out = new haptic_object{std::move(handle)};
    return HAPTIC_OK;
  });
}

template <typename CSpec>
int add_field(haptic_client* client, const CSpec* spec, haptic_field** out, haptic_error* err) {
  return guarded(err, [&] {
    require(out, "CreateField", "out");
    *out = nullptr;
    require(client, "CreateField", "client");
    const auto cpp = read_spec<CSpec>(spec, "CreateField");
    haptic::FieldHandle handle;
    if constexpr (std::is_same_v<CSpec, haptic_spring_field_spec>) handle = client->client.add_spring_field(cpp);
    else handle = client->client.add_field(cpp);
    *out = new haptic_field{std::move(handle)};
    return HAPTIC_OK;
  });
}

template <typename Handle, typename CSpec>
int update_item(Handle* item, const CSpec* spec, const char* call, haptic_error* err) {
  return guarded(err, [&] {
    require(item, call, "handle");
    item->handle.update(read_spec<CSpec>(spec, call));
    return HAPTIC_OK;
  });
}

/// A scene item's spec, as the C++ scene's object or field variant.
inline void add_scene_item(const haptic_scene_item& item, haptic::SceneSpec& scene, const char* call) {
  const void* spec = item.spec;
  switch (item.kind) {
    case HAPTIC_KIND_WALL: scene.objects.emplace_back(read_spec<haptic_wall_spec>(spec, call)); return;
    case HAPTIC_KIND_SPHERE: scene.objects.emplace_back(read_spec<haptic_sphere_spec>(spec, call)); return;
    case HAPTIC_KIND_BOX: scene.objects.emplace_back(read_spec<haptic_box_spec>(spec, call)); return;
    case HAPTIC_KIND_CAPSULE: scene.objects.emplace_back(read_spec<haptic_capsule_spec>(spec, call)); return;
    case HAPTIC_KIND_TANGENT_PLANE: scene.objects.emplace_back(read_spec<haptic_tangent_plane_spec>(spec, call)); return;
    case HAPTIC_KIND_MESH: scene.objects.emplace_back(read_spec<haptic_mesh_spec>(spec, call)); return;
    case HAPTIC_KIND_SPRING_FIELD: scene.fields.emplace_back(read_spec<haptic_spring_field_spec>(spec, call)); return;
    case HAPTIC_KIND_DISTANCE_SPRING: scene.fields.emplace_back(read_spec<haptic_distance_spring_spec>(spec, call)); return;
    case HAPTIC_KIND_POTENTIAL_FIELD: scene.fields.emplace_back(read_spec<haptic_potential_field_spec>(spec, call)); return;
    case HAPTIC_KIND_LINEAR_FIELD: scene.fields.emplace_back(read_spec<haptic_linear_field_spec>(spec, call)); return;
    case HAPTIC_KIND_VISCOUS_FIELD: scene.fields.emplace_back(read_spec<haptic_viscous_field_spec>(spec, call)); return;
    case HAPTIC_KIND_DETENT_FIELD: scene.fields.emplace_back(read_spec<haptic_detent_field_spec>(spec, call)); return;
    case HAPTIC_KIND_ORIENTATION_SPRING: scene.fields.emplace_back(read_spec<haptic_orientation_spring_spec>(spec, call)); return;
    case HAPTIC_KIND_ORIENTATION_DETENT: scene.fields.emplace_back(read_spec<haptic_orientation_detent_spec>(spec, call)); return;
    default:
      throw InvalidArgumentError(std::string(call) + ": kind: " + std::to_string(item.kind) +
                                 " is not a haptic_kind");
  }
}

inline haptic::SceneSpec scene_of(const haptic_scene_item* items, std::uint32_t count, const char* call) {
  if (count > 0) require(items, call, "items");
  haptic::SceneSpec scene;
  for (std::uint32_t i = 0; i < count; ++i) add_scene_item(items[i], scene, call);
  return scene;
}

/// The kind of a read-back object or field, from its C++ spec's C twin.
template <typename Variant>
std::int32_t kind_of(const Variant& v) {
  return std::visit([](const auto& spec) {
    return SpecTraits<typename CTwin<std::decay_t<decltype(spec)>>::type>::kind;
  }, v);
}

/// Copies a read-back spec into the caller's struct of its kind (size checked).
template <typename Variant>
void copy_spec(const Variant& v, void* out, const char* call) {
  std::visit([&](const auto& spec) {
    using Cpp = std::decay_t<decltype(spec)>;
    using CSpec = typename CTwin<Cpp>::type;
    static_assert(std::is_same_v<typename SpecTraits<CSpec>::Cpp, Cpp>);
    *SizedOut<CSpec>(out, call, SpecTraits<CSpec>::name) = spec_to_c(spec);
  }, v);
}

// ---- state, stability, events ----

inline void copy_state(const haptic::State& s, haptic_state& state) {
  haptic_state* out = &state;
  const std::uint32_t size = out->size;
  *out = haptic_state{};
  out->size = size;
  out->tick = s.tick;
  out->sequence = s.sequence;
  out->server_time = s.server_time;
  out->position = to_c(s.position);
  out->velocity = to_c(s.velocity);
  out->force = to_c(s.force);
  out->proxy = to_c(s.proxy);
  out->contact_count = s.contact_count;
  out->flags = s.flags;
  out->buttons = s.buttons;
  out->has_orientation = s.orientation.has_value();
  out->orientation = to_c(s.orientation.value_or(haptic::Quaternion{}));
  out->torque = to_c(s.torque.value_or(haptic::Vec3{}));
  out->received_at_ns = steady_ns(s.received_at);
  out->arrived_at_ns = s.arrived_at ? steady_ns(*s.arrived_at) : 0;
  out->age_ns = s.age.count();
}

inline haptic::State state_of(const haptic_state& c) {
  haptic::State s;
  s.tick = c.tick;
  s.server_time = c.server_time;
  s.position = to_cpp(c.position);
  s.velocity = to_cpp(c.velocity);
  return s;
}

inline void copy_report(const haptic::StabilityReport& r, haptic_stability_report& out) {
  const std::uint32_t size = out.size;
  out = haptic_stability_report{};
  out.size = size;
  out.available = 1;
  out.colgate_min_damping = r.colgate_min_damping;
  out.device_mass = r.device_mass;
  out.device_damping = r.device_damping;
  out.max_stable_stiffness = r.max_stable_stiffness;
  out.max_pole_magnitude = r.max_pole_magnitude;
  out.chosen_damping = r.chosen_damping;
  out.chosen_stiffness = r.chosen_stiffness;
  out.passive = r.passive;
  out.device_known = r.device_known;
  out.stable = r.stable;
  out.robustly_stable = r.robustly_stable;
  copy_text(out.warning, sizeof(out.warning), r.warning);
}

inline void copy_recording(const haptic::RecordingStatus& r, haptic_recording_status* out) {
  if (out == nullptr) return;
  SizedOut<haptic_recording_status> written(out, "Recording", "status");
  haptic_recording_status& c = *written;
  const std::uint32_t size = c.size;
  c = haptic_recording_status{};
  c.size = size;
  copy_text(c.path, sizeof(c.path), r.path);
  c.start_tick = r.start_tick;
  c.samples = r.samples;
  c.samples_missed = r.samples_missed;
  c.changes = r.changes;
  c.records_not_written = r.records_not_written;
  copy_text(c.write_error, sizeof(c.write_error), r.write_error);
}

/// Copies up to `capacity` of `items` (each by `convert`) and sets *count to how many there are.
template <typename C, typename Cpp, typename Convert>
void copy_list(const std::vector<Cpp>& items, C* out, std::uint32_t capacity, std::uint32_t* count,
               const char* call, Convert convert) {
  require(count, call, "count");
  if (capacity > 0) require(out, call, "out");
  *count = static_cast<std::uint32_t>(items.size());
  const std::size_t n = std::min<std::size_t>(capacity, items.size());
  for (std::size_t i = 0; i < n; ++i) out[i] = convert(items[i]);
}

static_assert(static_cast<int>(haptic::Event::Kind::kReset) == HAPTIC_EVENT_RESET);
static_assert(static_cast<int>(haptic::ConnectionChange::State::kEnded) == HAPTIC_CONNECTION_ENDED);
static_assert(static_cast<int>(haptic::Role::kAdmin) == HAPTIC_ROLE_ADMIN);
static_assert(static_cast<int>(haptic::ImpedanceLaw::kTustin) == HAPTIC_LAW_TUSTIN);
static_assert(static_cast<int>(haptic::Distance::Kind::kSphere) == HAPTIC_DISTANCE_SPHERE);
static_assert(static_cast<int>(haptic::OperatorInput::Profile::Shape::kRecorded) == HAPTIC_PROFILE_RECORDED);

inline haptic::OperatorInput operator_of(const haptic_operator_input& c) {
  using Input = haptic::OperatorInput;
  Input in;
  in.mode = enum_from<Input::Mode>(c.mode, HAPTIC_OPERATOR_PUSH, "mode");
  in.target = to_cpp(c.target);
  in.stiffness = c.stiffness;
  in.damping = c.damping;
  in.mass = c.mass;
  in.grip = enum_from<Input::Grip>(c.grip, HAPTIC_GRIP_TIGHT, "grip");
  in.path.shape = enum_from<Input::Path::Shape>(c.path_shape, HAPTIC_PATH_SINE, "path_shape");
  in.path.end = to_cpp(c.path_end);
  in.path.duration_s = c.path_duration_s;
  in.path.amplitude = to_cpp(c.path_amplitude);
  in.path.frequency_hz = c.path_frequency_hz;
  in.force = to_cpp(c.force);
  in.profile.shape = enum_from<Input::Profile::Shape>(c.profile_shape, HAPTIC_PROFILE_RECORDED,
                                                      "profile_shape");
  in.profile.start_s = c.profile_start_s;
  in.profile.rise_s = c.profile_rise_s;
  in.profile.frequency_hz = c.profile_frequency_hz;
  in.profile.offset = to_cpp(c.profile_offset);
  if (c.profile_sample_count > 0 && c.profile_samples == nullptr) {
    throw FieldProblem{"profile_samples", "is NULL with profile_sample_count > 0"};
  }
  for (std::uint32_t i = 0; i < c.profile_sample_count; ++i) {
    in.profile.samples.push_back(to_cpp(c.profile_samples[i]));
  }
  in.profile.sample_period_s = c.profile_sample_period_s;
  in.profile.repeat = c.profile_repeat != 0;
  return in;
}

inline const haptic::ClientConfig& defaults() {
  static const haptic::ClientConfig config;
  return config;
}

inline std::string text_or_empty(const char* text) { return text != nullptr ? text : ""; }

inline haptic_applied_scene* applied_of(haptic::AppliedScene&& applied,
                                 const std::vector<haptic::StabilityReport>& stability) {
  auto* out = new haptic_applied_scene;
  for (auto& o : applied.objects) out->objects.emplace_back(std::move(o));
  for (auto& f : applied.fields) out->fields.emplace_back(std::move(f));
  out->stability = stability;
  return out;
}
template <typename List>
void check_index(const List& list, std::uint32_t index, const char* call) {
  if (index >= list.size()) {
    throw InvalidArgumentError(std::string(call) + ": index: " + std::to_string(index) +
                               " is past the scene's " + std::to_string(list.size()));
  }
}


}  // namespace haptic::c_api
