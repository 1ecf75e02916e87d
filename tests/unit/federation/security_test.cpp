// DDS Security for the federation over real Cyclone DDS on loopback: files from
// scripts/federation-certs (made into a temporary folder when the test starts), sites as domains
// of their own in this process (local_domain_id), all in one DDS domain on the network. Bounded:
// every wait has a deadline.
#include <gtest/gtest.h>

#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "federation/dds_log.hpp"
#include "federation/dds_participant.hpp"
#include "federation/item_replicator.hpp"
#include "federation/item_topic.hpp"
#include "federation/sample_relay.hpp"
#include "federation/tool_topic.hpp"
#include "haptic/dds/federation.h"
#include "support/dds_domain.hpp"

namespace haptic::federation {
namespace {

namespace fs = std::filesystem;

/// Runs scripts/federation-certs once per test process: CA "lab" with members bench-a and
/// bench-c and observer bench-b; CA "other" with member bench-a (the same name, another CA).
class Certs {
 public:
  static const Certs& get() {
    static const Certs certs;
    return certs;
  }
  ~Certs() {
    std::error_code ignored;
    if (!root_.empty()) fs::remove_all(root_, ignored);
  }

  const std::string& error() const { return error_; }

  /// The files of `site` from the CA in folder `ca`.
  SecurityFiles site(const std::string& ca, const std::string& site) const {
    const std::string dir = root_ + "/" + ca;
    SecurityFiles files;
    files.identity_ca = dir + "/ca.pem";
    files.identity_certificate = dir + "/" + site + "/identity.pem";
    files.identity_private_key = dir + "/" + site + "/identity.key";
    files.permissions_ca = dir + "/ca.pem";
    files.governance = dir + "/governance.p7s";
    files.permissions = dir + "/" + site + "/permissions.p7s";
    return files;
  }

 private:
  Certs() {
    std::string pattern = (fs::temp_directory_path() / "hapticd-dds-security-XXXXXX").string();
    if (mkdtemp(pattern.data()) == nullptr) {
      error_ = "mkdtemp failed";
      return;
    }
    root_ = pattern;
    const std::string script = std::string(HAPTIC_SOURCE_DIR) + "/scripts/federation-certs";
    for (const std::string& args : {" --out " + root_ + "/lab bench-a bench-b:observer bench-c",
                                   " --out " + root_ + "/other bench-a"}) {
      const std::string command = script + args + " > " + root_ + "/log 2>&1";
      const int status = std::system(command.c_str());
      if (status != 0) {
        std::ifstream log(root_ + "/log");
        error_ = command + " failed:\n" + std::string(std::istreambuf_iterator<char>(log), {});
        return;
      }
    }
  }

  std::string root_;
  std::string error_;
};

/// A DDS domain of this test process's own (ctest runs tests in parallel), on loopback; each site
/// a Cyclone domain of its own in it (local_domain_id `local`).
DomainOptions site_domain(std::uint32_t local, std::optional<SecurityFiles> security) {
  DomainOptions options;
  options.domain_id = test::process_dds_domain();
  options.interface = "lo";
  options.peers = {"127.0.0.1"};
  options.local_domain_id = local;
  options.security = std::move(security);
  return options;
}

template <class Condition>
bool eventually(Condition&& condition, std::chrono::milliseconds limit) {
  const auto deadline = std::chrono::steady_clock::now() + limit;
  while (std::chrono::steady_clock::now() < deadline) {
    if (condition()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return condition();
}

ToolState a_tool() {
  ToolState tool;
  tool.site = "bench-a";
  tool.port = 0;
  tool.p_WT = {0.01, -0.02, 0.03};
  tool.R_WT = {1.0, 0.0, 0.0, 0.0};
  return tool;
}

/// Skips the test without Cyclone's plugins; fails it when the files could not be made.
#define REQUIRE_SECURITY()                                                                          \
  do {                                                                                              \
    if (!security_plugins_available()) {                                                            \
      GTEST_SKIP() << "Cyclone's DDS Security plugins are not installed (looked in \""              \
                   << security_plugin_dir() << "\"; Debian: libddsc0debian)";                       \
    }                                                                                               \
    ASSERT_EQ(Certs::get().error(), "");                                                            \
  } while (false)

/// Site A publishes until site B has a sample (the handshake takes a few hundred ms), then goes on
/// for `after` while `outsider` (if any) must receive nothing.
void exchange(Participant& a, Participant& b, Participant* outsider, std::chrono::milliseconds after) {
  ToolPublisher publisher(a, "bench-a");
  ToolSubscriber subscriber(b);
  std::optional<ToolSubscriber> outside;
  if (outsider != nullptr) outside.emplace(*outsider);
  ToolState tool = a_tool();
  std::vector<ToolState> received;
  std::vector<ToolState> overheard;
  ASSERT_TRUE(eventually(
      [&] {
        ++tool.tick;
        EXPECT_TRUE(publisher.publish(tool)) << publisher.error();
        subscriber.take(received);
        return !received.empty();
      },
      std::chrono::seconds(20)))
      << "no sample between two sites of one CA in 20 s";
  EXPECT_EQ(received.back().site, "bench-a");
  EXPECT_EQ(received.back().writer_site, "bench-a");
  EXPECT_EQ(received.back().p_WT, tool.p_WT);
  if (!outside) return;
  // The outsider has had the whole handshake time and `after` more (the channel demonstrably
  // carrying samples all along): it must have nothing.
  eventually(
      [&] {
        ++tool.tick;
        EXPECT_TRUE(publisher.publish(tool)) << publisher.error();
        outside->take(overheard);
        return !overheard.empty();
      },
      after);
  received.clear();
  subscriber.take(received);
  EXPECT_FALSE(received.empty()) << "the members stopped hearing each other";
  EXPECT_TRUE(overheard.empty()) << "a site outside the federation read " << overheard.size() << " samples";
}

TEST(FederationSecurity, TwoSitesWithIdentitiesFromOneCaExchangeATool) {
  REQUIRE_SECURITY();
  const Certs& certs = Certs::get();
  Participant a(site_domain(1, certs.site("lab", "bench-a")));
  Participant b(site_domain(2, certs.site("lab", "bench-c")));
  exchange(a, b, nullptr, {});
}

TEST(FederationSecurity, ASiteWithoutSecurityReadsNothing) {
  REQUIRE_SECURITY();
  const Certs& certs = Certs::get();
  Participant a(site_domain(1, certs.site("lab", "bench-a")));
  Participant b(site_domain(2, certs.site("lab", "bench-c")));
  Participant plain(site_domain(3, std::nullopt));
  exchange(a, b, &plain, std::chrono::seconds(2));
}

TEST(FederationSecurity, ASiteWithACertificateFromAnotherCaReadsNothing) {
  REQUIRE_SECURITY();
  const Certs& certs = Certs::get();
  Participant a(site_domain(1, certs.site("lab", "bench-a")));
  Participant b(site_domain(2, certs.site("lab", "bench-c")));
  // Its files are consistent among themselves (same name, its own CA's governance): only trust
  // in the lab's CA is missing.
  Participant stranger(site_domain(3, certs.site("other", "bench-a")));
  exchange(a, b, &stranger, std::chrono::seconds(2));
}

// A rogue host (an identity from another CA) retries its handshake with each site about once a
// second, and each site's Cyclone says so each time; routed to hapticd's log, each message is
// written once and the rest counted when its window ends.
TEST(FederationSecurity, ARogueHostsFailedHandshakesAreLoggedOnceThenCounted) {
  REQUIRE_SECURITY();
  const Certs& certs = Certs::get();
  std::mutex mutex;
  std::vector<std::string> lines;
  route_dds_log([&](DdsLogLevel, const std::string& line) {
    std::lock_guard lock(mutex);
    lines.push_back(line);
  });
  {
    Participant a(site_domain(1, certs.site("lab", "bench-a")));
    Participant b(site_domain(2, certs.site("lab", "bench-c")));
    Participant stranger(site_domain(3, certs.site("other", "bench-a")));
    exchange(a, b, &stranger, std::chrono::seconds(3));
  }
  flush_dds_log(std::chrono::steady_clock::now() + std::chrono::seconds(11));
  route_dds_log({});
  std::lock_guard lock(mutex);
  std::vector<std::string> refused;
  std::vector<std::string> summaries;
  for (const std::string& line : lines) {
    if (line.find("handshake") == std::string::npos) continue;
    (line.find(" more in 10 s)") == std::string::npos ? refused : summaries).push_back(line);
  }
  ASSERT_EQ(refused.size(), 1u) << "each failed handshake's message once, not " << refused.size() << " times";
  EXPECT_EQ(refused[0].rfind("dds: ", 0), 0u) << refused[0];
  EXPECT_NE(refused[0].find("subject: /O=hapticd/CN=bench-a"), std::string::npos) << refused[0];
  ASSERT_EQ(summaries.size(), 1u) << "the retries counted in one line";
  EXPECT_EQ(summaries[0].rfind(refused[0] + " (and ", 0), 0u) << summaries[0];
}

/// A ToolSample topic named `name` (access control looks at the name, not the type).
dds_entity_t topic_on(const Participant& site, const char* name) {
  return dds_create_topic(site.handle(), &haptic_federation_ToolSample_desc, name, nullptr, nullptr);
}

/// A writer (or reader) on `topic` in `partition` ("": the default partition); Cyclone's entity
/// or its refusal.
dds_entity_t endpoint_in(const Participant& site, dds_entity_t topic, const char* partition, bool writer = true) {
  dds_qos_t* qos = dds_create_qos();
  if (partition[0] != '\0') dds_qset_partition1(qos, partition);
  const dds_entity_t entity = writer ? dds_create_writer(site.handle(), topic, qos, nullptr)
                                     : dds_create_reader(site.handle(), topic, qos, nullptr);
  dds_delete_qos(qos);
  return entity;
}

TEST(FederationSecurity, AnObserverPublishesNothingAMemberActsOnAndAMemberOnlyUnderItsOwnName) {
  REQUIRE_SECURITY();
  const Certs& certs = Certs::get();
  Participant observer(site_domain(1, certs.site("lab", "bench-b")));
  for (const char* name : {"haptic_federation_items", "haptic_federation_masses", "haptic_federation_tool"}) {
    const dds_entity_t topic = topic_on(observer, name);
    ASSERT_GT(topic, 0) << name << ": an observer may make the topic (it subscribes to it)";
    for (const char* partition : {"bench-b", "bench-a", ""}) {
      EXPECT_EQ(endpoint_in(observer, topic, partition), DDS_RETCODE_NOT_ALLOWED_BY_SECURITY)
          << name << " in partition \"" << partition << "\"";
    }
    EXPECT_GT(endpoint_in(observer, topic, "*", false), 0) << name;
  }
  const dds_entity_t pose = topic_on(observer, "rt/hapticd/bench_b/port0/pose");
  ASSERT_GT(pose, 0);
  EXPECT_GT(endpoint_in(observer, pose, ""), 0) << "its own ROS 2 topics are open to it";
  const dds_entity_t wrench = topic_on(observer, "rt/hapticd/bench_a/port0/wrench_command");
  ASSERT_GT(wrench, 0);
  EXPECT_EQ(endpoint_in(observer, wrench, ""), DDS_RETCODE_NOT_ALLOWED_BY_SECURITY)
      << "an observer may not command a member's tool";
  EXPECT_GT(endpoint_in(observer, wrench, "", false), 0);
  EXPECT_LT(topic_on(observer, "some_other_topic"), 0) << "what is not granted is denied";

  Participant member(site_domain(2, certs.site("lab", "bench-a")));
  for (const char* name : {"haptic_federation_items", "haptic_federation_masses", "haptic_federation_tool"}) {
    const dds_entity_t topic = topic_on(member, name);
    ASSERT_GT(topic, 0) << name;
    EXPECT_GT(endpoint_in(member, topic, "bench-a"), 0) << name << ": under its own name";
    for (const char* partition : {"bench-c", "bench-*", "*", ""}) {
      EXPECT_EQ(endpoint_in(member, topic, partition), DDS_RETCODE_NOT_ALLOWED_BY_SECURITY)
          << name << " in partition \"" << partition << "\": another site's name, a pattern, or none";
    }
    EXPECT_GT(endpoint_in(member, topic, "*", false), 0) << name;
  }
}

TEST(FederationSecurity, AMemberSpeakingForAnotherSiteIsRefusedByTheRelayAndLogged) {
  REQUIRE_SECURITY();
  const Certs& certs = Certs::get();
  std::vector<std::string> log;
  runtime::SampleRing ring;
  runtime::LatestValue<runtime::RemoteToolSet> mailbox;
  RelayOptions options;
  options.site = "bench-a";
  options.domain = site_domain(1, certs.site("lab", "bench-a"));
  options.log = [&log](const std::string& line) { log.push_back(line); };
  SampleRelay relay(options, {RelayPort{&ring, 0, &mailbox}});
  Participant forger(site_domain(2, certs.site("lab", "bench-c")));
  ToolPublisher publisher(forger, "bench-c");  // its own partition: the only one it may use
  ToolState tool = a_tool();
  tool.site = "bench-b";  // another member's name
  ASSERT_TRUE(eventually(
      [&] {
        ++tool.tick;
        EXPECT_TRUE(publisher.publish(tool)) << publisher.error();
        relay.step(std::chrono::steady_clock::now());
        return relay.samples_refused() > 0;
      },
      std::chrono::seconds(20)))
      << "nothing arrived in 20 s";
  for (const runtime::RemoteTool& remote : mailbox.load().tools) EXPECT_EQ(remote.key, 0u) << "a forged tool was taken";
  bool logged = false;
  for (const std::string& line : log) {
    logged = logged || line.find("naming site \"bench-b\" refused: its writer speaks for site \"bench-c\"") !=
                           std::string::npos;
  }
  EXPECT_TRUE(logged);
}

TEST(FederationSecurity, AnObserverReadsAMembersSharedItemButCannotPublishOne) {
  REQUIRE_SECURITY();
  const Certs& certs = Certs::get();
  Participant member(site_domain(1, certs.site("lab", "bench-a")));
  Participant observer(site_domain(2, certs.site("lab", "bench-b")));
  EXPECT_THROW(ItemPublisher refused(observer, "bench-b"), std::runtime_error);
  ItemPublisher publisher(member, "bench-a");
  ItemSubscriber subscriber(observer);
  SharedItemState item;
  item.site = "bench-a";
  item.item = 7;
  item.version = 1;
  item.spec = "a wall";
  ASSERT_TRUE(publisher.put(item)) << publisher.error();  // reliable, transient-local: sent once
  std::vector<SharedItemEvent> events;
  ASSERT_TRUE(eventually([&] { return subscriber.take(events) > 0 || !events.empty(); },
                         std::chrono::seconds(20)))
      << "the observer did not get the member's item in 20 s";
  EXPECT_EQ(events.front().what, SharedItemEvent::What::kPut);
  EXPECT_EQ(events.front().state.site, "bench-a");
  EXPECT_EQ(events.front().state.spec, "a wall");
  EXPECT_EQ(events.front().writer_site, "bench-a");
}

/// A shared scene in memory, for the replicators below: its own items and what it received.
class TinyScene : public ReplicatedScene {
 public:
  std::uint64_t generation() const override { return own_.size(); }
  std::vector<LocalSharedItem> shared_items() const override {
    std::vector<LocalSharedItem> items;
    for (const auto& [id, spec] : own_) items.push_back({id, SharedItemKind::kObject, id});
    return items;
  }
  std::string describe(std::uint64_t id) const override { return own_.count(id) ? own_.at(id) : std::string(); }
  std::string put_remote(const SharedItemState& item) override {
    std::lock_guard lock(mutex_);
    received_.push_back(item.site + ":" + item.spec);
    return {};
  }
  void remove_remote(const std::string&, std::uint64_t) override {}
  std::vector<std::string> received() {
    std::lock_guard lock(mutex_);
    return received_;
  }
  std::map<std::uint64_t, std::string> own_;

 private:
  std::mutex mutex_;
  std::vector<std::string> received_;
};

TEST(FederationSecurity, AnObserversReplicatorReceivesTheSharedSceneAndSaysWhyItSharesNothing) {
  REQUIRE_SECURITY();
  const Certs& certs = Certs::get();
  Participant member(site_domain(1, certs.site("lab", "bench-a")));
  Participant observer(site_domain(2, certs.site("lab", "bench-b")));
  TinyScene at_member, at_observer;
  at_member.own_[7] = "a wall";
  at_observer.own_[9] = "a box";
  std::vector<std::string> log;
  ReplicatorOptions member_options, observer_options;
  member_options.site = "bench-a";
  observer_options.site = "bench-b";
  observer_options.log = [&log](const std::string& line) { log.push_back(line); };
  ItemReplicator from_member(member_options, at_member, member);
  ItemReplicator from_observer(observer_options, at_observer, observer);  // made: receiving only
  ASSERT_FALSE(log.empty());
  EXPECT_NE(log.front().find("this site shares no items"), std::string::npos) << log.front();
  EXPECT_NE(log.front().find("Not Allowed By Security"), std::string::npos) << log.front();
  ASSERT_TRUE(eventually(
      [&] {
        from_member.poll();
        from_observer.poll();
        return !at_observer.received().empty();
      },
      std::chrono::seconds(20)))
      << "the observer did not get the member's item in 20 s";
  EXPECT_EQ(at_observer.received().front(), "bench-a:a wall");
  EXPECT_EQ(from_observer.published(), 0u);
  EXPECT_TRUE(at_member.received().empty());  // nothing came from the observer
  EXPECT_NE(log.back().find("item 9 not shared"), std::string::npos) << log.back();
}

TEST(FederationSecurity, AnObserversRelayCouplesToSharedMassesWithoutPublishingItsCopies) {
  REQUIRE_SECURITY();
  const Certs& certs = Certs::get();
  runtime::LatestValue<runtime::LocalMassTable> local;
  runtime::LatestValue<runtime::RemoteMassTable> remote;
  RelayOptions options;
  options.site = "bench-b";
  options.domain = site_domain(3, certs.site("lab", "bench-b"));
  SampleRelay observer(options, {}, RelayMasses{&local, &remote});  // made, not refused
  EXPECT_NE(observer.masses_refused().find("haptic_federation_masses"), std::string::npos) << observer.masses_refused();
  EXPECT_NE(observer.tools_refused().find("haptic_federation_tool"), std::string::npos) << observer.tools_refused();
  options.site = "bench-a";
  options.domain = site_domain(4, certs.site("lab", "bench-a"));
  SampleRelay member(options, {}, RelayMasses{&local, &remote});
  EXPECT_EQ(member.masses_refused(), "");
  EXPECT_EQ(member.tools_refused(), "");
}

TEST(FederationSecurity, PermissionsOfAnotherSiteAreRefusedWhenTheParticipantIsMade) {
  REQUIRE_SECURITY();
  const Certs& certs = Certs::get();
  SecurityFiles files = certs.site("lab", "bench-a");
  files.permissions = certs.site("lab", "bench-c").permissions;  // grants CN=bench-c, not bench-a
  try {
    Participant refused(site_domain(1, files));
    ADD_FAILURE() << "a site with another site's permissions was made";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("DDS Security refused this site's files"), std::string::npos)
        << error.what();
  }
}

TEST(DomainOptions, SecurityFilesAreCheckedAndNamedAndGoIntoTheConfigurationAsFileUris) {
  DomainOptions options;
  const std::string missing = "/nonexistent/hapticd/gov.p7s";
  SecurityFiles files;
  const std::string here = (fs::path(HAPTIC_SOURCE_DIR) / "scripts" / "federation-certs").string();
  files.identity_ca = files.identity_certificate = files.identity_private_key = here;
  files.permissions_ca = files.permissions = here;
  files.governance = missing;
  options.security = files;
  EXPECT_EQ(validate(options), "security.governance: cannot read " + missing);
  options.security->governance = HAPTIC_SOURCE_DIR;  // a folder
  EXPECT_EQ(validate(options), std::string("security.governance: cannot read ") + HAPTIC_SOURCE_DIR);
  options.security->governance = here;
  EXPECT_EQ(validate(options), "");
  options.security->permissions = "";
  EXPECT_EQ(validate(options), "security.permissions: required with security (a file's absolute path)");
  options.security->permissions = "relative/permissions.p7s";
  EXPECT_NE(validate(options).find("security.permissions: must be an absolute path"), std::string::npos);
  options.security->identity_ca = "/x/ca.pem</IdentityCA><Tracing>";
  EXPECT_EQ(validate(options),
            "security.identity_ca: must be an absolute path of letters, digits and / . _ - +, got "
            "\"/x/ca.pem</IdentityCA><Tracing>\"");
  try {
    Participant refused(options);
    ADD_FAILURE() << "a bad security file was accepted";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("federation.security.identity_ca"), std::string::npos) << error.what();
  }

  options.security = SecurityFiles{"/s/ca.pem", "/s/a/identity.pem", "/s/a/identity.key",
                                   "/s/ca.pem", "/s/governance.p7s", "/s/a/permissions.p7s"};
  const std::string xml = cyclone_config(options);
  for (const char* part : {"<IdentityCA>file:/s/ca.pem</IdentityCA>",
                           "<IdentityCertificate>file:/s/a/identity.pem</IdentityCertificate>",
                           "<PrivateKey>file:/s/a/identity.key</PrivateKey>",
                           "<PermissionsCA>file:/s/ca.pem</PermissionsCA>",
                           "<Governance>file:/s/governance.p7s</Governance>",
                           "<Permissions>file:/s/a/permissions.p7s</Permissions>",
                           "initFunction=\"init_authentication\"", "initFunction=\"init_access_control\"",
                           "initFunction=\"init_crypto\""}) {
    EXPECT_NE(xml.find(part), std::string::npos) << part << " not in " << xml;
  }
  if (!security_plugin_dir().empty()) {
    EXPECT_NE(xml.find("<Library path=\"" + security_plugin_dir() + "/libdds_security_auth.so\""), std::string::npos)
        << xml;
  }
  EXPECT_EQ(cyclone_config(DomainOptions{}).find("<Security>"), std::string::npos) << "none without security";
}

TEST(DomainOptions, ALocalDomainIdPutsTheDomainOnTheNetworkAsItsExternalId) {
  DomainOptions options;
  options.domain_id = 7;
  EXPECT_EQ(cyclone_config(options).find("ExternalDomainId"), std::string::npos);
  options.local_domain_id = 3;
  EXPECT_NE(cyclone_config(options).find("<Discovery><ExternalDomainId>7</ExternalDomainId></Discovery>"),
            std::string::npos)
      << cyclone_config(options);
  options.peers = {"127.0.0.1"};
  EXPECT_NE(cyclone_config(options).find("</Peers><ExternalDomainId>7</ExternalDomainId></Discovery>"),
            std::string::npos)
      << cyclone_config(options);
}

}  // namespace
}  // namespace haptic::federation
