// Which device the scene's objects are designed and validated for when several device ports
// share one scene: the least damped, so a virtual coupling passive on it is passive on every port
// (Colgate: b > K_c T/2 + B_c only gets easier with more b).
#include <gtest/gtest.h>

#include "config/server_config.hpp"
#include "config/devices.hpp"
#include "engine/scene/impedance.hpp"
#include "schema/scene_specs.hpp"

namespace haptic::config {
namespace {

std::vector<PortDevice> devices_of(const std::string& json) {
  v1::ServerConfig config = parse_config(json, "test.json");
  fill_defaults(config);
  return make_devices(config);
}

schema::SceneLimits limits_for(const DesignDevice& design) {
  schema::SceneLimits limits;
  limits.device_mass = design.mass;
  limits.device_damping = design.damping;
  limits.device_unknown_reason = design.unknown_reason;
  return limits;
}

std::string virtual_coupling_error(const schema::SceneLimits& limits, engine::ObjectSpec& spec) {
  v1::Object object;
  object.mutable_half_space()->mutable_normal()->set_z(1.0);
  object.mutable_impedance()->set_virtual_coupling(true);
  return schema::to_object_spec(object, "object", limits, spec);
}

TEST(SixDofDevice, TheRotationMakesThePointMassTurnAndTakeTorques) {
  const std::vector<PortDevice> devices =
      devices_of(R"({"simulated_point_mass": {"rotation": {"inertia": 2e-4, "max_torque": 0.3}}})");
  const runtime::DeviceDescription& six = devices[0].device->description();
  EXPECT_EQ(six.dof, 6u);
  EXPECT_TRUE(six.capabilities.orientation);
  EXPECT_TRUE(six.capabilities.torque);
  EXPECT_EQ(six.max_torque, 0.3);
  EXPECT_EQ(six.apparent_inertia, 2e-4);
  EXPECT_EQ(six.apparent_rotational_damping, 5e-4);
  const std::vector<PortDevice> point_mass = devices_of("{}");
  const runtime::DeviceDescription& three = point_mass[0].device->description();
  EXPECT_EQ(three.dof, 3u);
  EXPECT_FALSE(three.capabilities.torque);
  EXPECT_EQ(three.apparent_inertia, 0.0);
}

TEST(DesignDevice, OnePortIsThatPortsDevice) {
  const DesignDevice design = scene_design_device(devices_of("{}"));
  EXPECT_EQ(design.port, 0);
  EXPECT_EQ(design.mass, 0.01);      // Eom et al.'s point mass
  EXPECT_EQ(design.damping, 0.022);
  EXPECT_EQ(design.unknown_reason, "this one does not");
}

TEST(DesignDevice, TheLeastDampedPortIsTheOneObjectsAreDesignedFor) {
  const std::vector<PortDevice> devices = devices_of(
      R"({"extra_devices": [{"simulated_point_mass": {"damping": 0.05}},
                            {"simulated_point_mass": {"mass": 0.02, "damping": 0.011}}]})");
  const DesignDevice design = scene_design_device(devices);
  EXPECT_EQ(design.port, 2);
  EXPECT_EQ(design.damping, 0.011);
  EXPECT_EQ(design.mass, 0.02);
  EXPECT_NE(design.name.find("port 2's device"), std::string::npos) << design.name;
  // The virtual coupling designed for it is passive on port 2, hence on ports 0 and 1.
  engine::ObjectSpec spec;
  ASSERT_EQ(virtual_coupling_error(limits_for(design), spec), "");
  const double T = 1e-3;
  for (const double b : {0.022, 0.05, 0.011}) {
    EXPECT_GT(b, spec.stiffness * T / 2.0 + spec.damping) << b;  // Colgate, Madill eq. 2.6
  }
  // Port 0's design would not be passive on port 2: the reason for the rule.
  engine::ObjectSpec port0;
  ASSERT_EQ(virtual_coupling_error(limits_for(scene_design_device(devices_of("{}"))), port0), "");
  EXPECT_LT(0.011, port0.stiffness * T / 2.0 + port0.damping);
}

TEST(DesignDevice, APortWithoutAModelMakesItUnknownAndTheErrorNamesThatPort) {
  const DesignDevice design = scene_design_device(
      devices_of(R"({"extra_devices": [{"simulated_joystick": {}}]})"));
  EXPECT_EQ(design.port, -1);
  EXPECT_EQ(design.mass, 0.0);
  engine::ObjectSpec spec;
  const std::string error = virtual_coupling_error(limits_for(design), spec);
  EXPECT_EQ(error.rfind("object.impedance.virtual_coupling: needs a device that gives its damping (port 1's device (", 0), 0u)
      << error;
  EXPECT_NE(error.find("does not, and objects are designed for every port)"), std::string::npos) << error;
}

}  // namespace
}  // namespace haptic::config
