#include "conversions.hpp"

namespace haptic::detail {

v1::Vec3 to_proto(const Vec3& v) {
  v1::Vec3 out;
  out.set_x(v.x);
  out.set_y(v.y);
  out.set_z(v.z);
  return out;
}

Vec3 from_proto(const v1::Vec3& v) { return {v.x(), v.y(), v.z()}; }

namespace {
void set_impedance(v1::Object& object, const Impedance& impedance) {
  object.mutable_impedance()->set_stiffness(impedance.stiffness);
  object.mutable_impedance()->set_damping(impedance.damping);
}
}  // namespace

v1::Object to_proto(const WallSpec& wall) {
  v1::Object object;
  *object.mutable_pose()->mutable_position() = to_proto(wall.point);
  set_impedance(object, wall.impedance);
  *object.mutable_half_space()->mutable_normal() = to_proto(wall.normal);
  return object;
}

v1::Object to_proto(const SphereSpec& sphere) {
  v1::Object object;
  *object.mutable_pose()->mutable_position() = to_proto(sphere.center);
  set_impedance(object, sphere.impedance);
  object.mutable_sphere()->set_radius(sphere.radius);
  return object;
}

v1::Field to_proto(const SpringFieldSpec& spring) {
  v1::Field field;
  auto* s = field.mutable_spring_to_point();
  *s->mutable_anchor() = to_proto(spring.anchor);
  s->set_stiffness(spring.stiffness);
  s->set_damping(spring.damping);
  s->set_max_force(spring.max_force);
  return field;
}

v1::OperatorInput to_proto(const OperatorInput& input) {
  v1::OperatorInput out;
  switch (input.mode) {
    case OperatorInput::Mode::kRelease:
      out.set_mode(v1::OperatorInput::NONE);
      break;
    case OperatorInput::Mode::kFollow: {
      out.set_mode(v1::OperatorInput::FOLLOW_TARGET);
      *out.mutable_target() = to_proto(input.target);
      out.set_stiffness(input.stiffness);
      out.set_damping(input.damping);
      out.set_mass(input.mass);
      out.set_grip(input.grip == OperatorInput::Grip::kLoose   ? v1::OperatorInput::LOOSE
                   : input.grip == OperatorInput::Grip::kTight ? v1::OperatorInput::TIGHT
                                                               : v1::OperatorInput::CUSTOM);
      auto* path = out.mutable_trajectory();
      switch (input.path.shape) {
        case OperatorInput::Path::Shape::kFixed: path->set_shape(v1::TargetTrajectory::FIXED); break;
        case OperatorInput::Path::Shape::kLine: path->set_shape(v1::TargetTrajectory::LINE); break;
        case OperatorInput::Path::Shape::kSine: path->set_shape(v1::TargetTrajectory::SINE); break;
      }
      *path->mutable_end() = to_proto(input.path.end);
      path->set_duration_s(input.path.duration_s);
      *path->mutable_amplitude() = to_proto(input.path.amplitude);
      path->set_frequency_hz(input.path.frequency_hz);
      break;
    }
    case OperatorInput::Mode::kPush: {
      out.set_mode(v1::OperatorInput::APPLY_FORCE);
      *out.mutable_force() = to_proto(input.force);
      auto* profile = out.mutable_profile();
      switch (input.profile.shape) {
        case OperatorInput::Profile::Shape::kConstant: profile->set_shape(v1::ForceProfile::CONSTANT); break;
        case OperatorInput::Profile::Shape::kStep: profile->set_shape(v1::ForceProfile::STEP); break;
        case OperatorInput::Profile::Shape::kRamp: profile->set_shape(v1::ForceProfile::RAMP); break;
        case OperatorInput::Profile::Shape::kSine: profile->set_shape(v1::ForceProfile::SINE); break;
        case OperatorInput::Profile::Shape::kRecorded:
          profile->set_shape(v1::ForceProfile::RECORDED);
          for (const Vec3& sample : input.profile.samples) *profile->add_samples() = to_proto(sample);
          profile->set_sample_period_s(input.profile.sample_period_s);
          profile->set_repeat(input.profile.repeat);
          break;
      }
      profile->set_start_s(input.profile.start_s);
      profile->set_rise_s(input.profile.rise_s);
      profile->set_frequency_hz(input.profile.frequency_hz);
      *profile->mutable_offset() = to_proto(input.profile.offset);
      break;
    }
  }
  return out;
}

DeviceInfo from_proto(const v1::DeviceInfo& info) {
  DeviceInfo out;
  out.name = info.name();
  out.dof = info.dof();
  out.workspace_min = from_proto(info.workspace_min());
  out.workspace_max = from_proto(info.workspace_max());
  out.max_force = info.max_force();
  out.loop_rate_hz = info.loop_rate_hz();
  out.simulated = info.simulated();
  out.model = info.model();
  const v1::DeviceCapabilities& caps = info.capabilities();
  out.capabilities = {caps.gravity(),        caps.brakes(),
                      caps.flexible_modes(), caps.friction(),
                      caps.force_sensor(),   caps.quantized_position(),
                      caps.state_estimator(), caps.disturbance_observer()};
  return out;
}

Stats from_proto(const v1::Stats& s) {
  Stats out;
  out.ticks = s.ticks();
  out.achieved_rate_hz = s.achieved_rate_hz();
  out.lateness_p50_us = s.lateness_p50_us();
  out.lateness_p99_us = s.lateness_p99_us();
  out.lateness_max_us = s.lateness_max_us();
  out.overruns = s.overruns();
  out.sessions = s.sessions();
  out.objects = s.objects();
  out.fields = s.fields();
  out.datagrams_sent = s.datagrams_sent();
  out.datagrams_received = s.datagrams_received();
  out.datagrams_dropped = s.datagrams_dropped();
  out.force_faults = s.force_faults();
  out.force_saturations = s.force_saturations();
  out.leases_expired = s.leases_expired();
  out.device_faults = s.device_faults();
  return out;
}

State from_proto(const v1::ToolState& s) {
  State out;
  out.tick = s.tick();
  out.server_time = s.server_time_s();
  out.position = from_proto(s.position());
  out.velocity = from_proto(s.velocity());
  out.force = from_proto(s.force());
  out.proxy = from_proto(s.proxy());
  out.contact_count = s.contact_count();
  out.flags = s.flags();
  out.received_at = std::chrono::steady_clock::now();
  return out;
}

}  // namespace haptic::detail
