// The Force Dimension stand-in (libdrd.so.3 from fake_forcedimension.cpp) tested on its own, the
// way a driver uses it: dlopen the built file, dlsym each function, call it through a pointer of
// the declared type. Each test starts from `reset` with its own FAKE_DHD_DEVICES.
#include <dlfcn.h>
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <string>
#include <thread>

#include "fake_forcedimension.hpp"

namespace {

using namespace fake_dhd;

// Every function the test calls, resolved once.
struct Api {
  void* handle = nullptr;
  dhdGetDeviceCount_t dhdGetDeviceCount;
  dhdGetAvailableCount_t dhdGetAvailableCount;
  dhdOpen_t dhdOpen;
  dhdOpenID_t dhdOpenID;
  dhdOpenSerial_t dhdOpenSerial;
  dhdClose_t dhdClose;
  dhdSetDevice_t dhdSetDevice;
  dhdGetDeviceID_t dhdGetDeviceID;
  dhdGetSystemType_t dhdGetSystemType;
  dhdGetSystemName_t dhdGetSystemName;
  dhdGetSerialNumber_t dhdGetSerialNumber;
  dhdGetSDKVersion_t dhdGetSDKVersion;
  dhdEnableForce_t dhdEnableForce;
  dhdSetGravityCompensation_t dhdSetGravityCompensation;
  dhdSetBrakes_t dhdSetBrakes;
  dhdStop_t dhdStop;
  dhdGetPosition_t dhdGetPosition;
  dhdGetLinearVelocity_t dhdGetLinearVelocity;
  dhdGetOrientationFrame_t dhdGetOrientationFrame;
  dhdGetAngularVelocityRad_t dhdGetAngularVelocityRad;
  dhdGetGripperAngleRad_t dhdGetGripperAngleRad;
  dhdGetButtonMask_t dhdGetButtonMask;
  dhdGetButton_t dhdGetButton;
  dhdSetForce_t dhdSetForce;
  dhdSetForceAndTorque_t dhdSetForceAndTorque;
  dhdSetForceAndTorqueAndGripperForce_t dhdSetForceAndTorqueAndGripperForce;
  dhdHasWrist_t dhdHasWrist;
  dhdHasActiveWrist_t dhdHasActiveWrist;
  dhdHasGripper_t dhdHasGripper;
  dhdHasActiveGripper_t dhdHasActiveGripper;
  dhdIsLeftHanded_t dhdIsLeftHanded;
  dhdGetStatus_t dhdGetStatus;
  dhdErrorGetLast_t dhdErrorGetLast;
  dhdErrorGetLastStr_t dhdErrorGetLastStr;
  dhdErrorGetStr_t dhdErrorGetStr;
  dhdGetTime_t dhdGetTime;
  drdIsSupported_t drdIsSupported;
  drdIsInitialized_t drdIsInitialized;
  drdAutoInit_t drdAutoInit;
  drdStop_t drdStop;
  drdOpenID_t drdOpenID;
  drdClose_t drdClose;
  fake_dhd_control_t fake_dhd_control;
  fake_dhd_calls_t fake_dhd_calls;
  fake_dhd_clear_calls_t fake_dhd_clear_calls;
  fake_dhd_blocked_t fake_dhd_blocked;
};

template <typename Fn>
void resolve(void* handle, Fn& fn, const char* name) {
  fn = reinterpret_cast<Fn>(dlsym(handle, name));
  if (!fn) ADD_FAILURE() << "libdrd.so.3 lacks " << name;
}

#define RESOLVE(fn) resolve(api.handle, api.fn, #fn)

Api load() {
  Api api;
  api.handle = dlopen(FAKE_FORCEDIMENSION_LIBRARY, RTLD_NOW);
  if (!api.handle) {
    ADD_FAILURE() << "dlopen: " << dlerror();
    return api;
  }
  RESOLVE(dhdGetDeviceCount);
  RESOLVE(dhdGetAvailableCount);
  RESOLVE(dhdOpen);
  RESOLVE(dhdOpenID);
  RESOLVE(dhdOpenSerial);
  RESOLVE(dhdClose);
  RESOLVE(dhdSetDevice);
  RESOLVE(dhdGetDeviceID);
  RESOLVE(dhdGetSystemType);
  RESOLVE(dhdGetSystemName);
  RESOLVE(dhdGetSerialNumber);
  RESOLVE(dhdGetSDKVersion);
  RESOLVE(dhdEnableForce);
  RESOLVE(dhdSetGravityCompensation);
  RESOLVE(dhdSetBrakes);
  RESOLVE(dhdStop);
  RESOLVE(dhdGetPosition);
  RESOLVE(dhdGetLinearVelocity);
  RESOLVE(dhdGetOrientationFrame);
  RESOLVE(dhdGetAngularVelocityRad);
  RESOLVE(dhdGetGripperAngleRad);
  RESOLVE(dhdGetButtonMask);
  RESOLVE(dhdGetButton);
  RESOLVE(dhdSetForce);
  RESOLVE(dhdSetForceAndTorque);
  RESOLVE(dhdSetForceAndTorqueAndGripperForce);
  RESOLVE(dhdHasWrist);
  RESOLVE(dhdHasActiveWrist);
  RESOLVE(dhdHasGripper);
  RESOLVE(dhdHasActiveGripper);
  RESOLVE(dhdIsLeftHanded);
  RESOLVE(dhdGetStatus);
  RESOLVE(dhdErrorGetLast);
  RESOLVE(dhdErrorGetLastStr);
  RESOLVE(dhdErrorGetStr);
  RESOLVE(dhdGetTime);
  RESOLVE(drdIsSupported);
  RESOLVE(drdIsInitialized);
  RESOLVE(drdAutoInit);
  RESOLVE(drdStop);
  RESOLVE(drdOpenID);
  RESOLVE(drdClose);
  RESOLVE(fake_dhd_control);
  RESOLVE(fake_dhd_calls);
  RESOLVE(fake_dhd_clear_calls);
  RESOLVE(fake_dhd_blocked);
  return api;
}

// Displacement of a mass m with viscous damping b, from rest, under a constant force F for t.
double mass_damper_x(double F, double m, double b, double t) {
  return F / b * (t - m / b * (1.0 - std::exp(-b * t / m)));
}
double mass_damper_v(double F, double m, double b, double t) {
  return F / b * (1.0 - std::exp(-b * t / m));
}

struct Position {
  double x = NAN, y = NAN, z = NAN;
};

class FakeForceDimension : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (!api_) api_ = new Api(load());  // once per process, kept to the end
  }

  // Every test starts from a fresh stand-in with `devices` attached and no script.
  void attach(const char* devices, const char* script = nullptr) {
    ASSERT_NE(api_->handle, nullptr);
    if (devices)
      setenv("FAKE_DHD_DEVICES", devices, 1);
    else
      unsetenv("FAKE_DHD_DEVICES");
    if (script)
      setenv("FAKE_DHD_SCRIPT", script, 1);
    else
      unsetenv("FAKE_DHD_SCRIPT");
    ASSERT_EQ(api_->fake_dhd_control("reset"), 0);
  }

  int control(const std::string& command) { return api_->fake_dhd_control(command.c_str()); }

  Position position(char id) {
    Position p;
    EXPECT_EQ(api_->dhdGetPosition(&p.x, &p.y, &p.z, id), 0);
    return p;
  }

  // Opens `id`, calibrates it the way CHAI3D does (drdAutoInit, drdStop(true)) and enables forces.
  void open_ready(char id) {
    ASSERT_EQ(api_->drdOpenID(id), id);
    if (!api_->drdIsInitialized(id)) {
      ASSERT_EQ(api_->drdAutoInit(id), 0);
    }
    ASSERT_EQ(api_->drdStop(true, id), 0);
    ASSERT_EQ(api_->dhdEnableForce(DHD_ON, id), 0);
  }

  static Api* api_;
};

Api* FakeForceDimension::api_ = nullptr;

TEST_F(FakeForceDimension, DlopenOfTheSamePathGivesTheSameInstance) {
  attach("omega.3");
  void* again = dlopen(FAKE_FORCEDIMENSION_LIBRARY, RTLD_NOW);
  ASSERT_EQ(again, api_->handle);
  auto open_id = reinterpret_cast<dhdOpenID_t>(dlsym(again, "dhdOpenID"));
  EXPECT_EQ(open_id(0), 0);
  EXPECT_EQ(api_->dhdGetDeviceID(), 0);  // the open made through the second handle shows here
  dlclose(again);
}

TEST_F(FakeForceDimension, TheDevicesAreThoseOfFakeDhdDevices) {
  attach("omega.7, falcon,sigma.7");
  const Api& a = *api_;
  ASSERT_EQ(a.dhdGetDeviceCount(), 3);
  EXPECT_EQ(a.dhdGetAvailableCount(), 3);
  EXPECT_EQ(a.dhdGetDeviceID(), -1);  // nothing open yet

  EXPECT_EQ(a.dhdOpenID(0), 0);
  EXPECT_EQ(a.dhdOpenID(1), 1);
  EXPECT_EQ(a.dhdOpenID(2), 2);
  EXPECT_EQ(a.dhdGetAvailableCount(), 0);

  EXPECT_EQ(a.dhdGetSystemType(0), DHD_DEVICE_OMEGA7_RIGHT);
  EXPECT_EQ(a.dhdGetSystemType(1), DHD_DEVICE_FALCON);
  EXPECT_EQ(a.dhdGetSystemType(2), DHD_DEVICE_SIGMA7_RIGHT);
  EXPECT_STREQ(a.dhdGetSystemName(0), "omega.7");
  EXPECT_STREQ(a.dhdGetSystemName(1), "falcon");
  EXPECT_STREQ(a.dhdGetSystemName(2), "sigma.7");

  ushort sn = 0;
  EXPECT_EQ(a.dhdGetSerialNumber(&sn, 0), 0);
  EXPECT_EQ(sn, 1001);
  EXPECT_EQ(a.dhdGetSerialNumber(&sn, 1), 0);
  EXPECT_EQ(sn, 65535);  // the Falcon (SOURCES.md §1.6)
  EXPECT_EQ(a.dhdGetSerialNumber(&sn, 2), 0);
  EXPECT_EQ(sn, 1003);

  // omega.7: passive wrist, active gripper; falcon: neither; sigma.7: both active.
  EXPECT_TRUE(a.dhdHasWrist(0));
  EXPECT_FALSE(a.dhdHasActiveWrist(0));
  EXPECT_TRUE(a.dhdHasGripper(0));
  EXPECT_TRUE(a.dhdHasActiveGripper(0));
  EXPECT_FALSE(a.dhdHasWrist(1));
  EXPECT_FALSE(a.dhdHasGripper(1));
  EXPECT_TRUE(a.dhdHasActiveWrist(2));
  EXPECT_TRUE(a.dhdHasActiveGripper(2));

  // Buttons: four on the Falcon, one elsewhere.
  EXPECT_EQ(control("button 1 0xff"), 0);
  EXPECT_EQ(a.dhdGetButtonMask(1), 0xfu);
  EXPECT_EQ(a.dhdGetButton(3, 1), 1);
  EXPECT_EQ(control("button 0 3"), 0);
  EXPECT_EQ(a.dhdGetButtonMask(0), 1u);
  EXPECT_EQ(a.dhdGetButton(40, 0), -1);
  EXPECT_EQ(a.dhdErrorGetLast(), DHD_ERROR_INVALID_INDEX);

  int major = 0, minor = 0, release = 0, revision = -1;
  a.dhdGetSDKVersion(&major, &minor, &release, &revision);
  EXPECT_EQ(major * 10000 + minor * 100 + release, 31705);
  EXPECT_EQ(revision, 0);
}

TEST_F(FakeForceDimension, WithoutFakeDhdDevicesThereIsOneOmega3AndUnknownNamesAreLeftOut) {
  attach(nullptr);
  EXPECT_EQ(api_->dhdGetDeviceCount(), 1);
  EXPECT_EQ(api_->dhdOpen(), 0);
  EXPECT_EQ(api_->dhdGetSystemType(-1), DHD_DEVICE_OMEGA3);

  attach("omega.3,not.a.device,delta.3");
  EXPECT_EQ(api_->dhdGetDeviceCount(), 2);
  EXPECT_EQ(api_->dhdOpenID(1), 1);
  EXPECT_EQ(api_->dhdGetSystemType(1), DHD_DEVICE_DELTA3);

  attach("");
  EXPECT_EQ(api_->dhdGetDeviceCount(), 0);
  EXPECT_EQ(api_->dhdOpen(), -1);
  EXPECT_EQ(api_->dhdErrorGetLast(), DHD_ERROR_NO_DEVICE_FOUND);
}

TEST_F(FakeForceDimension, OpeningReturnsTheIdAndMakesItTheDefault) {
  attach("omega.3,delta.3");
  const Api& a = *api_;
  EXPECT_EQ(a.dhdOpenID(5), -1);
  EXPECT_EQ(a.dhdErrorGetLast(), DHD_ERROR_NO_DEVICE_FOUND);
  EXPECT_STREQ(a.dhdErrorGetLastStr(), a.dhdErrorGetStr(DHD_ERROR_NO_DEVICE_FOUND));
  EXPECT_EQ(a.dhdGetSystemType(-1), -1);  // no default device yet
  EXPECT_EQ(a.dhdErrorGetLast(), DHD_ERROR_NO_DEVICE_FOUND);

  EXPECT_EQ(a.dhdOpen(), 0);
  EXPECT_EQ(a.dhdGetDeviceID(), 0);
  EXPECT_EQ(a.dhdOpen(), 1);
  EXPECT_EQ(a.dhdGetDeviceID(), 1);
  EXPECT_EQ(a.dhdGetSystemType(-1), DHD_DEVICE_DELTA3);  // -1 = the default device
  EXPECT_EQ(a.dhdOpen(), -1);                            // none left
  EXPECT_EQ(a.dhdErrorGetLast(), DHD_ERROR_NO_DEVICE_FOUND);

  EXPECT_EQ(a.dhdSetDevice(0), 0);
  EXPECT_EQ(a.dhdGetSystemType(-1), DHD_DEVICE_OMEGA3);
  EXPECT_EQ(a.dhdOpenSerial(1002), 1);  // already open: its ID again, and it becomes the default
  EXPECT_EQ(a.dhdGetDeviceID(), 1);
  EXPECT_EQ(a.dhdOpenSerial(4242), -1);
  EXPECT_EQ(a.dhdErrorGetLast(), DHD_ERROR_NO_DEVICE_FOUND);

  EXPECT_EQ(a.dhdClose(1), 0);
  EXPECT_EQ(a.dhdGetDeviceID(), 0);  // the default moves to a device still open
  EXPECT_EQ(a.dhdGetSystemType(1), -1);
  EXPECT_EQ(a.dhdErrorGetLast(), DHD_ERROR_INVALID_INDEX);
  EXPECT_EQ(a.dhdSetDevice(1), -1);
  EXPECT_EQ(a.dhdErrorGetLast(), DHD_ERROR_INVALID_INDEX);
  EXPECT_EQ(a.drdClose(0), 0);
  EXPECT_EQ(a.dhdGetDeviceID(), -1);
}

TEST_F(FakeForceDimension, AForceAlongXMovesTheEffectorAsTheMassDamperPredicts) {
  for (const char* model : {"omega.3", "falcon"}) {
    SCOPED_TRACE(model);
    attach(model);
    open_ready(0);
    const double m = std::string(model) == "falcon" ? 0.1 : 0.2, b = 2.0, F = 1.0;
    for (int i = 0; i < 100; ++i) ASSERT_EQ(api_->dhdSetForce(F, 0, 0, 0), 0);
    const Position p = position(0);
    const double expected = mass_damper_x(F, m, b, 0.1);
    EXPECT_NEAR(p.x, expected, 0.01 * expected);
    EXPECT_GT(p.x, 0.01);
    EXPECT_EQ(p.y, 0.0);
    EXPECT_EQ(p.z, 0.0);
    double vx = 0, vy = 0, vz = 0;
    ASSERT_EQ(api_->dhdGetLinearVelocity(&vx, &vy, &vz, 0), 0);
    EXPECT_NEAR(vx, mass_damper_v(F, m, b, 0.1), 0.01 * mass_damper_v(F, m, b, 0.1));
  }
}

TEST_F(FakeForceDimension, DtIsChangeableAndTheHandForceActsWithForcesOff) {
  attach("falcon");
  ASSERT_EQ(api_->dhdOpenID(0), 0);
  ASSERT_EQ(control("dt 0.0005"), 0);
  ASSERT_EQ(control("hand 0 0 -1 0"), 0);  // forces off: only the hand (and gravity) move it
  for (int i = 0; i < 200; ++i) ASSERT_EQ(api_->dhdSetForce(5, 0, 0, 0), 0);
  const Position p = position(0);
  EXPECT_EQ(p.x, 0.0);
  EXPECT_NEAR(p.y, mass_damper_x(-1, 0.1, 2.0, 0.1), 1e-9);
  EXPECT_NEAR(p.z, mass_damper_x(-0.1 * kStandardGravity, 0.1, 2.0, 0.1), 1e-9);  // its weight
}

// Gravity acts on the plant's z unless the SDK's compensation holds it, and that needs a force
// command since forces were enabled (SOURCES.md §1.6: computed on the host, sent with each
// command). `elapse` lets time pass without one, as between enabling forces and a first command.
TEST_F(FakeForceDimension, GravityActsUntilAForceCommandCarriesTheCompensation) {
  attach("omega.3");
  const Api& a = *api_;
  open_ready(0);  // forces on, no command yet
  ASSERT_EQ(control("dt 0.0005"), 0);
  ASSERT_EQ(control("elapse 0 0.0075"), 0);  // 15 steps
  double vx, vy, vz;
  ASSERT_EQ(a.dhdGetLinearVelocity(&vx, &vy, &vz, 0), 0);
  const double m = 0.2, b = 2.0, W = m * kStandardGravity;
  EXPECT_NEAR(vz, -mass_damper_v(W, m, b, 0.0075), 1e-9);  // free fall, through the damping
  EXPECT_NEAR(vz, -0.0709, 1e-4);
  EXPECT_NEAR(position(0).z, -mass_damper_x(W, m, b, 0.0075), 1e-12);

  // A zero command carries the compensation: the arm stops falling (only the damping acts).
  ASSERT_EQ(a.dhdSetForce(0, 0, 0, 0), 0);
  ASSERT_EQ(a.dhdGetLinearVelocity(&vx, &vy, &vz, 0), 0);
  const double v1 = vz;
  ASSERT_EQ(control("elapse 0 0.01"), 0);
  ASSERT_EQ(a.dhdGetLinearVelocity(&vx, &vy, &vz, 0), 0);
  EXPECT_NEAR(vz, v1 * std::exp(-b / m * 0.01), 1e-12);

  // Enabled again, no command yet: falling again. With the compensation off it falls under
  // commands too.
  ASSERT_EQ(a.dhdEnableForce(DHD_ON, 0), 0);
  ASSERT_EQ(control("elapse 0 0.05"), 0);
  ASSERT_EQ(a.dhdGetLinearVelocity(&vx, &vy, &vz, 0), 0);
  EXPECT_LT(vz, -0.3);
  attach("omega.3");
  open_ready(0);
  ASSERT_EQ(a.dhdSetGravityCompensation(DHD_OFF, 0), 0);
  for (int i = 0; i < 10; ++i) ASSERT_EQ(a.dhdSetForce(0, 0, 0, 0), 0);
  ASSERT_EQ(a.dhdGetLinearVelocity(&vx, &vy, &vz, 0), 0);
  EXPECT_NEAR(vz, -mass_damper_v(W, m, b, 0.01), 1e-9);
  EXPECT_EQ(control("elapse 0 -1"), -1);
  EXPECT_EQ(control("elapse 0"), -1);
}

// The velocity guard (SOURCES.md §1.6, "Safety"): an axis past the threshold with forces on turns
// them off and brakes, the setters still return 0 while nothing is applied, and dhdGetStatus says
// why until dhdEnableForce turns them on again.
TEST_F(FakeForceDimension, TheVelocityGuardTurnsForcesOffAndSaysWhy) {
  attach("omega.3");
  const Api& a = *api_;
  open_ready(0);
  ASSERT_EQ(control("velocity 0 0.5"), 0);
  int status[DHD_MAX_STATUS] = {};
  double vx = 0, vy, vz;
  int ticks = 0;
  while (vx <= 0.5 && ticks < 1000) {
    ASSERT_EQ(a.dhdSetForce(12, 0, 0, 0), 0);
    ASSERT_EQ(a.dhdGetLinearVelocity(&vx, &vy, &vz, 0), 0);
    ++ticks;
  }
  // 12 N on 0.2 kg with 2 N·s/m: past 0.5 m/s in the 9th millisecond.
  EXPECT_EQ(ticks, 9);
  ASSERT_EQ(a.dhdGetStatus(status, 0), 0);
  EXPECT_EQ(status[DHD_STATUS_FORCE], 0);
  EXPECT_EQ(status[DHD_STATUS_BRAKE], 1);
  EXPECT_EQ(status[DHD_STATUS_FORCE_OFF_CAUSE], DHD_FORCE_OFF_VELOCITY);
  // The setter still succeeds; the force is not applied (the brake slows the effector).
  for (int i = 0; i < 20; ++i) ASSERT_EQ(a.dhdSetForce(12, 0, 0, 0), 0);
  const double v_braked = vx;
  ASSERT_EQ(a.dhdGetLinearVelocity(&vx, &vy, &vz, 0), 0);
  EXPECT_LT(vx, 0.5 * v_braked);
  ASSERT_EQ(a.dhdGetStatus(status, 0), 0);
  EXPECT_EQ(status[DHD_STATUS_FORCE_OFF_CAUSE], DHD_FORCE_OFF_VELOCITY);
  // Enabled again: forces act, the cause is cleared.
  ASSERT_EQ(a.dhdEnableForce(DHD_ON, 0), 0);
  ASSERT_EQ(a.dhdGetStatus(status, 0), 0);
  EXPECT_EQ(status[DHD_STATUS_FORCE], 1);
  EXPECT_EQ(status[DHD_STATUS_FORCE_OFF_CAUSE], DHD_FORCE_OFF_NONE);
  ASSERT_EQ(control("velocity 0 0"), 0);  // off: nothing trips it
  for (int i = 0; i < 200; ++i) ASSERT_EQ(a.dhdSetForce(12, 0, 0, 0), 0);
  ASSERT_EQ(a.dhdGetStatus(status, 0), 0);
  EXPECT_EQ(status[DHD_STATUS_FORCE], 1);
  EXPECT_EQ(control("velocity 0 -1"), -1);
}

// dhdSetBrakes does not take a device out of FORCE mode (BRAKE is the forces-off mode, SOURCES.md
// §1.6); dhdEnableForce(OFF) does, into BRAKE.
TEST_F(FakeForceDimension, BrakesDoNotStopForcesDisablingForcesBrakes) {
  attach("omega.3");
  const Api& a = *api_;
  open_ready(0);
  int status[DHD_MAX_STATUS] = {};
  ASSERT_EQ(a.dhdSetBrakes(DHD_ON, 0), 0);
  ASSERT_EQ(a.dhdGetStatus(status, 0), 0);
  EXPECT_EQ(status[DHD_STATUS_FORCE], 1);
  EXPECT_EQ(status[DHD_STATUS_BRAKE], 0);
  ASSERT_EQ(a.dhdEnableForce(DHD_OFF, 0), 0);
  ASSERT_EQ(a.dhdGetStatus(status, 0), 0);
  EXPECT_EQ(status[DHD_STATUS_FORCE], 0);
  EXPECT_EQ(status[DHD_STATUS_BRAKE], 1);
  EXPECT_EQ(status[DHD_STATUS_FORCE_OFF_CAUSE], DHD_FORCE_OFF_SOFTWARE);
  ASSERT_EQ(a.dhdSetBrakes(DHD_OFF, 0), 0);  // forces off, brakes off: IDLE
  ASSERT_EQ(a.dhdGetStatus(status, 0), 0);
  EXPECT_EQ(status[DHD_STATUS_IDLE], 1);
}

// `fail ID FUNCTION [CODE]` fails one force setter alone, sending nothing; the others still work.
TEST_F(FakeForceDimension, FailMakesOneForceSetterFailAlone) {
  attach("sigma.7");
  const Api& a = *api_;
  open_ready(0);
  ASSERT_EQ(control("fail 0 dhdSetForce"), 0);
  EXPECT_EQ(a.dhdSetForce(1, 0, 0, 0), -1);
  EXPECT_EQ(a.dhdErrorGetLast(), DHD_ERROR_COM);
  EXPECT_EQ(position(0).x, 0.0);  // nothing sent: the plant did not step
  EXPECT_EQ(a.dhdSetForceAndTorqueAndGripperForce(1, 0, 0, 0, 0, 0, 0, 0), 0);
  double x, y, z;
  EXPECT_EQ(a.dhdGetPosition(&x, &y, &z, 0), 0);
  ASSERT_EQ(control("fail 0 dhdSetForceAndTorqueAndGripperForce 21"), 0);  // DHD_ERROR_INVALID
  EXPECT_EQ(a.dhdSetForceAndTorqueAndGripperForce(1, 0, 0, 0, 0, 0, 0, 0), -1);
  EXPECT_EQ(a.dhdErrorGetLast(), DHD_ERROR_INVALID);
  EXPECT_EQ(a.dhdSetForce(1, 0, 0, 0), 0);  // only the last named one fails
  ASSERT_EQ(control("fail 0 none"), 0);
  EXPECT_EQ(a.dhdSetForceAndTorqueAndGripperForce(1, 0, 0, 0, 0, 0, 0, 0), 0);
  EXPECT_EQ(control("fail 0 dhdGetPosition"), -1);
  EXPECT_EQ(control("fail 0 dhdSetForce 99"), -1);
}

// A left-handed model (SOURCES.md §1.5's *_LEFT codes) says so, and its gripper angle is negative
// (§1.6: the lambda.7 manual; CHAI3D negates it), its force opening it when negative.
TEST_F(FakeForceDimension, ALeftHandedDeviceSaysSoAndItsGripperAngleIsNegative) {
  attach("omega.7-left,omega.7");
  const Api& a = *api_;
  open_ready(0);
  open_ready(1);
  EXPECT_EQ(a.dhdGetSystemType(0), DHD_DEVICE_OMEGA7_LEFT);
  EXPECT_TRUE(a.dhdIsLeftHanded(0));
  EXPECT_FALSE(a.dhdIsLeftHanded(1));
  double angle = 0;
  ASSERT_EQ(a.dhdGetGripperAngleRad(&angle, 0), 0);
  EXPECT_EQ(angle, -0.5);
  for (int i = 0; i < 10; ++i)
    ASSERT_EQ(a.dhdSetForceAndTorqueAndGripperForce(0, 0, 0, 0, 0, 0, 0.001, 0), 0);
  ASSERT_EQ(a.dhdGetGripperAngleRad(&angle, 0), 0);
  EXPECT_NEAR(angle, -(0.5 + mass_damper_x(-0.001, 1e-4, 1e-3, 0.01)), 1e-9);  // closing
}

// drdIsSupported: the DRD regulates the omega.3, not the Falcon, whose drdAutoInit fails.
TEST_F(FakeForceDimension, TheDrdSupportsTheOmegaNotTheFalcon) {
  attach("omega.3,falcon");
  const Api& a = *api_;
  ASSERT_EQ(a.drdOpenID(0), 0);
  ASSERT_EQ(a.drdOpenID(1), 1);
  EXPECT_TRUE(a.drdIsSupported(0));
  EXPECT_FALSE(a.drdIsSupported(1));
  EXPECT_EQ(a.drdAutoInit(1), -1);
  EXPECT_EQ(a.dhdErrorGetLast(), DHD_ERROR_NOT_AVAILABLE);
  EXPECT_EQ(a.drdAutoInit(0), 0);
}

TEST_F(FakeForceDimension, NothingMovesBeforeForcesAreEnabled) {
  attach("falcon,omega.3");
  const Api& a = *api_;
  ASSERT_EQ(a.dhdOpenID(0), 0);  // the Falcon needs no calibration
  for (int i = 0; i < 100; ++i) ASSERT_EQ(a.dhdSetForce(2, 0, 0, 0), 0);
  EXPECT_EQ(position(0).x, 0.0);
  int status[32] = {};
  ASSERT_EQ(a.dhdGetStatus(status, 0), 0);
  EXPECT_EQ(status[DHD_STATUS_FORCE], 0);
  EXPECT_EQ(status[DHD_STATUS_IDLE], 1);

  ASSERT_EQ(a.dhdEnableForce(DHD_ON, 0), 0);
  ASSERT_EQ(a.dhdGetStatus(status, 0), 0);
  EXPECT_EQ(status[DHD_STATUS_FORCE], 1);
  for (int i = 0; i < 100; ++i) ASSERT_EQ(a.dhdSetForce(2, 0, 0, 0), 0);
  EXPECT_GT(position(0).x, 0.01);

  // Disabled again, or stopped (BRAKE): commanded forces do nothing.
  ASSERT_EQ(a.dhdStop(0), 0);
  ASSERT_EQ(a.dhdGetStatus(status, 0), 0);
  EXPECT_EQ(status[DHD_STATUS_FORCE], 0);
  EXPECT_EQ(status[DHD_STATUS_BRAKE], 1);
  EXPECT_EQ(status[DHD_STATUS_FORCE_OFF_CAUSE], DHD_FORCE_OFF_SOFTWARE);
  for (int i = 0; i < 200; ++i) ASSERT_EQ(a.dhdSetForce(2, 0, 0, 0), 0);
  double vx = 1, vy = 1, vz = 1;
  ASSERT_EQ(a.dhdGetLinearVelocity(&vx, &vy, &vz, 0), 0);
  EXPECT_LT(std::fabs(vx), 1e-6);  // the brake stopped it
}

TEST_F(FakeForceDimension, TheBrakeDampsTheHandHard) {
  attach("omega.3");
  ASSERT_EQ(api_->dhdOpenID(0), 0);
  ASSERT_EQ(api_->dhdSetBrakes(DHD_ON, 0), 0);
  ASSERT_EQ(control("hand 0 0 0.1 0"), 0);
  for (int i = 0; i < 1000; ++i) ASSERT_EQ(api_->dhdSetForce(0, 0, 0, 0), 0);
  double vx = 0, vy = 0, vz = 0;
  ASSERT_EQ(api_->dhdGetLinearVelocity(&vx, &vy, &vz, 0), 0);
  EXPECT_NEAR(vy, 0.1 / 52.0, 1e-9);  // terminal velocity under 2 + 50 N·s/m
  ASSERT_EQ(api_->dhdSetBrakes(DHD_OFF, 0), 0);
  for (int i = 0; i < 1000; ++i) ASSERT_EQ(api_->dhdSetForce(0, 0, 0, 0), 0);
  ASSERT_EQ(api_->dhdGetLinearVelocity(&vx, &vy, &vz, 0), 0);
  EXPECT_NEAR(vy, 0.1 / 2.0, 1e-4);  // and under 2 N·s/m alone
}

TEST_F(FakeForceDimension, TheWorkspaceStopsTheEffectorAtItsBox) {
  attach("omega.3,delta.3");
  ASSERT_EQ(api_->dhdOpenID(0), 0);
  ASSERT_EQ(api_->dhdOpenID(1), 1);
  ASSERT_EQ(control("hand 0 -10 0 0"), 0);
  ASSERT_EQ(control("hand 1 0 0 10"), 0);
  for (int i = 0; i < 3000; ++i) {
    ASSERT_EQ(api_->dhdSetForce(0, 0, 0, 0), 0);
    ASSERT_EQ(api_->dhdSetForce(0, 0, 0, 1), 0);
  }
  EXPECT_DOUBLE_EQ(position(0).x, -0.075);
  EXPECT_DOUBLE_EQ(position(1).z, 0.15);
  double vx = 1, vy = 1, vz = 1;
  ASSERT_EQ(api_->dhdGetLinearVelocity(&vx, &vy, &vz, 0), 0);
  EXPECT_EQ(vx, 0.0);
}

TEST_F(FakeForceDimension, UnplugMakesCallsFailWithComAndReplugNeedsANewEnableForce) {
  attach("omega.3");
  const Api& a = *api_;
  open_ready(0);
  for (int i = 0; i < 50; ++i) ASSERT_EQ(a.dhdSetForce(1, 0, 0, 0), 0);
  const double x_before = position(0).x;
  ASSERT_GT(x_before, 0.0);

  ASSERT_EQ(control("unplug 0"), 0);
  EXPECT_EQ(a.dhdSetForce(1, 0, 0, 0), -1);
  EXPECT_EQ(a.dhdErrorGetLast(), DHD_ERROR_COM);
  double x, y, z;
  EXPECT_EQ(a.dhdGetPosition(&x, &y, &z, 0), -1);
  EXPECT_EQ(a.dhdErrorGetLast(), DHD_ERROR_COM);
  EXPECT_EQ(a.dhdEnableForce(DHD_ON, 0), -1);
  EXPECT_EQ(a.dhdErrorGetLast(), DHD_ERROR_COM);
  int status[DHD_MAX_STATUS] = {};
  EXPECT_EQ(a.dhdGetStatus(status, 0), -1);
  EXPECT_EQ(a.dhdErrorGetLast(), DHD_ERROR_COM);
  EXPECT_EQ(status[DHD_STATUS_CONNECTED], 0);
  EXPECT_EQ(status[DHD_STATUS_POWER], 0);
  EXPECT_EQ(status[DHD_STATUS_FORCE_OFF_CAUSE], DHD_FORCE_OFF_USBDISCN);
  EXPECT_STREQ(a.dhdErrorGetStr(DHD_ERROR_COM), "communication error with the device");

  ASSERT_EQ(control("replug 0"), 0);
  ASSERT_EQ(a.dhdGetStatus(status, 0), 0);
  EXPECT_EQ(status[DHD_STATUS_CONNECTED], 1);
  EXPECT_EQ(status[DHD_STATUS_FORCE], 0);  // forces stay off after a reconnect
  double v0, vx, vy, vz;
  ASSERT_EQ(a.dhdGetLinearVelocity(&v0, &vy, &vz, 0), 0);
  ASSERT_GT(v0, 0.1);
  for (int i = 0; i < 50; ++i) ASSERT_EQ(a.dhdSetForce(1, 0, 0, 0), 0);
  ASSERT_EQ(a.dhdGetLinearVelocity(&vx, &vy, &vz, 0), 0);
  EXPECT_NEAR(vx, v0 * std::exp(-0.5), 1e-9);  // only coasting: the force is not applied
  ASSERT_EQ(a.dhdEnableForce(DHD_ON, 0), 0);
  for (int i = 0; i < 50; ++i) ASSERT_EQ(a.dhdSetForce(1, 0, 0, 0), 0);
  ASSERT_EQ(a.dhdGetLinearVelocity(&vx, &vy, &vz, 0), 0);
  EXPECT_GT(vx, 0.2);  // pushed again
}

TEST_F(FakeForceDimension, CalibrationStartsInResetUntilDrdAutoInit) {
  attach("omega.3,falcon");
  const Api& a = *api_;
  ASSERT_EQ(a.drdOpenID(0), 0);
  ASSERT_EQ(a.drdOpenID(1), 1);
  EXPECT_FALSE(a.drdIsInitialized(0));
  EXPECT_TRUE(a.drdIsInitialized(1));  // the Falcon needs none
  int status[DHD_MAX_STATUS] = {};
  ASSERT_EQ(a.dhdGetStatus(status, 0), 0);
  EXPECT_EQ(status[DHD_STATUS_RESET], 1);
  EXPECT_EQ(status[DHD_STATUS_POWER], 1);
  EXPECT_EQ(status[DHD_STATUS_CONNECTED], 1);
  EXPECT_EQ(status[DHD_STATUS_FORCE], 0);
  EXPECT_EQ(status[DHD_STATUS_BRAKE], 0);
  EXPECT_EQ(a.dhdEnableForce(DHD_ON, 0), -1);  // not before calibration
  EXPECT_EQ(a.dhdErrorGetLast(), DHD_ERROR_DEVICE_NOT_READY);

  ASSERT_EQ(control("hand 0 1 0 0"), 0);  // moved by hand while uncalibrated
  for (int i = 0; i < 20; ++i) ASSERT_EQ(a.dhdSetForce(0, 0, 0, 0), 0);
  ASSERT_GT(position(0).x, 0.0);
  ASSERT_EQ(control("hand 0 0 0 0"), 0);

  ASSERT_EQ(a.drdAutoInit(0), 0);
  EXPECT_TRUE(a.drdIsInitialized(0));
  ASSERT_EQ(a.dhdGetStatus(status, 0), 0);
  EXPECT_EQ(status[DHD_STATUS_RESET], 0);
  EXPECT_EQ(position(0).x, 0.0);  // drdAutoInit left it at the origin
  for (int i = 0; i < 20; ++i) ASSERT_EQ(a.dhdSetForce(3, 0, 0, 0), 0);
  EXPECT_EQ(position(0).x, 0.0);  // held by the regulation until drdStop
  ASSERT_EQ(a.drdStop(true, 0), 0);  // forces kept on
  ASSERT_EQ(a.dhdGetStatus(status, 0), 0);
  EXPECT_EQ(status[DHD_STATUS_FORCE], 1);
  for (int i = 0; i < 20; ++i) ASSERT_EQ(a.dhdSetForce(3, 0, 0, 0), 0);
  EXPECT_GT(position(0).x, 0.0);

  ASSERT_EQ(control("uncalibrate 0"), 0);
  EXPECT_FALSE(a.drdIsInitialized(0));
  ASSERT_EQ(a.dhdGetStatus(status, 0), 0);
  EXPECT_EQ(status[DHD_STATUS_RESET], 1);
  EXPECT_EQ(status[DHD_STATUS_FORCE], 0);
}

TEST_F(FakeForceDimension, TheCallLogCountsRepeatedCalls) {
  attach("omega.3");
  const Api& a = *api_;
  ASSERT_EQ(a.dhdOpenID(0), 0);
  a.fake_dhd_clear_calls();
  EXPECT_STREQ(a.fake_dhd_calls(), "");
  double x, y, z;
  EXPECT_EQ(a.dhdEnableForce(1, 0), -1);  // uncalibrated
  EXPECT_EQ(a.drdAutoInit(0), 0);
  EXPECT_EQ(a.drdStop(true, 0), 0);
  EXPECT_EQ(a.dhdEnableForce(1, 0), 0);
  for (int i = 0; i < 42; ++i) a.dhdGetPosition(&x, &y, &z, 0);
  for (int i = 0; i < 3; ++i) a.dhdSetForceAndTorqueAndGripperForce(0, 0, -1, 0, 0, 0, 0, 0);
  a.dhdSetForce(0.25, 0, 0, -1);
  a.dhdGetPosition(&x, &y, &z, 0);
  a.dhdOpenID(0);
  a.dhdOpenID(0);  // not a high-rate call: listed twice
  EXPECT_STREQ(a.fake_dhd_calls(),
               "dhdEnableForce 1 0\n"
               "drdAutoInit 0\n"
               "drdStop 1 0\n"
               "dhdEnableForce 1 0\n"
               "dhdGetPosition 0 x42\n"
               "dhdSetForceAndTorqueAndGripperForce 0 0 -1 0 0 0 0 0 x3\n"
               "dhdSetForce 0.25 0 0 -1\n"
               "dhdGetPosition 0\n"
               "dhdOpenID 0\n"
               "dhdOpenID 0\n");
  a.fake_dhd_clear_calls();
  EXPECT_STREQ(a.fake_dhd_calls(), "");
}

TEST_F(FakeForceDimension, ForcesAboveTheMaximumReturnMotorSaturated) {
  attach("omega.3,sigma.7");
  const Api& a = *api_;
  open_ready(0);
  open_ready(1);
  // 20 N asked of a 12 N omega.3 (SOURCES.md §1.7): saturated, and 12 N is what acts.
  for (int i = 0; i < 20; ++i) ASSERT_EQ(a.dhdSetForce(20, 0, 0, 0), DHD_MOTOR_SATURATED);
  const double expected = mass_damper_x(12.0, 0.2, 2.0, 0.02);
  EXPECT_NEAR(position(0).x, expected, 0.01 * expected);
  EXPECT_EQ(a.dhdSetForce(-11.9, 0, 0, 0), 0);
  EXPECT_EQ(a.dhdSetForce(-7, -7, -7, 0), DHD_MOTOR_SATURATED);  // |F| = 12.1 N

  // The sigma.7's wrist: 0.2 N·m; its gripper: 8 N.
  EXPECT_EQ(a.dhdSetForceAndTorque(0, 0, 0, 0, 0, 0.1, 1), 0);
  EXPECT_EQ(a.dhdSetForceAndTorque(0, 0, 0, 0, 0, 0.5, 1), DHD_MOTOR_SATURATED);
  EXPECT_EQ(a.dhdSetForceAndTorqueAndGripperForce(0, 0, 0, 0, 0, 0, -9, 1), DHD_MOTOR_SATURATED);
  EXPECT_EQ(a.dhdSetForceAndTorqueAndGripperForce(0, 0, 0, 0, 0, 0, -1, 1), 0);

  // Forced on through the control API.
  ASSERT_EQ(control("saturate 1 on"), 0);
  EXPECT_EQ(a.dhdSetForce(0.1, 0, 0, 1), DHD_MOTOR_SATURATED);
  ASSERT_EQ(control("saturate 1 off"), 0);
  EXPECT_EQ(a.dhdSetForce(0.1, 0, 0, 1), 0);
  EXPECT_EQ(a.dhdSetForce(NAN, 0, 0, 1), -1);
  EXPECT_EQ(a.dhdErrorGetLast(), DHD_ERROR_INVALID);
}

TEST_F(FakeForceDimension, AnActiveWristTurnsUnderTorqueAPassiveOneOnlyByHand) {
  attach("sigma.7,omega.6,falcon");
  const Api& a = *api_;
  open_ready(0);
  open_ready(1);
  open_ready(2);
  // sigma.7: 0.01 N·m about z for 0.1 s over inertia 1e-4 and damping 1e-3.
  for (int i = 0; i < 100; ++i) ASSERT_EQ(a.dhdSetForceAndTorque(0, 0, 0, 0, 0, 0.01, 0), 0);
  double R[3][3];
  ASSERT_EQ(a.dhdGetOrientationFrame(R, 0), 0);
  const double angle = mass_damper_x(0.01, 1e-4, 1e-3, 0.1);
  EXPECT_NEAR(std::atan2(R[1][0], R[0][0]), angle, 1e-6);  // a rotation about z, row-major
  EXPECT_NEAR(R[0][1], -std::sin(angle), 1e-6);
  EXPECT_NEAR(R[2][2], 1.0, 1e-12);
  double wx, wy, wz;
  ASSERT_EQ(a.dhdGetAngularVelocityRad(&wx, &wy, &wz, 0), 0);
  EXPECT_NEAR(wz, mass_damper_v(0.01, 1e-4, 1e-3, 0.1), 1e-6);

  // omega.6: the torque does nothing; `turn` sets it.
  for (int i = 0; i < 100; ++i) ASSERT_EQ(a.dhdSetForceAndTorque(0, 0, 0, 0.1, 0, 0, 1), 0);
  ASSERT_EQ(a.dhdGetOrientationFrame(R, 1), 0);
  EXPECT_EQ(R[0][0], 1.0);
  EXPECT_EQ(R[1][1], 1.0);
  ASSERT_EQ(control("turn 1 0.5 0 0"), 0);
  ASSERT_EQ(a.dhdGetOrientationFrame(R, 1), 0);
  EXPECT_NEAR(R[1][1], std::cos(0.5), 1e-12);
  EXPECT_NEAR(R[2][1], std::sin(0.5), 1e-12);

  // falcon: no wrist, identity, and `turn` is refused.
  ASSERT_EQ(a.dhdGetOrientationFrame(R, 2), 0);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) EXPECT_EQ(R[i][j], i == j ? 1.0 : 0.0);
  EXPECT_EQ(control("turn 2 0.5 0 0"), -1);
}

TEST_F(FakeForceDimension, TheGripperStartsOpenAndClosesUnderForce) {
  attach("omega.7,omega.3");
  const Api& a = *api_;
  open_ready(0);
  open_ready(1);
  double angle = 0;
  ASSERT_EQ(a.dhdGetGripperAngleRad(&angle, 0), 0);
  EXPECT_EQ(angle, 0.5);
  for (int i = 0; i < 10; ++i)
    ASSERT_EQ(a.dhdSetForceAndTorqueAndGripperForce(0, 0, 0, 0, 0, 0, -0.001, 0), 0);
  ASSERT_EQ(a.dhdGetGripperAngleRad(&angle, 0), 0);
  EXPECT_NEAR(angle, 0.5 + mass_damper_x(-0.001, 1e-4, 1e-3, 0.01), 1e-9);
  for (int i = 0; i < 1000; ++i)
    ASSERT_EQ(a.dhdSetForceAndTorqueAndGripperForce(0, 0, 0, 0, 0, 0, -1, 0), 0);
  ASSERT_EQ(a.dhdGetGripperAngleRad(&angle, 0), 0);
  EXPECT_EQ(angle, 0.0);  // closed against its stop
  EXPECT_EQ(a.dhdGetGripperAngleRad(&angle, 1), -1);  // the omega.3 has none
  EXPECT_EQ(a.dhdErrorGetLast(), DHD_ERROR_NOT_AVAILABLE);
}

TEST_F(FakeForceDimension, AHungPositionReadWaitsForReleaseWithoutBlockingOthers) {
  attach("omega.3,falcon");
  const Api& a = *api_;
  ASSERT_EQ(a.dhdOpenID(0), 0);
  ASSERT_EQ(a.dhdOpenID(1), 1);
  ASSERT_EQ(control("hang 0"), 0);
  std::atomic<int> result{99};
  std::thread reader([&] {
    double x, y, z;
    result = a.dhdGetPosition(&x, &y, &z, 0);
  });
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (a.fake_dhd_blocked() == 0 && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  EXPECT_EQ(a.fake_dhd_blocked(), 1);
  EXPECT_EQ(result.load(), 99);
  // The library is not locked meanwhile.
  EXPECT_EQ(a.dhdGetSystemType(1), DHD_DEVICE_FALCON);
  EXPECT_EQ(a.dhdSetForce(0, 0, 0, 0), 0);
  ASSERT_EQ(control("release"), 0);
  reader.join();
  EXPECT_EQ(result.load(), 0);
  EXPECT_EQ(a.fake_dhd_blocked(), 0);
  double x, y, z;
  EXPECT_EQ(a.dhdGetPosition(&x, &y, &z, 0), 0);  // one read only

  // With a time limit, it returns by itself.
  ASSERT_EQ(control("hang 1 0.05"), 0);
  const auto start = std::chrono::steady_clock::now();
  EXPECT_EQ(a.dhdGetPosition(&x, &y, &z, 1), 0);
  EXPECT_GE(std::chrono::steady_clock::now() - start, std::chrono::milliseconds(45));
}

TEST_F(FakeForceDimension, FakeDhdScriptActsAtTheGivenTicks) {
  attach("falcon", "3 unplug 0; 6 replug 0;0 hand 0 0 1 0");
  const Api& a = *api_;
  ASSERT_EQ(a.dhdOpenID(0), 0);
  int results[8];
  for (int& r : results) r = a.dhdSetForce(0, 0, 0, 0);
  const int expected[8] = {0, 0, 0, -1, -1, -1, 0, 0};  // unplugged after 3 ticks, back after 6
  for (int i = 0; i < 8; ++i) EXPECT_EQ(results[i], expected[i]) << "tick " << i + 1;
  EXPECT_GT(position(0).y, 0.0);  // the tick-0 hand force
}

TEST_F(FakeForceDimension, ErrorsArePerThreadAndTextsFixed) {
  attach("omega.3");
  const Api& a = *api_;
  ASSERT_EQ(a.dhdOpenID(7), -1);
  ASSERT_EQ(a.dhdErrorGetLast(), DHD_ERROR_NO_DEVICE_FOUND);
  int other = -1;
  std::thread([&] { other = a.dhdErrorGetLast(); }).join();
  EXPECT_EQ(other, DHD_NO_ERROR);
  EXPECT_EQ(a.dhdErrorGetLast(), DHD_ERROR_NO_DEVICE_FOUND);
  for (int code = 0; code <= DHD_ERROR_NO_REGULATION; ++code) {
    ASSERT_NE(a.dhdErrorGetStr(code), nullptr);
    EXPECT_GT(std::string(a.dhdErrorGetStr(code)).size(), 3u);
    for (int other_code = 0; other_code < code; ++other_code)
      EXPECT_STRNE(a.dhdErrorGetStr(code), a.dhdErrorGetStr(other_code));
  }
  EXPECT_STREQ(a.dhdErrorGetStr(999), "unknown error");
  const double t0 = a.dhdGetTime();
  std::this_thread::sleep_for(std::chrono::milliseconds(5));
  EXPECT_GE(a.dhdGetTime() - t0, 0.004);
}

TEST_F(FakeForceDimension, TheControlApiRefusesWhatItDoesNotUnderstand) {
  attach("omega.3");
  EXPECT_EQ(control("bogus"), -1);
  EXPECT_EQ(control(""), -1);
  EXPECT_EQ(control("hand 3 1 2 3"), -1);  // no device 3
  EXPECT_EQ(control("hand 0 1 2"), -1);
  EXPECT_EQ(control("hand 0 1 2 3 4"), -1);
  EXPECT_EQ(control("dt 0"), -1);
  EXPECT_EQ(control("saturate 0 maybe"), -1);
  EXPECT_EQ(control("hang 0 soon"), -1);
  EXPECT_EQ(control("turn 0 0 0 1"), -1);  // the omega.3 has no wrist
  EXPECT_EQ(api_->fake_dhd_control(nullptr), -1);
  EXPECT_EQ(control("hand 0 1 2 3"), 0);
  EXPECT_EQ(control("dt 0.002"), 0);
  EXPECT_EQ(control("gravity"), -1);
  EXPECT_EQ(api_->dhdOpenID(0), 0);
  EXPECT_EQ(api_->dhdSetGravityCompensation(DHD_OFF, 0), 0);
  int status[DHD_MAX_STATUS] = {};
  ASSERT_EQ(api_->dhdGetStatus(status, 0), 0);
  EXPECT_EQ(status[DHD_STATUS_GRAVITY], 0);
}

}  // namespace
