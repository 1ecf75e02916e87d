// The shared scene over real Cyclone DDS on loopback: two sites' replicators (two participants of
// one domain in this process) over in-memory scenes. An item marked across_sites at one site
// appears at the other, its updates and its removal follow, a site that joins late gets what is
// there, a site that goes takes its items with it, and an item the other site's checks refuse is
// reported, not applied. Bounded: every wait has a deadline.
#include <gtest/gtest.h>

#include <unistd.h>

#include <chrono>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "federation/item_replicator.hpp"
#include "federation/item_topic.hpp"
#include "support/loopback_dds.hpp"

namespace haptic::federation {
namespace {

using test::loopback_domain;

/// A site's scene in memory: its own items (id → description, version key) and the other sites'
/// (site/item → description). put_remote refuses a description that starts with "bad".
class MemoryScene : public ReplicatedScene {
 public:
  void create(std::uint64_t id, const std::string& spec) {
    std::lock_guard lock(mutex_);
    own_[id] = {spec, ++next_key_};
    ++generation_;
  }
  void remove(std::uint64_t id) {
    std::lock_guard lock(mutex_);
    own_.erase(id);
    ++generation_;
  }
  std::map<std::string, std::string> remote() const {
    std::lock_guard lock(mutex_);
    return remote_;
  }

  std::uint64_t generation() const override {
    std::lock_guard lock(mutex_);
    return generation_;
  }
  std::vector<LocalSharedItem> shared_items() const override {
    std::lock_guard lock(mutex_);
    std::vector<LocalSharedItem> items;
    for (const auto& [id, item] : own_) items.push_back({id, SharedItemKind::kObject, item.second});
    return items;
  }
  std::string describe(std::uint64_t id) const override {
    std::lock_guard lock(mutex_);
    const auto found = own_.find(id);
    return found == own_.end() ? std::string() : found->second.first;
  }
  std::string put_remote(const SharedItemState& item) override {
    if (item.spec.rfind("bad", 0) == 0) return "object.impedance.stiffness: must be finite and >= 0, got -1";
    std::lock_guard lock(mutex_);
    remote_[item.site + "/" + std::to_string(item.item)] = item.spec;
    return {};
  }
  void remove_remote(const std::string& site, std::uint64_t item) override {
    std::lock_guard lock(mutex_);
    remote_.erase(site + "/" + std::to_string(item));
  }

 private:
  mutable std::mutex mutex_;
  std::map<std::uint64_t, std::pair<std::string, std::uint64_t>> own_;
  std::map<std::string, std::string> remote_;
  std::uint64_t generation_ = 0;
  std::uint64_t next_key_ = 0;
};

std::string site_name(const char* which) { return std::string(which) + "-" + std::to_string(getpid()); }

/// Polls the replicators until `condition` holds (at most 10 s).
template <class Condition>
bool eventually(std::vector<ItemReplicator*> replicators, Condition&& condition) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (std::chrono::steady_clock::now() < deadline) {
    for (ItemReplicator* replicator : replicators) replicator->poll();
    if (condition()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return condition();
}

ReplicatorOptions options_for(const std::string& site, std::vector<std::string>* log = nullptr) {
  ReplicatorOptions options;
  options.site = site;
  options.domain = loopback_domain();
  if (log != nullptr) options.log = [log](const std::string& line) { log->push_back(line); };
  return options;
}

TEST(ItemReplicator, AnItemAppearsAtTheOtherSiteItsUpdateFollowsAndItsRemoval) {
  const std::string a = site_name("lab-a"), b = site_name("lab-b");
  MemoryScene scene_a, scene_b;
  ItemReplicator site_a(options_for(a), scene_a);
  ItemReplicator site_b(options_for(b), scene_b);
  scene_a.create(7, "sphere r=0.02");
  const std::string key = a + "/7";
  ASSERT_TRUE(eventually({&site_a, &site_b}, [&] { return scene_b.remote().count(key) == 1; }))
      << "the item did not reach the other site in 10 s";
  EXPECT_EQ(scene_b.remote().at(key), "sphere r=0.02");
  EXPECT_TRUE(scene_a.remote().empty());  // a site's own items never come back to it

  scene_a.create(7, "sphere r=0.03");  // an update: same id, new version
  ASSERT_TRUE(eventually({&site_a, &site_b}, [&] { return scene_b.remote().at(key) == "sphere r=0.03"; }));
  EXPECT_EQ(site_a.published(), 2u);

  scene_a.remove(7);
  ASSERT_TRUE(eventually({&site_a, &site_b}, [&] { return scene_b.remote().empty(); }))
      << "the removal did not reach the other site in 10 s";
}

TEST(ItemReplicator, ASiteThatJoinsLateGetsWhatIsThere) {
  const std::string a = site_name("early"), b = site_name("late");
  MemoryScene scene_a, scene_b;
  ItemReplicator site_a(options_for(a), scene_a);
  scene_a.create(1, "box");
  scene_a.create(2, "field");
  site_a.poll();  // published before anyone listens
  ASSERT_EQ(site_a.published(), 2u);
  ItemReplicator site_b(options_for(b), scene_b);
  ASSERT_TRUE(eventually({&site_a, &site_b}, [&] { return scene_b.remote().size() == 2; }))
      << "the late site got " << scene_b.remote().size() << " of 2 items in 10 s";
  EXPECT_EQ(scene_b.remote().at(a + "/1"), "box");
}

TEST(ItemReplicator, ASiteThatGoesTakesItsItemsWithIt) {
  const std::string a = site_name("leaving"), b = site_name("staying");
  MemoryScene scene_a, scene_b;
  // The first participant in a process owns the domain (dds_participant.hpp): the staying site.
  ItemReplicator site_b(options_for(b), scene_b);
  auto site_a = std::make_unique<ItemReplicator>(options_for(a), scene_a);
  scene_a.create(3, "capsule");
  ASSERT_TRUE(eventually({site_a.get(), &site_b}, [&] { return scene_b.remote().size() == 1; }));
  site_a.reset();
  ASSERT_TRUE(eventually({&site_b}, [&] { return scene_b.remote().empty(); }))
      << "the gone site's item stayed for 10 s";
}

TEST(ItemReplicator, AnItemTheOtherSiteRefusesIsReportedNotApplied) {
  const std::string a = site_name("sender"), b = site_name("checker");
  std::vector<std::string> log;
  MemoryScene scene_a, scene_b;
  ItemReplicator site_a(options_for(a), scene_a);
  ItemReplicator site_b(options_for(b, &log), scene_b);
  scene_a.create(4, "bad stiffness");
  scene_a.create(5, "good");
  ASSERT_TRUE(eventually({&site_a, &site_b}, [&] { return site_b.refused() == 1 && scene_b.remote().size() == 1; }));
  EXPECT_EQ(scene_b.remote().count(a + "/5"), 1u);
  ASSERT_FALSE(log.empty());
  EXPECT_NE(log.front().find("site " + a + " item 4 (version 1) refused: object.impedance.stiffness"), std::string::npos)
      << log.front();
}

TEST(ItemReplicator, AnItemOrRemovalNamingAnotherSiteIsRefusedAndLoggedAndChangesNothing) {
  const std::string a = site_name("lab-a"), b = site_name("lab-b"), c = site_name("lab-c");
  std::vector<std::string> log;
  MemoryScene scene_a, scene_b;
  ItemReplicator site_a(options_for(a, &log), scene_a);
  ItemReplicator site_b(options_for(b), scene_b);
  scene_b.create(4, "b's wall");
  ASSERT_TRUE(eventually({&site_a, &site_b}, [&] { return scene_a.remote().count(b + "/4") == 1; }));
  // A third participant writes under b's name from its own partition: an update, a new item, and
  // a removal of b's wall.
  Participant forger(loopback_domain());
  ItemPublisher publisher(forger, c);
  ASSERT_TRUE(eventually({&site_a}, [&] { return publisher.matched_readers() > 0; }));
  ASSERT_TRUE(publisher.put(SharedItemState{b, 4, 9, SharedItemKind::kObject, "a forged wall"})) << publisher.error();
  ASSERT_TRUE(publisher.put(SharedItemState{b, 5, 1, SharedItemKind::kObject, "a forged box"})) << publisher.error();
  ASSERT_TRUE(publisher.remove(b, 4)) << publisher.error();
  // Keep last one per (site, item): the wall's forged update may be overtaken by its forged
  // removal before site a takes either, so two refusals at least.
  ASSERT_TRUE(eventually({&site_a, &site_b}, [&] { return site_a.refused() >= 2; }))
      << "refused " << site_a.refused();
  EXPECT_EQ(scene_a.remote().at(b + "/4"), "b's wall");
  EXPECT_EQ(scene_a.remote().count(b + "/5"), 0u);
  bool logged = false;
  for (const std::string& line : log) {
    logged = logged || line.find("refused: its writer speaks for site \"" + c + "\"") != std::string::npos;
  }
  EXPECT_TRUE(logged);
}

}  // namespace
}  // namespace haptic::federation
