// Two sites in lockstep, each a device held by a scripted hand and rendering the other site's tool
// as a touchable sphere at its delayed position, through a delay line with seeded loss: without
// the network passivity layer the delayed contact creates energy and the tools pass through each
// other; with it the channel stays passive for every delay and loss, and the tools come to rest
// where they would with no network at all. 60 s of simulated time per run.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <deque>
#include <random>

#include "engine/device/point_mass_plant.hpp"
#include "engine/safety/network_passivity.hpp"
#include "support/allocation_counter.hpp"

namespace haptic::engine {
namespace {

constexpr double kT = 1e-3;        // s
constexpr double kStiffness = 1e3; // the avatars' contact. N/m
constexpr double kRadius = 0.01;   // the avatars' reach: tools closer than this touch. m
constexpr double kHandK = 200.0;   // N/m
constexpr double kHandB = 2.0;     // N·s/m
constexpr double kMaxForce = 20.0; // the devices' limit. N

struct Message {
  Vec3 p_WT;
  double energy_sent = 0.0;
  long arrives = 0;
  bool lost = false;
};

struct Scenario {
  long delay_ticks = 0;      // one way
  double loss = 0.0;         // fraction of messages lost, seeded
  bool layer = true;
  Vec3 start[2] = {{-0.02, 0, 0}, {0.02, 0, 0}};
  Vec3 target[2] = {{0.01, 0, 0}, {-0.01, 0, 0}};  // the hands' targets, reached over 1.5 s
  long ticks = 60'000;
};

struct Outcome {
  double min_channel_energy = 0.0;  // min over time of Σ injected − Σ given, by the test's own books. J
  double largest_force = 0.0;       // N
  bool finite = true;
  Vec3 end[2];
  double conservation_error = 0.0;  // |Σ injected − Σ given − Σ reservoir − in flight| at the end. J
};

Outcome run(const Scenario& scenario) {
  PointMassParams device;
  device.mass = 0.05;
  device.damping = 0.1;
  device.workspace_min = {-1, -1, -1};
  device.workspace_max = {1, 1, 1};
  PointMassPlant plants[2] = {PointMassPlant(device, {scenario.start[0], {}}), PointMassPlant(device, {scenario.start[1], {}})};
  NetworkPassivityParams params;
  params.period = kT;
  params.max_damping = device.mass / kT;
  NetworkPassivity layers[2] = {NetworkPassivity(params), NetworkPassivity(params)};
  std::deque<Message> lines[2];  // lines[i]: from site i to the other
  Vec3 remote[2];
  bool has_remote[2] = {false, false};
  Vec3 F_previous[2], p_previous[2];
  double in[2] = {0, 0}, out[2] = {0, 0};
  std::mt19937 random(29);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  Outcome outcome;
  for (long k = 0; k < scenario.ticks; ++k) {
    for (int i = 0; i < 2; ++i) {
      while (!lines[1 - i].empty() && lines[1 - i].front().arrives <= k) {
        const Message m = lines[1 - i].front();
        lines[1 - i].pop_front();
        if (m.lost) continue;
        remote[i] = m.p_WT;
        has_remote[i] = true;
        if (scenario.layer) layers[i].receive(m.energy_sent);
      }
      const PointMassState& state = plants[i].state();
      if (k > 0) {  // the test's own books: the work the applied force did on this user
        const double W = dot(F_previous[i], state.p_WT - p_previous[i]);
        (W > 0.0 ? out[i] : in[i]) += std::abs(W);
      }
      // The other site's tool as a sphere at its delayed position.
      Vec3 F;
      double stored = 0.0;
      if (has_remote[i]) {
        const Vec3 apart = state.p_WT - remote[i];
        const double distance = norm(apart);
        const double depth = kRadius - distance;
        if (depth > 0.0 && distance > 0.0) {
          F = (kStiffness * depth / distance) * apart;
          stored = 0.5 * kStiffness * depth * depth;
        }
      }
      if (scenario.layer) F = layers[i].apply(F, state.v_WT, state.p_WT, stored).F_T_W;
      const double magnitude = norm(F);
      if (magnitude > kMaxForce) F *= kMaxForce / magnitude;  // the force guard
      outcome.largest_force = std::max(outcome.largest_force, norm(F));
      F_previous[i] = F;
      p_previous[i] = state.p_WT;
      lines[i].push_back({state.p_WT, layers[i].sent(), k + scenario.delay_ticks, uniform(random) < scenario.loss});
      const double t = static_cast<double>(k) * kT;
      const Vec3 target = scenario.start[i] + std::min(1.0, t / 1.5) * (scenario.target[i] - scenario.start[i]);
      plants[i].step(F, kT, [&](const Vec3& p, const Vec3& v) { return kHandK * (target - p) - kHandB * v; });
      outcome.finite = outcome.finite && is_finite(plants[i].state().p_WT);
    }
    outcome.min_channel_energy = std::min(outcome.min_channel_energy, in[0] + in[1] - out[0] - out[1]);
  }
  for (int i = 0; i < 2; ++i) outcome.end[i] = plants[i].state().p_WT;
  if (scenario.layer) {
    const double in_flight = layers[0].sent() - layers[1].received() + layers[1].sent() - layers[0].received();
    const double held = layers[0].reservoir() + layers[1].reservoir() + in_flight;
    const double net = layers[0].injected() + layers[1].injected() - layers[0].given() - layers[1].given();
    outcome.conservation_error = std::abs(net - held);
  }
  return outcome;
}

TEST(NetworkPassivity, WithoutTheLayerTheDelayedContactCreatesEnergyAndTheToolsPassThrough) {
  for (const long delay : {10L, 50L, 100L}) {
    Scenario scenario;
    scenario.delay_ticks = delay;
    scenario.layer = false;
    const Outcome outcome = run(scenario);
    std::printf("no layer, %ld ms one way: channel energy down to %.4f J, tool A ends at x = %.4f m\n", delay,
                outcome.min_channel_energy, outcome.end[0].x);
    EXPECT_LT(outcome.min_channel_energy, -0.1) << delay << " ms";
    EXPECT_GT(outcome.end[0].x, outcome.end[1].x) << delay << " ms: the tools did not pass through each other";
  }
}

TEST(NetworkPassivity, WithoutTheLayerTheContactTurnsActiveAtAFewMillisecondsOfDelay) {
  // The stability boundary without the layer: the shortest one-way delay at which the delayed
  // contact creates more than 10 mJ over the run (the sampled contact alone stays near 1e-5 J).
  long boundary = -1;
  for (long delay = 0; delay <= 10 && boundary < 0; ++delay) {
    Scenario scenario;
    scenario.delay_ticks = delay;
    scenario.layer = false;
    scenario.ticks = 20'000;
    const Outcome outcome = run(scenario);
    std::printf("no layer, %ld ms one way: channel energy down to %.6f J\n", delay, outcome.min_channel_energy);
    if (outcome.min_channel_energy < -1e-2) boundary = delay;
  }
  std::printf("no layer: active from %ld ms one way\n", boundary);
  EXPECT_GE(boundary, 1);   // with no delay the contact is passive (up to its sampling)
  EXPECT_LE(boundary, 10);  // and a few milliseconds make it active
}

TEST(NetworkPassivity, WithTheLayerTheChannelStaysPassiveForEveryDelayAndLoss) {
  const Outcome still = run(Scenario{});  // no delay, no loss: where the tools come to rest
  ASSERT_LT(still.end[0].x, still.end[1].x);
  for (const long delay : {0L, 10L, 50L, 100L}) {
    for (const double loss : {0.0, 0.1}) {
      Scenario scenario;
      scenario.delay_ticks = delay;
      scenario.loss = loss;
      const Outcome outcome = run(scenario);
      std::printf("layer, %ld ms one way, %.0f %% loss: channel energy down to %.6f J, largest force %.2f N\n",
                  delay, 100.0 * loss, outcome.min_channel_energy, outcome.largest_force);
      ASSERT_TRUE(outcome.finite);
      // ε: the one-period prediction error the controller dissipates afterwards.
      EXPECT_GT(outcome.min_channel_energy, -2e-3) << delay << " ms, " << loss;
      EXPECT_LE(outcome.largest_force, kMaxForce);
      for (int i = 0; i < 2; ++i) {
        EXPECT_NEAR(outcome.end[i].x, still.end[i].x, 2e-4) << "site " << i << ", " << delay << " ms, " << loss;
      }
      EXPECT_LT(outcome.conservation_error, 1e-9);  // Σ R + in flight = Σ injected − Σ given
    }
  }
}

TEST(NetworkPassivity, APushReachesTheOtherSiteAcrossTheDelay) {
  // B's hand holds still; A's pushes past it: B is pushed to where it would be with no network.
  Scenario scenario;
  scenario.target[0] = {0.03, 0, 0};
  scenario.target[1] = {0.02, 0, 0};
  const Outcome near = run(scenario);
  scenario.delay_ticks = 50;
  const Outcome far = run(scenario);
  EXPECT_GT(near.end[1].x, 0.025);  // pushed
  EXPECT_NEAR(far.end[1].x, near.end[1].x, 2e-4);
  EXPECT_GT(far.min_channel_energy, -1e-2);
}

TEST(NetworkPassivity, ReceivedEnergyIsCreditedOnceAndAnOlderTotalChangesNothing) {
  // The other site's cumulative total: what it adds beyond the last total taken goes into the
  // reservoir, once; a total older than one taken (reordered, or from before a loss) adds nothing.
  NetworkPassivity layer(NetworkPassivityParams{});
  layer.receive(0.010);
  EXPECT_DOUBLE_EQ(layer.reservoir(), 0.010);
  EXPECT_DOUBLE_EQ(layer.received(), 0.010);
  layer.receive(0.004);
  EXPECT_DOUBLE_EQ(layer.reservoir(), 0.010);
  layer.receive(0.025);
  EXPECT_DOUBLE_EQ(layer.reservoir(), 0.025);
  EXPECT_DOUBLE_EQ(layer.received(), 0.025);
  // What it may give is what it holds: a push along v is not damped while the reservoir pays.
  const NetworkPassivityStep step = layer.apply({1.0, 0, 0}, {0.1, 0, 0}, {}, 0.0);
  EXPECT_EQ(step.alpha, 0.0);
}

TEST(NetworkPassivity, ApplyAllocatesNothing) {
  NetworkPassivity layer(NetworkPassivityParams{});
  double sink = 0.0;
  haptic::test::reset_allocations();
  {
    haptic::test::CountAllocations counting;
    for (int k = 0; k < 1000; ++k) {
      const Vec3 p{1e-4 * k, 0, 0};
      sink += layer.apply({-1.0, 0, 0}, {0.1, 0, 0}, p, 1e-4).F_T_W.x;
      layer.receive(1e-6 * k);
    }
  }
  EXPECT_EQ(haptic::test::allocations(), 0u);
  EXPECT_TRUE(std::isfinite(sink));
}

}  // namespace
}  // namespace haptic::engine
