#include "net/validation.hpp"

#include <cmath>
#include <sstream>

namespace haptic::net {
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

std::string check_impedance(const v1::Impedance& impedance, const std::string& path,
                            const SceneLimits& limits) {
  if (auto e = check_range(impedance.stiffness(), 0.0, limits.max_stiffness, path + ".stiffness");
      !e.empty()) {
    return e;
  }
  return check_range(impedance.damping(), 0.0, limits.max_damping, path + ".damping");
}

// An unset orientation is identity; a set one must be a unit quaternion to within 1e-3 and is
// renormalised, so clients may send rounded values.
std::string to_quat(const v1::Pose& pose, const std::string& path, engine::Quat& out) {
  out = engine::Quat{};
  if (!pose.has_orientation()) return {};
  const auto& q = pose.orientation();
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

}  // namespace

engine::Vec3 to_engine(const v1::Vec3& v) { return {v.x(), v.y(), v.z()}; }

v1::Vec3 to_proto(const engine::Vec3& v) {
  v1::Vec3 out;
  out.set_x(v.x);
  out.set_y(v.y);
  out.set_z(v.z);
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
  out.stiffness = object.impedance().stiffness();
  out.damping = object.impedance().damping();

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
    case v1::Object::SHAPE_NOT_SET:
      break;
  }
  return path + ".shape: one of half_space, sphere is required";
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
    case v1::Field::KIND_NOT_SET:
      break;
  }
  return path + ".kind: one of spring_to_point is required";
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

}  // namespace haptic::net
