#include "runtime/remote_tool_stage.hpp"

#include "engine/safety/passive_source.hpp"
#include "engine/scene/avatar_contact.hpp"

namespace haptic::runtime {

RemoteToolStage::RemoteToolStage(const LatestValue<RemoteToolSet>& remote, CouplingLedger* ledger,
                                 const AvatarParams& avatar, double apparent_mass, double period_s,
                                 std::int64_t fade_ticks)
    : remote_(remote),
      ledger_(ledger),
      avatar_(avatar),
      apparent_mass_(apparent_mass),
      period_s_(period_s),
      fade_ticks_(fade_ticks) {}

engine::Vec3 RemoteToolStage::force(const ToolReading& reading) {
  const RemoteToolSet remote = remote_.load();
  engine::Vec3 total;
  for (std::size_t slot = 0; slot < kMaxRemoteTools; ++slot) {
    RemoteTool tool = remote.tools[slot];
    if (tool.key == 0 && coupling_keys_[slot] != 0 && fade_left_[slot] == 0) {
      // Its site went quiet: the avatar fades out over the output ramp, as a removed item does,
      // held where the tool was last heard and still limited by the coupling's layer.
      fade_left_[slot] = fade_ticks_;
    }
    if (fade_left_[slot] > 0 && tool.key == 0) {
      tool = last_heard_[slot];
      tool.v_WT = {};
    } else if (tool.key != coupling_keys_[slot] || (tool.key != 0 && fade_left_[slot] > 0)) {
      // Another remote tool in this slot (or the same one back while fading): a new coupling,
      // with nothing booked.
      fade_left_[slot] = 0;
      coupling_keys_[slot] = tool.key;
      couplings_[slot].reset();
      if (tool.key != 0) couplings_[slot].emplace(engine::port_layer_params(apparent_mass_, period_s_));
    }
    if (!couplings_[slot]) {
      // No coupling in the slot: its books are cleared once, not written every tick.
      if (ledger_ && ledger_->key(slot) != 0) ledger_->record(slot, CouplingBooks{});
      continue;
    }
    double gain = 1.0;
    if (fade_left_[slot] > 0) {
      gain = static_cast<double>(fade_left_[slot]) / static_cast<double>(fade_ticks_);
      if (--fade_left_[slot] == 0) {  // faded: the coupling ends
        coupling_keys_[slot] = 0;
        couplings_[slot].reset();
        if (ledger_) ledger_->record(slot, CouplingBooks{});
        continue;
      }
    } else {
      last_heard_[slot] = tool;
    }
    engine::NetworkPassivity& coupling = *couplings_[slot];
    coupling.receive(tool.energy_sent_to_us);
    const engine::AvatarContact contact = engine::avatar_contact(
        reading.p_WT, reading.v_WT, tool.p_WT, tool.v_WT, avatar_.radius, avatar_.stiffness, avatar_.damping, gain);
    total += coupling.apply(contact.F_T_W, reading.v_WT, reading.p_WT, contact.stored_J).F_T_W;
    if (ledger_) {
      ledger_->record(slot, CouplingBooks{coupling_keys_[slot], coupling.sent(), coupling.received(),
                                          coupling.injected(), coupling.given(), coupling.reservoir()});
    }
  }
  return total;
}

}  // namespace haptic::runtime
