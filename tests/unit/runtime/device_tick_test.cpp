// What every simulated device owes the loop: no heap allocation in a tick (read + write), and no
// NaN ever in a reading it calls good — a non-finite command or plant state is an error, and the
// device then holds its safe state.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "runtime/five_bar_estimator.hpp"
#include "runtime/simulated_dc_motor_device.hpp"
#include "runtime/simulated_device.hpp"
#include "runtime/simulated_dob_device.hpp"
#include "runtime/simulated_five_bar_device.hpp"
#include "runtime/simulated_joystick_device.hpp"
#include "support/allocation_counter.hpp"

namespace haptic::runtime {
namespace {

constexpr double kT = 1e-3;

struct Made {
  std::unique_ptr<Device> device;
  std::function<void(const engine::HandInput&)> set_hand;
};

template <typename D>
Made wrap(std::unique_ptr<D> device) {
  D* raw = device.get();
  return {std::move(device), [raw](const engine::HandInput& hand) { raw->set_hand(hand); }};
}

std::vector<std::pair<std::string, std::function<Made()>>> every_device() {
  return {
      {"point_mass",
       [] {
         return wrap(std::make_unique<SimulatedPointMassDevice>(engine::PointMassParams{},
                                                                engine::PointMassState{}, 20.0));
       }},
      {"dc_motor_000",
       [] {
         return wrap(std::make_unique<SimulatedDcMotorDevice>(
             engine::DcMotorParams{}, engine::DcMotorModel::kWithInductance, 0.5, 5.0,
             engine::IntegrationSettings{}));
       }},
      {"five_bar_003",
       [] {
         auto device = std::make_unique<SimulatedFiveBarDevice>(engine::FiveBarParams{});
         device->set_velocity_estimator(std::make_unique<FiveBarStateEstimators>(kT));
         return wrap(std::move(device));
       }},
      {"five_bar_003",  // with the flexible link (eq. 3.31) on
       [] {
         SimulatedFiveBarOptions options;
         options.plant.flexible_mode = true;
         return wrap(std::make_unique<SimulatedFiveBarDevice>(engine::FiveBarParams{},
                                                              engine::FiveBarState{}, options));
       }},
      {"joystick_004",
       [] { return wrap(std::make_unique<SimulatedJoystickDevice>(SimulatedJoystickConfig{})); }},
      {"parallel_2dof_001",
       [] {
         return wrap(std::make_unique<SimulatedDobDevice>(engine::Parallel2DofParams{},
                                                          engine::DisturbanceObserverParams{},
                                                          engine::Vec3{0.0, 0.25, 0.0}, 10.0));
       }},
  };
}

engine::HandInput sine_push() {
  engine::HandInput hand;
  hand.mode = engine::HandInput::Mode::kApplyForce;
  hand.force = {0.01, 0.01, 0.01};
  hand.profile.shape = engine::ForceProfile::Shape::kSine;
  hand.profile.frequency_hz = 2.0;
  return hand;
}

TEST(EveryDevice, ATickAllocatesNothing) {
  {  // the counter must see an allocation when one happens, or a zero below proves nothing
    test::reset_allocations();
    test::CountAllocations counting;
    auto probe = std::make_unique<int>(7);
    ASSERT_EQ(test::allocations(), 1u);
  }
  for (const auto& [name, make] : every_device()) {
    Made made = make();
    made.set_hand(sine_push());
    DeviceReading reading;
    made.device->read(reading);
    made.device->write({}, kT);  // the first tick adopts the hand input
    test::reset_allocations();
    {
      test::CountAllocations counting;
      for (int k = 0; k < 1000; ++k) {
        made.device->read(reading);
        made.device->write(DeviceCommand{{0.001, -0.001, 0.001}}, kT);
      }
    }
    EXPECT_EQ(test::allocations(), 0u) << name;
    EXPECT_EQ(made.device->description().model, name);
  }
}

TEST(EveryDevice, ANonFiniteCommandIsAnErrorAndNoReadingItCallsGoodHoldsANaN) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const auto& [name, make] : every_device()) {
    Made made = make();
    DeviceReading reading;
    ASSERT_EQ(made.device->read(reading), DeviceStatus::kOk) << name;
    // The command is refused as an error (the loop then goes to its safe state)...
    EXPECT_EQ(made.device->write(DeviceCommand{{nan, 0.0, 0.0}}, kT), DeviceStatus::kError) << name;
    // ...and never reaches the plant: the next reading is good, and finite.
    ASSERT_EQ(made.device->read(reading), DeviceStatus::kOk) << name;
    EXPECT_TRUE(std::isfinite(reading.p_WT.x) && std::isfinite(reading.p_WT.y) &&
                std::isfinite(reading.p_WT.z) && std::isfinite(reading.v_WT.x) &&
                std::isfinite(reading.v_WT.y) && std::isfinite(reading.v_WT.z))
        << name;
    made.device->enter_safe_state();  // must be callable at any time
    EXPECT_EQ(made.device->write(DeviceCommand{}, kT), DeviceStatus::kOk) << name;
  }
}

}  // namespace
}  // namespace haptic::runtime
