// The study's document-device cases (study.hpp, device_cases): each is a hapticd configuration —
// the same text as its file under config/lab/, so any figure can be reproduced with
// `haptic-lab run --scene config/lab/<file>` — run in lockstep through simulate_scene (the
// server's own TickRunner) with the device's integrator and sub-step count replaced per run:
// step h = T / substeps, T the 1 ms tick. The loop itself (scene, force guard, passivity
// controller, observers, estimators) runs at T whatever h is, so what changes between runs is
// only how the plant is integrated between ticks.
//
// Observable: the tool position p_WT (m) as the device reports it, at every output sample, less
// its start p_WT(0), so that the study's relative errors are relative to how far the tool moved
// (the devices' tools sit 0.2 to 0.7 m from W's origin).
// Energy: the work the scene's force did on the tool minus the work the tool did against it
// (J, trapezoidal on F·v at the tick rate, lab_run); none for a scene without objects or fields.
// Sources: ../shared/research/seed-000-001.md (000, 001), seed-003-madill.md (003),
// seed-004-russo.md (004); docs/devices.md.

#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "config/server_config.hpp"
#include "config/devices.hpp"
#include "engine/device/dc_motor_plant.hpp"
#include "haptic/wire/datagram.hpp"
#include "lab/lab_run.hpp"
#include "lab/lab_scenes.hpp"
#include "lab/study.hpp"

namespace haptic::lab {
namespace {

// ---------------------------------------------------------------------------------------------
// The scenes: the files under config/lab/, compiled in by the build (lab/lab_scenes.hpp is
// generated from them, so the files are the one copy; study_devices_test checks that running a
// file gives its case's trajectory).

/// config/lab/dc_motor_mass_000.json. 000's 1-DOF device (DC motor, gearbox, link under gravity,
/// gravity compensated; docs/devices.md) with the link at θ_L = 0.5 rad, so the tool (the link's
/// end, on a circle of radius 0.2 m) is at (0.1755, 0.0959, 0) m. The hand pushes 1 N along the
/// circle's tangent there, (−sin 0.5, cos 0.5, 0), into a sphere of radius 20 mm that is a
/// virtual mass on a viscous surface (000 eq. 7.1, f_V = m_V Ẍ + B_V Ẋ, m_V = 0.05 kg,
/// B_V = 2 N·s/m), 2 mm ahead of the tool along the circle. The contact (K = 1000 N/m, B = 1 N·s/m)
/// meets the scene's mass bounds at T = 1 ms: m_V ≥ 4 K T² = 0.004 kg, B + B_V ≥ K T / 2 = 0.5.
/// The centre sits on the chord at angle 0.5 + 0.111 rad: 2 l sin(0.111 / 2) = 22.2 mm from the
/// tool, 2.2 mm more than the radius.
constexpr const char* kDcMotorMass = lab_scenes::k_dc_motor_mass_000;

/// config/lab/parallel_dob_wall_001.json. 001's experiment (seed-000-001.md, "Experiment"): the
/// 2-DOF parallel device behind its per-axis disturbance observer (nominal m = 0.01 kg,
/// b = 0.022 N·s/m, 1 ms sampling), the operator pushing −5 N into a wall of K = 1000 N/m with
/// the damping 001 finds transparency-optimal, B_c = 15 N·s/m (Fig. 8), plus a ±2 N, 5 Hz sine
/// so that the tool keeps moving. The wall is the half-space y < 0.25 m, its surface through the
/// tool's start (0, 0.25, 0), so the push starts at the surface. (With the plain wall's
/// B = 1 N·s/m the contact oscillates, as 001's Fig. 7 says, here into a saturated limit cycle
/// 0.2 m deep: a chaotic trajectory that no step size reproduces, so not a case for numerics.)
constexpr const char* kParallelDobWall = lab_scenes::k_parallel_dob_wall_001;

/// config/lab/five_bar_wall_003.json. 003's five-bar (Madill; docs/devices.md) as configured in
/// config/five_bar_003.json — π/6000 axial encoders, Table 5.4's joint friction, the non-linear
/// state estimator for the velocities — with the tip at home (0.6, 0, 0.3) m. The axial joint q1
/// moves the tip along x with a 0.3 m lever (J = [[0, −0.3, 0], …] at home), so Madill's
/// conventional axial wall, Kp = 400 N·m/rad, Kd = 0 (seed-003-madill.md: "already slightly too
/// stiff" for the position-only wall) is K = 400 / 0.3² = 4444 N/m at the tip; the scene's walls
/// are Cartesian, so it is the half-space x > 0.599 m (normal −x), 1 mm from the tip, with
/// B = 5 / 0.3² = 55.6 N·s/m (the estimator wall's Kd = 5 N·m·s/rad). The hand pushes 3 N along +x.
constexpr const char* kFiveBarWall = lab_scenes::k_five_bar_wall_003;

/// config/lab/five_bar_swing_003.json. The five-bar swung about its base joint q0 and its axial
/// joint q1 by a 4 Hz sine force of 6 N amplitude along (0.6, 0.8, 0) at the tip, no scene:
/// q̇0 drives the coupling (Coriolis) terms of L2382 and link 5's horizontal mode. The encoders
/// are ideal (quantized_encoders false) so that the model choices, not the counts, set the
/// difference; the fidelity cases switch `coriolis` and `flexible_mode`.
constexpr const char* kFiveBarSwing = lab_scenes::k_five_bar_swing_003;

/// config/lab/joystick_shaft_004.json. 004's joystick (Russo; docs/devices.md) at mid-stroke
/// (R = 0.24 m along z), the hand pushing 8 N down the shaft (−z) — above the sleeve's 5.66 N
/// Coulomb friction — onto a wall at z = 0.2395 m (K = 5000 N/m, B = 20 N·s/m) that the shaft
/// motor renders. Between the motor side x_m and the shaft R sits the cable, k_t = 82,340 N/m,
/// b_t = 45 N·s/m (seed-004-russo.md, "Measured"): with M_m = 0.30 kg and M_s = 0.11 kg its mode is
/// ω = √(k_t (1/M_m + 1/M_s)) ≈ 1011 rad/s, the stiff part (explicit Euler needs h ω well below
/// 2 with ζ ≈ 0.28: at h = 1 ms it diverges). The push keeps the shaft below the watchdog's
/// 8 rad/s of the drive pulley (76 mm/s of shaft).
constexpr const char* kJoystickShaft = lab_scenes::k_joystick_shaft_004;

// ---------------------------------------------------------------------------------------------
// Running a scene with a scheme and a step.

/// A model variant: its name and what it changes in the configuration.
struct Variant {
  std::string name;
  std::function<void(v1::ServerConfig&)> apply;
};

/// Sets the configured device's integrator and sub-steps.
void set_integration(v1::ServerConfig& config, engine::Integrator method, std::uint32_t substeps) {
  const std::string name(engine::integrator_name(method));
  if (config.has_simulated_dc_motor()) {
    config.mutable_simulated_dc_motor()->set_integrator(name);
    config.mutable_simulated_dc_motor()->set_substeps(substeps);
  } else if (config.has_simulated_five_bar()) {
    config.mutable_simulated_five_bar()->set_integrator(name);
    config.mutable_simulated_five_bar()->set_substeps(substeps);
  } else if (config.has_simulated_joystick()) {
    config.mutable_simulated_joystick()->set_integrator(name);
    config.mutable_simulated_joystick()->set_substeps(substeps);
  } else if (config.has_simulated_parallel_dob()) {
    config.mutable_simulated_parallel_dob()->set_integrator(name);
    config.mutable_simulated_parallel_dob()->set_substeps(substeps);
  } else {
    throw std::invalid_argument("scene: no document device configured");
  }
}

/// "" when h = step_s divides the tick period_s into 1 … 10,000 equal sub-steps (what the
/// configuration accepts), else what is wrong with the step.
std::string substep_problem(double step_s, double period_s) {
  if (!(std::isfinite(step_s) && step_s > 0.0)) return "step_s must be finite and > 0, got " + std::to_string(step_s);
  const double ratio = period_s / step_s;
  const double n = std::round(ratio);
  if (n < 1.0 || n > 10000.0 || std::abs(ratio - n) > 1e-9 * n) {
    return "step_s " + std::to_string(step_s) + " s does not divide the " + std::to_string(period_s) +
           " s tick into 1 to 10000 equal sub-steps";
  }
  return {};
}

/// T / h as a whole number of sub-steps, or std::invalid_argument naming the case and the step.
std::uint32_t substeps_for(double step_s, double period_s, const std::string& case_name) {
  if (const std::string problem = substep_problem(step_s, period_s); !problem.empty()) {
    throw std::invalid_argument(case_name + ": " + problem);
  }
  return static_cast<std::uint32_t>(std::round(period_s / step_s));
}

/// One device case's fixed parts.
struct DeviceScene {
  std::string name;
  v1::ServerConfig config;
  double duration_s = 0.5;
  double output_period_s = 0.01;
  std::vector<Variant> variants;  // Empty: the configuration as it is.
  double bound_m = 0.5;           // The tool leaving its start by more than this is divergence.
  bool energy = true;             // false: the scene has no objects or fields, so no energy.
};

Trajectory simulate_device(const DeviceScene& scene, Scheme scheme, double step_s, const std::string& variant) {
  const std::optional<engine::Integrator> method = as_integrator(scheme);
  if (!method) {
    throw std::invalid_argument(scene.name + ": scheme " + std::string(scheme_name(scheme)) +
                                " does not apply (the device's plant is not linear)");
  }
  v1::ServerConfig config = scene.config;
  if (!scene.variants.empty()) {
    const Variant* chosen = variant.empty() ? &scene.variants.front() : nullptr;
    for (const Variant& v : scene.variants) {
      if (v.name == variant) chosen = &v;
    }
    if (chosen == nullptr) throw std::invalid_argument(scene.name + ": unknown variant \"" + variant + "\"");
    chosen->apply(config);
  } else if (!variant.empty()) {
    throw std::invalid_argument(scene.name + ": has no variant \"" + variant + "\"");
  }
  const double period_s = 1.0 / config.loop_rate_hz();
  const std::uint32_t substeps = substeps_for(step_s, period_s, scene.name);
  set_integration(config, *method, substeps);
  // 000's model with inductance raises its sub-steps to keep the electrical pole inside every
  // method's stability interval (DcMotorPlant::substeps_for): the step actually taken is smaller.
  std::string step_note;
  if (config.has_simulated_dc_motor() && config.simulated_dc_motor().with_inductance()) {
    const engine::DcMotorPlant plant(config::dc_motor_params(config.simulated_dc_motor()),
                                     engine::DcMotorModel::kWithInductance, {},
                                     engine::IntegrationSettings{*method, substeps});
    const std::uint32_t taken = plant.substeps_for(period_s);
    if (taken != substeps) {
      std::ostringstream note;
      note << "the inductance model took " << taken << " sub-steps per tick (h = " << period_s / taken
           << " s), not " << substeps;
      step_note = note.str();
    }
  }
  const auto every = static_cast<std::uint64_t>(std::llround(scene.output_period_s / period_s));

  Trajectory out;
  engine::Vec3 start;
  std::uint64_t first_fault = 0;
  const auto is_finite = [](const std::array<double, 3>& a) {
    return std::isfinite(a[0]) && std::isfinite(a[1]) && std::isfinite(a[2]);
  };
  const auto on_tick = [&](const TickRecord& r) {
    if (r.port != 0) return true;
    const runtime::TickSample& s = r.sample;
    if (s.flags & (wire::kFlagForceFault | wire::kFlagDeviceFault)) {
      if (out.fault_ticks++ == 0) first_fault = s.tick;
    }
    const double t = static_cast<double>(s.tick - 1) * period_s;
    // The loop publishes the last good reading when the plant fails: look at the plant itself.
    if (!engine::is_finite(s.p_WT) || !engine::is_finite(s.v_WT) || !is_finite(r.joints.q) ||
        !is_finite(r.joints.q_dot)) {
      out.finite = false;
      out.note = "non-finite state at t = " + std::to_string(t) + " s";
      return false;
    }
    if (s.tick == 1) start = s.p_WT;
    if (engine::norm(s.p_WT - start) > scene.bound_m) {
      out.diverged = true;
      out.note = "tool left its start by more than " + std::to_string(scene.bound_m) + " m at t = " +
                 std::to_string(t) + " s";
      return false;
    }
    if ((s.tick - 1) % every == 0) {
      out.samples.push_back(s.p_WT - start);
      if (scene.energy) out.energy.push_back(r.energy_to_device_j - r.energy_from_device_j);
    }
    return true;
  };
  // One tick past the duration, so that the sample at t = duration is taken.
  simulate_scene(config, scene.duration_s + period_s, on_tick);
  if (!step_note.empty()) out.note = out.note.empty() ? step_note : out.note + "; " + step_note;
  if (out.fault_ticks > 0) {
    if (!out.note.empty()) out.note += "; ";
    out.note += std::to_string(out.fault_ticks) +
                " fault ticks (force or device fault, e.g. the watchdog), first at t = " +
                std::to_string(static_cast<double>(first_fault - 1) * period_s) + " s";
  }
  return out;
}

StudyCase make_case(DeviceScene scene, std::string title, std::string source, bool short_suite,
                    std::string group = "schemes") {
  StudyCase c;
  c.name = scene.name;
  c.title = std::move(title);
  c.source = std::move(source);
  c.observable = "tool displacement p_WT(t) - p_WT(0) as the device reports it, m";
  c.group = std::move(group);
  c.duration_s = scene.duration_s;
  c.output_period_s = scene.output_period_s;
  for (const Variant& v : scene.variants) c.variants.push_back(v.name);
  if (c.group == "fidelity") {
    c.schemes = {Scheme::kRk4, Scheme::kSemiImplicitEuler};
    c.steps_s = short_suite ? std::vector<double>{1e-3, 1e-4} : std::vector<double>{1e-3, 2e-4, 1e-4, 1e-5};
  } else {
    c.schemes.assign(std::begin(kIntegratorSchemes), std::end(kIntegratorSchemes));
    c.steps_s = short_suite ? std::vector<double>{1e-3, 1e-4, 1e-5, 1e-6}
                            : std::vector<double>{1e-3, 5e-4, 2e-4, 1e-4, 5e-5, 2e-5, 1e-5, 5e-6, 2e-6, 1e-6};
  }
  // Scheme cases: 2,000 sub-steps per tick, below the finest step studied; its convergence is
  // shown against 1e-6 s (the harness runs both). Fidelity cases compare models, not steps:
  // 1,000 sub-steps are converged far below the models' differences.
  c.reference_scheme = Scheme::kRk4;
  c.reference_step_s = c.group == "fidelity" ? 1e-6 : 5e-7;
  c.check_step = [period_s = 1.0 / scene.config.loop_rate_hz()](double step_s) {
    return substep_problem(step_s, period_s);
  };
  c.simulate = [scene = std::move(scene)](Scheme scheme, double step_s, const std::string& variant) {
    return simulate_device(scene, scheme, step_s, variant);
  };
  return c;
}

DeviceScene scene(std::string name, const char* json, const char* file, double duration_s) {
  DeviceScene s;
  s.name = std::move(name);
  s.config = config::parse_config(json, file);
  s.duration_s = duration_s;
  s.energy = s.config.initial_scene().objects_size() + s.config.initial_scene().fields_size() > 0;
  return s;
}

}  // namespace

std::vector<StudyCase> device_cases(bool short_suite) {
  // Short suite: 0.2 s of each scene (the contacts and the cable's transients are over by then);
  // full: 0.5 s.
  const double d = short_suite ? 0.2 : 0.5;
  std::vector<StudyCase> cases;
  cases.push_back(make_case(
      scene("dc_motor_mass_000", kDcMotorMass, "config/lab/dc_motor_mass_000.json", d),
      "000's DC-motor device pushing a virtual mass on a viscous surface",
      "000 eqs. 3.9, 4.6, 6.7 (device), eq. 7.1 f_V = m_V Ẍ + B_V Ẋ (m_V 0.05 kg, B_V 2 N·s/m); "
      "config/lab/dc_motor_mass_000.json",
      short_suite));
  cases.push_back(make_case(
      scene("parallel_dob_wall_001", kParallelDobWall, "config/lab/parallel_dob_wall_001.json", d),
      "001's parallel device behind its disturbance observer, pushed into a 1000 N/m wall",
      "001 eqs. 2-5 (device, DOB), experiment: m 0.01 kg, b 0.022 N·s/m, K 1000 N/m, -5 N; "
      "B_c 15 N·s/m (Fig. 8); "
      "config/lab/parallel_dob_wall_001.json",
      short_suite));
  cases.push_back(make_case(
      scene("five_bar_wall_003", kFiveBarWall, "config/lab/five_bar_wall_003.json", d),
      "003's five-bar (axial joint, friction, π/6000 encoders, estimator) pushed into a wall; read "
      "through the encoders, so errors come in counts (π/6000 rad: 0.157 mm at the tip)",
      "003 Table 5.4 (friction), Table 5.2/ch. 6 (encoders), ch. 6.3 (estimator); conventional wall "
      "Kp 400 N·m/rad as 4444 N/m at the 0.3 m lever; config/lab/five_bar_wall_003.json",
      short_suite));
  cases.push_back(make_case(
      scene("joystick_shaft_004", kJoystickShaft, "config/lab/joystick_shaft_004.json", d),
      "004's joystick, pushed down its shaft onto a wall through the stiff cable",
      "004 L935: k_t 82,340 N/m, b_t 45 N·s/m; eq. 3.38 sleeve friction; config/lab/joystick_shaft_004.json",
      short_suite));

  // Model fidelity: a richer model (the first variant, the reference's) against a cheaper one.
  DeviceScene inductance = scene("dc_motor_inductance_000", kDcMotorMass, "config/lab/dc_motor_mass_000.json", d);
  inductance.variants = {
      {"with_inductance",
       [](v1::ServerConfig& c) { c.mutable_simulated_dc_motor()->set_with_inductance(true); }},
      {"without_inductance",
       [](v1::ServerConfig& c) { c.mutable_simulated_dc_motor()->set_with_inductance(false); }}};
  cases.push_back(make_case(
      std::move(inductance), "000's device with and without the motor's inductance",
      "000 eqs. 2.1-2.8 (full motor) against the reduced eq. 3.9 (t_e << t_m); "
      "config/lab/dc_motor_mass_000.json",
      short_suite, "fidelity"));
  DeviceScene flexible = scene("five_bar_flexible_003", kFiveBarSwing, "config/lab/five_bar_swing_003.json", d);
  flexible.variants = {
      {"flexible_mode", [](v1::ServerConfig& c) { c.mutable_simulated_five_bar()->set_flexible_mode(true); }},
      {"rigid", [](v1::ServerConfig& c) { c.mutable_simulated_five_bar()->set_flexible_mode(false); }}};
  cases.push_back(make_case(
      std::move(flexible), "003's five-bar swung by a sine force: link 5's first mode against a rigid link",
      "003 eqs. 3.29-3.31, 5.11 (ω1 = 222.3 rad/s, ζ 0.02 assumed); config/lab/five_bar_swing_003.json",
      short_suite, "fidelity"));
  DeviceScene coriolis = scene("five_bar_coriolis_003", kFiveBarSwing, "config/lab/five_bar_swing_003.json", d);
  coriolis.variants = {
      {"coriolis", [](v1::ServerConfig& c) { c.mutable_simulated_five_bar()->set_coriolis(true); }},
      {"no_coriolis", [](v1::ServerConfig& c) { c.mutable_simulated_five_bar()->set_coriolis(false); }}};
  cases.push_back(make_case(
      std::move(coriolis), "003's five-bar swung by a sine force: with and without the q̇0 coupling terms",
      "003 L2382 (velocity terms) against L2388's 'haptic speeds' approximation; "
      "config/lab/five_bar_swing_003.json",
      short_suite, "fidelity"));
  return cases;
}

}  // namespace haptic::lab
