// The shared scene store: ownership, limits, atomic replacement, fade-out and compaction.
#include <gtest/gtest.h>

#include "net/scene_store.hpp"

namespace haptic::net {
namespace {

engine::ObjectSpec wall(double z) {
  engine::ObjectSpec spec;
  spec.p_WO = {0.0, 0.0, z};
  spec.stiffness = 1000.0;
  spec.shape = engine::HalfSpaceSpec{{0.0, 0.0, 1.0}};
  return spec;
}

/// A flat mesh of `triangles` triangles (a strip of quads) at height z.
engine::ObjectSpec mesh(std::size_t triangles, double z) {
  auto model = std::make_shared<engine::MeshModel>();
  for (std::size_t i = 0; i <= triangles / 2; ++i) {
    const double x = 0.001 * static_cast<double>(i);
    model->mesh.vertices_O.push_back({x, 0.0, z});
    model->mesh.vertices_O.push_back({x, 0.01, z});
  }
  for (std::uint32_t t = 0; t < triangles; ++t) {
    const std::uint32_t base = 2 * (t / 2);
    model->mesh.triangles.push_back(t % 2 == 0 ? std::array<std::uint32_t, 3>{base, base + 2, base + 3}
                                               : std::array<std::uint32_t, 3>{base, base + 3, base + 1});
  }
  model->bvh = engine::MeshBvh::build(model->mesh);
  engine::ObjectSpec spec;
  spec.stiffness = 1000.0;
  spec.shape = engine::MeshShapeSpec{model};
  return spec;
}

struct StoreRig {
  runtime::SceneExchange exchange{std::make_unique<const engine::CompiledScene>()};
  std::int64_t next_tick = 1;
  SceneStore store{exchange, [this] { return next_tick; }, 50, 3};

  const engine::CompiledScene& scene() { return exchange.adopt(); }
};

TEST(SceneStore, CreateUpdateDeleteAreSeenByTheLoop) {
  StoreRig rig;
  std::uint64_t id = 0;
  ASSERT_TRUE(rig.store.create(7, ItemKind::kObject, wall(0.0), id).ok());
  ASSERT_EQ(rig.scene().half_spaces.size(), 1u);
  EXPECT_EQ(rig.scene().half_spaces[0].ramp.appear_tick, 1);  // ramps in from the next tick
  rig.next_tick = 20;
  ASSERT_TRUE(rig.store.update(7, ItemKind::kObject, id, wall(0.01)).ok());
  // The new version fades in from tick 20 while the old one fades out against it.
  ASSERT_EQ(rig.scene().half_spaces.size(), 2u);
  EXPECT_DOUBLE_EQ(rig.scene().half_spaces[0].point_W.z, 0.01);
  EXPECT_EQ(rig.scene().half_spaces[0].ramp.appear_tick, 20);
  EXPECT_EQ(rig.scene().half_spaces[1].point_W.z, 0.0);
  EXPECT_EQ(rig.scene().half_spaces[1].ramp.superseded_at[0], 20);
  EXPECT_EQ(rig.store.counts().fading, 1u);
  rig.next_tick = 71;  // the old version's ramp is over
  EXPECT_EQ(rig.store.compact(), 1u);
  rig.next_tick = 100;
  ASSERT_TRUE(rig.store.remove(7, ItemKind::kObject, id).ok());
  // Still in the compiled scene, fading from tick 100; no longer addressable.
  ASSERT_EQ(rig.scene().half_spaces.size(), 1u);
  EXPECT_EQ(rig.scene().half_spaces[0].ramp.fade_begin_tick, 100);
  EXPECT_EQ(rig.store.remove(7, ItemKind::kObject, id).error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_EQ(rig.store.counts().fading, 1u);
  rig.next_tick = 150;  // tick 150 is the ramp's last (gain 0): keep until it has run
  EXPECT_EQ(rig.store.compact(), 0u);
  rig.next_tick = 151;
  EXPECT_EQ(rig.store.compact(), 1u);
  EXPECT_TRUE(rig.scene().half_spaces.empty());
}

TEST(SceneStore, UpdatesFasterThanTheRampKeepAtMostFourVersionsWithGainsSummingToOne) {
  StoreRig rig;
  std::uint64_t id = 0;
  ASSERT_TRUE(rig.store.create(7, ItemKind::kObject, wall(0.0), id).ok());
  for (int k = 1; k <= 6; ++k) {  // an update every 5 ticks against a 50-tick ramp
    rig.next_tick = 100 + 5 * k;
    ASSERT_TRUE(rig.store.update(7, ItemKind::kObject, id, wall(0.001 * k)).ok());
    const engine::CompiledScene& scene = rig.scene();
    EXPECT_LE(scene.half_spaces.size(), 4u);
    double sum = 0.0;
    for (const auto& version : scene.half_spaces) sum += engine::ramp_gain(version.ramp, rig.next_tick + 3, 50);
    EXPECT_NEAR(sum, 1.0, 1e-12) << k;
  }
}

TEST(SceneStore, ASharedObjectAnySessionMayUpdateButOnlyItsOwnerDeletes) {
  StoreRig rig;
  std::uint64_t id = 0;
  engine::ObjectSpec table = wall(0.0);
  table.shared = true;
  ASSERT_TRUE(rig.store.create(1, ItemKind::kObject, table, id).ok());
  engine::ObjectSpec moved = table;
  moved.p_WO.z = 0.01;
  EXPECT_TRUE(rig.store.update(2, ItemKind::kObject, id, moved).ok());  // another session moves it
  EXPECT_DOUBLE_EQ(rig.scene().half_spaces[0].point_W.z, 0.01);
  const grpc::Status remove = rig.store.remove(2, ItemKind::kObject, id);
  EXPECT_EQ(remove.error_code(), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_NE(remove.error_message().find("only its owner may delete it"), std::string::npos);
  engine::ObjectSpec made_private = moved;
  made_private.shared = false;
  EXPECT_EQ(rig.store.update(2, ItemKind::kObject, id, made_private).error_code(),
            grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_TRUE(rig.store.update(1, ItemKind::kObject, id, made_private).ok());  // the owner may
  EXPECT_EQ(rig.store.update(2, ItemKind::kObject, id, moved).error_code(),
            grpc::StatusCode::PERMISSION_DENIED);  // now private
  EXPECT_EQ(rig.store.remove_session(1), 1u);  // it goes with its owner
}

TEST(SceneStore, AnotherSessionsItemIsPermissionDenied) {
  StoreRig rig;
  std::uint64_t id = 0;
  ASSERT_TRUE(rig.store.create(1, ItemKind::kObject, wall(0.0), id).ok());
  EXPECT_EQ(rig.store.update(2, ItemKind::kObject, id, wall(0.1)).error_code(),
            grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(rig.store.remove(2, ItemKind::kObject, id).error_code(),
            grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(rig.store.remove(1, ItemKind::kField, id).error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_DOUBLE_EQ(rig.scene().half_spaces[0].point_W.z, 0.0);
}

TEST(SceneStore, LimitPerSessionIsResourceExhaustedAndChangesNothing) {
  StoreRig rig;
  std::uint64_t id = 0;
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(rig.store.create(1, ItemKind::kObject, wall(i), id).ok());
  EXPECT_EQ(rig.store.create(1, ItemKind::kObject, wall(9), id).error_code(),
            grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_EQ(rig.scene().half_spaces.size(), 3u);
  // Other sessions have their own budget.
  EXPECT_TRUE(rig.store.create(2, ItemKind::kObject, wall(9), id).ok());

  std::vector<std::uint64_t> object_ids, field_ids;
  const std::vector<engine::ObjectSpec> four(4, wall(0.5));
  EXPECT_EQ(rig.store.replace_session_scene(1, four, {}, object_ids, field_ids).error_code(),
            grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_EQ(rig.store.counts().objects, 4u);
  EXPECT_EQ(rig.store.counts().fading, 0u);
}

TEST(SceneStore, ReplaceSessionSceneFadesTheOldAndAddsTheNewAtOnce) {
  StoreRig rig;
  std::uint64_t mine = 0, theirs = 0;
  ASSERT_TRUE(rig.store.create(1, ItemKind::kObject, wall(0.0), mine).ok());
  ASSERT_TRUE(rig.store.create(2, ItemKind::kObject, wall(0.0), theirs).ok());
  const auto generation_before = rig.exchange.adopted_generation();
  rig.scene();
  std::vector<std::uint64_t> object_ids, field_ids;
  const std::vector<engine::FieldSpec> fields{
      engine::FieldSpec{engine::SpringToPointSpec{{}, 10.0, 0.0, 0.0}}};
  ASSERT_TRUE(rig.store.replace_session_scene(1, {wall(0.02), wall(0.03)}, fields, object_ids,
                                              field_ids).ok());
  EXPECT_EQ(object_ids.size(), 2u);
  EXPECT_EQ(field_ids.size(), 1u);
  const auto& scene = rig.scene();
  EXPECT_GT(rig.exchange.adopted_generation(), generation_before);
  EXPECT_EQ(scene.half_spaces.size(), 4u);  // two new, the fading old one, the other session's
  EXPECT_EQ(scene.springs.size(), 1u);
  EXPECT_EQ(rig.store.counts().fading, 1u);
  EXPECT_EQ(rig.store.update(1, ItemKind::kObject, mine, wall(0.0)).error_code(),
            grpc::StatusCode::NOT_FOUND);
  EXPECT_TRUE(rig.store.update(2, ItemKind::kObject, theirs, wall(0.1)).ok());
}

TEST(SceneStore, RemoveSessionFadesOnlyThatSession) {
  StoreRig rig;
  std::uint64_t id = 0;
  ASSERT_TRUE(rig.store.create(1, ItemKind::kObject, wall(0.0), id).ok());
  ASSERT_TRUE(rig.store.create(1, ItemKind::kField,
                               engine::FieldSpec{engine::SpringToPointSpec{{}, 1.0, 0.0, 0.0}}, id)
                  .ok());
  ASSERT_TRUE(rig.store.create(2, ItemKind::kObject, wall(0.0), id).ok());
  EXPECT_EQ(rig.store.remove_session(1), 2u);
  const SceneCounts counts = rig.store.counts();
  EXPECT_EQ(counts.objects, 1u);
  EXPECT_EQ(counts.fields, 0u);
  EXPECT_EQ(counts.fading, 2u);
}

}  // namespace
}  // namespace haptic::net

namespace haptic::net {
namespace {

TEST(SceneStore, TheWholeScenesTriangleAndMemoryBudgetsHoldAcrossSessions) {
  runtime::SceneExchange exchange{std::make_unique<const engine::CompiledScene>()};
  std::int64_t next_tick = 1;
  SceneStore store{exchange, [&] { return next_tick; }, 50, 256, 1e-3, 0.0, 1,
                   SceneBudget{.max_triangles = 1000}};
  std::uint64_t first = 0, second = 0, id = 0;
  ASSERT_TRUE(store.create(1, ItemKind::kObject, mesh(600, 0.0), first).ok());
  ASSERT_TRUE(store.create(2, ItemKind::kObject, mesh(400, 0.01), second).ok());  // exactly 1000
  // A third session's mesh, however small, is over the whole scene's budget, named.
  const grpc::Status over = store.create(3, ItemKind::kObject, mesh(2, 0.02), id);
  EXPECT_EQ(over.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_EQ(over.error_message(),
            "object: 2 more triangles would bring the scene (every session's, fading items "
            "included) to 1002, over max_scene_triangles (1000)");
  EXPECT_TRUE(store.create(3, ItemKind::kObject, wall(0.0), id).ok());  // no triangles: fine
  // An update holds both versions while the old one fades: refused until there is room.
  EXPECT_EQ(store.update(2, ItemKind::kObject, second, mesh(400, 0.02)).error_code(),
            grpc::StatusCode::RESOURCE_EXHAUSTED);
  ASSERT_TRUE(store.remove(1, ItemKind::kObject, first).ok());
  EXPECT_EQ(store.create(3, ItemKind::kObject, mesh(2, 0.02), id).error_code(),
            grpc::StatusCode::RESOURCE_EXHAUSTED);  // still fading: still held
  next_tick = 100;
  ASSERT_EQ(store.compact(), 1u);
  EXPECT_TRUE(store.update(2, ItemKind::kObject, second, mesh(400, 0.02)).ok());
  // The same rule for a whole scene at once: the session's old items fade, the new come on top.
  std::vector<std::uint64_t> objects, fields;
  const grpc::Status scene = store.replace_session_scene(2, {mesh(400, 0.03)}, {}, objects, fields);
  EXPECT_EQ(scene.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_EQ(scene.error_message().rfind("scene: 400 more triangles", 0), 0u) << scene.error_message();
}

TEST(SceneStore, OneSessionAndOneHostsSessionsHoldNoMoreThanTheirShares) {
  runtime::SceneExchange exchange{std::make_unique<const engine::CompiledScene>()};
  // Sessions 1 and 2 come from one host, 3 from another; 0 is the server's own.
  const auto host_of = [](std::uint64_t session) { return session == 3 ? std::string("10.0.0.3") : std::string("10.0.0.1"); };
  SceneBudget budget{2000, 0, 400, 0, 600, 0, host_of};
  SceneStore store{exchange, [] { return std::int64_t{1}; }, 50, 256, 1e-3, 0.0, 1, budget};
  std::uint64_t id = 0;
  ASSERT_TRUE(store.create(1, ItemKind::kObject, mesh(400, 0.0), id).ok());  // the session's share
  const grpc::Status session_over = store.create(1, ItemKind::kObject, mesh(2, 0.01), id);
  EXPECT_EQ(session_over.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_EQ(session_over.error_message(),
            "object: 2 more triangles would bring this session's items (fading items included) to 402, "
            "over max_scene_triangles_per_session (400)");
  ASSERT_TRUE(store.create(2, ItemKind::kObject, mesh(200, 0.02), id).ok());  // the host's 600
  const grpc::Status host_over = store.create(2, ItemKind::kObject, mesh(2, 0.03), id);
  EXPECT_EQ(host_over.error_message(),
            "object: 2 more triangles would bring the items of the sessions from 10.0.0.1 (fading items "
            "included) to 602, over max_scene_triangles_per_peer (600)");
  // Another host still has room, up to its own shares and the whole.
  EXPECT_TRUE(store.create(3, ItemKind::kObject, mesh(300, 0.04), id).ok());
  // The server's own scene is held to the whole only.
  EXPECT_TRUE(store.create(0, ItemKind::kObject, mesh(500, 0.05), id).ok());
  // A whole scene at once is held to the same shares (the session's old items fade, still held).
  std::vector<std::uint64_t> objects, fields;
  const grpc::Status scene = store.replace_session_scene(3, {mesh(101, 0.06)}, {}, objects, fields);
  EXPECT_EQ(scene.error_message(),
            "scene: 101 more triangles would bring this session's items (fading items included) to "
            "401, over max_scene_triangles_per_session (400)");
}

TEST(SceneStore, TheMemoryBudgetCountsAMeshAndItsHierarchy) {
  const ItemCost small = cost_of(mesh(2, 0.0));
  const ItemCost large = cost_of(mesh(2000, 0.0));
  EXPECT_EQ(small.triangles, 2u);
  EXPECT_EQ(large.triangles, 2000u);
  // At least the triangles' vertices and indices, and the hierarchy's copy of every triangle.
  EXPECT_GT(large.bytes, 2000u * (3 * 4 + 3 * 24));
  EXPECT_EQ(cost_of(wall(0.0)).triangles, 0u);
  runtime::SceneExchange exchange{std::make_unique<const engine::CompiledScene>()};
  SceneStore store{exchange, [] { return std::int64_t{1}; }, 50, 256, 1e-3, 0.0, 1,
                   SceneBudget{.max_bytes = large.bytes + small.bytes}};
  std::uint64_t id = 0;
  ASSERT_TRUE(store.create(1, ItemKind::kObject, mesh(2000, 0.0), id).ok());
  const grpc::Status over = store.create(2, ItemKind::kObject, mesh(20, 0.0), id);
  EXPECT_EQ(over.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_NE(over.error_message().find("over max_scene_bytes"), std::string::npos) << over.error_message();
}

}  // namespace
}  // namespace haptic::net
