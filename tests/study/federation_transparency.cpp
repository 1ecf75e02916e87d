// The federation's transparency against delay, and the shared mass's stability boundary without
// the network passivity layer (docs/federation.md, "Transparency"; scripts/plot_federation.py
// draws the chart):
//
//   federation_transparency --out DIR [--delays 0,1,2,5,...] [--losses 0,0.1] [--seconds 30]
//                           [--boundary-seconds 26] [--boundary-max-ms 200]
//
// Sites in lockstep at 1 kHz, each a 0.05 kg, 0.1 N·s/m device held by a scripted hand (200 N/m,
// 2 N·s/m; the force guard at 20 N), joined by delay lines with seeded loss, as in
// engine_network_passivity_test and engine_shared_mass_test. A one-way delay of d ms: what a site
// measured at tick k is used by the other at tick k + d (0: the same tick). Each message carries
// the sender's state and what its coupling's layer has sent so far; a lost one leaves the
// receiver with the last that arrived.
//
// Tool contact (each site renders the other's tool as the default avatar: a 10 mm sphere of
// 500 N/m, AvatarParams): the users press their tools together, A pushes B back, eases, shoves,
// and both let go.
//   force error    = RMS_t |F_A + F_B| / RMS_t |F_A|: how far from action = reaction the two
//                    users feel (0 with no network);
//   position error = RMS_t |(p_B − p_A)(t) − (p_B − p_A)_ref(t)|, the tools' true relative
//                    position (both read at the same instant) against the no-network run (no
//                    delay, no loss, no layer): extra penetration, lag, and passing through.
// Shared mass (default SharedMassParams, a copy per site): A's hand pushes the mass along x,
// presses it against B's tool, which B's hand holds still, and lets go.
//   force error    = RMS_t |F_A − F_A,ref| / RMS_t |F_A,ref|, F_A the force on A's tool and
//                    F_A,ref the same with no network at all: one site simulating the mass for
//                    both tools;
//   position error = RMS_t |p_copy_A(t) − p_copy_B(t)|.
// Both: RMS over the whole run (30 s: the hands let go at 11 s, and what lingers after counts),
// and how long after the let-go some user still feels more than 0.1 N (lingers_s).
// A run is unstable when a state goes non-finite, when it rings up — for the shared mass, the
// copies' spread in free motion from 1.5 s after the let-go grows faster than engine::kRingUpRate
// (engine::envelope_growth: a pole at 1.0001 per tick; a stable pair comes to rest) — or when the
// couplings create more than 10 mJ (the most, over the run, of what they gave their users minus
// what the users put in, by the study's own books as in the tests: the tool contact's verdict,
// whose tools part at the let-go, so there is no free motion to fit). Energy alone misses a slow
// ring-up: counted from t = 0, a ring-up must first give back what the push put in (0.14–0.37 J).
// An unstable run's figures are written but not charted, and one whose couplings have created
// 1 kJ is stopped there (its figures cover the run up to then).
//
// The boundary: the smallest one-way delay (1 ms steps) at which the shared mass's coupled copies
// without the layer are unstable (as above) in --boundary-seconds, for 2 and 3 sites (the third
// holds its tool still, clear of the mass), beside the continuous-time model's (the copies'
// characteristic equation), and the same for the tool contact.
//
// Writes DIR/transparency.csv and DIR/boundary.csv; a progress line per configuration on
// standard error. Exit status: 0 done; 2 a file that could not be written; CLI11's own codes
// (> 100) for malformed command lines.

#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "engine/analysis/growth.hpp"
#include "engine/device/point_mass_plant.hpp"
#include "engine/safety/network_passivity.hpp"
#include "engine/scene/shared_mass.hpp"

namespace haptic::engine {
namespace {

constexpr double kT = 1e-3;               // the sites' period. s
constexpr double kHandK = 200.0;          // N/m
constexpr double kHandB = 2.0;            // N·s/m
constexpr double kMaxForce = 20.0;        // the devices' limit (the force guard). N
constexpr double kAvatarRadius = 0.01;    // AvatarParams' default. m
constexpr double kAvatarStiffness = 500;  // AvatarParams' default. N/m
constexpr double kUnstableEnergy = 1e-2;  // created energy above which a run is unstable. J
constexpr double kRunaway = 1e3;          // created energy at which an unstable run is stopped. J
constexpr double kLetGo = 11.0;           // when the scripted hands let go. s
constexpr double kFelt = 0.1;             // a force a user still feels after the let-go. N
constexpr double kGrowthWindow = 0.5;     // the envelope's windows (several of the copies' periods). s
constexpr double kRestFloor = 1e-9;       // copies closer than this are at rest. m

PointMassParams device_params() {
  PointMassParams device;
  device.mass = 0.05;
  device.damping = 0.1;
  device.workspace_min = {-1, -1, -1};
  device.workspace_max = {1, 1, 1};
  return device;
}

/// A hand's target, piecewise linear: from each phase's start it moves to the phase's target
/// over the phase's ramp.
struct HandScript {
  struct Phase {
    double start_s = 0.0;
    double ramp_s = 1.5;
    Vec3 target;
  };
  std::vector<Phase> phases;  // the first one's target is where the hand starts

  Vec3 at(double t) const {
    Vec3 target = phases.front().target;
    for (std::size_t i = 1; i < phases.size() && t >= phases[i].start_s; ++i) {
      const double s = std::min(1.0, (t - phases[i].start_s) / phases[i].ramp_s);
      target = phases[i - 1].target + s * (phases[i].target - phases[i - 1].target);
    }
    return target;
  }
};

/// Tool contact: A and B press their tools together (1.7 N with no network), A's hand pushes B back
/// 4 mm (its target at 1 cm/s; 2.5 N), eases off, shoves B back again (its target at 5 cm/s), eases
/// again, and from 11 s both let go. Within what the avatar holds (K r = 5 N): with no network the
/// tools stay 5 mm or more apart.
std::vector<HandScript> contact_hands() {
  return {
      {{{0, 0, {-0.02, 0, 0}}, {0, 1.5, {0.005, 0, 0}}, {3, 1.0, {0.015, 0, 0}}, {5, 1.0, {0.0, 0, 0}},
        {7, 0.3, {0.015, 0, 0}}, {9, 1.0, {0.005, 0, 0}}, {kLetGo, 1.5, {-0.03, 0, 0}}}},
      {{{0, 0, {0.02, 0, 0}}, {0, 1.5, {-0.005, 0, 0}}, {kLetGo, 1.5, {0.03, 0, 0}}}},
  };
}

/// Shared mass (at the origin, radius 20 mm): A pushes it along x from 1 s and from 4 s, presses it
/// against B's still tool from 7 s, and lets go from 11 s; B (and C) hold still.
std::vector<HandScript> mass_hands(int sites) {
  std::vector<HandScript> hands = {
      {{{0, 0, {-0.05, 0, 0}}, {1, 1.5, {-0.01, 0, 0}}, {4, 1.5, {0.02, 0, 0}}, {7, 1.5, {0.05, 0, 0}},
        {kLetGo, 1.5, {-0.05, 0, 0}}}},
      {{{0, 0, {0.065, 0, 0}}}},
      {{{0, 0, {0.0, -0.08, 0}}}},
  };
  hands.resize(static_cast<std::size_t>(sites));
  return hands;
}

/// One direction between two sites: messages arrive delay ticks after they are sent, or are lost
/// (seeded).
template <typename Payload>
class DelayLine {
 public:
  DelayLine(long delay_ticks, double loss, std::uint32_t seed) : delay_(delay_ticks), loss_(loss), random_(seed) {}

  void send(long k, const Payload& payload) {
    queue_.push_back({k + delay_, uniform_(random_) < loss_, payload});
  }

  /// take(payload) for each message due by tick k that was not lost, oldest first.
  template <typename Take>
  void deliver(long k, Take&& take) {
    while (!queue_.empty() && queue_.front().arrives <= k) {
      if (!queue_.front().lost) take(queue_.front().payload);
      queue_.pop_front();
    }
  }

 private:
  struct Message {
    long arrives;
    bool lost;
    Payload payload;
  };
  long delay_;
  double loss_;
  std::mt19937 random_;
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};
  std::deque<Message> queue_;
};

struct Network {
  long delay_ticks = 0;  // one way
  double loss = 0.0;     // fraction of messages lost
  bool layer = true;
};

/// The work the coupling forces did, booked by the study (not by the layers): what the users (or
/// copies) put in and what they were given. The channel's energy is in − out.
struct EnergyBooks {
  double in = 0.0;
  double out = 0.0;
  double created = 0.0;  // the most, over the run, of out − in. J
  void book(const Vec3& F_held, const Vec3& displacement) {
    const double W = dot(F_held, displacement);
    (W > 0.0 ? out : in) += std::abs(W);
  }
  void close_tick() { created = std::max(created, out - in); }
};

struct Outcome {
  bool finite = true;
  double blew_up_at_s = -1.0;  // s: when a state went non-finite; -1: never
  double runaway_at_s = -1.0;  // s: when the couplings had created kRunaway and the run stopped
  double energy_created_J = 0.0;
  double force_error = 0.0;
  double position_error_m = 0.0;
  double max_position_error_m = 0.0;
  double largest_force_N = 0.0;
  /// From the let-go until no user feels more than kFelt any more: how long a contact lingers.
  /// NaN: the run ended before the let-go; infinity: still felt at the end. Unit: s.
  double lingers_s = NAN;
  /// How fast the coupling's oscillation grows (engine::envelope_growth) where the run measures it.
  GrowthFit growth{-INFINITY};
  bool stable() const { return finite && energy_created_J <= kUnstableEnergy && !rings_up(growth); }
};

/// The last tick at which a user felt more than kFelt, for Outcome::lingers_s.
struct Lingering {
  long last_felt = -1;
  void book(long k, const Vec3& F) {
    if (norm(F) > kFelt) last_felt = std::max(last_felt, k);
  }
  double seconds(long ticks_run) const {
    const double end = static_cast<double>(ticks_run) * kT;
    if (end <= kLetGo) return NAN;
    if (last_felt >= ticks_run - 1) return INFINITY;
    return std::max(0.0, static_cast<double>(last_felt + 1) * kT - kLetGo);
  }
};

/// Root mean squares accumulated over a run.
struct Rms {
  double sum = 0.0;
  long count = 0;
  void add(double value) { sum += value * value; ++count; }
  double value() const { return count > 0 ? std::sqrt(sum / static_cast<double>(count)) : 0.0; }
};

// ---- Tool contact ----------------------------------------------------------------------------

struct ToolMessage {
  Vec3 p_WT;
  double energy_sent = 0.0;
};

struct ContactTrace {
  std::vector<Vec3> apart;  // p_B − p_A per tick. m
};

/// Two sites rendering each other's tool as an avatar. `reference` (may be null) is the
/// no-network run's trace for the position error; `trace` (may be null) records this run's.
Outcome run_contact(const Network& network, long ticks, const ContactTrace* reference, ContactTrace* trace) {
  const std::vector<HandScript> hands = contact_hands();
  const PointMassParams device = device_params();
  PointMassPlant plants[2] = {PointMassPlant(device, {hands[0].at(0), {}}), PointMassPlant(device, {hands[1].at(0), {}})};
  NetworkPassivityParams params;
  params.period = kT;
  params.max_damping = device.mass / kT;
  NetworkPassivity layers[2] = {NetworkPassivity(params), NetworkPassivity(params)};
  DelayLine<ToolMessage> lines[2] = {DelayLine<ToolMessage>(network.delay_ticks, network.loss, 29),
                                     DelayLine<ToolMessage>(network.delay_ticks, network.loss, 31)};
  Vec3 remote[2];
  bool has_remote[2] = {false, false};
  Vec3 F_previous[2], p_previous[2];
  EnergyBooks books;
  Rms action_reaction, felt_A, position;
  Lingering lingering;
  Outcome outcome;
  long k = 0;
  if (trace != nullptr) trace->apart.assign(static_cast<std::size_t>(ticks), Vec3{});
  for (; k < ticks; ++k) {
    // Each site publishes its tool and its ledger at the start of the tick.
    for (int i = 0; i < 2; ++i) lines[i].send(k, {plants[i].state().p_WT, layers[i].sent()});
    Vec3 F[2];
    for (int i = 0; i < 2; ++i) {
      lines[1 - i].deliver(k, [&](const ToolMessage& m) {
        remote[i] = m.p_WT;
        has_remote[i] = true;
        if (network.layer) layers[i].receive(m.energy_sent);
      });
      const PointMassState& state = plants[i].state();
      if (k > 0) books.book(F_previous[i], state.p_WT - p_previous[i]);
      double stored = 0.0;
      if (has_remote[i]) {
        const Vec3 apart = state.p_WT - remote[i];
        const double distance = norm(apart);
        const double depth = kAvatarRadius - distance;
        if (depth > 0.0 && distance > 0.0) {
          F[i] = (kAvatarStiffness * depth / distance) * apart;
          stored = 0.5 * kAvatarStiffness * depth * depth;
        }
      }
      if (network.layer) F[i] = layers[i].apply(F[i], state.v_WT, state.p_WT, stored).F_T_W;
      F[i] = clip_norm(F[i], kMaxForce);  // the force guard
      outcome.largest_force_N = std::max(outcome.largest_force_N, norm(F[i]));
      lingering.book(k, F[i]);
      F_previous[i] = F[i];
      p_previous[i] = state.p_WT;
    }
    books.close_tick();
    action_reaction.add(norm(F[0] + F[1]));
    felt_A.add(norm(F[0]));
    const Vec3 apart = plants[1].state().p_WT - plants[0].state().p_WT;
    if (trace != nullptr) trace->apart[static_cast<std::size_t>(k)] = apart;
    if (reference != nullptr) {
      const double error = norm(apart - reference->apart[static_cast<std::size_t>(k)]);
      position.add(error);
      outcome.max_position_error_m = std::max(outcome.max_position_error_m, error);
    }
    const double t = static_cast<double>(k) * kT;
    for (int i = 0; i < 2; ++i) {
      const Vec3 target = hands[static_cast<std::size_t>(i)].at(t);
      plants[i].step(F[i], kT, [&](const Vec3& p, const Vec3& v) { return kHandK * (target - p) - kHandB * v; });
      outcome.finite = outcome.finite && is_finite(plants[i].state().p_WT) && is_finite(F[i]);
    }
    if (!outcome.finite || !std::isfinite(books.in - books.out)) {
      outcome.finite = false;
      outcome.blew_up_at_s = t;
      break;
    }
    if (books.created > kRunaway) {
      outcome.runaway_at_s = t;
      ++k;
      break;
    }
  }
  outcome.energy_created_J = books.created;
  outcome.lingers_s = lingering.seconds(k);
  outcome.force_error = felt_A.value() > 0.0 ? action_reaction.value() / felt_A.value() : 0.0;
  outcome.position_error_m = position.value();
  return outcome;
}

// ---- Shared mass -----------------------------------------------------------------------------

struct CopyMessage {
  SharedMassState copy;
  double energy_sent = 0.0;  // the sender's coupling with the receiver, cumulative. J
};

struct MassTrace {
  std::vector<Vec3> F_A;  // the force on A's tool per tick. N
};

/// `sites` copies of one shared mass, each touched by its site's tool. sites == 1: the mass with
/// no network, both scripted tools (A's and B's) touching the one copy. `reference` (may be null):
/// the no-network run's trace for the force error; `trace` (may be null) records this run's.
Outcome run_mass(int sites, const Network& network, long ticks, const MassTrace* reference, MassTrace* trace) {
  const bool alone = sites == 1;
  const int n = sites;  // copies
  const int tools_n = alone ? 2 : sites;
  const std::vector<HandScript> hands = mass_hands(tools_n);
  const PointMassParams device = device_params();
  SharedMassParams mass;
  mass.passivity_layer = network.layer;
  std::vector<PointMassPlant> tools;
  for (int i = 0; i < tools_n; ++i) tools.emplace_back(device, PointMassState{hands[static_cast<std::size_t>(i)].at(0), {}});
  std::vector<SharedMass> copies(static_cast<std::size_t>(n), SharedMass(mass, SharedMassState{}));
  const auto slot_of = [](int i, int j) { return static_cast<std::size_t>(j < i ? j : j - 1); };  // site j at site i
  std::vector<DelayLine<CopyMessage>> lines;  // [from * n + to]
  for (int from = 0; from < n; ++from) {
    for (int to = 0; to < n; ++to) {
      lines.emplace_back(network.delay_ticks, network.loss, static_cast<std::uint32_t>(30 + from * n + to));
    }
  }
  std::vector<std::vector<RemoteMassCopy>> received(static_cast<std::size_t>(n),
                                                    std::vector<RemoteMassCopy>(static_cast<std::size_t>(n - 1)));
  std::vector<Vec3> F_held(static_cast<std::size_t>(n * n));  // coupling forces over the last period
  std::vector<Vec3> p_previous(static_cast<std::size_t>(n));
  std::vector<Vec3> F_tool(static_cast<std::size_t>(tools_n));
  std::vector<double> spread;  // per tick: the copies' largest distance from copy 0. m
  spread.reserve(static_cast<std::size_t>(ticks));
  EnergyBooks books;
  Rms force_difference, felt_reference, apart;
  Lingering lingering;
  Outcome outcome;
  long k = 0;
  if (trace != nullptr) trace->F_A.assign(static_cast<std::size_t>(ticks), Vec3{});
  for (; k < ticks; ++k) {
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        if (j != i) {
          lines[static_cast<std::size_t>(i * n + j)].send(
              k, {copies[static_cast<std::size_t>(i)].state(), copies[static_cast<std::size_t>(i)].energy_sent(slot_of(i, j))});
        }
      }
    }
    for (int i = 0; i < n; ++i) {
      const auto ui = static_cast<std::size_t>(i);
      for (int j = 0; j < n; ++j) {
        if (j == i) continue;
        lines[static_cast<std::size_t>(j * n + i)].deliver(k, [&](const CopyMessage& m) {
          received[ui][slot_of(i, j)] = {static_cast<std::uint64_t>(j + 1), m.copy.p_WM, m.copy.v_WM, m.energy_sent};
        });
      }
      SharedMass& copy = copies[ui];
      if (k > 0) {
        for (std::size_t s = 0; s + 1 < static_cast<std::size_t>(n); ++s) {
          books.book(F_held[ui * static_cast<std::size_t>(n) + s], copy.state().p_WM - p_previous[ui]);
        }
      }
      p_previous[ui] = copy.state().p_WM;
      // Alone, both tools touch the one copy; otherwise each site's tool touches its own.
      for (int tool = alone ? 0 : i; tool < (alone ? tools_n : i + 1); ++tool) {
        const auto ut = static_cast<std::size_t>(tool);
        const Vec3 F = copy.touch(tools[ut].state().p_WT);
        F_tool[ut] = clip_norm(F, kMaxForce);  // the force guard
        outcome.largest_force_N = std::max(outcome.largest_force_N, norm(F));
        lingering.book(k, F_tool[ut]);
      }
      copy.step(received[ui]);
      for (std::size_t s = 0; s + 1 < static_cast<std::size_t>(n); ++s) {
        F_held[ui * static_cast<std::size_t>(n) + s] = copy.coupling_force(s);
      }
    }
    books.close_tick();
    if (trace != nullptr) trace->F_A[static_cast<std::size_t>(k)] = F_tool[0];
    if (reference != nullptr) {
      const Vec3& F_ref = reference->F_A[static_cast<std::size_t>(k)];
      force_difference.add(norm(F_tool[0] - F_ref));
      felt_reference.add(norm(F_ref));
    }
    if (n > 1) {
      const double gap = norm(copies[0].state().p_WM - copies[1].state().p_WM);
      apart.add(gap);
      outcome.max_position_error_m = std::max(outcome.max_position_error_m, gap);
      double widest = 0.0;
      for (int i = 1; i < n; ++i) widest = std::max(widest, norm(copies[0].state().p_WM - copies[static_cast<std::size_t>(i)].state().p_WM));
      spread.push_back(widest);
    }
    const double t = static_cast<double>(k) * kT;
    for (int i = 0; i < tools_n; ++i) {
      const auto ui = static_cast<std::size_t>(i);
      const Vec3 target = hands[ui].at(t);
      tools[ui].step(F_tool[ui], kT, [&](const Vec3& p, const Vec3& v) { return kHandK * (target - p) - kHandB * v; });
      outcome.finite = outcome.finite && is_finite(tools[ui].state().p_WT);
    }
    for (const SharedMass& copy : copies) outcome.finite = outcome.finite && is_finite(copy.state().p_WM);
    if (!outcome.finite || !std::isfinite(books.in - books.out)) {
      outcome.finite = false;
      outcome.blew_up_at_s = t;
      break;
    }
    if (books.created > kRunaway) {
      outcome.runaway_at_s = t;
      ++k;
      break;
    }
  }
  outcome.energy_created_J = books.created;
  // Free motion from 1.5 s after the let-go: a stable pair of copies comes to rest, an unstable
  // one rings up however slowly.
  if (n > 1) outcome.growth = envelope_growth(spread, kT, kLetGo + 1.5, kGrowthWindow, kRestFloor);
  outcome.lingers_s = lingering.seconds(k);
  outcome.force_error = felt_reference.value() > 0.0 ? force_difference.value() / felt_reference.value() : 0.0;
  outcome.position_error_m = apart.value();
  return outcome;
}

// ---- The study -------------------------------------------------------------------------------

struct Options {
  std::string out;
  std::vector<long> delays_ms = {0, 1, 2, 5, 10, 20, 50, 100, 200};
  std::vector<double> losses = {0.0, 0.1};
  double seconds = 30.0;
  double boundary_seconds = 26.0;
  long boundary_max_ms = 200;
};

long ticks_of(double seconds) { return std::lround(seconds / kT); }

std::string note_of(const Outcome& o) {
  char text[96];
  if (!o.finite) {
    std::snprintf(text, sizeof text, "non-finite at %.3f s", o.blew_up_at_s);
  } else if (o.runaway_at_s >= 0.0) {
    std::snprintf(text, sizeof text, "runaway: created %.3g J by %.3f s (stopped)", o.energy_created_J, o.runaway_at_s);
  } else if (rings_up(o.growth)) {
    std::snprintf(text, sizeof text, "rings up at %.3g/s; created %.3g J", o.growth.rate_per_s, o.energy_created_J);
  } else if (o.energy_created_J > kUnstableEnergy) {
    std::snprintf(text, sizeof text, "created %.3g J", o.energy_created_J);
  } else {
    text[0] = '\0';
  }
  return text;
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void progress(int index, int total, const char* coupling, const Network& network, const Outcome& o, double wall_s) {
  char figures[160];
  if (o.stable()) {
    std::snprintf(figures, sizeof figures, "force error %.3g, position error %.3g mm, created %.3g mJ, lingers %.3g s",
                  o.force_error, 1e3 * o.position_error_m, 1e3 * o.energy_created_J, o.lingers_s);
  } else {
    std::snprintf(figures, sizeof figures, "unstable (%s)", note_of(o).c_str());
  }
  std::fprintf(stderr, "federation_transparency: [%2d/%d] %-12s %3ld ms %2.0f %% loss layer %-3s: %s (%.2f s)\n", index,
               total, coupling, network.delay_ticks, 100.0 * network.loss, network.layer ? "on" : "off", figures, wall_s);
}

struct Boundary {
  const char* coupling = "";
  int sites = 0;
  long delay_ms = -1;  // -1: none up to the scan's end
  double energy_J = 0.0;
  double predicted_ms = NAN;  // the continuous-time model's, where there is one
  std::string note;
};

/// The shared mass's boundary in continuous time: the smallest one-way delay τ at which the copies'
/// non-common modes reach the imaginary axis. With n copies of mass M (friction b), each coupled to
/// the other n − 1 by K_s, B_s at their delayed positions, a mode whose copies sum to zero obeys
///   M s² + ((n−1) B_s + b) s + (n−1) K_s + (K_s + B_s s) e^{−sτ} = 0
/// (the other copies' sum is minus its own). On s = jω the magnitudes must match, a quadratic in ω²;
/// each root gives the delays that match the phase, the first one is the boundary. NaN: none.
/// A check on the lockstep runs, which cross a little earlier: each coupling force there is
/// computed from the other copy's state at the start of the tick and held over the 1 ms period
/// (a zero-order hold, about T/2 of extra lag on top of the network's), and more lag reaches the
/// imaginary axis at less network delay (12 ms and 17 ms against 12.4 ms and 17.9 ms).
double predicted_boundary_ms(int sites, const SharedMassParams& p) {
  const double a = (sites - 1) * p.coupling_stiffness;
  const double c = (sites - 1) * p.coupling_damping + p.damping;
  const double K = p.coupling_stiffness, B = p.coupling_damping, M = p.mass;
  // M² w² + (c² − 2aM − B²) w + (a² − K²) = 0 in w = ω².
  const double qa = M * M, qb = c * c - 2.0 * a * M - B * B, qc = a * a - K * K;
  const double discriminant = qb * qb - 4.0 * qa * qc;
  if (discriminant < 0.0) return NAN;
  double best = NAN;
  for (const double sign : {-1.0, 1.0}) {
    const double w = (-qb + sign * std::sqrt(discriminant)) / (2.0 * qa);
    if (!(w > 0.0)) continue;
    const double omega = std::sqrt(w);
    // e^{−jωτ} = −(a − Mω² + j c ω) / (K + j B ω)
    const double phase = std::atan2(-c * omega, -(a - M * w)) - std::atan2(B * omega, K);
    double tau = std::fmod(-phase, 2.0 * std::numbers::pi);
    if (tau < 0.0) tau += 2.0 * std::numbers::pi;
    tau /= omega;
    if (std::isnan(best) || tau < best) best = tau;
  }
  return 1e3 * best;
}

/// The smallest one-way delay (1 ms steps up to max_ms) at which the run without the layer is
/// unstable (Outcome::stable).
template <typename Run>
Boundary find_boundary(const char* coupling, int sites, long max_ms, Run&& run) {
  Boundary boundary;
  boundary.coupling = coupling;
  boundary.sites = sites;
  for (long delay = 0; delay <= max_ms; ++delay) {
    const auto start = std::chrono::steady_clock::now();
    const Outcome o = run(Network{delay, 0.0, false});
    std::fprintf(stderr,
                 "federation_transparency: boundary, %s, %d sites, no layer, %3ld ms: created %.3g J, growth %.3g/s%s "
                 "(%.2f s)\n",
                 coupling, sites, delay, o.energy_created_J, o.growth.rate_per_s, o.finite ? "" : ", non-finite",
                 seconds_since(start));
    if (!o.stable()) {
      boundary.delay_ms = delay;
      boundary.energy_J = o.energy_created_J;
      boundary.note = note_of(o);
      break;
    }
  }
  return boundary;
}

int run_study(const Options& options) {
  std::filesystem::create_directories(options.out);
  const long ticks = ticks_of(options.seconds);
  const int total = static_cast<int>(2 * options.delays_ms.size() * options.losses.size() * 2);
  const auto study_start = std::chrono::steady_clock::now();

  ContactTrace contact_reference;
  run_contact(Network{0, 0.0, false}, ticks, nullptr, &contact_reference);
  MassTrace mass_reference;
  run_mass(1, Network{0, 0.0, false}, ticks, nullptr, &mass_reference);

  const std::string csv_path = options.out + "/transparency.csv";
  std::ofstream csv(csv_path);
  csv << "coupling,sites,delay_ms,loss,layer,stable,force_error,position_error_m,max_position_error_m,"
         "energy_created_J,largest_force_N,lingers_s,note\n";
  int index = 0;
  for (const char* coupling : {"tool_contact", "shared_mass"}) {
    const bool contact = coupling[0] == 't';
    for (const bool layer : {false, true}) {
      for (const double loss : options.losses) {
        for (const long delay : options.delays_ms) {
          const Network network{delay, loss, layer};
          const auto start = std::chrono::steady_clock::now();
          const Outcome o = contact ? run_contact(network, ticks, &contact_reference, nullptr)
                                    : run_mass(2, network, ticks, &mass_reference, nullptr);
          progress(++index, total, contact ? "tool contact" : "shared mass", network, o, seconds_since(start));
          char row[400];
          std::snprintf(row, sizeof row, "%s,2,%ld,%g,%d,%d,%.6g,%.6g,%.6g,%.6g,%.6g,%.4g,%s\n", coupling, delay,
                        loss, layer ? 1 : 0, o.stable() ? 1 : 0, o.force_error, o.position_error_m,
                        o.max_position_error_m, o.energy_created_J, o.largest_force_N, o.lingers_s, note_of(o).c_str());
          csv << row;
        }
      }
    }
  }
  csv.close();
  if (!csv) {
    std::fprintf(stderr, "federation_transparency: could not write %s\n", csv_path.c_str());
    return 2;
  }

  const long boundary_ticks = ticks_of(options.boundary_seconds);
  std::vector<Boundary> boundaries;
  for (const int sites : {2, 3}) {
    boundaries.push_back(find_boundary("shared_mass", sites, options.boundary_max_ms, [&](const Network& network) {
      return run_mass(sites, network, boundary_ticks, nullptr, nullptr);
    }));
    boundaries.back().predicted_ms = predicted_boundary_ms(sites, SharedMassParams{});
  }
  boundaries.push_back(find_boundary("tool_contact", 2, options.boundary_max_ms, [&](const Network& network) {
    return run_contact(network, boundary_ticks, nullptr, nullptr);
  }));
  const std::string boundary_path = options.out + "/boundary.csv";
  std::ofstream boundary_csv(boundary_path);
  boundary_csv << "coupling,sites,seconds,searched_up_to_ms,boundary_delay_ms,energy_created_J,predicted_ms,note\n";
  for (const Boundary& b : boundaries) {
    char predicted[32] = "";
    char predicted_text[64] = "";
    if (std::isfinite(b.predicted_ms)) {
      std::snprintf(predicted, sizeof predicted, "%.4g", b.predicted_ms);
      std::snprintf(predicted_text, sizeof predicted_text, "; %.1f ms in continuous time", b.predicted_ms);
    }
    char row[300];
    std::snprintf(row, sizeof row, "%s,%d,%g,%ld,%ld,%.6g,%s,%s\n", b.coupling, b.sites, options.boundary_seconds,
                  options.boundary_max_ms, b.delay_ms, b.energy_J, predicted, b.note.c_str());
    boundary_csv << row;
    if (b.delay_ms >= 0) {
      std::printf("stability boundary without the layer, %s, %d sites: active from %ld ms one way (%s in %g s%s)\n",
                  b.coupling, b.sites, b.delay_ms, b.note.c_str(), options.boundary_seconds, predicted_text);
    } else {
      std::printf("stability boundary without the layer, %s, %d sites: passive up to %ld ms one way (%g s%s)\n",
                  b.coupling, b.sites, options.boundary_max_ms, options.boundary_seconds, predicted_text);
    }
  }
  boundary_csv.close();
  if (!boundary_csv) {
    std::fprintf(stderr, "federation_transparency: could not write %s\n", boundary_path.c_str());
    return 2;
  }
  std::printf("federation_transparency: wrote %s and %s (%.1f s)\n", csv_path.c_str(), boundary_path.c_str(),
              seconds_since(study_start));
  return 0;
}

}  // namespace
}  // namespace haptic::engine

int main(int argc, char** argv) {
  haptic::engine::Options options;
  CLI::App app{"The federation's transparency against delay and the shared mass's stability boundary"};
  app.add_option("--out", options.out, "folder for transparency.csv and boundary.csv")->required();
  app.add_option("--delays", options.delays_ms, "one-way delays, ms")->delimiter(',')->check(CLI::NonNegativeNumber);
  app.add_option("--losses", options.losses, "fractions of messages lost")->delimiter(',')->check(CLI::Range(0.0, 1.0));
  app.add_option("--seconds", options.seconds, "simulated time per transparency run, s")->check(CLI::PositiveNumber);
  app.add_option("--boundary-seconds", options.boundary_seconds, "simulated time per boundary run, s")
      ->check(CLI::PositiveNumber);
  app.add_option("--boundary-max-ms", options.boundary_max_ms, "longest one-way delay the boundary search tries, ms")
      ->check(CLI::NonNegativeNumber);
  CLI11_PARSE(app, argc, argv);
  try {
    return haptic::engine::run_study(options);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "federation_transparency: %s\n", error.what());
    return 2;
  }
}
