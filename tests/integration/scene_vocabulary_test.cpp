// The scene vocabulary over gRPC, from the SDK and from scene files, against the real hapticd in
// lockstep: boxes, capsules, meshes (held by a god object), friction, discrete laws, the energy
// fields, and bad input that names the element and changes nothing.
#include <gtest/gtest.h>

#include <haptic/haptic.hpp>

#include <chrono>
#include <cmath>
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <string>
#include <utility>

#include "integration/sdk_harness.hpp"
#include "integration/server_process.hpp"

namespace haptic {
namespace {

using test::config_for;
using test::step_and_get;

using std::chrono::seconds;

class SceneVocabulary : public ::testing::Test {
 protected:
  // The point-mass device starts at z = 20 mm.
  test::ServerProcess server_{test::lockstep_config()};
};

TEST_F(SceneVocabulary, ABoxTopCarriesTheHandsPushAtKTimesPenetration) {
  Client client(config_for(server_));
  // A box whose top face is at z = 0, rotated 90° about z (a square box: same top).
  auto box = client.add_box({.pose = {.position = {0, 0, -0.01}, .orientation = {0.7071067811865476, 0, 0, 0.7071067811865476}},
                             .half_extents = {0.05, 0.05, 0.01},
                             .impedance = {.stiffness = 1000.0, .damping = 1.0}});
  step_and_get(client, 100);  // a new object ramps in over 50 ms before anyone leans on it
  client.set_operator(OperatorInput::push({0, 0, -2.0}));
  const State s = step_and_get(client, 3000);
  EXPECT_EQ(s.contact_count, 1u);
  EXPECT_NEAR(s.force.z, 2.0, 1e-3);
  EXPECT_NEAR(s.position.z, -0.002, 1e-5);
  EXPECT_NEAR(s.proxy.z, 0.0, 1e-9);  // the surface point above the tool
}

TEST_F(SceneVocabulary, AThinMeshPlateHoldsAPushThatWouldGoStraightThrough) {
  Client client(config_for(server_));
  // One two-triangle plate at z = 0, no thickness at all.
  auto plate = client.add_mesh({.pose = {},
                                .vertices = {{-0.05, -0.05, 0}, {0.05, -0.05, 0}, {0.05, 0.05, 0}, {-0.05, 0.05, 0}},
                                .indices = {0, 1, 2, 0, 2, 3},
                                .impedance = {.stiffness = 1000.0, .damping = 1.0}});
  client.set_operator(OperatorInput::push({0, 0, -3.0}));
  const State s = step_and_get(client, 3000);
  EXPECT_EQ(s.contact_count, 1u);
  EXPECT_NEAR(s.force.z, 3.0, 1e-3);
  EXPECT_NEAR(s.position.z, -0.003, 2e-5);  // the tool sinks K⁻¹ F below; the proxy stays on top
  EXPECT_GT(s.proxy.z, 0.0);
}

TEST_F(SceneVocabulary, FrictionHoldsASidewaysPushBelowTheStaticCone) {
  Client client(config_for(server_));
  auto floor = client.add_box({.pose = {.position = {0, 0, -0.01}},
                               .half_extents = {0.09, 0.09, 0.01},
                               .impedance = {.stiffness = 1000.0, .damping = 2.0,
                                             .static_friction = 0.5, .dynamic_friction = 0.4}});
  step_and_get(client, 100);
  // A hand (500 N/m, 5 N·s/m) pulling towards 6 mm below the surface presses with 2 N: the box
  // takes 1000 d = 500 (6 mm − d), d = 2 mm.
  client.set_operator(OperatorInput::follow({0, 0, -0.006}, 500.0, 5.0));
  const State pressed = step_and_get(client, 2000);
  ASSERT_EQ(pressed.contact_count, 1u);
  EXPECT_NEAR(pressed.force.z, 2.0, 1e-3);
  // The hand's target moves 1.8 mm sideways: sticking, the proxy holds and the friction spring
  // (K = 1000 N/m) and the hand share the offset, 1000 x = 500 (1.8 mm − x): x = 0.6 mm and
  // 0.6 N of friction, inside μ_s F_n = 1 N.
  client.set_operator(OperatorInput::follow({0.0018, 0, -0.006}, 500.0, 5.0));
  const State held = step_and_get(client, 2000);
  EXPECT_NEAR(held.force.x, -0.6, 1e-3);
  EXPECT_NEAR(held.position.x, 0.0006, 1e-5);
  // 10 mm sideways asks for more than the cone: it slides and comes to rest where the hand's pull
  // has fallen to the dynamic cone, μ_d F_n = 0.8 N.
  client.set_operator(OperatorInput::follow({0.010, 0, -0.006}, 500.0, 5.0));
  const State slid = step_and_get(client, 3000);
  EXPECT_NEAR(slid.force.x, -0.8, 0.01);
  EXPECT_NEAR(slid.position.x, 0.010 - 0.8 / 500.0, 2e-5);
}

TEST_F(SceneVocabulary, FieldsPullTheToolWhereTheirPotentialsSay) {
  Client client(config_for(server_));
  // A spring onto the plane z = 5 mm, and a viscous field that damps the approach.
  auto plane_spring = client.add_field(DistanceSpringSpec{
      .anchor = {.kind = Distance::Kind::kPlane, .origin = {0, 0, 0.005}, .axis = {0, 0, 1}},
      .stiffness = 50.0});
  auto viscous = client.add_field(ViscousFieldSpec{.damping = 0.5});
  State s = step_and_get(client, 3000);
  EXPECT_NEAR(s.position.z, 0.005, 1e-5);
  EXPECT_NEAR(s.position.x, 0.0, 1e-12);  // a plane constrains only its normal
  // A detent (a well with a rim) 10 mm to the side replaces the spring and draws the tool in.
  plane_spring.remove();
  auto detent = client.add_field(DetentFieldSpec{
      .distance = {.kind = Distance::Kind::kPoint, .origin = {0.01, 0, 0.005}},
      .depth = 0.01, .radius = 0.02, .rim_height = 0.002, .rim_width = 0.005});
  s = step_and_get(client, 4000);
  EXPECT_NEAR(s.position.x, 0.01, 1e-4);
  EXPECT_NEAR(s.position.z, 0.005, 1e-4);
  // A polynomial potential (n = 2) is a soft repulsive ball: K (c − f) outward inside f < c.
  detent.remove();
  auto ball = client.add_field(PotentialFieldSpec{
      .distance = {.kind = Distance::Kind::kPoint, .origin = {0.0, 0, 0.005}},
      .order = 2, .gain = 0.5, .offset = 0.02});
  // After the ramps (the ball in, the detent out), still inside, being pushed out along +x.
  s = step_and_get(client, 60);
  const double f = std::hypot(s.position.x, s.position.z - 0.005);
  ASSERT_LT(f, 0.02);
  EXPECT_NEAR(s.force.x, 0.5 * (0.02 - f) * s.position.x / f - 0.5 * s.velocity.x, 1e-6);
  // Overdamped by the viscous field, it creeps up to the ball's surface, where the push ends.
  s = step_and_get(client, 3000);
  EXPECT_LT(s.position.x, 0.02);
  EXPECT_GT(s.position.x, 0.019);
}

TEST_F(SceneVocabulary, BadGeometryAndImpossibleLawsAreRefusedNamingTheElement) {
  Client client(config_for(server_));
  try {
    auto bad = client.add_mesh({.vertices = {{0, 0, 0}, {1e-3, 0, 0}, {0, 1e-3, 0}, {2e-3, 0, 0}},
                                .indices = {0, 1, 2, 0, 1, 3},  // the second is degenerate
                                .impedance = {.stiffness = 1000.0}});
    FAIL() << "a degenerate triangle was accepted";
  } catch (const InvalidArgumentError& error) {
    EXPECT_NE(std::string(error.what()).find("mesh.triangles[1]: zero area"), std::string::npos)
        << error.what();
  }
  try {
    auto bad = client.add_box({.half_extents = {0.01, 0.0, 0.01}, .impedance = {.stiffness = 1000.0}});
    FAIL() << "a flat box was accepted";
  } catch (const InvalidArgumentError& error) {
    EXPECT_NE(std::string(error.what()).find("box.half_extents.y"), std::string::npos) << error.what();
  }
  try {
    auto bad = client.add_box({.half_extents = {0.01, 0.01, 0.01},
                               .impedance = {.stiffness = 1000.0, .damping = 1.0, .law = ImpedanceLaw::kTustin}});
    FAIL() << "an unstable Tustin damper was accepted";
  } catch (const InvalidArgumentError& error) {
    EXPECT_NE(std::string(error.what()).find("impedance.law: TUSTIN"), std::string::npos) << error.what();
  }
  try {
    auto bad = client.add_field(LinearFieldSpec{.radius = 0.1, .fade_width = 0.0});
    FAIL() << "a linear field without a fade was accepted";
  } catch (const InvalidArgumentError& error) {
    EXPECT_NE(std::string(error.what()).find("linear."), std::string::npos) << error.what();
  }
}

TEST_F(SceneVocabulary, AScenefileAppliesWholeOrNotAtAll) {
  Client client(config_for(server_));
  auto handles = client.apply_scene_file(std::string(HAPTIC_SOURCE_DIR) + "/config/scenes/wall_sphere_spring.json");
  EXPECT_EQ(handles.objects.size(), 2u);
  EXPECT_EQ(handles.fields.size(), 1u);
  const State before = step_and_get(client, 2000);
  // A file with one good and one bad object changes nothing, and the error names the object.
  const std::string path = ::testing::TempDir() + "/half_bad_scene.json";
  {
    std::ofstream out(path);
    out << R"({"objects": [{"impedance": {"stiffness": 100}, "sphere": {"radius": 0.01}},
                          {"impedance": {"stiffness": 100}, "capsule": {"radius": -1}}]})";
  }
  try {
    client.apply_scene_file(path);
    FAIL() << "a bad scene file was applied";
  } catch (const InvalidArgumentError& error) {
    EXPECT_NE(std::string(error.what()).find("objects[1].capsule.radius"), std::string::npos)
        << error.what();
  }
  const State after = step_and_get(client, 100);
  EXPECT_NEAR(after.position.z, before.position.z, 1e-9);  // the old scene still holds the tool
  EXPECT_THROW(client.apply_scene_file(path + ".missing"), InvalidArgumentError);
}

TEST_F(SceneVocabulary, RegistrationReportsColgatesBoundAndTheSampledMarginOnThisDevice) {
  Client client(config_for(server_));
  auto wall = client.add_wall({.point = {0, 0, 0}, .normal = {0, 0, 1}, .impedance = {1000.0, 1.0}});
  const StabilityReport& r = wall.stability();
  EXPECT_DOUBLE_EQ(r.colgate_min_damping, 1000.0 * 0.001 / 2 + 1.0);  // K T / 2 + |B|
  EXPECT_TRUE(r.device_known);
  EXPECT_EQ(r.device_mass, 0.01);     // the point mass (Eom et al.)
  EXPECT_EQ(r.device_damping, 0.022);
  EXPECT_FALSE(r.passive);            // 0.022 N·s/m of physical damping is far below 1.5
  EXPECT_GT(r.max_stable_stiffness, 0.0);
  EXPECT_EQ(r.stable, 1000.0 < r.max_stable_stiffness);
  EXPECT_EQ(r.stable, r.max_pole_magnitude < 1.0);
  // A far stiffer wall with the same damping is past the margin.
  auto stiff = client.add_wall({.point = {0, 0, -1}, .normal = {0, 0, 1}, .impedance = {1e6, 1.0}});
  EXPECT_FALSE(stiff.stability().stable);
  EXPECT_GT(stiff.stability().max_pole_magnitude, 1.0);
  // Accepted, but not without a word: the report says why (the server logs the same line).
  EXPECT_NE(stiff.stability().warning.find("not stable on this device: K = 1e+06 N/m"),
            std::string::npos)
      << stiff.stability().warning;
  EXPECT_EQ(r.warning.empty(), r.stable) << r.warning;
  // An update reports on the new impedance: softened, the wall is stable and the warning goes.
  stiff.update(WallSpec{.point = {0, 0, -1}, .normal = {0, 0, 1}, .impedance = {100.0, 1.0}});
  EXPECT_TRUE(stiff.stability().stable);
  EXPECT_EQ(stiff.stability().warning, "");
  stiff.update(WallSpec{.point = {0, 0, -1}, .normal = {0, 0, 1}, .impedance = {1e6, 1.0}});
  EXPECT_FALSE(stiff.stability().stable);
  EXPECT_NE(stiff.stability().warning, "");
  client.apply_scene({{.point = {0, 0, 0}, .normal = {0, 0, 1}, .impedance = {200.0, 2.0}}}, {}, {});
  ASSERT_EQ(client.last_scene_stability().size(), 1u);
  EXPECT_DOUBLE_EQ(client.last_scene_stability()[0].colgate_min_damping, 200.0 * 0.001 / 2 + 2.0);
}

/// A hand that holds the tool with a stiff, overdamped grip (800 N/m, 20 N·s/m on the 10 g tool)
/// while its target moves along a line: the tool follows slowly, without ringing.
OperatorInput slow_line(Vec3 from, Vec3 to, double duration_s) {
  OperatorInput input = OperatorInput::follow(from, 800.0, 20.0);
  input.path.shape = OperatorInput::Path::Shape::kLine;
  input.path.end = to;
  input.path.duration_s = duration_s;
  return input;
}

TEST_F(SceneVocabulary, EachItemReportsTheEnergyItExchangedWithTheDevice) {
  Client client(config_for(server_));
  auto wall = client.add_wall({.point = {0, 0, 0}, .normal = {0, 0, 1}, .impedance = {1000.0, 0.0}});
  // The hand first takes the tool to 5 mm above the wall and holds it there.
  client.set_operator(OperatorInput::follow({0, 0, 0.005}, 800.0, 20.0));
  step_and_get(client, 500);
  auto viscous = client.add_field(ViscousFieldSpec{.damping = 0.2});
  step_and_get(client, 100);
  // The hand's target goes 10 mm below the surface and back, slowly: the tool settles where the
  // grip (800 N/m) and the wall (1000 N/m) balance, d = 800 × 0.010 / 1800 = 4.44 mm deep.
  client.set_operator(slow_line({0, 0, 0.005}, {0, 0, -0.010}, 1.0));
  const State held = step_and_get(client, 1500);
  client.set_operator(slow_line({0, 0, -0.010}, {0, 0, 0.005}, 1.0));
  step_and_get(client, 1500);
  const std::vector<ItemEnergy> energy = client.scene_energy();
  const auto find = [&](std::uint64_t id) {
    for (const ItemEnergy& e : energy) {
      if (e.id == id) return e;
    }
    ADD_FAILURE() << "no energy for item " << id;
    return ItemEnergy{};
  };
  const ItemEnergy w = find(wall.id());
  const ItemEnergy v = find(viscous.id());
  EXPECT_TRUE(w.is_object);
  EXPECT_FALSE(v.is_object);
  // Pressed in slowly, the undamped wall stored ½ K d_max² and gave all of it back. While the
  // target moves at u = 15 mm/s the tool follows a steady ramp, d' = u K_h / (K_h + K_w), and the
  // grip's damper pushes b_h (u − d') beyond the springs' balance: when the target stops at
  // D = 10 mm, d_max = (K_h D + b_h (u − d')) / (K_h + K_w) = 4.537 mm; then it settles at
  // K_h D / (K_h + K_w) = 4.444 mm.
  constexpr double kHand = 800.0, kWall = 1000.0, b_hand = 20.0, u = 0.015, depth = 0.010;
  const double settled = kHand * depth / (kHand + kWall);
  EXPECT_NEAR(-held.position.z, settled, 1e-9);
  const double d_max = (kHand * depth + b_hand * u * (1.0 - kHand / (kHand + kWall))) / (kHand + kWall);
  const double stored = 0.5 * kWall * d_max * d_max;  // 10.29 mJ
  EXPECT_NEAR(w.absorbed_from_device, stored, 0.02 * stored);
  EXPECT_NEAR(w.given_to_device, stored, 0.02 * stored);
  // The viscous field only absorbs: b ∫ v² dt, the tool never faster than its target's 15 mm/s
  // over the 2 s it moves.
  EXPECT_GT(v.absorbed_from_device, 0.0);
  EXPECT_LT(v.absorbed_from_device, 0.2 * 0.015 * 0.015 * 2.0);
  EXPECT_EQ(v.given_to_device, 0.0);
}

TEST_F(SceneVocabulary, TheHandPushesAVirtualMassAndEveryClientSeesWhereItWent_Eq7_1) {
  Client client(config_for(server_));
  Client watcher(config_for(server_));
  // A 100 g ball on a rough floor (B_V = 4 N·s/m) 20 mm to the side of the tool.
  auto ball = client.add_sphere({.center = {0.02, 0, 0.02}, .radius = 0.01,
                                 .impedance = {.stiffness = 1000.0, .damping = 2.0},
                                 .dynamics = {.mass = 0.1, .damping = 4.0}});
  step_and_get(client, 100);
  client.set_operator(OperatorInput::push({0.2, 0, 0}));
  step_and_get(client, 1500);
  const std::vector<ObjectState> seen = watcher.object_states();
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_EQ(seen[0].id, ball.id());
  // Tool and ball move together at the terminal speed F / (B_V + b_tool) = 0.2 / 4.022 m/s.
  const double v_terminal = 0.2 / 4.022;
  EXPECT_NEAR(seen[0].velocity.x, v_terminal, 1e-4);
  // Where it went: never further than at that speed all along, and not much less: the tool
  // reaches it in about 32 ms (0.2 N on 10 g over 10 mm) and the pair settles to the speed with
  // the time constant (M + m) / (B_V + b) = 27 ms, well inside 0.3 s.
  EXPECT_LT(seen[0].position.x - 0.02, v_terminal * 1.5);
  EXPECT_GT(seen[0].position.x - 0.02, v_terminal * (1.5 - 0.3));
  EXPECT_NEAR(seen[0].position.y, 0.0, 1e-12);
  // From here on it moves exactly at that speed: 0.2 s more is v_terminal × 0.2 s further (and
  // the tool stays inside the workspace, |x| ≤ 0.1 m).
  step_and_get(client, 200);
  const std::vector<ObjectState> later = watcher.object_states();
  ASSERT_EQ(later.size(), 1u);
  EXPECT_NEAR(later[0].position.x - seen[0].position.x, v_terminal * 0.2, 1e-5);
  // Too light for its contact stiffness at 1 kHz: refused with the bound it needs.
  try {
    auto feather = client.add_sphere({.center = {0, 0.05, 0}, .radius = 0.01,
                                      .impedance = {.stiffness = 1000.0, .damping = 2.0},
                                      .dynamics = {.mass = 0.001, .damping = 0.0}});
    FAIL() << "a mass too light for its stiffness was accepted";
  } catch (const InvalidArgumentError& error) {
    EXPECT_NE(std::string(error.what()).find("dynamics.mass"), std::string::npos) << error.what();
  }
}

TEST_F(SceneVocabulary, ATangentPlaneFromASlowHostHoldsTheToolAndPullsItToItsReferencePoint) {
  Client client(config_for(server_));
  // The host says: the surface near the tool is the plane z = 0 (normal +z), and the tool should
  // rest at (5 mm, 0) on it. The hand pushes 1 N down.
  auto plane = client.add_tangent_plane({.normal = {0, 0, 1}, .reference = {0.005, 0, 0},
                                         .tangential_stiffness = 200.0, .tangential_damping = 2.0,
                                         .impedance = {.stiffness = 1000.0, .damping = 1.0}});
  step_and_get(client, 100);
  client.set_operator(OperatorInput::push({0, 0, -1.0}));
  State s = step_and_get(client, 3000);
  EXPECT_NEAR(s.position.z, -0.001, 1e-5);  // F / K behind the plane
  EXPECT_NEAR(s.position.x, 0.005, 1e-5);   // drawn to the reference point
  // At 25 Hz the host sends the next plane, tilted and a little higher: the change cross-fades.
  plane.update({.normal = {0, 0.1, 1}, .reference = {0.005, 0, 0.001},
                .tangential_stiffness = 200.0, .tangential_damping = 2.0,
                .impedance = {.stiffness = 1000.0, .damping = 1.0}});
  double largest_step = 0.0;
  double previous = s.force.z;
  for (int k = 0; k < 40; ++k) {
    s = step_and_get(client, 1);
    largest_step = std::max(largest_step, std::abs(s.force.z - previous));
    previous = s.force.z;
  }
  EXPECT_LT(largest_step, 0.1);  // no jump: at most a few percent of the 1 N per tick
}

TEST_F(SceneVocabulary, AWallCanAskForTheTransparencyOptimalDamping_001Eq11) {
  Client client(config_for(server_));
  auto wall = client.add_wall({.point = {0, 0, 0}, .normal = {0, 0, 1},
                               .impedance = {.stiffness = 1000.0, .damping = 1.0,
                                             .transparency_optimal_damping = true}});
  // Eom et al.'s device (0.01 kg, 0.022 N·s/m), K = 1000 N/m, w1 at 100 rad/s: B_c* ≈ 15.46 N·s/m
  // (docs/devices.md), robustly stable at ±50 %.
  EXPECT_NEAR(wall.stability().chosen_damping, 15.0, 0.5);   // 001 Fig. 8: 15 N·s/m
  EXPECT_NEAR(wall.stability().chosen_damping, 15.46, 0.05);  // regression pin: this model's
  EXPECT_TRUE(wall.stability().robustly_stable);
}

TEST_F(SceneVocabulary, AVirtualCouplingIsPassiveOnThisDeviceWhateverTheObject) {
  Client client(config_for(server_));
  // Colgate et al. 1995 on the default device (b = 0.022 N·s/m, 1 kHz): B_c = b/2 = 0.011 N·s/m,
  // K_c = 0.9 · 2 (b − B_c) / T = 19.8 N/m — passive, and soft.
  auto wall = client.add_wall({.point = {0, 0, 0}, .normal = {0, 0, 1},
                               .impedance = {.stiffness = 5000.0, .virtual_coupling = true}});
  const StabilityReport& r = wall.stability();
  EXPECT_NEAR(r.chosen_stiffness, 19.8, 1e-9);
  EXPECT_NEAR(r.chosen_damping, 0.011, 1e-12);
  EXPECT_TRUE(r.passive);
  EXPECT_TRUE(r.stable);
  try {
    auto both = client.add_wall({.point = {0, 0, 0}, .normal = {0, 0, 1},
                                 .impedance = {.stiffness = 1000.0, .transparency_optimal_damping = true,
                                               .virtual_coupling = true}});
    FAIL() << "two replacements of the same impedance were accepted";
  } catch (const InvalidArgumentError& error) {
    EXPECT_NE(std::string(error.what()).find("impedance.virtual_coupling"), std::string::npos);
  }
}

/// Largest tool speed over the last `ticks` ticks, stepping one tick at a time. Unit: m/s.
double peak_speed(Client& client, int ticks) {
  double peak = 0.0;
  for (int k = 0; k < ticks; ++k) {
    const State s = step_and_get(client, 1);
    peak = std::max(peak, std::sqrt(s.velocity.x * s.velocity.x + s.velocity.y * s.velocity.y +
                                    s.velocity.z * s.velocity.z));
  }
  return peak;
}

// The report's max_stable_stiffness, checked against the server's own wall: a little under it a
// pressed wall settles, a little over it the contact oscillates and keeps bouncing. The law is the
// backward difference, the one the report models; the passivity controller is off, as it would
// mask the difference.
TEST(StabilityReport, TheStiffnessLimitItReportsIsWhereTheServersWallStopsBeingStable) {
  const auto peak_after = [](double stiffness) {
    test::ServerProcess server(test::lockstep_config(R"("passivity": {"enabled": false})"));
    Client client(config_for(server));
    const Impedance impedance{.stiffness = stiffness, .damping = 1.0,
                              .law = ImpedanceLaw::kBackwardDifference};
    auto wall = client.add_wall({.point = {0, 0, 0.02}, .normal = {0, 0, 1}, .impedance = impedance});
    step_and_get(client, 100);  // ramped in, the tool resting on the surface
    client.set_operator(OperatorInput::push({0, 0, -0.5}));
    step_and_get(client, 3000);
    return std::pair{peak_speed(client, 500), wall.stability()};
  };
  // The limit as the server reports it for this wall (any stiffness: it is the report's output).
  const StabilityReport report = peak_after(1000.0).second;
  ASSERT_TRUE(report.device_known);
  const double k_max = report.max_stable_stiffness;
  EXPECT_GT(k_max, 100.0);
  const auto [below, report_below] = peak_after(0.9 * k_max);
  const auto [above, report_above] = peak_after(1.1 * k_max);
  std::printf("  K_max %.1f N/m: peak speed over the last 0.5 s %.3g m/s at 0.9 K_max, %.3g m/s at 1.1 K_max\n",
              k_max, below, above);
  EXPECT_TRUE(report_below.stable);
  EXPECT_FALSE(report_above.stable);
  EXPECT_LT(below, 1e-4);   // settled
  EXPECT_GT(above, 1e-2);   // still bouncing
}

TEST(PassivityController, AStiffWallMadeActiveBySamplingIsCalmedAndAPassiveOneIsLeftAlone) {
  // K = 20 000 N/m on the 10 g point mass at 1 kHz: far beyond the sampled margin, the wall
  // gives back more energy at each bounce than it took (Hannaford & Ryu 2002, Fig. 6).
  const auto bounce = [](bool passivity) {
    test::ServerProcess server(test::lockstep_config(
        std::string(R"("passivity": {"enabled": )") + (passivity ? "true" : "false") + "}"));
    Client client(config_for(server));
    auto wall = client.add_wall({.point = {0, 0, 0.0195}, .normal = {0, 0, 1}, .impedance = {20000.0, 0.0}});
    step_and_get(client, 100);
    client.set_operator(OperatorInput::push({0, 0, -0.5}));
    step_and_get(client, 2000);
    return std::pair{peak_speed(client, 500), client.stats().passivity_active_ticks};
  };
  const auto [without_speed, without_ticks] = bounce(false);
  const auto [with_speed, with_ticks] = bounce(true);
  std::printf("  peak speed over the last 0.5 s: %.3g m/s without, %.3g m/s with the controller "
              "(%llu damped ticks)\n",
              without_speed, with_speed, static_cast<unsigned long long>(with_ticks));
  EXPECT_EQ(without_ticks, 0u);
  EXPECT_GT(with_ticks, 0u);
  EXPECT_GT(without_speed, 0.05);  // still bouncing
  EXPECT_LT(with_speed, 0.2 * without_speed);

  // A wall within its margin (1000 N/m, 1 N·s/m): the controller never acts.
  test::ServerProcess server(test::lockstep_config());
  Client client(config_for(server));
  auto wall = client.add_wall({.point = {0, 0, 0.0195}, .normal = {0, 0, 1}, .impedance = {1000.0, 1.0}});
  step_and_get(client, 100);
  client.set_operator(OperatorInput::push({0, 0, -2.0}));
  step_and_get(client, 2000);
  EXPECT_EQ(client.stats().passivity_active_ticks, 0u);
}

}  // namespace
}  // namespace haptic
