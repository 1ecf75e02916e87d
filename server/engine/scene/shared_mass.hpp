#pragma once
// A dynamic object several sites push together (docs/federation.md, "Shared masses"): a sphere of
// mass M each site simulates as its own copy, at its own loop rate, so that its users touch it
// with no network in their contact loop. The copies are held together by a spring-damper from each
// copy to every other site's copy at its delayed position (the coupled-copies architecture of
// distributed haptic virtual environments; each copy is one end of a position–position
// teleoperator), and each of those couplings runs through its own network passivity layer
// (engine/safety/network_passivity.hpp): a delayed spring between two masses creates energy (the
// tests show it ring up at 50–100 ms one way), the layer keeps it passive for any delay and loss.
//
// One period at a site:
//   touch(p_WT) for each local tool   → the force on the tool, F = K_c d n (pushing out of the
//                                        sphere, d the depth, n from the centre to the tool), and
//                                        −F booked on the copy;
//   step(remotes)                      → per remote copy j: F_j = K_s (p_j − p) + B_s (v_j − v),
//                                        limited by that coupling's layer; then the copy advances
//                                        exactly over T under Σ F held (M v' = F − b v).
// A remote copy's key that changes starts a new coupling; a slot left empty ends one.
//
// Runs on the loop: no allocation, no throw.

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>

#include "engine/core/site_key.hpp"
#include "engine/core/vec3.hpp"
#include "engine/device/exact_step.hpp"
#include "engine/safety/network_passivity.hpp"

namespace haptic::engine {

/// Most other sites' copies one copy couples to.
inline constexpr std::size_t kMaxRemoteCopies = 8;

struct SharedMassParams {
  double mass = 0.5;                // M. Unit: kg. > 0.
  /// b: viscous friction to the world, so a released mass comes to rest. Unit: N·s/m. ≥ 0.
  double damping = 1.0;
  double radius = 0.02;             // Unit: m. > 0.
  double contact_stiffness = 500.0; // K_c: a tool inside the sphere. Unit: N/m. ≥ 0.
  double coupling_stiffness = 400;// K_s: between copies. Unit: N/m. ≥ 0.
  double coupling_damping = 2;    // B_s: between copies. Unit: N·s/m. ≥ 0.
  double period = 1e-3;             // T: the loop's period. Unit: s. > 0.
  /// The network passivity layer on every coupling. Off only in studies that show what it
  /// prevents; a server always runs it.
  bool passivity_layer = true;
};

/// "" or one message naming the bad parameter ("mass: must be finite and > 0, got 0").
std::string validate(const SharedMassParams& params);

/// Another site's copy as it arrived (late by the network's delay).
struct RemoteMassCopy {
  SiteKey key;                    // the remote site's copy; none: an empty slot
  Vec3 p_WM;                      // its centre. Unit: m.
  Vec3 v_WM;                      // Unit: m/s.
  double energy_sent_to_us = 0.0; // what its coupling with this copy has sent, cumulative. Unit: J.
  /// The copy has its place (runtime/shared_masses: a joining copy takes a settled one's state
  /// before anyone couples to it).
  bool settled = true;
};

struct SharedMassState {
  Vec3 p_WM;  // centre. Unit: m.
  Vec3 v_WM;  // Unit: m/s.
};

/// The couplings of one copy to the other sites' copies, each through its own network passivity
/// layer: what SharedMass steps with, and what the loop adds to a scene's virtual mass shared
/// across sites (runtime/shared_masses). No allocation, no throw.
class CopyCouplings {
 public:
  /// The coupling force on a copy of mass `mass` (kg) at `copy` over the coming period, from
  /// `remotes` (slot i is remote i; at most kMaxRemoteCopies), with params' coupling stiffness,
  /// damping, period and layer switch. Books each coupling's layer.
  Vec3 force(std::span<const RemoteMassCopy> remotes, const SharedMassState& copy, double mass,
             const SharedMassParams& params);

  SiteKey key(std::size_t slot) const { return keys_[slot]; }
  double energy_sent(std::size_t slot) const { return couplings_[slot] ? couplings_[slot]->sent() : 0.0; }
  const NetworkPassivity* coupling(std::size_t slot) const {
    return couplings_[slot] ? &*couplings_[slot] : nullptr;
  }
  /// The force slot i applied over the last period (after its layer). Unit: N.
  const Vec3& force_of(std::size_t slot) const { return forces_[slot]; }
  /// Ends every coupling (the copy went).
  void clear();

 private:
  std::array<SiteKey, kMaxRemoteCopies> keys_{};
  std::array<std::optional<NetworkPassivity>, kMaxRemoteCopies> couplings_{};
  std::array<Vec3, kMaxRemoteCopies> forces_{};
};

class SharedMass {
 public:
  SharedMass(const SharedMassParams& params, const SharedMassState& initial);

  /// The force on a tool at p_WT (N, W frame): pushes it out of the sphere; the reaction acts on
  /// the copy at the next step(). Call once per tool per period, before step().
  Vec3 touch(const Vec3& p_WT);

  /// One period: the couplings to `remotes` (slot i is remote i; at most kMaxRemoteCopies) and the
  /// reactions booked by touch(), then the copy's exact step.
  void step(std::span<const RemoteMassCopy> remotes);

  const SharedMassState& state() const { return state_; }
  const SharedMassParams& params() const { return params_; }

  /// Slot i's coupling: the remote copy it couples to (0: none), what it sent (cumulative, J),
  /// and its layer's books. The energy sent goes to that remote site with this copy's state.
  SiteKey coupling_key(std::size_t slot) const { return couplings_.key(slot); }
  double energy_sent(std::size_t slot) const { return couplings_.energy_sent(slot); }
  const NetworkPassivity* coupling(std::size_t slot) const { return couplings_.coupling(slot); }
  /// The force slot i's coupling applied over the last period (after its layer). Unit: N.
  const Vec3& coupling_force(std::size_t slot) const { return couplings_.force_of(slot); }

 private:
  SharedMassParams params_;
  SharedMassState state_;
  ExactMassDamperStep weights_;
  Vec3 F_contacts_;  // the tools' reactions booked this period. Unit: N.
  CopyCouplings couplings_;
};

}  // namespace haptic::engine
