// What a site logs about the other sites (docs/federation.md, "What a site logs"), over real
// Cyclone DDS on loopback: another site's arrival, its going quiet and its return, one line each,
// on the relay's own clock (step's time); and Cyclone's own log routed to hapticd's with
// identical messages written once and counted. Bounded: every wait has a deadline.
#include <gtest/gtest.h>

#include <unistd.h>

#include <chrono>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <dds/dds.h>

#include "federation/dds_log.hpp"
#include "federation/dds_participant.hpp"
#include "federation/sample_relay.hpp"
#include "federation/tool_topic.hpp"
#include "support/loopback_dds.hpp"

namespace haptic::federation {
namespace {

using std::chrono::milliseconds;
using std::chrono::seconds;
using test::eventually;
using test::loopback_domain;

TEST(SiteLog, AnotherSitesArrivalDepartureAndReturnAreOneLineEach) {
  const DomainOptions domain = loopback_domain();
  std::vector<std::string> lines;
  runtime::SampleRing ring;  // this site's port: nothing ticks, nothing is published
  runtime::LatestValue<runtime::RemoteToolSet> mailbox;
  RelayOptions options;
  options.site = "bench-a";
  options.domain = domain;
  options.silence_s = 0.5;
  options.log = [&](const std::string& line) { lines.push_back(line); };
  SampleRelay relay(options, {RelayPort{&ring, 0, &mailbox}});

  Participant b(domain);
  ToolPublisher publisher(b, "bench-b");
  ASSERT_TRUE(eventually([&] { return publisher.matched_readers() > 0; })) << "no reader matched in 10 s";
  ToolState tool;
  tool.site = "bench-b";
  tool.R_WT = {1.0, 0.0, 0.0, 0.0};
  // The relay's clock is step's argument: every sample of one phase arrives at one instant.
  const auto t0 = std::chrono::steady_clock::time_point{} + std::chrono::hours(1);
  const auto publish_until_heard = [&](std::chrono::steady_clock::time_point now, std::size_t count) {
    return eventually([&] {
      ++tool.tick;
      EXPECT_TRUE(publisher.publish(tool)) << publisher.error();
      relay.step(now);
      return lines.size() >= count;
    });
  };
  ASSERT_TRUE(publish_until_heard(t0, 1)) << "bench-b's tool never arrived";
  // Samples still under way are taken at t0 too.
  std::this_thread::sleep_for(milliseconds(100));
  for (int i = 0; i < 10; ++i) relay.step(t0);
  ASSERT_EQ(lines, std::vector<std::string>{"federation: site \"bench-b\" heard for the first time"});

  relay.step(t0 + milliseconds(500));  // not yet: silent for 0.5 s, not more
  EXPECT_EQ(lines.size(), 1u);
  for (int i = 0; i < 10; ++i) relay.step(t0 + seconds(2));
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[1], "federation: site \"bench-b\" not heard for 0.5 s: its tools and mass copies are dropped");

  ASSERT_TRUE(publish_until_heard(t0 + seconds(60), 3)) << "bench-b's tool never came back";
  for (int i = 0; i < 10; ++i) relay.step(t0 + seconds(60));
  ASSERT_EQ(lines.size(), 3u);
  EXPECT_EQ(lines[2], "federation: site \"bench-b\" heard again after 60.0 s of silence");
}

TEST(SiteLog, ASiteThatComesAndGoesIsLoggedOnceAWindowEachWayAndCounted) {
  const DomainOptions domain = loopback_domain();
  std::vector<std::string> lines;
  runtime::SampleRing ring;
  runtime::LatestValue<runtime::RemoteToolSet> mailbox;
  RelayOptions options;
  options.site = "bench-a";
  options.domain = domain;
  options.log = [&](const std::string& line) { lines.push_back(line); };
  SampleRelay relay(options, {RelayPort{&ring, 0, &mailbox}});
  Participant b(domain);
  ToolPublisher publisher(b, "bench-b");
  ASSERT_TRUE(eventually([&] { return publisher.matched_readers() > 0; }));
  ToolState tool;
  tool.site = "bench-b";
  tool.R_WT = {1.0, 0.0, 0.0, 0.0};
  const auto t0 = std::chrono::steady_clock::time_point{} + std::chrono::hours(1);
  // Five times within 10 s: heard at t0, t0 + 2 s, ..., quiet from 1 s after each.
  for (int k = 0; k < 5; ++k) {
    const auto t = t0 + seconds(2 * k);
    ASSERT_TRUE(eventually([&] {
      ++tool.tick;
      EXPECT_TRUE(publisher.publish(tool)) << publisher.error();
      relay.step(t);
      return mailbox.load().tools[0].key != 0;
    })) << "bench-b's tool did not arrive, time " << k;
    std::this_thread::sleep_for(milliseconds(50));
    relay.step(t);  // samples still under way
    relay.step(t + seconds(1));
    ASSERT_EQ(mailbox.load().tools[0].key, 0u) << "bench-b still in the mailbox after 1 s of silence";
  }
  EXPECT_EQ(lines, (std::vector<std::string>{
                       "federation: site \"bench-b\" heard for the first time",
                       "federation: site \"bench-b\" not heard for 0.5 s: its tools and mass copies are dropped",
                   }));
  relay.step(t0 + seconds(20));
  ASSERT_EQ(lines.size(), 4u);
  EXPECT_EQ(lines[2], "federation: site \"bench-b\" heard again after 2.0 s of silence (and 3 more in 10 s)");
  EXPECT_EQ(lines[3],
            "federation: site \"bench-b\" not heard for 0.5 s: its tools and mass copies are dropped (and 3 more "
            "in 10 s)");
}

TEST(DdsLog, IdenticalCycloneMessagesAreWrittenOnceThenCountedAndOthersStillGetTheirLine) {
  std::mutex mutex;
  std::vector<std::pair<DdsLogLevel, std::string>> lines;
  route_dds_log([&](DdsLogLevel level, const std::string& line) {
    std::lock_guard lock(mutex);
    lines.emplace_back(level, line);
  });
  for (int i = 0; i < 50; ++i) {
    dds_log(DDS_LC_ERROR, __FILE__, __LINE__, DDS_FUNCTION, "Begin handshake reply failed: Certificate not valid\n");
  }
  dds_log(DDS_LC_WARNING, __FILE__, __LINE__, DDS_FUNCTION, "another message\n");
  flush_dds_log(std::chrono::steady_clock::now() + seconds(11));
  route_dds_log({});
  std::lock_guard lock(mutex);
  ASSERT_EQ(lines.size(), 3u);
  EXPECT_EQ(lines[0].first, DdsLogLevel::kError);
  EXPECT_EQ(lines[0].second, "dds: Begin handshake reply failed: Certificate not valid");
  EXPECT_EQ(lines[1].first, DdsLogLevel::kWarning);
  EXPECT_EQ(lines[1].second, "dds: another message");
  EXPECT_EQ(lines[2].first, DdsLogLevel::kError) << "the summary at its messages' level";
  EXPECT_EQ(lines[2].second, "dds: Begin handshake reply failed: Certificate not valid (and 48 more in 10 s)");
}

}  // namespace
}  // namespace haptic::federation
