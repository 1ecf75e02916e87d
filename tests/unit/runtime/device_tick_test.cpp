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

#include "runtime/cartesian_model.hpp"
#include "runtime/dc_motor_model.hpp"
#include "runtime/device_port.hpp"
#include "runtime/five_bar_estimator.hpp"
#include "runtime/five_bar_model.hpp"
#include "runtime/joystick_model.hpp"
#include "runtime/parallel_dob_model.hpp"
#include "runtime/simulated_dc_motor_device.hpp"
#include "runtime/simulated_point_mass_device.hpp"
#include "runtime/simulated_dob_device.hpp"
#include "runtime/simulated_five_bar_device.hpp"
#include "runtime/simulated_joystick_device.hpp"
#include "support/allocation_counter.hpp"

namespace haptic::runtime {
namespace {

constexpr double kT = 1e-3;

/// A device, its model and the port that drives both at the tool point.
struct Made {
  std::unique_ptr<SimulatedDevice> device;
  std::unique_ptr<DeviceModel> model;
  std::unique_ptr<DevicePort> port;
  void set_hand(const engine::HandInput& hand) const { device->set_hand(hand); }
};

Made made_of(std::unique_ptr<SimulatedDevice> device, std::unique_ptr<DeviceModel> model) {
  auto port = std::make_unique<DevicePort>(*device, *model);
  return {std::move(device), std::move(model), std::move(port)};
}

std::vector<std::pair<std::string, std::function<Made()>>> every_device() {
  return {
      {"point_mass",
       [] {
         return made_of(std::make_unique<SimulatedPointMassDevice>(engine::PointMassParams{},
                                                                   engine::PointMassState{}, 20.0),
                        std::make_unique<CartesianModel>());
       }},
      {"dc_motor_000",
       [] {
         return made_of(std::make_unique<SimulatedDcMotorDevice>(
                            engine::DcMotorParams{}, engine::DcMotorModel::kWithInductance, 0.5, 5.0,
                            engine::IntegrationSettings{}),
                        std::make_unique<DcMotorModel>(engine::DcMotorParams{}, true));
       }},
      {"five_bar_003",
       [] {
         auto model = std::make_unique<FiveBarModel>(engine::FiveBarParams{}, 20.0);
         model->set_velocity_estimator(std::make_unique<FiveBarStateEstimators>(kT));
         return made_of(std::make_unique<SimulatedFiveBarDevice>(engine::FiveBarParams{}),
                        std::move(model));
       }},
      {"five_bar_003",  // with the flexible link (eq. 3.31) on
       [] {
         SimulatedFiveBarOptions options;
         options.plant.flexible_mode = true;
         return made_of(std::make_unique<SimulatedFiveBarDevice>(engine::FiveBarParams{},
                                                                 engine::FiveBarState{}, options),
                        std::make_unique<FiveBarModel>(engine::FiveBarParams{}, 20.0));
       }},
      {"joystick_004",
       [] {
         return made_of(std::make_unique<SimulatedJoystickDevice>(SimulatedJoystickConfig{}),
                        std::make_unique<JoystickModel>(SimulatedJoystickConfig{}.model()));
       }},
      {"parallel_2dof_001",
       [] {
         const engine::Vec3 start{0.0, 0.25, 0.0};
         return made_of(std::make_unique<SimulatedDobDevice>(engine::Parallel2DofParams{}, start, 10.0),
                        std::make_unique<ParallelDobModel>(engine::Parallel2DofParams{},
                                                           engine::DisturbanceObserverParams{}, start));
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
    ToolReading reading;
    made.port->read(reading);
    made.port->write({}, kT);  // the first tick adopts the hand input
    test::reset_allocations();
    {
      test::CountAllocations counting;
      for (int k = 0; k < 1000; ++k) {
        made.port->read(reading);
        made.port->write(ToolCommand{{0.001, -0.001, 0.001}}, kT);
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
    ToolReading reading;
    ASSERT_EQ(made.port->read(reading), DeviceStatus::kOk) << name;
    // The command is refused as an error (the loop then goes to its safe state)...
    EXPECT_EQ(made.port->write(ToolCommand{{nan, 0.0, 0.0}}, kT), DeviceStatus::kError) << name;
    // ...and never reaches the plant: the next reading is good, and finite.
    ASSERT_EQ(made.port->read(reading), DeviceStatus::kOk) << name;
    EXPECT_TRUE(std::isfinite(reading.p_WT.x) && std::isfinite(reading.p_WT.y) &&
                std::isfinite(reading.p_WT.z) && std::isfinite(reading.v_WT.x) &&
                std::isfinite(reading.v_WT.y) && std::isfinite(reading.v_WT.z))
        << name;
    made.port->enter_safe_state();  // must be callable at any time
    EXPECT_EQ(made.port->write(ToolCommand{}, kT), DeviceStatus::kOk) << name;
  }
}

}  // namespace
}  // namespace haptic::runtime
