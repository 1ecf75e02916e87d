#include "federation/sample_relay.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

namespace haptic::federation {

namespace {

std::chrono::steady_clock::duration log_window(const RelayOptions& options) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(options.log_window_s));
}

std::string seconds(std::chrono::steady_clock::duration d) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f", std::chrono::duration<double>(d).count());
  return text;
}

}  // namespace


SampleRelay::SampleRelay(const RelayOptions& options, const std::vector<RelayPort>& ports, RelayMasses masses)
    : options_(options),
      ports_(ports),
      participant_(std::make_unique<Participant>(options.domain)),
      masses_(masses),
      masses_on_(masses.local != nullptr && masses.remote != nullptr),
      peer_log_(log_window(options)) {
  dds_ = std::make_unique<DdsTransport>(*participant_, options_.site, options_.tools, masses_on_);
  transport_ = dds_.get();
  // An observer's permissions refuse the mass topic's writer: this site's copies are not
  // published (it still couples to the others'), and hapticd says so at start.
  masses_refused_ = dds_->masses_refused();
  tools_refused_ = dds_->tools_refused();
  last_tick_.assign(ports_.size(), 0);
  slots_.resize(ports_.size());
  if (options_.ros2) {
    for (std::size_t port = 0; port < ports_.size(); ++port) {
      Ros2Options ros2 = *options_.ros2;
      ros2.ros_namespace += "/port" + std::to_string(port);
      ros2.buttons = ports_[port].buttons;
      ros2_.push_back(std::make_unique<Ros2ToolPublisher>(*participant_, ros2));
      const bool wrench = !ros2.wrench_topic.empty() && ports_[port].robot != nullptr;
      wrenches_in_.push_back(wrench ? std::make_unique<Ros2WrenchSubscriber>(
                                          *participant_, ros2.ros_namespace + "/" + ros2.wrench_topic, ros2.frame_id)
                                    : nullptr);
    }
    wrench_logged_.assign(ports_.size(), {false, false});
  }
}

SampleRelay::SampleRelay(const RelayOptions& options, Transport& transport, const std::vector<RelayPort>& ports,
                         RelayMasses masses)
    : options_(options),
      ports_(ports),
      transport_(&transport),
      masses_(masses),
      masses_on_(masses.local != nullptr && masses.remote != nullptr),
      peer_log_(log_window(options)) {
  options_.ros2.reset();
  last_tick_.assign(ports_.size(), 0);
  slots_.resize(ports_.size());
}

SampleRelay::~SampleRelay() { stop(); }

void SampleRelay::start() {
  if (thread_.joinable()) return;
  stopping_.store(false, std::memory_order_release);
  thread_ = std::thread([this] { run(); });
}

void SampleRelay::stop() {
  stopping_.store(true, std::memory_order_release);
  if (thread_.joinable()) thread_.join();
}

void SampleRelay::run() {
  const auto period = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(1.0 / options_.rate_hz));
  auto next = std::chrono::steady_clock::now();
  while (!stopping_.load(std::memory_order_acquire)) {
    step(std::chrono::steady_clock::now());
    next += period;
    const auto now = std::chrono::steady_clock::now();
    if (next < now) next = now;  // behind (a slow host): skip, never burst
    std::this_thread::sleep_until(next);
  }
}

void SampleRelay::step(std::chrono::steady_clock::time_point now) {
  if (options_.tools) receive(now);
  publish();
  if (masses_on_) {
    receive_masses(now);
    publish_masses();
  }
  if (!wrenches_in_.empty()) receive_wrenches();
  watch_sites(now);
  ++periods_;
}

void SampleRelay::receive(std::chrono::steady_clock::time_point now) {
  received_.clear();
  transport_->take_tools(received_);
  std::erase_if(received_, [&](const ToolState& tool) {
    const bool finite = engine::is_finite(tool.p_WT) && engine::is_finite(tool.v_WT) && engine::is_finite(tool.F_T_W);
    return !admit(tool.site, tool.writer_site, finite, "tool", now);
  });
  for (const ToolState& tool : received_) heard(tool.site, now);
  const auto silence = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(options_.silence_s));
  for (std::size_t port = 0; port < ports_.size(); ++port) {
    if (ports_[port].remote == nullptr) continue;
    runtime::RemoteToolSet set = ports_[port].remote->load();
    bool changed = !received_.empty();
    for (std::size_t i = 0; i < runtime::kMaxRemoteTools; ++i) {
      Slot& s = slots_[port][i];
      // Gone quiet, or cut off: no ghost left in the scene (the loop fades its avatar out).
      if (s.used && (now - s.heard > silence || cut_off_.contains(s.site))) {
        s = Slot{};
        set.tools[i] = runtime::RemoteTool{};
        changed = true;
      }
    }
    if (!changed) continue;
    for (const ToolState& tool : received_) {
      // This remote tool's slot, or a free one (a ninth remote tool is not rendered).
      std::size_t slot = runtime::kMaxRemoteTools;
      for (std::size_t i = 0; i < runtime::kMaxRemoteTools && slot == runtime::kMaxRemoteTools; ++i) {
        const Slot& s = slots_[port][i];
        if (s.used && s.site == tool.site && s.port == tool.port) slot = i;
      }
      for (std::size_t i = 0; i < runtime::kMaxRemoteTools && slot == runtime::kMaxRemoteTools; ++i) {
        if (!slots_[port][i].used) {
          slots_[port][i] = Slot{tool.site, tool.port, true, now, CreditAccount{}};
          slot = i;
        }
      }
      if (slot == runtime::kMaxRemoteTools) continue;
      Slot& s = slots_[port][slot];
      s.heard = now;
      const CouplingEnergy* to_us = nullptr;
      for (const CouplingEnergy& energy : tool.energy) {
        if (energy.site == options_.site && energy.port == port) to_us = &energy;
      }
      if (to_us != nullptr &&
          !credit(s.credit, to_us->sent, tool.site, CouplingName{static_cast<long>(tool.port), static_cast<long>(port)},
                  now)) {
        s = Slot{};
        set.tools[slot] = runtime::RemoteTool{};
        continue;
      }
      set.tools[slot] = runtime::RemoteTool{engine::tool_key(tool.site, tool.port), tool.p_WT, tool.v_WT, s.credit.credited()};
    }
    ports_[port].remote->store(set);
  }
}

void SampleRelay::publish() {
  for (std::size_t port = 0; port < ports_.size(); ++port) {
    const std::uint64_t newest = ports_[port].samples->newest();
    if (newest == 0 || newest == last_tick_[port]) continue;  // nothing new: nothing converted
    runtime::TickSample sample;
    if (!ports_[port].samples->read(newest, sample)) continue;  // overwritten meanwhile: next period
    last_tick_[port] = newest;
    ToolState tool;
    tool.site = options_.site;
    tool.port = static_cast<std::uint32_t>(port);
    tool.tick = sample.tick;
    tool.time_ns = sample.time_ns;
    tool.p_WT = sample.p_WT;
    tool.v_WT = sample.v_WT;
    tool.F_T_W = sample.F_T_W;
    tool.R_WT = sample.R_WT;
    tool.w_WT = sample.w_WT;
    tool.tau_T_W = sample.tau_T_W;
    tool.buttons = sample.buttons;
    if (const runtime::CouplingLedger* ledger = ports_[port].ledger) {
      for (std::size_t slot = 0; slot < runtime::kMaxRemoteTools; ++slot) {
        const Slot& s = slots_[port][slot];
        if (s.used && ledger->key(slot) == engine::tool_key(s.site, s.port)) {
          tool.energy.push_back({s.site, s.port, ledger->sent(slot)});
        }
      }
    }
    bool ok = true;
    if (options_.tools && tools_refused_.empty()) ok = transport_->publish_tool(tool) && ok;
    const bool ros2_period = periods_ % std::max<std::uint32_t>(1, options_.ros2_every) == 0;
    if (!ros2_.empty() && ros2_period) ok = ros2_[port]->publish(tool) && ok;
    (ok ? published_ : failed_).fetch_add(1, std::memory_order_relaxed);
  }
}

}  // namespace haptic::federation

namespace haptic::federation {

void SampleRelay::receive_masses(std::chrono::steady_clock::time_point now) {
  received_masses_.clear();
  transport_->take_masses(received_masses_);
  std::erase_if(received_masses_, [&](const MassState& mass) {
    return !admit(mass.site, mass.writer_site, engine::is_finite(mass.p_WM) && engine::is_finite(mass.v_WM), "mass copy", now);
  });
  for (const MassState& mass : received_masses_) heard(mass.site, now);
  const auto silence = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(options_.silence_s));
  const engine::SiteKey own = engine::site_key(options_.site);
  runtime::RemoteMassTable table = masses_.remote->load();
  bool changed = !received_masses_.empty();
  for (const MassState& mass : received_masses_) {
    // The mass's entry, or a free one (a fifth mass is not coupled).
    std::size_t entry = runtime::kMaxSharedMasses;
    for (std::size_t i = 0; i < runtime::kMaxSharedMasses && entry == runtime::kMaxSharedMasses; ++i) {
      if (table.masses[i].mass_key == mass.mass) entry = i;
    }
    for (std::size_t i = 0; i < runtime::kMaxSharedMasses && entry == runtime::kMaxSharedMasses; ++i) {
      if (table.masses[i].mass_key == 0) {
        entry = i;
        table.masses[i] = runtime::RemoteMassCopies{};
        table.masses[i].mass_key = mass.mass;
      }
    }
    if (entry == runtime::kMaxSharedMasses) continue;
    const engine::SiteKey site = engine::site_key(mass.site);
    auto& copies = table.masses[entry].copies;
    std::size_t slot = engine::kMaxRemoteCopies;
    for (std::size_t i = 0; i < engine::kMaxRemoteCopies && slot == engine::kMaxRemoteCopies; ++i) {
      if (copies[i].key == site) slot = i;
    }
    for (std::size_t i = 0; i < engine::kMaxRemoteCopies && slot == engine::kMaxRemoteCopies; ++i) {
      if (!copies[i].key) slot = i;
    }
    if (slot == engine::kMaxRemoteCopies) continue;
    if (copies[slot].key != site) mass_credit_[entry][slot] = CreditAccount{};  // a new coupling
    const double* to_us = nullptr;
    for (const auto& [to, sent] : mass.sent) {
      if (to == own) to_us = &sent;
    }
    if (to_us != nullptr && !credit(mass_credit_[entry][slot], *to_us, mass.site, CouplingName{}, now)) {
      copies[slot] = engine::RemoteMassCopy{};
      changed = true;
      continue;
    }
    copies[slot] =
        engine::RemoteMassCopy{site, mass.p_WM, mass.v_WM, mass_credit_[entry][slot].credited(), mass.settled};
    mass_heard_[entry][slot] = now;
  }
  for (std::size_t i = 0; i < runtime::kMaxSharedMasses; ++i) {
    if (table.masses[i].mass_key == 0) continue;
    bool any = false;
    for (std::size_t k = 0; k < engine::kMaxRemoteCopies; ++k) {
      engine::RemoteMassCopy& copy = table.masses[i].copies[k];
      // Its site went quiet, or was cut off: uncoupled.
      if (copy.key && (now - mass_heard_[i][k] > silence || cut_off_key(copy.key))) {
        copy = engine::RemoteMassCopy{};
        changed = true;
      }
      any = any || static_cast<bool>(copy.key);
    }
    if (!any) table.masses[i].mass_key = 0;
  }
  if (changed) masses_.remote->store(table);
}

void SampleRelay::publish_masses() {
  const runtime::LocalMassTable local = masses_.local->load();
  if (local.tick == last_mass_tick_) return;  // the loop has not moved them since
  last_mass_tick_ = local.tick;
  for (const runtime::LocalMassCopy& copy : local.masses) {
    if (copy.mass_key == 0) continue;
    MassState mass;
    mass.site = options_.site;
    mass.mass = copy.mass_key;
    mass.tick = local.tick;
    mass.p_WM = copy.p_WM;
    mass.v_WM = copy.v_WM;
    mass.settled = copy.settled;
    for (std::size_t k = 0; k < engine::kMaxRemoteCopies; ++k) {
      if (copy.coupled_site[k]) mass.sent.emplace_back(copy.coupled_site[k], copy.sent[k]);
    }
    const bool ok = masses_refused_.empty() && transport_->publish_mass(mass);
    (ok ? published_ : failed_).fetch_add(1, std::memory_order_relaxed);
  }
}

}  // namespace haptic::federation

namespace haptic::federation {

void SampleRelay::receive_wrenches() {
  for (std::size_t port = 0; port < wrenches_in_.size(); ++port) {
    if (!wrenches_in_[port]) continue;
    const WrenchTaken taken = wrenches_in_[port]->take();
    if (taken.wrong_frame + taken.not_finite > 0) {
      wrenches_refused_.fetch_add(taken.wrong_frame + taken.not_finite, std::memory_order_relaxed);
      // Once per port and reason: a node that keeps sending them would otherwise fill the log.
      const std::string& topic = wrenches_in_[port]->ros_topic();
      if (taken.wrong_frame > 0 && !wrench_logged_[port][0] && options_.log) {
        options_.log("federation: a wrench on " + topic + " in frame \"" + taken.refused_frame +
                     "\" refused: it must be in \"" + options_.ros2->frame_id + "\" (hapticd does not transform " +
                     "frames); further ones are counted, not logged");
        wrench_logged_[port][0] = true;
      }
      if (taken.not_finite > 0 && !wrench_logged_[port][1] && options_.log) {
        options_.log("federation: a wrench on " + topic + " with a NaN or an infinity refused; further ones are " +
                     "counted, not logged");
        wrench_logged_[port][1] = true;
      }
    }
    if (!taken.accepted) continue;
    runtime::RobotWrench wrench = ports_[port].robot->load();
    ++wrench.sequence;
    wrench.F_T_W = taken.F_T_W;
    wrench.tau_T_W = taken.tau_T_W;
    ports_[port].robot->store(wrench);
    wrenches_accepted_.fetch_add(1, std::memory_order_relaxed);
  }
}

}  // namespace haptic::federation

namespace haptic::federation {

void SampleRelay::heard(const std::string& site, std::chrono::steady_clock::time_point now) {
  const auto [it, first] = peers_.try_emplace(site);
  Peer& peer = it->second;
  if (!peer.present) {
    // Arrivals share a key, departures another: a site that comes and goes is logged once a
    // window each way, its further comings and goings counted.
    const std::string line = first ? "federation: site \"" + site + "\" heard for the first time"
                                   : "federation: site \"" + site + "\" heard again after " +
                                         seconds(now - peer.heard) + " s of silence";
    peer_log_.admit(site + "\n+", line, now, log_lines_);
    peer.present = true;
  }
  peer.heard = now;
}

void SampleRelay::watch_sites(std::chrono::steady_clock::time_point now) {
  const auto silence = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(options_.silence_s));
  for (auto& [site, peer] : peers_) {
    if (peer.present && now - peer.heard > silence) {
      peer.present = false;
      peer_log_.admit(site + "\n-",
                      "federation: site \"" + site + "\" not heard for " + seconds(silence) +
                          " s: its tools and mass copies are dropped",
                      now, log_lines_);
    }
  }
  peer_log_.flush(now, log_lines_);
  for (const std::string& line : log_lines_) {
    if (options_.log) options_.log(line);
  }
  log_lines_.clear();
}

}  // namespace haptic::federation

namespace haptic::federation {

bool SampleRelay::cut_off_key(engine::SiteKey site) const {
  for (const std::string& name : cut_off_) {
    if (engine::site_key(name) == site) return true;
  }
  return false;
}

bool SampleRelay::admit(const std::string& site, const std::optional<std::string>& writer_site, bool finite,
                        const char* what, std::chrono::steady_clock::time_point now) {
  std::string refusal;
  if (writer_site && *writer_site != site) {
    refusal = std::string("federation: a ") + what + " sample naming site \"" + site + "\" refused: its writer speaks for " +
              (writer_site->empty() ? std::string("no single site") : "site \"" + *writer_site + "\"") +
              " (a site publishes only under its own name; under DDS Security its permissions allow no other)";
  } else if (cut_off_.contains(site)) {
    samples_refused_.fetch_add(1, std::memory_order_relaxed);  // logged when it was cut off
    return false;
  } else if (!finite) {
    refusal = std::string("federation: a ") + what + " sample from site \"" + site +
              "\" refused: it holds a NaN or an infinity";
  } else {
    return true;
  }
  samples_refused_.fetch_add(1, std::memory_order_relaxed);
  // Per claimed site and reason: a forger that keeps at it gives one line a window.
  peer_log_.admit(site + (writer_site && *writer_site != site ? "\nforged" : "\nnan"), refusal, now, log_lines_);
  return false;
}

bool SampleRelay::credit(CreditAccount& account, double claimed, const std::string& site, CouplingName name,
                         std::chrono::steady_clock::time_point now) {
  const double refused_before = account.refused();
  const CreditAccount::Verdict verdict = account.take(claimed, now, options_.credit);
  energy_refused_.fetch_add(account.refused() - refused_before, std::memory_order_relaxed);
  if (verdict == CreditAccount::Verdict::kCredited) return true;
  if (cut_off_.insert(site).second) {
    sites_cut_off_.fetch_add(1, std::memory_order_relaxed);
    // Named here only, on the way out: the relay builds no text per sample.
    const std::string coupling = name.remote_port < 0 ? std::string("its copy of a shared mass")
                                                      : "its tool " + std::to_string(name.remote_port) +
                                                            " to this site's tool " + std::to_string(name.local_port);
    char cap[96];
    std::snprintf(cap, sizeof cap, "%.3g W, %.3g J at once", options_.credit.max_power_W, options_.credit.burst_J);
    std::string reason;
    if (verdict == CreditAccount::Verdict::kNotFinite) {
      char value[32];
      std::snprintf(value, sizeof value, "%g", claimed);
      reason = "the energy " + coupling + " says it sent is " + value;
    } else {
      char total[64];
      std::snprintf(total, sizeof total, "%.3f J (%.3f J of it not credited)", claimed, account.refused());
      reason = "the energy " + coupling + " says it sent, " + total + ", runs over the cap (" + cap + ") by more than a burst";
    }
    // Never rate-limited: a site is cut off once.
    log_lines_.push_back("federation: site \"" + site + "\" cut off: its books do not add up: " + reason +
                         "; nothing more is taken from it until this hapticd restarts");
  }
  return false;
}

}  // namespace haptic::federation
