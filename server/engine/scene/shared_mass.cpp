#include "engine/scene/shared_mass.hpp"

#include <algorithm>
#include <cmath>

#include "engine/core/parameter_checks.hpp"

namespace haptic::engine {

std::string validate(const SharedMassParams& params) {
  if (!is_positive(params.mass)) return bad_parameter("mass", "must be finite and > 0", params.mass);
  if (!is_non_negative(params.damping)) return bad_parameter("damping", "must be finite and >= 0", params.damping);
  if (!is_positive(params.radius)) return bad_parameter("radius", "must be finite and > 0", params.radius);
  if (!is_non_negative(params.contact_stiffness)) {
    return bad_parameter("contact_stiffness", "must be finite and >= 0", params.contact_stiffness);
  }
  if (!is_non_negative(params.coupling_stiffness)) {
    return bad_parameter("coupling_stiffness", "must be finite and >= 0", params.coupling_stiffness);
  }
  if (!is_non_negative(params.coupling_damping)) {
    return bad_parameter("coupling_damping", "must be finite and >= 0", params.coupling_damping);
  }
  if (!is_positive(params.period)) return bad_parameter("period", "must be finite and > 0", params.period);
  return {};
}

SharedMass::SharedMass(const SharedMassParams& params, const SharedMassState& initial)
    : params_(params), state_(initial), weights_(ExactMassDamperStep::of(params.mass, params.damping, params.period)) {}

Vec3 SharedMass::touch(const Vec3& p_WT) {
  const Vec3 apart = p_WT - state_.p_WM;
  const double distance = norm(apart);
  const double depth = params_.radius - distance;
  if (!(depth > 0.0) || !(distance > 0.0)) return {};  // apart, or a non-finite tool: no force
  const Vec3 F = (params_.contact_stiffness * depth / distance) * apart;
  F_contacts_ -= F;
  return F;
}

void CopyCouplings::clear() {
  keys_ = {};
  for (auto& coupling : couplings_) coupling.reset();
  forces_ = {};
}

Vec3 CopyCouplings::force(std::span<const RemoteMassCopy> remotes, const SharedMassState& copy, double mass,
                          const SharedMassParams& params) {
  // The couplings' dampers act on one copy together, each explicitly over the period: their sum
  // stays at M/T (a held damper α on mass M is stable only for α T / M < 2), so each coupling gets
  // its share of it.
  std::size_t active = 0;
  for (std::size_t slot = 0; slot < std::min(remotes.size(), kMaxRemoteCopies); ++slot) {
    if (remotes[slot].key) ++active;
  }
  const double max_damping = mass / params.period / static_cast<double>(std::max<std::size_t>(active, 1));
  Vec3 total;
  for (std::size_t slot = 0; slot < kMaxRemoteCopies; ++slot) {
    const RemoteMassCopy empty;
    const RemoteMassCopy& remote = slot < remotes.size() ? remotes[slot] : empty;
    if (remote.key != keys_[slot]) {
      // Another copy in this slot (or none): a new coupling, with nothing booked.
      keys_[slot] = remote.key;
      couplings_[slot].reset();
      if (remote.key) {
        NetworkPassivityParams layer;
        layer.period = params.period;
        // A copy is no device with sensor noise: the damper acts down to µm/s, or the delayed
        // couplings keep a small oscillation going just below the threshold.
        layer.velocity_threshold = 1e-6;
        // Its velocity holds over a period (a simulated body, no hand on it): the layer may cancel
        // a coupling's whole pull along v, which the damper's cap alone cannot when a stretched
        // spring is let go.
        layer.cancel_along_velocity = true;
        // The copies' springs are the two ends of one coupling, whose storage exists once: neither
        // keeps energy for its own spring (each would keep ½ K d² of it, and a released copy would
        // wait seconds for energy the other holds back). What a copy's layer holds flows out to the
        // other over 50 ms instead of at once, so it can use what it holds while it flows.
        layer.send_time_constant = 0.05;
        // Another site's copy that moves without sending the energy (a forging peer) takes at most
        // this much out of the copy here before the coupling's pull is withheld.
        layer.max_deficit_J = kCouplingMaxDeficitJ;
        couplings_[slot].emplace(layer);
      }
    }
    forces_[slot] = {};
    if (!couplings_[slot]) continue;
    // A non-finite copy from the network (a faulty site) couples nothing this period.
    if (!is_finite(remote.p_WM) || !is_finite(remote.v_WM) || !std::isfinite(remote.energy_sent_to_us)) continue;
    NetworkPassivity& coupling = *couplings_[slot];
    coupling.set_max_damping(max_damping);
    coupling.receive(remote.energy_sent_to_us);
    const Vec3 stretch = remote.p_WM - copy.p_WM;
    Vec3 F = params.coupling_stiffness * stretch + params.coupling_damping * (remote.v_WM - copy.v_WM);
    if (params.passivity_layer) F = coupling.apply(F, copy.v_WM, copy.p_WM, 0.0).F_T_W;
    forces_[slot] = F;
    total += F;
  }
  return total;
}

void SharedMass::step(std::span<const RemoteMassCopy> remotes) {
  const Vec3 F_total = F_contacts_ + couplings_.force(remotes, state_, params_.mass, params_);
  F_contacts_ = {};
  const Vec3 accel = (1.0 / params_.mass) * F_total;
  weights_.advance(state_.p_WM.x, state_.v_WM.x, accel.x);
  weights_.advance(state_.p_WM.y, state_.v_WM.y, accel.y);
  weights_.advance(state_.p_WM.z, state_.v_WM.z, accel.z);
}

}  // namespace haptic::engine
