// The SDK's value types in Python: what a client sends (specs, impedances, operator inputs) and
// what the server reports (state, device, stability, statistics, events). SI units throughout;
// positions, velocities and forces in the device's world frame W.

#include <pybind11/stl.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "bindings.hpp"
#include "binding_support.hpp"
#include "haptic/haptic.hpp"

namespace haptic::python {

namespace {

void bind_enums(py::module_& m) {
  py::enum_<ImpedanceLaw>(m, "ImpedanceLaw", "How penetration becomes force (docs/scene.md).")
      .value("VELOCITY", ImpedanceLaw::kVelocity, "K d − B v·n with the measured velocity")
      .value("BACKWARD_DIFFERENCE", ImpedanceLaw::kBackwardDifference, "K d + B ḋ + M d̈, sampled")
      .value("EXACT_ZOH", ImpedanceLaw::kExactZoh, "the exact zero-order-hold spring-damper")
      .value("TUSTIN", ImpedanceLaw::kTustin, "bilinear; refused with damping > 0");
  py::enum_<Role>(m, "Role", "What a server's bearer token lets its holder do.")
      .value("NONE", Role::kNone)
      .value("OBSERVER", Role::kObserver)
      .value("CONTROLLER", Role::kController)
      .value("ADMIN", Role::kAdmin);
  py::enum_<StateFlag>(m, "StateFlag", "Bits of State.flags.", py::arithmetic())
      .value("FORCE_SATURATED", kForceSaturated)
      .value("FORCE_FAULT", kForceFault)
      .value("RAMPING_OUT", kRampingOut)
      .value("DEVICE_FAULT", kDeviceFault);
}

// The doc of every spec's across_sites (types.hpp).
constexpr const char* kAcrossSites =
    "shared with the other sites of a federation; refused by a server not in one";

void bind_scene_specs(py::module_& m) {
  StructBinder<Impedance>(m, "Impedance", "A virtual spring-damper with optional Coulomb friction.")
      .field("stiffness", &Impedance::stiffness, "N/m, finite, >= 0")
      .field("damping", &Impedance::damping, "N·s/m, finite, >= 0")
      .field("static_friction", &Impedance::static_friction, "μ_s >= 0")
      .field("dynamic_friction", &Impedance::dynamic_friction, "0 <= μ_d <= μ_s")
      .field("law", &Impedance::law, "ImpedanceLaw")
      .field("mass", &Impedance::mass, "M of the discrete laws, kg")
      .field("transparency_optimal_damping", &Impedance::transparency_optimal_damping,
             "let the server choose the transparency-optimal damping (001)")
      .field("virtual_coupling", &Impedance::virtual_coupling,
             "let the server replace K and B by a coupling passive on its device")
      .finish();
  StructBinder<Pose>(m, "Pose", "An origin (m) and orientation (w, x, y, z) in W.")
      .field("position", &Pose::position, "m")
      .field("orientation", &Pose::orientation, "unit quaternion (w, x, y, z)")
      .finish();
  StructBinder<Dynamics>(m, "Dynamics", "A virtual mass the tool can push: m ẍ + B ẋ = f.")
      .field("mass", &Dynamics::mass, "kg; 0: the object is fixed")
      .field("damping", &Dynamics::damping, "viscous friction with the ground, N·s/m")
      .finish();
  StructBinder<WallSpec>(m, "WallSpec", "A half-space wall: the solid lies behind `point` along −normal.")
      .field("point", &WallSpec::point, "m")
      .field("normal", &WallSpec::normal, "non-zero; normalised by the server")
      .field("impedance", &WallSpec::impedance, "Impedance")
      .field("shared", &WallSpec::shared, "any session may update it")
      .field("across_sites", &WallSpec::across_sites, kAcrossSites)
      .finish();
  StructBinder<SphereSpec>(m, "SphereSpec", "A solid sphere the tool is pushed out of.")
      .field("center", &SphereSpec::center, "m")
      .field("radius", &SphereSpec::radius, "m, > 0")
      .field("impedance", &SphereSpec::impedance, "Impedance")
      .field("dynamics", &SphereSpec::dynamics, "mass > 0: it can be pushed around")
      .field("shared", &SphereSpec::shared, "any session may update it")
      .field("across_sites", &SphereSpec::across_sites, kAcrossSites)
      .finish();
  StructBinder<BoxSpec>(m, "BoxSpec", "A solid box centred on its pose.")
      .field("pose", &BoxSpec::pose, "Pose")
      .field("half_extents", &BoxSpec::half_extents, "m, each > 0")
      .field("impedance", &BoxSpec::impedance, "Impedance")
      .field("dynamics", &BoxSpec::dynamics, "Dynamics")
      .field("shared", &BoxSpec::shared, "any session may update it")
      .field("across_sites", &BoxSpec::across_sites, kAcrossSites)
      .finish();
  StructBinder<CapsuleSpec>(m, "CapsuleSpec", "A solid capsule along its pose's z axis.")
      .field("pose", &CapsuleSpec::pose, "Pose")
      .field("radius", &CapsuleSpec::radius, "m, > 0")
      .field("half_length", &CapsuleSpec::half_length, "m, >= 0")
      .field("impedance", &CapsuleSpec::impedance, "Impedance")
      .field("dynamics", &CapsuleSpec::dynamics, "Dynamics")
      .field("shared", &CapsuleSpec::shared, "any session may update it")
      .field("across_sites", &CapsuleSpec::across_sites, kAcrossSites)
      .finish();
  StructBinder<MeshSpec>(m, "MeshSpec", "A triangle mesh in its pose's frame (god-object rendering).")
      .field("pose", &MeshSpec::pose, "Pose")
      .property(
          "vertices", [](const MeshSpec& mesh) { return points_to_array(mesh.vertices); },
          [](MeshSpec& mesh, const py::object& array) {
            mesh.vertices = points_from_array(array, "MeshSpec.vertices");
          },
          "(N, 3) array, m, in the object frame")
      .property(
          "indices",
          [](const MeshSpec& mesh) {
            py::array_t<std::uint32_t> array(static_cast<py::ssize_t>(mesh.indices.size()));
            std::copy(mesh.indices.begin(), mesh.indices.end(), array.mutable_data());
            return array;
          },
          [](MeshSpec& mesh, const py::object& array) {
            mesh.indices = indices_from_array(array, "MeshSpec.indices");
          },
          "three vertex indices per triangle: (3T,) or (T, 3) array")
      .field("impedance", &MeshSpec::impedance, "Impedance")
      .field("shared", &MeshSpec::shared, "any session may update it")
      .field("across_sites", &MeshSpec::across_sites, kAcrossSites)
      .finish();
  StructBinder<TangentPlaneSpec>(m, "TangentPlaneSpec",
                                 "Russo's tangent-plane local model (004), for a slow host.")
      .field("pose", &TangentPlaneSpec::pose, "Pose")
      .field("normal", &TangentPlaneSpec::normal, "outward, object frame")
      .field("reference", &TangentPlaneSpec::reference, "object frame, m")
      .field("tangential_stiffness", &TangentPlaneSpec::tangential_stiffness, "N/m")
      .field("tangential_damping", &TangentPlaneSpec::tangential_damping, "N·s/m")
      .field("impedance", &TangentPlaneSpec::impedance, "Impedance")
      .field("across_sites", &TangentPlaneSpec::across_sites, kAcrossSites)
      .finish();

  StructBinder<SpringFieldSpec>(m, "SpringFieldSpec", "F = −k (p − anchor) − b v, clipped to max_force.")
      .field("anchor", &SpringFieldSpec::anchor, "m")
      .field("stiffness", &SpringFieldSpec::stiffness, "N/m")
      .field("damping", &SpringFieldSpec::damping, "N·s/m")
      .field("max_force", &SpringFieldSpec::max_force, "N; 0: no clip")
      .field("across_sites", &SpringFieldSpec::across_sites, kAcrossSites)
      .finish();
  StructBinder<Distance> distance(m, "Distance", "A distance function the fields are built on.");
  py::enum_<Distance::Kind>(distance.cls(), "Kind")
      .value("POINT", Distance::Kind::kPoint)
      .value("LINE", Distance::Kind::kLine)
      .value("PLANE", Distance::Kind::kPlane)
      .value("SPHERE", Distance::Kind::kSphere);
  distance.field("kind", &Distance::kind, "Distance.Kind")
      .field("origin", &Distance::origin, "m")
      .field("axis", &Distance::axis, "LINE: direction; PLANE: normal")
      .field("radius", &Distance::radius, "SPHERE, m")
      .finish();
  StructBinder<DistanceSpringSpec>(m, "DistanceSpringSpec", "A spring onto a point, line or plane.")
      .field("anchor", &DistanceSpringSpec::anchor, "Distance")
      .field("stiffness", &DistanceSpringSpec::stiffness, "N/m")
      .field("damping", &DistanceSpringSpec::damping, "N·s/m")
      .field("max_force", &DistanceSpringSpec::max_force, "N; 0: no clip")
      .field("across_sites", &DistanceSpringSpec::across_sites, kAcrossSites)
      .finish();
  StructBinder<PotentialFieldSpec> potential(
      m, "PotentialFieldSpec", "F = −∇U over a distance: polynomial or Khatib (004 eqs. 5.6–5.7).");
  py::enum_<PotentialFieldSpec::Kind>(potential.cls(), "Kind")
      .value("POLYNOMIAL", PotentialFieldSpec::Kind::kPolynomial)
      .value("KHATIB", PotentialFieldSpec::Kind::kKhatib);
  potential.field("distance", &PotentialFieldSpec::distance, "Distance")
      .field("kind", &PotentialFieldSpec::kind, "PotentialFieldSpec.Kind")
      .field("order", &PotentialFieldSpec::order, "n, 2 … 8")
      .field("gain", &PotentialFieldSpec::gain, "K")
      .field("offset", &PotentialFieldSpec::offset, "c (polynomial), m")
      .field("influence_distance", &PotentialFieldSpec::influence_distance, "f0 (Khatib), m")
      .field("min_distance", &PotentialFieldSpec::min_distance, "Khatib's force is capped below, m")
      .field("central_differences", &PotentialFieldSpec::central_differences,
             "gradient by central differences instead of analytic")
      .field("across_sites", &PotentialFieldSpec::across_sites, kAcrossSites)
      .finish();
  StructBinder<LinearFieldSpec>(m, "LinearFieldSpec",
                                "F = F0 + K (p − origin) inside radius, fading to zero.")
      .field("origin", &LinearFieldSpec::origin, "m")
      .field("force", &LinearFieldSpec::force, "F0, N")
      .property(
          "jacobian",
          [](const LinearFieldSpec& field) {
            return points_to_array({field.jacobian[0], field.jacobian[1], field.jacobian[2]});
          },
          [](LinearFieldSpec& field, const py::object& array) {
            const std::vector<Vec3> rows = points_from_array(array, "LinearFieldSpec.jacobian");
            if (rows.size() != 3) {
              throw py::value_error("LinearFieldSpec.jacobian: expected a (3, 3) array, got " +
                                    std::to_string(rows.size()) + " rows");
            }
            for (int i = 0; i < 3; ++i) field.jacobian[i] = rows[static_cast<std::size_t>(i)];
          },
          "K as a (3, 3) array of rows, N/m")
      .field("radius", &LinearFieldSpec::radius, "m")
      .field("fade_width", &LinearFieldSpec::fade_width, "m")
      .field("across_sites", &LinearFieldSpec::across_sites, kAcrossSites)
      .finish();
  StructBinder<ViscousFieldSpec>(m, "ViscousFieldSpec", "F = −B v, everywhere or inside a sphere.")
      .field("damping", &ViscousFieldSpec::damping, "N·s/m")
      .field("center", &ViscousFieldSpec::center, "m")
      .field("radius", &ViscousFieldSpec::radius, "m; 0: everywhere")
      .field("fade_width", &ViscousFieldSpec::fade_width, "m")
      .field("across_sites", &ViscousFieldSpec::across_sites, kAcrossSites)
      .finish();
  StructBinder<DetentFieldSpec>(m, "DetentFieldSpec", "A potential well with a repulsive rim.")
      .field("distance", &DetentFieldSpec::distance, "Distance")
      .field("depth", &DetentFieldSpec::depth, "J")
      .field("radius", &DetentFieldSpec::radius, "m")
      .field("rim_height", &DetentFieldSpec::rim_height, "J")
      .field("rim_width", &DetentFieldSpec::rim_width, "m")
      .field("across_sites", &DetentFieldSpec::across_sites, kAcrossSites)
      .finish();
  StructBinder<OrientationSpringSpec>(m, "OrientationSpringSpec",
                                      "A rotational spring-damper pulling the tool's orientation "
                                      "towards target: τ = −K θ − B ω, in W.")
      .field("target", &OrientationSpringSpec::target, "R_WG, unit quaternion (w, x, y, z)")
      .field("stiffness", &OrientationSpringSpec::stiffness, "K, N·m/rad, finite, >= 0")
      .field("damping", &OrientationSpringSpec::damping, "B, N·m·s/rad, finite, >= 0")
      .field("max_torque", &OrientationSpringSpec::max_torque, "N·m; 0: no clip")
      .field("law", &OrientationSpringSpec::law, "ImpedanceLaw (VELOCITY: the measured ω)")
      .field("across_sites", &OrientationSpringSpec::across_sites, kAcrossSites)
      .finish();
  StructBinder<OrientationDetentSpec>(m, "OrientationDetentSpec",
                                      "A potential well with a repulsive rim over the angle "
                                      "between the tool's orientation and target.")
      .field("target", &OrientationDetentSpec::target, "R_WG, unit quaternion (w, x, y, z)")
      .field("depth", &OrientationDetentSpec::depth, "J, > 0")
      .field("radius", &OrientationDetentSpec::radius, "rad, > 0")
      .field("rim_height", &OrientationDetentSpec::rim_height, "J, >= 0")
      .field("rim_width", &OrientationDetentSpec::rim_width, "rad")
      .field("damping", &OrientationDetentSpec::damping, "N·m·s/rad, inside radius + rim_width")
      .field("across_sites", &OrientationDetentSpec::across_sites, kAcrossSites)
      .finish();

  StructBinder<SceneSpec>(m, "SceneSpec",
                          "A whole scene for Client.apply_scene. objects and fields are lists: "
                          "assign whole lists (appending to the attribute changes a copy).")
      .field("objects", &SceneSpec::objects, "WallSpec, SphereSpec, BoxSpec, CapsuleSpec, "
                                              "TangentPlaneSpec or MeshSpec, in order")
      .field("fields", &SceneSpec::fields, "SpringFieldSpec, DistanceSpringSpec, "
                                            "PotentialFieldSpec, LinearFieldSpec, "
                                            "ViscousFieldSpec, DetentFieldSpec, "
                                            "OrientationSpringSpec or OrientationDetentSpec, in order")
      .finish();
  StructBinder<RegisteredScene>(m, "RegisteredScene", "A scene read back from the server.")
      .readonly("scene", &RegisteredScene::scene, "SceneSpec, each item as last given")
      .readonly("object_ids", &RegisteredScene::object_ids, "ids, in the order of scene.objects")
      .readonly("field_ids", &RegisteredScene::field_ids, "ids, in the order of scene.fields")
      .readonly("object_sessions", &RegisteredScene::object_sessions, "0: the server's own")
      .readonly("field_sessions", &RegisteredScene::field_sessions, "0: the server's own")
      .finish();
}

void bind_operator(py::module_& m) {
  StructBinder<OperatorInput> input(
      m, "OperatorInput",
      "What the server's simulated operator (a hand holding the tool) does. Build one with "
      "follow(), follow_line(), push(), push_recorded() or release().");
  py::enum_<OperatorInput::Mode>(input.cls(), "Mode")
      .value("RELEASE", OperatorInput::Mode::kRelease)
      .value("FOLLOW", OperatorInput::Mode::kFollow)
      .value("PUSH", OperatorInput::Mode::kPush);
  py::enum_<OperatorInput::Grip>(input.cls(), "Grip")
      .value("CUSTOM", OperatorInput::Grip::kCustom, "mass, stiffness and damping as given")
      .value("LOOSE", OperatorInput::Grip::kLoose, "0.2 kg, 2 N/m, 3 N·s/m")
      .value("TIGHT", OperatorInput::Grip::kTight, "2 kg, 800 N/m, 15 N·s/m");
  StructBinder<OperatorInput::Path> path(input.cls(), "Path", "How the target moves (FOLLOW).");
  py::enum_<OperatorInput::Path::Shape>(path.cls(), "Shape")
      .value("FIXED", OperatorInput::Path::Shape::kFixed)
      .value("LINE", OperatorInput::Path::Shape::kLine)
      .value("SINE", OperatorInput::Path::Shape::kSine);
  path.field("shape", &OperatorInput::Path::shape, "Path.Shape")
      .field("end", &OperatorInput::Path::end, "LINE: to here over duration_s, m")
      .field("duration_s", &OperatorInput::Path::duration_s, "s")
      .field("amplitude", &OperatorInput::Path::amplitude, "SINE: target + amplitude sin(2π f t), m")
      .field("frequency_hz", &OperatorInput::Path::frequency_hz, "Hz")
      .finish();
  StructBinder<OperatorInput::Profile> profile(input.cls(), "Profile",
                                               "How the pushing force changes (PUSH).");
  py::enum_<OperatorInput::Profile::Shape>(profile.cls(), "Shape")
      .value("CONSTANT", OperatorInput::Profile::Shape::kConstant)
      .value("STEP", OperatorInput::Profile::Shape::kStep)
      .value("RAMP", OperatorInput::Profile::Shape::kRamp)
      .value("SINE", OperatorInput::Profile::Shape::kSine)
      .value("RECORDED", OperatorInput::Profile::Shape::kRecorded);
  profile.field("shape", &OperatorInput::Profile::shape, "Profile.Shape")
      .field("start_s", &OperatorInput::Profile::start_s, "STEP, RAMP: when it begins, s")
      .field("rise_s", &OperatorInput::Profile::rise_s, "RAMP: rise time, s")
      .field("frequency_hz", &OperatorInput::Profile::frequency_hz, "SINE, Hz")
      .field("offset", &OperatorInput::Profile::offset, "SINE, N")
      .property(
          "samples",
          [](const OperatorInput::Profile& p) { return points_to_array(p.samples); },
          [](OperatorInput::Profile& p, const py::object& array) {
            p.samples = points_from_array(array, "OperatorInput.Profile.samples");
          },
          "RECORDED: (N, 3) forces one every sample_period_s, N, in W")
      .field("sample_period_s", &OperatorInput::Profile::sample_period_s, "RECORDED, s")
      .field("repeat", &OperatorInput::Profile::repeat, "RECORDED: wrap round after the last")
      .finish();
  input.field("mode", &OperatorInput::mode, "OperatorInput.Mode")
      .field("target", &OperatorInput::target, "FOLLOW: where the hand pulls the tool, m")
      .field("stiffness", &OperatorInput::stiffness, "FOLLOW, CUSTOM grip: N/m")
      .field("damping", &OperatorInput::damping, "FOLLOW, CUSTOM grip: N·s/m")
      .field("mass", &OperatorInput::mass, "FOLLOW, CUSTOM grip: hand mass, kg")
      .field("grip", &OperatorInput::grip, "OperatorInput.Grip")
      .field("path", &OperatorInput::path, "OperatorInput.Path")
      .field("force", &OperatorInput::force, "PUSH: the force (the profile's amplitude), N")
      .field("profile", &OperatorInput::profile, "OperatorInput.Profile")
      .finish();
  input.cls()
      .def_static("follow", &OperatorInput::follow, py::arg("target"), py::arg("stiffness"),
                  py::arg("damping"), "The hand pulls the tool towards target like a spring-damper.")
      .def_static("follow_line", &OperatorInput::follow_line, py::arg("start"), py::arg("end"),
                  py::arg("duration_s"), py::arg("grip"),
                  "A LOOSE or TIGHT grip whose target moves from start to end in duration_s.")
      .def_static("push", py::overload_cast<Vec3>(&OperatorInput::push), py::arg("force"),
                  "The hand pushes with a constant force (N).")
      .def_static("push", py::overload_cast<Vec3, OperatorInput::Profile>(&OperatorInput::push),
                  py::arg("force"), py::arg("profile"),
                  "The hand pushes with a force (N) that follows profile.")
      .def_static(
          "push_recorded",
          [](const py::object& samples, double sample_period_s, bool repeat) {
            return OperatorInput::push_recorded(
                points_from_array(samples, "OperatorInput.push_recorded samples"), sample_period_s,
                repeat);
          },
          py::arg("samples"), py::arg("sample_period_s"), py::arg("repeat") = false,
          "The hand pushes with recorded forces: an (N, 3) array, one every sample_period_s.")
      .def_static("release", &OperatorInput::release, "The hand lets go.");
}

void bind_reports(py::module_& m) {
  StructBinder<State>(m, "State",
                      "One tick's sample as the server streamed it. Vectors are float64 arrays in "
                      "W; times are seconds (received_at and arrived_at on time.monotonic()'s clock).")
      .readonly("tick", &State::tick, "server loop tick")
      .readonly("sequence", &State::sequence, "datagram sequence; 0 from a step() reply")
      .readonly("server_time", &State::server_time, "s")
      .readonly("position", &State::position, "tool position p_WT, m")
      .readonly("velocity", &State::velocity, "tool velocity, m/s")
      .readonly("force", &State::force, "force commanded on the tool, N")
      .readonly("proxy", &State::proxy, "contact (proxy) point; the position out of contact, m")
      .readonly("contact_count", &State::contact_count, "contacts this tick")
      .readonly("flags", &State::flags, "StateFlag bits")
      .readonly("buttons", &State::buttons, "bit i: button i")
      .readonly("orientation", &State::orientation, "(w, x, y, z) or None")
      .readonly("torque", &State::torque,
                "torque commanded on the tool τ_T_W in W, N·m; None exactly when orientation is")
      .readonly_property(
          "received_at", [](const State& s) { return monotonic_seconds(s.received_at); },
          "local receipt time, s on time.monotonic()'s clock")
      .readonly_property(
          "arrived_at",
          [](const State& s) -> std::optional<double> {
            if (!s.arrived_at) return std::nullopt;
            return monotonic_seconds(*s.arrived_at);
          },
          "the kernel's receive stamp, s on time.monotonic()'s clock; None without one")
      .readonly_property(
          "age", [](const State& s) { return std::chrono::duration<double>(s.age).count(); },
          "how much longer it took to arrive than the quickest recent sample, s")
      .finish();

  StructBinder<DeviceCapabilities>(m, "DeviceCapabilities", "What a device has.")
      .readonly("gravity", &DeviceCapabilities::gravity, "")
      .readonly("brakes", &DeviceCapabilities::brakes, "")
      .readonly("flexible_modes", &DeviceCapabilities::flexible_modes, "")
      .readonly("friction", &DeviceCapabilities::friction, "")
      .readonly("force_sensor", &DeviceCapabilities::force_sensor, "")
      .readonly("quantized_position", &DeviceCapabilities::quantized_position, "")
      .readonly("state_estimator", &DeviceCapabilities::state_estimator, "")
      .readonly("disturbance_observer", &DeviceCapabilities::disturbance_observer, "")
      .readonly("orientation", &DeviceCapabilities::orientation, "")
      .readonly("torque", &DeviceCapabilities::torque, "")
      .finish();
  StructBinder<DeviceInfo>(m, "DeviceInfo", "The device, as reported when the session opened.")
      .readonly("name", &DeviceInfo::name, "")
      .readonly("model", &DeviceInfo::model, "point_mass, dc_motor_000, five_bar_003, …")
      .readonly("capabilities", &DeviceInfo::capabilities, "DeviceCapabilities")
      .readonly("dof", &DeviceInfo::dof, "")
      .readonly("workspace_min", &DeviceInfo::workspace_min, "m")
      .readonly("workspace_max", &DeviceInfo::workspace_max, "m")
      .readonly("max_force", &DeviceInfo::max_force, "N")
      .readonly("loop_rate_hz", &DeviceInfo::loop_rate_hz, "Hz")
      .readonly("simulated", &DeviceInfo::simulated, "")
      .readonly("buttons", &DeviceInfo::buttons, "buttons reported in State.buttons")
      .readonly("max_torque", &DeviceInfo::max_torque, "N·m (capabilities.torque)")
      .finish();
  StructBinder<StabilityReport>(m, "StabilityReport",
                                "What the server can say about an object's impedance on its device.")
      .readonly("colgate_min_damping", &StabilityReport::colgate_min_damping, "K T / 2 + |B|, N·s/m")
      .readonly("device_mass", &StabilityReport::device_mass, "kg; 0: no model")
      .readonly("device_damping", &StabilityReport::device_damping, "N·s/m")
      .readonly("passive", &StabilityReport::passive, "")
      .readonly("device_known", &StabilityReport::device_known, "")
      .readonly("stable", &StabilityReport::stable, "the sampled loop in contact is stable")
      .readonly("max_stable_stiffness", &StabilityReport::max_stable_stiffness, "N/m")
      .readonly("max_pole_magnitude", &StabilityReport::max_pole_magnitude, "")
      .readonly("chosen_damping", &StabilityReport::chosen_damping, "N·s/m")
      .readonly("chosen_stiffness", &StabilityReport::chosen_stiffness, "N/m")
      .readonly("robustly_stable", &StabilityReport::robustly_stable, "‖L‖∞ ≤ 1 (001 eq. 17)")
      .readonly("warning", &StabilityReport::warning, "why contact may not stay stable")
      .finish();
  StructBinder<ObjectState>(m, "ObjectState", "Where a virtual mass has been pushed to.")
      .readonly("id", &ObjectState::id, "")
      .readonly("position", &ObjectState::position, "m")
      .readonly("velocity", &ObjectState::velocity, "m/s")
      .finish();
  StructBinder<ItemEnergy>(m, "ItemEnergy", "Work an object or field has exchanged with the device.")
      .readonly("id", &ItemEnergy::id, "")
      .readonly("session_id", &ItemEnergy::session_id, "0: the server's own scene")
      .readonly("is_object", &ItemEnergy::is_object, "")
      .readonly("given_to_device", &ItemEnergy::given_to_device, "J")
      .readonly("absorbed_from_device", &ItemEnergy::absorbed_from_device, "J")
      .finish();
  StructBinder<ClientStats>(m, "ClientStats", "One client's state stream, as Stats reports it.")
      .readonly("session_id", &ClientStats::session_id, "")
      .readonly("client_name", &ClientStats::client_name, "")
      .readonly("peer", &ClientStats::peer, "")
      .readonly("device_index", &ClientStats::device_index, "")
      .readonly("decimation", &ClientStats::decimation, "0: no subscription")
      .readonly("datagrams_sent", &ClientStats::datagrams_sent, "")
      .readonly("heartbeats", &ClientStats::heartbeats, "")
      .readonly("states_received", &ClientStats::states_received, "")
      .readonly("states_lost", &ClientStats::states_lost, "")
      .readonly("ack_window", &ClientStats::ack_window, "lockstep flow control granted; 0: none")
      .readonly("acknowledged_sequence", &ClientStats::acknowledged_sequence, "")
      .readonly("samples_unsent", &ClientStats::samples_unsent, "numbered for it, never sent")
      .readonly("last_heartbeat_age_s", &ClientStats::last_heartbeat_age_s, "s; -1: none yet")
      .readonly("round_trip_samples", &ClientStats::round_trip_samples, "")
      .readonly("round_trip_p50_us", &ClientStats::round_trip_p50_us, "µs")
      .readonly("round_trip_p99_us", &ClientStats::round_trip_p99_us, "µs")
      .readonly("round_trip_p999_us", &ClientStats::round_trip_p999_us, "µs")
      .finish();
  StructBinder<CouplingStats> coupling(
      m, "CouplingStats",
      "One coupling across a federation's network: its passivity layer's books at this site, "
      "cumulative since it began (docs/federation.md).");
  py::enum_<CouplingStats::Kind>(coupling.cls(), "Kind")
      .value("TOOL", CouplingStats::Kind::kTool, "this site's tool at `port` and a remote tool")
      .value("MASS", CouplingStats::Kind::kMass, "this site's copy of `mass` and another site's");
  coupling.readonly("kind", &CouplingStats::kind, "CouplingStats.Kind")
      .readonly("port", &CouplingStats::port, "TOOL: this site's device port")
      .readonly("remote", &CouplingStats::remote, "TOOL: the remote tool's key; MASS: the other site's")
      .readonly("mass", &CouplingStats::mass, "MASS: the mass's key")
      .readonly("injected_j", &CouplingStats::injected_j, "J, put in by this site's user (or copy)")
      .readonly("given_j", &CouplingStats::given_j, "J, given to this site's user (or copy)")
      .readonly("sent_j", &CouplingStats::sent_j, "J, sent to the other site")
      .readonly("received_j", &CouplingStats::received_j, "J, received from it")
      .readonly("reservoir_j", &CouplingStats::reservoir_j,
                "J, held here now: injected − given + received − sent")
      .finish();
  StructBinder<FederationStats>(m, "FederationStats",
                                "What crossed between the sites of a federation (Stats.federation).")
      .readonly("samples_published", &FederationStats::samples_published,
                "tool and mass-copy samples this site published")
      .readonly("samples_failed", &FederationStats::samples_failed, "publications DDS refused")
      .readonly("items_published", &FederationStats::items_published,
                "versions of this site's across_sites items sent")
      .readonly("items_applied", &FederationStats::items_applied,
                "other sites' item versions applied here")
      .readonly("items_refused", &FederationStats::items_refused, "refused by this site's checks")
      .readonly("wrenches_accepted", &FederationStats::wrenches_accepted, "ROS 2 wrenches taken in")
      .readonly("wrenches_refused", &FederationStats::wrenches_refused, "refused (frame, NaN)")
      .readonly("samples_refused", &FederationStats::samples_refused,
                "other sites' tool and mass samples refused (another site's name, NaN, cut off)")
      .readonly("energy_refused_j", &FederationStats::energy_refused_j,
                "energy other sites claimed and were not credited (over the cap), J")
      .readonly("sites_cut_off", &FederationStats::sites_cut_off, "sites cut off: their energy books did not add up")
      .readonly("couplings", &FederationStats::couplings, "list of CouplingStats")
      .finish();
  StructBinder<Stats>(m, "Stats", "The server's counters (GetStats).")
      .readonly("ticks", &Stats::ticks, "")
      .readonly("achieved_rate_hz", &Stats::achieved_rate_hz, "Hz")
      .readonly("lateness_p50_us", &Stats::lateness_p50_us, "µs")
      .readonly("lateness_p99_us", &Stats::lateness_p99_us, "µs")
      .readonly("lateness_max_us", &Stats::lateness_max_us, "µs")
      .readonly("lateness_p999_us", &Stats::lateness_p999_us, "µs")
      .readonly("lateness_samples", &Stats::lateness_samples, "ticks in the window")
      .readonly("window_s", &Stats::window_s, "s")
      .readonly("overruns", &Stats::overruns, "")
      .readonly("sessions", &Stats::sessions, "")
      .readonly("objects", &Stats::objects, "")
      .readonly("fields", &Stats::fields, "")
      .readonly("datagrams_sent", &Stats::datagrams_sent, "")
      .readonly("datagrams_received", &Stats::datagrams_received, "")
      .readonly("datagrams_dropped", &Stats::datagrams_dropped, "")
      .readonly("force_faults", &Stats::force_faults, "")
      .readonly("force_saturations", &Stats::force_saturations, "")
      .readonly("passivity_active_ticks", &Stats::passivity_active_ticks, "")
      .readonly("leases_expired", &Stats::leases_expired, "")
      .readonly("device_faults", &Stats::device_faults, "")
      .readonly("send_delay_p50_us", &Stats::send_delay_p50_us, "µs")
      .readonly("send_delay_p99_us", &Stats::send_delay_p99_us, "µs")
      .readonly("send_delay_p999_us", &Stats::send_delay_p999_us, "µs")
      .readonly("heartbeats_rate_limited", &Stats::heartbeats_rate_limited, "")
      .readonly("datagrams_foreign_source", &Stats::datagrams_foreign_source, "")
      .readonly("path_challenges_sent", &Stats::path_challenges_sent, "")
      .readonly("samples_skipped", &Stats::samples_skipped, "")
      .readonly("samples_missed", &Stats::samples_missed, "")
      .readonly("ack_stalls", &Stats::ack_stalls, "")
      .readonly("connections_open", &Stats::connections_open, "")
      .readonly("connections_refused", &Stats::connections_refused, "")
      .readonly("connections_timed_out", &Stats::connections_timed_out,
                "no TLS handshake or HTTP/2 preface within handshake_timeout_ms")
      .readonly("connections_evicted", &Stats::connections_evicted,
                "closed at max_connections for a host holding fewer")
      .readonly("tls_handshakes_failed", &Stats::tls_handshakes_failed, "")
      .readonly("clients", &Stats::clients, "list of ClientStats, in session id order")
      .readonly("federation", &Stats::federation,
                "FederationStats; None for a server without a federation section")
      .finish();
  StructBinder<SessionSummary>(m, "SessionSummary", "One open session, as an admin sees it.")
      .readonly("session_id", &SessionSummary::session_id, "")
      .readonly("client_name", &SessionSummary::client_name, "")
      .readonly("device_index", &SessionSummary::device_index, "")
      .readonly("peer", &SessionSummary::peer, "")
      .readonly("token_name", &SessionSummary::token_name, "")
      .readonly("role", &SessionSummary::role, "Role")
      .readonly("opened_time", &SessionSummary::opened_time, "server time, s")
      .finish();
  StructBinder<RecordingStatus>(m, "RecordingStatus", "A recording on the server.")
      .readonly("path", &RecordingStatus::path, "on the server")
      .readonly("start_tick", &RecordingStatus::start_tick, "")
      .readonly("samples", &RecordingStatus::samples, "")
      .readonly("samples_missed", &RecordingStatus::samples_missed, "")
      .readonly("changes", &RecordingStatus::changes, "")
      .readonly("records_not_written", &RecordingStatus::records_not_written,
                "records a failed write kept from the file (0: whole)")
      .readonly("write_error", &RecordingStatus::write_error, "the first failed write; empty if none")
      .finish();
  StructBinder<ReceiveCounters>(m, "ReceiveCounters", "What the SDK's UDP receiver has seen.")
      .readonly("accepted", &ReceiveCounters::accepted, "")
      .readonly("rejected", &ReceiveCounters::rejected, "")
      .readonly("skipped", &ReceiveCounters::skipped, "")
      .readonly("challenges_answered", &ReceiveCounters::challenges_answered, "")
      .readonly("callback_skipped", &ReceiveCounters::callback_skipped, "")
      .readonly("lost", &ReceiveCounters::lost, "")
      .readonly("reordered", &ReceiveCounters::reordered, "")
      .readonly("duplicates", &ReceiveCounters::duplicates, "")
      .readonly("reconnects", &ReceiveCounters::reconnects, "")
      .finish();

  StructBinder<Event> event(m, "Event", "Something that happened on the server (Client.on_event).");
  py::enum_<Event::Kind>(event.cls(), "Kind")
      .value("UNKNOWN", Event::Kind::kUnknown)
      .value("SESSION_OPENED", Event::Kind::kSessionOpened)
      .value("SESSION_CLOSED", Event::Kind::kSessionClosed)
      .value("LEASE_EXPIRED", Event::Kind::kLeaseExpired)
      .value("SCENE_CHANGED", Event::Kind::kSceneChanged)
      .value("FORCE_FAULT", Event::Kind::kForceFault)
      .value("WATCH_STARTED", Event::Kind::kWatchStarted)
      .value("DEVICE_FAULT", Event::Kind::kDeviceFault)
      .value("RESET", Event::Kind::kReset);
  event.readonly("kind", &Event::kind, "Event.Kind")
      .readonly("session_id", &Event::session_id, "0: the server's own")
      .readonly("server_time", &Event::server_time, "s")
      .readonly("message", &Event::message, "")
      .readonly("item_id", &Event::item_id, "SCENE_CHANGED for one item: its id")
      .finish();
  StructBinder<ConnectionChange> change(m, "ConnectionChange",
                                        "A change of a Client's connection (Client.on_connection).");
  py::enum_<ConnectionChange::State>(change.cls(), "State")
      .value("CONNECTED", ConnectionChange::State::kConnected)
      .value("LOST", ConnectionChange::State::kLost)
      .value("RESUMED", ConnectionChange::State::kResumed)
      .value("ENDED", ConnectionChange::State::kEnded);
  change.readonly("state", &ConnectionChange::state, "ConnectionChange.State")
      .readonly("session_id", &ConnectionChange::session_id, "")
      .readonly("new_session", &ConnectionChange::new_session, "")
      .readonly("items_not_restored", &ConnectionChange::items_not_restored, "")
      .readonly("reason", &ConnectionChange::reason, "")
      .readonly_property(
          "outage", [](const ConnectionChange& c) { return seconds(c.outage); },
          "RESUMED: from the loss to the resumption, s")
      .finish();
}

}  // namespace

py::array_t<double> points_to_array(const std::vector<Vec3>& points) {
  py::array_t<double> array({static_cast<py::ssize_t>(points.size()), py::ssize_t{3}});
  auto out = array.mutable_unchecked<2>();
  for (std::size_t i = 0; i < points.size(); ++i) {
    const auto row = static_cast<py::ssize_t>(i);
    out(row, 0) = points[i].x;
    out(row, 1) = points[i].y;
    out(row, 2) = points[i].z;
  }
  return array;
}

std::vector<Vec3> points_from_array(const py::handle& source, const char* what) {
  const auto array = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(source);
  if (!array) {
    PyErr_Clear();
    throw py::value_error(std::string(what) + ": expected an (N, 3) array of numbers, got " +
                          py::repr(source).cast<std::string>());
  }
  const bool empty = array.size() == 0;
  if (!empty && (array.ndim() != 2 || array.shape(1) != 3)) {
    std::string shape;
    for (py::ssize_t i = 0; i < array.ndim(); ++i) {
      shape += (i > 0 ? ", " : "") + std::to_string(array.shape(i));
    }
    throw py::value_error(std::string(what) + ": expected an (N, 3) array, got shape (" + shape + ")");
  }
  std::vector<Vec3> points;
  if (empty) return points;
  const auto in = array.unchecked<2>();
  points.reserve(static_cast<std::size_t>(in.shape(0)));
  for (py::ssize_t i = 0; i < in.shape(0); ++i) points.push_back({in(i, 0), in(i, 1), in(i, 2)});
  return points;
}

std::vector<std::uint32_t> indices_from_array(const py::handle& source, const char* what) {
  const auto array = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>::ensure(source);
  if (!array) {
    PyErr_Clear();
    throw py::value_error(std::string(what) + ": expected an array of integers, got " +
                          py::repr(source).cast<std::string>());
  }
  std::vector<std::uint32_t> indices;
  indices.reserve(static_cast<std::size_t>(array.size()));
  const std::int64_t* data = array.data();
  for (py::ssize_t i = 0; i < array.size(); ++i) {
    if (data[i] < 0 || data[i] > std::int64_t{UINT32_MAX}) {
      throw py::value_error(std::string(what) + "[" + std::to_string(i) + "]: " +
                            std::to_string(data[i]) + " is not a vertex index (0 … 2³² − 1)");
    }
    indices.push_back(static_cast<std::uint32_t>(data[i]));
  }
  return indices;
}

void assign_fields(const py::object& target, const py::kwargs& values, const std::string& unknown) {
  const py::tuple fields = py::type::of(target).attr("_fields");
  const std::string type_name = py::type::of(target).attr("__name__").cast<std::string>();
  for (const auto& [key, item] : values) {
    const auto name = py::str(key).cast<std::string>();
    if (!fields.contains(key)) {
      std::string listed;
      for (const py::handle field : fields) listed += (listed.empty() ? "" : ", ") + field.cast<std::string>();
      throw py::type_error(unknown + " '" + name + "'; its fields: " + listed);
    }
    try {
      py::setattr(target, key, item);
    } catch (py::error_already_set& error) {
      if (!error.matches(PyExc_TypeError)) throw;
      // pybind11's refusal names the setter's parameter type: "... arg0: numpy.ndarray[3]) -> ...".
      const std::string refusal = error.what();
      const auto start = refusal.find("arg0: ");
      const auto end = refusal.find(") -> ", start);
      const std::string expected = start == std::string::npos || end == std::string::npos
                                       ? "another type"
                                       : refusal.substr(start + 6, end - start - 6);
      throw py::type_error(type_name + "." + name + ": cannot take " +
                           py::repr(item).cast<std::string>() + "; expected " + expected);
    }
  }
}

std::chrono::milliseconds milliseconds_from_seconds(double value, const char* what) {
  if (!std::isfinite(value) || value < 0.0) {
    throw py::value_error(std::string(what) + ": " + std::to_string(value) +
                          " s is not a duration (finite, >= 0)");
  }
  return std::chrono::milliseconds(static_cast<std::int64_t>(std::llround(value * 1e3)));
}

void bind_value_types(py::module_& m) {
  bind_enums(m);
  bind_scene_specs(m);
  bind_operator(m);
  bind_reports(m);
}

}  // namespace haptic::python
