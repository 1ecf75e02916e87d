#pragma once
// Time-domain passivity at one device port: the passivity observer (PO) and the passivity
// controller (PC) of Hannaford & Ryu, "Time-domain passivity control of haptic interfaces",
// IEEE Trans. Robotics and Automation 18(1), 2002.
//
// The port is the one between the device and the virtual environment (everything the scene adds).
// Sign convention (Hannaford & Ryu 2002: energy flowing INTO the one-port is positive, and
// the one-port is passive iff its observed energy never goes negative): F_T_W is the force the
// environment puts on the tool and v_WT the tool's velocity, so the tool delivers the power
// −F_T_W·v_WT (Unit: W) to the environment. A passive wall absorbs (E ≥ 0); a wall made active
// by sampling returns more than it took (E < 0).
//
// Runs on the loop: no allocation, no throw. Call reset() when the environment at the port is
// replaced (a new contact or a new scene) if its stored energy should not carry over.

#include <string>

#include "engine/core/vec3.hpp"

namespace haptic::engine {

/// How the observer measures the energy that crossed the port.
enum class PassivityObserverMode {
  /// E(n) = T Σ_{k≤n} −F_T_W(k)·v_WT(k): Hannaford & Ryu's observer as written, the sampled
  /// power. Under a zero-order hold it misses the work the held force does between samples; for a
  /// stiff wall that lasts two or three samples (K = 20000 N/m on 0.01 kg at 1 kHz, ωT = 1.4) it
  /// reads positive while the wall generates energy (the test shows it).
  kSampledPower,
  /// The work the force actually sent did over each completed period, −F(k−1)·(p_WT(k) −
  /// p_WT(k−1)): exact for a ZOH port with an exact position, one tick late (how sampled and
  /// continuous-time passivity differ: Ryu, Kim & Hannaford 2004, "Sampled- and continuous-time
  /// passivity and stability of virtual environments", IEEE T-RO 20(4)). The controller adds to
  /// it the sampled power of the coming period, −T F(n)·v(n), as its prediction.
  kHeldForceWork,
};

/// The passivity observer alone (no control), with the sign above. Unit of E: J.
class PassivityObserver {
 public:
  /// T: the sampling period. Unit: s, > 0.
  explicit PassivityObserver(double T,
                             PassivityObserverMode mode = PassivityObserverMode::kHeldForceWork)
      : period_(T), mode_(mode) {}

  /// Records the tick: F_T_W the force sent this tick (N), v_WT and p_WT the tool's velocity
  /// (m/s) and position (m) it was computed from. Returns E through what is known: for
  /// kSampledPower through this tick's sample, for kHeldForceWork through the last completed
  /// period.
  double observe(const Vec3& F_T_W, const Vec3& v_WT, const Vec3& p_WT) {
    if (mode_ == PassivityObserverMode::kSampledPower) {
      energy_ -= period_ * dot(F_T_W, v_WT);
    } else {
      complete_period(p_WT);
      sent(F_T_W, p_WT);
    }
    return energy_;
  }

  /// kHeldForceWork: books the previous period's work, now that p_WT(k) is known.
  void complete_period(const Vec3& p_WT) {
    if (has_previous_) energy_ -= dot(F_previous_, p_WT - p_previous_);
  }
  /// kHeldForceWork: remembers the force sent at p_WT for the next period.
  void sent(const Vec3& F_T_W, const Vec3& p_WT) {
    F_previous_ = F_T_W;
    p_previous_ = p_WT;
    has_previous_ = true;
  }
  /// kSampledPower: books T (−F·v) directly.
  void add(double energy) { energy_ += energy; }

  double energy() const { return energy_; }  // Unit: J.
  void reset() {
    energy_ = 0.0;
    has_previous_ = false;
  }
  double period() const { return period_; }
  PassivityObserverMode mode() const { return mode_; }

 private:
  double period_;
  PassivityObserverMode mode_;
  double energy_ = 0.0;
  bool has_previous_ = false;
  Vec3 F_previous_;  // Unit: N.
  Vec3 p_previous_;  // Unit: m.
};

struct PassivityControllerParams {
  double period = 1e-3;  // T. Unit: s. Finite, > 0.
  /// α_max: the largest damping the controller adds. Unit: N·s/m. Finite, >= 0.
  /// The PC's damper is applied through the sampler like any virtual damper: on a device of mass
  /// m it changes the velocity over one period by about −(α T/m) v, so α > m/T reverses the
  /// velocity within a tick (the damper itself then oscillates) and α > 2m/T makes it unstable.
  /// passivity_params_for_device sets α_max = m/T, the damper that just stops the mass in one
  /// period.
  double max_damping = 10.0;
  /// v_min: below this speed the controller does nothing. Unit: m/s. Finite, >= 0.
  /// α = −E/(T|v|²) grows without bound as v → 0, and a velocity near the sensor's resolution is
  /// mostly quantization noise whose direction means nothing; the deficit stays in E and is
  /// dissipated on a later tick at which the tool moves.
  double velocity_threshold = 1e-4;
  PassivityObserverMode observer = PassivityObserverMode::kHeldForceWork;
};

/// α_max = m/T and v_min = velocity_resolution for a device of mass m (kg) sampled at T (s).
/// velocity_resolution: Unit m/s (an encoder quantum over T for a differenced velocity).
PassivityControllerParams passivity_params_for_device(double m, double T,
                                                      double velocity_resolution);

/// "" or one message naming the bad field and its value.
std::string validate_passivity(const PassivityControllerParams& params);

/// One tick of the controller.
struct PassivityStep {
  Vec3 F_T_W;          // The force to send: the environment's force plus the PC's damping. N.
  double alpha = 0.0;  // The damping added at this tick, along v: F_T_W −= α v_WT. N·s/m.
  double energy = 0.0; // E(n) after this tick, the PC's dissipation included. Unit: J.
  bool limited = false;  // α was cut at α_max (E stays negative; the rest waits for later ticks).
};

/// The passivity controller for impedance causality (Hannaford & Ryu 2002): with E(n−1) the
/// observer's energy before this tick's force (kHeldForceWork: exact through the period just
/// completed), the environment's force F_T_W(n) and the velocity v_WT(n),
///   E_obs(n) = E(n−1) − T F_T_W(n)·v_WT(n),
///   α(n) = min(α_max, −E_obs(n) / (T |v_WT(n)|²))   if E_obs(n) < 0 and |v_WT(n)| >= v_min,
///   α(n) = 0                                         otherwise,
///   F_out(n) = F_T_W(n) − α(n) v_WT(n),
/// and PassivityStep::energy = E_obs(n) + α(n) T |v_WT(n)|² (zero after a tick that acts
/// unclipped: the controller adds only the damping needed). With kHeldForceWork the prediction
/// T F·v is replaced by the work actually done once the period completes, so a deficit the
/// sampled power missed is dissipated on the following ticks.
/// One damper along v (not one per axis): it dissipates the deficit with the least force, and
/// never pushes across the direction of motion.
class PassivityController {
 public:
  explicit PassivityController(const PassivityControllerParams& params)
      : params_(params), observer_(params.period, params.observer) {}

  /// F_T_W: the environment's force on the tool (N); v_WT, p_WT: the tool's velocity (m/s) and
  /// position (m) it was computed from.
  PassivityStep apply(const Vec3& F_T_W, const Vec3& v_WT, const Vec3& p_WT);

  /// Forgets the stored energy (and the dissipation count).
  void reset() {
    observer_.reset();
    dissipated_ = 0.0;
  }

  double energy() const { return observer_.energy(); }  // E(n). Unit: J.
  double dissipated() const { return dissipated_; }     // T Σ α v². Unit: J.
  const PassivityControllerParams& params() const { return params_; }

 private:
  PassivityControllerParams params_;
  PassivityObserver observer_;
  double dissipated_ = 0.0;
};

}  // namespace haptic::engine
