// A simulated device read through encoders (runtime/encoder_device): the port sees whole counts
// and their difference as the rate, or the device's own rates where it has tachometers; writes
// and the description pass through.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "runtime/encoder_device.hpp"
#include "runtime/simulated_dc_motor_device.hpp"

namespace haptic::runtime {
namespace {

std::unique_ptr<Device> motor() {
  return std::make_unique<SimulatedDcMotorDevice>(engine::DcMotorParams{}, engine::DcMotorModel::kWithoutInductance,
                                                  0.5, 5.0, engine::IntegrationSettings{});
}

TEST(EncoderDevice, ThePortReadsWholeCountsAndTheirDifferenceAsTheRate) {
  EncoderOptions options;
  const double count = 2.0 * 3.141592653589793 / 8000.0;  // a 2,000-line quadrature encoder
  options.encoder.quantization[0] = count;
  options.period_s = 1e-3;
  EncoderDevice device(motor(), options);
  EXPECT_TRUE(device.description().capabilities.quantized_position);
  EXPECT_EQ(device.description().joints, 1u);
  DeviceReading reading;
  ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
  EXPECT_EQ(reading.q_dot[0], 0.0);  // the first reading has no difference
  double last = reading.q[0];
  DeviceCommand command;
  command.tau[0] = 0.05;
  bool moved = false;
  for (int tick = 0; tick < 200; ++tick) {
    ASSERT_EQ(device.write(command, 1e-3), DeviceStatus::kOk);
    ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
    EXPECT_NEAR(reading.q[0] / count, std::round(reading.q[0] / count), 1e-9) << "tick " << tick;
    EXPECT_NEAR(reading.q_dot[0], (reading.q[0] - last) / 1e-3, 1e-9) << "tick " << tick;
    moved = moved || reading.q[0] != last;
    last = reading.q[0];
  }
  EXPECT_TRUE(moved) << "the command drives the motor through the wrapper";
}

TEST(EncoderDevice, WithTachometersTheDevicesOwnRatesStay) {
  EncoderOptions options;
  options.encoder.quantization[0] = 1e-2;
  options.tachometers = true;
  EncoderDevice through(motor(), options);
  auto bare = motor();
  DeviceCommand command;
  command.tau[0] = 0.05;
  DeviceReading a, b;
  for (int tick = 0; tick < 50; ++tick) {
    ASSERT_EQ(through.write(command, 1e-3), DeviceStatus::kOk);
    ASSERT_EQ(bare->write(command, 1e-3), DeviceStatus::kOk);
    ASSERT_EQ(through.read(a), DeviceStatus::kOk);
    ASSERT_EQ(bare->read(b), DeviceStatus::kOk);
    EXPECT_EQ(a.q_dot[0], b.q_dot[0]);
    EXPECT_NEAR(a.q[0], b.q[0], 0.5e-2 + 1e-12);
  }
}

TEST(EncoderDevice, NoiseIsSeededSoALockstepRunRepeats) {
  EncoderOptions options;
  options.encoder.noise[0] = 1e-3;
  options.encoder.seed = 11;
  EncoderDevice first(motor(), options), second(motor(), options);
  DeviceReading a, b;
  double spread = 0.0;
  for (int tick = 0; tick < 20; ++tick) {
    ASSERT_EQ(first.read(a), DeviceStatus::kOk);
    ASSERT_EQ(second.read(b), DeviceStatus::kOk);
    EXPECT_EQ(a.q[0], b.q[0]);
    spread += std::abs(a.q[0] - 0.5 / engine::DcMotorParams{}.r);
  }
  EXPECT_GT(spread, 0.0);
}

}  // namespace
}  // namespace haptic::runtime
