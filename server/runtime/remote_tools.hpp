#pragma once
// Other sites' tools at a device port (docs/federation.md): the federation's receiver thread
// writes what arrived into a mailbox the loop reads each tick, and the loop renders each as a
// touchable sphere (an avatar) through its own coupling's network passivity layer; what each
// coupling sent to the other site goes back out through a ledger the sender thread reads.

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>

#include "engine/core/vec3.hpp"

namespace haptic::runtime {

/// Most other sites' tools one port renders (a federation of up to 9 sites, one port each).
inline constexpr std::size_t kMaxRemoteTools = 8;

/// Another site's tool as it arrived. Slot i of a RemoteToolSet keeps one remote tool while its
/// key stays; a new key in a slot starts a new coupling there.
struct RemoteTool {
  std::uint64_t key = 0;         // the remote site and port; 0: an empty slot
  engine::Vec3 p_WT;             // its position as received (late by the network's delay). Unit: m.
  engine::Vec3 v_WT;             // Unit: m/s.
  double energy_sent_to_us = 0.0;  // what its coupling with this port has sent, cumulative. Unit: J.
};

struct RemoteToolSet {
  std::array<RemoteTool, kMaxRemoteTools> tools{};
};

/// The avatar every remote tool is rendered as: a sphere about its position that pushes this
/// port's tool out (a frictionless contact, F = K d n − B (v − v_remote)·n n, pushing only).
struct AvatarParams {
  double radius = 0.01;      // Unit: m. > 0: tools nearer than this touch.
  double stiffness = 500.0;  // K. Unit: N/m. ≥ 0.
  double damping = 0.0;      // B. Unit: N·s/m. ≥ 0.
};

/// What each coupling has sent to its remote tool (cumulative, J), for the sender thread: written
/// by the loop, read anywhere (relaxed atomics).
class CouplingLedger {
 public:
  void record(std::size_t slot, std::uint64_t key, double sent) {
    keys_[slot].store(key, std::memory_order_relaxed);
    sent_[slot].store(sent, std::memory_order_relaxed);
  }
  std::uint64_t key(std::size_t slot) const { return keys_[slot].load(std::memory_order_relaxed); }
  double sent(std::size_t slot) const { return sent_[slot].load(std::memory_order_relaxed); }

 private:
  std::array<std::atomic<std::uint64_t>, kMaxRemoteTools> keys_{};
  std::array<std::atomic<double>, kMaxRemoteTools> sent_{};
};

}  // namespace haptic::runtime
