// The server's scene as the shared scene's replicator sees it (app::FederatedScene): which of this
// site's items go to the other sites, and how another site's items are checked, applied under an
// owner of their own, updated and removed, over a real scene store.
#include <gtest/gtest.h>

#include "app/federated_scene.hpp"
#include "net/session_registry.hpp"

namespace haptic::app {
namespace {

struct Rig {
  runtime::SceneExchange exchange{std::make_unique<const engine::CompiledScene>()};
  net::SceneStore store{exchange, [] { return std::int64_t{1}; }, 50, 8};
  FederatedScene scene{store, schema::SceneLimits{}};

  std::vector<net::SceneEntry> live() const { return store.read(0, true); }
};

v1::Object sphere(double radius, double stiffness, bool across_sites) {
  v1::Object object;
  object.mutable_sphere()->set_radius(radius);
  object.mutable_impedance()->set_stiffness(stiffness);
  object.set_across_sites(across_sites);
  return object;
}

federation::SharedItemState remote(const std::string& site, std::uint64_t item, const v1::Object& object) {
  return {site, item, 1, federation::SharedItemKind::kObject, object.SerializeAsString()};
}

/// Adds `object` to the store as session `session`'s.
std::uint64_t create_local(Rig& rig, std::uint64_t session, const v1::Object& object) {
  engine::ObjectSpec spec;
  EXPECT_EQ(schema::to_object_spec(object, "object", schema::SceneLimits{}, spec), "");
  std::uint64_t id = 0;
  EXPECT_TRUE(rig.store.create(session, net::ItemKind::kObject, spec, id, {std::make_shared<const v1::Object>(object), {}}).ok());
  return id;
}

TEST(FederatedScene, OnlyThisSitesItemsMarkedAcrossSitesAreShared) {
  Rig rig;
  const std::uint64_t shared = create_local(rig, 5, sphere(0.02, 300, true));
  create_local(rig, 5, sphere(0.03, 300, false));
  ASSERT_EQ(rig.scene.put_remote(remote("lab-b", 1, sphere(0.01, 200, true))), "");
  const std::vector<federation::LocalSharedItem> items = rig.scene.shared_items();
  ASSERT_EQ(items.size(), 1u);  // not the private one, and not lab-b's (never echoed back)
  EXPECT_EQ(items[0].id, shared);
  v1::Object described;
  ASSERT_TRUE(described.ParseFromString(rig.scene.describe(shared)));
  EXPECT_DOUBLE_EQ(described.sphere().radius(), 0.02);
  EXPECT_EQ(rig.scene.describe(999), "");
}

TEST(FederatedScene, AnotherSitesItemIsAppliedUnderItsSitesOwnerUpdatedAndRemoved) {
  Rig rig;
  ASSERT_EQ(rig.scene.put_remote(remote("lab-b", 4, sphere(0.01, 200, true))), "");
  ASSERT_EQ(rig.scene.put_remote(remote("lab-c", 4, sphere(0.01, 200, true))), "");
  std::vector<net::SceneEntry> entries = rig.live();
  ASSERT_EQ(entries.size(), 2u);
  EXPECT_NE(entries[0].session_id & net::kRemoteSiteOwnerBit, 0u);
  EXPECT_NE(entries[0].session_id, entries[1].session_id);  // one owner per site
  EXPECT_EQ(entries[0].session_id, rig.scene.owner_of("lab-b"));

  federation::SharedItemState update = remote("lab-b", 4, sphere(0.05, 200, true));
  update.version = 2;
  ASSERT_EQ(rig.scene.put_remote(update), "");
  entries = rig.live();
  ASSERT_EQ(entries.size(), 2u);  // updated in place: same item, new version
  EXPECT_DOUBLE_EQ(entries[0].source.object->sphere().radius(), 0.05);

  rig.scene.remove_remote("lab-b", 4);
  entries = rig.live();
  ASSERT_EQ(entries.size(), 1u);  // lab-b's ramps out; lab-c's stays
  EXPECT_EQ(entries[0].session_id, rig.scene.owner_of("lab-c"));
  rig.scene.remove_remote("lab-b", 4);  // again: nothing
  rig.scene.remove_remote("lab-z", 1);  // never seen: nothing
  EXPECT_EQ(rig.live().size(), 1u);
}

TEST(FederatedScene, AnItemThisSitesChecksRefuseIsNamedAndNothingIsApplied) {
  Rig rig;
  EXPECT_EQ(rig.scene.put_remote(remote("lab-b", 1, sphere(0.01, -5, true))),
            "object.impedance.stiffness: must be finite and in [0, 1e+06], got -5");
  EXPECT_EQ(rig.scene.put_remote({"lab-b", 2, 1, federation::SharedItemKind::kObject, "\xff\xff not protobuf"}),
            "spec: not a haptic.v1.Object");
  EXPECT_TRUE(rig.live().empty());
  // A refused update leaves the version already applied.
  ASSERT_EQ(rig.scene.put_remote(remote("lab-b", 3, sphere(0.01, 200, true))), "");
  EXPECT_NE(rig.scene.put_remote(remote("lab-b", 3, sphere(-1.0, 200, true))), "");
  ASSERT_EQ(rig.live().size(), 1u);
  EXPECT_DOUBLE_EQ(rig.live()[0].source.object->sphere().radius(), 0.01);
}

TEST(FederatedScene, AnotherSitesSharedObjectIsNoLocalSessionsToChange) {
  Rig rig;
  v1::Object object = sphere(0.01, 200, true);
  object.set_shared(true);
  ASSERT_EQ(rig.scene.put_remote(remote("lab-b", 1, object)), "");
  const std::uint64_t id = rig.live()[0].id;
  engine::ObjectSpec spec;
  ASSERT_EQ(schema::to_object_spec(object, "object", schema::SceneLimits{}, spec), "");
  const grpc::Status status = rig.store.update(5, net::ItemKind::kObject, id, spec);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::PERMISSION_DENIED) << status.error_message();
}

}  // namespace
}  // namespace haptic::app
