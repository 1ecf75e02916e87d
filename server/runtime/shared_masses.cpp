#include "runtime/shared_masses.hpp"

#include <array>

namespace haptic::runtime {

SharedMassStage::SharedMassStage(engine::SiteKey own_site, const MassCouplingParams& coupling, double period_s,
                                 const LatestValue<RemoteMassTable>* in, LatestValue<LocalMassTable>* out)
    : own_site_(own_site), in_(in), out_(out) {
  params_.coupling_stiffness = coupling.stiffness;
  params_.coupling_damping = coupling.damping;
  params_.period = period_s;
}

void SharedMassStage::run(const engine::CompiledScene& scene, std::uint64_t tick) {
  if (scene.shared_masses.empty() && !any_) return;
  const RemoteMassTable remote = in_->load();
  LocalMassTable local;
  local.tick = tick;
  std::array<bool, kMaxSharedMasses> seen{};
  for (const std::uint32_t contact : scene.shared_masses) {
    const engine::CompiledContact& compiled = scene.contacts[contact];
    const std::uint64_t key =
        engine::shared_mass_key(compiled.origin_site ? compiled.origin_site : own_site_, compiled.origin_id);
    std::size_t slot = kMaxSharedMasses;
    for (std::size_t i = 0; i < kMaxSharedMasses && slot == kMaxSharedMasses; ++i) {
      if (slots_[i].mass_key == key) slot = i;
    }
    for (std::size_t i = 0; i < kMaxSharedMasses && slot == kMaxSharedMasses; ++i) {
      if (slots_[i].mass_key == 0) {
        slot = i;
        slots_[i].mass_key = key;
        slots_[i].couplings.clear();
        slots_[i].settled = false;
        slots_[i].first_tick = tick;
      }
    }
    if (slot == kMaxSharedMasses) {
      ++over_capacity_;
      continue;
    }
    seen[slot] = true;
    Slot& s = slots_[slot];
    // The copies this one couples to: the settled ones, once it is settled itself.
    std::array<engine::RemoteMassCopy, engine::kMaxRemoteCopies> settled{};
    const engine::RemoteMassCopy* first_settled = nullptr;
    for (const RemoteMassCopies& entry : remote.masses) {
      if (entry.mass_key != key) continue;
      for (std::size_t i = 0; i < engine::kMaxRemoteCopies; ++i) {
        const engine::RemoteMassCopy& copy = entry.copies[i];
        if (!copy.key || !copy.settled) continue;
        settled[i] = copy;
        if (first_settled == nullptr && engine::is_finite(copy.p_WM) && engine::is_finite(copy.v_WM)) {
          first_settled = &entry.copies[i];
        }
      }
    }
    if (!s.settled) {
      if (first_settled != nullptr) {
        // Joining a mass others have: take it where they have it, before anything couples.
        engine::place_mass(scene, contact, first_settled->p_WM, first_settled->v_WM);
        s.settled = true;
      } else if (static_cast<double>(tick - s.first_tick) * params_.period >= kSettleTime) {
        s.settled = true;  // nobody had it: it is where this site made it
      }
    }
    if (!s.settled) settled = {};
    const engine::MassNow now = engine::mass_now(scene, contact);
    const engine::Vec3 F = s.couplings.force(settled, {now.p_WO, now.v_WO}, compiled.object_mass, params_);
    engine::push_mass(scene, contact, F);
    LocalMassCopy& out = local.masses[slot];
    out.mass_key = key;
    out.settled = s.settled;
    out.p_WM = now.p_WO;
    out.v_WM = now.v_WO;
    for (std::size_t i = 0; i < engine::kMaxRemoteCopies; ++i) {
      out.coupled_site[i] = slots_[slot].couplings.key(i);
      if (const engine::NetworkPassivity* layer = slots_[slot].couplings.coupling(i)) {
        out.sent[i] = layer->sent();
        out.received[i] = layer->received();
        out.injected[i] = layer->injected();
        out.given[i] = layer->given();
        out.reservoir[i] = layer->reservoir();
      }
    }
  }
  any_ = false;
  for (std::size_t i = 0; i < kMaxSharedMasses; ++i) {
    if (!seen[i] && slots_[i].mass_key != 0) {
      // The mass left the scene (removed, or its site went): its couplings end.
      slots_[i].mass_key = 0;
      slots_[i].couplings.clear();
    }
    any_ = any_ || slots_[i].mass_key != 0;
  }
  out_->store(local);
}

}  // namespace haptic::runtime
