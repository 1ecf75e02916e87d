// Three real-time hapticd sites over real Cyclone DDS between network namespaces
// (federation_netns.sh makes them; run alone this test skips): sites A, B and C, each in its own
// namespace on a veth bridge, with its own address for DDS, gRPC and UDP, the other two as its
// unicast peers, the federation in the clear (allow_insecure). The test runs in a fourth
// namespace: it starts each hapticd there with `ip netns exec`, and a client of each (the SDK)
// holds the site's tool with a simulated hand, makes its items across_sites, and reads what the
// site holds (its scene with all_sessions: its own items and the other sites').
//
//  1. An across_sites sphere made at A appears at B and C; its update and its removal follow.
//  2. C is SIGKILLed: its item leaves A and B once its writer's lease (1 s) has run out, and its
//     tool's avatar once its tool has been quiet for 0.5 s.
//  3. C restarts under the same name: it gets A's and B's live items (late join), and its new
//     item reaches A and B.
//
// Each wait is bounded by a stated time and polls (every 5 ms); each time taken is printed.

#include <gtest/gtest.h>
#include <signal.h>

#include <haptic/haptic.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <variant>
#include <vector>

#include "federation/item_topic.hpp"
#include "integration/server_process.hpp"

namespace haptic::test {
namespace {

using Clock = std::chrono::steady_clock;
using Seconds = std::chrono::duration<double>;

std::vector<std::string> words(const char* text) {
  std::vector<std::string> out;
  std::istringstream in(text == nullptr ? "" : text);
  for (std::string word; in >> word;) out.push_back(word);
  return out;
}

/// A site: its name in the federation, its namespace and address, where its tool is held.
struct Site {
  std::string name;
  std::string ns;
  std::string address;
  double x0 = 0.0;  // its tool's x, where a hand holds it. Unit: m.
};

/// A real-time hapticd in its namespace: DDS, gRPC and UDP on its namespace's address, the other
/// sites as unicast peers.
std::string site_config(const Site& site, const std::vector<Site>& sites) {
  std::string peers;
  for (const Site& other : sites) {
    if (other.name == site.name) continue;
    peers += (peers.empty() ? "\"" : ", \"") + other.address + "\"";
  }
  return R"({"udp_address": ")" + site.address + R"(", "status_period_s": 0,
      "real_time": {"use_fifo": false},
      "simulated_point_mass": {"initial_position": {"x": )" + std::to_string(site.x0) + R"(, "y": 0, "z": 0}},
      "federation": {"site": ")" + site.name + R"(", "domain_id": 7, "interface": ")" + site.address +
         R"(", "peers": [)" + peers + R"(], "allow_insecure": true}})";
}

std::unique_ptr<ServerProcess> start_site(const Site& site, const std::vector<Site>& sites) {
  return std::make_unique<ServerProcess>(site_config(site, sites), "--insecure", 0, 0, 0,
                                         ServerHost{{"ip", "netns", "exec", site.ns}, site.address});
}

// A tool held in another's avatar is pushed out with ≈ 0.44 N (0.9 mm deep at 500 N/m); once
// that avatar has gone no force is left (the third tool is 18 mm away).
constexpr double kTouching = 0.2;  // N
constexpr double kFree = 0.05;     // N

/// A site's client (the SDK): a hand holding its tool at x0 (400 N/m, 20 N·s/m, 0.2 kg: well
/// damped, so a contact settles rather than rings), inside the avatar of a tool 8 mm away (10 mm,
/// 500 N/m), so that the force the site renders is that avatar's; its items made across_sites;
/// what the site holds.
class SiteClient {
 public:
  SiteClient(const ServerProcess& server, const Site& site) : client_(config(server, site)) {
    OperatorInput hand = OperatorInput::follow({site.x0, 0.0, 0.0}, 400.0, 20.0);
    hand.mass = 0.2;
    client_.set_operator(hand);
  }

  /// An across_sites sphere (5 mm, 40 N/m: stable on the point mass) at (tag, y, 0.06), away
  /// from every tool.
  ObjectHandle add(double tag, double y) { return client_.add_sphere(sphere(tag, y)); }
  static void move(ObjectHandle& item, double tag, double y) { item.update(sphere(tag, y)); }

  /// Whether the site holds a live sphere tagged `tag` (at y, when y is given); false when the
  /// call fails.
  bool holds(double tag, std::optional<double> y = std::nullopt) { return read(tag, y).value_or(false); }
  /// Whether the site is seen not to hold it; false when the call fails.
  bool lacks(double tag) { return !read(tag, std::nullopt).value_or(true); }

  /// The size of the force the site renders on its tool now. Unit: N. −1: no state.
  double tool_force() {
    State state;
    if (!client_.poll_state(state, std::chrono::milliseconds(200))) return -1.0;
    return std::sqrt(state.force.x * state.force.x + state.force.y * state.force.y + state.force.z * state.force.z);
  }

 private:
  static ClientConfig config(const ServerProcess& server, const Site& site) {
    ClientConfig config;
    config.server_address = server.address();
    config.client_name = site.name;
    config.heartbeat_period = std::chrono::milliseconds(20);
    config.rpc_timeout = std::chrono::seconds(5);
    config.reconnect = false;  // C is killed: its client ends with it
    return config;
  }
  static SphereSpec sphere(double tag, double y) {
    SphereSpec spec;
    spec.center = {tag, y, 0.06};
    spec.radius = 0.005;
    spec.impedance.stiffness = 40.0;
    spec.across_sites = true;
    return spec;
  }
  /// Whether the site holds it; none when the call fails.
  std::optional<bool> read(double tag, std::optional<double> y) {
    RegisteredScene registered;
    try {
      registered = client_.scene(true);
    } catch (const Error&) {
      return std::nullopt;
    }
    for (const SceneSpec::Object& object : registered.scene.objects) {
      const auto* sphere = std::get_if<SphereSpec>(&object);
      if (sphere == nullptr) continue;
      if (std::abs(sphere->center.x - tag) < 1e-9 && (!y || std::abs(sphere->center.y - *y) < 1e-9)) return true;
    }
    return false;
  }

  Client client_;
};

/// Polls every condition together every 5 ms from now until each has held once or `give_up`
/// has passed since `from`: for each, the seconds from `from` to the first poll it held at, or
/// −1 for one that never did.
std::vector<double> seconds_until(const std::vector<std::function<bool()>>& conditions, Clock::time_point from,
                                  Seconds give_up) {
  std::vector<double> took(conditions.size(), -1.0);
  std::size_t pending = conditions.size();
  while (pending > 0 && Clock::now() - from < give_up) {
    for (std::size_t i = 0; i < conditions.size(); ++i) {
      if (took[i] >= 0.0 || !conditions[i]()) continue;
      took[i] = Seconds(Clock::now() - from).count();
      --pending;
    }
    if (pending > 0) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return took;
}

/// Whether a tool is free of every avatar: its force below kFree at every poll for 50 ms (one
/// poll could catch a contact's force passing zero). `since` is when that began.
class ToolFree {
 public:
  explicit ToolFree(SiteClient& site) : site_(site) {}
  bool operator()() {
    const double force = site_.tool_force();
    const auto now = Clock::now();
    if (force < 0.0 || force >= kFree) {
      since_.reset();
      return false;
    }
    if (!since_) since_ = now;
    return now - *since_ >= std::chrono::milliseconds(50);
  }
  /// Seconds from `from` to the start of the free run (−1: none).
  double since(Clock::time_point from) const { return since_ ? Seconds(*since_ - from).count() : -1.0; }

 private:
  SiteClient& site_;
  std::optional<Clock::time_point> since_;
};

/// Checks each time against `bound` (−1: never), and prints them on one line.
void expect_within(const char* what, const std::vector<std::string>& where, const std::vector<double>& took,
                   Seconds bound) {
  std::string line = std::string("  ") + what + ":";
  for (std::size_t i = 0; i < took.size(); ++i) {
    char text[96];
    if (took[i] < 0.0) std::snprintf(text, sizeof text, "%s never", where[i].c_str());
    else std::snprintf(text, sizeof text, "%s %.3f s", where[i].c_str(), took[i]);
    line += (i == 0 ? " " : ", ") + std::string(text);
    EXPECT_GE(took[i], 0.0) << what << " at " << where[i] << ": not within " << bound.count() << " s";
  }
  std::printf("%s (bound %.1f s)\n", line.c_str(), bound.count());
  std::fflush(stdout);
}

// The tags (x of each sphere) tell the items apart at every site.
constexpr double kSphereA1 = -0.05;
constexpr double kSphereA2 = -0.04;
constexpr double kSphereB1 = -0.03;
constexpr double kSphereC1 = -0.02;
constexpr double kSphereC2 = -0.01;

// The bounds: that each thing happens, not how soon (the times are printed; their figures are
// tests/bench/federation_latency_netns.sh's). Discovery (a site's first contact with the others)
// is unicast SPDP to the peers and its replies; once sites know each other an item crosses the
// bridge in the replicator's period (10 ms) and a reliable write's round trip. A lost site: its
// writer's lease (federation::kItemLease) and the relay's 0.5 s of silence. Each has 5 s more,
// for the polls, the removal ramp (50 ms) and a loaded machine's RPCs.
constexpr Seconds kDiscovery{10.0};
constexpr Seconds kPropagation{5.0};
constexpr Seconds kItemsLost{Seconds(federation::kItemLease).count() + 5.0};
constexpr Seconds kAvatarLost{0.5 + 5.0};

TEST(FederationNetns, ThreeSitesShareItemsLoseAKilledSiteAndTakeItBack) {
  const std::vector<std::string> namespaces = words(std::getenv("HAPTIC_FEDERATION_NAMESPACES"));
  const std::vector<std::string> addresses = words(std::getenv("HAPTIC_FEDERATION_ADDRESSES"));
  if (namespaces.size() != 3 || addresses.size() != 3) GTEST_SKIP() << "runs inside federation_netns.sh's namespaces";
  const std::vector<Site> sites = {{"site-a", namespaces[0], addresses[0], -0.008},
                                   {"site-b", namespaces[1], addresses[1], 0.008},
                                   {"site-c", namespaces[2], addresses[2], 0.0}};
  const Site& c = sites[2];

  // Three sites; each tool held, A's and B's 8 mm either side of C's (16 mm apart: out of each
  // other's avatars).
  const auto starting = Clock::now();
  auto server_a = start_site(sites[0], sites);
  auto server_b = start_site(sites[1], sites);
  auto server_c = start_site(c, sites);
  const auto all_ready = Clock::now();
  std::printf("  three sites started in %.3f s\n", Seconds(all_ready - starting).count());
  SiteClient a(*server_a, sites[0]);
  SiteClient b(*server_b, sites[1]);
  auto site_c = std::make_unique<SiteClient>(*server_c, c);

  // The tool topic has found its peers once A and B feel C's tool (from the moment the three
  // were ready).
  expect_within("C's tool felt (discovery)", {"A", "B"},
                seconds_until({[&] { return a.tool_force() > kTouching; }, [&] { return b.tool_force() > kTouching; }},
                              all_ready, kDiscovery),
                kDiscovery);

  // 1. A sphere made at A: at B and C; then moved; then removed.
  auto made = Clock::now();
  ObjectHandle a1 = a.add(kSphereA1, 0.06);
  expect_within("A's sphere appears (the item topic's first use)", {"B", "C"},
                seconds_until({[&] { return b.holds(kSphereA1, 0.06); }, [&] { return site_c->holds(kSphereA1, 0.06); }},
                              made, kDiscovery),
                kDiscovery);
  made = Clock::now();
  SiteClient::move(a1, kSphereA1, 0.07);
  expect_within("its update arrives", {"B", "C"},
                seconds_until({[&] { return b.holds(kSphereA1, 0.07); }, [&] { return site_c->holds(kSphereA1, 0.07); }},
                              made, kPropagation),
                kPropagation);
  made = Clock::now();
  a1.remove();
  expect_within("its removal arrives", {"B", "C"},
                seconds_until({[&] { return b.lacks(kSphereA1); }, [&] { return site_c->lacks(kSphereA1); }}, made,
                              kPropagation),
                kPropagation);

  // 2. An item from each site, held everywhere; then C is killed.
  made = Clock::now();
  const ObjectHandle a2 = a.add(kSphereA2, 0.06);
  const ObjectHandle b1 = b.add(kSphereB1, 0.06);
  auto c1 = std::make_unique<ObjectHandle>(site_c->add(kSphereC1, 0.06));
  expect_within("one item from each site, at the others",
                {"A has B's", "A has C's", "B has A's", "B has C's", "C has A's", "C has B's"},
                seconds_until({[&] { return a.holds(kSphereB1); }, [&] { return a.holds(kSphereC1); },
                               [&] { return b.holds(kSphereA2); }, [&] { return b.holds(kSphereC1); },
                               [&] { return site_c->holds(kSphereA2); }, [&] { return site_c->holds(kSphereB1); }},
                              made, kPropagation),
                kPropagation);

  std::printf("  force on the tools in C's avatar before the kill: A %.2f N, B %.2f N\n", a.tool_force(),
              b.tool_force());
  const auto killed = Clock::now();
  ASSERT_EQ(::kill(server_c->pid(), SIGKILL), 0);
  EXPECT_EQ(server_c->wait(), 128 + SIGKILL);
  // Both losses polled together, each measured from the kill.
  ToolFree free_a(a), free_b(b);
  std::vector<double> lost = seconds_until(
      {[&] { return a.lacks(kSphereC1); }, [&] { return b.lacks(kSphereC1); }, std::ref(free_a), std::ref(free_b)},
      killed, std::max(kItemsLost, kAvatarLost));
  if (lost[2] >= 0.0) lost[2] = free_a.since(killed);
  if (lost[3] >= 0.0) lost[3] = free_b.since(killed);
  expect_within("C SIGKILLed: its item gone", {"A", "B"}, {lost[0], lost[1]}, kItemsLost);
  expect_within("C SIGKILLed: its tool's avatar gone", {"A", "B"}, {lost[2], lost[3]}, kAvatarLost);
  EXPECT_LE(std::max(lost[0], lost[1]), kItemsLost.count());
  EXPECT_LE(std::max(lost[2], lost[3]), kAvatarLost.count());
  // The live sites' items stay.
  EXPECT_TRUE(a.holds(kSphereB1));
  EXPECT_TRUE(b.holds(kSphereA2));
  c1.reset();
  site_c.reset();

  // 3. C again, under the same name: A's and B's items reach it (late join), and its tool is felt
  // again; its new item reaches them.
  const auto restarting = Clock::now();
  server_c = start_site(c, sites);
  site_c = std::make_unique<SiteClient>(*server_c, c);
  const std::vector<double> joined = seconds_until(
      {[&] { return site_c->holds(kSphereA2); }, [&] { return site_c->holds(kSphereB1); },
       [&] { return a.tool_force() > kTouching; }, [&] { return b.tool_force() > kTouching; }},
      restarting, kDiscovery);
  expect_within("C restarted: the live items there (late join)", {"A's", "B's"}, {joined[0], joined[1]}, kDiscovery);
  expect_within("C restarted: its tool felt again", {"A", "B"}, {joined[2], joined[3]}, kDiscovery);
  made = Clock::now();
  const ObjectHandle c2 = site_c->add(kSphereC2, 0.06);
  expect_within("C's new item arrives", {"A", "B"},
                seconds_until({[&] { return a.holds(kSphereC2); }, [&] { return b.holds(kSphereC2); }}, made,
                              kPropagation),
                kPropagation);
  // The killed C's item is brought back by no one, nor is A's removed one.
  EXPECT_TRUE(a.lacks(kSphereC1));
  EXPECT_TRUE(b.lacks(kSphereC1));
  EXPECT_TRUE(site_c->lacks(kSphereC1));
  EXPECT_TRUE(site_c->lacks(kSphereA1));
  std::printf("  whole run %.1f s\n", Seconds(Clock::now() - starting).count());
}

}  // namespace
}  // namespace haptic::test
