#pragma once
// Passivity across the network: the energy reservoir of one coupling between this site's tool and
// another site (docs/federation.md, "The passivity layer"). Contact between users at two sites is
// bilateral teleoperation with delay and loss; each site computes its coupling force from the
// other's delayed state, and the pair can create energy (the test shows it: 0.30–0.42 J in 60 s
// at 10–100 ms one way). The layer keeps the pair passive for any delay and loss:
//
//   - each site books the work its coupling force actually did on its own tool over each period,
//     W(k) = F(k−1)·(p(k) − p(k−1)) (the held-force work of PassivityObserver): W < 0 is energy
//     its user put into the coupling, W > 0 energy the coupling gave its user;
//   - its reservoir R holds what it may give: R += −W; energy the other site sent is added when it
//     arrives; energy this site sends is taken out;
//   - its user is never given more than R: when the force about to be applied would deliver more
//     than R over the coming period (predicted T F·v), a damper along v takes the excess out
//     (Hannaford and Ryu's passivity controller), capped at max_damping like theirs (or, for a
//     simulated body, at cancelling the force's component along v where that is more); a
//     reservoir in deficit (a period gave more than predicted) is paid back the same way;
//   - the damper is capped, so against a hand holding still a push gives up to F²T²/2m a period
//     that T F·v does not predict, and such periods add up (a tool moved at the other site without
//     its user putting anything in, as a forging peer's does, took 13 mJ out of a held hand in
//     10 s). So the force is then scaled (s in [0, 1]) to what R + max_deficit_J pays for over
//     the coming period, its own push on the mass m = max_damping T included:
//       s T F·v + s² T² |F|² / 2m ≤ R + max_deficit_J.
//     An honest coupling stays far inside it (its deficits are a few mJ and the term µJ), and
//     whatever the other end does, the coupling gives its user at most what the user put in, plus
//     what was received, plus max_deficit_J;
//   - what R holds beyond the energy stored in this site's own coupling spring (which its user may
//     take back on release, so a contact does not feel plastic) is sent to the other site, as a
//     cumulative total: a lost message is made good by the next, and nothing is counted twice.
//
// Energy is conserved by construction — Σ R + in flight = Σ injected − Σ given ≥ 0 — so the pair
// is passive up to the one-period prediction error of the controller, which the next periods
// dissipate. The basis: the time-domain passivity approach on the network (Ryu, Artigas and
// Preusche, "A passive bilateral control scheme for a teleoperator with time-varying
// communication delay", Mechatronics 20(7), 2010; Artigas, Ryu, Preusche and Hirzinger, "Network
// representation and passivity of delayed teleoperation systems", IROS 2011), with the energy
// each side may return to its own user kept locally.
//
// Runs on the loop: no allocation, no throw.

#include <algorithm>
#include <cmath>
#include <limits>

#include "engine/core/vec3.hpp"

namespace haptic::engine {

/// The deficit hapticd allows its couplings across the network (tools' and shared masses'): above
/// the −1.8 … −3.7 mJ its honest lockstep runs reach at worst across the channel (two light tools'
/// held contact released at once, tests/unit/federation/lockstep_sites_test), far below what a
/// forging peer took before the bound. Unit: J.
inline constexpr double kCouplingMaxDeficitJ = 5e-3;

struct NetworkPassivityParams {
  double period = 1e-3;              // T. Unit: s. > 0.
  /// The damper's cap: m/T stops the device's mass within one period (see
  /// PassivityControllerParams::max_damping). Unit: N·s/m. ≥ 0.
  double max_damping = 50.0;
  double velocity_threshold = 1e-4;  // below it the damper does nothing. Unit: m/s.
  /// Lets the damper cancel the whole force along v where max_damping cannot: a spring the budget
  /// cannot pay for then stops pulling along v, whatever its force. For simulated bodies (shared
  /// masses), whose velocity holds over a period; on a light device pushed by a hand the velocity
  /// reverses within a period and the cancelled force chatters, so devices keep the cap alone.
  bool cancel_along_velocity = false;
  /// τ: what the reservoir holds beyond `stored_J` goes out as a first-order lag of this time
  /// constant instead of at once, so a site can use energy it holds while it flows to the other.
  /// For the copies of a shared mass (which keep nothing for their own springs: the pair's storage
  /// exists once). 0: at once (avatars). Unit: s. ≥ 0.
  double send_time_constant = 0.0;
  /// The most the reservoir may be in deficit: the force is scaled to keep it there (see above).
  /// Unit: J. ≥ 0; infinity: no bound.
  double max_deficit_J = std::numeric_limits<double>::infinity();
};

/// One tick of the layer.
struct NetworkPassivityStep {
  Vec3 F_T_W;          // the force to apply to the tool. Unit: N.
  double alpha = 0.0;  // the damping added along v this tick. Unit: N·s/m.
  double scale = 1.0;   // what the deficit bound left of the force (s above), 1 when it did nothing
};

class NetworkPassivity {
 public:
  explicit NetworkPassivity(const NetworkPassivityParams& params)
      : params_(params),
        send_fraction_(params.send_time_constant > 0.0 ? -std::expm1(-params.period / params.send_time_constant) : 1.0) {}

  /// The coupling force F_T_W requested for the tool at p_WT moving at v_WT (the tick's reading);
  /// stored_J: the energy the coupling spring at this site holds now (½ K d² for a contact; J),
  /// which the reservoir keeps for this site's user. Books the last period's work, limits F, and
  /// moves the reservoir's excess to what is sent.
  NetworkPassivityStep apply(const Vec3& F_T_W, const Vec3& v_WT, const Vec3& p_WT, double stored_J) {
    if (has_previous_) {
      const double W = dot(F_previous_, p_WT - p_previous_);  // work on this site's user
      if (W > 0.0) {
        given_ += W;
      } else {
        injected_ -= W;
      }
      reservoir_ -= W;
    }
    NetworkPassivityStep step;
    step.F_T_W = F_T_W;
    const double predicted = params_.period * dot(F_T_W, v_WT);  // work about to be given
    // A reservoir in deficit (the last period gave more than predicted) is paid back by the next.
    const double budget = reservoir_;
    const double v2 = dot(v_WT, v_WT);
    if (predicted > budget && v2 >= params_.velocity_threshold * params_.velocity_threshold) {
      // The damper is capped at max_damping (a held damper is stable on mass m only below 2m/T),
      // or, with cancel_along_velocity, at cancelling the force's component along v where that is
      // more (α_cancel v = (F·v̂) v̂ only takes back force that was asked for, never reverses it).
      const double cancel = params_.cancel_along_velocity ? std::max(dot(F_T_W, v_WT), 0.0) / v2 : 0.0;
      step.alpha = std::min(std::max(cancel, params_.max_damping), (predicted - budget) / (params_.period * v2));
      step.F_T_W -= step.alpha * v_WT;
    }
    if (std::isfinite(params_.max_deficit_J) && params_.max_damping > 0.0) {
      const double mass = params_.max_damping * params_.period;  // what the damper's cap stops in T
      const double limit = reservoir_ + params_.max_deficit_J;
      const double a = params_.period * params_.period * dot(step.F_T_W, step.F_T_W) / (2.0 * mass);
      const double b = params_.period * dot(step.F_T_W, v_WT);
      if (a + b > limit) {
        const double discriminant = b * b + 4.0 * a * limit;
        step.scale = discriminant < 0.0 ? 0.0 : std::clamp((-b + std::sqrt(discriminant)) / (2.0 * a), 0.0, 1.0);
        step.F_T_W = step.scale * step.F_T_W;
      }
    }
    F_previous_ = step.F_T_W;
    p_previous_ = p_WT;
    has_previous_ = true;
    // The excess over what this site's own spring may return goes to the other site.
    const double keep = std::max(stored_J, 0.0);
    if (reservoir_ > keep) {
      const double excess = send_fraction_ * (reservoir_ - keep);
      sent_ += excess;
      reservoir_ -= excess;
    }
    return step;
  }

  /// The other site's cumulative `sent()` as it arrived (delayed; a lost message is skipped, the
  /// next carries it; an older total than one already taken changes nothing).
  void receive(double remote_sent_total) {
    if (remote_sent_total > received_) {
      reservoir_ += remote_sent_total - received_;
      received_ = remote_sent_total;
    }
  }

  /// Changes the damper's cap (N·s/m, ≥ 0): several couplings on one body share its M/T.
  void set_max_damping(double max_damping) { params_.max_damping = max_damping; }
  double max_damping() const { return params_.max_damping; }

  double sent() const { return sent_; }          // J sent to the other site, cumulative
  double received() const { return received_; } // J received from it, cumulative
  double reservoir() const { return reservoir_; } // J this site may still give its user
  double injected() const { return injected_; }  // J this site's user put in, cumulative
  double given() const { return given_; }        // J the coupling gave this site's user, cumulative

 private:
  NetworkPassivityParams params_;
  double send_fraction_;  // of the excess sent each period: 1 − e^{−T/τ}, 1 without τ
  double reservoir_ = 0.0;
  double sent_ = 0.0;
  double received_ = 0.0;
  double injected_ = 0.0;
  double given_ = 0.0;
  bool has_previous_ = false;
  Vec3 F_previous_;
  Vec3 p_previous_;
};

}  // namespace haptic::engine
