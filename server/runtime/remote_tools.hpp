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
  std::uint64_t key = 0;         // the remote site and port (engine::tool_key); 0: an empty slot
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

/// Each coupling's books (its network passivity layer's, cumulative, J), for the sender thread
/// (what it sent goes to the remote tool's site) and the stats: written by the loop, read anywhere
/// (relaxed atomics; a reader may see one field a tick newer than another).
struct CouplingBooks {
  std::uint64_t key = 0;  // the remote tool; 0: no coupling in the slot
  double sent = 0.0;
  double received = 0.0;
  double injected = 0.0;  // what this port's user put in
  double given = 0.0;     // what the coupling gave this port's user
  double reservoir = 0.0;
};

class CouplingLedger {
 public:
  void record(std::size_t slot, const CouplingBooks& books) {
    Slot& s = slots_[slot];
    s.key.store(books.key, std::memory_order_relaxed);
    s.sent.store(books.sent, std::memory_order_relaxed);
    s.received.store(books.received, std::memory_order_relaxed);
    s.injected.store(books.injected, std::memory_order_relaxed);
    s.given.store(books.given, std::memory_order_relaxed);
    s.reservoir.store(books.reservoir, std::memory_order_relaxed);
  }
  std::uint64_t key(std::size_t slot) const { return slots_[slot].key.load(std::memory_order_relaxed); }
  double sent(std::size_t slot) const { return slots_[slot].sent.load(std::memory_order_relaxed); }
  CouplingBooks books(std::size_t slot) const {
    const Slot& s = slots_[slot];
    return {s.key.load(std::memory_order_relaxed),      s.sent.load(std::memory_order_relaxed),
            s.received.load(std::memory_order_relaxed), s.injected.load(std::memory_order_relaxed),
            s.given.load(std::memory_order_relaxed),    s.reservoir.load(std::memory_order_relaxed)};
  }

 private:
  struct Slot {
    std::atomic<std::uint64_t> key{0};
    std::atomic<double> sent{0.0}, received{0.0}, injected{0.0}, given{0.0}, reservoir{0.0};
  };
  std::array<Slot, kMaxRemoteTools> slots_{};
};

}  // namespace haptic::runtime
