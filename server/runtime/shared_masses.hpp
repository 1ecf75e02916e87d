#pragma once
// Virtual masses shared across the sites of a federation (docs/federation.md, "Shared masses"):
// each site's scene holds its own copy of the mass (the item replicated by the shared scene) and
// moves it at its own loop rate under its own tools; once a tick, after every port and before the
// masses advance, this stage adds to each shared copy the couplings to the other sites' copies
// (engine::CopyCouplings, each through its network passivity layer). The federation's thread
// writes the other sites' copies into a mailbox the loop reads, and reads back what the loop
// moved and what each coupling sent.

#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "engine/core/site_key.hpp"
#include "engine/scene/compiled_scene.hpp"
#include "engine/scene/shared_mass.hpp"
#include "runtime/latest_value.hpp"

namespace haptic::runtime {

/// Most masses shared across sites one scene couples (a mailbox is copied every tick).
inline constexpr std::size_t kMaxSharedMasses = 4;

/// The other sites' copies of one shared mass as they arrived; copy i's key is its site's key.
struct RemoteMassCopies {
  std::uint64_t mass_key = 0;  // 0: unused
  std::array<engine::RemoteMassCopy, engine::kMaxRemoteCopies> copies{};
};
struct RemoteMassTable {
  std::array<RemoteMassCopies, kMaxSharedMasses> masses{};
};

/// This site's copy of one shared mass as the loop moved it, and what its couplings sent.
struct LocalMassCopy {
  std::uint64_t mass_key = 0;  // 0: unused
  engine::Vec3 p_WM;           // where its origin is. Unit: m.
  engine::Vec3 v_WM;           // Unit: m/s.
  std::array<engine::SiteKey, engine::kMaxRemoteCopies> coupled_site{};  // none: no coupling in the slot
  std::array<double, engine::kMaxRemoteCopies> sent{};                 // cumulative. Unit: J.
  /// The rest of each coupling's books (cumulative, J), for the stats.
  std::array<double, engine::kMaxRemoteCopies> received{};
  std::array<double, engine::kMaxRemoteCopies> injected{};
  std::array<double, engine::kMaxRemoteCopies> given{};
  std::array<double, engine::kMaxRemoteCopies> reservoir{};
  /// It has its place: it took a settled copy's state when it joined, or found none to take
  /// within kSettleTime. Other sites couple to it only then.
  bool settled = false;
};
struct LocalMassTable {
  std::uint64_t tick = 0;  // the tick that moved them
  std::array<LocalMassCopy, kMaxSharedMasses> masses{};
};

/// The couplings between copies: stiffness and damping (the same at every site), and the layer.
struct MassCouplingParams {
  double stiffness = 400.0;  // K_s. Unit: N/m.
  double damping = 2.0;      // B_s. Unit: N·s/m.
};

/// How long a new copy waits for a settled copy of another site to take its state from before it
/// settles where it is (the first copy, or every copy new at once). Longer than a site's first
/// samples take to arrive; shorter than the relay's silence before it drops a copy. Unit: s.
inline constexpr double kSettleTime = 0.25;

/// A copy that joins takes the shared mass where it is. A site that creates its copy (it joins
/// late, or restarted) has the mass where the item's description put it, which the others' users
/// may have pushed far from; coupled at once, it would drag their copies back with nobody touching
/// them. So a new copy does not couple while it is not settled, and no site couples to a copy
/// that is not: when a settled copy of another site arrives, the new copy takes its position and
/// velocity (late by the network's one-way delay) and settles; without one for kSettleTime it
/// settles where it is.
class SharedMassStage {
 public:
  /// own_site: this site's key; in: the other sites' copies (written by the federation); out:
  /// this site's copies (read by it). Neither owned.
  SharedMassStage(engine::SiteKey own_site, const MassCouplingParams& coupling, double period_s,
                  const LatestValue<RemoteMassTable>* in, LatestValue<LocalMassTable>* out);

  /// On the loop, after every port and before engine::advance_scene. Nothing for a scene without
  /// shared masses (once the last coupling has ended). No allocation.
  void run(const engine::CompiledScene& scene, std::uint64_t tick);

  /// Shared masses the scene held beyond kMaxSharedMasses (not coupled), so far.
  std::uint64_t over_capacity() const { return over_capacity_; }
  /// The couplings of mass `mass_key` (null: not coupled now). On the loop's thread, or while it
  /// runs no tick (lockstep tests).
  const engine::CopyCouplings* couplings_of(std::uint64_t mass_key) const {
    for (const Slot& slot : slots_) {
      if (slot.mass_key == mass_key && mass_key != 0) return &slot.couplings;
    }
    return nullptr;
  }

 private:
  struct Slot {
    std::uint64_t mass_key = 0;
    engine::CopyCouplings couplings;
    bool settled = false;
    std::uint64_t first_tick = 0;  // the tick the copy came into the slot
  };

  engine::SiteKey own_site_;
  engine::SharedMassParams params_;  // the couplings' stiffness, damping, period
  const LatestValue<RemoteMassTable>* in_;
  LatestValue<LocalMassTable>* out_;
  std::array<Slot, kMaxSharedMasses> slots_{};
  bool any_ = false;  // some slot is in use
  std::uint64_t over_capacity_ = 0;
};

}  // namespace haptic::runtime
