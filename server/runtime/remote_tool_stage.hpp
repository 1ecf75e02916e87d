#pragma once
// The avatars at one device port, a stage of the tick (docs/architecture.md, step 5): each other
// site's tool in the port's mailbox (remote_tools.hpp) is a sphere this port's user touches
// (engine::avatar_contact), through a network passivity layer of its own per coupling whose books
// go to the port's ledger for the relay. A new key in a slot starts a fresh coupling; a tool gone
// from its slot fades out over the output ramp, held where it was last heard, and then its
// coupling ends. Federation only: a port without a mailbox has no stage and does no avatar work.

#include <array>
#include <cstdint>
#include <optional>

#include "engine/core/vec3.hpp"
#include "engine/safety/network_passivity.hpp"
#include "runtime/device.hpp"
#include "runtime/latest_value.hpp"
#include "runtime/remote_tools.hpp"

namespace haptic::runtime {

class RemoteToolStage {
 public:
  /// remote: the mailbox the federation writes; ledger: where each coupling's books go (null:
  /// nowhere). Neither owned. apparent_mass: the device's at its tool (kg; 0: unknown, the layers'
  /// default damper cap). period_s: the tick (s); fade_ticks: a departed tool's fade-out (≥ 1).
  RemoteToolStage(const LatestValue<RemoteToolSet>& remote, CouplingLedger* ledger, const AvatarParams& avatar,
                  double apparent_mass, double period_s, std::int64_t fade_ticks);

  /// On the loop, once a tick with a good reading: the force of every remote tool on this port's
  /// tool, each through its coupling's layer. Unit: N, in W.
  engine::Vec3 force(const ToolReading& reading);

 private:
  const LatestValue<RemoteToolSet>& remote_;
  CouplingLedger* ledger_;
  AvatarParams avatar_;
  double apparent_mass_;
  double period_s_;
  std::int64_t fade_ticks_;
  /// This port's coupling with each remote tool (by slot), and its key.
  std::array<std::optional<engine::NetworkPassivity>, kMaxRemoteTools> couplings_{};
  std::array<std::uint64_t, kMaxRemoteTools> coupling_keys_{};
  /// A remote tool that left its slot: ticks of its fade-out left (0: not fading), and the tool
  /// as last heard.
  std::array<std::int64_t, kMaxRemoteTools> fade_left_{};
  std::array<RemoteTool, kMaxRemoteTools> last_heard_{};
};

}  // namespace haptic::runtime
