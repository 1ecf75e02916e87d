// What a new compiled scene takes over from the last (carry_state: contacts, filters, god
// objects, motions and meters, by item key), and the scene state read out for the stats
// (object_motions, energy_totals). Off the loop but carry_state, which the loop runs at adoption.
#include "engine/scene/compiled_scene.hpp"

#include <algorithm>
#include <span>
#include <vector>

namespace haptic::engine {

namespace {

/// One port's part of a per-port array (port-major, per_port entries a port).
template <class T>
std::span<T> port_slice(std::vector<T>& items, std::uint32_t port, std::uint32_t per_port) {
  return {items.data() + std::size_t{port} * per_port, per_port};
}

/// Copies the state of every item version both sides hold, matched by key. Both sides are short
/// and compiled in item order, in which keys ascend except where a newer version (a larger key)
/// follows; a merge over key-sorted views would need scratch space, so match by a forward scan
/// with a moving start (linear when the orders agree, which is the rule).
template <class State, class Copy>
void carry_by_key(std::span<const State> old_items, std::span<State> new_items, Copy copy) {
  std::size_t start = 0;
  for (State& item : new_items) {
    for (std::size_t probe = 0; probe < old_items.size(); ++probe) {
      const std::size_t i = (start + probe) % old_items.size();
      if (old_items[i].key == item.key) {
        copy(old_items[i], item);
        start = i + 1;
        break;
      }
    }
  }
}

/// A virtual mass moves once, whichever tools push it: its motion carries once, by port 0's keys
/// (every port holds the same item versions in the same order), from the same version or else
/// from the item's newest old version.
template <class State>
void carry_motions(std::span<const State> old_keys, std::span<const State> new_keys,
                   const std::vector<ContactMotion>& old_motions,
                   std::vector<ContactMotion>& new_motions) {
  for (std::size_t j = 0; j < new_keys.size(); ++j) {
    std::size_t source = old_keys.size();
    std::size_t newest = old_keys.size();
    for (std::size_t i = 0; i < old_keys.size(); ++i) {
      if (old_keys[i].key == new_keys[j].key) {
        source = i;
        break;
      }
      if (old_keys[i].id == new_keys[j].id &&
          (newest == old_keys.size() || old_keys[i].key > old_keys[newest].key)) {
        newest = i;
      }
    }
    if (source == old_keys.size()) source = newest;
    if (source == old_keys.size()) continue;
    new_motions[j].displacement_W = old_motions[source].displacement_W;
    new_motions[j].velocity_W = old_motions[source].velocity_W;
  }
}

/// One port's stateful contacts: each version's proxy, filter history and touching flag.
void carry_contacts(std::span<const ContactState> old_contacts, std::span<ContactState> new_contacts) {
  carry_by_key(old_contacts, new_contacts, [](const ContactState& a, ContactState& b) {
    b.proxy = a.proxy;
    b.touching = a.touching;
    // The filter's weights are the new version's own; only its past samples carry over.
    b.filter.copy_history_from(a.filter);
  });
  // A new version of a contact (a client changed its pose or impedance) continues from its
  // item's newest old version: a discrete law its past samples (no damper spike from a
  // restarted difference), a friction proxy its place on the surface (in the object frame).
  for (ContactState& fresh : new_contacts) {
    const ContactState* newest = nullptr;
    for (const ContactState& old : old_contacts) {
      if (old.key == fresh.key) {
        newest = nullptr;
        break;
      }
      if (old.id == fresh.id && (!newest || old.key > newest->key)) newest = &old;
    }
    if (newest) {
      fresh.proxy = newest->proxy;
      fresh.touching = newest->touching;
      fresh.filter.copy_history_from(newest->filter);
    }
  }
}

/// One port's orientation fields: each version's spring filters, and a new version of a spring
/// continues from its item's newest old version's (no damper spike when a client moves the target).
void carry_orientations(std::span<const OrientationState> old_fields,
                        std::span<OrientationState> new_fields) {
  carry_by_key(old_fields, new_fields, [](const OrientationState& a, OrientationState& b) {
    b.spring.copy_history_from(a.spring);
  });
  for (OrientationState& fresh : new_fields) {
    const OrientationState* newest = nullptr;
    for (const OrientationState& old : old_fields) {
      if (old.key == fresh.key) {
        newest = nullptr;
        break;
      }
      if (old.id == fresh.id && (!newest || old.key > newest->key)) newest = &old;
    }
    if (newest) fresh.spring.copy_history_from(newest->spring);
  }
}

/// One port's meshes: each version's god object and friction anchor.
void carry_meshes(std::span<const MeshState> old_meshes, std::span<MeshState> new_meshes) {
  carry_by_key(old_meshes, new_meshes, [](const MeshState& a, MeshState& b) {
    b.god = a.god;
    b.needs_rebase = a.needs_rebase;
    b.anchor_O = a.anchor_O;
    b.anchored = a.anchored;
    b.sliding = a.sliding;
  });
  // A mesh version new to this snapshot takes over the god object of its item's newest old version.
  for (MeshState& fresh : new_meshes) {
    if (fresh.god.initialized) continue;
    const MeshState* newest = nullptr;
    for (const MeshState& old : old_meshes) {
      if (old.id == fresh.id && old.key != fresh.key && (!newest || old.key > newest->key)) newest = &old;
    }
    if (newest && newest->god.initialized) {
      fresh.god = newest->god;
      fresh.needs_rebase = true;
    }
  }
}

/// Energy meters, matched once by key for every port (a forward scan with a moving start: linear
/// when the two snapshots list their items in the same order, the rule): for each new meter the
/// old one it continues, and which old meters were taken.
void match_meters(SceneState& old_state, SceneState& new_state) {
  std::fill(old_state.meter_taken.begin(), old_state.meter_taken.end(), std::uint8_t{0});
  std::size_t start = 0;
  const std::size_t old_count = old_state.meter_keys.size();
  for (std::size_t j = 0; j < new_state.meter_keys.size(); ++j) {
    new_state.meter_source[j] = SceneState::kNoMeter;
    for (std::size_t probe = 0; probe < old_count; ++probe) {
      const std::size_t i = (start + probe) % old_count;
      if (old_state.meter_keys[i] == new_state.meter_keys[j]) {
        new_state.meter_source[j] = static_cast<std::uint32_t>(i);
        old_state.meter_taken[i] = 1;
        start = i + 1;
        break;
      }
    }
  }
}

/// One port's meters, as match_meters paired them.
void carry_meters(const SceneState& old_state, SceneState& new_state, std::uint32_t port) {
  const std::size_t old_base = std::size_t{port} * old_state.meters_per_port;
  const std::size_t new_base = std::size_t{port} * new_state.meters_per_port;
  for (std::size_t j = 0; j < new_state.meter_keys.size(); ++j) {
    if (new_state.meter_source[j] != SceneState::kNoMeter) {
      new_state.meters[new_base + j] = old_state.meters[old_base + new_state.meter_source[j]];
    }
  }
  // A version that is gone leaves its totals to a remaining version of the same item.
  for (std::size_t i = 0; i < old_state.meter_keys.size(); ++i) {
    if (old_state.meter_taken[i]) continue;
    for (std::size_t j = 0; j < new_state.meter_keys.size(); ++j) {
      if (new_state.meter_ids[j] == old_state.meter_ids[i]) {
        EnergyMeter& heir = new_state.meters[new_base + j];
        const EnergyMeter& gone = old_state.meters[old_base + i];
        heir.work += gone.work;
        heir.work_out += gone.work_out;
        heir.work_in += gone.work_in;
        break;
      }
    }
  }
}

/// Publishes every carried meter's totals for GetSceneEnergy.
void publish_meters(SceneState& state) {
  for (std::size_t j = 0; j < state.meters.size(); ++j) {
    state.work_out[j].store(state.meters[j].work_out, std::memory_order_relaxed);
    state.work_in[j].store(state.meters[j].work_in, std::memory_order_relaxed);
  }
}

}  // namespace

void carry_state(const CompiledScene& from, const CompiledScene& to) {
  if (from.run != to.run) return;  // a reset: every item starts afresh
  SceneState& old_state = *from.state;  // the loop owns both states; meter_taken is scratch
  SceneState& new_state = *to.state;
  carry_motions<ContactState>(port_slice(old_state.contacts, 0, old_state.contacts_per_port),
                              port_slice(new_state.contacts, 0, new_state.contacts_per_port),
                              old_state.motions, new_state.motions);
  carry_motions<MeshState>(port_slice(old_state.meshes, 0, old_state.meshes_per_port),
                           port_slice(new_state.meshes, 0, new_state.meshes_per_port),
                           old_state.mesh_motions, new_state.mesh_motions);
  match_meters(old_state, new_state);
  const std::uint32_t ports = std::min(old_state.ports, new_state.ports);
  for (std::uint32_t port = 0; port < ports; ++port) {
    carry_contacts(port_slice(old_state.contacts, port, old_state.contacts_per_port),
                   port_slice(new_state.contacts, port, new_state.contacts_per_port));
    carry_meshes(port_slice(old_state.meshes, port, old_state.meshes_per_port),
                 port_slice(new_state.meshes, port, new_state.meshes_per_port));
    carry_orientations(port_slice(old_state.orientations, port, old_state.orientations_per_port),
                       port_slice(new_state.orientations, port, new_state.orientations_per_port));
    carry_meters(old_state, new_state, port);
  }
  publish_meters(new_state);
}

std::vector<ObjectMotion> object_motions(const CompiledScene& scene) {
  const SceneState& state = *scene.state;
  std::vector<ObjectMotion> out;
  for (const CompiledContact& contact : scene.contacts) {
    if (contact.object_mass <= 0.0) continue;
    const ContactState& s = state.contacts[contact.state];
    ObjectMotion motion;
    motion.id = s.id;
    const auto at = [&](int k) { return state.motion[6 * contact.state + k].load(std::memory_order_relaxed); };
    motion.p_WO = {at(0), at(1), at(2)};
    motion.v_WO = {at(3), at(4), at(5)};
    // The live version of an item is compiled before its superseded ones: keep the first.
    auto it = std::find_if(out.begin(), out.end(), [&](const ObjectMotion& m) { return m.id == motion.id; });
    if (it == out.end()) out.push_back(motion);
  }
  for (const CompiledMesh& mesh : scene.meshes) {
    if (mesh.object_mass <= 0.0) continue;
    ObjectMotion motion;
    motion.id = state.meshes[mesh.state].id;
    const auto at = [&](int k) { return state.mesh_motion[6 * mesh.state + k].load(std::memory_order_relaxed); };
    motion.p_WO = {at(0), at(1), at(2)};
    motion.v_WO = {at(3), at(4), at(5)};
    auto it = std::find_if(out.begin(), out.end(), [&](const ObjectMotion& m) { return m.id == motion.id; });
    if (it == out.end()) out.push_back(motion);
  }
  return out;
}

std::vector<ItemEnergyTotals> energy_totals(const CompiledScene& scene) {
  const SceneState& state = *scene.state;
  std::vector<ItemEnergyTotals> out;
  for (std::size_t i = 0; i < state.meter_ids.size(); ++i) {
    const std::uint64_t id = state.meter_ids[i];
    auto it = std::find_if(out.begin(), out.end(), [&](const ItemEnergyTotals& e) { return e.id == id; });
    if (it == out.end()) {
      out.push_back({id, state.meter_sessions[i], state.meter_is_object[i] != 0, 0.0, 0.0});
      it = out.end() - 1;
    }
    for (std::size_t port = 0; port < state.ports; ++port) {
      const std::size_t meter = port * state.meters_per_port + i;
      it->given += state.work_out[meter].load(std::memory_order_relaxed);
      it->absorbed += state.work_in[meter].load(std::memory_order_relaxed);
    }
  }
  return out;
}

}  // namespace haptic::engine
