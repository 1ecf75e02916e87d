// Two and three sites in lockstep, each with its own copy of one shared mass and a device held by a
// scripted hand, the copies coupled across a delay line with seeded loss (0, 10, 50, 100 ms one
// way; 0 % and 10 % loss): the hands push the mass from opposite sides, squeeze it, push it
// through, and let go; 60 s of simulated time per run. With the network passivity layer the
// couplings never create more than ε, the devices' forces stay under their limit, and the copies
// agree once the hands are gone; without it the delayed couplings create energy.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <deque>
#include <random>
#include <vector>

#include "engine/device/point_mass_plant.hpp"
#include "engine/scene/shared_mass.hpp"
#include "support/allocation_counter.hpp"

namespace haptic::engine {
namespace {

constexpr double kT = 1e-3;          // s
constexpr double kHandK = 200.0;     // N/m
constexpr double kHandB = 2.0;       // N·s/m
constexpr double kMaxForce = 20.0;   // the devices' limit. N
constexpr long kTicks = 60'000;      // 60 s

struct Message {
  SharedMassState copy;
  double energy_sent = 0.0;  // the sender's coupling with the receiver, cumulative. J
  long arrives = 0;
  bool lost = false;
};

/// Where each site's hand holds its tool, by phase: start outside the mass, push it, squeeze it,
/// push it through, and let go (back to the start) from 40 s. Targets move over 1.5 s.
struct HandScript {
  std::vector<double> times;   // s, phase starts
  std::vector<Vec3> targets;   // m
  Vec3 at(double t) const {
    Vec3 target = targets.front();
    for (std::size_t i = 1; i < times.size(); ++i) {
      if (t < times[i]) break;
      const double s = std::min(1.0, (t - times[i]) / 1.5);
      target = targets[i - 1] + s * (targets[i] - targets[i - 1]);
    }
    return target;
  }
};

std::vector<HandScript> hands(int sites) {
  std::vector<HandScript> script = {
      {{0, 1, 12, 25, 40}, {{-0.05, 0, 0}, {-0.005, 0, 0}, {-0.005, 0, 0}, {0.01, 0, 0}, {-0.05, 0, 0}}},
      {{0, 1, 12, 25, 40}, {{0.05, 0, 0}, {0.05, 0, 0}, {0.0, 0, 0}, {0.0, 0, 0}, {0.05, 0, 0}}},
      {{0, 1, 18, 25, 40}, {{0.01, -0.05, 0}, {0.01, -0.05, 0}, {0.01, -0.01, 0}, {0.01, -0.01, 0}, {0.01, -0.05, 0}}},
  };
  script.resize(static_cast<std::size_t>(sites));
  return script;
}

struct Scenario {
  int sites = 2;
  long delay_ticks = 0;  // one way, every pair
  double loss = 0.0;     // fraction of messages lost, seeded
  bool layer = true;
  long ticks = kTicks;
};

struct Outcome {
  double min_channel_energy = 0.0;  // min over time of Σ (energy into the couplings − out), by the test's books. J
  double largest_force = 0.0;       // the largest force asked of a device. N
  bool finite = true;
  double largest_disagreement = 0.0;  // at the end: max |p_i − p_j| over the copies. m
  double largest_speed = 0.0;         // at the end: max |v_i|. m/s
  double travel = 0.0;                // how far copy 0 went from the start at its farthest. m
  double conservation_error = 0.0;    // |Σ injected − Σ given − Σ reservoirs − in flight|. J
  double blew_up_at = -1.0;           // s: when a copy or tool first went non-finite; -1: never
};

Outcome run(const Scenario& scenario) {
  const int n = scenario.sites;
  const std::vector<HandScript> script = hands(n);
  PointMassParams device;
  device.mass = 0.05;
  device.damping = 0.1;
  device.workspace_min = {-1, -1, -1};
  device.workspace_max = {1, 1, 1};
  SharedMassParams mass;
  mass.passivity_layer = scenario.layer;
  std::vector<PointMassPlant> tools;
  std::vector<SharedMass> copies;
  for (int i = 0; i < n; ++i) {
    tools.emplace_back(device, PointMassState{script[static_cast<std::size_t>(i)].targets.front(), {}});
    copies.emplace_back(mass, SharedMassState{});
  }
  // Each site's slots hold the other sites in order.
  const auto slot_of = [](int i, int j) { return j < i ? j : j - 1; };  // site j's slot at site i
  std::vector<std::deque<Message>> lines(static_cast<std::size_t>(n * n));  // [from * n + to]
  std::vector<std::vector<RemoteMassCopy>> received(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) received[static_cast<std::size_t>(i)].resize(static_cast<std::size_t>(n - 1));
  std::vector<Vec3> F_previous(static_cast<std::size_t>(n * kMaxRemoteCopies));
  std::vector<Vec3> p_previous(static_cast<std::size_t>(n));
  double in = 0.0, out = 0.0;
  std::mt19937 random(30);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  Outcome outcome;
  for (long k = 0; k < scenario.ticks; ++k) {
    const double t = static_cast<double>(k) * kT;
    for (int i = 0; i < n; ++i) {
      const auto ui = static_cast<std::size_t>(i);
      for (int j = 0; j < n; ++j) {
        if (j == i) continue;
        std::deque<Message>& line = lines[static_cast<std::size_t>(j * n + i)];
        while (!line.empty() && line.front().arrives <= k) {
          const Message m = line.front();
          line.pop_front();
          if (m.lost) continue;
          RemoteMassCopy& copy = received[ui][static_cast<std::size_t>(slot_of(i, j))];
          copy = {static_cast<std::uint64_t>(j + 1), m.copy.p_WM, m.copy.v_WM, m.energy_sent};
        }
      }
      SharedMass& copy = copies[ui];
      // The test's own books: the work each coupling force did on this copy over the last period.
      if (k > 0) {
        for (std::size_t s = 0; s + 1 < static_cast<std::size_t>(n); ++s) {
          const double W = dot(F_previous[ui * kMaxRemoteCopies + s], copy.state().p_WM - p_previous[ui]);
          (W > 0.0 ? out : in) += std::abs(W);
        }
      }
      p_previous[ui] = copy.state().p_WM;
      Vec3 F = copy.touch(tools[ui].state().p_WT);
      outcome.largest_force = std::max(outcome.largest_force, norm(F));
      const double magnitude = norm(F);
      if (magnitude > kMaxForce) F *= kMaxForce / magnitude;  // the force guard
      copy.step(received[ui]);
      for (std::size_t s = 0; s + 1 < static_cast<std::size_t>(n); ++s) {
        F_previous[ui * kMaxRemoteCopies + s] = copy.coupling_force(s);
      }
      for (int j = 0; j < n; ++j) {
        if (j == i) continue;
        lines[static_cast<std::size_t>(i * n + j)].push_back(
            {copy.state(), copy.energy_sent(static_cast<std::size_t>(slot_of(i, j))),
             k + scenario.delay_ticks, uniform(random) < scenario.loss});
      }
      const Vec3 target = script[ui].at(t);
      tools[ui].step(F, kT, [&](const Vec3& p, const Vec3& v) { return kHandK * (target - p) - kHandB * v; });
      outcome.finite = outcome.finite && is_finite(tools[ui].state().p_WT) && is_finite(copy.state().p_WM);
    }
    if (!outcome.finite || !std::isfinite(in - out)) {
      outcome.blew_up_at = t;
      outcome.min_channel_energy = -INFINITY;
      return outcome;
    }
    outcome.min_channel_energy = std::min(outcome.min_channel_energy, in - out);
    outcome.travel = std::max(outcome.travel, norm(copies[0].state().p_WM));
  }
  for (int i = 0; i < n; ++i) {
    outcome.largest_speed = std::max(outcome.largest_speed, norm(copies[static_cast<std::size_t>(i)].state().v_WM));
    for (int j = 0; j < n; ++j) {
      outcome.largest_disagreement = std::max(
          outcome.largest_disagreement,
          norm(copies[static_cast<std::size_t>(i)].state().p_WM - copies[static_cast<std::size_t>(j)].state().p_WM));
    }
  }
  if (scenario.layer) {
    double net = 0.0, held = 0.0;
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        if (j == i) continue;
        const NetworkPassivity* ij = copies[static_cast<std::size_t>(i)].coupling(static_cast<std::size_t>(slot_of(i, j)));
        const NetworkPassivity* ji = copies[static_cast<std::size_t>(j)].coupling(static_cast<std::size_t>(slot_of(j, i)));
        net += ij->injected() - ij->given();
        held += ij->reservoir() + ij->sent() - ji->received();  // in flight from i to j
      }
    }
    outcome.conservation_error = std::abs(net - held);
  }
  return outcome;
}

TEST(SharedMass, ValidateNamesTheBadParameter) {
  SharedMassParams params;
  EXPECT_EQ(validate(params), "");
  params.mass = 0.0;
  EXPECT_EQ(validate(params), "mass: must be finite and > 0, got 0");
  params = {};
  params.coupling_damping = -1.0;
  EXPECT_EQ(validate(params), "coupling_damping: must be finite and >= 0, got -1");
  params = {};
  params.radius = NAN;
  EXPECT_NE(validate(params).find("radius"), std::string::npos);
}

TEST(SharedMass, ATouchPushesTheToolOutAndTheMassAway) {
  SharedMass mass(SharedMassParams{}, SharedMassState{});
  const Vec3 F = mass.touch({-0.015, 0, 0});  // 5 mm deep on the −x side
  EXPECT_NEAR(F.x, -500.0 * 0.005, 1e-12);
  EXPECT_EQ(mass.touch({-0.03, 0, 0}), Vec3{});
  EXPECT_EQ(mass.touch({NAN, 0, 0}), Vec3{});  // a non-finite tool: nothing
  mass.step({});
  EXPECT_GT(mass.state().v_WM.x, 0.0);  // the reaction pushed it +x
}

TEST(SharedMass, TheCouplingsOfOneCopyShareItsDamperCap) {
  // A held damper α on mass M is stable only for α T / M < 2: the couplings acting on one copy
  // together get M/T between them, M/(2T) each with two copies coupled, M/T with one.
  const SharedMassParams params;
  const double M_over_T = params.mass / params.period;
  CopyCouplings couplings;
  const SharedMassState copy{{0, 0, 0}, {0.1, 0, 0}};
  const RemoteMassCopy two[2] = {{7, {0.01, 0, 0}, {}, 0.0}, {8, {-0.01, 0, 0}, {}, 0.0}};
  couplings.force(two, copy, params.mass, params);
  ASSERT_NE(couplings.coupling(0), nullptr);
  ASSERT_NE(couplings.coupling(1), nullptr);
  EXPECT_DOUBLE_EQ(couplings.coupling(0)->max_damping(), M_over_T / 2.0);
  EXPECT_DOUBLE_EQ(couplings.coupling(1)->max_damping(), M_over_T / 2.0);
  // One of them gone: the other has the whole cap.
  const RemoteMassCopy one[2] = {{7, {0.01, 0, 0}, {}, 0.0}, {}};
  couplings.force(one, copy, params.mass, params);
  EXPECT_EQ(couplings.coupling(1), nullptr);
  EXPECT_DOUBLE_EQ(couplings.coupling(0)->max_damping(), M_over_T);
}

TEST(SharedMass, ANonFiniteRemoteCopyCouplesNothing) {
  SharedMass mass(SharedMassParams{}, SharedMassState{});
  const RemoteMassCopy bad[1] = {{7, {NAN, 0, 0}, {}, 0.0}};
  for (int k = 0; k < 10; ++k) mass.step(bad);
  EXPECT_TRUE(is_finite(mass.state().p_WM));
  EXPECT_EQ(mass.state().p_WM, Vec3{});
}

TEST(SharedMass, WithoutTheLayerTheDelayedCouplingsCreateEnergy) {
  for (const int sites : {2, 3}) {
    for (const long delay : {50L, 100L}) {
      Scenario scenario;
      scenario.sites = sites;
      scenario.delay_ticks = delay;
      scenario.layer = false;
      const Outcome outcome = run(scenario);
      if (outcome.blew_up_at >= 0.0) {
        std::printf("%d sites, no layer, %ld ms one way: rang up to non-finite at %.1f s\n", sites, delay,
                    outcome.blew_up_at);
      } else {
        std::printf("%d sites, no layer, %ld ms one way: channel energy down to %.3g J\n", sites, delay,
                    outcome.min_channel_energy);
      }
      EXPECT_LT(outcome.min_channel_energy, -0.1) << sites << " sites, " << delay << " ms";
    }
  }
}

TEST(SharedMass, WithTheLayerEveryDelayAndLossStaysPassiveAndTheCopiesAgree) {
  for (const int sites : {2, 3}) {
    for (const long delay : {0L, 10L, 50L, 100L}) {
      for (const double loss : {0.0, 0.1}) {
        Scenario scenario;
        scenario.sites = sites;
        scenario.delay_ticks = delay;
        scenario.loss = loss;
        const Outcome outcome = run(scenario);
        std::printf("%d sites, layer, %3ld ms, %2.0f %% loss: channel energy down to %.2e J, largest force %.2f N, "
                    "copies %.2e m apart, moving %.1e m/s at the end; pushed %.3f m\n",
                    sites, delay, 100.0 * loss, outcome.min_channel_energy, outcome.largest_force,
                    outcome.largest_disagreement, outcome.largest_speed, outcome.travel);
        ASSERT_TRUE(outcome.finite);
        EXPECT_GT(outcome.min_channel_energy, -2e-3) << sites << " sites, " << delay << " ms, " << loss;
        EXPECT_LE(outcome.largest_force, kMaxForce);
        EXPECT_LT(outcome.largest_disagreement, 1e-5) << sites << " sites, " << delay << " ms, " << loss;
        EXPECT_GT(outcome.travel, 0.01);  // the hands did move the mass
        EXPECT_LT(outcome.conservation_error, 1e-9);
      }
    }
  }
}

TEST(SharedMass, StepAllocatesNothing) {
  SharedMass mass(SharedMassParams{}, SharedMassState{});
  const RemoteMassCopy remotes[2] = {{1, {0.001, 0, 0}, {}, 0.0}, {2, {0, 0.001, 0}, {}, 0.0}};
  double sink = 0.0;
  haptic::test::reset_allocations();
  {
    haptic::test::CountAllocations counting;
    for (int k = 0; k < 1000; ++k) {
      sink += mass.touch({-0.015, 0, 0}).x;
      mass.step(remotes);
    }
  }
  EXPECT_EQ(haptic::test::allocations(), 0u);
  EXPECT_TRUE(std::isfinite(sink));
}

}  // namespace
}  // namespace haptic::engine
