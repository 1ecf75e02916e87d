// The C API (haptic/haptic_c.h) over haptic::Client: every entry point catches every exception
// and reports it as a code and message, so nothing unwinds into C. Each spec kind has one pair of
// conversions (CSpec ↔ the C++ spec) that init, add, update, scenes and read-back share.

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

namespace {

using haptic::InvalidArgumentError;

// ---- errors ----

/// Copies `text` into a fixed buffer, truncated to fit and NUL-terminated (only what it needs:
/// a success's empty message writes one byte).
void copy_text(char* out, std::size_t capacity, const std::string& text) {
  const std::size_t n = std::min(capacity - 1, text.size());
  std::memcpy(out, text.data(), n);
  out[n] = '\0';
}

void set_error(haptic_error* err, int code, const std::string& message) {
  if (err == nullptr) return;
  err->code = code;
  copy_text(err->message, sizeof(err->message), message);
}

int code_of(haptic::ErrorCode code) {
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
void require(const void* pointer, const char* call, const char* field) {
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

std::int64_t steady_ns(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(t.time_since_epoch()).count();
}

// ---- value types and specs: each struct's fields listed once, walked in either direction ----

haptic_vec3 to_c(const haptic::Vec3& v) { return {v.x, v.y, v.z}; }
haptic::Vec3 to_cpp(const haptic_vec3& v) { return {v.x, v.y, v.z}; }
haptic_quaternion to_c(const haptic::Quaternion& q) { return {q.w, q.x, q.y, q.z}; }
haptic::Quaternion to_cpp(const haptic_quaternion& q) { return {q.w, q.x, q.y, q.z}; }

/// The last value of each C++ enum a C struct carries as an int32_t (values 0..last).
template <typename Enum> constexpr std::int32_t kLastValue = 0;
template <> constexpr std::int32_t kLastValue<haptic::ImpedanceLaw> = HAPTIC_LAW_TUSTIN;
template <> constexpr std::int32_t kLastValue<haptic::Distance::Kind> = HAPTIC_DISTANCE_SPHERE;
template <> constexpr std::int32_t kLastValue<haptic::PotentialFieldSpec::Kind> = HAPTIC_POTENTIAL_KHATIB;

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
haptic_mesh_spec mesh_to_c(const haptic::MeshSpec& s) {
  static_assert(sizeof(haptic_vec3) == sizeof(haptic::Vec3) && std::is_standard_layout_v<haptic::Vec3>);
  haptic_mesh_spec c = to_c(s);
  c.vertices = s.vertices.empty() ? nullptr : reinterpret_cast<const haptic_vec3*>(s.vertices.data());
  c.vertex_count = static_cast<std::uint32_t>(s.vertices.size());
  c.indices = s.indices.empty() ? nullptr : s.indices.data();
  c.index_count = static_cast<std::uint32_t>(s.indices.size());
  return c;
}
haptic::MeshSpec mesh_to_cpp(const haptic_mesh_spec& c) {
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
void add_scene_item(const haptic_scene_item& item, haptic::SceneSpec& scene, const char* call) {
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

haptic::SceneSpec scene_of(const haptic_scene_item* items, std::uint32_t count, const char* call) {
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

void copy_state(const haptic::State& s, haptic_state& state) {
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

haptic::State state_of(const haptic_state& c) {
  haptic::State s;
  s.tick = c.tick;
  s.server_time = c.server_time;
  s.position = to_cpp(c.position);
  s.velocity = to_cpp(c.velocity);
  return s;
}

void copy_report(const haptic::StabilityReport& r, haptic_stability_report& out) {
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

void copy_recording(const haptic::RecordingStatus& r, haptic_recording_status* out) {
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

haptic::OperatorInput operator_of(const haptic_operator_input& c) {
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

const haptic::ClientConfig& defaults() {
  static const haptic::ClientConfig config;
  return config;
}

std::string text_or_empty(const char* text) { return text != nullptr ? text : ""; }

haptic_applied_scene* applied_of(haptic::AppliedScene&& applied,
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

}  // namespace

extern "C" {

uint32_t haptic_c_version(void) { return HAPTIC_C_VERSION; }

// ---- client ----

namespace {
haptic_client_config client_config_defaults() {
  haptic_client_config value{};
  haptic_client_config* config = &value;
  const haptic::ClientConfig& d = defaults();
  config->server_address = d.server_address.c_str();
  config->client_name = d.client_name.c_str();
  config->token = "";
  config->tls_ca_file = "";
  config->tls_cert_file = "";
  config->tls_key_file = "";
  config->tls_server_name = "";
  config->udp_address = "";
  config->rpc_timeout_ms = static_cast<uint32_t>(d.rpc_timeout.count());
  config->heartbeat_period_ms = static_cast<uint32_t>(d.heartbeat_period.count());
  config->state_decimation = d.state_decimation;
  config->device_index = d.device_index;
  config->reconnect = d.reconnect;
  config->allow_plaintext_token = d.allow_plaintext_token;
  config->reconnect_backoff_min_ms = static_cast<uint32_t>(d.reconnect_backoff_min.count());
  config->reconnect_backoff_max_ms = static_cast<uint32_t>(d.reconnect_backoff_max.count());
  return value;
}
}  // namespace
HAPTIC_C_INIT(haptic_client_config, client_config_defaults())

int haptic_client_open(const haptic_client_config* config, haptic_client** out, haptic_error* err) {
  return guarded(err, [&] {
    require(out, "ClientConfig", "out");
    *out = nullptr;
    const auto& c = sized<haptic_client_config>(config, "ClientConfig", "config");
    haptic::ClientConfig cpp;
    if (c.server_address != nullptr) cpp.server_address = c.server_address;
    if (c.client_name != nullptr) cpp.client_name = c.client_name;
    cpp.token = text_or_empty(c.token);
    if (!text_or_empty(c.tls_ca_file).empty()) {
      cpp.tls = haptic::TlsOptions{c.tls_ca_file, text_or_empty(c.tls_cert_file),
                                   text_or_empty(c.tls_key_file), text_or_empty(c.tls_server_name)};
    } else if (!text_or_empty(c.tls_cert_file).empty() || !text_or_empty(c.tls_key_file).empty()) {
      throw InvalidArgumentError("ClientConfig: tls_ca_file: needed with tls_cert_file and tls_key_file");
    }
    cpp.udp_address = text_or_empty(c.udp_address);
    cpp.rpc_timeout = std::chrono::milliseconds(c.rpc_timeout_ms);
    cpp.heartbeat_period = std::chrono::milliseconds(c.heartbeat_period_ms);
    cpp.state_decimation = c.state_decimation;
    cpp.device_index = c.device_index;
    cpp.reconnect = c.reconnect != 0;
    cpp.allow_plaintext_token = c.allow_plaintext_token != 0;
    cpp.reconnect_backoff_min = std::chrono::milliseconds(c.reconnect_backoff_min_ms);
    cpp.reconnect_backoff_max = std::chrono::milliseconds(c.reconnect_backoff_max_ms);
    *out = new haptic_client{haptic::Client(std::move(cpp))};
    return HAPTIC_OK;
  });
}

int haptic_client_close(haptic_client* client, haptic_error* err) {
  if (client == nullptr) return guarded(err, [] { return HAPTIC_OK; });
  const int status = guarded(err, [&] {
    client->client.close();
    return HAPTIC_OK;
  });
  // From inside a callback close() refuses (it would wait for its own thread): the client stays.
  if (status == HAPTIC_ERROR_FAILED_PRECONDITION) return status;
  try {
    delete client;  // the destructor swallows its own errors; this catch keeps a surprise out of C
  } catch (...) {
  }
  return status;
}

int haptic_client_device_info(const haptic_client* client, haptic_device_info* out, haptic_error* err) {
  return guarded(err, [&] {
    require(client, "device_info", "client");
    SizedOut<haptic_device_info> written(out, "device_info", "out");
    auto& c = *written;
    const haptic::DeviceInfo& d = client->client.device_info();
    const std::uint32_t size = c.size;
    c = haptic_device_info{};
    c.size = size;
    copy_text(c.name, sizeof(c.name), d.name);
    copy_text(c.model, sizeof(c.model), d.model);
    const haptic::DeviceCapabilities& k = d.capabilities;
    const auto bit = [](bool has, unsigned flag) { return has ? static_cast<std::uint32_t>(flag) : 0u; };
    c.capabilities = bit(k.gravity, HAPTIC_CAPABILITY_GRAVITY) | bit(k.brakes, HAPTIC_CAPABILITY_BRAKES) |
                     bit(k.flexible_modes, HAPTIC_CAPABILITY_FLEXIBLE_MODES) |
                     bit(k.friction, HAPTIC_CAPABILITY_FRICTION) |
                     bit(k.force_sensor, HAPTIC_CAPABILITY_FORCE_SENSOR) |
                     bit(k.quantized_position, HAPTIC_CAPABILITY_QUANTIZED_POSITION) |
                     bit(k.state_estimator, HAPTIC_CAPABILITY_STATE_ESTIMATOR) |
                     bit(k.disturbance_observer, HAPTIC_CAPABILITY_DISTURBANCE_OBSERVER) |
                     bit(k.orientation, HAPTIC_CAPABILITY_ORIENTATION) |
                     bit(k.torque, HAPTIC_CAPABILITY_TORQUE);
    c.dof = d.dof;
    c.workspace_min = to_c(d.workspace_min);
    c.workspace_max = to_c(d.workspace_max);
    c.max_force = d.max_force;
    c.loop_rate_hz = d.loop_rate_hz;
    c.max_torque = d.max_torque;
    c.simulated = d.simulated;
    c.buttons = d.buttons;
    return HAPTIC_OK;
  });
}

uint64_t haptic_client_session_id(const haptic_client* client) {
  if (client == nullptr) return 0;
  try {
    return client->client.session_id();
  } catch (...) {
    return 0;
  }
}

int64_t haptic_client_lease_timeout_ms(const haptic_client* client) {
  if (client == nullptr) return 0;
  try {
    return client->client.lease_timeout().count();
  } catch (...) {
    return 0;
  }
}

// ---- state ----

int haptic_client_poll_state(haptic_client* client, haptic_state* out, uint32_t timeout_ms,
                             haptic_error* err) {
  return guarded(err, [&] {
    require(client, "poll_state", "client");
    sized<haptic_state>(out, "poll_state", "state");
    haptic::State s;
    if (!client->client.poll_state(s, std::chrono::milliseconds(timeout_ms))) return HAPTIC_TIMEOUT;
    copy_state(s, *SizedOut<haptic_state>(out, "poll_state", "state"));
    return HAPTIC_OK;
  });
}

int haptic_client_wait_for_tick(haptic_client* client, uint64_t tick, haptic_state* out,
                                uint32_t timeout_ms, haptic_error* err) {
  return guarded(err, [&] {
    require(client, "wait_for_tick", "client");
    sized<haptic_state>(out, "wait_for_tick", "state");
    haptic::State s;
    if (!client->client.wait_for_tick(tick, s, std::chrono::milliseconds(timeout_ms))) {
      return HAPTIC_TIMEOUT;
    }
    copy_state(s, *SizedOut<haptic_state>(out, "wait_for_tick", "state"));
    return HAPTIC_OK;
  });
}

int haptic_client_subscribe(haptic_client* client, uint32_t decimation, haptic_error* err) {
  return guarded(err, [&] {
    require(client, "Subscribe", "client");
    client->client.subscribe(decimation);
    return HAPTIC_OK;
  });
}

int haptic_client_on_state(haptic_client* client, haptic_state_callback callback, void* user_data,
                           haptic_error* err) {
  return guarded(err, [&] {
    require(client, "on_state", "client");
    if (callback == nullptr) {
      client->client.on_state({});
      return HAPTIC_OK;
    }
    client->client.on_state([callback, user_data](const haptic::State& s) {
      haptic_state c{};
      c.size = sizeof(c);
      copy_state(s, c);
      callback(&c, user_data);
    });
    return HAPTIC_OK;
  });
}

int64_t haptic_steady_clock_ns(void) { return steady_ns(std::chrono::steady_clock::now()); }

int32_t haptic_client_server_time_at(const haptic_client* client, int64_t local_ns, double* out) {
  if (client == nullptr || out == nullptr) return 0;
  try {
    const auto local = std::chrono::steady_clock::time_point(std::chrono::nanoseconds(local_ns));
    const std::optional<double> t = client->client.server_time_at(local);
    if (!t) return 0;
    *out = *t;
    return 1;
  } catch (...) {
    return 0;
  }
}

int32_t haptic_client_clock_offset_ns(const haptic_client* client, int64_t* out) {
  if (client == nullptr || out == nullptr) return 0;
  try {
    const auto offset = client->client.clock_offset();
    if (!offset) return 0;
    *out = offset->count();
    return 1;
  } catch (...) {
    return 0;
  }
}

int32_t haptic_client_clock_drift(const haptic_client* client, double* out) {
  if (client == nullptr || out == nullptr) return 0;
  try {
    const auto drift = client->client.clock_drift();
    if (!drift) return 0;
    *out = *drift;
    return 1;
  } catch (...) {
    return 0;
  }
}

haptic_vec3 haptic_interpolate_position(const haptic_state* a, const haptic_state* b, double t) {
  if (a == nullptr || b == nullptr) return {0.0, 0.0, 0.0};
  return to_c(haptic::interpolate_position(state_of(*a), state_of(*b), t));
}

haptic_vec3 haptic_predict_position(const haptic_state* previous, const haptic_state* latest,
                                    double t) {
  if (previous == nullptr || latest == nullptr) return {0.0, 0.0, 0.0};
  return to_c(haptic::predict_position(state_of(*previous), state_of(*latest), t));
}

int haptic_client_receive_counters(const haptic_client* client, haptic_receive_counters* out,
                                   haptic_error* err) {
  return guarded(err, [&] {
    require(client, "receive_counters", "client");
    SizedOut<haptic_receive_counters> written(out, "receive_counters", "out");
    auto& c = *written;
    const haptic::ReceiveCounters r = client->client.receive_counters();
    c.accepted = r.accepted;
    c.rejected = r.rejected;
    c.skipped = r.skipped;
    c.challenges_answered = r.challenges_answered;
    c.callback_skipped = r.callback_skipped;
    c.lost = r.lost;
    c.reordered = r.reordered;
    c.duplicates = r.duplicates;
    c.reconnects = r.reconnects;
    return HAPTIC_OK;
  });
}

int haptic_client_set_heartbeats_enabled(haptic_client* client, int32_t enabled, haptic_error* err) {
  return guarded(err, [&] {
    require(client, "set_heartbeats_enabled", "client");
    client->client.set_heartbeats_enabled(enabled != 0);
    return HAPTIC_OK;
  });
}

// ---- specs ----

HAPTIC_C_INIT(haptic_wall_spec, spec_defaults<haptic_wall_spec>())
HAPTIC_C_INIT(haptic_sphere_spec, spec_defaults<haptic_sphere_spec>())
HAPTIC_C_INIT(haptic_box_spec, spec_defaults<haptic_box_spec>())
HAPTIC_C_INIT(haptic_capsule_spec, spec_defaults<haptic_capsule_spec>())
HAPTIC_C_INIT(haptic_tangent_plane_spec, spec_defaults<haptic_tangent_plane_spec>())
HAPTIC_C_INIT(haptic_mesh_spec, spec_defaults<haptic_mesh_spec>())
HAPTIC_C_INIT(haptic_spring_field_spec, spec_defaults<haptic_spring_field_spec>())
HAPTIC_C_INIT(haptic_distance_spring_spec, spec_defaults<haptic_distance_spring_spec>())
HAPTIC_C_INIT(haptic_potential_field_spec, spec_defaults<haptic_potential_field_spec>())
HAPTIC_C_INIT(haptic_linear_field_spec, spec_defaults<haptic_linear_field_spec>())
HAPTIC_C_INIT(haptic_viscous_field_spec, spec_defaults<haptic_viscous_field_spec>())
HAPTIC_C_INIT(haptic_detent_field_spec, spec_defaults<haptic_detent_field_spec>())
HAPTIC_C_INIT(haptic_orientation_spring_spec, spec_defaults<haptic_orientation_spring_spec>())
HAPTIC_C_INIT(haptic_orientation_detent_spec, spec_defaults<haptic_orientation_detent_spec>())

#define HAPTIC_C_ADD_OBJECT(NAME, CSPEC)                                                        \
  int haptic_client_add_##NAME(haptic_client* client, const CSPEC* spec, haptic_object** out,  \
                               haptic_error* err) {                                            \
    return add_object(client, spec, out, err);                                                 \
  }                                                                                            \
  int haptic_object_update_##NAME(haptic_object* object, const CSPEC* spec, haptic_error* err) { \
    return update_item(object, spec, "UpdateObject", err);                                     \
  }
HAPTIC_C_ADD_OBJECT(wall, haptic_wall_spec)
HAPTIC_C_ADD_OBJECT(sphere, haptic_sphere_spec)
HAPTIC_C_ADD_OBJECT(box, haptic_box_spec)
HAPTIC_C_ADD_OBJECT(capsule, haptic_capsule_spec)
HAPTIC_C_ADD_OBJECT(tangent_plane, haptic_tangent_plane_spec)
HAPTIC_C_ADD_OBJECT(mesh, haptic_mesh_spec)
#undef HAPTIC_C_ADD_OBJECT

#define HAPTIC_C_ADD_FIELD(NAME, CSPEC)                                                         \
  int haptic_client_add_##NAME(haptic_client* client, const CSPEC* spec, haptic_field** out,   \
                               haptic_error* err) {                                            \
    return add_field(client, spec, out, err);                                                  \
  }                                                                                            \
  int haptic_field_update_##NAME(haptic_field* field, const CSPEC* spec, haptic_error* err) {  \
    return update_item(field, spec, "UpdateField", err);                                       \
  }
HAPTIC_C_ADD_FIELD(spring_field, haptic_spring_field_spec)
HAPTIC_C_ADD_FIELD(distance_spring, haptic_distance_spring_spec)
HAPTIC_C_ADD_FIELD(potential_field, haptic_potential_field_spec)
HAPTIC_C_ADD_FIELD(linear_field, haptic_linear_field_spec)
HAPTIC_C_ADD_FIELD(viscous_field, haptic_viscous_field_spec)
HAPTIC_C_ADD_FIELD(detent_field, haptic_detent_field_spec)
HAPTIC_C_ADD_FIELD(orientation_spring, haptic_orientation_spring_spec)
HAPTIC_C_ADD_FIELD(orientation_detent, haptic_orientation_detent_spec)
#undef HAPTIC_C_ADD_FIELD

uint64_t haptic_object_id(const haptic_object* object) {
  return object != nullptr ? object->handle.id() : 0;
}
uint64_t haptic_field_id(const haptic_field* field) { return field != nullptr ? field->handle.id() : 0; }

int haptic_object_remove(haptic_object* object, haptic_error* err) {
  const int status = guarded(err, [&] {
    if (object != nullptr) object->handle.remove();
    return HAPTIC_OK;
  });
  delete object;  // the handle owns nothing any more, or its destructor swallows the error
  return status;
}

int haptic_field_remove(haptic_field* field, haptic_error* err) {
  const int status = guarded(err, [&] {
    if (field != nullptr) field->handle.remove();
    return HAPTIC_OK;
  });
  delete field;
  return status;
}

uint64_t haptic_object_release(haptic_object* object) {
  if (object == nullptr) return 0;
  const std::uint64_t id = object->handle.release();
  delete object;
  return id;
}

uint64_t haptic_field_release(haptic_field* field) {
  if (field == nullptr) return 0;
  const std::uint64_t id = field->handle.release();
  delete field;
  return id;
}

int haptic_object_stability(const haptic_object* object, haptic_stability_report* out,
                            haptic_error* err) {
  return guarded(err, [&] {
    require(object, "stability", "object");
    copy_report(object->handle.stability(), *SizedOut<haptic_stability_report>(out, "stability", "out"));
    return HAPTIC_OK;
  });
}

int haptic_field_stability(const haptic_field* field, haptic_stability_report* out,
                           haptic_error* err) {
  return guarded(err, [&] {
    require(field, "stability", "field");
    SizedOut<haptic_stability_report> written(out, "stability", "out");
    auto& c = *written;
    if (field->handle.stability()) {
      copy_report(*field->handle.stability(), c);
    } else {
      const std::uint32_t size = c.size;
      c = haptic_stability_report{};
      c.size = size;
    }
    return HAPTIC_OK;
  });
}

// ---- scenes ----

int haptic_client_apply_scene(haptic_client* client, const haptic_scene_item* items, uint32_t count,
                              haptic_applied_scene** out, haptic_error* err) {
  return guarded(err, [&] {
    require(out, "ApplyScene", "out");
    *out = nullptr;
    require(client, "ApplyScene", "client");
    haptic::AppliedScene applied = client->client.apply_scene(scene_of(items, count, "ApplyScene"));
    *out = applied_of(std::move(applied), client->client.last_scene_stability());
    return HAPTIC_OK;
  });
}

int haptic_client_apply_scene_file(haptic_client* client, const char* path,
                                   haptic_applied_scene** out, haptic_error* err) {
  return guarded(err, [&] {
    require(out, "apply_scene_file", "out");
    *out = nullptr;
    require(client, "apply_scene_file", "client");
    require(path, "apply_scene_file", "path");
    haptic::AppliedScene applied = client->client.apply_scene_file(path);
    *out = applied_of(std::move(applied), client->client.last_scene_stability());
    return HAPTIC_OK;
  });
}

void haptic_applied_scene_counts(const haptic_applied_scene* scene, uint32_t* objects,
                                 uint32_t* fields) {
  if (objects != nullptr) *objects = scene ? static_cast<uint32_t>(scene->objects.size()) : 0;
  if (fields != nullptr) *fields = scene ? static_cast<uint32_t>(scene->fields.size()) : 0;
}

haptic_object* haptic_applied_scene_take_object(haptic_applied_scene* scene, uint32_t index) {
  if (scene == nullptr || index >= scene->objects.size() || !scene->objects[index]) return nullptr;
  try {
    auto* object = new haptic_object{std::move(*scene->objects[index])};
    scene->objects[index].reset();
    return object;
  } catch (...) {
    return nullptr;
  }
}

haptic_field* haptic_applied_scene_take_field(haptic_applied_scene* scene, uint32_t index) {
  if (scene == nullptr || index >= scene->fields.size() || !scene->fields[index]) return nullptr;
  try {
    auto* field = new haptic_field{std::move(*scene->fields[index])};
    scene->fields[index].reset();
    return field;
  } catch (...) {
    return nullptr;
  }
}

int haptic_applied_scene_stability(const haptic_applied_scene* scene, uint32_t index,
                                   haptic_stability_report* out, haptic_error* err) {
  return guarded(err, [&] {
    require(scene, "last_scene_stability", "scene");
    if (index >= scene->stability.size()) {
      throw InvalidArgumentError("last_scene_stability: index: " + std::to_string(index) +
                                 " is past the scene's " + std::to_string(scene->stability.size()) +
                                 " objects");
    }
    copy_report(scene->stability[index],
                *SizedOut<haptic_stability_report>(out, "last_scene_stability", "out"));
    return HAPTIC_OK;
  });
}

void haptic_applied_scene_free(haptic_applied_scene* scene) {
  if (scene == nullptr) return;
  // Handles not taken let go of their items rather than removing them (haptic_c.h).
  for (auto& o : scene->objects) {
    if (o) o->release();
  }
  for (auto& f : scene->fields) {
    if (f) f->release();
  }
  delete scene;
}

int haptic_scene_json(const haptic_scene_item* items, uint32_t count, char* buffer, size_t capacity,
                      size_t* length, haptic_error* err) {
  return guarded(err, [&] {
    require(length, "scene_json", "length");
    if (capacity > 0) require(buffer, "scene_json", "buffer");
    const std::string json = haptic::scene_json(scene_of(items, count, "scene_json"));
    *length = json.size();
    if (capacity > 0) copy_text(buffer, capacity, json);
    return HAPTIC_OK;
  });
}

int haptic_client_scene(haptic_client* client, int32_t all_sessions, haptic_registered_scene** out,
                        haptic_error* err) {
  return guarded(err, [&] {
    require(out, "GetScene", "out");
    *out = nullptr;
    require(client, "GetScene", "client");
    *out = new haptic_registered_scene{client->client.scene(all_sessions != 0)};
    return HAPTIC_OK;
  });
}

void haptic_registered_scene_counts(const haptic_registered_scene* scene, uint32_t* objects,
                                    uint32_t* fields) {
  if (objects != nullptr) *objects = scene ? static_cast<uint32_t>(scene->scene.scene.objects.size()) : 0;
  if (fields != nullptr) *fields = scene ? static_cast<uint32_t>(scene->scene.scene.fields.size()) : 0;
}

int haptic_registered_scene_object(const haptic_registered_scene* scene, uint32_t index,
                                   haptic_scene_entry* out, haptic_error* err) {
  return guarded(err, [&] {
    require(scene, "scene.objects", "scene");
    check_index(scene->scene.scene.objects, index, "scene.objects");
    SizedOut<haptic_scene_entry> written(out, "scene.objects", "out");
    auto& c = *written;
    c.kind = kind_of(scene->scene.scene.objects[index]);
    c.id = scene->scene.object_ids[index];
    c.session_id = scene->scene.object_sessions[index];
    return HAPTIC_OK;
  });
}

int haptic_registered_scene_field(const haptic_registered_scene* scene, uint32_t index,
                                  haptic_scene_entry* out, haptic_error* err) {
  return guarded(err, [&] {
    require(scene, "scene.fields", "scene");
    check_index(scene->scene.scene.fields, index, "scene.fields");
    SizedOut<haptic_scene_entry> written(out, "scene.fields", "out");
    auto& c = *written;
    c.kind = kind_of(scene->scene.scene.fields[index]);
    c.id = scene->scene.field_ids[index];
    c.session_id = scene->scene.field_sessions[index];
    return HAPTIC_OK;
  });
}

int haptic_registered_scene_object_spec(const haptic_registered_scene* scene, uint32_t index,
                                        void* spec, haptic_error* err) {
  return guarded(err, [&] {
    require(scene, "scene.objects", "scene");
    check_index(scene->scene.scene.objects, index, "scene.objects");
    copy_spec(scene->scene.scene.objects[index], spec, "scene.objects");
    return HAPTIC_OK;
  });
}

int haptic_registered_scene_field_spec(const haptic_registered_scene* scene, uint32_t index,
                                       void* spec, haptic_error* err) {
  return guarded(err, [&] {
    require(scene, "scene.fields", "scene");
    check_index(scene->scene.scene.fields, index, "scene.fields");
    copy_spec(scene->scene.scene.fields[index], spec, "scene.fields");
    return HAPTIC_OK;
  });
}

void haptic_registered_scene_free(haptic_registered_scene* scene) { delete scene; }

int haptic_client_scene_energy(haptic_client* client, haptic_item_energy* out, uint32_t capacity,
                               uint32_t* count, haptic_error* err) {
  return guarded(err, [&] {
    require(client, "GetSceneEnergy", "client");
    copy_list(client->client.scene_energy(), out, capacity, count, "GetSceneEnergy",
              [](const haptic::ItemEnergy& e) {
                return haptic_item_energy{e.id, e.session_id, e.is_object, e.given_to_device,
                                          e.absorbed_from_device};
              });
    return HAPTIC_OK;
  });
}

int haptic_client_object_states(haptic_client* client, haptic_object_state* out, uint32_t capacity,
                                uint32_t* count, haptic_error* err) {
  return guarded(err, [&] {
    require(client, "GetObjectStates", "client");
    copy_list(client->client.object_states(), out, capacity, count, "GetObjectStates",
              [](const haptic::ObjectState& s) {
                return haptic_object_state{s.id, to_c(s.position), to_c(s.velocity)};
              });
    return HAPTIC_OK;
  });
}

// ---- operator, lockstep ----

namespace {
haptic_operator_input operator_input_defaults() {
  haptic_operator_input value{};
  haptic_operator_input* input = &value;
  const haptic::OperatorInput d;
  input->mode = static_cast<int32_t>(d.mode);
  input->target = to_c(d.target);
  input->stiffness = d.stiffness;
  input->damping = d.damping;
  input->mass = d.mass;
  input->grip = static_cast<int32_t>(d.grip);
  input->path_shape = static_cast<int32_t>(d.path.shape);
  input->path_end = to_c(d.path.end);
  input->path_duration_s = d.path.duration_s;
  input->path_amplitude = to_c(d.path.amplitude);
  input->path_frequency_hz = d.path.frequency_hz;
  input->force = to_c(d.force);
  input->profile_shape = static_cast<int32_t>(d.profile.shape);
  input->profile_repeat = d.profile.repeat;
  input->profile_start_s = d.profile.start_s;
  input->profile_rise_s = d.profile.rise_s;
  input->profile_frequency_hz = d.profile.frequency_hz;
  input->profile_offset = to_c(d.profile.offset);
  input->profile_sample_period_s = d.profile.sample_period_s;
  return value;
}
}  // namespace
HAPTIC_C_INIT(haptic_operator_input, operator_input_defaults())

int haptic_client_set_operator(haptic_client* client, const haptic_operator_input* input,
                               haptic_error* err) {
  return guarded(err, [&] {
    require(client, "SetOperator", "client");
    const auto& c = sized<haptic_operator_input>(input, "SetOperator", "input");
    client->client.set_operator(converting("SetOperator", "input", [&] { return operator_of(c); }));
    return HAPTIC_OK;
  });
}

int haptic_client_set_operator_push(haptic_client* client, haptic_vec3 force, haptic_error* err) {
  return guarded(err, [&] {
    require(client, "SetOperator", "client");
    client->client.set_operator(haptic::OperatorInput::push(to_cpp(force)));
    return HAPTIC_OK;
  });
}

int haptic_client_set_operator_follow(haptic_client* client, haptic_vec3 target, double stiffness,
                                      double damping, haptic_error* err) {
  return guarded(err, [&] {
    require(client, "SetOperator", "client");
    client->client.set_operator(haptic::OperatorInput::follow(to_cpp(target), stiffness, damping));
    return HAPTIC_OK;
  });
}

int haptic_client_step(haptic_client* client, uint32_t ticks, uint64_t* last_tick, haptic_error* err) {
  return guarded(err, [&] {
    require(client, "Step", "client");
    const std::uint64_t last = client->client.step(ticks);
    if (last_tick != nullptr) *last_tick = last;
    return HAPTIC_OK;
  });
}

int haptic_client_reset(haptic_client* client, haptic_error* err) {
  return guarded(err, [&] {
    require(client, "Reset", "client");
    client->client.reset();
    return HAPTIC_OK;
  });
}

// ---- events, connection ----

int haptic_client_on_event(haptic_client* client, haptic_event_callback callback, void* user_data,
                           haptic_error* err) {
  return guarded(err, [&] {
    require(client, "WatchEvents", "client");
    if (callback == nullptr) {
      client->client.on_event({});
      return HAPTIC_OK;
    }
    client->client.on_event([callback, user_data](const haptic::Event& e) {
      haptic_event c{};
      c.size = sizeof(c);
      c.kind = static_cast<int32_t>(e.kind);
      c.session_id = e.session_id;
      c.item_id = e.item_id;
      c.server_time = e.server_time;
      c.message = e.message.c_str();
      callback(&c, user_data);
    });
    return HAPTIC_OK;
  });
}

int haptic_client_on_connection(haptic_client* client, haptic_connection_callback callback,
                                void* user_data, haptic_error* err) {
  return guarded(err, [&] {
    require(client, "on_connection", "client");
    if (callback == nullptr) {
      client->client.on_connection({});
      return HAPTIC_OK;
    }
    client->client.on_connection([callback, user_data](const haptic::ConnectionChange& change) {
      haptic_connection_change c{};
      c.size = sizeof(c);
      c.state = static_cast<int32_t>(change.state);
      c.session_id = change.session_id;
      c.new_session = change.new_session;
      c.items_not_restored = change.items_not_restored;
      c.outage_ms = change.outage.count();
      c.reason = change.reason.c_str();
      callback(&c, user_data);
    });
    return HAPTIC_OK;
  });
}

int32_t haptic_client_connection_state(const haptic_client* client) {
  if (client == nullptr) return HAPTIC_CONNECTION_ENDED;
  try {
    return static_cast<int32_t>(client->client.connection_state());
  } catch (...) {
    return HAPTIC_CONNECTION_ENDED;
  }
}

// ---- administration ----

int haptic_client_sessions(haptic_client* client, haptic_session_summary* out, uint32_t capacity,
                           uint32_t* count, haptic_error* err) {
  return guarded(err, [&] {
    require(client, "ListSessions", "client");
    copy_list(client->client.sessions(), out, capacity, count, "ListSessions",
              [](const haptic::SessionSummary& s) {
                haptic_session_summary c{};
                c.session_id = s.session_id;
                copy_text(c.client_name, sizeof(c.client_name), s.client_name);
                copy_text(c.peer, sizeof(c.peer), s.peer);
                copy_text(c.token_name, sizeof(c.token_name), s.token_name);
                c.device_index = s.device_index;
                c.role = static_cast<int32_t>(s.role);
                c.opened_time = s.opened_time;
                return c;
              });
    return HAPTIC_OK;
  });
}

int haptic_client_kick_session(haptic_client* client, uint64_t session_id, const char* reason,
                               haptic_error* err) {
  return guarded(err, [&] {
    require(client, "KickSession", "client");
    client->client.kick_session(session_id, text_or_empty(reason));
    return HAPTIC_OK;
  });
}

void haptic_session_id_text(uint64_t session_id, char out[17]) {
  if (out == nullptr) return;
  try {
    copy_text(out, 17, haptic::session_id_text(session_id));
  } catch (...) {
    out[0] = '\0';
  }
}

int haptic_client_stats(haptic_client* client, haptic_stats* out, haptic_stream_stats* clients,
                        uint32_t clients_capacity, haptic_coupling_stats* couplings,
                        uint32_t couplings_capacity, haptic_error* err) {
  return guarded(err, [&] {
    require(client, "GetStats", "client");
    SizedOut<haptic_stats> written(out, "GetStats", "out");
    auto& c = *written;
    if (clients_capacity > 0) require(clients, "GetStats", "clients");
    if (couplings_capacity > 0) require(couplings, "GetStats", "couplings");
    const haptic::Stats s = client->client.stats();
    const std::uint32_t size = c.size;
    c = haptic_stats{};
    c.size = size;
    c.sessions = s.sessions;
    c.ticks = s.ticks;
    c.achieved_rate_hz = s.achieved_rate_hz;
    c.lateness_p50_us = s.lateness_p50_us;
    c.lateness_p99_us = s.lateness_p99_us;
    c.lateness_p999_us = s.lateness_p999_us;
    c.lateness_max_us = s.lateness_max_us;
    c.lateness_samples = s.lateness_samples;
    c.window_s = s.window_s;
    c.overruns = s.overruns;
    c.objects = s.objects;
    c.fields = s.fields;
    c.datagrams_sent = s.datagrams_sent;
    c.datagrams_received = s.datagrams_received;
    c.datagrams_dropped = s.datagrams_dropped;
    c.force_faults = s.force_faults;
    c.force_saturations = s.force_saturations;
    c.passivity_active_ticks = s.passivity_active_ticks;
    c.leases_expired = s.leases_expired;
    c.device_faults = s.device_faults;
    c.send_delay_p50_us = s.send_delay_p50_us;
    c.send_delay_p99_us = s.send_delay_p99_us;
    c.send_delay_p999_us = s.send_delay_p999_us;
    c.heartbeats_rate_limited = s.heartbeats_rate_limited;
    c.datagrams_foreign_source = s.datagrams_foreign_source;
    c.path_challenges_sent = s.path_challenges_sent;
    c.samples_skipped = s.samples_skipped;
    c.connections_refused = s.connections_refused;
    c.connections_timed_out = s.connections_timed_out;
    c.connections_evicted = s.connections_evicted;
    c.tls_handshakes_failed = s.tls_handshakes_failed;
    c.connections_open = s.connections_open;
    c.client_count = static_cast<uint32_t>(s.clients.size());
    for (std::size_t i = 0; i < std::min<std::size_t>(clients_capacity, s.clients.size()); ++i) {
      const haptic::ClientStats& k = s.clients[i];
      haptic_stream_stats& o = clients[i];
      o = haptic_stream_stats{};
      o.session_id = k.session_id;
      copy_text(o.client_name, sizeof(o.client_name), k.client_name);
      copy_text(o.peer, sizeof(o.peer), k.peer);
      o.device_index = k.device_index;
      o.decimation = k.decimation;
      o.datagrams_sent = k.datagrams_sent;
      o.heartbeats = k.heartbeats;
      o.states_received = k.states_received;
      o.states_lost = k.states_lost;
      o.last_heartbeat_age_s = k.last_heartbeat_age_s;
      o.round_trip_samples = k.round_trip_samples;
      o.round_trip_p50_us = k.round_trip_p50_us;
      o.round_trip_p99_us = k.round_trip_p99_us;
      o.round_trip_p999_us = k.round_trip_p999_us;
    }
    if (s.federation) {
      const haptic::FederationStats& f = *s.federation;
      c.has_federation = 1;
      c.coupling_count = static_cast<uint32_t>(f.couplings.size());
      c.federation_samples_published = f.samples_published;
      c.federation_samples_failed = f.samples_failed;
      c.federation_items_published = f.items_published;
      c.federation_items_applied = f.items_applied;
      c.federation_items_refused = f.items_refused;
      c.federation_wrenches_accepted = f.wrenches_accepted;
      c.federation_wrenches_refused = f.wrenches_refused;
      for (std::size_t i = 0; i < std::min<std::size_t>(couplings_capacity, f.couplings.size()); ++i) {
        const haptic::CouplingStats& k = f.couplings[i];
        couplings[i] = haptic_coupling_stats{static_cast<int32_t>(k.kind), k.port, k.remote, k.mass,
                                             k.injected_j, k.given_j, k.sent_j, k.received_j,
                                             k.reservoir_j};
      }
    }
    return HAPTIC_OK;
  });
}

int haptic_client_start_recording(haptic_client* client, const char* name,
                                  haptic_recording_status* out, haptic_error* err) {
  return guarded(err, [&] {
    require(client, "StartRecording", "client");
    require(name, "StartRecording", "name");
    if (out != nullptr) sized<haptic_recording_status>(out, "StartRecording", "out");
    copy_recording(client->client.start_recording(name), out);
    return HAPTIC_OK;
  });
}

int haptic_client_stop_recording(haptic_client* client, haptic_recording_status* out,
                                 haptic_error* err) {
  return guarded(err, [&] {
    require(client, "StopRecording", "client");
    if (out != nullptr) sized<haptic_recording_status>(out, "StopRecording", "out");
    copy_recording(client->client.stop_recording(), out);
    return HAPTIC_OK;
  });
}

// ---- the recorder ----

namespace {
void copy_recorder_stats(const haptic::RecorderStats& r, haptic_recorder_stats& c) {
  const std::uint32_t size = c.size;
  c = haptic_recorder_stats{};
  c.size = size;
  c.samples_received = r.samples_received;
  c.samples_written = r.samples_written;
  c.dropped = r.dropped;
  c.events_written = r.events_written;
  c.events_dropped = r.events_dropped;
  c.write_errors = r.write_errors;
  copy_text(c.first_error, sizeof(c.first_error), r.first_error);
}

haptic_recorder_options recorder_options_defaults() {
  haptic_recorder_options value{};
  haptic_recorder_options* options = &value;
  const haptic::RecorderOptions d;
  options->path = "";
  options->format = static_cast<int32_t>(d.format);
  options->events = d.events;
  options->overwrite = d.overwrite;
  options->queue_capacity = d.queue_capacity;
  return value;
}
}  // namespace
HAPTIC_C_INIT(haptic_recorder_options, recorder_options_defaults())

int haptic_client_record(haptic_client* client, const haptic_recorder_options* options,
                         haptic_recorder** out, haptic_error* err) {
  return guarded(err, [&] {
    require(out, "record", "out");
    *out = nullptr;
    require(client, "record", "client");
    const auto& c = sized<haptic_recorder_options>(options, "record", "options");
    haptic::RecorderOptions cpp;
    cpp.path = text_or_empty(c.path);
    cpp.format = converting("record", "options", [&] {
      return enum_from<haptic::RecorderOptions::Format>(c.format, HAPTIC_RECORDER_HDF5, "format");
    });
    cpp.events = c.events != 0;
    cpp.overwrite = c.overwrite != 0;
    cpp.queue_capacity = static_cast<std::size_t>(c.queue_capacity);
    *out = new haptic_recorder{haptic::Recorder(client->client, cpp)};
    return HAPTIC_OK;
  });
}

int haptic_recorder_get_stats(const haptic_recorder* recorder, haptic_recorder_stats* out,
                              haptic_error* err) {
  return guarded(err, [&] {
    require(recorder, "recorder_stats", "recorder");
    copy_recorder_stats(recorder->recorder.stats(), *SizedOut<haptic_recorder_stats>(out, "recorder_stats", "out"));
    return HAPTIC_OK;
  });
}

const char* haptic_recorder_path(const haptic_recorder* recorder) {
  return recorder != nullptr ? recorder->recorder.path().c_str() : "";
}

const char* haptic_recorder_events_path(const haptic_recorder* recorder) {
  return recorder != nullptr ? recorder->recorder.events_path().c_str() : "";
}

int haptic_recorder_close(haptic_recorder* recorder, haptic_recorder_stats* totals, haptic_error* err) {
  const int status = guarded(err, [&] {
    if (totals != nullptr) sized<haptic_recorder_stats>(totals, "recorder_close", "totals");
    return HAPTIC_OK;
  });
  if (recorder == nullptr) return status;
  const haptic::RecorderStats stats = recorder->recorder.close();  // never throws
  if (status == HAPTIC_OK && totals != nullptr) {
    copy_recorder_stats(stats, *SizedOut<haptic_recorder_stats>(totals, "recorder_close", "totals"));
  }
  delete recorder;
  return status;
}

}  // extern "C"
