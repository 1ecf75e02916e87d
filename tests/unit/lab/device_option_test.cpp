// haptic-lab's --device: the tool-point mass-damper and loop rate zwidth and transparency take
// from a hapticd configuration (server/lab/device_model.hpp).
#include <gtest/gtest.h>

#include <fstream>
#include <stdexcept>
#include <string>

#include "config/server_config.hpp"
#include "lab/device_model.hpp"

namespace haptic::lab {
namespace {

DeviceModel model_of(const std::string& json) {
  return device_model(config::parse_config(json, "test.json"), "test.json");
}

std::string write_file(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + "/" + name;
  std::ofstream(path) << text;
  return path;
}

TEST(LabDeviceModel, ThePointMassGivesItsOwnMassDamperAndTheLoopRate) {
  const DeviceModel m = model_of(
      R"({"loop_rate_hz": 2000, "simulated_point_mass": {"mass": 0.05, "damping": 0.3}})");
  EXPECT_EQ(m.method, "description");
  EXPECT_DOUBLE_EQ(m.mass, 0.05);
  EXPECT_DOUBLE_EQ(m.damping, 0.3);
  EXPECT_DOUBLE_EQ(m.loop_rate_hz, 2000.0);
  EXPECT_EQ(m.axis, -1);
}

// Madill Table 5.4 at home (q1 = 90°, q2 = 180°): the vertical joint's α2 = 0.026 kg·m² and
// B = 0.009 N·m·s/rad seen at the tip l_f = 0.60 m away (eq. 3.120: ∂z/∂q2 = −l_f cos q2 = l_f)
// give the least damped axis, z: m = α2 / l_f², b = B / l_f².
TEST(LabDeviceModel, TheFiveBarsToolPointModelIsItsJointInertiaThroughTheJacobian_Table5_4) {
  const DeviceModel m = model_of(R"({"simulated_five_bar": {"inertias": "identified"}})");
  EXPECT_EQ(m.method, "jacobian");
  EXPECT_EQ(m.model, "five_bar_003");
  ASSERT_EQ(m.axis, 2);
  EXPECT_NEAR(m.mass, 0.026 / (0.6 * 0.6), 1e-9);
  EXPECT_NEAR(m.damping, 0.009 / (0.6 * 0.6), 1e-9);
  // The axial joint (x): α1 = 0.204 kg·m², B = 0.012 N·m·s/rad at l1 = 0.30 m.
  EXPECT_NEAR(m.axis_mass[0], 0.204 / (0.3 * 0.3), 1e-9);
  EXPECT_NEAR(m.axis_damping[0], 0.012 / (0.3 * 0.3), 1e-9);
  EXPECT_GT(m.axis_damping[1], m.damping);
}

// 004 at θ = Φ = 0 with the shaft at R: a gimbal axis moves the handle R per radian, so it
// weighs I / R²; the shaft carries M_m + M_s = 0.41 kg (Russo L935/L940). No viscous friction.
TEST(LabDeviceModel, TheJoysticksLightestUndampedAxisIsAGimbalAxis) {
  const DeviceModel m = model_of(R"({"simulated_joystick": {"initial_shaft_length": 0.24}})");
  EXPECT_EQ(m.method, "jacobian");
  EXPECT_EQ(m.model, "joystick_004");
  EXPECT_NEAR(m.mass, 2.5e-3 / (0.24 * 0.24), 1e-9);
  EXPECT_EQ(m.damping, 0.0);
  EXPECT_NEAR(m.axis_mass[2], 0.41, 1e-9);
  const DeviceModel longer = model_of(R"({"simulated_joystick": {"initial_shaft_length": 0.30}})");
  EXPECT_LT(longer.mass, m.mass);  // a longer lever arm lightens the gimbal axes as 1/R²
}

// 000's link seen at the tool along its tangent (eq. 3.10): J_eff = J_m + r² J_L / η with the
// maxon RE 40's J_m = 134 g·cm², r = 0.1, η = 0.9 and the 0.2 kg, 0.2 m rod (J_L = m l²/12 +
// m l_c² = 2.667e-3 kg·m²) is 4.3030e-5 kg·m²; the tool moves r l = 0.02 m per motor radian, so
// m = J_eff / (r l)² = 0.10757 kg. B = B_m + k_b k_m / R_m = 3.1470e-3 N·m·s/rad gives 7.8675 N·s/m.
TEST(LabDeviceModel, TheDcMotorGivesItsReflectedInertia_Eq3_10) {
  const DeviceModel m = model_of(R"({"simulated_dc_motor": {}})");
  EXPECT_EQ(m.method, "description");
  // η J_eff / (l r)²: J_eff of eq. 3.10 alone gives 0.107574 kg; a force crossing the gearbox
  // reaches the motor as (r / η) l F (eq. 3.8), so the tool feels η of it.
  EXPECT_NEAR(m.mass, 0.9 * 0.107574, 1e-6);
  EXPECT_NEAR(m.damping, 0.9 * 7.8675, 1e-4);
}

TEST(LabDeviceModel, AnInvalidConfigurationIsRefusedNamingTheFileAndField) {
  v1::ServerConfig config = config::default_config();
  config.set_loop_rate_hz(50.0);  // below the 100 Hz the server accepts
  try {
    device_model(config, "slow.json");
    FAIL() << "accepted a 50 Hz loop";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("slow.json: loop_rate_hz"), std::string::npos) << error.what();
  }
  EXPECT_THROW(device_model_from_file(::testing::TempDir() + "/no_such_config.json"), std::invalid_argument);
}

TEST(LabDeviceArguments, WithoutADeviceNothingChanges) {
  double mass = 1.0, damping = 2.0, period = 3.0;
  EXPECT_FALSE(apply_device_arguments({}, mass, damping, period));
  EXPECT_EQ(mass, 1.0);
  EXPECT_EQ(damping, 2.0);
  EXPECT_EQ(period, 3.0);
}

TEST(LabDeviceArguments, TheDeviceSetsMassDampingAndThePeriodFromTheLoopRate) {
  const std::string path = write_file(
      "lab_device_2k.json", R"({"loop_rate_hz": 2000, "simulated_point_mass": {"mass": 0.05, "damping": 0.3}})");
  double mass = 1.0, damping = 2.0, period = 3.0;
  DeviceArguments arguments;
  arguments.device_path = path;
  const auto model = apply_device_arguments(arguments, mass, damping, period);
  ASSERT_TRUE(model);
  EXPECT_DOUBLE_EQ(mass, 0.05);
  EXPECT_DOUBLE_EQ(damping, 0.3);
  EXPECT_DOUBLE_EQ(period, 5e-4);
  EXPECT_NE(describe(*model).find(path), std::string::npos);

  arguments.period_given = true;  // an explicit --period wins over the loop rate
  period = 2e-3;
  apply_device_arguments(arguments, mass, damping, period);
  EXPECT_DOUBLE_EQ(period, 2e-3);
}

TEST(LabDeviceArguments, MassOrDampingBesideADeviceIsAnErrorNamingBoth) {
  double mass = 1.0, damping = 2.0, period = 3.0;
  DeviceArguments arguments;
  arguments.device_path = "config.json";
  arguments.damping_given = true;
  try {
    apply_device_arguments(arguments, mass, damping, period);
    FAIL() << "accepted --damping beside --device";
  } catch (const std::invalid_argument& error) {
    const std::string what = error.what();
    EXPECT_NE(what.find("--device and --damping"), std::string::npos) << what;
  }
  arguments.mass_given = true;
  try {
    apply_device_arguments(arguments, mass, damping, period);
    FAIL() << "accepted --mass and --damping beside --device";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("--device and --mass and --damping"), std::string::npos);
  }
  EXPECT_EQ(mass, 1.0);  // nothing changed before the error
}

}  // namespace
}  // namespace haptic::lab
