// The study's ODE cases: a mass against a linear spring-damper (walls from soft to K = 1e7 N/m,
// masses down to 1e-4 kg, zero damping, a 1e3 N force step, a NaN injected into the force), the
// virtual mass on a viscous surface (000 eq. 7.1), a joint with Coulomb friction (003) under
// three friction models, a wall rendered at each tick period by each impedance law, and a Khatib
// potential field (004) with its gradient analytic or by central differences. Each is integrated with the engine's integrators (engine/core/
// integrator.hpp, the code the plants use) and, where linear, with its exact ZOH discretization;
// the linear ones are compared with their closed-form solutions.

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <utility>
#include <string>

#include "engine/core/integrator.hpp"
#include "engine/core/rotation.hpp"
#include "engine/device/rigid_body_rotation.hpp"
#include "engine/device/joint_friction.hpp"
#include "engine/safety/force_guard.hpp"
#include "engine/scene/fields.hpp"
#include "engine/scene/impedance.hpp"
#include "engine/scene/orientation_fields.hpp"
#include "config/server_config.hpp"
#include "lab/lab_run.hpp"
#include "haptic/wire/datagram.hpp"
#include "lab/study.hpp"

namespace haptic::lab {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

/// m ẍ + B ẋ + K x = F(t) on one axis, with F(t) = force_before for t < step_time and
/// force_after from then on. x is the tool's penetration coordinate (m; negative: inside the wall,
/// the spring pushing it out), F the operator's force (N).
struct LinearOscillator {
  double mass = 0.01;       // m. Unit: kg.
  double damping = 1.0;     // B. Unit: N·s/m.
  double stiffness = 1e3;   // K. Unit: N/m. 0: no spring (a mass on a viscous surface).
  double x0 = -0.005;       // Unit: m.
  double v0 = 0.0;          // Unit: m/s.
  double force_before = 0.0;  // Unit: N.
  double force_after = 0.0;   // Unit: N.
  double step_time = 0.0;     // Unit: s.
  /// A NaN replaces the force over [nan_from, nan_until) (the NaN-injection case).
  double nan_from = -1.0, nan_until = -1.0;
  /// Pass the force through the server's last stage (engine::ForceGuard) as a device would see it.
  bool guarded = false;

  double force(double t) const {
    if (t >= nan_from && t < nan_until) return kNan;
    return t < step_time ? force_before : force_after;
  }

  /// Stored energy plus the potential of the current constant force: ½mv² + ½Kx² − F x (J).
  double energy(double x, double v, double f) const {
    return 0.5 * mass * v * v + 0.5 * stiffness * x * x - f * x;
  }

  /// The closed-form free-plus-constant-force solution from (x, v) over time t under force f.
  void advance_exact(double& x, double& v, double f, double t) const {
    const double m = mass, b = damping, k = stiffness;
    if (k == 0.0) {
      if (b == 0.0) {
        x += v * t + 0.5 * f / m * t * t;
        v += f / m * t;
        return;
      }
      const double v_inf = f / b, tau = m / b, decay = std::exp(-t / tau);
      x += v_inf * t + (v - v_inf) * tau * (1.0 - decay);
      v = v_inf + (v - v_inf) * decay;
      return;
    }
    const double x_eq = f / k;
    const double y0 = x - x_eq;
    const double sigma = b / (2.0 * m);
    const double w2 = k / m - sigma * sigma;  // ω_d² (> 0: underdamped)
    if (w2 > 0.0) {
      const double wd = std::sqrt(w2);
      const double c = (v + sigma * y0) / wd;
      const double e = std::exp(-sigma * t), cs = std::cos(wd * t), sn = std::sin(wd * t);
      x = x_eq + e * (y0 * cs + c * sn);
      v = e * ((-sigma * y0 + c * wd) * cs + (-sigma * c - y0 * wd) * sn);
    } else if (w2 < 0.0) {
      const double r = std::sqrt(-w2), l1 = -sigma + r, l2 = -sigma - r;
      const double c1 = (v - l2 * y0) / (l1 - l2), c2 = y0 - c1;
      x = x_eq + c1 * std::exp(l1 * t) + c2 * std::exp(l2 * t);
      v = c1 * l1 * std::exp(l1 * t) + c2 * l2 * std::exp(l2 * t);
    } else {
      const double c = v + sigma * y0, e = std::exp(-sigma * t);
      x = x_eq + (y0 + c * t) * e;
      v = (c - sigma * (y0 + c * t)) * e;
    }
  }
};

/// How far a run may go before it is called diverged: 1e3 times the larger of the start and the
/// static deflection under the largest force, or 1 m.
double bound_of(const LinearOscillator& o) {
  double scale = std::abs(o.x0) + std::abs(o.v0) * std::sqrt(o.mass / std::max(o.stiffness, 1e-9));
  if (o.stiffness > 0.0) scale = std::max(scale, std::max(std::abs(o.force_before), std::abs(o.force_after)) / o.stiffness);
  return std::max(1e3 * scale, 1.0);
}

std::size_t output_count(const StudyCase& c) {
  return static_cast<std::size_t>(std::llround(c.duration_s / c.output_period_s)) + 1;
}

/// The sampling loop every ODE case shares: `advance(step_index)` takes one step of h, `observe()`
/// returns the observable and the energy now, recorded at t = 0 and every output period. Stops on
/// the first non-finite sample (finite = false) or the first beyond ±bound (diverged = true).
template <typename Advance, typename Observe>
Trajectory sample_run(const StudyCase& c, double h, double bound, Advance&& advance, Observe&& observe) {
  const auto steps_per_output = static_cast<std::int64_t>(std::llround(c.output_period_s / h));
  const std::size_t n = output_count(c);
  Trajectory out;
  out.samples.reserve(n);
  out.energy.reserve(n);
  std::int64_t step = 0;
  for (std::size_t k = 0; k < n; ++k) {
    for (std::int64_t i = 0; k > 0 && i < steps_per_output; ++i) advance(step++);
    const auto [value, energy] = observe();
    if (!(std::isfinite(value) && std::isfinite(energy))) {
      out.finite = false;
      return out;
    }
    if (std::abs(value) > bound) {
      out.diverged = true;
      return out;
    }
    out.samples.push_back({value, 0.0, 0.0});
    out.energy.push_back(energy);
  }
  return out;
}

Trajectory exact_solution(const LinearOscillator& o, const StudyCase& c) {
  Trajectory out;
  double x = o.x0, v = o.v0;
  const std::size_t n = output_count(c);
  for (std::size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) * c.output_period_s;
    if (k > 0) {
      const double t_prev = t - c.output_period_s;
      if (t_prev < o.step_time && t > o.step_time) {  // split at the force step
        o.advance_exact(x, v, o.force_before, o.step_time - t_prev);
        o.advance_exact(x, v, o.force_after, t - o.step_time);
      } else {
        // The NaN window reaches the device as zero through the guard: the reference is the
        // force the scene meant, which is zero there too (see nan_injection).
        const double f = t_prev < o.step_time ? o.force_before : o.force_after;
        o.advance_exact(x, v, f, c.output_period_s);
      }
    }
    out.samples.push_back({x, 0.0, 0.0});
    const double f_now = t < o.step_time ? o.force_before : o.force_after;
    out.energy.push_back(o.energy(x, v, f_now));
  }
  return out;
}

/// Integrates the oscillator with `scheme` at step h (the force held over each step, as a
/// device's D/A holds it), sampling every output period.
Trajectory integrate(const LinearOscillator& o, const StudyCase& c, Scheme scheme, double h) {
  if (!(std::isfinite(h) && h > 0.0)) throw std::invalid_argument(c.name + ": step must be > 0 s");
  engine::ForceGuard guard({1e9, 0.0});  // only its fault check matters here
  engine::StateVector<2> x{o.x0, o.v0};
  const std::array<std::array<double, 2>, 2> a{{{0.0, 1.0}, {-o.stiffness / o.mass, -o.damping / o.mass}}};
  const engine::ZohStep<2> zoh = engine::exact_zoh<2>(a, {0.0, 1.0 / o.mass}, h);
  std::uint64_t fault_ticks = 0;
  double t_now = 0.0;
  auto advance = [&](std::int64_t step) {
    // The force held over this step (a hair past its start, so a step that begins exactly on
    // the force's switching time sees the new value despite rounding in step · h).
    double f = o.force((static_cast<double>(step) + 1e-6) * h);
    if (o.guarded) {
      const engine::GuardedForce g = guard.apply({f, 0.0, 0.0}, h);
      if (g.fault) ++fault_ticks;
      f = g.F_T_W.x;
    }
    if (scheme == Scheme::kExactZoh) {
      const double q = x[0], qd = x[1];
      x[0] = zoh.phi[0][0] * q + zoh.phi[0][1] * qd + zoh.gamma[0] * f;
      x[1] = zoh.phi[1][0] * q + zoh.phi[1][1] * qd + zoh.gamma[1] * f;
    } else {
      engine::integrate_step<1>(*as_integrator(scheme), x, h, [&](const engine::StateVector<2>& s) {
        return engine::StateVector<2>{s[1], (f - o.stiffness * s[0] - o.damping * s[1]) / o.mass};
      });
    }
    t_now = static_cast<double>(step + 1) * h;
  };
  auto observe = [&] {
    const double f_now = o.force(t_now);
    return std::pair{x[0], o.energy(x[0], x[1], std::isfinite(f_now) ? f_now : 0.0)};
  };
  Trajectory out = sample_run(c, h, bound_of(o), advance, observe);
  out.fault_ticks = fault_ticks;
  return out;
}

/// A case's description (what the report and the charts print), sampled every 10 ms.
StudyCase describe(std::string name, std::string title, std::string source, std::string observable,
                   std::string group, double duration_s) {
  StudyCase c;
  c.name = std::move(name);
  c.title = std::move(title);
  c.source = std::move(source);
  c.observable = std::move(observable);
  c.group = std::move(group);
  c.duration_s = duration_s;
  c.output_period_s = 0.01;
  return c;
}

/// Sets c.simulate to simulate(scheme, step, variant, c) with a copy of c's description (the
/// closure keeps the case's duration and output period, not the case itself).
template <typename Simulate>
void set_simulation(StudyCase& c, Simulate simulate) {
  const StudyCase shape = c;
  c.simulate = [shape, simulate](Scheme scheme, double step_s, const std::string& variant) {
    return simulate(scheme, step_s, variant, shape);
  };
}

/// A case for one oscillator: every scheme (exact ZOH included), the closed form as reference.
StudyCase oscillator_case(std::string name, std::string title, std::string source, const LinearOscillator& o,
                          double duration_s, const std::vector<double>& steps) {
  StudyCase c = describe(std::move(name), std::move(title), std::move(source), "tool position x, m",
                         "schemes", duration_s);
  c.schemes.assign(std::begin(kAllSchemes), std::end(kAllSchemes));
  c.steps_s = steps;
  c.conservative = o.damping == 0.0 && o.force_before == 0.0 && o.force_after == 0.0;
  set_simulation(c, [o](Scheme scheme, double h, const std::string&, const StudyCase& shape) {
    return integrate(o, shape, scheme, h);
  });
  c.exact = [o, shape = c] { return exact_solution(o, shape); };
  return c;
}

// --- 003's joint with Coulomb friction ------------------------------------------------------

/// Madill's axial joint (Table 5.4: J = 0.204 kg·m², B = 0.012 N·m·s/rad, f = 0.088 N·m) held by
/// a P-D wall τ = −K_p q − K_d q̇ for q < 0 (K_p = 400 N·m/rad, L2869) and pushed into it by the
/// operator with τ_h = 0.5 N·m sin(2π·2 t) − 0.2 N·m. The friction model is the variant:
/// Karnopp's stick band (the simulation's model, joint_friction.hpp), the smooth saturation the
/// estimator assumes (f0 sat(q̇/v0), v0 = 0.03 rad/s, L3211), or viscous only.
Trajectory joint_with_friction(Scheme scheme, double h, const std::string& variant, const StudyCase& c) {
  constexpr double kInertia = 0.204, kDamping = 0.012, kCoulomb = 0.088;
  constexpr double kWallStiffness = 400.0, kWallDamping = 1.0;
  const engine::CoulombViscousFriction karnopp{kCoulomb, kDamping, 1e-4};
  const engine::CoulombViscousFriction smooth{kCoulomb, kDamping, 0.03};
  const auto integrator = as_integrator(scheme);
  if (!integrator) throw std::invalid_argument(c.name + ": exact_zoh does not apply (friction is not linear)");
  engine::StateVector<2> x{0.01, 0.0};  // q (rad), q̇ (rad/s): 10 mrad outside the wall
  auto advance = [&](std::int64_t step) {
    const double t = static_cast<double>(step) * h;
    const double hand = 0.5 * std::sin(2.0 * 3.14159265358979323846 * 2.0 * t) - 0.2;  // N·m, held
    engine::integrate_step<1>(*integrator, x, h, [&](const engine::StateVector<2>& s) {
      const double wall = s[0] < 0.0 ? -kWallStiffness * s[0] - kWallDamping * s[1] : 0.0;
      const double applied = hand + wall;
      double friction = kDamping * s[1];
      if (variant == "karnopp") friction = karnopp.resisting(s[1], applied);
      if (variant == "smooth") friction = smooth.smooth(s[1]);
      return engine::StateVector<2>{s[1], (applied - friction) / kInertia};
    });
  };
  auto observe = [&] {
    const double wall_energy = x[0] < 0.0 ? 0.5 * kWallStiffness * x[0] * x[0] : 0.0;
    return std::pair{x[0], 0.5 * kInertia * x[1] * x[1] + wall_energy};
  };
  return sample_run(c, h, 10.0, advance, observe);
}

// --- A wall rendered by the loop: each impedance law at each tick period ---------------------

/// 001's device (m = 0.01 kg, b = 0.022 N·s/m; Eom et al.) coupled to a K = 1e3 N/m, B = 1 N·s/m
/// spring-damper the loop renders at tick period T with one of the scene's impedance laws
/// (engine::ImpedanceFilter; 000 eqs. 8.9–8.16), the force held over each tick, the device's
/// own motion integrated exactly between ticks. The reference is the continuous coupling,
/// m ẍ + (b + B) ẋ + K x = 0, in closed form: the error is what rendering the wall at T costs.
/// Variant "velocity" is the law on the device's measured velocity, f = K d + B v.
constexpr double kDeviceMass = 0.01, kDeviceDamping = 0.022, kWallK = 1e3, kWallB = 1.0;

Trajectory sampled_wall(Scheme scheme, double period, const std::string& law, const StudyCase& c) {
  if (scheme != Scheme::kExactZoh) {
    throw std::invalid_argument(c.name + ": the device is integrated exactly between ticks; scheme must be exact_zoh");
  }
  const engine::ImpedanceParams wall{kWallK, kWallB, 0.0};
  engine::ImpedanceDiscretization discretization = engine::ImpedanceDiscretization::kBackwardDifference;
  if (law == "exact_zoh") discretization = engine::ImpedanceDiscretization::kExactZoh;
  if (law == "tustin") discretization = engine::ImpedanceDiscretization::kTustin;
  if (law != "velocity" && law != "backward_difference" && law != "exact_zoh" && law != "tustin") {
    throw std::invalid_argument(c.name + ": unknown impedance law \"" + law + "\"");
  }
  engine::ImpedanceFilter filter(wall, discretization, period);
  const double x0 = -0.005;  // m: 5 mm in, at rest
  filter.reset(-x0, 0.0);
  const engine::ZohStep<2> device = engine::exact_zoh<2>({{{0.0, 1.0}, {0.0, -kDeviceDamping / kDeviceMass}}},
                                         {0.0, 1.0 / kDeviceMass}, period);
  double x = x0, v = 0.0;
  auto advance = [&](std::int64_t) {
    const double d = -x;  // penetration, m (> 0 inside)
    const double f = law == "velocity" ? kWallK * d - kWallB * v : filter.update(d);  // N, along +x
    const double q = x, qd = v;
    x = device.phi[0][0] * q + device.phi[0][1] * qd + device.gamma[0] * f;
    v = device.phi[1][0] * q + device.phi[1][1] * qd + device.gamma[1] * f;
  };
  auto observe = [&] { return std::pair{x, 0.5 * kDeviceMass * v * v + 0.5 * kWallK * x * x}; };
  return sample_run(c, period, 5.0, advance, observe);
}

// --- An orientation spring on the 6-DOF handle: each law at each tick period ------------------

/// The 6-DOF point mass's handle (I = 1e-4 kg·m², b = 5e-4 N·m·s/rad: config/six_dof.json)
/// turned 0.2 rad about z and held by an orientation spring (k = 0.3 N·m/rad, b_s = 2e-4
/// N·m·s/rad) the loop renders at tick period T with each law (engine::OrientationSpringState: the
/// impedance laws per axis of the rotation vector), the torque held over each tick and the handle
/// stepped exactly (engine::RigidBodyRotation). The reference is the continuous coupling
/// I θ̈ + (b + b_s) θ̇ + k θ = 0 in closed form.
constexpr double kHandleInertia = 1e-4, kHandleDamping = 5e-4, kHandleSpringK = 0.3, kHandleSpringB = 2e-4;
constexpr double kHandleAngle0 = 0.2;  // rad

Trajectory orientation_spring(Scheme scheme, double period, const std::string& law, const StudyCase& c) {
  if (scheme != Scheme::kExactZoh) {
    throw std::invalid_argument(c.name + ": the handle is stepped exactly between ticks; scheme must be exact_zoh");
  }
  engine::OrientationSpringSpec spring;
  spring.stiffness = kHandleSpringK;
  spring.damping = kHandleSpringB;
  if (law == "velocity") {
    spring.law = engine::ContactLaw::kVelocity;
  } else if (law == "backward_difference") {
    spring.law = engine::ContactLaw::kBackwardDifference;
  } else if (law == "exact_zoh") {
    spring.law = engine::ContactLaw::kExactZoh;
  } else if (law == "tustin") {
    spring.law = engine::ContactLaw::kTustin;
  } else {
    throw std::invalid_argument(c.name + ": unknown law \"" + law + "\"");
  }
  engine::OrientationSpringState state;
  state.set_weights(engine::orientation_spring_weights(spring, period));
  engine::RigidBodyRotation handle(engine::RotationParams{kHandleInertia, kHandleDamping, 1},
                                   engine::RotationState{engine::quat_from_axis_angle({0, 0, 1}, kHandleAngle0), {}});
  const auto no_hand = [](const engine::Quat&, const engine::Vec3&) { return engine::Vec3{}; };
  // The angle unwrapped across ±π tick by tick, so a run that rings up leaves the bound instead
  // of folding back into [−π, π].
  double angle = kHandleAngle0;
  double wrapped = kHandleAngle0;
  auto advance = [&](std::int64_t) {
    const engine::RotationState& now = handle.state();
    handle.step(state.update(spring, now.R_WT, now.w_WT, period).tau_T_W, period, no_hand);
    const double next = engine::rotation_vector(handle.state().R_WT).z;
    angle += std::remainder(next - wrapped, 2.0 * std::numbers::pi);
    wrapped = next;
  };
  auto observe = [&] {
    const double w = handle.state().w_WT.z;
    return std::pair{angle, 0.5 * kHandleInertia * w * w + 0.5 * kHandleSpringK * angle * angle};
  };
  return sample_run(c, period, 3.0, advance, observe);
}

// --- A potential field: the gradient analytic or by central differences ----------------------

/// A 0.01 kg tool pushed by a constant 0.5 N toward a plane that repels it with Khatib's field
/// (004 eq. 5.7, U = (1/n) K (1/f − 1/f0)ⁿ, n = 2, K = 1.67e-7 J·m², f0 = 20 mm, f_m = 1 mm),
/// evaluated by engine::evaluate_field with the gradient analytic or by central differences
/// (eq. 5.7, second, step 1e-3 or 1e-6 m). It bounces between 15 mm and ≈ 4 mm; nothing
/// dissipates, so E = ½mv² + U + 0.5 N · z must stay.
Trajectory khatib_bounce(Scheme scheme, double h, const std::string& variant, const StudyCase& c) {
  const auto integrator = as_integrator(scheme);
  if (!integrator) throw std::invalid_argument(c.name + ": exact_zoh does not apply (the field is not linear)");
  engine::PotentialFieldSpec field;
  field.distance = engine::plane_distance({0.0, 0.0, 0.0}, {0.0, 0.0, 1.0});
  field.kind = engine::PotentialKind::kKhatib;
  field.order = 2;
  field.gain = 1.67e-7;
  field.influence_distance = 0.02;
  field.min_distance = 0.001;
  if (variant == "central_1e-3" || variant == "central_1e-6") {
    field.gradient = engine::GradientMethod::kCentralDifference;
    field.difference_step = variant == "central_1e-3" ? 1e-3 : 1e-6;
  } else if (variant != "analytic") {
    throw std::invalid_argument(c.name + ": unknown gradient variant \"" + variant + "\"");
  }
  constexpr double kMass = 0.01, kPush = -0.5;  // kg; N along z
  engine::StateVector<2> x{0.015, 0.0};  // z (m), ż (m/s)
  auto advance = [&](std::int64_t) {
    engine::integrate_step<1>(*integrator, x, h, [&](const engine::StateVector<2>& s) {
      const double fz = engine::evaluate_field(field, {0.0, 0.0, s[0]}, {0.0, 0.0, s[1]}).F_T_W.z;
      return engine::StateVector<2>{s[1], (fz + kPush) / kMass};
    });
  };
  auto observe = [&] {
    const double U = engine::evaluate_field(field, {0.0, 0.0, x[0]}, {}).U;
    return std::pair{x[0], 0.5 * kMass * x[1] * x[1] + U - kPush * x[0]};
  };
  return sample_run(c, h, 1.0, advance, observe);
}


// --- The same rendering through the whole server, at loop rates from 100 Hz to 10 kHz -------

/// 001's device as hapticd's simulated point mass (0.01 kg, 0.022 N·s/m; exact under the held
/// force) held by a spring-to-point field (K 1e3 N/m, B 1 N·s/m on the measured velocity: the
/// velocity law) and pushed with a 0.5 N step by the simulated hand, run by simulate_scene —
/// TickRunner, compiled scene, force guard — at loop rate 1/T with the passivity controller off
/// (it would act on what is being measured). Reference: the continuous system in closed form.
/// The configuration is printed in the case's source so that `haptic-lab run` reproduces a run.
constexpr double kServerSpringK = 1e3, kServerSpringB = 1.0, kServerPush = 0.5, kServerAnchorZ = 0.02;

std::string server_spring_config(double period) {
  const long rate = std::lround(1.0 / period);
  return "{\"loop_rate_hz\": " + std::to_string(rate) +
         ", \"time_mode\": \"LOCKSTEP\", \"real_time\": {\"spin_us\": 10}, \"passivity\": {\"enabled\": false}, "
         "\"simulated_point_mass\": {\"mass\": 0.01, \"damping\": 0.022, "
         "\"initial_position\": {\"x\": 0, \"y\": 0, \"z\": 0.02}}, "
         "\"initial_scene\": {\"fields\": [{\"spring_to_point\": {\"anchor\": {\"x\": 0, \"y\": 0, \"z\": 0.02}, "
         "\"stiffness\": 1000, \"damping\": 1}}]}, "
         "\"initial_operator\": {\"mode\": \"APPLY_FORCE\", \"force\": {\"x\": 0, \"y\": 0, \"z\": 0.5}}}";
}

/// "" when `period` is 1/rate for a loop rate hapticd accepts (100 … 10000 Hz), else why not.
std::string tick_period_problem(double period) {
  const long rate = std::lround(1.0 / period);
  if (rate < 100 || rate > 10000 || std::abs(1.0 / static_cast<double>(rate) - period) > 1e-12 * period) {
    return "the step is the tick period, 1/rate for a loop rate of 100 ... 10000 Hz; got " + std::to_string(period) + " s";
  }
  return {};
}

Trajectory server_spring(Scheme scheme, double period, const StudyCase& c) {
  if (scheme != Scheme::kExactZoh) {
    throw std::invalid_argument(c.name + ": the point mass is integrated exactly under the held force; scheme must be exact_zoh");
  }
  if (const std::string problem = tick_period_problem(period); !problem.empty()) {
    throw std::invalid_argument(c.name + ": " + problem);
  }
  const v1::ServerConfig config = config::parse_config(server_spring_config(period), c.name);
  const auto ticks_per_output = static_cast<std::uint64_t>(std::llround(c.output_period_s / period));
  Trajectory out;
  auto record = [&](const runtime::TickSample& s) {
    const double x = s.p_WT.z - kServerAnchorZ, v = s.v_WT.z;
    out.samples.push_back({x, 0.0, 0.0});
    out.energy.push_back(0.5 * 0.01 * v * v + 0.5 * kServerSpringK * x * x - kServerPush * x);
  };
  // The sample of tick k is the state at (k − 1) T; the run covers the duration plus one tick so
  // that the last output instant is sampled too.
  simulate_scene(config, c.duration_s + period, [&](const TickRecord& r) {
    const std::uint64_t index = r.sample.tick - 1;
    if (!(engine::is_finite(r.sample.p_WT) && engine::is_finite(r.sample.v_WT))) {
      out.finite = false;
      return false;
    }
    if (index % ticks_per_output == 0 && out.samples.size() < output_count(c)) record(r.sample);
    if (r.sample.flags & (wire::kFlagForceFault | wire::kFlagDeviceFault)) ++out.fault_ticks;
    return true;
  });
  return out;
}

}  // namespace

std::vector<StudyCase> ode_cases(bool short_suite) {
  // Steps over three decades (1e-5 … 1e-2 s), each dividing the 10 ms output period.
  const std::vector<double> steps =
      short_suite ? std::vector<double>{1e-5, 1e-4, 1e-3, 1e-2}
                  : std::vector<double>{1e-5, 2e-5, 5e-5, 1e-4, 2e-4, 5e-4, 1e-3, 2e-3, 5e-3, 1e-2};
  const std::vector<double> fine_steps =  // for the stiffest cases: down to 1e-6 s
      short_suite ? std::vector<double>{1e-6, 1e-5, 1e-4, 1e-3}
                  : std::vector<double>{1e-6, 2e-6, 5e-6, 1e-5, 2e-5, 5e-5, 1e-4, 2e-4, 5e-4, 1e-3, 1e-2};
  const double duration = short_suite ? 0.2 : 0.5;
  std::vector<StudyCase> cases;

  LinearOscillator wall;  // 001's device mass against the transparency study's wall
  wall.mass = 0.01;
  wall.damping = 1.0;
  wall.stiffness = 1e3;
  wall.x0 = -0.005;
  cases.push_back(oscillator_case(
      "linear_wall", "Linear spring-damper wall, exact solution (m 0.01 kg, K 1e3 N/m, B 1 N·s/m)",
      "001's device mass (Eom et al.); wall as in 001's design, bilateral so the solution is closed-form",
      wall, duration, steps));

  LinearOscillator surface;  // 000 eq. 7.1: f_V = m_V Ẍ + B_V Ẋ, pushed with 1 N from rest
  surface.mass = 0.2;
  surface.damping = 4.0;
  surface.stiffness = 0.0;
  surface.x0 = 0.0;
  surface.force_before = surface.force_after = 1.0;
  cases.push_back(oscillator_case(
      "viscous_surface", "Virtual mass on a viscous surface (m_V 0.2 kg, B_V 4 N·s/m, 1 N push)",
      "000 eq. 7.1, f_V = m_V Ẍ + B_V Ẋ", surface, duration, steps));

  LinearOscillator stiff = wall;
  stiff.stiffness = 1e5;
  stiff.x0 = -1e-3;
  cases.push_back(oscillator_case("stiff_wall", "Stiff wall (K 1e5 N/m, m 0.01 kg, B 1 N·s/m)",
                                  "stiff case: K ≥ 1e5 N/m with m = 0.01 kg", stiff, duration, fine_steps));

  LinearOscillator undamped = wall;
  undamped.stiffness = 1e4;
  undamped.damping = 0.0;
  undamped.x0 = -1e-3;
  cases.push_back(oscillator_case("zero_damping", "Zero damping (K 1e4 N/m, m 0.01 kg, B 0): energy must stay",
                                  "extreme case: zero damping, the energy drift shows the scheme", undamped, duration, steps));

  LinearOscillator tiny = wall;
  tiny.mass = 1e-4;
  tiny.damping = 0.01;  // σ = B/2m = 50 1/s, as the other walls: the motion lasts the run
  tiny.x0 = -1e-3;
  cases.push_back(oscillator_case("tiny_mass", "Tiny mass (m 1e-4 kg, K 1e3 N/m, B 0.01 N·s/m)",
                                  "extreme case: the smallest mass (1e-4 kg)", tiny, duration, fine_steps));

  LinearOscillator hard = wall;
  hard.stiffness = 1e7;
  hard.damping = 1.0;  // σ = 50 1/s: the 5 kHz ringing lasts long enough for the 10 ms samples to see it
  hard.x0 = -1e-4;
  cases.push_back(oscillator_case("huge_stiffness", "K 1e7 N/m (m 0.01 kg, B 1 N·s/m)", "extreme case: the stiffest wall",
                                  hard, short_suite ? 0.1 : 0.2, fine_steps));

  LinearOscillator kick = wall;
  kick.mass = 0.1;
  kick.stiffness = 1e4;
  kick.damping = 10.0;
  kick.x0 = 0.0;
  kick.force_before = 0.0;
  kick.force_after = 1e3;
  kick.step_time = 0.05;
  cases.push_back(oscillator_case("force_step", "Force step of 1e3 N into a wall (K 1e4 N/m, m 0.1 kg, B 10 N·s/m)",
                                  "extreme case: a 1e3 N force step at t = 0.05 s", kick, duration, steps));

  // NaN in the force for 10 ms from t = 0.1 s. Unguarded, the integrator carries it into the state
  // (a non-finite result, reported as such); through engine::ForceGuard, the server's last stage,
  // it becomes zero — the force the scene meant — and the run matches the exact solution.
  for (const bool guarded : {false, true}) {
    LinearOscillator poisoned = wall;
    poisoned.nan_from = 0.1;
    poisoned.nan_until = 0.11;
    poisoned.guarded = guarded;
    cases.push_back(oscillator_case(
        guarded ? "nan_guarded" : "nan_unguarded",
        guarded ? "NaN force for 10 ms, through the force guard" : "NaN force for 10 ms, straight into the plant",
        "extreme case; the guard is engine::ForceGuard, the loop's last stage", poisoned, duration, steps));
  }

  StudyCase friction = describe("joint_friction_models",
      "003 axial joint against a 400 N·m/rad wall: friction models",
      "003 Table 5.4 (axial J, B, f), L2869 (K_p 400), L3211 (smooth model, v0 0.03 rad/s)",
      "joint angle q, rad", "fidelity", duration);
  friction.schemes = {Scheme::kSemiImplicitEuler, Scheme::kRk4, Scheme::kImplicitEuler};
  friction.steps_s = short_suite ? std::vector<double>{1e-5, 1e-4, 1e-3} : std::vector<double>{1e-5, 2e-5, 5e-5, 1e-4, 2e-4, 5e-4, 1e-3};
  friction.variants = {"karnopp", "smooth", "viscous_only"};
  friction.reference_scheme = Scheme::kRk4;
  friction.reference_step_s = short_suite ? 2e-6 : 1e-6;
  set_simulation(friction, joint_with_friction);
  cases.push_back(std::move(friction));

  StudyCase laws = describe("sampled_wall_laws",
      "A wall rendered at tick period T by each impedance law (001's device, K 1e3 N/m, B 1 N·s/m)",
      "000 eqs. 8.9-8.16 (backward difference, exact ZOH), Tustin; the device's motion exact between ticks",
      "tool position x, m", "impedance", duration);
  laws.schemes = {Scheme::kExactZoh};
  laws.steps_s = steps;  // here: the tick period T
  laws.variants = {"velocity", "backward_difference", "exact_zoh", "tustin"};
  set_simulation(laws, sampled_wall);
  LinearOscillator continuous;  // m ẍ + (b + B) ẋ + K x = 0
  continuous.mass = kDeviceMass;
  continuous.damping = kDeviceDamping + kWallB;
  continuous.stiffness = kWallK;
  continuous.x0 = -0.005;
  laws.exact = [continuous, shape = laws] { return exact_solution(continuous, shape); };
  cases.push_back(std::move(laws));

  StudyCase handle = describe("orientation_spring_laws",
      "An orientation spring on the 6-DOF handle at tick period T by each law (I 1e-4 kg·m², k 0.3 N·m/rad)",
      "000 eqs. 8.9-8.16 per axis of the rotation vector; the handle's rotation exact between ticks",
      "handle angle about z, rad", "impedance", 4.0 * duration);  // long enough to see slow ringing up
  handle.schemes = {Scheme::kExactZoh};
  handle.steps_s = steps;  // here: the tick period T
  handle.variants = {"velocity", "backward_difference", "exact_zoh", "tustin"};
  set_simulation(handle, orientation_spring);
  LinearOscillator turning;  // I θ̈ + (b + b_s) θ̇ + k θ = 0
  turning.mass = kHandleInertia;
  turning.damping = kHandleDamping + kHandleSpringB;
  turning.stiffness = kHandleSpringK;
  turning.x0 = kHandleAngle0;
  handle.exact = [turning, shape = handle] { return exact_solution(turning, shape); };
  cases.push_back(std::move(handle));

  StudyCase khatib = describe("khatib_field",
      "Khatib's potential field against a 0.5 N push: gradient analytic or by central differences",
      "004 eq. 5.7 (U = (1/n) K (1/f - 1/f0)^n; central differences, its second equation)",
      "tool height z, m", "fields", duration);
  khatib.schemes.assign(std::begin(kIntegratorSchemes), std::end(kIntegratorSchemes));
  khatib.steps_s = short_suite ? std::vector<double>{1e-5, 1e-4, 1e-3} : std::vector<double>{1e-5, 2e-5, 5e-5, 1e-4, 2e-4, 5e-4, 1e-3, 2e-3};
  khatib.variants = {"analytic", "central_1e-6", "central_1e-3"};
  khatib.reference_scheme = Scheme::kRk4;
  khatib.reference_step_s = short_suite ? 2e-6 : 1e-6;
  khatib.conservative = true;
  set_simulation(khatib, khatib_bounce);
  cases.push_back(std::move(khatib));

  StudyCase server = describe("server_spring_rates",
      "001's device on a spring through the whole server at loop rates 100 Hz ... 10 kHz",
      "hapticd's point mass, spring_to_point field (K 1e3 N/m, B 1 N·s/m), 0.5 N hand step, passivity "
      "controller off; the step is the tick period",
      "tool position z from the anchor, m", "impedance", duration);
  server.schemes = {Scheme::kExactZoh};
  server.steps_s = short_suite ? std::vector<double>{1e-4, 1e-3, 1e-2} : std::vector<double>{1e-4, 2e-4, 5e-4, 1e-3, 2e-3, 5e-3, 1e-2};
  server.check_step = tick_period_problem;
  set_simulation(server, [](Scheme scheme, double period, const std::string&, const StudyCase& shape) {
    return server_spring(scheme, period, shape);
  });
  LinearOscillator spring;  // m ẍ + (b + B) ẋ + K x = F
  spring.mass = kDeviceMass;
  spring.damping = kDeviceDamping + kServerSpringB;
  spring.stiffness = kServerSpringK;
  spring.x0 = 0.0;
  spring.force_before = spring.force_after = kServerPush;
  server.exact = [spring, shape = server] { return exact_solution(spring, shape); };
  cases.push_back(std::move(server));
  return cases;
}

}  // namespace haptic::lab
