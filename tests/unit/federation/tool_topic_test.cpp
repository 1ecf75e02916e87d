// The federation's tool topic over real Cyclone DDS on loopback: two participants of one domain
// (as two sites would be, here in one process), the options' checks and the configuration they
// make. Bounded: every wait has a deadline.
#include <gtest/gtest.h>

#include <unistd.h>

#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include "federation/dds_participant.hpp"
#include "federation/tool_topic.hpp"
#include "support/loopback_dds.hpp"

namespace haptic::federation {
namespace {

using test::eventually;
using test::loopback_domain;

TEST(ToolTopic, ASitesToolReachesAnotherParticipant) {
  const DomainOptions options = loopback_domain();
  Participant site_a(options);
  Participant site_b(options);
  ToolPublisher publisher(site_a, "bench-a");
  ToolSubscriber subscriber(site_b);
  ASSERT_TRUE(eventually([&] { return publisher.matched_readers() > 0; })) << "no reader matched in 10 s";
  ToolState tool;
  tool.site = "bench-a";
  tool.port = 1;
  tool.time_ns = 42'000'000;
  tool.p_WT = {0.01, -0.02, 0.03};
  tool.v_WT = {0.1, 0.0, -0.1};
  tool.F_T_W = {0.0, 0.0, 1.5};
  tool.R_WT = {0.0, 0.0, 0.0, 1.0};
  tool.buttons = 2;
  tool.energy = {{"bench-b", 0, 0.125}, {"bench-c", 1, 2.5e-3}};
  std::vector<ToolState> received;
  // Best effort: publish until one arrives (bounded), each tick a new sample as the loop would.
  ASSERT_TRUE(eventually([&] {
    ++tool.tick;
    EXPECT_TRUE(publisher.publish(tool)) << publisher.error();
    subscriber.take(received);
    return !received.empty();
  })) << "no sample in 10 s";
  const ToolState& got = received.back();
  EXPECT_EQ(got.site, "bench-a");
  EXPECT_EQ(got.port, 1u);
  EXPECT_GE(got.tick, 1u);
  EXPECT_EQ(got.time_ns, 42'000'000);
  EXPECT_EQ(got.p_WT, tool.p_WT);
  EXPECT_EQ(got.v_WT, tool.v_WT);
  EXPECT_EQ(got.F_T_W, tool.F_T_W);
  EXPECT_EQ(got.R_WT.z, 1.0);
  EXPECT_EQ(got.buttons, 2u);
  EXPECT_EQ(got.writer_site, "bench-a");  // the partition it came through
  ASSERT_EQ(got.energy.size(), 2u);  // what its couplings sent, per other tool
  EXPECT_EQ(got.energy[0].site, "bench-b");
  EXPECT_EQ(got.energy[0].sent, 0.125);
  EXPECT_EQ(got.energy[1].port, 1u);
  EXPECT_EQ(got.energy[1].sent, 2.5e-3);
}

// A site's own samples never come back to it: its reader, in the participant its writer is in,
// does not match that writer (Cyclone's ignore-local: from_other_sites), while another site's
// reader, made after it, matches and takes every sample.
TEST(ToolTopic, ASitesReaderNeverTakesItsOwnSamples) {
  const DomainOptions options = loopback_domain();
  Participant site_a(options);
  Participant site_b(options);
  ToolPublisher publisher(site_a, "bench-a");
  ToolSubscriber own(site_a);
  ToolSubscriber other(site_b);
  ToolState tool;
  tool.site = "bench-a";
  std::vector<ToolState> mine, theirs;
  ASSERT_TRUE(eventually([&] {
    ++tool.tick;
    EXPECT_TRUE(publisher.publish(tool)) << publisher.error();
    own.take(mine);
    other.take(theirs);
    return theirs.size() >= 10;
  })) << "the other site took " << theirs.size() << " samples in 10 s";
  own.take(mine);
  EXPECT_TRUE(mine.empty()) << mine.size() << " of its own samples came back";
  EXPECT_EQ(own.matched_writers(), 0u);
  EXPECT_EQ(publisher.matched_readers(), 1u);  // the other site's reader alone
}

TEST(ToolTopic, ASampleNamingAnotherSiteArrivesWithTheSiteItsWriterSpeaksFor) {
  const DomainOptions options = loopback_domain();
  Participant site_a(options);
  Participant site_c(options);
  ToolPublisher forger(site_c, "bench-c");
  ToolSubscriber subscriber(site_a);
  ASSERT_TRUE(eventually([&] { return forger.matched_readers() > 0; })) << "no reader matched in 10 s";
  ToolState tool;
  tool.site = "bench-b";  // not its own
  std::vector<ToolState> received;
  ASSERT_TRUE(eventually([&] {
    ++tool.tick;
    EXPECT_TRUE(forger.publish(tool)) << forger.error();
    subscriber.take(received);
    return !received.empty();
  })) << "no sample in 10 s";
  EXPECT_EQ(received.back().site, "bench-b");
  EXPECT_EQ(received.back().writer_site, "bench-c");  // which the relay refuses (forging_peer_test)
}

TEST(ToolTopic, ASiteNameLongerThanTheTypeAllowsIsRefusedNamingIt) {
  Participant site(loopback_domain());
  ToolPublisher publisher(site, "bench-x");
  ToolState tool;
  tool.site = std::string(65, 'x');
  EXPECT_FALSE(publisher.publish(tool));
  EXPECT_EQ(publisher.error(), "site: at most 64 characters, got 65");
}

TEST(DomainOptions, BadOptionsAreNamedAndNothingCanBeInjectedIntoTheConfiguration) {
  DomainOptions options;
  EXPECT_EQ(validate(options), "");
  options.domain_id = 300;
  EXPECT_EQ(validate(options), "domain_id: must be 0 to 232, got 300");
  options.domain_id = 0;
  options.interface = "lo\"/><Tracing";
  EXPECT_NE(validate(options).find("interface: must be an interface name or address"), std::string::npos);
  options.interface = "eth0";
  options.peers = {"10.0.0.2", "host name"};
  EXPECT_EQ(validate(options), "peers[1]: must be a host name or address, got \"host name\"");
  try {
    Participant refused(options);
    ADD_FAILURE() << "a bad peer was accepted";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("federation.peers[1]"), std::string::npos) << error.what();
  }
  options.peers = {"10.0.0.2"};
  const std::string xml = cyclone_config(options);
  EXPECT_NE(xml.find("<NetworkInterface name=\"eth0\"/>"), std::string::npos) << xml;
  EXPECT_NE(xml.find("<Peer address=\"10.0.0.2\"/>"), std::string::npos) << xml;
  EXPECT_NE(xml.find("<AllowMulticast>false</AllowMulticast>"), std::string::npos) << xml;
  options.interface = "192.168.1.5";
  EXPECT_NE(cyclone_config(options).find("<NetworkInterface address=\"192.168.1.5\"/>"), std::string::npos);
}

}  // namespace
}  // namespace haptic::federation
