// The OpenHaptics stand-in (libHD.so.3.4 from fake_openhaptics.cpp) tested on its own, the way a
// driver uses it: dlopen the built file, dlsym each function, call it through a pointer of the
// declared type. Each test starts from `reset` with its own FAKE_HD_DEVICES and FAKE_HD_CLOCK.
#include <dlfcn.h>
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "fake_openhaptics.hpp"

namespace {

using namespace fake_hd;

// Every function the test calls, resolved once.
struct Api {
  void* handle = nullptr;
  hdInitDevice_t hdInitDevice;
  hdDisableDevice_t hdDisableDevice;
  hdMakeCurrentDevice_t hdMakeCurrentDevice;
  hdGetCurrentDevice_t hdGetCurrentDevice;
  hdBeginFrame_t hdBeginFrame;
  hdEndFrame_t hdEndFrame;
  hdGetError_t hdGetError;
  hdGetErrorString_t hdGetErrorString;
  hdEnable_t hdEnable;
  hdDisable_t hdDisable;
  hdIsEnabled_t hdIsEnabled;
  hdGetBooleanv_t hdGetBooleanv;
  hdGetIntegerv_t hdGetIntegerv;
  hdGetFloatv_t hdGetFloatv;
  hdGetDoublev_t hdGetDoublev;
  hdGetLongv_t hdGetLongv;
  hdGetString_t hdGetString;
  hdSetBooleanv_t hdSetBooleanv;
  hdSetIntegerv_t hdSetIntegerv;
  hdSetFloatv_t hdSetFloatv;
  hdSetDoublev_t hdSetDoublev;
  hdSetLongv_t hdSetLongv;
  hdCheckCalibration_t hdCheckCalibration;
  hdCheckCalibrationStyle_t hdCheckCalibrationStyle;
  hdUpdateCalibration_t hdUpdateCalibration;
  hdStartScheduler_t hdStartScheduler;
  hdStopScheduler_t hdStopScheduler;
  hdSetSchedulerRate_t hdSetSchedulerRate;
  hdScheduleSynchronous_t hdScheduleSynchronous;
  hdScheduleAsynchronous_t hdScheduleAsynchronous;
  hdUnschedule_t hdUnschedule;
  hdWaitForCompletion_t hdWaitForCompletion;
  hdGetSchedulerTimeStamp_t hdGetSchedulerTimeStamp;
  fake_hd_control_t fake_hd_control;
  fake_hd_calls_t fake_hd_calls;
  fake_hd_clear_calls_t fake_hd_clear_calls;
  fake_hd_blocked_t fake_hd_blocked;
};

template <typename Fn>
void resolve(void* handle, Fn& fn, const char* name) {
  fn = reinterpret_cast<Fn>(dlsym(handle, name));
  if (!fn) ADD_FAILURE() << "libHD.so.3.4 lacks " << name;
}

#define RESOLVE(fn) resolve(api.handle, api.fn, #fn)

Api load() {
  Api api;
  api.handle = dlopen(FAKE_OPENHAPTICS_LIBRARY, RTLD_NOW);
  if (!api.handle) {
    ADD_FAILURE() << "dlopen: " << dlerror();
    return api;
  }
  RESOLVE(hdInitDevice);
  RESOLVE(hdDisableDevice);
  RESOLVE(hdMakeCurrentDevice);
  RESOLVE(hdGetCurrentDevice);
  RESOLVE(hdBeginFrame);
  RESOLVE(hdEndFrame);
  RESOLVE(hdGetError);
  RESOLVE(hdGetErrorString);
  RESOLVE(hdEnable);
  RESOLVE(hdDisable);
  RESOLVE(hdIsEnabled);
  RESOLVE(hdGetBooleanv);
  RESOLVE(hdGetIntegerv);
  RESOLVE(hdGetFloatv);
  RESOLVE(hdGetDoublev);
  RESOLVE(hdGetLongv);
  RESOLVE(hdGetString);
  RESOLVE(hdSetBooleanv);
  RESOLVE(hdSetIntegerv);
  RESOLVE(hdSetFloatv);
  RESOLVE(hdSetDoublev);
  RESOLVE(hdSetLongv);
  RESOLVE(hdCheckCalibration);
  RESOLVE(hdCheckCalibrationStyle);
  RESOLVE(hdUpdateCalibration);
  RESOLVE(hdStartScheduler);
  RESOLVE(hdStopScheduler);
  RESOLVE(hdSetSchedulerRate);
  RESOLVE(hdScheduleSynchronous);
  RESOLVE(hdScheduleAsynchronous);
  RESOLVE(hdUnschedule);
  RESOLVE(hdWaitForCompletion);
  RESOLVE(hdGetSchedulerTimeStamp);
  RESOLVE(fake_hd_control);
  RESOLVE(fake_hd_calls);
  RESOLVE(fake_hd_clear_calls);
  RESOLVE(fake_hd_blocked);
  return api;
}

// Displacement of a mass m with viscous damping b, from rest, under a constant force F for t.
double mass_damper_x(double F, double m, double b, double t) {
  return F / b * (t - m / b * (1.0 - std::exp(-b * t / m)));
}
double mass_damper_v(double F, double m, double b, double t) {
  return F / b * (1.0 - std::exp(-b * t / m));
}

// A scheduler callback that runs a std::function given as its user data.
using Body = std::function<HDCallbackCode()>;
HDCallbackCode run_body(void* user) { return (*static_cast<Body*>(user))(); }

struct Vec {
  double x = NAN, y = NAN, z = NAN;
};

constexpr const char* kPremium = "PHANTOM Premium 1.5 6DOF";

class FakeOpenHaptics : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (!api_) api_ = new Api(load());  // once per process, kept to the end
  }

  // Every test starts from a fresh stand-in with `devices` attached, the given clock, no script.
  void attach(const char* devices, const char* clock = "manual", const char* script = nullptr) {
    ASSERT_NE(api_->handle, nullptr);
    if (devices)
      setenv("FAKE_HD_DEVICES", devices, 1);
    else
      unsetenv("FAKE_HD_DEVICES");
    if (clock)
      setenv("FAKE_HD_CLOCK", clock, 1);
    else
      unsetenv("FAKE_HD_CLOCK");
    if (script)
      setenv("FAKE_HD_SCRIPT", script, 1);
    else
      unsetenv("FAKE_HD_SCRIPT");
    ASSERT_EQ(api_->fake_hd_control("reset"), 0);
  }

  void TearDown() override {
    if (api_ && api_->handle) api_->fake_hd_control("reset");  // stops any servo thread
  }

  int control(const std::string& command) { return api_->fake_hd_control(command.c_str()); }

  // The calling thread's error stack, most recent first, emptied.
  std::vector<HDerror> errors() {
    std::vector<HDerror> out;
    for (HDErrorInfo e = api_->hdGetError(); e.errorCode != HD_SUCCESS; e = api_->hdGetError())
      out.push_back(e.errorCode);
    return out;
  }

  Vec get3(HDenum pname) {
    double v[3] = {NAN, NAN, NAN};
    api_->hdGetDoublev(pname, v);
    return {v[0], v[1], v[2]};
  }

  // Opens `name`, enables forces, calibrates (the §2.3 canonical sequence), starts the scheduler.
  HHD open_ready(const char* name) {
    const Api& a = *api_;
    const HHD h = a.hdInitDevice(name);
    EXPECT_NE(h, HD_INVALID_HANDLE);
    a.hdEnable(HD_FORCE_OUTPUT);
    a.hdStartScheduler();
    HDint style = 0;
    a.hdGetIntegerv(HD_CALIBRATION_STYLE, &style);
    a.hdUpdateCalibration(static_cast<HDenum>(style));
    EXPECT_EQ(a.hdCheckCalibration(), HD_CALIBRATION_OK);
    EXPECT_TRUE(errors().empty());
    return h;
  }

  static Api* api_;
};

Api* FakeOpenHaptics::api_ = nullptr;

TEST_F(FakeOpenHaptics, DlopenOfTheSamePathGivesTheSameInstance) {
  attach(nullptr);
  void* again = dlopen(FAKE_OPENHAPTICS_LIBRARY, RTLD_NOW);
  ASSERT_EQ(again, api_->handle);
  auto init = reinterpret_cast<hdInitDevice_t>(dlsym(again, "hdInitDevice"));
  const HHD h = init(HD_DEFAULT_DEVICE);
  EXPECT_NE(h, HD_INVALID_HANDLE);
  EXPECT_EQ(api_->hdGetCurrentDevice(), h);  // made through the second handle, seen here
  dlclose(again);
}

TEST_F(FakeOpenHaptics, TheDevicesAreThoseOfFakeHdDevices) {
  attach(" Left=Touch, Right = Touch X ,Big=PHANTOM Premium 1.5 6DOF");
  const Api& a = *api_;
  const HHD left = a.hdInitDevice("Left");
  const HHD right = a.hdInitDevice("Right");
  const HHD big = a.hdInitDevice("Big");
  ASSERT_NE(left, HD_INVALID_HANDLE);
  ASSERT_NE(right, HD_INVALID_HANDLE);
  ASSERT_NE(big, HD_INVALID_HANDLE);
  EXPECT_NE(left, right);
  EXPECT_NE(right, big);
  EXPECT_EQ(a.hdGetCurrentDevice(), big);  // hdInitDevice makes the new device current

  struct Expect {
    HHD h;
    const char* model;
    const char* serial;
    double radius, force;
    int output_dof, style;
  };
  const Expect expected[] = {
      {left, "Touch", "10001", 75, 3.3, 3, HD_CALIBRATION_INKWELL},
      {right, "Touch X", "10002", 75, 7.9, 3, HD_CALIBRATION_ENCODER_RESET},
      {big, kPremium, "10003", 120, 8.5, 6, HD_CALIBRATION_ENCODER_RESET},
  };
  for (const Expect& e : expected) {
    SCOPED_TRACE(e.model);
    a.hdMakeCurrentDevice(e.h);
    EXPECT_EQ(a.hdGetCurrentDevice(), e.h);
    EXPECT_STREQ(a.hdGetString(HD_DEVICE_MODEL_TYPE), e.model);
    EXPECT_STREQ(a.hdGetString(HD_DEVICE_SERIAL_NUMBER), e.serial);
    EXPECT_STREQ(a.hdGetString(HD_DEVICE_VENDOR), "3D Systems");
    EXPECT_STREQ(a.hdGetString(HD_VERSION), "3.4.0");
    double usable[6], max[6];
    a.hdGetDoublev(HD_USABLE_WORKSPACE_DIMENSIONS, usable);
    a.hdGetDoublev(HD_MAX_WORKSPACE_DIMENSIONS, max);
    for (int i = 0; i < 3; ++i) {
      EXPECT_EQ(usable[i], -e.radius);
      EXPECT_EQ(usable[i + 3], e.radius);
      EXPECT_DOUBLE_EQ(max[i], -1.2 * e.radius);
      EXPECT_DOUBLE_EQ(max[i + 3], 1.2 * e.radius);
    }
    double force = 0, continuous = 0;
    a.hdGetDoublev(HD_NOMINAL_MAX_FORCE, &force);
    a.hdGetDoublev(HD_NOMINAL_MAX_CONTINUOUS_FORCE, &continuous);
    EXPECT_EQ(force, e.force);
    EXPECT_EQ(continuous, e.force / 2);
    HDint in = 0, out = 0, style = 0;
    a.hdGetIntegerv(HD_INPUT_DOF, &in);
    a.hdGetIntegerv(HD_OUTPUT_DOF, &out);
    a.hdGetIntegerv(HD_CALIBRATION_STYLE, &style);
    EXPECT_EQ(in, 6);
    EXPECT_EQ(out, e.output_dof);
    EXPECT_EQ(style, e.style);
    EXPECT_EQ(a.hdCheckCalibrationStyle(), static_cast<HDenum>(e.style));
    HDint rate = 0;
    a.hdGetIntegerv(HD_UPDATE_RATE, &rate);
    EXPECT_EQ(rate, 1000);  // the default rate (SOURCES.md §2.3)
    EXPECT_TRUE(errors().empty());
  }

  // Two buttons: HD_DEVICE_BUTTON_1 and _2.
  ASSERT_EQ(control("button Right 0xff"), 0);
  a.hdMakeCurrentDevice(right);
  HDint buttons = -1;
  a.hdGetIntegerv(HD_CURRENT_BUTTONS, &buttons);
  EXPECT_EQ(buttons, HD_DEVICE_BUTTON_1 | HD_DEVICE_BUTTON_2);
  HDlong lbuttons = -1;
  a.hdGetLongv(HD_CURRENT_BUTTONS, &lbuttons);
  EXPECT_EQ(lbuttons, 3);
  ASSERT_EQ(control("button Right 2"), 0);
  a.hdGetIntegerv(HD_CURRENT_BUTTONS, &buttons);
  EXPECT_EQ(buttons, HD_DEVICE_BUTTON_2);
}

TEST_F(FakeOpenHaptics, WithoutFakeHdDevicesThereIsOneTouchCalledDefaultDevice) {
  attach(nullptr);
  const Api& a = *api_;
  const HHD h = a.hdInitDevice(HD_DEFAULT_DEVICE);
  ASSERT_NE(h, HD_INVALID_HANDLE);
  EXPECT_STREQ(a.hdGetString(HD_DEVICE_MODEL_TYPE), "Touch");
  EXPECT_EQ(a.hdInitDevice("Default Device"), HD_INVALID_HANDLE);  // the same device
  const HDErrorInfo e = a.hdGetError();
  EXPECT_EQ(e.errorCode, HD_DEVICE_ALREADY_INITIATED);
  EXPECT_EQ(e.hHD, h);

  // HD_DEFAULT_DEVICE opens the first of the list; a bad item is left out.
  attach("A=Touch X,B=Falcon,C=Touch");
  EXPECT_EQ(a.hdInitDevice("B"), HD_INVALID_HANDLE);
  EXPECT_EQ(a.hdGetError().errorCode, HD_DEVICE_FAULT);
  ASSERT_NE(a.hdInitDevice(HD_DEFAULT_DEVICE), HD_INVALID_HANDLE);
  EXPECT_STREQ(a.hdGetString(HD_DEVICE_MODEL_TYPE), "Touch X");
  ASSERT_NE(a.hdInitDevice("C"), HD_INVALID_HANDLE);
  EXPECT_STREQ(a.hdGetString(HD_DEVICE_SERIAL_NUMBER), "10002");  // B was left out

  attach("");
  EXPECT_EQ(a.hdInitDevice(HD_DEFAULT_DEVICE), HD_INVALID_HANDLE);
  EXPECT_EQ(a.hdGetError().errorCode, HD_DEVICE_FAULT);
}

TEST_F(FakeOpenHaptics, InitDeviceFailuresGiveTheInvalidHandleAndAnError) {
  attach("Phantom1=Touch,Phantom2=Touch");
  const Api& a = *api_;
  // An unknown name: HD_INVALID_HANDLE and HD_DEVICE_FAULT (SOURCES.md §2.3).
  EXPECT_EQ(a.hdInitDevice("Default PHANToM"), HD_INVALID_HANDLE);
  HDErrorInfo e = a.hdGetError();
  EXPECT_EQ(e.errorCode, HD_DEVICE_FAULT);
  EXPECT_EQ(e.hHD, HD_INVALID_HANDLE);
  EXPECT_EQ(a.hdGetError().errorCode, HD_SUCCESS);  // the stack is empty again

  const HHD h1 = a.hdInitDevice("Phantom1");
  ASSERT_NE(h1, HD_INVALID_HANDLE);
  EXPECT_EQ(a.hdInitDevice("Phantom1"), HD_INVALID_HANDLE);
  EXPECT_EQ(a.hdInitDevice("nobody"), HD_INVALID_HANDLE);
  // Most recent first.
  EXPECT_EQ(errors(), (std::vector<HDerror>{HD_DEVICE_FAULT, HD_DEVICE_ALREADY_INITIATED}));

  // An unplugged device does not answer.
  ASSERT_EQ(control("unplug Phantom2"), 0);
  EXPECT_EQ(a.hdInitDevice("Phantom2"), HD_INVALID_HANDLE);
  EXPECT_EQ(a.hdGetError().errorCode, HD_COMM_ERROR);
  ASSERT_EQ(control("replug Phantom2"), 0);
  const HHD h2 = a.hdInitDevice("Phantom2");
  ASSERT_NE(h2, HD_INVALID_HANDLE);

  // A disabled device's handle is bad; initialized again, it gets a new one.
  a.hdDisableDevice(h1);
  EXPECT_TRUE(errors().empty());
  a.hdMakeCurrentDevice(h1);
  e = a.hdGetError();
  EXPECT_EQ(e.errorCode, HD_BAD_HANDLE);
  EXPECT_EQ(e.hHD, h1);
  EXPECT_EQ(a.hdGetCurrentDevice(), h2);
  const HHD again = a.hdInitDevice("Phantom1");
  EXPECT_NE(again, HD_INVALID_HANDLE);
  EXPECT_NE(again, h1);
  a.hdDisableDevice(h1);
  EXPECT_EQ(a.hdGetError().errorCode, HD_BAD_HANDLE);

  // Every code has its own text.
  const HDerror codes[] = {HD_SUCCESS, HD_INVALID_ENUM, HD_INVALID_VALUE, HD_INVALID_OPERATION,
                           HD_INVALID_INPUT_TYPE, HD_BAD_HANDLE, HD_WARM_MOTORS,
                           HD_EXCEEDED_MAX_FORCE, HD_EXCEEDED_MAX_FORCE_IMPULSE,
                           HD_EXCEEDED_MAX_VELOCITY, HD_FORCE_ERROR, HD_DEVICE_FAULT,
                           HD_DEVICE_ALREADY_INITIATED, HD_COMM_ERROR, HD_COMM_CONFIG_ERROR,
                           HD_TIMER_ERROR, HD_ILLEGAL_BEGIN, HD_ILLEGAL_END, HD_FRAME_ERROR,
                           HD_INVALID_PRIORITY, HD_SCHEDULER_FULL, HD_INVALID_LICENSE};
  for (HDerror c : codes) {
    ASSERT_NE(a.hdGetErrorString(c), nullptr);
    EXPECT_STRNE(a.hdGetErrorString(c), "unknown error") << std::hex << c;
    for (HDerror other : codes)
      if (other < c) {
        EXPECT_STRNE(a.hdGetErrorString(c), a.hdGetErrorString(other));
      }
  }
  EXPECT_STREQ(a.hdGetErrorString(0x9999), "unknown error");
}

TEST_F(FakeOpenHaptics, CalibrationNeedsAnUpdateWithASupportedStyle) {
  attach("T=Touch,P=PHANTOM Premium 1.5 6DOF");
  const Api& a = *api_;
  const HHD t = a.hdInitDevice("T");
  const HHD p = a.hdInitDevice("P");
  a.hdMakeCurrentDevice(t);
  EXPECT_EQ(a.hdCheckCalibration(), HD_CALIBRATION_NEEDS_UPDATE);
  a.hdUpdateCalibration(HD_CALIBRATION_ENCODER_RESET);  // the Touch uses its inkwell
  EXPECT_EQ(a.hdGetError().errorCode, HD_INVALID_VALUE);
  EXPECT_EQ(a.hdCheckCalibration(), HD_CALIBRATION_NEEDS_UPDATE);
  a.hdUpdateCalibration(HD_CALIBRATION_INKWELL);
  EXPECT_EQ(a.hdCheckCalibration(), HD_CALIBRATION_OK);

  a.hdMakeCurrentDevice(p);
  EXPECT_EQ(a.hdCheckCalibration(), HD_CALIBRATION_NEEDS_UPDATE);  // each device on its own
  a.hdUpdateCalibration(HD_CALIBRATION_INKWELL);
  EXPECT_EQ(a.hdGetError().errorCode, HD_INVALID_VALUE);
  a.hdUpdateCalibration(HD_CALIBRATION_ENCODER_RESET);
  EXPECT_EQ(a.hdCheckCalibration(), HD_CALIBRATION_OK);
  EXPECT_TRUE(errors().empty());

  ASSERT_EQ(control("uncalibrate T"), 0);
  a.hdMakeCurrentDevice(t);
  EXPECT_EQ(a.hdCheckCalibration(), HD_CALIBRATION_NEEDS_UPDATE);
  a.hdMakeCurrentDevice(p);
  EXPECT_EQ(a.hdCheckCalibration(), HD_CALIBRATION_OK);
}

TEST_F(FakeOpenHaptics, AForceAlongXMovesTheTipAsTheMassDamperPredicts) {
  struct Case {
    const char* model;
    double m, b;
  };
  for (const Case& c : {Case{"Touch", 0.05, 0.5}, Case{kPremium, 0.1, 1.0}}) {
    SCOPED_TRACE(c.model);
    attach((std::string("Arm=") + c.model).c_str());
    const Api& a = *api_;
    const HHD h = open_ready("Arm");
    int calls = 0;
    Body push = [&] {
      a.hdBeginFrame(a.hdGetCurrentDevice());
      const double f[3] = {1.0, 0.0, 0.0};
      a.hdSetDoublev(HD_CURRENT_FORCE, f);
      a.hdEndFrame(a.hdGetCurrentDevice());
      return ++calls < 100 ? HD_CALLBACK_CONTINUE : HD_CALLBACK_DONE;
    };
    const HDSchedulerHandle sh = a.hdScheduleAsynchronous(run_body, &push, HD_MAX_SCHEDULER_PRIORITY);
    ASSERT_NE(sh, 0u);
    EXPECT_EQ(a.hdWaitForCompletion(sh, HD_WAIT_CHECK_STATUS), HD_TRUE);
    ASSERT_EQ(control("tick 100"), 0);
    EXPECT_EQ(calls, 100);
    EXPECT_EQ(a.hdWaitForCompletion(sh, HD_WAIT_CHECK_STATUS), HD_FALSE);  // it returned DONE

    // mm, in the device frame.
    const double expected = 1000.0 * mass_damper_x(1.0, c.m, c.b, 0.1);
    const Vec p = get3(HD_CURRENT_POSITION);
    EXPECT_NEAR(p.x, expected, 0.01 * expected);
    EXPECT_GT(p.x, 10.0);
    EXPECT_EQ(p.y, 0.0);
    EXPECT_EQ(p.z, 0.0);
    const Vec v = get3(HD_CURRENT_VELOCITY);
    const double expected_v = 1000.0 * mass_damper_v(1.0, c.m, c.b, 0.1);
    EXPECT_NEAR(v.x, expected_v, 0.01 * expected_v);

    // Inside a frame (a synchronous call: one more tick, read before the plant moves on) the
    // transform's translation is the position, and its rotation the identity.
    double frame_p[3] = {}, T[16] = {};
    Body read = [&] {
      a.hdBeginFrame(h);
      a.hdGetDoublev(HD_CURRENT_POSITION, frame_p);
      a.hdGetDoublev(HD_CURRENT_TRANSFORM, T);
      a.hdEndFrame(h);
      return HD_CALLBACK_DONE;
    };
    a.hdScheduleSynchronous(run_body, &read, HD_DEFAULT_SCHEDULER_PRIORITY);
    EXPECT_EQ(frame_p[0], p.x);
    for (int i = 0; i < 3; ++i) EXPECT_EQ(T[12 + i], frame_p[i]);
    for (int r = 0; r < 4; ++r)
      for (int col = 0; col < 3; ++col)
        EXPECT_EQ(T[4 * col + r], r == col ? 1.0 : 0.0) << r << "," << col;
    EXPECT_EQ(T[15], 1.0);
    EXPECT_TRUE(errors().empty());
  }
}

TEST_F(FakeOpenHaptics, NothingMovesWithoutForceOutput) {
  attach(nullptr);
  const Api& a = *api_;
  const HHD h = a.hdInitDevice(HD_DEFAULT_DEVICE);
  EXPECT_EQ(a.hdIsEnabled(HD_FORCE_OUTPUT), HD_FALSE);
  EXPECT_EQ(a.hdIsEnabled(HD_MAX_FORCE_CLAMPING), HD_TRUE);  // on by default
  a.hdStartScheduler();
  double force[3] = {0.5, 0.0, 0.0};  // small enough to stay inside the workspace throughout
  Body push = [&] {
    a.hdBeginFrame(h);
    a.hdSetDoublev(HD_CURRENT_FORCE, force);
    a.hdEndFrame(h);
    return HD_CALLBACK_CONTINUE;
  };
  a.hdScheduleAsynchronous(run_body, &push, HD_DEFAULT_SCHEDULER_PRIORITY);
  ASSERT_EQ(control("tick 100"), 0);
  EXPECT_EQ(get3(HD_CURRENT_POSITION).x, 0.0);
  EXPECT_EQ(get3(HD_CURRENT_FORCE).x, 0.0);  // nothing committed

  a.hdEnable(HD_FORCE_OUTPUT);
  EXPECT_EQ(a.hdIsEnabled(HD_FORCE_OUTPUT), HD_TRUE);
  ASSERT_EQ(control("tick 100"), 0);
  EXPECT_NEAR(get3(HD_CURRENT_POSITION).x, 1000 * mass_damper_x(0.5, 0.05, 0.5, 0.1), 0.3);

  // Disabled again: the tip only coasts.
  a.hdDisable(HD_FORCE_OUTPUT);
  const double v0 = get3(HD_CURRENT_VELOCITY).x;
  ASSERT_EQ(control("tick 100"), 0);
  EXPECT_NEAR(get3(HD_CURRENT_VELOCITY).x, v0 * std::exp(-0.5 / 0.05 * 0.1), 1e-6);
  EXPECT_TRUE(errors().empty());
}

TEST_F(FakeOpenHaptics, TheHandMovesTheTipAndTurnSetsTheGimbal) {
  attach("Pen=Touch");
  const Api& a = *api_;
  const HHD h = a.hdInitDevice("Pen");
  a.hdStartScheduler();
  ASSERT_EQ(control("hand Pen 0 0 -0.5"), 0);  // pushed away from the user
  ASSERT_EQ(control("turn Pen 0 0 0.5"), 0);   // 0.5 rad about z
  ASSERT_EQ(control("tick 50"), 0);
  const Vec p = get3(HD_CURRENT_POSITION);
  EXPECT_NEAR(p.z, 1000 * mass_damper_x(-0.5, 0.05, 0.5, 0.05), 1e-6);
  double T[16];
  a.hdGetDoublev(HD_CURRENT_TRANSFORM, T);
  EXPECT_EQ(T[12], p.x);
  EXPECT_EQ(T[13], p.y);
  EXPECT_EQ(T[14], p.z);
  // Column-major: the first column is R's first column (cos, sin, 0).
  EXPECT_NEAR(T[0], std::cos(0.5), 1e-12);
  EXPECT_NEAR(T[1], std::sin(0.5), 1e-12);
  EXPECT_NEAR(T[4], -std::sin(0.5), 1e-12);
  EXPECT_NEAR(T[10], 1.0, 1e-12);
  const Vec g = get3(HD_CURRENT_GIMBAL_ANGLES);
  EXPECT_NEAR(g.x, 0.0, 1e-12);
  EXPECT_NEAR(g.y, 0.0, 1e-12);
  EXPECT_NEAR(g.z, 0.5, 1e-12);
  EXPECT_EQ(get3(HD_CURRENT_ANGULAR_VELOCITY).z, 0.0);  // a passive gimbal

  // Floats too.
  float fp[3] = {};
  a.hdGetFloatv(HD_CURRENT_POSITION, fp);
  EXPECT_FLOAT_EQ(fp[2], static_cast<float>(p.z));

  // HD_LAST_POSITION is the previous frame's.
  a.hdBeginFrame(h);
  a.hdEndFrame(h);
  ASSERT_EQ(control("tick 10"), 0);
  a.hdBeginFrame(h);
  const Vec now = get3(HD_CURRENT_POSITION), last = get3(HD_LAST_POSITION);
  a.hdEndFrame(h);
  EXPECT_EQ(last.z, p.z);
  EXPECT_LT(now.z, p.z);

  // The position stops at the maximum workspace.
  ASSERT_EQ(control("hand Pen 0 0 -50"), 0);
  ASSERT_EQ(control("tick 2000"), 0);
  EXPECT_DOUBLE_EQ(get3(HD_CURRENT_POSITION).z, -90.0);
  EXPECT_EQ(get3(HD_CURRENT_VELOCITY).z, 0.0);
  EXPECT_TRUE(errors().empty());
}

TEST_F(FakeOpenHaptics, ThePremiumsGimbalTurnsUnderTorqueTheTouchsDoesNot) {
  attach("P=PHANTOM Premium 1.5 6DOF,T=Touch");
  const Api& a = *api_;
  const HHD t = open_ready("T");
  const HHD p = open_ready("P");
  a.hdMakeCurrentDevice(t);
  a.hdEnable(HD_FORCE_OUTPUT);
  HDerror touch_error = HD_SUCCESS;
  Body twist = [&] {
    const double torque[3] = {10.0, 0.0, 0.0};  // mN·m on gimbal joint 0
    a.hdMakeCurrentDevice(p);
    a.hdBeginFrame(p);
    a.hdSetDoublev(HD_CURRENT_GIMBAL_TORQUE, torque);
    a.hdEndFrame(p);
    a.hdMakeCurrentDevice(t);
    a.hdBeginFrame(t);
    a.hdSetDoublev(HD_CURRENT_GIMBAL_TORQUE, torque);
    a.hdEndFrame(t);
    const HDErrorInfo e = a.hdGetError();
    if (e.errorCode != HD_SUCCESS) touch_error = e.errorCode;
    return HD_CALLBACK_CONTINUE;
  };
  a.hdScheduleAsynchronous(run_body, &twist, HD_DEFAULT_SCHEDULER_PRIORITY);
  ASSERT_EQ(control("tick 100"), 0);
  EXPECT_EQ(touch_error, HD_INVALID_OPERATION);
  a.hdMakeCurrentDevice(p);
  const Vec g = get3(HD_CURRENT_GIMBAL_ANGLES);
  EXPECT_NEAR(g.x, mass_damper_x(0.01, 1e-4, 1e-3, 0.1), 1e-9);
  EXPECT_EQ(g.y, 0.0);
  const Vec w = get3(HD_CURRENT_ANGULAR_VELOCITY);
  EXPECT_NEAR(w.y, mass_damper_v(0.01, 1e-4, 1e-3, 0.1), 1e-9);  // joint 0 turns about y (up)
  EXPECT_DOUBLE_EQ(get3(HD_CURRENT_GIMBAL_TORQUE).x, 10.0);
  a.hdMakeCurrentDevice(t);
  EXPECT_EQ(get3(HD_CURRENT_GIMBAL_ANGLES).x, 0.0);
}

TEST_F(FakeOpenHaptics, AFreeRunningSchedulerTicksAtItsRateAndStopsCleanly) {
  attach(nullptr, nullptr);  // FAKE_HD_CLOCK unset: the servo thread
  const Api& a = *api_;
  const HHD h = a.hdInitDevice(HD_DEFAULT_DEVICE);
  std::atomic<int> count{0};
  std::atomic<bool> frame_errors{false};
  Body counter = [&] {
    a.hdBeginFrame(h);
    double p[3];
    a.hdGetDoublev(HD_CURRENT_POSITION, p);
    a.hdEndFrame(h);
    if (a.hdGetError().errorCode != HD_SUCCESS) frame_errors = true;
    ++count;
    return HD_CALLBACK_CONTINUE;
  };
  const HDSchedulerHandle sh = a.hdScheduleAsynchronous(run_body, &counter, HD_MAX_SCHEDULER_PRIORITY);
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_EQ(count.load(), 0);  // not started yet

  // Before hdStartScheduler, a synchronous call runs at once on the caller's thread.
  std::thread::id where;
  Body here = [&] {
    where = std::this_thread::get_id();
    return HD_CALLBACK_DONE;
  };
  a.hdScheduleSynchronous(run_body, &here, HD_DEFAULT_SCHEDULER_PRIORITY);
  EXPECT_EQ(where, std::this_thread::get_id());

  // Ticks against the time they had: never more than the rate allows (a tick or two of slack at
  // either end), and some; a loaded machine may oversleep the 200 ms or starve the servo thread.
  const auto seconds_since = [](std::chrono::steady_clock::time_point from) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - from).count();
  };
  auto started = std::chrono::steady_clock::now();
  a.hdStartScheduler();
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  // Running: a synchronous call runs on the servo thread and returns when done.
  a.hdScheduleSynchronous(run_body, &here, HD_DEFAULT_SCHEDULER_PRIORITY);
  EXPECT_NE(where, std::this_thread::get_id());
  a.hdStopScheduler();
  const int ran = count.load();
  EXPECT_GE(ran, 10);  // about 200 at 1000 Hz
  EXPECT_LE(ran, 1000.0 * seconds_since(started) + 5.0);
  EXPECT_FALSE(frame_errors.load());
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_EQ(count.load(), ran);  // stopped
  EXPECT_EQ(a.hdWaitForCompletion(sh, HD_WAIT_CHECK_STATUS), HD_TRUE);  // still scheduled
  EXPECT_EQ(a.hdWaitForCompletion(sh, HD_WAIT_INFINITE), HD_TRUE);  // no tick can come: at once

  // Started again at 500 Hz, then unscheduled while running.
  a.hdSetSchedulerRate(500);
  EXPECT_TRUE(errors().empty());
  a.hdSetSchedulerRate(1234);
  EXPECT_EQ(a.hdGetError().errorCode, HD_INVALID_VALUE);
  started = std::chrono::steady_clock::now();
  a.hdStartScheduler();
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  a.hdUnschedule(sh);
  const int at_unschedule = count.load();
  EXPECT_GE(at_unschedule - ran, 10);  // about 100 at 500 Hz
  EXPECT_LE(at_unschedule - ran, 500.0 * seconds_since(started) + 5.0);  // 500 Hz, not 1000
  EXPECT_EQ(a.hdWaitForCompletion(sh, HD_WAIT_CHECK_STATUS), HD_FALSE);
  std::this_thread::sleep_for(std::chrono::milliseconds(30));
  EXPECT_EQ(count.load(), at_unschedule);  // never again after hdUnschedule returns
  a.hdStopScheduler();
  a.hdStopScheduler();  // twice is harmless
  const double stamp = a.hdGetSchedulerTimeStamp();
  EXPECT_GE(stamp, 0.0);
}

HDCallbackCode keep_going(void*) { return HD_CALLBACK_CONTINUE; }

TEST_F(FakeOpenHaptics, ExitingWithTheSchedulerRunningIsClean) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  attach(nullptr, nullptr);
  EXPECT_EXIT(
      {
        api_->hdInitDevice(HD_DEFAULT_DEVICE);
        api_->hdScheduleAsynchronous(keep_going, nullptr, HD_DEFAULT_SCHEDULER_PRIORITY);
        api_->hdStartScheduler();
        std::this_thread::sleep_for(std::chrono::milliseconds(30));
        std::exit(0);
      },
      ::testing::ExitedWithCode(0), "");
}

TEST_F(FakeOpenHaptics, ScheduledCallbacksRunInDecreasingPriority) {
  attach(nullptr);
  const Api& a = *api_;
  a.hdInitDevice(HD_DEFAULT_DEVICE);
  std::string order;
  Body low = [&] {
    order += "L";
    return HD_CALLBACK_CONTINUE;
  };
  Body high = [&] {
    order += "H";
    return HD_CALLBACK_CONTINUE;
  };
  Body mid = [&] {
    order += "M";
    return HD_CALLBACK_DONE;
  };
  a.hdScheduleAsynchronous(run_body, &low, HD_MIN_SCHEDULER_PRIORITY);
  a.hdScheduleAsynchronous(run_body, &high, HD_MAX_SCHEDULER_PRIORITY);
  a.hdStartScheduler();
  a.hdScheduleSynchronous(run_body, &mid, HD_DEFAULT_SCHEDULER_PRIORITY);  // one tick
  EXPECT_EQ(order, "HML");
  ASSERT_EQ(control("tick 2"), 0);
  EXPECT_EQ(order, "HMLHLHL");

  // Scheduled from inside a tick: a synchronous call runs at once; an asynchronous one runs at
  // once and then from the next tick on.
  order.clear();
  Body nested = [&] {
    order += "N";
    a.hdScheduleSynchronous(run_body, &mid, HD_MIN_SCHEDULER_PRIORITY);
    a.hdScheduleAsynchronous(run_body, &mid, HD_MAX_SCHEDULER_PRIORITY);  // DONE: runs once
    return HD_CALLBACK_DONE;
  };
  a.hdScheduleAsynchronous(run_body, &nested, HD_DEFAULT_SCHEDULER_PRIORITY);
  ASSERT_EQ(control("tick 2"), 0);
  EXPECT_EQ(order, "HNMMLHL");

  // Stopped: no tick; a synchronous call runs at once on the caller.
  a.hdStopScheduler();
  EXPECT_EQ(control("tick 1"), -1);
  order.clear();
  a.hdScheduleSynchronous(run_body, &mid, HD_DEFAULT_SCHEDULER_PRIORITY);
  EXPECT_EQ(order, "M");
}

TEST_F(FakeOpenHaptics, FramesMisusedPushIllegalBeginAndEnd) {
  attach(nullptr);
  const Api& a = *api_;
  const HHD h = a.hdInitDevice(HD_DEFAULT_DEVICE);
  a.hdEndFrame(h);
  EXPECT_EQ(a.hdGetError().errorCode, HD_ILLEGAL_END);
  a.hdBeginFrame(h);
  a.hdBeginFrame(h);
  EXPECT_EQ(a.hdGetError().errorCode, HD_ILLEGAL_BEGIN);
  a.hdEndFrame(h);
  EXPECT_TRUE(errors().empty());
  a.hdBeginFrame(h + 7);
  const HDErrorInfo e = a.hdGetError();
  EXPECT_EQ(e.errorCode, HD_BAD_HANDLE);
  EXPECT_EQ(e.hHD, h + 7);

  // A force outside a frame is refused; parameters of the wrong type or unknown are too.
  a.hdEnable(HD_FORCE_OUTPUT);
  const double f[3] = {1, 0, 0};
  a.hdSetDoublev(HD_CURRENT_FORCE, f);
  EXPECT_EQ(a.hdGetError().errorCode, HD_INVALID_OPERATION);
  const HDint i3[3] = {1, 0, 0};
  a.hdBeginFrame(h);
  a.hdSetIntegerv(HD_CURRENT_FORCE, i3);
  EXPECT_EQ(a.hdGetError().errorCode, HD_INVALID_INPUT_TYPE);
  const double bad[3] = {NAN, 0, 0};
  a.hdSetDoublev(HD_CURRENT_FORCE, bad);
  EXPECT_EQ(a.hdGetError().errorCode, HD_INVALID_VALUE);
  a.hdSetDoublev(HD_CURRENT_POSITION, f);
  EXPECT_EQ(a.hdGetError().errorCode, HD_INVALID_ENUM);
  a.hdEndFrame(h);
  HDint ip[3] = {7, 7, 7};
  a.hdGetIntegerv(HD_CURRENT_POSITION, ip);
  EXPECT_EQ(a.hdGetError().errorCode, HD_INVALID_INPUT_TYPE);
  EXPECT_EQ(ip[0], 7);
  double d = 7;
  a.hdGetDoublev(HD_DEVICE_MODEL_TYPE, &d);
  EXPECT_EQ(a.hdGetError().errorCode, HD_INVALID_INPUT_TYPE);
  a.hdGetDoublev(0x2999, &d);
  EXPECT_EQ(a.hdGetError().errorCode, HD_INVALID_ENUM);
  EXPECT_EQ(d, 7.0);
  EXPECT_EQ(a.hdGetString(HD_CURRENT_POSITION), nullptr);
  EXPECT_EQ(a.hdGetError().errorCode, HD_INVALID_INPUT_TYPE);
  a.hdEnable(0x4999);
  EXPECT_EQ(a.hdGetError().errorCode, HD_INVALID_ENUM);
  EXPECT_TRUE(errors().empty());
}

TEST_F(FakeOpenHaptics, UnplugMakesCallsFailWithCommErrorAndReplugNeedsForcesAgain) {
  attach("Default Device=Touch");
  const Api& a = *api_;
  const HHD h = open_ready("Default Device");
  double p[3] = {1234, 1234, 1234};
  std::vector<HDerror> seen;
  double force[3] = {1, 0, 0};
  Body servo = [&] {
    a.hdBeginFrame(h);
    a.hdGetDoublev(HD_CURRENT_POSITION, p);
    a.hdSetDoublev(HD_CURRENT_FORCE, force);
    a.hdEndFrame(h);
    for (HDErrorInfo e = a.hdGetError(); e.errorCode != HD_SUCCESS; e = a.hdGetError()) {
      seen.push_back(e.errorCode);
      EXPECT_EQ(e.hHD, h);
    }
    return HD_CALLBACK_CONTINUE;
  };
  a.hdScheduleAsynchronous(run_body, &servo, HD_MAX_SCHEDULER_PRIORITY);
  ASSERT_EQ(control("tick 20"), 0);
  EXPECT_TRUE(seen.empty());
  const double x_before = p[0];
  EXPECT_GT(x_before, 0.0);

  ASSERT_EQ(control("unplug Default Device"), 0);
  p[0] = p[1] = p[2] = 1234;
  ASSERT_EQ(control("tick 1"), 0);
  // hdBeginFrame, hdGetDoublev, hdSetDoublev, hdEndFrame: each HD_COMM_ERROR (most recent first).
  EXPECT_EQ(seen, (std::vector<HDerror>(4, HD_COMM_ERROR)));
  EXPECT_EQ(p[0], 1234.0);  // untouched
  EXPECT_EQ(p[1], 1234.0);
  a.hdGetDoublev(HD_CURRENT_POSITION, p);
  EXPECT_EQ(a.hdGetError().errorCode, HD_COMM_ERROR);
  EXPECT_EQ(a.hdGetString(HD_DEVICE_MODEL_TYPE), nullptr);
  EXPECT_EQ(a.hdGetError().errorCode, HD_COMM_ERROR);
  a.hdEnable(HD_FORCE_OUTPUT);
  EXPECT_EQ(a.hdGetError().errorCode, HD_COMM_ERROR);

  ASSERT_EQ(control("replug Default Device"), 0);
  seen.clear();
  ASSERT_EQ(control("tick 1"), 0);
  EXPECT_TRUE(seen.empty());
  EXPECT_NE(p[0], 1234.0);
  EXPECT_EQ(a.hdIsEnabled(HD_FORCE_OUTPUT), HD_FALSE);  // forces stay off after a reconnect
  const double v0 = get3(HD_CURRENT_VELOCITY).x;
  ASSERT_EQ(control("tick 100"), 0);
  EXPECT_NEAR(get3(HD_CURRENT_VELOCITY).x, v0 * std::exp(-1.0), 1e-6);  // coasting only
  a.hdEnable(HD_FORCE_OUTPUT);
  ASSERT_EQ(control("tick 30"), 0);
  EXPECT_GT(get3(HD_CURRENT_VELOCITY).x, 300.0);  // pushed again (coasting, it would be < 150)
  EXPECT_TRUE(seen.empty());
}

TEST_F(FakeOpenHaptics, AHungBeginFrameWaitsForReleaseWithoutLockingTheLibrary) {
  attach("Default Device=Touch,Other=Touch X");
  const Api& a = *api_;
  const HHD h = a.hdInitDevice(HD_DEFAULT_DEVICE);
  a.hdInitDevice("Other");
  a.hdStartScheduler();
  std::atomic<int> frames{0};
  Body servo = [&] {
    a.hdBeginFrame(h);
    a.hdEndFrame(h);
    ++frames;
    return HD_CALLBACK_CONTINUE;
  };
  a.hdScheduleAsynchronous(run_body, &servo, HD_DEFAULT_SCHEDULER_PRIORITY);
  ASSERT_EQ(control("hang Default Device"), 0);
  std::atomic<int> result{99};
  std::thread ticker([&] { result = a.fake_hd_control("tick 1"); });
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (a.fake_hd_blocked() == 0 && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  EXPECT_EQ(a.fake_hd_blocked(), 1);
  EXPECT_EQ(result.load(), 99);
  EXPECT_EQ(frames.load(), 0);
  // The library is not locked meanwhile.
  EXPECT_STREQ(a.hdGetString(HD_DEVICE_MODEL_TYPE), "Touch X");
  EXPECT_EQ(control("hand Other 0 1 0"), 0);
  ASSERT_EQ(control("release"), 0);
  ticker.join();
  EXPECT_EQ(result.load(), 0);
  EXPECT_EQ(frames.load(), 1);
  EXPECT_EQ(a.fake_hd_blocked(), 0);
  ASSERT_EQ(control("tick 1"), 0);  // one frame only
  EXPECT_EQ(frames.load(), 2);

  // With a time limit, it returns by itself.
  ASSERT_EQ(control("hang Default Device 0.05"), 0);
  const auto start = std::chrono::steady_clock::now();
  ASSERT_EQ(control("tick 1"), 0);
  EXPECT_GE(std::chrono::steady_clock::now() - start, std::chrono::milliseconds(45));
  EXPECT_EQ(frames.load(), 3);
  EXPECT_TRUE(errors().empty());
}

TEST_F(FakeOpenHaptics, ForcesAboveTheNominalMaximumPushExceededMaxForceAndAreClamped) {
  attach(nullptr);
  const Api& a = *api_;
  const HHD h = open_ready(HD_DEFAULT_DEVICE);
  std::vector<HDerror> seen;
  double force[3] = {5.0, 0.0, 0.0};  // the Touch's nominal maximum is 3.3 N
  Body servo = [&] {
    a.hdBeginFrame(h);
    a.hdSetDoublev(HD_CURRENT_FORCE, force);
    a.hdEndFrame(h);
    for (HDErrorInfo e = a.hdGetError(); e.errorCode != HD_SUCCESS; e = a.hdGetError())
      seen.push_back(e.errorCode);
    return HD_CALLBACK_CONTINUE;
  };
  a.hdScheduleAsynchronous(run_body, &servo, HD_DEFAULT_SCHEDULER_PRIORITY);
  ASSERT_EQ(control("tick 20"), 0);
  EXPECT_EQ(seen, (std::vector<HDerror>(20, HD_EXCEEDED_MAX_FORCE)));
  EXPECT_TRUE(errors().empty());  // on the thread that ended the frame only
  const double expected = 1000 * mass_damper_x(3.3, 0.05, 0.5, 0.02);
  EXPECT_NEAR(get3(HD_CURRENT_POSITION).x, expected, 0.01 * expected);
  EXPECT_DOUBLE_EQ(get3(HD_CURRENT_FORCE).x, 3.3);  // the committed force, clamped

  // A force within the maximum: no error.
  seen.clear();
  force[0] = -3.0, force[1] = 1.0;
  ASSERT_EQ(control("tick 1"), 0);
  EXPECT_TRUE(seen.empty());
  EXPECT_EQ(get3(HD_CURRENT_FORCE).x, -3.0);

  // Without clamping the error stays and the frame's force is dropped.
  a.hdDisable(HD_MAX_FORCE_CLAMPING);
  EXPECT_EQ(a.hdIsEnabled(HD_MAX_FORCE_CLAMPING), HD_FALSE);
  force[0] = 0, force[1] = 0, force[2] = 4;
  ASSERT_EQ(control("tick 1"), 0);
  EXPECT_EQ(seen, std::vector<HDerror>{HD_EXCEEDED_MAX_FORCE});
  const Vec f = get3(HD_CURRENT_FORCE);
  EXPECT_EQ(f.x, 0.0);
  EXPECT_EQ(f.z, 0.0);
}

TEST_F(FakeOpenHaptics, TheCallLogCountsRepeatedCalls) {
  attach(nullptr);
  const Api& a = *api_;
  const HHD h = a.hdInitDevice(HD_DEFAULT_DEVICE);
  a.hdInitDevice("nobody");
  a.hdEnable(HD_FORCE_OUTPUT);
  a.hdStartScheduler();
  a.fake_hd_clear_calls();
  EXPECT_STREQ(a.fake_hd_calls(), "");
  double p[3];
  for (int i = 0; i < 42; ++i) a.hdGetDoublev(HD_CURRENT_POSITION, p);
  a.hdBeginFrame(h);
  const double f[3] = {0.25, 0, -1};
  for (int i = 0; i < 3; ++i) a.hdSetDoublev(HD_CURRENT_FORCE, f);
  a.hdEndFrame(h);
  a.hdGetError();
  a.hdGetError();
  a.hdUpdateCalibration(HD_CALIBRATION_INKWELL);
  a.hdInitDevice(HD_DEFAULT_DEVICE);
  a.hdInitDevice(HD_DEFAULT_DEVICE);  // not a high-rate call: listed twice
  a.hdStopScheduler();
  EXPECT_STREQ(a.fake_hd_calls(),
               "hdGetDoublev 0x2050 x42\n"
               "hdBeginFrame 0\n"
               "hdSetDoublev 0x2700 0.25 0 -1 x3\n"
               "hdEndFrame 0\n"
               "hdGetError x2\n"
               "hdUpdateCalibration 0x0004\n"
               "hdInitDevice NULL\n"
               "hdInitDevice NULL\n"
               "hdStopScheduler\n");
  a.fake_hd_clear_calls();
  EXPECT_STREQ(a.fake_hd_calls(), "");
  a.hdInitDevice("Default Device");
  EXPECT_STREQ(a.fake_hd_calls(), "hdInitDevice \"Default Device\"\n");
}

TEST_F(FakeOpenHaptics, ErrorsArePerThread) {
  attach(nullptr);
  const Api& a = *api_;
  EXPECT_EQ(a.hdInitDevice("nobody"), HD_INVALID_HANDLE);
  HDerror other = 0xdead;
  std::thread([&] { other = a.hdGetError().errorCode; }).join();
  EXPECT_EQ(other, HD_SUCCESS);
  EXPECT_EQ(a.hdGetError().errorCode, HD_DEVICE_FAULT);
  // `reset` empties every thread's stack.
  EXPECT_EQ(a.hdInitDevice("nobody"), HD_INVALID_HANDLE);
  ASSERT_EQ(control("reset"), 0);
  EXPECT_EQ(a.hdGetError().errorCode, HD_SUCCESS);
}

TEST_F(FakeOpenHaptics, FakeHdScriptActsAtTheGivenTicks) {
  attach("Default Device=Touch", "manual",
         "2 unplug Default Device; 4 replug Default Device;0 hand Default Device 0 1 0");
  const Api& a = *api_;
  const HHD h = a.hdInitDevice(HD_DEFAULT_DEVICE);
  a.hdStartScheduler();
  std::vector<int> failed;
  Body servo = [&] {
    a.hdBeginFrame(h);
    a.hdEndFrame(h);
    int n = 0;
    while (a.hdGetError().errorCode != HD_SUCCESS) ++n;
    failed.push_back(n);
    return HD_CALLBACK_CONTINUE;
  };
  a.hdScheduleAsynchronous(run_body, &servo, HD_DEFAULT_SCHEDULER_PRIORITY);
  ASSERT_EQ(control("tick 6"), 0);
  EXPECT_EQ(failed, (std::vector<int>{0, 0, 2, 2, 0, 0}));  // unplugged after 2 ticks, back at 4
  EXPECT_GT(get3(HD_CURRENT_POSITION).y, 0.0);              // the tick-0 hand force
}

TEST_F(FakeOpenHaptics, TheControlApiRefusesWhatItDoesNotUnderstand) {
  attach("Default Device=Touch");
  EXPECT_EQ(control("bogus"), -1);
  EXPECT_EQ(control(""), -1);
  EXPECT_EQ(control("hand Nobody 1 2 3"), -1);
  EXPECT_EQ(control("hand Default Device 1 2"), -1);
  EXPECT_EQ(control("hand Default Device 1 2 x"), -1);
  EXPECT_EQ(control("turn Default Device 0 0"), -1);
  EXPECT_EQ(control("button Default Device"), -1);
  EXPECT_EQ(control("hang Default Device soon"), -1);
  EXPECT_EQ(control("unplug"), -1);
  EXPECT_EQ(control("tick 1"), -1);  // the scheduler is not started
  EXPECT_EQ(control("tick 0"), -1);
  EXPECT_EQ(control("reset now"), -1);
  EXPECT_EQ(api_->fake_hd_control(nullptr), -1);
  EXPECT_EQ(control("hand Default Device 1 2 3"), 0);
  EXPECT_EQ(control("release"), 0);

  attach("Default Device=Touch", nullptr);  // the servo thread: `tick` is refused
  api_->hdInitDevice(HD_DEFAULT_DEVICE);
  api_->hdStartScheduler();
  EXPECT_EQ(control("tick 1"), -1);
  api_->hdStopScheduler();
}

}  // namespace
