// A federation peer that lies (issue: "a federation peer speaks only for its own site"), against one
// whole site as hapticd runs it (its TickRunner, simulated device held still by a hand, mailbox of
// remote tools, ledger, SampleRelay) over a delay line. The forger publishes tool samples straight
// onto the network: under another site's name, with a NaN, with energy it never sent, or moving its
// tool into the user's without sending any. What the user is given beyond what they put in is the
// test's own books: the work the commanded force F_T_W did on the tool, Σ F(k−1)·(p(k) − p(k−1)).
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "engine/safety/network_passivity.hpp"
#include "federation/sample_relay.hpp"
#include "support/delay_line_network.hpp"
#include "support/lockstep_site.hpp"

namespace haptic::federation {
namespace {

constexpr double kPeriod = 1e-3;
constexpr std::uint64_t kDelay = 5;  // one way, ticks
const auto kT0 = std::chrono::steady_clock::time_point{} + std::chrono::hours(1);
const std::string kVictim = "site-0";
const std::string kForger = "site-9";

std::chrono::steady_clock::time_point clock_at(std::uint64_t tick) {
  return kT0 + std::chrono::milliseconds(static_cast<std::int64_t>(tick));
}

std::unique_ptr<const engine::CompiledScene> empty_scene() {
  return std::make_unique<const engine::CompiledScene>(engine::compile_scene(engine::SceneDescription{}, 50, 1, kPeriod));
}

/// The victim: one port, its tool at the origin, held there by the hand (200 N/m).
struct Victim : test::LockstepSite {
  Victim(test::DelayLineNetwork& network, const RelayOptions& options)
      : LockstepSite(engine::site_key(kVictim), {0, 0, 0}, empty_scene(),
                     {.period_s = kPeriod, .max_force_N = 20.0, .remote_tools = true, .avatar_radius_m = 0.01}),
        relay(options, network.site(kVictim), {RelayPort{&samples, 0, &remote, &ledger}}) {}
  SampleRelay relay;
};

RelayOptions victim_options(std::vector<std::string>* log) {
  RelayOptions options;
  options.site = kVictim;
  if (log != nullptr) options.log = [log](const std::string& line) { log->push_back(line); };
  return options;
}

/// What the forger sends each tick: its tool's position and what it says it sent the victim.
struct Forgery {
  std::string claimed_site = kForger;  // the site the sample names
  /// The forger's tool along x at time t (s); the victim's tool sits at 0 with a 1 cm avatar.
  double (*x)(double t) = nullptr;
  /// The cumulative energy it claims its coupling sent the victim's port 0, at time t. J.
  double (*claimed_J)(double t) = nullptr;
  double seconds = 10.0;
};

struct Outcome {
  double extracted_J = 0.0;   // the most the victim's user was given beyond what they put in. J
  double largest_force_N = 0.0;
  double force_at_end_N = 0.0;
  bool coupled = false;       // the forger's tool ever reached the victim's mailbox
  bool all_finite = true;
  double credited_J = 0.0;    // the most the coupling was credited (its layer's received). J
  std::uint64_t samples_refused = 0;
  std::uint64_t sites_cut_off = 0;
  double cut_off_at_s = -1.0;  // when the relay cut the forger off
};

Outcome run(const Forgery& forgery, std::vector<std::string>* log = nullptr) {
  test::DelayLineNetwork network(kDelay, 0.0);
  Victim victim(network, victim_options(log));
  Transport& forger = network.site(kForger);
  Outcome outcome;
  runtime::TickSample sample, previous;
  double given = 0.0;
  const auto ticks = static_cast<std::uint64_t>(forgery.seconds / kPeriod);
  for (std::uint64_t tick = 1; tick <= ticks; ++tick) {
    const double t = static_cast<double>(tick - 1) * kPeriod;
    ToolState tool;
    tool.site = forgery.claimed_site;
    tool.tick = tick;
    tool.time_ns = static_cast<std::int64_t>(tick) * 1'000'000;
    tool.p_WT = {forgery.x(t), 0, 0};
    if (forgery.claimed_J != nullptr) tool.energy.push_back({kVictim, 0, forgery.claimed_J(t)});
    forger.publish_tool(tool);
    victim.runner.run(tick, static_cast<std::int64_t>(tick - 1) * 1'000'000);
    victim.samples.read(tick, sample);
    if (tick > 1) given += engine::dot(previous.F_T_W, sample.p_WT - previous.p_WT);
    previous = sample;
    outcome.extracted_J = std::max(outcome.extracted_J, given);
    outcome.largest_force_N = std::max(outcome.largest_force_N, engine::norm(sample.F_T_W));
    outcome.all_finite = outcome.all_finite && std::isfinite(sample.F_T_W.x) && std::isfinite(sample.p_WT.x);
    for (const runtime::RemoteTool& remote : victim.remote.load().tools) {
      outcome.coupled = outcome.coupled || remote.key != 0;
    }
    outcome.credited_J = std::max(outcome.credited_J, victim.ledger.books(0).received);
    victim.relay.step(clock_at(tick));
    network.advance();
    if (outcome.cut_off_at_s < 0.0 && victim.relay.sites_cut_off() > 0) outcome.cut_off_at_s = t;
  }
  outcome.force_at_end_N = engine::norm(sample.F_T_W);
  outcome.samples_refused = victim.relay.samples_refused();
  outcome.sites_cut_off = victim.relay.sites_cut_off();
  return outcome;
}

/// A tool that pushes the user's in (from 12 mm to 4 mm away, the avatar's reach 10 mm) over each
/// quarter second and then jumps back out, so the user's tool returns with no force on it: each
/// push gives the user energy that nobody put in, the most a tool can take out of a held hand.
double pushing(double t) { return 0.012 - 0.008 * (4.0 * t - std::floor(4.0 * t)); }

double never_sent(double) { return 0.0; }

const CreditCap kCap;  // the default

TEST(ForgingPeer, AToolNamingAnotherSiteIsRefusedAndLoggedOnce) {
  std::vector<std::string> log;
  Forgery forgery;
  forgery.claimed_site = "site-1";  // not the forger's own
  forgery.x = pushing;
  forgery.claimed_J = [](double t) { return 0.01 * t; };
  forgery.seconds = 5.0;
  const Outcome o = run(forgery, &log);
  EXPECT_FALSE(o.coupled) << "a sample under another site's name reached the loop";
  EXPECT_EQ(o.largest_force_N, 0.0);
  EXPECT_GE(o.samples_refused, 5000u - kDelay);  // all but those still in flight
  ASSERT_EQ(log.size(), 1u) << "the forger's samples are logged once a window";
  EXPECT_NE(log[0].find("a tool sample naming site \"site-1\" refused: its writer speaks for site \"site-9\""),
            std::string::npos)
      << log[0];
}

TEST(ForgingPeer, ASampleWithANaNIsRefusedAndLogged) {
  std::vector<std::string> log;
  Forgery forgery;
  forgery.x = [](double t) { return t < 1.0 ? 0.008 : std::numeric_limits<double>::quiet_NaN(); };
  forgery.claimed_J = never_sent;
  forgery.seconds = 3.0;
  const Outcome o = run(forgery, &log);
  EXPECT_TRUE(o.all_finite);
  EXPECT_GE(o.samples_refused, 1990u);  // every NaN sample (the first second's are taken)
  std::size_t refusals = 0;
  for (const std::string& line : log) {
    if (line.find("a tool sample from site \"site-9\" refused: it holds a NaN or an infinity") != std::string::npos) {
      ++refusals;
    }
  }
  EXPECT_EQ(refusals, 1u) << "logged once a window";
  EXPECT_EQ(o.force_at_end_N, 0.0) << "the tool's avatar outlived its last finite sample";
}

TEST(ForgingPeer, AToolThatPushesWithoutSendingEnergyGivesTheUserAtMostTheDeficitBound) {
  Forgery forgery;
  forgery.x = pushing;
  forgery.claimed_J = never_sent;
  forgery.seconds = 30.0;
  const Outcome o = run(forgery);
  std::printf("a tool pushing without energy, 4 pushes a second for 30 s: the user given %.2f mJ beyond what they "
              "put in (bound %.1f mJ), %.2f N at most\n",
              o.extracted_J * 1e3, engine::kCouplingMaxDeficitJ * 1e3, o.largest_force_N);
  EXPECT_TRUE(o.coupled);
  EXPECT_TRUE(o.all_finite);
  EXPECT_GT(o.largest_force_N, 0.3);  // it did push
  EXPECT_LE(o.extracted_J, engine::kCouplingMaxDeficitJ + 1e-4);
  EXPECT_EQ(o.sites_cut_off, 0u);  // nothing it says is false: it is held by the layer, not cut off
}

TEST(ForgingPeer, EnergyClaimedUnderTheCapIsCreditedNoFasterThanTheCap) {
  Forgery forgery;
  forgery.x = pushing;
  forgery.claimed_J = [](double t) { return 0.9 * t; };  // 0.9 W "sent", just under the cap
  forgery.seconds = 10.0;
  const Outcome o = run(forgery);
  std::printf("a tool claiming 0.9 W for 10 s (cap %.1f W, %.2f J at once): %.3f J credited, the user given %.2f mJ "
              "beyond what they put in\n",
              kCap.max_power_W, kCap.burst_J, o.credited_J, o.extracted_J * 1e3);
  EXPECT_EQ(o.sites_cut_off, 0u);
  EXPECT_LE(o.credited_J, kCap.burst_J + kCap.max_power_W * forgery.seconds);
  EXPECT_LE(o.extracted_J, o.credited_J + engine::kCouplingMaxDeficitJ + 1e-4);
}

TEST(ForgingPeer, EnergyClaimedOverTheCapCutsTheSiteOff) {
  struct Case {
    const char* what;
    double (*claimed_J)(double t);
  };
  for (const Case& c : {Case{"10 W", [](double t) { return 10.0 * t; }},
                        Case{"100 J at 1 s", [](double t) { return t < 1.0 ? 0.0 : 100.0; }},
                        Case{"a NaN at 1 s", [](double t) { return t < 1.0 ? 0.0 : std::nan(""); }},
                        Case{"-1 J at 1 s", [](double t) { return t < 1.0 ? 0.0 : -1.0; }}}) {
    std::vector<std::string> log;
    Forgery forgery;
    forgery.x = pushing;
    forgery.claimed_J = c.claimed_J;
    forgery.seconds = 5.0;
    const Outcome o = run(forgery, &log);
    std::printf("a tool claiming %s: cut off at %.3f s, %.3f J credited, the user given %.2f mJ beyond what they put "
                "in\n",
                c.what, o.cut_off_at_s, o.credited_J, o.extracted_J * 1e3);
    EXPECT_EQ(o.sites_cut_off, 1u) << c.what;
    EXPECT_EQ(o.force_at_end_N, 0.0) << c.what << ": its avatar outlived the cut";
    EXPECT_LE(o.credited_J, 2.0 * kCap.burst_J) << c.what;
    EXPECT_LE(o.extracted_J, o.credited_J + engine::kCouplingMaxDeficitJ + 1e-4) << c.what;
    bool logged = false;
    for (const std::string& line : log) {
      if (line.find("federation: site \"site-9\" cut off: its books do not add up") != 0) continue;
      logged = true;
      std::printf("  %s\n", line.c_str());
    }
    EXPECT_TRUE(logged) << c.what;
  }
}

TEST(ForgingPeer, AMassCopyWithANaNIsRefusedAndOneClaimingOverTheCapCutsItsSiteOff) {
  test::DelayLineNetwork network(kDelay, 0.0);
  std::vector<std::string> log;
  runtime::LatestValue<runtime::LocalMassTable> local;
  runtime::LatestValue<runtime::RemoteMassTable> remote;
  SampleRelay victim(victim_options(&log), network.site(kVictim), {}, RelayMasses{&local, &remote});
  Transport& forger = network.site(kForger);
  const std::uint64_t mass = engine::shared_mass_key(engine::site_key(kVictim), 1);
  const auto copies_of_forger = [&] {
    std::size_t copies = 0;
    for (const runtime::RemoteMassCopies& entry : remote.load().masses) {
      for (const engine::RemoteMassCopy& copy : entry.copies) copies += copy.key == engine::site_key(kForger);
    }
    return copies;
  };
  bool coupled = false;
  for (std::uint64_t tick = 1; tick <= 3000; ++tick) {
    MassState copy;
    copy.site = kForger;
    copy.mass = mass;
    copy.tick = tick;
    copy.p_WM = {tick < 1000 ? 0.0 : NAN, 0.0, 0.0};  // a NaN from 1 s to 2 s
    if (tick >= 2000) copy.p_WM = {};
    copy.sent = {{engine::site_key(kVictim), tick < 2500 ? 0.0 : 100.0}};  // 100 J "sent" at 2.5 s
    forger.publish_mass(copy);
    victim.step(clock_at(tick));
    network.advance();
    if (tick == 900) coupled = copies_of_forger() == 1;
  }
  EXPECT_TRUE(coupled) << "an honest copy was not taken";
  EXPECT_GE(victim.samples_refused(), 1000u - kDelay);  // the NaNs, then everything after the cut
  EXPECT_EQ(victim.sites_cut_off(), 1u);
  EXPECT_EQ(copies_of_forger(), 0u) << "the cut-off site's copy is still coupled";
  std::size_t nan_lines = 0, cut_lines = 0;
  for (const std::string& line : log) {
    nan_lines += line.find("a mass copy sample from site \"site-9\" refused: it holds a NaN") != std::string::npos;
    cut_lines += line.find("site \"site-9\" cut off: its books do not add up: the energy its copy of a shared mass") !=
                 std::string::npos;
  }
  EXPECT_EQ(nan_lines, 1u);
  EXPECT_EQ(cut_lines, 1u);
}

}  // namespace
}  // namespace haptic::federation
