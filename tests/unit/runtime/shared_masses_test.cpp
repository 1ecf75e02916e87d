// Two and three sites' loops in lockstep, each the server's own TickRunner with a simulated device
// and a scene holding its copy of one virtual mass shared across sites (as the shared scene
// replicates it), joined as the federation joins them: each site's copies go out through a delay
// line with seeded loss into the others' mailboxes (the relay's job), and the SharedMassStage
// couples each copy to the others through its network passivity layers. Scripted hands push the
// mass from two or three sides, squeeze it, push it through and let go; 60 s of simulated time.
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
constexpr std::uint64_t kTicks = 60'000;
constexpr double kMaxForce = 20.0;  // the devices' limit. N

using engine::shared_mass_key;
using engine::site_key;
using test::hand_towards;
using test::Phase;

/// The shared sphere as site `site` (0: the one that made it, item 1) compiles it.
std::unique_ptr<const engine::CompiledScene> scene_at(int site) {
  return test::shared_sphere_at(site, "site-0", 0.02, kPeriod);
}

/// Where each site's hand takes its tool, phase by phase (targets move over 1.5 s): push the
/// mass, squeeze it, push it through, and let go from 40 s.
std::vector<std::vector<Phase>> scripts() {
  return {{{0, {-0.05, 0, 0}}, {1, {-0.005, 0, 0}}, {25, {0.01, 0, 0}}, {40, {-0.05, 0, 0}}},
          {{0, {0.05, 0, 0}}, {12, {0.0, 0, 0}}, {40, {0.05, 0, 0}}},
          {{0, {0.01, -0.05, 0}}, {18, {0.01, -0.01, 0}}, {40, {0.01, -0.05, 0}}}};
}

/// A site's loop with the mass stage (no remote tools).
struct Site : test::LockstepSite {
  Site(int index, const engine::Vec3& start)
      : LockstepSite(site_key("site-" + std::to_string(index)), start, scene_at(index),
                     {.period_s = kPeriod, .max_force_N = kMaxForce, .shared_masses = true}) {}
};

struct Message {
  LocalMassCopy copy;
  std::uint64_t arrives = 0;
  bool lost = false;
};

struct Outcome {
  double lowest_channel_energy = 0.0;  // min over time of Σ (injected − given) over every coupling. J
  double largest_force = 0.0;          // the largest force a device was given. N
  double disagreement = 0.0;           // at the end: the copies' largest distance apart. m
  double travel = 0.0;                 // how far site 0's copy went at its farthest. m
  std::uint64_t force_faults = 0;
};

Outcome run(int sites, std::uint64_t delay, double loss) {
  const std::vector<std::vector<Phase>> script = scripts();
  std::vector<std::unique_ptr<Site>> site;
  for (int i = 0; i < sites; ++i) site.push_back(std::make_unique<Site>(i, script[static_cast<std::size_t>(i)][0].target));
  std::vector<std::deque<Message>> lines(static_cast<std::size_t>(sites * sites));  // [from * sites + to]
  std::vector<std::size_t> phase(static_cast<std::size_t>(sites), 0);
  std::mt19937 random(30);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  Outcome outcome;
  const std::uint64_t mass_key = shared_mass_key(site_key("site-0"), 1);
  for (std::uint64_t tick = 1; tick <= kTicks; ++tick) {
    const double t = static_cast<double>(tick - 1) * kPeriod;
    double channel = 0.0;
    for (int i = 0; i < sites; ++i) {
      Site& s = *site[static_cast<std::size_t>(i)];
      const std::vector<Phase>& mine = script[static_cast<std::size_t>(i)];
      std::size_t& next = phase[static_cast<std::size_t>(i)];
      if (next + 1 < mine.size() && t >= mine[next + 1].at_s) {
        s.device.set_hand(hand_towards(mine[next].target, mine[next + 1].target));
        ++next;
      }
      // Deliver what has arrived into this site's mailbox (the relay's receiver).
      RemoteMassTable table = s.in.load();
      table.masses[0].mass_key = mass_key;
      for (int j = 0; j < sites; ++j) {
        std::deque<Message>& line = lines[static_cast<std::size_t>(j * sites + i)];
        while (!line.empty() && line.front().arrives <= tick) {
          const Message m = line.front();
          line.pop_front();
          if (m.lost) continue;
          double sent_to_us = 0.0;
          for (std::size_t k = 0; k < engine::kMaxRemoteCopies; ++k) {
            if (m.copy.coupled_site[k] == s.key) sent_to_us = m.copy.sent[k];
          }
          table.masses[0].copies[static_cast<std::size_t>(j)] = {site[static_cast<std::size_t>(j)]->key, m.copy.p_WM,
                                                                  m.copy.v_WM, sent_to_us};
        }
      }
      s.in.store(table);
      s.runner.run(tick, static_cast<std::int64_t>(tick - 1) * 1'000'000);
      TickSample sample;
      s.samples.read(tick, sample);
      outcome.largest_force = std::max(outcome.largest_force, engine::norm(sample.F_T_W));
      const LocalMassCopy copy = s.out.load().masses[0];
      for (int j = 0; j < sites; ++j) {
        if (j != i) lines[static_cast<std::size_t>(i * sites + j)].push_back({copy, tick + delay, uniform(random) < loss});
      }
      if (i == 0) outcome.travel = std::max(outcome.travel, engine::norm(copy.p_WM));
      const engine::CopyCouplings* couplings = s.stage.couplings_of(mass_key);
      for (std::size_t k = 0; couplings != nullptr && k < engine::kMaxRemoteCopies; ++k) {
        if (const engine::NetworkPassivity* layer = couplings->coupling(k)) channel += layer->injected() - layer->given();
      }
    }
    outcome.lowest_channel_energy = std::min(outcome.lowest_channel_energy, channel);
  }
  for (int i = 0; i < sites; ++i) {
    outcome.force_faults += site[static_cast<std::size_t>(i)]->counters.force_faults.load();
    for (int j = 0; j < sites; ++j) {
      outcome.disagreement = std::max(outcome.disagreement, engine::norm(site[static_cast<std::size_t>(i)]->out.load().masses[0].p_WM -
                                                                         site[static_cast<std::size_t>(j)]->out.load().masses[0].p_WM));
    }
  }
  return outcome;
}

TEST(SharedMasses, SitesLoopsPushOneMassPassivelyAcrossDelayAndLossAndTheCopiesAgree) {
  for (const int sites : {2, 3}) {
    for (const std::uint64_t delay : {0u, 10u, 50u, 100u}) {
      for (const double loss : {0.0, 0.1}) {
        const Outcome outcome = run(sites, delay, loss);
        std::printf("%d loops, %3llu ms one way, %2.0f %% loss: channel energy down to %.2e J, largest force %.2f N, "
                    "copies %.1e m apart at the end; pushed %.3f m\n",
                    sites, static_cast<unsigned long long>(delay), 100.0 * loss, outcome.lowest_channel_energy,
                    outcome.largest_force, outcome.disagreement, outcome.travel);
        EXPECT_GT(outcome.lowest_channel_energy, -2e-3) << sites << " sites, " << delay << " ms, " << loss;
        EXPECT_LE(outcome.largest_force, kMaxForce);
        EXPECT_EQ(outcome.force_faults, 0u);
        EXPECT_LT(outcome.disagreement, 1e-5) << sites << " sites, " << delay << " ms, " << loss;
        EXPECT_GT(outcome.travel, 0.01);  // the hands moved the mass
      }
    }
  }
}

TEST(SharedMasses, KeysAreTheSameAtEverySiteAndNeverZero) {
  EXPECT_EQ(site_key("lab-a"), site_key(std::string("lab-") + "a"));
  EXPECT_NE(site_key("lab-a"), site_key("lab-b"));
  EXPECT_NE(shared_mass_key(site_key("lab-a"), 1), shared_mass_key(site_key("lab-a"), 2));
  EXPECT_NE(shared_mass_key(site_key("lab-a"), 1), shared_mass_key(site_key("lab-b"), 1));
  EXPECT_NE(shared_mass_key(engine::SiteKey{}, 0), 0u);
}

TEST(SharedMasses, ATickWithASharedMassAllocatesNothing) {
  Site a(0, {-0.05, 0, 0});
  RemoteMassTable table;
  table.masses[0].mass_key = shared_mass_key(a.key, 1);
  table.masses[0].copies[0] = {site_key("site-1"), {0.001, 0, 0}, {}, 0.0};
  a.in.store(table);
  for (std::uint64_t tick = 1; tick <= 100; ++tick) a.runner.run(tick, static_cast<std::int64_t>(tick) * 1'000'000);
  ASSERT_NE(a.stage.couplings_of(table.masses[0].mass_key), nullptr);
  haptic::test::reset_allocations();
  {
    haptic::test::CountAllocations counting;
    for (std::uint64_t tick = 101; tick <= 1100; ++tick) a.runner.run(tick, static_cast<std::int64_t>(tick) * 1'000'000);
  }
  EXPECT_EQ(haptic::test::allocations(), 0u);
}

}  // namespace
}  // namespace haptic::runtime
