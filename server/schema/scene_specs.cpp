#include "schema/scene_specs.hpp"

#include <cmath>
#include <memory>
#include <sstream>

#include "engine/analysis/wall_design.hpp"
#include "engine/scene/impedance.hpp"
#include "engine/scene/shapes.hpp"

namespace haptic::schema {
namespace {

std::string describe(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

std::string check_finite(double value, const std::string& path) {
  if (!std::isfinite(value)) return path + ": must be finite, got " + describe(value);
  return {};
}

std::string check_range(double value, double min, double max, const std::string& path) {
  if (!std::isfinite(value) || value < min || value > max) {
    return path + ": must be finite and in [" + describe(min) + ", " + describe(max) + "], got " +
           describe(value);
  }
  return {};
}

std::string check_vec(const v1::Vec3& v, double max_abs, const std::string& path) {
  for (const auto& [value, axis] : {std::pair{v.x(), ".x"}, {v.y(), ".y"}, {v.z(), ".z"}}) {
    if (auto error = check_range(value, -max_abs, max_abs, path + axis); !error.empty()) return error;
  }
  return {};
}

/// Each component of a size (half extents): finite and in (0, max].
std::string check_positive_vec(const v1::Vec3& v, double max, const std::string& path) {
  for (const auto& [value, axis] : {std::pair{v.x(), ".x"}, {v.y(), ".y"}, {v.z(), ".z"}}) {
    if (!std::isfinite(value) || value <= 0.0 || value > max) {
      return path + axis + ": must be finite and in (0, " + describe(max) + "], got " + describe(value);
    }
  }
  return {};
}

/// A law the enum names, and never TUSTIN with a damper (objects and orientation springs alike).
std::string check_law(v1::Impedance::Law law, double damping, const std::string& path) {
  switch (law) {
    case v1::Impedance::VELOCITY:
    case v1::Impedance::BACKWARD_DIFFERENCE:
    case v1::Impedance::EXACT_ZOH:
      return {};
    case v1::Impedance::TUSTIN:
      if (damping > 0.0) {
        return path + ".law: TUSTIN with damping > 0 is unstable on every sampled device (its "
                      "damper has a pole at z = -1); use EXACT_ZOH or BACKWARD_DIFFERENCE";
      }
      return {};
    default:
      return path + ".law: must be VELOCITY, BACKWARD_DIFFERENCE, EXACT_ZOH or TUSTIN, got " +
             std::to_string(static_cast<int>(law));
  }
}

std::string check_impedance(const v1::Impedance& impedance, const std::string& path,
                            const SceneLimits& limits) {
  if (auto e = check_range(impedance.stiffness(), 0.0, limits.max_stiffness, path + ".stiffness");
      !e.empty()) {
    return e;
  }
  if (auto e = check_range(impedance.damping(), 0.0, limits.max_damping, path + ".damping");
      !e.empty()) {
    return e;
  }
  if (auto e = check_range(impedance.static_friction(), 0.0, limits.max_friction,
                           path + ".static_friction");
      !e.empty()) {
    return e;
  }
  if (auto e = check_range(impedance.dynamic_friction(), 0.0, impedance.static_friction(),
                           path + ".dynamic_friction");
      !e.empty()) {
    return e + " (at most static_friction)";
  }
  if (auto e = check_range(impedance.mass(), 0.0, limits.max_impedance_mass, path + ".mass");
      !e.empty()) {
    return e;
  }
  switch (impedance.law()) {
    case v1::Impedance::VELOCITY:
      if (impedance.mass() != 0.0) return path + ".mass: needs a discrete law (VELOCITY has no mass term)";
      return {};
    case v1::Impedance::BACKWARD_DIFFERENCE:
    case v1::Impedance::EXACT_ZOH:
    case v1::Impedance::TUSTIN:
      if (impedance.static_friction() > 0.0) {
        return path + ".static_friction: friction needs the VELOCITY law";
      }
      return check_law(impedance.law(), impedance.damping(), path);
    default:
      return check_law(impedance.law(), impedance.damping(), path);
  }
}

engine::ContactLaw to_law(v1::Impedance::Law law) {
  switch (law) {
    case v1::Impedance::BACKWARD_DIFFERENCE: return engine::ContactLaw::kBackwardDifference;
    case v1::Impedance::EXACT_ZOH: return engine::ContactLaw::kExactZoh;
    case v1::Impedance::TUSTIN: return engine::ContactLaw::kTustin;
    default: return engine::ContactLaw::kVelocity;
  }
}

/// Prefixes an engine validator's message ("half_extents.y: …") with the path, or "" if none.
std::string at(const std::string& path, const std::string& message) {
  return message.empty() ? message : path + "." + message;
}

std::string to_distance(const v1::Distance& d, const std::string& path, const SceneLimits& limits,
                        engine::DistanceSpec& out) {
  if (auto e = check_vec(d.origin(), limits.max_abs_position, path + ".origin"); !e.empty()) return e;
  const engine::Vec3 origin = to_engine(d.origin());
  switch (d.kind()) {
    case v1::Distance::POINT:
      out = engine::point_distance(origin);
      break;
    case v1::Distance::LINE:
    case v1::Distance::PLANE: {
      if (auto e = check_vec(d.axis(), 1e6, path + ".axis"); !e.empty()) return e;
      const engine::Vec3 axis = to_engine(d.axis());
      if (!(engine::norm(axis) > 1e-9)) return path + ".axis: must be non-zero";
      out = d.kind() == v1::Distance::LINE ? engine::line_distance(origin, axis)
                                           : engine::plane_distance(origin, axis);
      break;
    }
    case v1::Distance::SPHERE:
      if (auto e = check_range(d.radius(), 1e-6, limits.max_radius, path + ".radius"); !e.empty()) {
        return e;
      }
      out = engine::sphere_distance(origin, d.radius());
      break;
    default:
      return path + ".kind: must be POINT, LINE, PLANE or SPHERE";
  }
  return at(path, engine::validate_field(out));
}

// An unset orientation is identity; a set one must be a unit quaternion to within 1e-3 and is
// renormalised, so clients may send rounded values.
std::string to_quat(const v1::Quaternion* set, const std::string& path, engine::Quat& out) {
  out = engine::Quat{};
  if (set == nullptr) return {};
  const v1::Quaternion& q = *set;
  for (const auto& [value, axis] :
       {std::pair{q.w(), ".w"}, {q.x(), ".x"}, {q.y(), ".y"}, {q.z(), ".z"}}) {
    if (auto e = check_finite(value, path + axis); !e.empty()) return e;
  }
  const double n = std::sqrt(q.w() * q.w() + q.x() * q.x() + q.y() * q.y() + q.z() * q.z());
  if (std::abs(n - 1.0) > 1e-3) {
    return path + ": must be a unit quaternion, got norm " + describe(n);
  }
  out = engine::Quat{q.w() / n, q.x() / n, q.y() / n, q.z() / n};
  return {};
}

std::string to_quat(const v1::Pose& pose, const std::string& path, engine::Quat& out) {
  return to_quat(pose.has_orientation() ? &pose.orientation() : nullptr, path, out);
}

}  // namespace

engine::Vec3 to_engine(const v1::Vec3& v) { return {v.x(), v.y(), v.z()}; }

v1::Vec3 to_proto(const engine::Vec3& v) {
  v1::Vec3 out;
  out.set_x(v.x);
  out.set_y(v.y);
  out.set_z(v.z);
  return out;
}

v1::Quaternion to_proto(const engine::Quat& q) {
  v1::Quaternion out;
  out.set_w(q.w);
  out.set_x(q.x);
  out.set_y(q.y);
  out.set_z(q.z);
  return out;
}

std::string to_object_spec(const v1::Object& object, const std::string& path,
                           const SceneLimits& limits, engine::ObjectSpec& out) {
  if (auto e = check_vec(object.pose().position(), limits.max_abs_position, path + ".pose.position");
      !e.empty()) {
    return e;
  }
  if (auto e = to_quat(object.pose(), path + ".pose.orientation", out.R_WO); !e.empty()) return e;
  out.p_WO = to_engine(object.pose().position());
  if (!object.has_impedance()) return path + ".impedance: is required";
  if (auto e = check_impedance(object.impedance(), path + ".impedance", limits); !e.empty()) return e;
  out.shared = object.shared();
  out.across_sites = object.across_sites();
  const v1::Impedance& impedance = object.impedance();
  out.stiffness = impedance.stiffness();
  out.damping = impedance.damping();
  if (impedance.virtual_coupling()) {
    if (impedance.transparency_optimal_damping()) {
      return path + ".impedance.virtual_coupling: not with transparency_optimal_damping";
    }
    if (!(limits.device_damping > 0.0)) {
      return path + ".impedance.virtual_coupling: needs a device that gives its damping (" +
             limits.device_unknown_reason + ")";
    }
    const engine::VirtualCouplingDesign coupling = engine::design_virtual_coupling(
        limits.device_mass > 0.0 ? limits.device_mass : 1.0, limits.device_damping, limits.period_s);
    out.stiffness = coupling.gains.stiffness;
    out.damping = coupling.gains.damping;
  }
  if (impedance.transparency_optimal_damping()) {
    if (limits.device_mass <= 0.0) {
      return path + ".impedance.transparency_optimal_damping: needs a device that gives its mass "
                    "and damping (" + limits.device_unknown_reason + ")";
    }
    if (!(impedance.stiffness() > 0.0)) {
      return path + ".impedance.transparency_optimal_damping: needs stiffness > 0";
    }
    engine::WallDesignParams design;
    design.mass = limits.device_mass;
    design.damping = limits.device_damping;
    design.wall_stiffness = impedance.stiffness();
    design.wall_damping = impedance.damping() > 0.0 ? impedance.damping() : 1.0;
    design.sample_period = limits.period_s;
    out.damping = engine::optimise_controller_damping(design).controller_damping;
  }
  out.static_friction = impedance.static_friction();
  out.dynamic_friction = impedance.dynamic_friction();
  out.impedance_mass = impedance.mass();
  out.law = to_law(impedance.law());

  if (object.has_dynamics()) {
    const v1::Dynamics& dynamics = object.dynamics();
    const std::string d = path + ".dynamics";
    if (object.shape_case() == v1::Object::kHalfSpace ||
        object.shape_case() == v1::Object::kTangentPlane) {
      return d + ": only bounded objects (spheres, boxes, capsules, meshes) can be virtual masses";
    }
    if (auto e = check_range(dynamics.mass(), 1e-6, limits.max_object_mass, d + ".mass"); !e.empty()) {
      return e;
    }
    if (auto e = check_range(dynamics.damping(), 0.0, limits.max_damping, d + ".damping"); !e.empty()) {
      return e;
    }
    // The tool and the mass meet through the sampled contact spring: its mode must be well
    // resolved (ω T ≤ 0.5, ω = √(K/m)), and the held contact force must not pump the mass
    // (Colgate: B_contact + B_V > K T / 2).
    const double T = limits.period_s;
    const double K = out.stiffness;
    if (dynamics.mass() < 4.0 * K * T * T) {
      return d + ".mass: " + describe(dynamics.mass()) + " kg is too light for stiffness " +
             describe(K) + " N/m at " + describe(1.0 / T) + " Hz: needs at least 4 K T^2 = " +
             describe(4.0 * K * T * T) + " kg";
    }
    if (out.damping + dynamics.damping() <= 0.5 * K * T) {
      return d + ".damping: impedance.damping + dynamics.damping must exceed K T / 2 = " +
             describe(0.5 * K * T) + " N*s/m for the pushed mass to stay passive";
    }
    out.object_mass = dynamics.mass();
    out.object_damping = dynamics.damping();
  }

  switch (object.shape_case()) {
    case v1::Object::kHalfSpace: {
      const auto& normal = object.half_space().normal();
      const std::string normal_path = path + ".half_space.normal";
      if (auto e = check_vec(normal, 1e6, normal_path); !e.empty()) return e;
      const engine::Vec3 n = to_engine(normal);
      if (!(engine::norm(n) > 1e-9)) return normal_path + ": must be non-zero";
      out.shape = engine::HalfSpaceSpec{n};
      return {};
    }
    case v1::Object::kSphere: {
      const double radius = object.sphere().radius();
      if (!std::isfinite(radius) || radius <= 0.0 || radius > limits.max_radius) {
        return path + ".sphere.radius: must be finite and in (0, " + describe(limits.max_radius) +
               "], got " + describe(radius);
      }
      out.shape = engine::SphereSpec{radius};
      return {};
    }
    case v1::Object::kBox: {
      const std::string box_path = path + ".box.half_extents";
      if (auto e = check_positive_vec(object.box().half_extents(), limits.max_radius, box_path);
          !e.empty()) {
        return e;
      }
      const engine::BoxSpec box{to_engine(object.box().half_extents())};
      if (auto e = engine::validate(box); !e.empty()) return path + ".box." + e;
      out.shape = box;
      return {};
    }
    case v1::Object::kCapsule: {
      const engine::CapsuleSpec capsule{object.capsule().radius(), object.capsule().half_length()};
      if (auto e = check_range(capsule.radius, 0.0, limits.max_radius, path + ".capsule.radius");
          !e.empty()) {
        return e;
      }
      if (auto e = check_range(capsule.half_length, 0.0, limits.max_radius,
                               path + ".capsule.half_length");
          !e.empty()) {
        return e;
      }
      if (auto e = engine::validate(capsule); !e.empty()) return path + ".capsule." + e;
      out.shape = capsule;
      return {};
    }
    case v1::Object::kMesh: {
      const v1::TriangleMesh& mesh = object.mesh();
      const std::string mesh_path = path + ".mesh";
      if (mesh.indices_size() % 3 != 0) {
        return mesh_path + ".indices: must hold three per triangle, got " +
               std::to_string(mesh.indices_size());
      }
      if (static_cast<std::size_t>(mesh.indices_size() / 3) > limits.max_mesh_triangles) {
        return mesh_path + ".indices: " + std::to_string(mesh.indices_size() / 3) +
               " triangles exceed the limit of " + std::to_string(limits.max_mesh_triangles);
      }
      auto model = std::make_shared<engine::MeshModel>();
      model->mesh.vertices_O.reserve(static_cast<std::size_t>(mesh.vertices_size()));
      for (int i = 0; i < mesh.vertices_size(); ++i) {
        model->mesh.vertices_O.push_back(to_engine(mesh.vertices(i)));
      }
      model->mesh.triangles.reserve(static_cast<std::size_t>(mesh.indices_size() / 3));
      for (int i = 0; i + 2 < mesh.indices_size(); i += 3) {
        model->mesh.triangles.push_back({mesh.indices(i), mesh.indices(i + 1), mesh.indices(i + 2)});
      }
      if (auto e = engine::validate_mesh(model->mesh, limits.max_mesh_triangles); !e.empty()) {
        return mesh_path + "." + e;
      }
      model->bvh = engine::MeshBvh::build(model->mesh);
      out.shape = engine::MeshShapeSpec{std::move(model)};
      return {};
    }
    case v1::Object::kTangentPlane: {
      const v1::TangentPlane& plane = object.tangent_plane();
      const std::string p = path + ".tangent_plane";
      if (auto e = check_vec(plane.normal(), 1e6, p + ".normal"); !e.empty()) return e;
      if (!(engine::norm(to_engine(plane.normal())) > 1e-9)) return p + ".normal: must be non-zero";
      if (auto e = check_vec(plane.reference(), limits.max_abs_position, p + ".reference"); !e.empty()) {
        return e;
      }
      if (auto e = check_range(plane.tangential_stiffness(), 0.0, limits.max_stiffness,
                               p + ".tangential_stiffness");
          !e.empty()) {
        return e;
      }
      if (auto e = check_range(plane.tangential_damping(), 0.0, limits.max_damping,
                               p + ".tangential_damping");
          !e.empty()) {
        return e;
      }
      if (out.static_friction > 0.0) {
        return path + ".impedance.static_friction: a tangent plane's tangential law is its spring";
      }
      const engine::Vec3 n = to_engine(plane.normal());
      out.shape = engine::TangentPlaneSpec{n * (1.0 / engine::norm(n)), to_engine(plane.reference()),
                                           plane.tangential_stiffness(), plane.tangential_damping()};
      return {};
    }
    case v1::Object::SHAPE_NOT_SET:
      break;
  }
  return path + ".shape: one of half_space, sphere, box, capsule, mesh, tangent_plane is required";
}

std::string to_field_spec(const v1::Field& field, const std::string& path,
                          const SceneLimits& limits, engine::FieldSpec& out) {
  switch (field.kind_case()) {
    case v1::Field::kSpringToPoint: {
      const auto& spring = field.spring_to_point();
      const std::string p = path + ".spring_to_point";
      if (auto e = check_vec(spring.anchor(), limits.max_abs_position, p + ".anchor"); !e.empty()) {
        return e;
      }
      if (auto e = check_range(spring.stiffness(), 0.0, limits.max_stiffness, p + ".stiffness");
          !e.empty()) {
        return e;
      }
      if (auto e = check_range(spring.damping(), 0.0, limits.max_damping, p + ".damping");
          !e.empty()) {
        return e;
      }
      if (auto e = check_range(spring.max_force(), 0.0, limits.max_force, p + ".max_force");
          !e.empty()) {
        return e;
      }
      out.kind = engine::SpringToPointSpec{to_engine(spring.anchor()), spring.stiffness(),
                                           spring.damping(), spring.max_force()};
      return {};
    }
    case v1::Field::kSpring: {
      const auto& spring = field.spring();
      const std::string p = path + ".spring";
      engine::SpringFieldSpec spec;
      if (auto e = to_distance(spring.anchor(), p + ".anchor", limits, spec.anchor); !e.empty()) return e;
      spec.stiffness = spring.stiffness();
      spec.damping = spring.damping();
      spec.max_force = spring.max_force();
      if (auto e = check_range(spec.stiffness, 0.0, limits.max_stiffness, p + ".stiffness"); !e.empty()) return e;
      if (auto e = check_range(spec.damping, 0.0, limits.max_damping, p + ".damping"); !e.empty()) return e;
      if (auto e = check_range(spec.max_force, 0.0, limits.max_force, p + ".max_force"); !e.empty()) return e;
      if (auto e = engine::validate_field(spec); !e.empty()) return p + "." + e;
      out.kind = spec;
      return {};
    }
    case v1::Field::kPotential: {
      const auto& potential = field.potential();
      const std::string p = path + ".potential";
      engine::PotentialFieldSpec spec;
      if (auto e = to_distance(potential.distance(), p + ".distance", limits, spec.distance); !e.empty()) {
        return e;
      }
      switch (potential.kind()) {
        case v1::PotentialField::POLYNOMIAL: spec.kind = engine::PotentialKind::kPolynomial; break;
        case v1::PotentialField::KHATIB: spec.kind = engine::PotentialKind::kKhatib; break;
        default: return p + ".kind: must be POLYNOMIAL or KHATIB";
      }
      // No default: 0 is refused like any order outside 2 ... 8 (clamped only to stay an int).
      spec.order = static_cast<int>(std::min<std::uint32_t>(potential.order(), 1000));
      spec.gain = potential.gain();
      spec.offset = potential.offset();
      spec.influence_distance = potential.influence_distance();
      spec.min_distance = potential.min_distance();
      switch (potential.gradient()) {
        case v1::PotentialField::ANALYTIC: spec.gradient = engine::GradientMethod::kAnalytic; break;
        case v1::PotentialField::CENTRAL_DIFFERENCE:
          spec.gradient = engine::GradientMethod::kCentralDifference;
          break;
        default: return p + ".gradient: must be ANALYTIC or CENTRAL_DIFFERENCE";
      }
      if (potential.difference_step() != 0.0) spec.difference_step = potential.difference_step();
      if (auto e = engine::validate_field(spec); !e.empty()) return p + "." + e;
      out.kind = spec;
      return {};
    }
    case v1::Field::kLinear: {
      const auto& linear = field.linear();
      const std::string p = path + ".linear";
      engine::LinearFieldSpec spec;
      if (auto e = check_vec(linear.origin(), limits.max_abs_position, p + ".origin"); !e.empty()) return e;
      if (auto e = check_vec(linear.force(), limits.max_force, p + ".force"); !e.empty()) return e;
      if (linear.jacobian_size() != 3) {
        return p + ".jacobian: must have three rows, got " + std::to_string(linear.jacobian_size());
      }
      for (int row = 0; row < 3; ++row) {
        if (auto e = check_vec(linear.jacobian(row), limits.max_stiffness,
                               p + ".jacobian[" + std::to_string(row) + "]");
            !e.empty()) {
          return e;
        }
        spec.jacobian[static_cast<std::size_t>(row)] = to_engine(linear.jacobian(row));
      }
      spec.origin_W = to_engine(linear.origin());
      spec.force_W = to_engine(linear.force());
      spec.radius = linear.radius();
      spec.fade_width = linear.fade_width();
      if (auto e = engine::validate_field(spec); !e.empty()) return p + "." + e;
      out.kind = spec;
      return {};
    }
    case v1::Field::kViscous: {
      const auto& viscous = field.viscous();
      const std::string p = path + ".viscous";
      if (auto e = check_range(viscous.damping(), 0.0, limits.max_damping, p + ".damping"); !e.empty()) return e;
      if (auto e = check_vec(viscous.center(), limits.max_abs_position, p + ".center"); !e.empty()) return e;
      engine::ViscousFieldSpec spec{viscous.damping(), to_engine(viscous.center()), viscous.radius(),
                                    viscous.fade_width()};
      if (auto e = engine::validate_field(spec); !e.empty()) return p + "." + e;
      out.kind = spec;
      return {};
    }
    case v1::Field::kDetent: {
      const auto& detent = field.detent();
      const std::string p = path + ".detent";
      engine::DetentFieldSpec spec;
      if (auto e = to_distance(detent.distance(), p + ".distance", limits, spec.distance); !e.empty()) return e;
      spec.depth = detent.depth();
      spec.radius = detent.radius();
      spec.rim_height = detent.rim_height();
      spec.rim_width = detent.rim_width();
      if (auto e = engine::validate_field(spec); !e.empty()) return p + "." + e;
      out.kind = spec;
      return {};
    }
    case v1::Field::kOrientationSpring: {
      const auto& spring = field.orientation_spring();
      const std::string p = path + ".orientation_spring";
      engine::OrientationSpringSpec spec;
      if (auto e = to_quat(spring.has_target() ? &spring.target() : nullptr, p + ".target", spec.R_WG);
          !e.empty()) {
        return e;
      }
      if (auto e = check_range(spring.stiffness(), 0.0, limits.max_rotational_stiffness, p + ".stiffness");
          !e.empty()) {
        return e;
      }
      if (auto e = check_range(spring.damping(), 0.0, limits.max_rotational_damping, p + ".damping");
          !e.empty()) {
        return e;
      }
      if (auto e = check_range(spring.max_torque(), 0.0, limits.max_torque, p + ".max_torque"); !e.empty()) {
        return e;
      }
      if (auto e = check_law(spring.law(), spring.damping(), p); !e.empty()) return e;
      spec.stiffness = spring.stiffness();
      spec.damping = spring.damping();
      spec.max_torque = spring.max_torque();
      spec.law = to_law(spring.law());
      if (auto e = engine::validate_orientation_spring(spec, limits.period_s); !e.empty()) return p + "." + e;
      out.kind = spec;
      return {};
    }
    case v1::Field::kOrientationDetent: {
      const auto& detent = field.orientation_detent();
      const std::string p = path + ".orientation_detent";
      engine::OrientationDetentSpec spec;
      if (auto e = to_quat(detent.has_target() ? &detent.target() : nullptr, p + ".target", spec.R_WG);
          !e.empty()) {
        return e;
      }
      if (auto e = check_range(detent.depth(), 0.0, limits.max_field_energy, p + ".depth"); !e.empty()) return e;
      if (auto e = check_range(detent.rim_height(), 0.0, limits.max_field_energy, p + ".rim_height");
          !e.empty()) {
        return e;
      }
      if (auto e = check_range(detent.damping(), 0.0, limits.max_rotational_damping, p + ".damping");
          !e.empty()) {
        return e;
      }
      spec.depth = detent.depth();
      spec.radius = detent.radius();
      spec.rim_height = detent.rim_height();
      spec.rim_width = detent.rim_width();
      spec.damping = detent.damping();
      if (auto e = engine::validate_orientation_detent(spec); !e.empty()) return p + "." + e;
      out.kind = spec;
      return {};
    }
    case v1::Field::KIND_NOT_SET:
      break;
  }
  return path + ".kind: one of spring_to_point, spring, potential, linear, viscous, detent, "
                "orientation_spring, orientation_detent is required";
}

std::string to_scene_specs(const v1::Scene& scene, const std::string& prefix,
                           const SceneLimits& limits, SceneSpecs& out) {
  SceneSpecs specs;
  specs.objects.resize(static_cast<std::size_t>(scene.objects_size()));
  specs.fields.resize(static_cast<std::size_t>(scene.fields_size()));
  for (int i = 0; i < scene.objects_size(); ++i) {
    const std::string path = prefix + "objects[" + std::to_string(i) + "]";
    if (auto e = to_object_spec(scene.objects(i), path, limits, specs.objects[static_cast<std::size_t>(i)]);
        !e.empty()) {
      return e;
    }
  }
  for (int i = 0; i < scene.fields_size(); ++i) {
    const std::string path = prefix + "fields[" + std::to_string(i) + "]";
    if (auto e = to_field_spec(scene.fields(i), path, limits, specs.fields[static_cast<std::size_t>(i)]);
        !e.empty()) {
      return e;
    }
  }
  out = std::move(specs);
  return {};
}

std::string to_hand_input(const v1::OperatorInput& input, const std::string& path,
                          const SceneLimits& limits, engine::HandInput& out) {
  out = engine::HandInput{};
  switch (input.mode()) {
    case v1::OperatorInput::NONE:
      out.mode = engine::HandInput::Mode::kNone;
      return {};
    case v1::OperatorInput::FOLLOW_TARGET: {
      if (auto e = check_vec(input.target(), limits.max_abs_position, path + ".target"); !e.empty()) {
        return e;
      }
      out.mode = engine::HandInput::Mode::kFollowTarget;
      out.target = to_engine(input.target());
      switch (input.grip()) {
        case v1::OperatorInput::LOOSE:
        case v1::OperatorInput::TIGHT: {
          const engine::Grip grip =
              input.grip() == v1::OperatorInput::LOOSE ? engine::kLooseGrip : engine::kTightGrip;
          out.mass = grip.mass;
          out.stiffness = grip.stiffness;
          out.damping = grip.damping;
          break;
        }
        case v1::OperatorInput::CUSTOM:
          if (auto e = check_range(input.stiffness(), 0.0, limits.max_stiffness, path + ".stiffness");
              !e.empty()) {
            return e;
          }
          if (auto e = check_range(input.damping(), 0.0, limits.max_damping, path + ".damping");
              !e.empty()) {
            return e;
          }
          if (auto e = check_range(input.mass(), 0.0, 10.0, path + ".mass"); !e.empty()) return e;
          out.stiffness = input.stiffness();
          out.damping = input.damping();
          out.mass = input.mass();
          break;
        default:
          return path + ".grip: must be CUSTOM, LOOSE or TIGHT, got " +
                 std::to_string(static_cast<int>(input.grip()));
      }
      const auto& trajectory = input.trajectory();
      const std::string tpath = path + ".trajectory";
      switch (trajectory.shape()) {
        case v1::TargetTrajectory::FIXED:
          break;
        case v1::TargetTrajectory::LINE:
          if (auto e = check_vec(trajectory.end(), limits.max_abs_position, tpath + ".end"); !e.empty()) {
            return e;
          }
          if (!std::isfinite(trajectory.duration_s()) || trajectory.duration_s() <= 0.0 ||
              trajectory.duration_s() > 3600.0) {
            return tpath + ".duration_s: must be finite and in (0, 3600], got " +
                   describe(trajectory.duration_s());
          }
          out.trajectory.shape = engine::TargetTrajectory::Shape::kLine;
          out.trajectory.end = to_engine(trajectory.end());
          out.trajectory.duration_s = trajectory.duration_s();
          break;
        case v1::TargetTrajectory::SINE:
          if (auto e = check_vec(trajectory.amplitude(), limits.max_abs_position, tpath + ".amplitude");
              !e.empty()) {
            return e;
          }
          if (auto e = check_range(trajectory.frequency_hz(), 0.0, 100.0, tpath + ".frequency_hz");
              !e.empty()) {
            return e;
          }
          out.trajectory.shape = engine::TargetTrajectory::Shape::kSine;
          out.trajectory.amplitude = to_engine(trajectory.amplitude());
          out.trajectory.frequency_hz = trajectory.frequency_hz();
          break;
        default:
          return tpath + ".shape: must be FIXED, LINE or SINE";
      }
      return {};
    }
    case v1::OperatorInput::APPLY_FORCE: {
      if (auto e = check_vec(input.force(), limits.max_force, path + ".force"); !e.empty()) return e;
      out.mode = engine::HandInput::Mode::kApplyForce;
      out.force = to_engine(input.force());
      const auto& profile = input.profile();
      const std::string ppath = path + ".profile";
      if (auto e = check_range(profile.start_s(), 0.0, 3600.0, ppath + ".start_s"); !e.empty()) return e;
      if (auto e = check_range(profile.rise_s(), 0.0, 3600.0, ppath + ".rise_s"); !e.empty()) return e;
      if (auto e = check_range(profile.frequency_hz(), 0.0, 100.0, ppath + ".frequency_hz"); !e.empty()) {
        return e;
      }
      if (auto e = check_vec(profile.offset(), limits.max_force, ppath + ".offset"); !e.empty()) return e;
      out.profile.start_s = profile.start_s();
      out.profile.rise_s = profile.rise_s();
      out.profile.frequency_hz = profile.frequency_hz();
      out.profile.offset = to_engine(profile.offset());
      switch (profile.shape()) {
        case v1::ForceProfile::CONSTANT: out.profile.shape = engine::ForceProfile::Shape::kConstant; break;
        case v1::ForceProfile::STEP: out.profile.shape = engine::ForceProfile::Shape::kStep; break;
        case v1::ForceProfile::RAMP: out.profile.shape = engine::ForceProfile::Shape::kRamp; break;
        case v1::ForceProfile::SINE: out.profile.shape = engine::ForceProfile::Shape::kSine; break;
        case v1::ForceProfile::RECORDED: {
          constexpr auto kMax = engine::RecordedForce::kMaxSamples;
          if (profile.samples_size() == 0 || profile.samples_size() > static_cast<int>(kMax)) {
            return ppath + ".samples: a RECORDED profile needs 1 to " + std::to_string(kMax) +
                   " samples, got " + std::to_string(profile.samples_size());
          }
          if (auto e = check_range(profile.sample_period_s(), 1e-4, 10.0, ppath + ".sample_period_s");
              !e.empty()) {
            return e;
          }
          engine::RecordedForce& recorded = out.profile.recorded;
          for (int i = 0; i < profile.samples_size(); ++i) {
            if (auto e = check_vec(profile.samples(i), limits.max_force,
                                   ppath + ".samples[" + std::to_string(i) + "]");
                !e.empty()) {
              return e;
            }
            recorded.samples[static_cast<std::size_t>(i)] = to_engine(profile.samples(i));
          }
          recorded.count = static_cast<std::uint32_t>(profile.samples_size());
          recorded.sample_period_s = profile.sample_period_s();
          recorded.repeat = profile.repeat();
          out.profile.shape = engine::ForceProfile::Shape::kRecorded;
          break;
        }
        default:
          return ppath + ".shape: must be CONSTANT, STEP, RAMP, SINE or RECORDED";
      }
      return {};
    }
    default:
      break;
  }
  return path + ".mode: must be NONE, FOLLOW_TARGET or APPLY_FORCE, got " +
         std::to_string(static_cast<int>(input.mode()));
}

}  // namespace haptic::schema
