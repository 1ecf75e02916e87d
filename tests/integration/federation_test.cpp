// hapticd as a federation site (docs/federation.md) in lockstep, its device port's tool on ROS 2
// topics over real Cyclone DDS on loopback, read as a ROS 2 subscription's middleware reads them:
// after a Step, the newest pose is the stepped tool's, stamped with its server time. Bounded waits.
#include <gtest/gtest.h>

#include <haptic/haptic.hpp>

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <string>
#include <thread>

#include "federation/dds_participant.hpp"
#include "federation/ros2_topics.hpp"
#include "haptic/dds/ros2.h"
#include "integration/raw_client.hpp"
#include "integration/sdk_harness.hpp"
#include "integration/server_process.hpp"
#include "support/dds_domain.hpp"

namespace haptic {
namespace {

using test::config_for;
using test::step_and_get;

/// Takes the poses waiting at `reader` (up to 4), calling `see` with each and its stamp (s).
template <typename See>
void take_poses(dds_entity_t reader, See see) {
  void* samples[4] = {};
  dds_sample_info_t infos[4];
  const dds_return_t n = dds_take(reader, samples, infos, 4, 4);
  for (dds_return_t i = 0; i < n; ++i) {
    if (!infos[i].valid_data) continue;
    const auto& pose = *static_cast<const geometry_msgs_msg_dds__PoseStamped_*>(samples[i]);
    see(pose, pose.header.stamp.sec + 1e-9 * pose.header.stamp.nanosec);
  }
  if (n > 0) dds_return_loan(reader, samples, n);
}

TEST(Federation, ASitesToolIsOnRos2TopicsAsItsNewestTick) {
  const std::uint32_t domain = test::unique_dds_domain();
  test::ServerProcess server(R"({"time_mode": "LOCKSTEP", "udp_address": "127.0.0.1", "status_period_s": 0,
      "real_time": {"use_fifo": false},
      "federation": {"site": "bench-a", "domain_id": )" + std::to_string(domain) + R"(, "peers": ["127.0.0.1"],
                     "ros2": {"rate_hz": 1000, "stamp_clock": "SERVER_TIME"}}})");
  federation::DomainOptions options;
  options.domain_id = domain;
  options.peers = {"127.0.0.1"};
  federation::Participant node(options);
  const dds_entity_t topic = dds_create_topic(node.handle(), &geometry_msgs_msg_dds__PoseStamped__desc,
                                              "rt/hapticd/bench_a/port0/pose", nullptr, nullptr);
  ASSERT_GT(topic, 0) << federation::dds_error(topic);
  const dds_entity_t reader = dds_create_reader(node.handle(), topic, nullptr, nullptr);
  ASSERT_GT(reader, 0) << federation::dds_error(reader);

  Client client(config_for(server));
  client.set_operator(OperatorInput::push({0.0, 0.0, -0.5}));
  const State stepped = step_and_get(client, 100);
  // The loop stands still between Steps: the relay's newest sample is tick 100's, published once
  // (best effort, so the reader may come late to it: step one tick more per try, bounded).
  bool matched = false;
  State last = stepped;
  for (int attempt = 0; attempt < 200 && !matched; ++attempt) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    take_poses(reader, [&](const geometry_msgs_msg_dds__PoseStamped_& pose, double stamp) {
      if (std::abs(stamp - last.server_time) < 1e-9) {
        EXPECT_EQ(pose.pose.position.z, last.position.z);
        EXPECT_EQ(pose.pose.position.x, last.position.x);
        EXPECT_EQ(pose.pose.orientation.w, 1.0);  // a 3-DOF device: identity
        EXPECT_STREQ(pose.header.frame_id, "hapticd_world");
        matched = true;
      }
    });
    if (!matched && attempt % 10 == 9) last = step_and_get(client, 1);  // discovery may have been late
  }
  EXPECT_TRUE(matched) << "no pose of the stepped tick within 4 s";
  EXPECT_LT(last.position.z, 0.02);  // the hand pushed the tool down
}

// As a ROS 2 node with the default QoS profile (reliable, keep last 10) subscribes: it matches
// hapticd's publishers, and header.stamp is this host's wall clock (the default stamp_clock), as
// tf2, rviz and `ros2 topic delay` expect, not the seconds since the server started.
TEST(Federation, ARos2NodeWithTheDefaultProfileGetsPosesStampedWithTheWallClock) {
  const std::uint32_t domain = test::unique_dds_domain();
  test::ServerProcess server(R"({"time_mode": "LOCKSTEP", "udp_address": "127.0.0.1", "status_period_s": 0,
      "real_time": {"use_fifo": false},
      "federation": {"site": "bench-r", "domain_id": )" + std::to_string(domain) + R"(, "peers": ["127.0.0.1"],
                     "ros2": {"rate_hz": 1000}}})");
  federation::DomainOptions options;
  options.domain_id = domain;
  options.peers = {"127.0.0.1"};
  federation::Participant node(options);
  const dds_entity_t topic = dds_create_topic(node.handle(), &geometry_msgs_msg_dds__PoseStamped__desc,
                                              "rt/hapticd/bench_r/port0/pose", nullptr, nullptr);
  ASSERT_GT(topic, 0) << federation::dds_error(topic);
  dds_qos_t* ros_default = dds_create_qos();  // rclcpp's default: reliable, keep last 10, volatile
  dds_qset_reliability(ros_default, DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
  dds_qset_history(ros_default, DDS_HISTORY_KEEP_LAST, 10);
  dds_qset_durability(ros_default, DDS_DURABILITY_VOLATILE);
  const dds_entity_t reader = dds_create_reader(node.handle(), topic, ros_default, nullptr);
  dds_delete_qos(ros_default);
  ASSERT_GT(reader, 0) << federation::dds_error(reader);

  Client client(config_for(server));
  bool received = false;
  for (int attempt = 0; attempt < 200 && !received; ++attempt) {
    step_and_get(client, 1);  // a new tick for the relay to publish each try
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    take_poses(reader, [&](const geometry_msgs_msg_dds__PoseStamped_&, double stamp) {
      const double now = std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
      // The wall clock (not seconds since start): within a minute of now, however loaded the host.
      EXPECT_NEAR(stamp, now, 60.0);
      received = true;
    });
  }
  EXPECT_TRUE(received) << "a reliable reader got no pose within 4 s: the writers do not match ROS 2's default profile";
}

// A ROS 2 node's wrench on the tool of a lockstep hapticd (federation.ros2.wrench_input): a writer
// of geometry_msgs/msg/WrenchStamped as rmw_cyclonedds makes one publishes a constant 3 N along +x
// on rt/hapticd/bench_w/port0/wrench_command while the hand draws the tool 3 cm along −x, into the
// force. Stepped one tick at a time: the tool feels it, never more than 3 N and never giving the
// hand more energy than the hand put in (the layer); a NaN wrench never reaches it; once the node
// stops, the force ramps out within stale_s and the ramp, never cut by the guard. Bounded waits.
TEST(Federation, ARos2NodesWrenchIsFeltOnTheSteppedToolThroughThePassivityLayer) {
  const std::uint32_t domain = test::unique_dds_domain();
  test::ServerProcess server(R"({"time_mode": "LOCKSTEP", "udp_address": "127.0.0.1", "status_period_s": 0,
      "real_time": {"use_fifo": false},
      "federation": {"site": "bench-w", "domain_id": )" + std::to_string(domain) + R"(, "peers": ["127.0.0.1"],
                     "ros2": {"rate_hz": 100, "wrench_input": {}}}})");
  federation::DomainOptions options;
  options.domain_id = domain;
  options.peers = {"127.0.0.1"};
  federation::Participant node(options);
  const dds_entity_t topic = dds_create_topic(node.handle(), &geometry_msgs_msg_dds__WrenchStamped__desc,
                                              "rt/hapticd/bench_w/port0/wrench_command", nullptr, nullptr);
  ASSERT_GT(topic, 0) << federation::dds_error(topic);
  const dds_entity_t writer = dds_create_writer(node.handle(), topic, nullptr, nullptr);  // reliable, as ROS 2's default
  ASSERT_GT(writer, 0) << federation::dds_error(writer);
  const auto publish = [&](double fx) {
    geometry_msgs_msg_dds__WrenchStamped_ m{};
    m.header.frame_id = const_cast<char*>("hapticd_world");
    m.wrench.force = {fx, 0.0, 0.0};
    ASSERT_EQ(dds_write(writer, &m), DDS_RETCODE_OK);
  };
  dds_publication_matched_status_t matched{};
  for (int i = 0; i < 500 && matched.current_count == 0; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    dds_get_publication_matched_status(writer, &matched);
  }
  ASSERT_EQ(matched.current_count, 1u) << "hapticd's wrench reader not matched in 5 s";

  Client client(config_for(server));
  const State start = step_and_get(client, 1);
  OperatorInput hand = OperatorInput::follow_line(start.position, {start.position.x - 0.03, start.position.y,
                                                   start.position.z}, 1.5, OperatorInput::Grip::kCustom);
  hand.stiffness = 200.0;
  hand.damping = 2.0;
  client.set_operator(hand);
  State previous = start;
  double channel = 0.0, lowest = 0.0, strongest = 0.0;
  bool felt = false;
  std::uint32_t faults = 0;
  const auto tick = [&] {
    const State s = step_and_get(client, 1);
    channel -= previous.force.x * (s.position.x - previous.position.x) + previous.force.y * (s.position.y - previous.position.y) +
               previous.force.z * (s.position.z - previous.position.z);
    lowest = std::min(lowest, channel);
    strongest = std::max(strongest, std::sqrt(s.force.x * s.force.x + s.force.y * s.force.y + s.force.z * s.force.z));
    felt = felt || s.force.x > 1.0;
    if ((s.flags & (kForceFault | kForceSaturated)) != 0 || !std::isfinite(s.force.x)) ++faults;
    previous = s;
    return s;
  };
  // The relay takes what arrives at its own pace: publish, then wait (bounded) for the first to be
  // felt before counting in ticks.
  for (int attempt = 0; attempt < 300 && !felt; ++attempt) {
    publish(3.0);
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    tick();
  }
  ASSERT_TRUE(felt) << "the node's wrench was not felt within 300 ticks";
  for (int i = 0; i < 1000; ++i) {
    if (i % 10 == 0) publish(3.0);
    tick();
  }
  std::printf("a ROS 2 node's 3 N on the stepped tool: up to %.3f N felt; the hand put in %.4f J net, channel energy "
              "never below %.3g J\n", strongest, channel, lowest);
  EXPECT_LE(strongest, 3.0 + 1e-9);
  EXPECT_GT(lowest, -1e-6);
  EXPECT_EQ(faults, 0u);
  // A NaN from the node: refused by the relay, never at the device.
  for (int i = 0; i < 20; ++i) {
    publish(std::numeric_limits<double>::quiet_NaN());
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
    EXPECT_TRUE(std::isfinite(tick().force.x));
  }
  EXPECT_EQ(faults, 0u);
  // The node stops: stale after 0.2 s, ramped out over the 50 ms removal ramp (the last wrench
  // may have reached the loop a few ticks late: 400 ticks leave room).
  for (int i = 0; i < 400; ++i) tick();
  EXPECT_LT(std::abs(previous.force.x), 1e-6) << "the stale wrench did not ramp out";
  EXPECT_EQ(faults, 0u) << "the ramp-out was cut by the guard or faulted";
  EXPECT_GT(lowest, -1e-6);
}

/// A real-time site on loopback: its point mass starts at x0 (m), in DDS domain `domain`.
std::string site_config(const std::string& site, std::uint32_t domain, double x0) {
  return R"({"udp_address": "127.0.0.1", "grpc_address": "127.0.0.1:0", "udp_port": 0, "status_period_s": 0,
             "real_time": {"use_fifo": false},
             "simulated_point_mass": {"mass": 0.05, "damping": 0.1, "initial_position": {"x": )" +
         std::to_string(x0) + R"(, "y": 0, "z": 0}},
             "federation": {"site": ")" + site + R"(", "domain_id": )" + std::to_string(domain) +
         R"(, "peers": ["127.0.0.1"]}})";
}

/// Polls until `site` holds `count` couplings or 10 s have passed (discovery over DDS takes its
/// time on a loaded machine); whether it does. One session of its own for all the polls (a
/// session a poll, never closed, would run into the server's max_sessions).
bool holds_couplings(const test::ServerProcess& site, int count) {
  test::RawClient raw(site.address());
  v1::OpenSessionResponse session;
  if (!raw.open(session, "couplings").ok()) return false;
  const auto held = [&] { return raw.stats(session).federation().couplings_size(); };
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (held() < count && std::chrono::steady_clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return held() >= count;
}

/// Two hands' targets pass through each other: A's from −2 cm to +1 cm, B's from +2 cm to −1 cm,
/// over 1.5 s (200 N/m, 2 N·s/m). Returns A's position after `seconds` of real time.
double push_past_each_other(Client& a, Client& b, double seconds) {
  OperatorInput hand_a = OperatorInput::follow_line({-0.02, 0, 0}, {0.01, 0, 0}, 1.5, OperatorInput::Grip::kCustom);
  hand_a.stiffness = 200.0;
  hand_a.damping = 2.0;
  OperatorInput hand_b = OperatorInput::follow_line({0.02, 0, 0}, {-0.01, 0, 0}, 1.5, OperatorInput::Grip::kCustom);
  hand_b.stiffness = 200.0;
  hand_b.damping = 2.0;
  a.set_operator(hand_a);
  b.set_operator(hand_b);
  std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
  State s;
  EXPECT_TRUE(a.poll_state(s, std::chrono::seconds(5)));
  return s.position.x;
}

// Two real-time sites on loopback DDS: each renders the other's tool as a sphere (its avatar,
// through the coupling's passivity layer); the hands' targets pass through each other, the tools
// do not (behaviour, not timing: where A rests, not when).
TEST(Federation, TwoSitesToolsTouchEachOtherOverDds) {
  const std::uint32_t domain = test::unique_dds_domain();
  test::ServerProcess site_a(site_config("bench-a", domain, -0.02));
  auto site_b = std::make_unique<test::ServerProcess>(site_config("bench-b", domain, 0.02));
  Client a(config_for(site_a));
  auto b = std::make_unique<Client>(config_for(*site_b));
  // The hands move once each site holds the other's tool: hands that met before discovery would
  // have passed each other already.
  ASSERT_TRUE(holds_couplings(site_a, 1)) << "A did not hear B's tool in 10 s";
  ASSERT_TRUE(holds_couplings(*site_b, 1)) << "B did not hear A's tool in 10 s";
  const double x = push_past_each_other(a, *b, 4.0);
  std::printf("two sites over DDS: tool A rests at x = %.4f m (its hand's target: +0.0100 m)\n", x);
  State s;
  ASSERT_TRUE(a.poll_state(s, std::chrono::seconds(5)));
  // With no other tool, A's hand would take it to +1 cm; blocked by B's avatar (10 mm, 500 N/m)
  // and B pushing back, it rests short of the middle.
  EXPECT_LT(x, -0.002) << "tool A passed into B's avatar";
  EXPECT_GT(x, -0.02);
  EXPECT_EQ(s.flags & kForceFault, 0u);
  {  // A's stats hold its coupling with B's tool, and its books balance (read a tick apart: 1 mJ)
    test::RawClient raw(site_a.address());
    v1::OpenSessionResponse session;
    ASSERT_TRUE(raw.open(session, "stats").ok());
    const v1::FederationStats federation = raw.stats(session).federation();
    ASSERT_EQ(federation.couplings_size(), 1);
    const v1::CouplingStats& coupling = federation.couplings(0);
    EXPECT_EQ(coupling.kind(), v1::CouplingStats::TOOL);
    EXPECT_EQ(coupling.port(), 0u);
    EXPECT_GT(coupling.injected_j(), 0.0);  // A's hand pushed into B's avatar
    EXPECT_NEAR(coupling.reservoir_j(),
                coupling.injected_j() - coupling.given_j() + coupling.received_j() - coupling.sent_j(), 1e-3);
  }
  // Site B stops: once it has been quiet for 0.5 s its avatar leaves A's scene, and A's hand
  // takes the tool on to its target.
  b.reset();
  site_b.reset();
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  do {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    ASSERT_TRUE(a.poll_state(s, std::chrono::seconds(5)));
  } while (std::abs(s.position.x - 0.01) > 1e-3 && std::chrono::steady_clock::now() < give_up);
  EXPECT_NEAR(s.position.x, 0.01, 1e-3) << "B's avatar stayed after B stopped";
}

// Two real-time sites on loopback DDS share one virtual mass: a client at A makes it across_sites,
// B gets its copy through the shared scene, A's hand pushes A's copy, and B's copy follows through
// the coupling (the mass topic and both sites' network passivity layers); once the hand holds
// still, the copies rest together (behaviour, not timing: where they rest, not when).
TEST(Federation, TwoSitesShareOneMassThatOneSitesHandPushes) {
  const std::uint32_t domain = test::unique_dds_domain();
  test::ServerProcess site_a(site_config("mass-a", domain, -0.08));
  test::ServerProcess site_b(site_config("mass-b", domain, 0.08));
  Client a(config_for(site_a));
  Client b(config_for(site_b));
  SphereSpec sphere;
  sphere.radius = 0.02;
  sphere.impedance.stiffness = 200.0;
  sphere.dynamics = {0.5, 1.0};
  sphere.across_sites = true;
  const ObjectHandle mass = a.add_sphere(sphere);  // held: the object lives as long as its handle
  const auto copies = [](Client& client) { return client.object_states(); };
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (copies(b).empty() && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_EQ(copies(b).size(), 1u) << "B did not get the shared mass in 10 s; B holds " << b.scene(true).object_ids.size() << " objects, A " << a.scene(true).object_ids.size() << " and " << copies(a).size() << " masses";
  // A's hand takes its tool from -8 cm to +1 cm over 2 s: the sphere (radius 2 cm) goes ahead of it.
  OperatorInput hand = OperatorInput::follow_line({-0.08, 0, 0}, {0.01, 0, 0}, 2.0, OperatorInput::Grip::kCustom);
  hand.stiffness = 200.0;
  hand.damping = 2.0;
  a.set_operator(hand);
  // The hand's line takes 2 s; then the copies come to rest together (polled, at most 15 s more).
  std::this_thread::sleep_for(std::chrono::seconds(2));
  const auto rest_by = std::chrono::steady_clock::now() + std::chrono::seconds(15);
  ObjectState at_a = copies(a).at(0), at_b = copies(b).at(0);
  while (!(at_a.position.x > 0.01 && std::abs(at_b.position.x - at_a.position.x) < 1e-3 &&
           std::abs(at_b.velocity.x) < 1e-3) &&
         std::chrono::steady_clock::now() < rest_by) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    at_a = copies(a).at(0);
    at_b = copies(b).at(0);
  }
  std::printf("shared mass over DDS: A's copy at x = %.5f m, B's at x = %.5f m (%.1e m apart)\n", at_a.position.x, at_b.position.x, std::abs(at_a.position.x - at_b.position.x));
  EXPECT_GT(at_a.position.x, 0.01) << "A's hand did not push the mass";
  EXPECT_NEAR(at_b.position.x, at_a.position.x, 1e-3) << "B's copy did not follow A's";
  EXPECT_LT(std::abs(at_b.velocity.x), 1e-3);
  // The coupling's books in A's stats: A's copy put energy into the coupling (A's hand pushed
  // it) and the layer holds what its books say it must (read at slightly different ticks: 1 mJ).
  test::RawClient raw(site_a.address());
  v1::OpenSessionResponse session;
  ASSERT_TRUE(raw.open(session, "stats").ok());
  const v1::FederationStats federation = raw.stats(session).federation();
  EXPECT_GT(federation.samples_published(), 1000u);
  EXPECT_EQ(federation.items_published(), 1u);
  int masses = 0;
  for (const v1::CouplingStats& coupling : federation.couplings()) {
    if (coupling.kind() != v1::CouplingStats::MASS) continue;
    ++masses;
    std::printf("A's mass coupling: injected %.4f J, given %.4f J, sent %.4f J, received %.4f J, held %.4f J\n",
                coupling.injected_j(), coupling.given_j(), coupling.sent_j(), coupling.received_j(), coupling.reservoir_j());
    EXPECT_GT(coupling.injected_j(), 0.0);
    EXPECT_NEAR(coupling.reservoir_j(),
                coupling.injected_j() - coupling.given_j() + coupling.received_j() - coupling.sent_j(), 1e-3);
  }
  EXPECT_EQ(masses, 1);
  State s;
  ASSERT_TRUE(a.poll_state(s, std::chrono::seconds(5)));
  EXPECT_EQ(s.flags & kForceFault, 0u);
}

}  // namespace
}  // namespace haptic
