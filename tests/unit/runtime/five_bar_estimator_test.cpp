// The five-bar device's velocity from Madill's non-linear state estimator on each joint
// (runtime/five_bar_estimator, ch. 6.3) against the conventional backward difference, on the same
// quantized device under the same operator.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>

#include "runtime/five_bar_estimator.hpp"
#include "runtime/simulated_five_bar_device.hpp"
#include "support/modelled_device.hpp"

namespace haptic::runtime {
namespace {

constexpr double kT = 1e-3;  // s

TEST(FiveBarStateEstimators, TheAxialJointIsTheThesisDesign_L3129) {
  const FiveBarStateEstimators estimators(kT);
  EXPECT_NEAR(estimators.joint(1).gain().v0, 14.4, 0.5e-2 * 14.4);
  EXPECT_NEAR(estimators.joint(1).gain().v1, 99.2, 0.5e-2 * 99.2);
  // The other joints: the same weights on their own Table 5.4 inertia (a heavier hub is slower).
  EXPECT_EQ(five_bar_estimator_params(0, kT).inertia, 0.733);
  EXPECT_EQ(five_bar_estimator_params(2, kT).inertia, 0.026);
  EXPECT_NEAR(five_bar_estimator_params(2, kT).friction_coulomb, 0.082 * 0.061 / 0.088, 1e-12);
  for (int j = 0; j < 3; ++j) {
    EXPECT_EQ(five_bar_estimator_params(j, kT).validate(), "") << j;
  }
}

/// RMS error of the device's reported tip velocity against the plant's true one, over 4 s of a
/// hand pushing with a 1 Hz sine of `amplitude` (N per axis) through the quantized encoders.
/// Unit: m/s.
double velocity_rms_error(bool estimator, double amplitude) {
  Modelled<SimulatedFiveBarDevice, FiveBarModel> device(FiveBarModel(engine::FiveBarParams{}, 20.0),
                                                        engine::FiveBarParams{});
  if (estimator) device.model.set_velocity_estimator(std::make_unique<FiveBarStateEstimators>(kT));
  engine::HandInput hand;
  hand.mode = engine::HandInput::Mode::kApplyForce;
  hand.force = {amplitude, amplitude, amplitude};
  hand.profile.shape = engine::ForceProfile::Shape::kSine;
  hand.profile.frequency_hz = 1.0;
  device->set_hand(hand);
  double sum = 0.0;
  int n = 0;
  for (int k = 0; k < 4000; ++k) {
    device.write({}, kT);
    ToolReading reading;
    EXPECT_EQ(device.read(reading), DeviceStatus::kOk);
    engine::Vec3 p_true, v_true;
    device->plant().tip_state(device->plant().state(), p_true, v_true);
    if (k >= 500) {  // after the start-up transient
      sum += std::pow(engine::norm(reading.v_WT - v_true), 2);
      ++n;
    }
  }
  return std::sqrt(sum / n);
}

TEST(FiveBarStateEstimators, ReportTheTipVelocityBetterThanTheBackwardDifference_Fig6_13) {
  // A brisk push (tip speeds up to ≈ 1 m/s): the difference's low-pass lags, the estimator
  // follows the dynamics.
  const double difference = velocity_rms_error(false, 1.0);
  const double estimated = velocity_rms_error(true, 1.0);
  std::printf("  1 N push: tip velocity RMS error, backward difference %.3g m/s, estimator %.3g m/s\n",
              difference, estimated);
  EXPECT_LT(estimated, 0.2 * difference);
  // A gentle push in stick-slip (0.2 N: the horizontal and axial joints stay stuck): the
  // estimator's smooth friction (0.061/0.088 of the identified, as the thesis tuned the axial
  // joint) lets it believe the stuck joints creep, and it is no better than the difference —
  // the thesis' own observation that the estimate runs ahead of the joint (L3211).
  const double slow_difference = velocity_rms_error(false, 0.2);
  const double slow_estimated = velocity_rms_error(true, 0.2);
  std::printf("  0.2 N push: backward difference %.3g m/s, estimator %.3g m/s\n", slow_difference,
              slow_estimated);
  EXPECT_LT(slow_estimated, 3.0 * slow_difference);  // bounded, not better
}

}  // namespace
}  // namespace haptic::runtime
