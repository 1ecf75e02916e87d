// Document 003's five-bar as a hapticd device (Madill 1998): the tool force through Jᵀ
// (eq. 3.58), encoder readings (Table 5.2), the conventional velocity (eq. 6.2), the operator's
// hand at the tip, the optional flexible mode (eqs. 3.29–3.31), and faults.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <set>
#include <vector>

#include "runtime/five_bar_model.hpp"
#include "runtime/simulated_five_bar_device.hpp"
#include "support/modelled_device.hpp"

namespace haptic::runtime {
namespace {

constexpr double kT = 1e-3;  // s, the thesis' 1 ms sampling period
constexpr double kPi = std::numbers::pi;

/// The five-bar with its model (FiveBarModel), driven at its tool point.
struct FiveBar : Modelled<SimulatedFiveBarDevice, FiveBarModel> {
  explicit FiveBar(const engine::FiveBarParams& params, const engine::FiveBarState& initial = {},
                   const SimulatedFiveBarOptions& options = {})
      : Modelled(FiveBarModel(params, options.velocity_cutoff), params, initial, options) {}
  /// Puts the plant somewhere else; the estimation starts at rest there.
  void set_plant_state(const engine::FiveBarState& state) {
    device.set_plant_state(state);
    port.restart_estimation();
  }
};

TEST(SimulatedFiveBarDevice, DescribesItselfAsTheBalancedFiveBar_L2380) {
  FiveBar device(engine::FiveBarParams{});
  const DeviceDescription& d = device->description();
  EXPECT_EQ(d.model, "five_bar_003");
  EXPECT_EQ(d.dof, 3u);
  EXPECT_TRUE(d.simulated);
  EXPECT_FALSE(d.capabilities.gravity);
  EXPECT_TRUE(d.capabilities.friction);
  EXPECT_TRUE(d.capabilities.quantized_position);
  EXPECT_FALSE(d.capabilities.flexible_modes);
  EXPECT_FALSE(d.capabilities.state_estimator);
  // The home tip (0.6, 0, 0.3) lies inside the workspace box.
  EXPECT_LT(d.workspace_min.x, 0.6);
  EXPECT_GT(d.workspace_max.x, 0.6);
  EXPECT_LT(d.workspace_min.z, 0.3);
  EXPECT_GT(d.workspace_max.z, 0.3);
}

TEST(SimulatedFiveBarDevice, HoldsStillWithZeroForce_L2380) {
  FiveBar device(engine::FiveBarParams{});
  ToolReading reading;
  ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
  EXPECT_NEAR(reading.p_WT.x, 0.6, 1e-15);
  EXPECT_NEAR(reading.p_WT.z, 0.3, 1e-15);
  const engine::Vec3 start = reading.p_WT;
  for (int k = 0; k < 2000; ++k) {
    ASSERT_EQ(device.write({}, kT), DeviceStatus::kOk);
    ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
  }
  EXPECT_EQ(reading.p_WT, start);
  EXPECT_EQ(reading.v_WT, engine::Vec3{});
}

// At home Jᵀ (F, 0, 0) = (0, −0.3 F, 0): only the axial joint turns, and the tip moves +x with
// α1 q̈1 = −0.3 F + f1 (Table 5.4 friction opposing), i.e. x grows by ½ (0.3 F − f1)/α1 · 0.3 t².
TEST(SimulatedFiveBarDevice, ForceAlongXMovesTheTipAsJacobianTransposeSays_Eq3_58) {
  const engine::FiveBarParams p;
  FiveBar device(p);
  const double F = 2.0, t = 0.2;
  for (int k = 0; k < 200; ++k) ASSERT_EQ(device.write({{F, 0.0, 0.0}}, kT), DeviceStatus::kOk);
  const engine::FiveBarState& s = device->plant().state();
  const engine::FiveBarJoints home = engine::five_bar_home();
  EXPECT_EQ(s.q[0], home[0]);
  EXPECT_EQ(s.q[2], home[2]);
  const double dq1 = -0.5 * (p.l1 * F - p.friction[1].coulomb) / p.alpha1 * t * t;
  EXPECT_NEAR(s.q[1] - home[1], dq1, 0.02 * std::abs(dq1));  // viscous B t / α1 ≈ 1 %
  ToolReading reading;
  ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
  const double count_at_tip = p.l1 * kPi / 6000.0;
  EXPECT_NEAR(reading.p_WT.x - 0.6, p.l1 * std::sin(-dq1), 0.02 * p.l1 * std::abs(dq1) + count_at_tip);
  EXPECT_NEAR(reading.p_WT.y, 0.0, 1e-15);
  EXPECT_GT(reading.v_WT.x, 0.0);  // the filtered backward difference sees it moving
  EXPECT_NEAR(reading.v_WT.y, 0.0, 1e-15);
}

// The operator pushing up at the tip drives only the vertical joint at home (Jᵀ (0, 0, F) =
// (0, 0, 0.6 F)); a 1 N push is well above q2's 0.082 N·m Coulomb friction.
TEST(SimulatedFiveBarDevice, OperatorForceActsAtTheTipThroughJacobianTranspose_Eq3_58) {
  FiveBar device(engine::FiveBarParams{});
  engine::HandInput hand;
  hand.mode = engine::HandInput::Mode::kApplyForce;
  hand.force = {0.0, 0.0, 1.0};
  device->set_hand(hand);
  for (int k = 0; k < 100; ++k) ASSERT_EQ(device.write({}, kT), DeviceStatus::kOk);
  const engine::FiveBarState& s = device->plant().state();
  EXPECT_EQ(s.q[0], engine::five_bar_home()[0]);
  EXPECT_EQ(s.q[1], engine::five_bar_home()[1]);
  EXPECT_GT(s.qdot[2], 0.0);
  ToolReading reading;
  ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
  EXPECT_GT(reading.p_WT.z, 0.3);
  // A push of 0.1 N (0.06 N·m at q2) stays under the friction: nothing moves.
  FiveBar weak(engine::FiveBarParams{});
  hand.force = {0.0, 0.0, 0.1};
  weak->set_hand(hand);
  for (int k = 0; k < 100; ++k) ASSERT_EQ(weak.write({}, kT), DeviceStatus::kOk);
  EXPECT_EQ(weak->plant().state().q[2], engine::five_bar_home()[2]);
}

// Table 5.2: with the encoders on, a motion smaller than a count does not show; without them
// the reading is the true tip.
TEST(SimulatedFiveBarDevice, ReadsThroughTheEncodersWhenQuantized_Table5_2) {
  engine::FiveBarState moved;
  moved.q[1] -= 0.3 * kPi / 6000.0;  // a third of an axial count
  FiveBar quantized(engine::FiveBarParams{}, moved);
  SimulatedFiveBarOptions options;
  options.quantized = false;
  FiveBar exact(engine::FiveBarParams{}, moved, options);
  EXPECT_FALSE(exact->description().capabilities.quantized_position);
  ToolReading a, b;
  ASSERT_EQ(quantized.read(a), DeviceStatus::kOk);
  ASSERT_EQ(exact.read(b), DeviceStatus::kOk);
  EXPECT_NEAR(a.p_WT.x, 0.6, 1e-15);  // still the home count
  EXPECT_NEAR(b.p_WT.x - 0.6, 0.3 * std::sin(0.3 * kPi / 6000.0), 1e-12);
  // The axial scale is negative (−π/6000, L3150): counts floor in the joint's negative direction,
  // so in the positive one the reading rounds up: 1.01 counts read as 2, 0.99 as 1.
  moved.q[1] = engine::five_bar_home()[1] + 1.01 * kPi / 6000.0;
  quantized.set_plant_state(moved);
  EXPECT_NEAR(quantized->measured_joints()[1] - engine::five_bar_home()[1], 2.0 * kPi / 6000.0, 1e-12);
  moved.q[1] = engine::five_bar_home()[1] + 0.99 * kPi / 6000.0;
  quantized.set_plant_state(moved);
  EXPECT_NEAR(quantized->measured_joints()[1] - engine::five_bar_home()[1], kPi / 6000.0, 1e-12);
  ASSERT_EQ(quantized.read(a), DeviceStatus::kOk);
  EXPECT_NEAR(a.p_WT.x - 0.6, -0.3 * std::sin(kPi / 6000.0), 1e-12);
}

TEST(SimulatedFiveBarDevice, NoiseBeforeTheCountsMakesACountFlickerOnlyNearItsStep) {
  // At rest a tenth of a count from a step, with noise of a tenth of a count: the reading is
  // always a whole count, and it flickers between the two counts either side of the step. Half a
  // count from it, the same noise never reaches the step. The same seed, the same readings.
  const double count = kPi / 6000.0;
  SimulatedFiveBarOptions options;
  options.encoder_noise = {0.0, 0.1 * count, 0.0};
  options.noise_seed = 5;
  const auto readings = [&](double offset_counts) {
    engine::FiveBarState at;
    at.q[1] = engine::five_bar_home()[1] - offset_counts * count;  // the axial scale is negative
    FiveBar device(engine::FiveBarParams{}, at, options);
    std::vector<double> seen;
    for (int k = 0; k < 400; ++k) {
      EXPECT_EQ(device->write(DeviceCommand{}, kT), DeviceStatus::kOk);
      seen.push_back((device->measured_joints()[1] - engine::five_bar_home()[1]) / count);
    }
    return seen;
  };
  const std::vector<double> near = readings(0.05), far = readings(0.5);
  for (const double c : near) EXPECT_NEAR(c, std::round(c), 1e-9) << "a whole count";
  std::set<long> near_counts, far_counts;
  for (const double c : near) near_counts.insert(std::lround(c));
  for (const double c : far) far_counts.insert(std::lround(c));
  EXPECT_EQ(near_counts.size(), 2u) << "the count flickers across the step";
  EXPECT_EQ(far_counts.size(), 1u) << "five sigma from the step it does not";
  EXPECT_EQ(readings(0.05), near);
}

// The flexible mode is declared, and the reading stays the encoders' rigid tip while the hand
// pushes the physical tip sideways: the difference is exactly link 5's deflection φ1(l) η n.
TEST(SimulatedFiveBarDevice, FlexibleModeIsDeclaredAndTheReadingIsTheEncodersRigidTip_Eq3_31) {
  SimulatedFiveBarOptions options;
  options.plant.flexible_mode = true;
  FiveBar device(engine::FiveBarParams{}, {}, options);
  EXPECT_TRUE(device->description().capabilities.flexible_modes);
  engine::HandInput hand;
  hand.mode = engine::HandInput::Mode::kApplyForce;
  hand.force = {0.0, 2.0, 0.0};  // sideways at home: 1.2 N·m about q0, above its friction
  device->set_hand(hand);
  for (int k = 0; k < 100; ++k) ASSERT_EQ(device.write({}, kT), DeviceStatus::kOk);
  ToolReading reading;
  ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
  const engine::FiveBarParams p;
  EXPECT_EQ(reading.p_WT, engine::five_bar_tip_position(p, device->measured_joints()));
  engine::Vec3 p_physical, v_physical;
  device->plant().physical_tip_state(p_physical, v_physical);
  const engine::Vec3 p_rigid = engine::five_bar_tip_position(p, device->plant().state().q);
  const double q0 = device->plant().state().q[0];
  const double deflection = options.plant.mode.tip_shape * device->plant().mode_state().eta;
  const engine::Vec3 bend = p_physical - p_rigid;
  EXPECT_NEAR(bend.x, -deflection * std::sin(q0), 1e-15);
  EXPECT_NEAR(bend.y, deflection * std::cos(q0), 1e-15);
  EXPECT_EQ(bend.z, 0.0);
  // Pushed from the tip, the link bends ahead of the hub (≈ φ1(l)² F / (ρω1²) ≈ 2 mm at 2 N).
  EXPECT_GT(deflection, 5e-4);
  EXPECT_GT(q0, 0.0);
  // set_plant_state puts the mode at rest again.
  device.set_plant_state({});
  EXPECT_EQ(device->plant().mode_state().eta, 0.0);
  EXPECT_EQ(device->plant().mode_state().eta_dot, 0.0);
}

// Mode off (the default) is the rigid device: the same readings, tick for tick, as one built with
// the option spelled out and the mode's parameters changed.
TEST(SimulatedFiveBarDevice, FlexibleModeOffIsTheRigidDevice) {
  SimulatedFiveBarOptions off;
  off.plant.flexible_mode = false;
  off.plant.mode.omega = 100.0;
  FiveBar rigid(engine::FiveBarParams{});
  FiveBar explicit_off(engine::FiveBarParams{}, {}, off);
  EXPECT_FALSE(explicit_off->description().capabilities.flexible_modes);
  engine::HandInput hand;
  hand.mode = engine::HandInput::Mode::kApplyForce;
  hand.force = {1.0, 2.0, 1.5};
  rigid->set_hand(hand);
  explicit_off->set_hand(hand);
  ToolReading a, b;
  for (int k = 0; k < 200; ++k) {
    ASSERT_EQ(rigid.write({{0.5, -0.5, 0.2}}, kT), DeviceStatus::kOk);
    ASSERT_EQ(explicit_off.write({{0.5, -0.5, 0.2}}, kT), DeviceStatus::kOk);
    ASSERT_EQ(rigid.read(a), DeviceStatus::kOk);
    ASSERT_EQ(explicit_off.read(b), DeviceStatus::kOk);
    ASSERT_EQ(a.p_WT, b.p_WT);
    ASSERT_EQ(a.v_WT, b.v_WT);
  }
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(rigid->plant().state().q[i], explicit_off->plant().state().q[i]);
    EXPECT_EQ(rigid->plant().state().qdot[i], explicit_off->plant().state().qdot[i]);
  }
}

class ConstantVelocity final : public FiveBarVelocityEstimator {
 public:
  void reset(const engine::FiveBarJoints&) override { resets++; }
  engine::FiveBarJoints update(const engine::FiveBarJoints&, const engine::FiveBarJoints& tau,
                               const engine::FiveBarJoints&, double) override {
    last_tau = tau;
    return {1.0, 0.0, 0.0};
  }
  int resets = 0;
  engine::FiveBarJoints last_tau{};
};

TEST(SimulatedFiveBarDevice, VelocityEstimatorHookReplacesTheDifference_Eq6_5) {
  SimulatedFiveBarOptions options;
  options.state_estimator = true;
  FiveBar device(engine::FiveBarParams{}, {}, options);
  EXPECT_TRUE(device->description().capabilities.state_estimator);
  auto owned = std::make_unique<ConstantVelocity>();
  ConstantVelocity* estimator = owned.get();
  device.model.set_velocity_estimator(std::move(owned));
  ToolReading reading;
  ASSERT_EQ(device.read(reading), DeviceStatus::kOk);  // the first estimate starts it at rest
  EXPECT_EQ(estimator->resets, 1);
  ASSERT_EQ(device.write({{20.0, 0.0, 0.0}}, kT), DeviceStatus::kOk);
  ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
  // It is fed the saturated torque: Jᵀ (20, 0, 0) = (0, −6, 0), inside the 7.22 N·m limit…
  EXPECT_NEAR(estimator->last_tau[1], -6.0, 1e-12);
  ASSERT_EQ(device.write({{40.0, 0.0, 0.0}}, kT), DeviceStatus::kOk);
  ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
  EXPECT_NEAR(estimator->last_tau[1], -0.373 * 3.87 * 5.0, 1e-12);  // …and clipped beyond (L3237)
  // q̇ = (1, 0, 0) at (nearly) home: v = J col 0 = (−ρ S0, ρ C0, 0) ≈ (0, 0.6, 0).
  EXPECT_NEAR(reading.v_WT.y, 0.6, 1e-3);
  EXPECT_EQ(estimator->resets, 1);
  device.model.set_velocity_estimator(nullptr);
  EXPECT_FALSE(device.model.has_velocity_estimator());
}

TEST(SimulatedFiveBarDevice, NonFiniteCommandOrStateIsAnError) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  FiveBar device(engine::FiveBarParams{});
  EXPECT_EQ(device.write({{nan, 0.0, 0.0}}, kT), DeviceStatus::kError);
  // The bad command was not applied: the device is still at rest and reads fine.
  ToolReading reading;
  EXPECT_EQ(device.read(reading), DeviceStatus::kOk);
  EXPECT_NEAR(reading.p_WT.x, 0.6, 1e-15);
  EXPECT_EQ(device.write({{0.0, std::numeric_limits<double>::infinity(), 0.0}}, kT),
            DeviceStatus::kError);
  EXPECT_EQ(device.write({}, kT), DeviceStatus::kOk);

  engine::FiveBarState broken;
  broken.qdot[1] = nan;
  device.set_plant_state(broken);
  EXPECT_EQ(device.read(reading), DeviceStatus::kError);
  EXPECT_EQ(device.write({}, kT), DeviceStatus::kError);
}

}  // namespace
}  // namespace haptic::runtime
