// The compiled scene's stateful stages: primitives with friction and discrete impedance laws,
// meshes with a god object, energy fields, energy meters, and the loop state that a newer
// snapshot carries across (engine/scene/compiled_scene).
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "engine/scene/compiled_scene.hpp"
#include "support/allocation_counter.hpp"

namespace haptic::engine {
namespace {

constexpr double kT = 1e-3;

ObjectEntry object(std::uint64_t id, std::uint64_t key, ObjectSpec spec) {
  ItemMeta meta;
  meta.session_id = 1;
  meta.id = id;
  meta.version_key = key;
  return {meta, std::move(spec)};
}

FieldEntry field(std::uint64_t id, std::uint64_t key, FieldSpec spec) {
  ItemMeta meta;
  meta.session_id = 1;
  meta.id = id;
  meta.version_key = key;
  return {meta, std::move(spec)};
}

ObjectSpec box_with_friction(double mu_s, double mu_d) {
  ObjectSpec spec;
  spec.stiffness = 1000.0;
  spec.static_friction = mu_s;
  spec.dynamic_friction = mu_d;
  spec.shape = BoxSpec{{0.05, 0.05, 0.01}};  // top face at z = 0.01
  return spec;
}

std::shared_ptr<const MeshModel> plate(double z) {
  auto model = std::make_shared<MeshModel>();
  model->mesh.vertices_O = {{-0.1, -0.1, z}, {0.1, -0.1, z}, {0.1, 0.1, z}, {-0.1, 0.1, z}};
  model->mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  model->bvh = MeshBvh::build(model->mesh);
  return model;
}

TEST(SceneStages, OnlyTheStagesAScenesItemsNeedAreCompiled) {
  EXPECT_EQ(compile_scene({}, 50, 1).stages, 0u);
  SceneDescription d;
  ObjectSpec wall;
  wall.stiffness = 1000.0;
  wall.shape = HalfSpaceSpec{{0, 0, 1}};
  d.objects.push_back(object(1, 1, wall));
  EXPECT_EQ(compile_scene(d, 50, 1).stages, static_cast<std::uint32_t>(kStageHalfSpaces));
  ObjectSpec rough = wall;
  rough.static_friction = 0.5;  // friction needs a proxy: the stateful stage
  d.objects.push_back(object(2, 2, rough));
  d.fields.push_back(field(3, 3, FieldSpec{ViscousFieldSpec{0.5, {}, 0.0, 0.0}}));
  const CompiledScene scene = compile_scene(d, 50, 1);
  EXPECT_EQ(scene.stages, static_cast<std::uint32_t>(kStageHalfSpaces | kStageContacts | kStageFields));
  EXPECT_EQ(scene.contacts.size(), 1u);
  EXPECT_EQ(scene.state->contacts.size(), 1u);
  EXPECT_EQ(scene.state->meters.size(), 3u);
}

TEST(SceneStages, BoxWithFrictionSticksThenSlidesAtTheDynamicCone) {
  SceneDescription d;
  d.objects.push_back(object(1, 1, box_with_friction(0.5, 0.3)));
  const CompiledScene scene = compile_scene(d, 50, 1);
  // 2 mm into the top face (F_n = 2 N), then dragged along +x.
  SceneForce f = evaluate_scene(scene, {0, 0, 0.008}, {}, 100, kT);
  EXPECT_NEAR(f.F_T_W.z, 2.0, 1e-12);
  f = evaluate_scene(scene, {0.0005, 0, 0.008}, {}, 101, kT);  // within the static cone
  EXPECT_NEAR(f.F_T_W.x, -0.5, 1e-9);
  for (int k = 0; k < 100; ++k) f = evaluate_scene(scene, {0.0005 + 0.0001 * k, 0, 0.008}, {}, 102 + k, kT);
  EXPECT_NEAR(f.F_T_W.x, -0.3 * 2.0, 1e-9);  // sliding: μ_d F_n
}

TEST(SceneStages, AnUnrelatedChangeKeepsTheContactState) {
  SceneDescription d;
  d.objects.push_back(object(1, 1, box_with_friction(0.5, 0.3)));
  const CompiledScene before = compile_scene(d, 50, 1);
  evaluate_scene(before, {0, 0, 0.008}, {}, 100, kT);
  evaluate_scene(before, {0.0005, 0, 0.008}, {}, 101, kT);  // sticking, 0.5 N of friction
  // Another client adds a sphere elsewhere: a new snapshot with the box's version unchanged.
  ObjectSpec sphere;
  sphere.stiffness = 500.0;
  sphere.p_WO = {1, 1, 1};
  sphere.shape = SphereSpec{0.01};
  d.objects.push_back(object(2, 2, sphere));
  const CompiledScene after = compile_scene(d, 50, 2);
  carry_state(before, after);
  const SceneForce f = evaluate_scene(after, {0.0006, 0, 0.008}, {}, 102, kT);
  EXPECT_NEAR(f.F_T_W.x, -0.6, 1e-9);  // the proxy stayed where it stuck
  // Without the carry the contact would have restarted at the closest point: no friction yet.
  const CompiledScene fresh = compile_scene(d, 50, 3);
  EXPECT_NEAR(evaluate_scene(fresh, {0.0006, 0, 0.008}, {}, 102, kT).F_T_W.x, 0.0, 1e-12);
}

TEST(SceneStages, ExactZohLawIsTheDiscreteSpringDamperOnThePenetration_Eq8_11) {
  SceneDescription d;
  ObjectSpec wall;
  wall.stiffness = 1000.0;
  wall.damping = 2.0;
  wall.law = ContactLaw::kExactZoh;
  wall.shape = HalfSpaceSpec{{0, 0, 1}};
  d.objects.push_back(object(1, 1, wall));
  const CompiledScene scene = compile_scene(d, 50, 1, kT);
  ASSERT_EQ(scene.contacts.size(), 1u);  // a discrete law needs the filter's state
  ImpedanceFilter reference(ImpedanceParams{1000.0, 2.0, 0.0}, ImpedanceDiscretization::kExactZoh, kT);
  reference.reset();
  for (int k = 1; k <= 20; ++k) {
    const double d_k = 1e-4 * k;
    const double expected = std::max(0.0, reference.update(d_k));
    EXPECT_NEAR(evaluate_scene(scene, {0, 0, -d_k}, {}, 100 + k, kT).F_T_W.z, expected, 1e-12);
  }
}

TEST(SceneStages, AMeshPlateCannotBePushedThroughAndANewVersionKeepsTheSide) {
  SceneDescription d;
  ObjectSpec mesh;
  mesh.stiffness = 1000.0;
  mesh.shape = MeshShapeSpec{plate(0.0)};
  d.objects.push_back(object(1, 1, mesh));
  const CompiledScene scene = compile_scene(d, 50, 1);
  EXPECT_EQ(scene.stages, static_cast<std::uint32_t>(kStageMeshes));
  evaluate_scene(scene, {0, 0, 0.01}, {}, 100, kT);              // above the plate
  SceneForce f = evaluate_scene(scene, {0, 0, -0.02}, {}, 101, kT);  // through it in one tick
  EXPECT_NEAR(f.F_T_W.z, 1000.0 * 0.02, 1000.0 * 1e-5);  // held on top
  // The client moves the plate up by 1 mm (a new version of the same item): the god object is
  // carried over and rebased, so the force follows the geometry instead of dropping to zero.
  SceneDescription moved;
  ObjectSpec raised = mesh;
  raised.shape = MeshShapeSpec{plate(0.001)};
  moved.objects.push_back(object(1, 2, raised));
  const CompiledScene next = compile_scene(moved, 50, 2);
  carry_state(scene, next);
  f = evaluate_scene(next, {0, 0, -0.02}, {}, 102, kT);
  EXPECT_NEAR(f.F_T_W.z, 1000.0 * 0.021, 1000.0 * 1e-5);
}

TEST(SceneStages, EnergyMetersReportWhatEachItemExchangedWithTheDevice) {
  SceneDescription d;
  ObjectSpec wall;
  wall.stiffness = 1000.0;
  wall.shape = HalfSpaceSpec{{0, 0, 1}};
  d.objects.push_back(object(1, 1, wall));
  d.fields.push_back(field(2, 2, FieldSpec{ViscousFieldSpec{0.5, {}, 0.0, 0.0}}));
  const CompiledScene scene = compile_scene(d, 50, 1);
  // In and out of the wall at 0.1 m/s: a spring gives back what it took; the damper only takes.
  double z = 0.001;
  const double v = 0.1;
  std::int64_t tick = 100;
  for (int k = 0; k < 40; ++k, ++tick) {
    z -= v * kT;
    evaluate_scene(scene, {0, 0, z}, {0, 0, -v}, tick, kT);
  }
  for (int k = 0; k < 40; ++k, ++tick) {
    z += v * kT;
    evaluate_scene(scene, {0, 0, z}, {0, 0, v}, tick, kT);
  }
  const SceneState& s = *scene.state;
  EXPECT_EQ(s.meter_ids[0], 1u);
  const double wall_in = s.work_in[0].load(), wall_out = s.work_out[0].load();
  // ½ K d² = 4.5 mJ at d = 3 mm each way; the trapezoid rule over the instant reversal of the
  // velocity differs between the two halves by at most one tick's power at the bottom, K d v T.
  EXPECT_NEAR(wall_in, 0.5 * 1000.0 * 0.003 * 0.003, 1000.0 * 0.003 * v * kT);
  EXPECT_NEAR(wall_out, wall_in, 1000.0 * 0.003 * v * kT + 1e-12);
  // B v² over the 79 intervals between the 80 samples (the first sample only starts the meter).
  EXPECT_NEAR(s.work_in[1].load(), 0.5 * v * v * 79 * kT, 1e-12);
  EXPECT_EQ(s.work_out[1].load(), 0.0);
}

TEST(SceneStages, AVirtualMassPushedAtConstantSpeedFeelsItsViscousFriction_Eq7_1) {
  // A 0.2 kg box on a rough surface (B_V = 3 N·s/m), pushed by a tool moving at 0.05 m/s along x.
  // Once the box has caught up, Ẍ = 0 and eq. 7.1 leaves f_V = B_V Ẋ = 0.15 N.
  SceneDescription d;
  ObjectSpec box;
  box.stiffness = 2000.0;
  box.damping = 5.0;
  box.shape = BoxSpec{{0.01, 0.01, 0.01}};
  box.p_WO = {0.02, 0, 0};
  box.object_mass = 0.2;
  box.object_damping = 3.0;
  d.objects.push_back(object(1, 1, box));
  const CompiledScene scene = compile_scene(d, 50, 1, kT);
  const double v = 0.05;
  SceneForce f;
  for (int k = 0; k < 3000; ++k) {
    f = evaluate_scene(scene, {0.005 + v * kT * k, 0, 0}, {v, 0, 0}, 100 + k, kT);
  }
  EXPECT_NEAR(-f.F_T_W.x, 3.0 * v, 1e-6);  // the tool feels B_V v pushing back
  const std::vector<ObjectMotion> motions = object_motions(scene);
  ASSERT_EQ(motions.size(), 1u);
  EXPECT_EQ(motions[0].id, 1u);
  EXPECT_NEAR(motions[0].v_WO.x, v, 1e-9);
  // The box's face is where the tool is less the contact's penetration f / K — plus the tick the
  // box has just moved (its state is reported after the step, the tool's was sampled before).
  EXPECT_NEAR(motions[0].p_WO.x - 0.01 - (0.005 + v * kT * 2999), -3.0 * v / 2000.0 + v * kT, 1e-9);
  // Left alone, it coasts to rest after X_stop = m v / B_V (the exact solution of eq. 7.1).
  const double x_release = motions[0].p_WO.x;
  for (int k = 0; k < 2000; ++k) evaluate_scene(scene, {-1, 0, 0}, {}, 4000 + k, kT);
  EXPECT_NEAR(object_motions(scene)[0].p_WO.x - x_release, 0.2 * v / 3.0, 1e-6);
  EXPECT_NEAR(object_motions(scene)[0].v_WO.x, 0.0, 1e-9);
}

TEST(SceneStages, EachSessionsForceIsClippedToItsBudgetAndTheServersSceneIsExempt) {
  SceneDescription d;
  const auto wall_of = [&](std::uint64_t session, std::uint64_t id, double k) {
    ObjectSpec wall;
    wall.stiffness = k;
    wall.shape = HalfSpaceSpec{{0, 0, 1}};
    ObjectEntry entry = object(id, id, wall);
    entry.meta.session_id = session;
    d.objects.push_back(entry);
  };
  wall_of(7, 1, 1000.0);   // session 7: two walls, 1 N + 3 N at 1 mm
  wall_of(7, 2, 3000.0);
  wall_of(8, 3, 1000.0);   // session 8: 1 N
  wall_of(0, 4, 10000.0);  // the server's own scene: 10 N, no budget
  const Vec3 p{0, 0, -0.001};
  EXPECT_NEAR(evaluate_scene(compile_scene(d, 50, 1, kT), p, {}, 100, kT).F_T_W.z, 15.0, 1e-9);
  const SceneForce f = evaluate_scene(compile_scene(d, 50, 1, kT, 2.5), p, {}, 100, kT);
  EXPECT_NEAR(f.F_T_W.z, 2.5 + 1.0 + 10.0, 1e-9);  // session 7's 4 N clipped to 2.5 N
  EXPECT_EQ(f.contact_count, 4u);
}

TEST(SceneStages, AMeshWithFrictionSticksThenSlidesAtTheDynamicCone) {
  // The same drag as the box's: a plate with μ_s = 0.5, μ_d = 0.3, the tool 2 mm under its
  // surface (F_n = 2 N) dragged along +x.
  SceneDescription d;
  ObjectSpec mesh;
  mesh.stiffness = 1000.0;
  mesh.static_friction = 0.5;
  mesh.dynamic_friction = 0.3;
  mesh.shape = MeshShapeSpec{plate(0.0)};
  d.objects.push_back(object(1, 1, mesh));
  const CompiledScene scene = compile_scene(d, 50, 1, kT);
  evaluate_scene(scene, {0, 0, 0.001}, {}, 100, kT);  // above: free
  SceneForce f = evaluate_scene(scene, {0, 0, -0.002}, {}, 101, kT);
  EXPECT_NEAR(f.F_T_W.z, 2.0 + 1000.0 * 1e-6, 1e-9);  // K (d + the god object's 1 µm margin)
  EXPECT_NEAR(f.F_T_W.x, 0.0, 1e-9);
  f = evaluate_scene(scene, {0.0005, 0, -0.002}, {}, 102, kT);  // inside the static cone: sticks
  EXPECT_NEAR(f.F_T_W.x, -0.5, 1e-3);
  for (int k = 0; k < 100; ++k) f = evaluate_scene(scene, {0.0005 + 0.0001 * k, 0, -0.002}, {}, 103 + k, kT);
  EXPECT_NEAR(f.F_T_W.x, -0.3 * 2.0, 2e-3);  // sliding: μ_d F_n
  // Frictionless, the same drag feels nothing sideways.
  mesh.static_friction = mesh.dynamic_friction = 0.0;
  SceneDescription smooth;
  smooth.objects.push_back(object(1, 1, mesh));
  const CompiledScene slick = compile_scene(smooth, 50, 1, kT);
  evaluate_scene(slick, {0, 0, 0.001}, {}, 100, kT);
  evaluate_scene(slick, {0, 0, -0.002}, {}, 101, kT);
  EXPECT_NEAR(evaluate_scene(slick, {0.0005, 0, -0.002}, {}, 102, kT).F_T_W.x, 0.0, 1e-9);
}

TEST(SceneStages, AMeshVirtualMassIsPushedLikeAnyOther_Eq7_1) {
  // A 0.2 kg plate on a rough floor (B_V = 3 N·s/m), pushed from above by a tool moving down at
  // 0.05 m/s: once it has caught up, the tool feels B_V v and the plate moves at v.
  SceneDescription d;
  ObjectSpec mesh;
  mesh.stiffness = 2000.0;
  mesh.damping = 5.0;
  mesh.shape = MeshShapeSpec{plate(0.0)};
  mesh.object_mass = 0.2;
  mesh.object_damping = 3.0;
  d.objects.push_back(object(1, 1, mesh));
  const CompiledScene scene = compile_scene(d, 50, 1, kT);
  const double v = 0.05;
  SceneForce f;
  evaluate_scene(scene, {0, 0, 0.001}, {0, 0, -v}, 99, kT);
  for (int k = 0; k < 3000; ++k) {
    f = evaluate_scene(scene, {0, 0, 0.0005 - v * kT * k}, {0, 0, -v}, 100 + k, kT);
  }
  EXPECT_NEAR(f.F_T_W.z, 3.0 * v, 1e-4);
  const std::vector<ObjectMotion> motions = object_motions(scene);
  ASSERT_EQ(motions.size(), 1u);
  EXPECT_NEAR(motions[0].v_WO.z, -v, 1e-6);
  EXPECT_LT(motions[0].p_WO.z, -0.1);  // it went down with the tool
}

TEST(SceneStages, EveryStateStageAllocatesNothingPerTick) {
  SceneDescription d;
  d.objects.push_back(object(1, 1, box_with_friction(0.5, 0.3)));
  ObjectSpec mesh;
  mesh.stiffness = 800.0;
  mesh.static_friction = 0.4;  // the friction path too
  mesh.dynamic_friction = 0.3;
  mesh.shape = MeshShapeSpec{plate(-0.005)};
  d.objects.push_back(object(2, 2, mesh));
  ObjectSpec capsule;
  capsule.stiffness = 600.0;
  capsule.damping = 1.0;
  capsule.law = ContactLaw::kBackwardDifference;
  capsule.shape = CapsuleSpec{0.01, 0.02};
  d.objects.push_back(object(3, 3, capsule));
  PotentialFieldSpec well;
  well.distance = point_distance({0, 0, 0});
  well.kind = PotentialKind::kPolynomial;
  well.order = 2;
  well.gain = 50.0;
  well.offset = 0.05;
  d.fields.push_back(field(4, 4, FieldSpec{well}));
  const CompiledScene scene = compile_scene(d, 50, 1);
  const CompiledScene next = compile_scene(d, 50, 2);
  haptic::test::reset_allocations();
  {
    haptic::test::CountAllocations counting;
    for (std::int64_t tick = 0; tick < 5000; ++tick) {
      const double t = static_cast<double>(tick) * kT;
      const Vec3 p{0.03 * std::sin(3 * t), 0.02 * std::cos(5 * t), 0.012 * std::sin(7 * t)};
      evaluate_scene(tick < 2500 ? scene : next, p, {0.09 * std::cos(3 * t), 0, 0}, tick, kT);
      if (tick == 2500) carry_state(scene, next);
    }
  }
  EXPECT_EQ(haptic::test::allocations(), 0u);

  // Two ports sharing the scene, with a virtual mass both push, carried from one port to two.
  ObjectSpec mass;
  mass.stiffness = 2000.0;
  mass.damping = 5.0;
  mass.shape = BoxSpec{{0.01, 0.01, 0.01}};
  mass.p_WO = {0.0, 0.0, -0.02};
  mass.object_mass = 0.2;
  mass.object_damping = 3.0;
  d.objects.push_back(object(5, 5, mass));
  const CompiledScene one_port = compile_scene(d, 50, 3);
  const CompiledScene two_ports = compile_scene(d, 50, 4, kT, 0.0, 2);
  haptic::test::reset_allocations();
  {
    haptic::test::CountAllocations counting;
    for (std::int64_t tick = 0; tick < 5000; ++tick) {
      const double t = static_cast<double>(tick) * kT;
      const Vec3 p{0.03 * std::sin(3 * t), 0.02 * std::cos(5 * t), 0.012 * std::sin(7 * t)};
      const Vec3 v{0.09 * std::cos(3 * t), 0, 0};
      if (tick < 2500) {
        evaluate_scene(one_port, p, v, tick, kT);
        continue;
      }
      if (tick == 2500) carry_state(one_port, two_ports);
      evaluate_scene_port(two_ports, 0, p, v, tick, kT);
      evaluate_scene_port(two_ports, 1, -1.0 * p, -1.0 * v, tick, kT);
      advance_scene(two_ports, kT);
    }
  }
  EXPECT_EQ(haptic::test::allocations(), 0u);
}

/// A 0.2 kg box on a rough surface (B_V = 3 N·s/m), 2000 N/m and 5 N·s/m, its -x face at x = 0.01.
ObjectSpec virtual_mass_box() {
  ObjectSpec box;
  box.stiffness = 2000.0;
  box.damping = 5.0;
  box.shape = BoxSpec{{0.01, 0.01, 0.01}};
  box.p_WO = {0.02, 0, 0};
  box.object_mass = 0.2;
  box.object_damping = 3.0;
  return box;
}

TEST(SceneStages, TwoToolsPushingAVirtualMassTogetherEachFeelHalfItsViscousFriction_Eq7_1) {
  // Two tools on the box's -x face (at y = ±5 mm), both moving along x at 0.05 m/s. The box moves
  // once per tick under the sum of their reactions, so once it has caught up Ẍ = 0 and eq. 7.1
  // gives f_V = B_V Ẋ = 0.15 N in all, shared equally: 0.075 N each (a single tool feels 0.15 N).
  SceneDescription d;
  d.objects.push_back(object(1, 1, virtual_mass_box()));
  const CompiledScene scene = compile_scene(d, 50, 1, kT, 0.0, 2);
  const double v = 0.05;
  SceneForce f0, f1;
  for (int k = 0; k < 3000; ++k) {
    const double x = 0.005 + v * kT * k;
    f0 = evaluate_scene_port(scene, 0, {x, 0.005, 0}, {v, 0, 0}, 100 + k, kT);
    f1 = evaluate_scene_port(scene, 1, {x, -0.005, 0}, {v, 0, 0}, 100 + k, kT);
    advance_scene(scene, kT);
  }
  EXPECT_NEAR(-f0.F_T_W.x, 3.0 * v / 2.0, 1e-6);
  EXPECT_NEAR(-f1.F_T_W.x, 3.0 * v / 2.0, 1e-6);
  const std::vector<ObjectMotion> motions = object_motions(scene);
  ASSERT_EQ(motions.size(), 1u);
  EXPECT_NEAR(motions[0].v_WO.x, v, 1e-9);
  // The face is where the tools are less each contact's penetration (B_V v / 2) / K, plus the
  // tick the box has just moved.
  EXPECT_NEAR(motions[0].p_WO.x - 0.01 - (0.005 + v * kT * 2999), -1.5 * v / 2000.0 + v * kT, 1e-9);
}

TEST(SceneStages, AVirtualMassSqueezedFromBothSidesStaysWhileEachToolFeelsItsContact_Eq7_1) {
  // Two tools close in on the box from opposite faces at 0.05 m/s each. Their reactions cancel in
  // the sum that drives the box (eq. 7.1 with f_V = 0 from rest), so it stays where it is, and
  // each tool feels its own contact K d + B v (v the tool's speed relative to the still box).
  SceneDescription d;
  d.objects.push_back(object(1, 1, virtual_mass_box()));
  const CompiledScene scene = compile_scene(d, 50, 1, kT, 0.0, 2);
  const double v = 0.05;
  SceneForce f0, f1;
  double x0 = 0.0, x1 = 0.0;
  for (int k = 0; k < 200; ++k) {
    x0 = 0.005 + v * kT * k;  // towards the -x face at x = 0.01
    x1 = 0.035 - v * kT * k;  // towards the +x face at x = 0.03
    f0 = evaluate_scene_port(scene, 0, {x0, 0, 0}, {v, 0, 0}, 100 + k, kT);
    f1 = evaluate_scene_port(scene, 1, {x1, 0, 0}, {-v, 0, 0}, 100 + k, kT);
    advance_scene(scene, kT);
  }
  const std::vector<ObjectMotion> motions = object_motions(scene);
  ASSERT_EQ(motions.size(), 1u);
  EXPECT_NEAR(motions[0].p_WO.x, 0.02, 1e-9);
  EXPECT_NEAR(motions[0].v_WO.x, 0.0, 1e-9);
  EXPECT_NEAR(-f0.F_T_W.x, 2000.0 * (x0 - 0.01) + 5.0 * v, 1e-6);
  EXPECT_NEAR(f1.F_T_W.x, 2000.0 * (0.03 - x1) + 5.0 * v, 1e-6);
  EXPECT_GT(-f0.F_T_W.x, 10.0);  // 4.95 mm deep: a real squeeze, not a touch
  // One tool alone would have pushed the box away: it is the sum that drives the mass.
  const CompiledScene alone = compile_scene(d, 50, 2, kT);
  for (int k = 0; k < 200; ++k) evaluate_scene(alone, {0.005 + v * kT * k, 0, 0}, {v, 0, 0}, 100 + k, kT);
  EXPECT_GT(object_motions(alone)[0].v_WO.x, 0.01);
}

TEST(SceneStages, EachPortHasItsOwnFrictionProxy) {
  // Port 0 sticks on the friction box while port 1 slides elsewhere on its top face: each feels
  // its own friction, port 0 the static spring K |P − S|, port 1 the dynamic cone μ_d F_n.
  SceneDescription d;
  d.objects.push_back(object(1, 1, box_with_friction(0.5, 0.3)));
  const CompiledScene scene = compile_scene(d, 50, 1, kT, 0.0, 2);
  // 2 mm into the top face (F_n = 2 N) at both ports.
  evaluate_scene_port(scene, 0, {0, 0, 0.008}, {}, 100, kT);
  evaluate_scene_port(scene, 1, {0.02, 0.02, 0.008}, {}, 100, kT);
  advance_scene(scene, kT);
  SceneForce f0, f1;
  for (int k = 0; k < 100; ++k) {
    f0 = evaluate_scene_port(scene, 0, {0.0005, 0, 0.008}, {}, 101 + k, kT);  // within the cone
    f1 = evaluate_scene_port(scene, 1, {0.02, 0.02 + 0.0001 * k, 0.008}, {}, 101 + k, kT);
    advance_scene(scene, kT);
  }
  EXPECT_NEAR(f0.F_T_W.x, -0.5, 1e-9);
  EXPECT_NEAR(f0.F_T_W.y, 0.0, 1e-12);
  EXPECT_NEAR(f0.F_T_W.z, 2.0, 1e-12);
  EXPECT_NEAR(f1.F_T_W.x, 0.0, 1e-12);
  EXPECT_NEAR(f1.F_T_W.y, -0.3 * 2.0, 1e-9);  // sliding: μ_d F_n
  EXPECT_NEAR(f1.F_T_W.z, 2.0, 1e-12);
}

TEST(SceneStages, ASnapshotForMorePortsKeepsPortZerosStateAndStartsTheNewPortFresh) {
  SceneDescription d;
  d.objects.push_back(object(1, 1, box_with_friction(0.5, 0.3)));
  ObjectSpec mass = virtual_mass_box();
  mass.p_WO = {0.2, 0, 0};  // its -x face at x = 0.19
  d.objects.push_back(object(2, 2, mass));
  const CompiledScene before = compile_scene(d, 50, 1, kT);
  const double v = 0.05;
  for (int k = 0; k < 300; ++k) evaluate_scene(before, {0.185 + v * kT * k, 0, 0}, {v, 0, 0}, k, kT);
  evaluate_scene(before, {0, 0, 0.008}, {}, 300, kT);
  evaluate_scene(before, {0.0005, 0, 0.008}, {}, 301, kT);  // sticking, 0.5 N of friction
  ASSERT_GT(object_motions(before)[0].v_WO.x, 0.0);          // the mass is coasting
  // A second device joins: the same items, compiled for two ports.
  const CompiledScene after = compile_scene(d, 50, 2, kT, 0.0, 2);
  carry_state(before, after);
  const std::vector<ItemEnergyTotals> energy_before = energy_totals(before);
  const std::vector<ItemEnergyTotals> energy_after = energy_totals(after);
  ASSERT_EQ(energy_after.size(), energy_before.size());
  for (std::size_t i = 0; i < energy_before.size(); ++i) {
    EXPECT_EQ(energy_after[i].given, energy_before[i].given);
    EXPECT_EQ(energy_after[i].absorbed, energy_before[i].absorbed);
  }
  const SceneForce f0 = evaluate_scene_port(after, 0, {0.0006, 0, 0.008}, {}, 302, kT);
  const SceneForce f1 = evaluate_scene_port(after, 1, {0.0006, 0, 0.008}, {}, 302, kT);
  advance_scene(after, kT);
  EXPECT_NEAR(f0.F_T_W.x, -0.6, 1e-9);   // port 0's proxy stayed where it stuck
  EXPECT_NEAR(f1.F_T_W.x, 0.0, 1e-12);   // port 1's contact starts at the closest point
  EXPECT_NEAR(f1.F_T_W.z, 2.0, 1e-12);
  // The mass's motion carried once: it coasts on exactly as it would have in the old snapshot.
  evaluate_scene(before, {0.0006, 0, 0.008}, {}, 302, kT);
  const ObjectMotion expected = object_motions(before)[0];
  const ObjectMotion carried = object_motions(after)[0];
  EXPECT_EQ(carried.id, 2u);
  EXPECT_DOUBLE_EQ(carried.p_WO.x, expected.p_WO.x);
  EXPECT_DOUBLE_EQ(carried.v_WO.x, expected.v_WO.x);
}

TEST(SceneStages, EnergyTotalsSumTheMetersOfEveryPort) {
  SceneDescription d;
  ObjectSpec wall;
  wall.stiffness = 1000.0;
  wall.shape = HalfSpaceSpec{{0, 0, 1}};
  d.objects.push_back(object(1, 1, wall));
  d.fields.push_back(field(2, 2, FieldSpec{ViscousFieldSpec{0.5, {}, 0.0, 0.0}}));
  const CompiledScene scene = compile_scene(d, 50, 1, kT, 0.0, 2);
  // Port 0 goes 3 mm into the wall and back at 0.1 m/s; port 1 moves through free space above it
  // at 0.2 m/s, so only the viscous field meters its work.
  double z = 0.001;
  const double v0 = 0.1, v1 = 0.2;
  std::int64_t tick = 100;
  for (int k = 0; k < 80; ++k, ++tick) {
    const double vz = k < 40 ? -v0 : v0;
    z += vz * kT;
    evaluate_scene_port(scene, 0, {0, 0, z}, {0, 0, vz}, tick, kT);
    evaluate_scene_port(scene, 1, {v1 * kT * k, 0, 0.5}, {v1, 0, 0}, tick, kT);
    advance_scene(scene, kT);
  }
  const std::vector<ItemEnergyTotals> totals = energy_totals(scene);
  ASSERT_EQ(totals.size(), 2u);
  EXPECT_EQ(totals[0].id, 1u);
  // The wall: port 0's ½ K d² each way, as with one tool (to within one tick's power, K d v T).
  EXPECT_NEAR(totals[0].absorbed, 0.5 * 1000.0 * 0.003 * 0.003, 1000.0 * 0.003 * v0 * kT);
  EXPECT_NEAR(totals[0].given, totals[0].absorbed, 1000.0 * 0.003 * v0 * kT + 1e-12);
  // The viscous field: B v² over 79 intervals at each port, summed.
  const double port0 = 0.5 * v0 * v0 * 79 * kT, port1 = 0.5 * v1 * v1 * 79 * kT;
  const SceneState& s = *scene.state;
  EXPECT_NEAR(s.work_in[1].load(), port0, 1e-12);
  EXPECT_NEAR(s.work_in[s.meters_per_port + 1].load(), port1, 1e-12);
  EXPECT_EQ(s.work_in[s.meters_per_port + 0].load(), 0.0);  // port 1 never touched the wall
  EXPECT_NEAR(totals[1].absorbed, port0 + port1, 1e-12);
  EXPECT_EQ(totals[1].given, 0.0);
}

}  // namespace
}  // namespace haptic::engine
