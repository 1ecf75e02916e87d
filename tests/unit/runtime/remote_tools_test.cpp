// Two sites' loops in lockstep, each the server's own TickRunner with a simulated device, joined
// as the federation joins them: each port's mailbox of remote tools (written here by a delay line
// with seeded loss, as the receiver thread would), its avatars rendered through each coupling's
// network passivity layer, and the ledger of what each coupling sent going back the other way.
// The scripted hands push the tools into each other for 60 s.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <deque>
#include <memory>
#include <random>
#include <vector>

#include "support/allocation_counter.hpp"
#include "support/lockstep_site.hpp"

namespace haptic::runtime {
namespace {

constexpr double kPeriod = 1e-3;

/// One site: its device held by a hand whose target moves from `start` to `end` over 1.5 s.
struct Site : test::LockstepSite {
  Site(const engine::Vec3& start, const engine::Vec3& end, std::uint64_t site)
      : LockstepSite(engine::SiteKey{site}, start,
                     std::make_unique<const engine::CompiledScene>(engine::compile_scene({}, 50, 1, kPeriod)),
                     {.period_s = kPeriod, .max_force_N = 20.0, .remote_tools = true, .avatar_radius_m = 0.01}) {
    device.set_hand(test::hand_towards(start, end));
  }
};

struct Message {
  engine::Vec3 p_WT, v_WT;
  double sent = 0.0;
  std::uint64_t arrives = 0;
  bool lost = false;
};

/// Runs both sites for `ticks` ticks with `delay` ticks one way; returns the lowest channel
/// energy (the work both users did on the couplings minus what they got back, from the samples).
double run(Site& a, Site& b, std::uint64_t delay, double loss, std::uint64_t ticks) {
  Site* sites[2] = {&a, &b};
  std::deque<Message> lines[2];
  std::mt19937 random(11);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  double channel = 0.0, lowest = 0.0;
  TickSample previous[2];
  for (std::uint64_t tick = 1; tick <= ticks; ++tick) {
    for (int i = 0; i < 2; ++i) {
      // Deliver what has arrived into this site's mailbox (the receiver thread's job).
      RemoteToolSet set = sites[i]->remote.load();
      while (!lines[1 - i].empty() && lines[1 - i].front().arrives <= tick) {
        const Message m = lines[1 - i].front();
        lines[1 - i].pop_front();
        if (m.lost) continue;
        set.tools[0] = RemoteTool{sites[1 - i]->key.value, m.p_WT, m.v_WT, m.sent};
      }
      sites[i]->remote.store(set);
      sites[i]->runner.run(tick, static_cast<std::int64_t>(tick - 1) * 1'000'000);
      TickSample sample;
      sites[i]->samples.read(tick, sample);
      if (tick > 1) channel -= engine::dot(previous[i].F_T_W, sample.p_WT - previous[i].p_WT);
      previous[i] = sample;
      lines[i].push_back({sample.p_WT, sample.v_WT, sites[i]->ledger.sent(0), tick + delay, uniform(random) < loss});
    }
    lowest = std::min(lowest, channel);
  }
  return lowest;
}

TEST(RemoteTools, TwoSitesLoopsTouchEachOtherPassivelyAcrossDelayAndLoss) {
  Site still_a({-0.02, 0, 0}, {0.01, 0, 0}, 0xA), still_b({0.02, 0, 0}, {-0.01, 0, 0}, 0xB);
  run(still_a, still_b, 0, 0.0, 60'000);
  const double rest_a = still_a.device.plant().state().p_WT.x;
  ASSERT_LT(rest_a, -0.002);  // blocked by the other tool, not passed through
  for (const std::uint64_t delay : {10u, 50u, 100u}) {
    for (const double loss : {0.0, 0.1}) {
      Site a({-0.02, 0, 0}, {0.01, 0, 0}, 0xA), b({0.02, 0, 0}, {-0.01, 0, 0}, 0xB);
      const double lowest = run(a, b, delay, loss, 60'000);
      std::printf("two loops, %llu ms one way, %.0f %% loss: channel energy down to %.6f J\n",
                  static_cast<unsigned long long>(delay), 100.0 * loss, lowest);
      EXPECT_GT(lowest, -2e-3) << delay << " ms, " << loss;
      EXPECT_NEAR(a.device.plant().state().p_WT.x, rest_a, 2e-4) << delay << " ms, " << loss;
      EXPECT_EQ(a.counters.force_faults.load(), 0u);
    }
  }
}

TEST(RemoteTools, ARemoteToolThatLeavesFadesOutOverTheRemovalRampAndItsBooksAreKept) {
  // A's hand holds its tool 5 mm inside the avatar of a remote tool that then leaves the mailbox
  // (its site went quiet): the avatar's force falls over the 50-tick output ramp, never a step.
  Site a({-0.005, 0, 0}, {-0.005, 0, 0}, 0xA);
  // A stiff, well-damped grip: the tool stays within 0.3 mm of where it is held, so the force
  // shows the ramp (a soft hand would follow the fading avatar in, as into any fading item).
  engine::HandInput grip;
  grip.mode = engine::HandInput::Mode::kFollowTarget;
  grip.target = {-0.005, 0, 0};
  grip.stiffness = 20000.0;
  grip.damping = 200.0;
  a.device.set_hand(grip);
  RemoteToolSet set;
  set.tools[0] = RemoteTool{0xB, {0, 0, 0}, {}, 0.0};
  a.remote.store(set);
  TickSample sample;
  std::uint64_t tick = 1;
  for (; tick <= 2000; ++tick) a.runner.run(tick, static_cast<std::int64_t>(tick) * 1'000'000);
  a.samples.read(tick - 1, sample);
  const double held = engine::norm(sample.F_T_W);
  ASSERT_GT(held, 4.0);  // pressed 5 mm into the avatar (1000 N/m)
  const CouplingBooks books = a.ledger.books(0);
  EXPECT_EQ(books.key, 0xBu);
  EXPECT_GE(books.injected - books.given + books.received - books.sent, books.reservoir - 1e-12);
  a.remote.store(RemoteToolSet{});
  double previous = held, largest_step = 0.0;
  std::vector<double> forces;
  for (int k = 0; k < 60; ++k, ++tick) {
    a.runner.run(tick, static_cast<std::int64_t>(tick) * 1'000'000);
    a.samples.read(tick, sample);
    const double now = engine::norm(sample.F_T_W);
    largest_step = std::max(largest_step, std::abs(now - previous));
    forces.push_back(now);
    previous = now;
  }
  std::printf("avatar fade-out: %.3f N held, largest step %.3f N a tick, %.3f N after 25 ticks\n", held, largest_step,
              forces[24]);
  EXPECT_GT(forces[0], 0.9 * held);              // not dropped at once
  EXPECT_NEAR(forces[24], 0.5 * held, 0.15 * held);  // half way down the ramp
  EXPECT_EQ(forces[55], 0.0);                    // gone once the ramp has run
  EXPECT_LT(largest_step, 0.1 * held);           // never a step
  EXPECT_EQ(a.ledger.books(0).key, 0u);          // the coupling ended
}

TEST(RemoteTools, ATickWithRemoteToolsAllocatesNothing) {
  Site a({-0.02, 0, 0}, {0.01, 0, 0}, 0xA), b({0.02, 0, 0}, {-0.01, 0, 0}, 0xB);
  run(a, b, 10, 0.0, 1000);  // the couplings exist
  haptic::test::reset_allocations();
  {
    haptic::test::CountAllocations counting;
    for (std::uint64_t tick = 1001; tick <= 2000; ++tick) a.runner.run(tick, static_cast<std::int64_t>(tick) * 1'000'000);
  }
  EXPECT_EQ(haptic::test::allocations(), 0u);
}

}  // namespace
}  // namespace haptic::runtime
