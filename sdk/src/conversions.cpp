#include "conversions.hpp"

#include <variant>

namespace haptic::detail {

v1::Vec3 to_proto(const Vec3& v) {
  v1::Vec3 out;
  out.set_x(v.x);
  out.set_y(v.y);
  out.set_z(v.z);
  return out;
}

Vec3 from_proto(const v1::Vec3& v) { return {v.x(), v.y(), v.z()}; }

v1::Quaternion to_proto(const Quaternion& q) {
  v1::Quaternion out;
  out.set_w(q.w);
  out.set_x(q.x);
  out.set_y(q.y);
  out.set_z(q.z);
  return out;
}

Quaternion from_proto(const v1::Quaternion& q) { return {q.w(), q.x(), q.y(), q.z()}; }

namespace {
v1::Impedance::Law law_to_proto(ImpedanceLaw law) {
  switch (law) {
    case ImpedanceLaw::kBackwardDifference: return v1::Impedance::BACKWARD_DIFFERENCE;
    case ImpedanceLaw::kExactZoh: return v1::Impedance::EXACT_ZOH;
    case ImpedanceLaw::kTustin: return v1::Impedance::TUSTIN;
    case ImpedanceLaw::kVelocity: break;
  }
  return v1::Impedance::VELOCITY;
}

ImpedanceLaw law_from_proto(v1::Impedance::Law law) {
  switch (law) {
    case v1::Impedance::BACKWARD_DIFFERENCE: return ImpedanceLaw::kBackwardDifference;
    case v1::Impedance::EXACT_ZOH: return ImpedanceLaw::kExactZoh;
    case v1::Impedance::TUSTIN: return ImpedanceLaw::kTustin;
    default: return ImpedanceLaw::kVelocity;
  }
}

// An unset Quaternion message means identity (types.proto), not its all-zero default.
Quaternion orientation_from_proto(bool present, const v1::Quaternion& q) {
  return present ? from_proto(q) : Quaternion{};
}

void set_impedance(v1::Object& object, const Impedance& impedance) {
  v1::Impedance& out = *object.mutable_impedance();
  out.set_stiffness(impedance.stiffness);
  out.set_damping(impedance.damping);
  out.set_static_friction(impedance.static_friction);
  out.set_dynamic_friction(impedance.dynamic_friction);
  out.set_mass(impedance.mass);
  out.set_transparency_optimal_damping(impedance.transparency_optimal_damping);
  out.set_virtual_coupling(impedance.virtual_coupling);
  out.set_law(law_to_proto(impedance.law));
}

// Who may change an item and where it goes, the flags beside every spec's shape: `shared` (not on
// tangent planes or fields) and `across_sites`.
template <class Message, class Spec>
void set_sharing(Message& message, const Spec& spec) {
  if constexpr (requires { spec.shared; }) message.set_shared(spec.shared);
  message.set_across_sites(spec.across_sites);
}

// set_sharing's inverse, for a spec read back.
template <class Spec, class Message>
void read_sharing(Spec& spec, const Message& message) {
  if constexpr (requires { spec.shared; }) spec.shared = message.shared();
  spec.across_sites = message.across_sites();
}

void set_dynamics(v1::Object& object, const Dynamics& dynamics) {
  if (dynamics.mass == 0.0 && dynamics.damping == 0.0) return;
  object.mutable_dynamics()->set_mass(dynamics.mass);
  object.mutable_dynamics()->set_damping(dynamics.damping);
}

void set_pose(v1::Object& object, const Pose& pose) {
  *object.mutable_pose()->mutable_position() = to_proto(pose.position);
  *object.mutable_pose()->mutable_orientation() = to_proto(pose.orientation);
}

v1::Distance distance_to_proto(const Distance& distance) {
  v1::Distance out;
  switch (distance.kind) {
    case Distance::Kind::kPoint: out.set_kind(v1::Distance::POINT); break;
    case Distance::Kind::kLine: out.set_kind(v1::Distance::LINE); break;
    case Distance::Kind::kPlane: out.set_kind(v1::Distance::PLANE); break;
    case Distance::Kind::kSphere: out.set_kind(v1::Distance::SPHERE); break;
  }
  *out.mutable_origin() = to_proto(distance.origin);
  *out.mutable_axis() = to_proto(distance.axis);
  out.set_radius(distance.radius);
  return out;
}
}  // namespace

v1::Object to_proto(const BoxSpec& box) {
  v1::Object object;
  set_pose(object, box.pose);
  set_impedance(object, box.impedance);
  *object.mutable_box()->mutable_half_extents() = to_proto(box.half_extents);
  set_dynamics(object, box.dynamics);
  set_sharing(object, box);
  return object;
}

v1::Object to_proto(const TangentPlaneSpec& plane) {
  v1::Object object;
  set_pose(object, plane.pose);
  set_impedance(object, plane.impedance);
  auto* out = object.mutable_tangent_plane();
  *out->mutable_normal() = to_proto(plane.normal);
  *out->mutable_reference() = to_proto(plane.reference);
  out->set_tangential_stiffness(plane.tangential_stiffness);
  out->set_tangential_damping(plane.tangential_damping);
  set_sharing(object, plane);
  return object;
}

v1::Object to_proto(const CapsuleSpec& capsule) {
  v1::Object object;
  set_pose(object, capsule.pose);
  set_impedance(object, capsule.impedance);
  object.mutable_capsule()->set_radius(capsule.radius);
  object.mutable_capsule()->set_half_length(capsule.half_length);
  set_dynamics(object, capsule.dynamics);
  set_sharing(object, capsule);
  return object;
}

v1::Object to_proto(const MeshSpec& mesh) {
  v1::Object object;
  set_pose(object, mesh.pose);
  set_impedance(object, mesh.impedance);
  auto* out = object.mutable_mesh();
  for (const Vec3& v : mesh.vertices) *out->add_vertices() = to_proto(v);
  for (const std::uint32_t i : mesh.indices) out->add_indices(i);
  set_sharing(object, mesh);
  return object;
}

v1::Field to_proto(const DistanceSpringSpec& spring) {
  v1::Field field;
  auto* s = field.mutable_spring();
  *s->mutable_anchor() = distance_to_proto(spring.anchor);
  s->set_stiffness(spring.stiffness);
  s->set_damping(spring.damping);
  s->set_max_force(spring.max_force);
  set_sharing(field, spring);
  return field;
}

v1::Field to_proto(const PotentialFieldSpec& potential) {
  v1::Field field;
  auto* p = field.mutable_potential();
  *p->mutable_distance() = distance_to_proto(potential.distance);
  p->set_kind(potential.kind == PotentialFieldSpec::Kind::kKhatib ? v1::PotentialField::KHATIB
                                                                  : v1::PotentialField::POLYNOMIAL);
  p->set_order(potential.order);
  p->set_gain(potential.gain);
  p->set_offset(potential.offset);
  p->set_influence_distance(potential.influence_distance);
  p->set_min_distance(potential.min_distance);
  p->set_gradient(potential.central_differences ? v1::PotentialField::CENTRAL_DIFFERENCE
                                                : v1::PotentialField::ANALYTIC);
  set_sharing(field, potential);
  return field;
}

v1::Field to_proto(const LinearFieldSpec& linear) {
  v1::Field field;
  auto* l = field.mutable_linear();
  *l->mutable_origin() = to_proto(linear.origin);
  *l->mutable_force() = to_proto(linear.force);
  for (const Vec3& row : linear.jacobian) *l->add_jacobian() = to_proto(row);
  l->set_radius(linear.radius);
  l->set_fade_width(linear.fade_width);
  set_sharing(field, linear);
  return field;
}

v1::Field to_proto(const ViscousFieldSpec& viscous) {
  v1::Field field;
  auto* v = field.mutable_viscous();
  v->set_damping(viscous.damping);
  *v->mutable_center() = to_proto(viscous.center);
  v->set_radius(viscous.radius);
  v->set_fade_width(viscous.fade_width);
  set_sharing(field, viscous);
  return field;
}

v1::Field to_proto(const DetentFieldSpec& detent) {
  v1::Field field;
  auto* d = field.mutable_detent();
  *d->mutable_distance() = distance_to_proto(detent.distance);
  d->set_depth(detent.depth);
  d->set_radius(detent.radius);
  d->set_rim_height(detent.rim_height);
  d->set_rim_width(detent.rim_width);
  set_sharing(field, detent);
  return field;
}

v1::Field to_proto(const OrientationSpringSpec& spring) {
  v1::Field field;
  auto* s = field.mutable_orientation_spring();
  *s->mutable_target() = to_proto(spring.target);
  s->set_stiffness(spring.stiffness);
  s->set_damping(spring.damping);
  s->set_max_torque(spring.max_torque);
  s->set_law(law_to_proto(spring.law));
  set_sharing(field, spring);
  return field;
}

v1::Field to_proto(const OrientationDetentSpec& detent) {
  v1::Field field;
  auto* d = field.mutable_orientation_detent();
  *d->mutable_target() = to_proto(detent.target);
  d->set_depth(detent.depth);
  d->set_radius(detent.radius);
  d->set_rim_height(detent.rim_height);
  d->set_rim_width(detent.rim_width);
  d->set_damping(detent.damping);
  set_sharing(field, detent);
  return field;
}

v1::Object to_proto(const WallSpec& wall) {
  v1::Object object;
  *object.mutable_pose()->mutable_position() = to_proto(wall.point);
  set_impedance(object, wall.impedance);
  *object.mutable_half_space()->mutable_normal() = to_proto(wall.normal);
  set_sharing(object, wall);
  return object;
}

v1::Object to_proto(const SphereSpec& sphere) {
  v1::Object object;
  *object.mutable_pose()->mutable_position() = to_proto(sphere.center);
  set_impedance(object, sphere.impedance);
  object.mutable_sphere()->set_radius(sphere.radius);
  set_dynamics(object, sphere.dynamics);
  set_sharing(object, sphere);
  return object;
}

v1::Field to_proto(const SpringFieldSpec& spring) {
  v1::Field field;
  auto* s = field.mutable_spring_to_point();
  *s->mutable_anchor() = to_proto(spring.anchor);
  s->set_stiffness(spring.stiffness);
  s->set_damping(spring.damping);
  s->set_max_force(spring.max_force);
  set_sharing(field, spring);
  return field;
}

namespace {
Impedance impedance_from_proto(const v1::Impedance& in) {
  Impedance out;
  out.stiffness = in.stiffness();
  out.damping = in.damping();
  out.static_friction = in.static_friction();
  out.dynamic_friction = in.dynamic_friction();
  out.mass = in.mass();
  out.transparency_optimal_damping = in.transparency_optimal_damping();
  out.virtual_coupling = in.virtual_coupling();
  out.law = law_from_proto(in.law());
  return out;
}

Dynamics dynamics_from_proto(const v1::Object& object) {
  if (!object.has_dynamics()) return {};
  return {object.dynamics().mass(), object.dynamics().damping()};
}

Pose pose_from_proto(const v1::Object& object) {
  Pose pose;
  pose.position = from_proto(object.pose().position());
  pose.orientation = orientation_from_proto(object.pose().has_orientation(), object.pose().orientation());
  return pose;
}

/// v rotated by the unit quaternion q (v' = q v q*).
Vec3 rotate(const Quaternion& q, const Vec3& v) {
  // t = 2 (q_v × v); v' = v + w t + q_v × t
  const Vec3 t{2.0 * (q.y * v.z - q.z * v.y), 2.0 * (q.z * v.x - q.x * v.z), 2.0 * (q.x * v.y - q.y * v.x)};
  return {v.x + q.w * t.x + (q.y * t.z - q.z * t.y), v.y + q.w * t.y + (q.z * t.x - q.x * t.z),
          v.z + q.w * t.z + (q.x * t.y - q.y * t.x)};
}

Distance distance_from_proto(const v1::Distance& in) {
  Distance out;
  switch (in.kind()) {
    case v1::Distance::LINE: out.kind = Distance::Kind::kLine; break;
    case v1::Distance::PLANE: out.kind = Distance::Kind::kPlane; break;
    case v1::Distance::SPHERE: out.kind = Distance::Kind::kSphere; break;
    default: out.kind = Distance::Kind::kPoint; break;
  }
  out.origin = from_proto(in.origin());
  out.axis = from_proto(in.axis());
  out.radius = in.radius();
  return out;
}

// The object's shape, impedance, pose and dynamics as its spec; from_proto adds the flags.
SceneSpec::Object object_shape_from_proto(const v1::Object& object) {
  const Impedance impedance = impedance_from_proto(object.impedance());
  switch (object.shape_case()) {
    case v1::Object::kSphere:
      return SphereSpec{from_proto(object.pose().position()), object.sphere().radius(), impedance,
                        dynamics_from_proto(object)};
    case v1::Object::kBox:
      return BoxSpec{pose_from_proto(object), from_proto(object.box().half_extents()), impedance,
                     dynamics_from_proto(object)};
    case v1::Object::kCapsule:
      return CapsuleSpec{pose_from_proto(object), object.capsule().radius(),
                         object.capsule().half_length(), impedance, dynamics_from_proto(object)};
    case v1::Object::kMesh: {
      MeshSpec mesh;
      mesh.pose = pose_from_proto(object);
      for (const auto& v : object.mesh().vertices()) mesh.vertices.push_back(from_proto(v));
      mesh.indices.assign(object.mesh().indices().begin(), object.mesh().indices().end());
      mesh.impedance = impedance;
      return mesh;
    }
    case v1::Object::kTangentPlane: {
      TangentPlaneSpec plane;
      plane.pose = pose_from_proto(object);
      plane.normal = from_proto(object.tangent_plane().normal());
      plane.reference = from_proto(object.tangent_plane().reference());
      plane.tangential_stiffness = object.tangent_plane().tangential_stiffness();
      plane.tangential_damping = object.tangent_plane().tangential_damping();
      plane.impedance = impedance;
      return plane;
    }
    default: {  // a half-space: its normal is in the object frame
      const Pose pose = pose_from_proto(object);
      return WallSpec{pose.position, rotate(pose.orientation, from_proto(object.half_space().normal())),
                      impedance};
    }
  }
}

// The field's kind and parameters as its spec; from_proto adds the flags.
SceneSpec::Field field_kind_from_proto(const v1::Field& field) {
  switch (field.kind_case()) {
    case v1::Field::kSpring:
      return DistanceSpringSpec{distance_from_proto(field.spring().anchor()), field.spring().stiffness(),
                                field.spring().damping(), field.spring().max_force()};
    case v1::Field::kPotential: {
      const auto& in = field.potential();
      PotentialFieldSpec out;
      out.distance = distance_from_proto(in.distance());
      out.kind = in.kind() == v1::PotentialField::KHATIB ? PotentialFieldSpec::Kind::kKhatib
                                                         : PotentialFieldSpec::Kind::kPolynomial;
      out.order = in.order();
      out.gain = in.gain();
      out.offset = in.offset();
      out.influence_distance = in.influence_distance();
      out.min_distance = in.min_distance();
      out.central_differences = in.gradient() == v1::PotentialField::CENTRAL_DIFFERENCE;
      return out;
    }
    case v1::Field::kLinear: {
      const auto& in = field.linear();
      LinearFieldSpec out;
      out.origin = from_proto(in.origin());
      out.force = from_proto(in.force());
      for (int row = 0; row < in.jacobian_size() && row < 3; ++row) out.jacobian[row] = from_proto(in.jacobian(row));
      out.radius = in.radius();
      out.fade_width = in.fade_width();
      return out;
    }
    case v1::Field::kViscous:
      return ViscousFieldSpec{field.viscous().damping(), from_proto(field.viscous().center()),
                              field.viscous().radius(), field.viscous().fade_width()};
    case v1::Field::kDetent:
      return DetentFieldSpec{distance_from_proto(field.detent().distance()), field.detent().depth(),
                             field.detent().radius(), field.detent().rim_height(),
                             field.detent().rim_width()};
    case v1::Field::kOrientationSpring: {
      const auto& in = field.orientation_spring();
      return OrientationSpringSpec{orientation_from_proto(in.has_target(), in.target()), in.stiffness(),
                                   in.damping(), in.max_torque(), law_from_proto(in.law())};
    }
    case v1::Field::kOrientationDetent: {
      const auto& in = field.orientation_detent();
      return OrientationDetentSpec{orientation_from_proto(in.has_target(), in.target()), in.depth(),
                                   in.radius(), in.rim_height(), in.rim_width(), in.damping()};
    }
    default:  // spring_to_point
      return SpringFieldSpec{from_proto(field.spring_to_point().anchor()), field.spring_to_point().stiffness(),
                             field.spring_to_point().damping(), field.spring_to_point().max_force()};
  }
}
}  // namespace

SceneSpec::Object from_proto(const v1::Object& object) {
  SceneSpec::Object out = object_shape_from_proto(object);
  std::visit([&](auto& spec) { read_sharing(spec, object); }, out);
  return out;
}

SceneSpec::Field from_proto(const v1::Field& field) {
  SceneSpec::Field out = field_kind_from_proto(field);
  std::visit([&](auto& spec) { read_sharing(spec, field); }, out);
  return out;
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
                      caps.state_estimator(), caps.disturbance_observer(),
                      caps.orientation(),    caps.torque()};
  out.buttons = info.buttons();
  out.max_torque = info.max_torque();
  return out;
}

StabilityReport from_proto(const v1::StabilityReport& r) {
  StabilityReport out;
  out.colgate_min_damping = r.colgate_min_damping();
  out.device_mass = r.device_mass();
  out.device_damping = r.device_damping();
  out.passive = r.passive();
  out.device_known = r.device_known();
  out.stable = r.stable();
  out.max_stable_stiffness = r.max_stable_stiffness();
  out.max_pole_magnitude = r.max_pole_magnitude();
  out.chosen_damping = r.chosen_damping();
  out.chosen_stiffness = r.chosen_stiffness();
  out.robustly_stable = r.robustly_stable();
  out.warning = r.warning();
  return out;
}

std::vector<StabilityReport> stability_reports(const v1::ApplySceneResponse& reply) {
  std::vector<StabilityReport> out;
  for (const auto& report : reply.object_stability()) out.push_back(from_proto(report));
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
  out.passivity_active_ticks = s.passivity_active_ticks();
  out.leases_expired = s.leases_expired();
  out.device_faults = s.device_faults();
  out.send_delay_p50_us = s.send_delay_p50_us();
  out.send_delay_p99_us = s.send_delay_p99_us();
  out.heartbeats_rate_limited = s.heartbeats_rate_limited();
  out.datagrams_foreign_source = s.datagrams_foreign_source();
  out.path_challenges_sent = s.path_challenges_sent();
  out.samples_skipped = s.samples_skipped();
  out.samples_missed = s.samples_missed();
  out.ack_stalls = s.ack_stalls();
  out.connections_open = s.connections_open();
  out.connections_refused = s.connections_refused();
  out.connections_timed_out = s.connections_timed_out();
  out.connections_evicted = s.connections_evicted();
  out.tls_handshakes_failed = s.tls_handshakes_failed();
  out.lateness_p999_us = s.lateness_p999_us();
  out.lateness_samples = s.lateness_samples();
  out.window_s = s.window_s();
  out.send_delay_p999_us = s.send_delay_p999_us();
  for (const v1::ClientStats& c : s.clients()) {
    ClientStats& client = out.clients.emplace_back();
    client.session_id = c.session_id();
    client.client_name = c.client_name();
    client.peer = c.peer();
    client.device_index = c.device_index();
    client.decimation = c.decimation();
    client.datagrams_sent = c.datagrams_sent();
    client.heartbeats = c.heartbeats();
    client.states_received = c.states_received();
    client.states_lost = c.states_lost();
    client.ack_window = c.ack_window();
    client.acknowledged_sequence = c.acknowledged_sequence();
    client.samples_unsent = c.samples_unsent();
    client.last_heartbeat_age_s = c.last_heartbeat_age_s();
    client.round_trip_samples = c.round_trip_samples();
    client.round_trip_p50_us = c.round_trip_p50_us();
    client.round_trip_p99_us = c.round_trip_p99_us();
    client.round_trip_p999_us = c.round_trip_p999_us();
  }
  if (s.has_federation()) {
    const v1::FederationStats& f = s.federation();
    FederationStats& federation = out.federation.emplace();
    federation.samples_published = f.samples_published();
    federation.samples_failed = f.samples_failed();
    federation.items_published = f.items_published();
    federation.items_applied = f.items_applied();
    federation.items_refused = f.items_refused();
    federation.wrenches_accepted = f.wrenches_accepted();
    federation.wrenches_refused = f.wrenches_refused();
    federation.samples_refused = f.samples_refused();
    federation.energy_refused_j = f.energy_refused_j();
    federation.sites_cut_off = f.sites_cut_off();
    for (const v1::CouplingStats& c : f.couplings()) {
      federation.couplings.push_back(
          {c.kind() == v1::CouplingStats::MASS ? CouplingStats::Kind::kMass : CouplingStats::Kind::kTool, c.port(),
           c.remote(), c.mass(), c.injected_j(), c.given_j(), c.sent_j(), c.received_j(), c.reservoir_j()});
    }
  }
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
  out.buttons = s.buttons();
  if (s.has_orientation()) out.orientation = from_proto(s.orientation());
  if (s.has_torque()) out.torque = from_proto(s.torque());
  out.received_at = std::chrono::steady_clock::now();
  return out;
}

Event from_proto(const v1::Event& e) {
  Event out;
  switch (e.kind()) {
    case v1::Event::SESSION_OPENED: out.kind = Event::Kind::kSessionOpened; break;
    case v1::Event::SESSION_CLOSED: out.kind = Event::Kind::kSessionClosed; break;
    case v1::Event::LEASE_EXPIRED: out.kind = Event::Kind::kLeaseExpired; break;
    case v1::Event::SCENE_CHANGED: out.kind = Event::Kind::kSceneChanged; break;
    case v1::Event::FORCE_FAULT: out.kind = Event::Kind::kForceFault; break;
    case v1::Event::WATCH_STARTED: out.kind = Event::Kind::kWatchStarted; break;
    case v1::Event::DEVICE_FAULT: out.kind = Event::Kind::kDeviceFault; break;
    case v1::Event::RESET: out.kind = Event::Kind::kReset; break;
    default: out.kind = Event::Kind::kUnknown; break;
  }
  out.session_id = e.session_id();
  out.server_time = e.server_time_s();
  out.message = e.message();
  out.item_id = e.item_id();
  return out;
}

SessionSummary from_proto(const v1::SessionSummary& session) {
  SessionSummary out;
  out.session_id = session.session_id();
  out.client_name = session.client_name();
  out.device_index = session.device_index();
  out.peer = session.peer();
  out.token_name = session.token_name();
  switch (session.role()) {
    case v1::OBSERVER: out.role = Role::kObserver; break;
    case v1::CONTROLLER: out.role = Role::kController; break;
    case v1::ADMIN: out.role = Role::kAdmin; break;
    default: out.role = Role::kNone; break;
  }
  out.opened_time = session.opened_s();
  return out;
}

}  // namespace haptic::detail
