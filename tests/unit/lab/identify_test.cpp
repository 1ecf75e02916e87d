// haptic-lab identify on the devices themselves, in lockstep: the point mass's mass and damping
// come back as its configuration gives them, with the hold's half tick as its delay; a run that
// carries the tool out of its box is stopped and refused saying how to change it.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <initializer_list>
#include <numbers>
#include <set>
#include <string>

#include "config/server_config.hpp"
#include "engine/scene/impedance.hpp"
#include "lab/device_zwidth.hpp"
#include "lab/identify.hpp"
#ifdef HAPLY_DRIVER
#include "driver/standins/fake_haply_service.hpp"
#endif
#ifdef OPENHAPTICS_DRIVER
#include "driver/driver_test_support.hpp"
#endif

namespace haptic::lab {
namespace {

IdentifyParams light_excitation(double amplitude_n) {
  IdentifyParams p;
  p.axis = 0;
  p.signal.amplitude_n = amplitude_n;
  p.signal.periods = 6;
  return p;
}

TEST(LabIdentify, ThePointMassIsItsConfiguredMassAndDampingWithTheHoldsHalfTick) {
  // Eom et al.'s device: 10 g, 0.022 N·s/m, at 1 kHz (the configuration's defaults).
  const v1::ServerConfig config = config::parse_config(R"({"time_mode": "LOCKSTEP"})", "test");
  const IdentifyParams params = light_excitation(0.02);
  const IdentifyResult result = identify(config, params, "test");
  ASSERT_TRUE(result.model_mass && result.model_damping) << result.model_method;
  EXPECT_EQ(result.model_method, "description");
  EXPECT_NEAR(result.fit.mass.value, 0.01, 0.01 * 0.01);
  EXPECT_NEAR(result.fit.damping.value, 0.022, 0.05 * 0.022);
  EXPECT_NEAR(result.fit.delay.value, 0.5e-3, 0.1e-3);
  EXPECT_NEAR(result.fit.coulomb.value, 0.0, 1e-4);
  EXPECT_LT(result.fit.relative_residual, 0.01);
  const std::string report = identify_report(result, params, "test");
  EXPECT_NE(report.find("| mass (kg) |"), std::string::npos) << report;
  EXPECT_EQ(report.find("compare --fit moving"), std::string::npos) << report;  // no friction to speak of
  const std::string csv = identify_response_csv(result);
  EXPECT_EQ(csv.rfind("frequency_hz,measured_m_per_n", 0), 0u);
  std::printf("%s", report.c_str());
}

TEST(LabIdentify, AnExcitationThatCarriesTheToolOutOfItsBoxIsStoppedAndRefusedSayingWhatToChange) {
  const v1::ServerConfig config = config::parse_config(R"({"time_mode": "LOCKSTEP"})", "test");
  const auto refusal = [&](const IdentifyParams& params) {
    try {
      identify(config, params, "test");
    } catch (const std::invalid_argument& error) {
      return std::string(error.what());
    }
    return std::string("not refused");
  };
  // 2 N on 10 g: faster than 0.5 m/s within a quarter second.
  std::string what = refusal(light_excitation(2.0));
  EXPECT_NE(what.find("the excitation stopped at tick"), std::string::npos) << what;
  EXPECT_NE(what.find("faster than"), std::string::npos) << what;
  EXPECT_NE(what.find("lower the amplitude"), std::string::npos) << what;
  // Allowed any speed, it leaves its ±50 mm box instead.
  IdentifyParams fast = light_excitation(2.0);
  fast.limits.max_speed_m_s = 100.0;
  what = refusal(fast);
  EXPECT_NE(what.find("left its box of ±50"), std::string::npos) << what;
  IdentifyParams bad = light_excitation(0.02);
  bad.axis = 3;
  EXPECT_THROW(identify(config, bad, "test"), std::invalid_argument);
  bad = light_excitation(0.02);
  bad.port = 4;
  EXPECT_THROW(identify(config, bad, "test"), std::invalid_argument);
  bad = light_excitation(0.02);
  bad.centering = {-5.0, 0.0};
  what = refusal(bad);
  EXPECT_NE(what.find("centering: stiffness and damping must be finite and >= 0"), std::string::npos) << what;
  bad.centering = {5.0, std::nan("")};
  EXPECT_NE(refusal(bad).find("centering:"), std::string::npos);
}

/// The Z-width the identified model predicts against the device's own, walls of increasing K run
/// on it in lockstep along the identified direction (check_zwidth), at `dampings`: each within
/// 10 %. Returns the largest error (a fraction).
double predicted_against_measured(const v1::ServerConfig& config, const IdentifyParams& params,
                                  const IdentifyResult& id, const std::vector<double>& dampings) {
  const std::vector<ZWidthCheck> checks = check_zwidth(config, params, id, dampings);
  std::printf("%s", zwidth_report(checks).c_str());
  double worst = 0.0;
  for (const ZWidthCheck& c : checks) {
    EXPECT_NEAR(c.predicted, c.measured, 0.10 * c.measured) << "B = " << c.damping;
    // One boundary: no wall above the first that rings settles again (looked for where a sensor's
    // noise or step, or friction, might make it).
    EXPECT_TRUE(c.settles_above.empty()) << "B = " << c.damping << ": " << c.settles_above.front() << " N/m";
    worst = std::max(worst, std::abs(c.predicted - c.measured) / c.measured);
  }
  return worst;
}

double predicted_against_measured(const v1::ServerConfig& config, const IdentifyParams& params,
                                  const std::vector<double>& dampings) {
  return predicted_against_measured(config, params, identify(config, params, "test"), dampings);
}

TEST(LabIdentify, TheIdentifiedModelPredictsThePointMasssOwnZWidthWithin10Percent) {
  const v1::ServerConfig config = config::parse_config(R"({"time_mode": "LOCKSTEP"})", "test");
  EXPECT_LT(predicted_against_measured(config, light_excitation(0.02), {0.0, 0.1, 0.3}), 0.01);
}

TEST(LabIdentify, ThePointMassWithANoisyQuantizedSensorIsStillItsMassAndPredictsItsZWidth) {
  // The same device measured as a real one is: 2 µm of noise, a 5 µm step, the velocity the
  // difference of what is measured.
  const v1::ServerConfig config = config::parse_config(R"({"time_mode": "LOCKSTEP",
      "simulated_point_mass": {"sensor": {"noise_m": 2e-6, "quantization_m": 5e-6, "seed": 3}}})", "test");
  const IdentifyParams params = light_excitation(0.02);
  const IdentifyResult id = identify(config, params, "test");
  EXPECT_NEAR(id.fit.mass.value, 0.01, 0.05 * 0.01);
  EXPECT_NEAR(id.fit.damping.value, 0.022, 0.05 * 0.022);
  ASSERT_TRUE(id.fit.quantization_m) << identify_report(id, params, "test");
  EXPECT_NEAR(*id.fit.quantization_m, 5e-6, 1e-12);
  EXPECT_NEAR(id.fit.noise_rms_m, std::sqrt(4e-12 + 25e-12 / 12.0), 0.5e-6);
  std::printf("%s", identify_report(id, params, "test").c_str());
  EXPECT_LT(predicted_against_measured(config, params, {0.0, 0.1, 0.3}), 0.10);
}

TEST(LabIdentify, OnADeviceThatNeverSticksTheFitInTimeAgreesWithTheHarmonics) {
  // The point mass through its noisy, quantized sensor: no friction holds it, so every stretch
  // between reversals is fitted, and the fit in time finds what the harmonics find.
  const v1::ServerConfig config = config::load_config_file(std::string(HAPTIC_SOURCE_DIR) + "/config/point_mass_sensor.json");
  IdentifyParams params = light_excitation(0.02);
  params.fit_method = engine::FitMethod::kMovingStretches;
  const IdentifyResult id = identify(config, params, "test");
  std::printf("%s", identify_report(id, params, "test").c_str());
  EXPECT_GT(id.fit.moving_fraction, 0.5);
  EXPECT_NEAR(id.fit.mass.value, 0.01, 0.01 * 0.01);
  EXPECT_NEAR(id.fit.damping.value, 0.022, 0.05 * 0.022);
  EXPECT_NEAR(id.fit.delay.value, 0.5e-3, 0.1e-3);
  EXPECT_NEAR(id.fit.coulomb.value, 0.0, 2e-4);
}

TEST(LabIdentify, ASweepsIntervalsNarrowWithTheExcitationsLengthAndAmplitude) {
  const v1::ServerConfig config = config::load_config_file(std::string(HAPTIC_SOURCE_DIR) + "/config/point_mass_sensor.json");
  const std::vector<IdentifySweepRow> rows =
      identify_sweep(config, light_excitation(0.01), {4, 16}, {0.005, 0.02}, "point_mass_sensor");
  ASSERT_EQ(rows.size(), 4u);
  // Per amplitude, four times the periods: a narrower interval, and a longer run.
  for (std::size_t a = 0; a < 2; ++a) {
    EXPECT_LT(rows[2 * a + 1].mass_half_width, rows[2 * a].mass_half_width);
    EXPECT_LT(rows[2 * a + 1].damping_half_width, rows[2 * a].damping_half_width);
    EXPECT_GT(rows[2 * a + 1].excitation_s, rows[2 * a].excitation_s);
  }
  // Four times the amplitude: narrower still, at the same length.
  EXPECT_LT(rows[2].damping_half_width, rows[0].damping_half_width);
  for (const IdentifySweepRow& r : rows) EXPECT_LT(r.mass_error, 0.01);
  EXPECT_EQ(identify_sweep_csv(rows).rfind("amplitude_n,periods,excitation_s,cpu_s,mass_error", 0), 0u);
}

TEST(LabIdentify, AProfileIsEachAxissMassAndDampingAndADriverPortTakesIt) {
  const v1::ServerConfig config = config::load_config_file(std::string(HAPTIC_SOURCE_DIR) + "/config/point_mass_sensor.json");
  const v1::DeviceProfile profile = identify_profile(config, light_excitation(0.02), "point_mass_sensor");
  for (const double mass : {profile.apparent_mass().x(), profile.apparent_mass().y(), profile.apparent_mass().z()}) {
    EXPECT_NEAR(mass, 0.01, 0.01 * 0.01);
  }
  for (const double b : {profile.apparent_damping().x(), profile.apparent_damping().y(), profile.apparent_damping().z()}) {
    EXPECT_NEAR(b, 0.022, 0.05 * 0.022);
  }
  EXPECT_LT(profile.delay_s(), 1e-4);  // the point mass adds none to the hold's half tick
  // A driver port's configuration takes it as it is.
  v1::ServerConfig driver;
  driver.set_time_mode(v1::LOCKSTEP);
  driver.mutable_driver()->set_library("x.so");
  *driver.mutable_driver()->mutable_profile() = profile;
  config::fill_defaults(driver);
  EXPECT_EQ(config::validate(driver), "");
}

/// config/`file` in lockstep, its `device` read through `encoders` (a SimulatedEncoderConfig in JSON).
v1::ServerConfig lockstep_config(const std::string& file, const std::string& device, const std::string& encoders) {
  v1::ServerConfig config = config::load_config_file(std::string(HAPTIC_SOURCE_DIR) + "/config/" + file);
  config.set_time_mode(v1::LOCKSTEP);
  v1::ServerConfig overlay = config::parse_config(R"({")" + device + R"(": {"encoders": )" + encoders + "}}", "test");
  config.MergeFrom(overlay);
  return config;
}

TEST(LabIdentify, TheDcMotorThroughItsEncoderAlongItsLinksTangentIsItsModelAndPredictsItsZWidth) {
  // 000's DC motor, its gearbox and link, read through a 2,000-line quadrature encoder on the
  // motor (π/4000 rad a count, 15.7 µm at the tool) with 0.2 mrad of noise: the tool moves on a
  // circle, so it is excited along the motion a push along y gives (the link's tangent).
  const v1::ServerConfig config = lockstep_config("dc_motor_000.json", "simulated_dc_motor",
                                                  R"({"quantization": [7.853981633974483e-4], "noise": [2e-4], "seed": 7})");
  IdentifyParams params = light_excitation(1.0);
  params.axis = 1;
  params.along_motion = true;
  const IdentifyResult id = identify(config, params, "test");
  // The tangent at the start, 0.5 rad: |y| = cos 0.5 = 0.878; the push's chord through the
  // encoder's counts bends it by a few thousandths.
  EXPECT_NEAR(std::abs(id.direction.y), std::cos(0.5), 0.01);
  ASSERT_TRUE(id.model_mass && id.model_damping);
  EXPECT_NEAR(id.fit.mass.value, *id.model_mass, 0.05 * *id.model_mass);
  EXPECT_NEAR(id.fit.damping.value, *id.model_damping, 0.05 * *id.model_damping);
  EXPECT_GT(id.fit.noise_rms_m, 2e-6);  // the encoder's noise and step, seen
  std::printf("%s", identify_report(id, params, "test").c_str());
  predicted_against_measured(config, params, {1.0, 5.0, 20.0});
}

TEST(LabIdentify, The6DofHandleWithANoisySensorIsItsMassAndPredictsItsZWidth) {
  // The 6-DOF point mass (config/six_dof.json: its handle turns too, held by orientation fields)
  // measured with 2 µm of noise and a 5 µm step, along each axis of W in turn.
  v1::ServerConfig config = config::load_config_file(std::string(HAPTIC_SOURCE_DIR) + "/config/six_dof.json");
  config.set_time_mode(v1::LOCKSTEP);
  config.mutable_simulated_point_mass()->mutable_sensor()->set_noise_m(2e-6);
  config.mutable_simulated_point_mass()->mutable_sensor()->set_quantization_m(5e-6);
  for (const int axis : {0, 2}) {
    IdentifyParams params = light_excitation(0.02);
    params.axis = axis;
    const IdentifyResult id = identify(config, params, "test");
    EXPECT_NEAR(id.fit.mass.value, 0.01, 0.05 * 0.01) << "axis " << axis;
    EXPECT_NEAR(id.fit.damping.value, 0.022, 0.05 * 0.022) << "axis " << axis;
    predicted_against_measured(config, params, {0.0, 0.1, 0.3});
  }
}

TEST(LabIdentify, TheParallelDeviceWithItsObserverThroughEncodersIsItsNominalMassAndItsDelayPredictsItsZWidth) {
  // 001's parallel device, its disturbance observer shaping it into the nominal 10 g and
  // 0.022 N·s/m, its joints read through 20,000-count encoders with 20 µrad of noise. The
  // observer's Q filter adds a lag the description does not know (it predicts a Z-width 2 to 8
  // times too high, below); the identification finds it as a delay (about 1 ms on y, 3.4 ms on x)
  // and predicts the device's own within 10 %. The band stops at 9 Hz, where the walls ring
  // (3.5 to 15 Hz): the observer's x axis is a mass-damper-and-delay only over a narrow band, and
  // its damping moves with the band's top (+2.7 % at 8 Hz, −3.0 % at 9, −6.1 % at 10, +9 % at 15,
  // −27 % at 40 Hz).
  const v1::ServerConfig config = lockstep_config("parallel_dob_001.json", "simulated_parallel_dob",
                                                  R"({"quantization": [1.5707963267948966e-4], "noise": [2e-5], "seed": 7})");
  for (const int axis : {0, 1}) {
    IdentifyParams params = light_excitation(0.05);
    params.axis = axis;
    params.signal.f_max_hz = 9.0;
    const IdentifyResult id = identify(config, params, "test");
    std::printf("%s", identify_report(id, params, "test").c_str());
    EXPECT_NEAR(id.fit.mass.value, 0.01, 0.05 * 0.01) << "axis " << axis;
    EXPECT_NEAR(id.fit.damping.value, 0.022, 0.05 * 0.022) << "axis " << axis;
    EXPECT_GT(id.fit.delay.value, 1.0e-3) << "axis " << axis;
    const std::vector<ZWidthCheck> checks = check_zwidth(config, params, id, {0.0, 0.1, 0.3});
    std::printf("%s", zwidth_report(checks).c_str());
    for (const ZWidthCheck& c : checks) {
      EXPECT_NEAR(c.predicted, c.measured, 0.10 * c.measured) << "axis " << axis << ", B = " << c.damping;
      ASSERT_TRUE(c.described);
      EXPECT_GT(*c.described, 2.0 * c.measured) << "the description, which knows no lag, is far too high";
    }
    // Fitted with a first-order lag instead (--lag): the observer's Q filter is one, and the mass
    // and damping come within 2 % on both axes (x: +1.2 % and −1.9 %). Its Z-width from that
    // model is 11 to 30 % low (docs/identification.md): for the walls the delay's model is the
    // better one.
    params.max_lag_s = 0.01;
    const IdentifyResult lagged = identify(config, params, "test");
    EXPECT_NEAR(lagged.fit.mass.value, 0.01, 0.05 * 0.01) << "axis " << axis;
    EXPECT_NEAR(lagged.fit.damping.value, 0.022, 0.05 * 0.022) << "axis " << axis;
    EXPECT_GT(lagged.fit.lag.value, 1e-3) << "axis " << axis;
  }
}

/// 003's five-bar on the bench (config/five_bar_bench_003.json, in lockstep: its π/6000 encoders,
/// 157 µm at the tool; the estimator's velocity; the identified inertias; 50 µrad of noise on
/// each joint before its counts, a tenth of an axial count), its noise drawn from `seed`.
v1::ServerConfig five_bar_bench(std::uint64_t seed) {
  v1::ServerConfig config =
      config::load_config_file(std::string(HAPTIC_SOURCE_DIR) + "/config/five_bar_bench_003.json");
  config.set_time_mode(v1::LOCKSTEP);
  EXPECT_EQ(config.simulated_five_bar().encoders().noise_size(), 1);
  EXPECT_EQ(config.simulated_five_bar().encoders().noise(0), 5e-5);
  config.mutable_simulated_five_bar()->mutable_encoders()->set_seed(seed);
  return config;
}

/// A bench device's excitation along `axis`: `amplitude_n` over `f_min_hz` to `f_max_hz`, 12
/// harmonics, stopped outside a ±100 mm box or faster than `max_speed_m_s`.
IdentifyParams bench_excitation(int axis, double amplitude_n, double f_min_hz, double f_max_hz, double max_speed_m_s) {
  IdentifyParams params = light_excitation(amplitude_n);
  params.axis = axis;
  params.signal.f_min_hz = f_min_hz;
  params.signal.f_max_hz = f_max_hz;
  params.signal.max_harmonics = 12;
  params.limits.box_half_width_m = 0.1;
  params.limits.max_speed_m_s = max_speed_m_s;
  return params;
}

/// The five-bar's, at the home pose: 4 N over 1 to 10 Hz (the tool's 2 kg barely moves at 40 Hz,
/// and under 1 Hz it leaves a ±100 mm box).
IdentifyParams five_bar_excitation(int axis) { return bench_excitation(axis, 4.0, 1.0, 10.0, 1.0); }

/// The walls check_zwidth runs on the five-bar along x (the identified noise's floor, its friction
/// of 0.296 N pressed 2.5 times), one run each.
DeviceWallParams five_bar_walls() {
  DeviceWallParams wall;
  wall.noise_floor_m = 5.0 * std::sqrt(12.0) * 42.4e-6;
  wall.penetration_m = 4.0 * wall.noise_floor_m;
  wall.push_n = 8.0;
  wall.min_push_n = 2.5 * 0.296;
  wall.still_settles = true;
  return wall;
}

TEST(LabIdentify, TheFiveBarThroughItsEncodersIsItsMassAndJointFrictionButAMultisineToTenHertzMissesItsDamping) {
  const v1::ServerConfig config = five_bar_bench(7);
  ASSERT_TRUE(config.simulated_five_bar().quantized_encoders());
  // Table 5.4's Coulomb friction at the tool: the axial joint's 0.088 N·m over its 0.3 m (x) and
  // the horizontal joint's 0.125 N·m over the 0.6 m reach (y).
  const double coulomb[2] = {0.088 / 0.3, 0.125 / 0.6};
  for (const int axis : {0, 1}) {
    const IdentifyParams params = five_bar_excitation(axis);
    const IdentifyResult id = identify(config, params, "test");
    std::printf("%s", identify_report(id, params, "test").c_str());
    ASSERT_TRUE(id.model_mass && id.model_damping) << id.model_method;
    EXPECT_NEAR(id.fit.mass.value, *id.model_mass, 0.05 * *id.model_mass) << "axis " << axis;
    // Friction within 1 % along x and 5 % along y (here +0.8 % and +3.4 %; without the noise
    // and with 8 periods +4.8 % along y, where the horizontal joint's sticking at the turning
    // points is no sign function).
    EXPECT_NEAR(id.fit.coulomb.value, coulomb[axis], (axis == 0 ? 0.01 : 0.05) * coulomb[axis]) << "axis " << axis;
    // Its damping, 0.13 N·s/m, is 1 % of the mass's impedance at 1 Hz and its pole (m/b, 17 s)
    // far below any band the box allows: at the harmonics of 1 to 10 Hz it is not found, and
    // the interval says so honestly (it holds the model's figure and is wider than it). Long,
    // slow strokes fitted in time find it (below).
    EXPECT_NEAR(id.fit.damping.value, *id.model_damping, id.fit.damping.half_width_95) << "axis " << axis;
    EXPECT_GT(id.fit.damping.half_width_95, *id.model_damping) << "axis " << axis;
  }
}

TEST(LabIdentify, TheFiveBarsDampingIsFoundInTimeOverLongSlowStrokesHeldInTheBoxByASpring) {
  // Along x, 10 N over 1.5 to 3 Hz (3 harmonics): strokes of several centimetres at up to about
  // 0.5 m/s, where the damping's force is a tenth of the friction's rather than a hundredth. A
  // spring about the start (50 N/m, part of the command, so part of the fit's force) keeps
  // stick and slip from walking the tool out of its box, and 80 periods (167 s on a bench) bring
  // the interval under 5 %. Fitted in time, over where the tool moved. Over the encoders' seeds
  // 0, 1, 2, 3 and 7: +2.2, +0.5, −1.8, +0.6 and +2.9 %, intervals ±4.1 to ±4.9 %; the mass
  // within 0.07 %. A band of 2 to 4 Hz, whose strokes are a quarter as long, finds −73 %.
  const v1::ServerConfig config = five_bar_bench(7);
  IdentifyParams params = bench_excitation(0, 10.0, 1.5, 3.0, 1.5);
  params.signal.max_harmonics = 3;
  params.signal.periods = 80;
  params.centering = {50.0, 0.0};
  params.fit_method = engine::FitMethod::kMovingStretches;
  const IdentifyResult id = identify(config, params, "test");
  std::printf("%s", identify_report(id, params, "test").c_str());
  ASSERT_TRUE(id.model_mass && id.model_damping) << id.model_method;
  EXPECT_NEAR(*id.model_damping, 0.012 / (0.3 * 0.3), 1e-9);  // Table 5.4's axial B over l1²
  EXPECT_NEAR(id.fit.mass.value, *id.model_mass, 0.01 * *id.model_mass);
  EXPECT_NEAR(id.fit.damping.value, *id.model_damping, 0.05 * *id.model_damping);
  EXPECT_LT(id.fit.damping.half_width_95, 0.05 * *id.model_damping);
  EXPECT_NEAR(id.fit.coulomb.value, 0.088 / 0.3, 0.01 * 0.088 / 0.3);
}

/// 004's joystick on the bench (config/joystick_bench_004.json, in lockstep) and the excitation
/// its gimbal takes: 7 N over 10 to 40 Hz, a spring and damper about the start (below).
v1::ServerConfig joystick_bench() {
  v1::ServerConfig config =
      config::load_config_file(std::string(HAPTIC_SOURCE_DIR) + "/config/joystick_bench_004.json");
  config.set_time_mode(v1::LOCKSTEP);
  return config;
}

IdentifyParams joystick_excitation(int axis) {
  // At most 1.8 m/s: under the watchdog's 8 rad/s (1.92 m/s at the handle).
  IdentifyParams params = bench_excitation(axis, 7.0, 10.0, 40.0, 1.8);
  params.max_lag_s = 0.02;
  params.centering = {100.0, 1.0};
  return params;
}

/// The gimbal axis fitted in time (`params` with FitMethod::kMovingStretches) against its truth:
/// the mass I/R² (kg), no viscous damping, the friction (N) and the motor's 8.8 ms lag; and its
/// Z-width predicted by its identified model's own walls within 10 % at B = 0.5, 2 and 5 N·s/m.
void expect_joystick_axis(const v1::ServerConfig& config, const IdentifyParams& params, double mass, double coulomb) {
  const IdentifyResult id = identify(config, params, "test");
  const std::string report = identify_report(id, params, "test");
  std::printf("%s", report.c_str());
  ASSERT_TRUE(id.model_mass && id.model_damping) << id.model_method;
  EXPECT_NEAR(*id.model_mass, mass, 1e-9);
  EXPECT_LT(id.fit.moving_fraction, 0.8);
  EXPECT_NEAR(id.fit.mass.value, mass, 0.05 * mass);
  EXPECT_NEAR(id.fit.damping.value, 0.0, std::max(0.02, id.fit.damping.half_width_95));
  EXPECT_NEAR(id.fit.coulomb.value, coulomb, 0.02 * coulomb);
  EXPECT_NEAR(id.fit.lag.value, 8.8e-3, 0.05 * 8.8e-3);
  EXPECT_NEAR(id.fit.delay.value, 0.5e-3, 0.1e-3);  // the hold's half tick: no delay of its own
  EXPECT_NE(report.find("Fitted in time over the stretches where the axis moved"), std::string::npos);
  EXPECT_EQ(report.find("Not a mass-damper"), std::string::npos) << report;

  // Its walls are held by its friction: the frictionless model's linear boundary (54 to 477 N/m)
  // is 5 to 15 times too low. Pressed with 2.5 times the friction, the same walls on the
  // identified model (mass, friction and lag, simulated) predict the device's own within 10 %.
  const std::vector<ZWidthCheck> checks = check_zwidth(config, params, id, {0.5, 2.0, 5.0});
  std::printf("%s", zwidth_report(checks).c_str());
  for (const ZWidthCheck& check : checks) {
    EXPECT_TRUE(check.friction_model) << "B = " << check.damping;
    EXPECT_NEAR(check.predicted, check.measured, 0.10 * check.measured) << "B = " << check.damping;
    EXPECT_GT(check.measured, 3.0 * check.linear) << "B = " << check.damping;
    EXPECT_TRUE(check.settles_above.empty()) << "B = " << check.damping;
  }
}

TEST(LabIdentify, TheJoysticksGimbalWithItsBrakesReleasedIsItsMassFrictionAndMotorLagFittedWhereItMoves) {
  // 004's joystick along x, its θ gimbal at mid-stroke (R = 0.24 m), brakes released (the
  // mechanism alone: the hybrid rule's brakes would take the excitation's dissipating half),
  // read through its encoders (0.0003835 rad a count, the code's angle tables, L1825: 92 µm at
  // the handle) with 20 µrad of noise, and its tachometers. Its truth, the Jacobian's: I_θ/R² =
  // 0.0434 kg, no viscous damping, the gimbal's 0.2 N·m of friction and the brake's 0.0778 N·m
  // of residual magnetism over R, 1.157 N, and the motor's 8.8 ms (L378). Friction holds it
  // through much of each period, and a spring and damper about the start (100 N/m, 1 N·s/m, part
  // of the command) keep stick and slip from walking it off to where its mass along x is
  // another (I_θ/(R cos θ)²).
  // config/joystick_bench_004.json is that joystick.
  const v1::ServerConfig config = joystick_bench();
  ASSERT_TRUE(config.simulated_joystick().brakes_released());
  ASSERT_EQ(config.simulated_joystick().encoders().quantization_size(), 1);
  EXPECT_EQ(config.simulated_joystick().encoders().quantization(0), 0.0003835);
  IdentifyParams params = joystick_excitation(0);
  const double mass = 2.5e-3 / (0.24 * 0.24), coulomb = (0.2 + 0.0778) / 0.24;

  // At the harmonics the stuck stretches read as mass and damping that are not there.
  const IdentifyResult harmonics = identify(config, params, "test");
  const std::string harmonics_report = identify_report(harmonics, params, "test");
  std::printf("%s", harmonics_report.c_str());
  EXPECT_GT(std::abs(harmonics.fit.mass.value / mass - 1.0), 0.2);
  EXPECT_LT(harmonics.fit.relative_residual, 0.2);  // nothing in the residual says so, but:
  EXPECT_NE(harmonics_report.find("compare --fit moving"), std::string::npos) << harmonics_report;

  params.fit_method = engine::FitMethod::kMovingStretches;
  expect_joystick_axis(config, params, mass, coulomb);
}

TEST(LabIdentify, TheJoysticksOtherGimbalAxisAlongYIsItsMassFrictionAndLagToo) {
  // Along y, the φ gimbal: at the handle's start (θ = φ = 0) the same inertia over R (0.0434 kg,
  // the Jacobian's), the same friction (the gimbal's and the brake's residual, over R) and motor.
  IdentifyParams params = joystick_excitation(1);
  params.fit_method = engine::FitMethod::kMovingStretches;
  expect_joystick_axis(joystick_bench(), params, 2.5e-3 / (0.24 * 0.24), (0.2 + 0.0778) / 0.24);
}

TEST(LabIdentify, TheFiveBarsZWidthIsTheFirstWallThatRingsGoingUpEveryWallUnderItSettles) {
  // 003's five-bar through its counts and 50 µrad of noise, along x at B = 5 N·s/m, its walls as
  // check_zwidth runs them on it (the identified noise's floor, friction 0.296 N pressed 2.5
  // times). Its stability is no single step along K: it rings at some K and settles again above
  // them, where a ring's few counts meet its friction. The figure is the first K that rings going
  // up, so every wall under it settles; a doubling bracket's bisection (before) gave 53 kN/m,
  // with walls at 37 and 44 kN/m ringing.
  const v1::ServerConfig config = five_bar_bench(0);
  const DeviceWallParams wall = five_bar_walls();
  const double damping = 5.0;
  const double boundary = device_zwidth_boundary(config, wall, damping, 1.0e5);
  std::printf("five-bar along x, B = %g N·s/m: K_max %.0f N/m\n", damping, boundary);
  ASSERT_GT(boundary, 1.0e4);
  ASSERT_LT(boundary, 1.0e5);
  for (int step = 1; step <= 8; ++step) {
    const double stiffness = boundary * std::pow(2.0, -step / 4.0);
    EXPECT_TRUE(device_wall_settles(config, wall, stiffness, damping)) << "K = " << stiffness << " N/m";
  }
  EXPECT_FALSE(device_wall_settles(config, wall, boundary * 1.01, damping));
  // And above it, walls settle again: the figure is a first crossing, which the report says.
  const std::vector<double> above = device_settles_above(config, wall, damping, boundary);
  EXPECT_FALSE(above.empty());
  for (const double k : above) std::printf("  settles again at %.0f N/m\n", k);
}

TEST(LabIdentify, OneRunAWallOverstatesWhatHoldsOnTheFiveBarWhoseCountsAndNoiseDecideItsWalls) {
  // Along x the five-bar is a point mass behind one counted joint, held by that joint's friction.
  // Its encoders count from home, so it starts on a count's edge, and the noise decides which
  // side of it the first readings fall: run once, its first ringing wall at B = 1 N·s/m is about
  // 37 kN/m with one draw and 16 to 21 kN/m with others.
  const v1::ServerConfig config = five_bar_bench(0);
  DeviceWallParams wall = five_bar_walls();
  const double damping = 1.0;
  const double once = device_zwidth_boundary(config, wall, damping, 1.0e5);
  wall.runs = 16;
  wall.vary = [](v1::ServerConfig& drawn, int run) { redraw_sensor_noise(drawn, 0, run); };
  const double every = device_zwidth_boundary(config, wall, damping, 1.0e5);
  std::printf("five-bar along x, B = %g N·s/m: one run a wall %.0f N/m, 16 draws of its noise %.0f N/m\n", damping,
              once, every);
  EXPECT_GT(once, 1.5 * every);
  // Each of the 16 draws settles at the figure, and a wall that the first run settled (every
  // wall under its figure did) rings with another draw of the noise.
  const DeviceWallParams single = five_bar_walls();
  const double passed_once = 0.9 * once;
  ASSERT_TRUE(device_wall_settles(config, single, passed_once, damping));
  int ringing = 0;
  for (int run = 0; run < wall.runs; ++run) {
    v1::ServerConfig drawn = config;
    if (run > 0) ASSERT_TRUE(redraw_sensor_noise(drawn, 0, run));
    EXPECT_TRUE(device_wall_settles(drawn, single, every, damping)) << "run " << run;
    if (!device_wall_settles(drawn, single, passed_once, damping)) ++ringing;
  }
  std::printf("  at %.0f N/m, %d of %d draws ring\n", passed_once, ringing, wall.runs);
  EXPECT_GT(ringing, 0);
}

TEST(LabIdentify, TheFiveBarsIdentifiedModelPredictsItsZWidthWhereverItRestsInACount) {
  // Along x the lab finds the axial count's step through the nonlinear map (0.6 − 0.3 sin q: a
  // lattice whose step changes slowly), the device's 12 N force limit, and no noise beyond the
  // step's own (it cannot tell the 15 µm before the counts from them). Each wall runs 16 times:
  // on the device with its noise drawn anew, on the identified model (a point mass with the
  // identified mass, damping and friction, read through the step) from 16 places in a count.
  const v1::ServerConfig config = five_bar_bench(7);
  const IdentifyParams params = five_bar_excitation(0);
  const IdentifyResult id = identify(config, params, "test");
  ASSERT_TRUE(id.fit.quantization_m);
  EXPECT_NEAR(*id.fit.quantization_m, 0.3 * std::numbers::pi / 6000.0, 0.01 * 0.3 * std::numbers::pi / 6000.0);
  EXPECT_EQ(id.max_force_n, 12.0);
  // Within 10 % at B = 5, 10 and 20 N·s/m (here +8.2, +1.6 and +1.6 %). The model stands high
  // (docs/identification.md: +0.5 to +17 % over five seeds and five B, within 5 % at 10 and
  // 20 N·s/m): the device's lowest walls come from its noise's draws, which a model without
  // that noise does not make.
  const std::vector<ZWidthCheck> checks = check_zwidth(config, params, id, {5.0, 10.0, 20.0});
  std::printf("%s", zwidth_report(checks).c_str());
  for (const ZWidthCheck& check : checks) {
    EXPECT_TRUE(check.friction_model) << "B = " << check.damping;
    EXPECT_EQ(check.runs, 16) << "B = " << check.damping;
    EXPECT_NEAR(check.predicted, check.measured, 0.10 * check.measured) << "B = " << check.damping;
  }
}

TEST(LabIdentify, AWallRunAgainDrawsThePortsSensorNoiseAnewAndNoOtherPorts) {
  v1::ServerConfig config = five_bar_bench(7);
  v1::DeviceConfig& quiet = *config.add_extra_devices();  // port 1: a point mass read exactly
  quiet.mutable_simulated_point_mass();
  v1::DeviceConfig& noisy = *config.add_extra_devices();  // port 2: read through noise
  noisy.mutable_simulated_point_mass()->mutable_sensor()->set_noise_m(1e-6);
  noisy.mutable_simulated_point_mass()->mutable_sensor()->set_seed(2);
  const v1::ServerConfig given = config;
  EXPECT_TRUE(reads_through_noise(config, 0));
  EXPECT_FALSE(reads_through_noise(config, 1));
  EXPECT_TRUE(reads_through_noise(config, 2));
  EXPECT_FALSE(reads_through_noise(config, 3));  // no such port
  // Port 0's runs draw its encoders' noise anew, each run its own seed; the other ports keep theirs.
  std::set<std::uint64_t> seeds{config.simulated_five_bar().encoders().seed()};
  for (int run = 1; run <= 16; ++run) {
    v1::ServerConfig drawn = given;
    EXPECT_TRUE(redraw_sensor_noise(drawn, 0, run));
    seeds.insert(drawn.simulated_five_bar().encoders().seed());
    EXPECT_EQ(drawn.extra_devices(1).simulated_point_mass().sensor().seed(), 2u);
  }
  EXPECT_EQ(seeds.size(), 17u);
  // Port 2's, and nothing of port 0's.
  EXPECT_TRUE(redraw_sensor_noise(config, 2, 3));
  EXPECT_NE(config.extra_devices(1).simulated_point_mass().sensor().seed(), 2u);
  EXPECT_EQ(config.simulated_five_bar().encoders().seed(), 7u);
  // Nothing to draw: a sensor without noise, a port read exactly, a port that is not there.
  EXPECT_FALSE(redraw_sensor_noise(config, 1, 1));
  EXPECT_FALSE(config.extra_devices(0).simulated_point_mass().has_sensor());
  EXPECT_FALSE(redraw_sensor_noise(config, 3, 1));
  v1::ServerConfig exact = config::parse_config(R"({"simulated_point_mass": {"sensor": {"quantization_m": 1e-5}}})", "test");
  EXPECT_FALSE(redraw_sensor_noise(exact, 0, 1));
  EXPECT_EQ(exact.simulated_point_mass().sensor().seed(), 0u);
  // A wall's runs must be one or more.
  DeviceWallParams wall;
  wall.runs = 0;
  EXPECT_THROW(device_wall_settles(exact, wall, 100.0, 0.0), std::invalid_argument);
}

TEST(LabIdentify, AWallOnADeviceThatFrictionHoldsIsPressedPastItsFrictionAndSettledWhereItStops) {
  // A 50 g point mass with 0.5 N of friction behind an 8 ms lag (simulated_point_mass.coulomb
  // and .actuator_lag), through a sensor.
  const v1::ServerConfig config = config::parse_config(R"({"time_mode": "LOCKSTEP",
      "simulated_point_mass": {"mass": 0.05, "damping": 0, "coulomb": 0.5, "actuator_lag": 0.008,
                               "substeps": 100, "sensor": {"noise_m": 1e-6, "seed": 2}}})", "test");
  DeviceWallParams wall;
  wall.noise_floor_m = 2e-5;
  wall.still_settles = true;
  // Pressed with less than its friction it never moves, and stands still at any K: that proves
  // nothing.
  wall.push_n = 0.3;
  EXPECT_TRUE(device_wall_settles(config, wall, 3000.0, 0.0));
  // Pressed past it, it falls in and stops within c/K of its equilibrium up to a few hundred N/m
  // (where the frictionless mass behind its lag rings at any K), and stiffer walls ring up.
  wall.min_push_n = 1.25;
  EXPECT_TRUE(device_wall_settles(config, wall, 300.0, 0.0));
  EXPECT_FALSE(device_wall_settles(config, wall, 1000.0, 0.0));
  EXPECT_FALSE(device_wall_settles(config, wall, 3000.0, 0.0));
  const double linear = engine::sampled_wall_margin({1.0, 0.0, 0.0}, engine::ImpedanceDiscretization::kBackwardDifference,
                                                    {0.05, 0.0, 0.008}, 1e-3)
                            .max_stable_stiffness;
  EXPECT_LT(linear, 30.0);
}

#ifdef FORCEDIMENSION_DRIVER
TEST(LabIdentify, TheForceDimensionStandInIsItsPlantAndPredictsItsZWidth) {
  // An omega.3 through the Force Dimension driver and its runtime's stand-in, whose plant (0.2 kg,
  // 2 N·s/m per axis, tests/driver/standins/fake_forcedimension.cpp) is the truth: a driver port
  // in the lab, started and stopped as hapticd does.
  setenv("FAKE_DHD_DEVICES", "omega.3", 1);
  const v1::ServerConfig config = config::parse_config(R"({"time_mode": "LOCKSTEP",
      "driver": {"library": ")" FORCEDIMENSION_DRIVER R"(", "call_timeout_ms": 0,
                 "params": {"library": ")" FAKE_FORCEDIMENSION_LIBRARY R"("}}})", "test");
  const IdentifyParams params = light_excitation(0.2);
  const IdentifyResult id = identify(config, params, "test");
  EXPECT_NEAR(id.fit.mass.value, 0.2, 0.01 * 0.2);
  EXPECT_NEAR(id.fit.damping.value, 2.0, 0.01 * 2.0);
  EXPECT_FALSE(id.model_mass) << "the driver reports no mass: " << id.model_method;
  EXPECT_LT(predicted_against_measured(config, params, {1.0, 5.0, 20.0}), 0.10);
  unsetenv("FAKE_DHD_DEVICES");
}

TEST(LabIdentify, PacedInRealTimeTheRunTakesItsDurationAndTheStandInIsStillItsPlant) {
  // --real-time, for hardware: the ticks wait for their deadlines on the monotonic clock. The
  // stand-in steps its plant per command, so its figures do not depend on when the ticks ran and
  // the run can be checked exactly on a loaded machine; what pacing adds is the run's wall time,
  // never less than its ticks' (a sleep cannot end early), and the late ticks it counts.
  setenv("FAKE_DHD_DEVICES", "omega.3", 1);
  const v1::ServerConfig config = config::parse_config(R"({"time_mode": "LOCKSTEP",
      "driver": {"library": ")" FORCEDIMENSION_DRIVER R"(", "call_timeout_ms": 0,
                 "params": {"library": ")" FAKE_FORCEDIMENSION_LIBRARY R"("}}})", "test");
  IdentifyParams params = light_excitation(0.2);
  params.signal.periods = 4;
  params.signal.samples_per_period = 512;
  params.signal.f_min_hz = 4.0;
  params.device_time.real_time = true;
  const auto start = std::chrono::steady_clock::now();
  const IdentifyResult id = identify(config, params, "test");
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_GE(wall_s, id.duration_s);
  EXPECT_NEAR(id.fit.mass.value, 0.2, 0.01 * 0.2);
  EXPECT_NEAR(id.fit.damping.value, 2.0, 0.01 * 2.0);
  const std::string report = identify_report(id, params, "test");
  EXPECT_NE(report.find("s of real-time ticks"), std::string::npos) << report;
  EXPECT_EQ(report.find("ticks started more than half a period late") != std::string::npos, id.late_ticks > 0) << report;
  unsetenv("FAKE_DHD_DEVICES");
}
#endif

#ifdef OPENHAPTICS_DRIVER
TEST(LabIdentify, TheOpenHapticsStandInIsItsPlantWithItsServoTicksDelayAndPredictsItsZWidth) {
  // A Touch through the OpenHaptics driver, server-clocked, and the HD runtime's stand-in on its
  // manual clock, stepped one servo tick before each loop tick as the two run side by side at
  // 1 kHz on the bench. Its plant (0.05 kg, 0.5 N·s/m, tests/driver/standins/README.md) is the
  // truth; the servo frame takes the state before the force hapticd just wrote goes out, so the
  // device's delay is one tick more than a driver that steps per command (the identification
  // must find it, and the Z-width depends on it).
  setenv("FAKE_HD_DEVICES", "Default Device=Touch", 1);
  setenv("FAKE_HD_CLOCK", "manual", 1);
  const runtime::test::StandinLibrary standin(FAKE_OPENHAPTICS_LIBRARY, "fake_hd");
  const v1::ServerConfig config = config::parse_config(R"({"time_mode": "LOCKSTEP",
      "driver": {"library": ")" OPENHAPTICS_DRIVER R"(", "call_timeout_ms": 0,
                 "params": {"library": ")" FAKE_OPENHAPTICS_LIBRARY R"("}}})", "test");
  IdentifyParams params = light_excitation(0.05);
  params.axis = 2;  // W's z, the HD frame's y (up)
  params.device_time.step_device = [&standin] { standin.control("tick 1"); };
  const IdentifyResult id = identify(config, params, "test");
  std::printf("%s", identify_report(id, params, "test").c_str());
  EXPECT_NEAR(id.fit.mass.value, 0.05, 0.01 * 0.05);
  EXPECT_NEAR(id.fit.damping.value, 0.5, 0.01 * 0.5);
  EXPECT_NEAR(id.fit.delay.value, 1.5e-3, 0.05e-3) << "the hold's half tick and the servo frame's whole one";
  EXPECT_LT(predicted_against_measured(config, params, id, {0.5, 2.0, 5.0}), 0.10);
  unsetenv("FAKE_HD_CLOCK");
  unsetenv("FAKE_HD_DEVICES");
}
#endif

#ifdef HAPLY_DRIVER
TEST(LabIdentify, TheHaplyStandInIsItsPlantAndPredictsItsZWidth) {
  // An Inverse3 through the Haply driver and the Inverse Service's stand-in, whose plant (0.2 kg,
  // 1 N·s/m per axis, tests/driver/standins/fake_haply_service.hpp) is the truth. The service
  // steps its plant once per message and read() waits for its answer: lockstep holds as long as
  // the answer comes within reply_timeout_ms, set long here so a loaded machine cannot break it.
  fake_haply::Options options;
  options.port = 0;
  fake_haply::Service service(options);
  std::string error;
  ASSERT_TRUE(service.start(&error)) << error;
  const v1::ServerConfig config = config::parse_config(R"({"time_mode": "LOCKSTEP",
      "driver": {"library": ")" HAPLY_DRIVER R"(", "call_timeout_ms": 0,
                 "params": {"url": "ws://127.0.0.1:)" + std::to_string(service.port()) +
                                                           R"(", "reply_timeout_ms": 5000, "max_force": 10}}})",
                                                       "test");
  IdentifyParams params = light_excitation(0.2);
  params.axis = 1;  // W's y, the service's x: another axis than the Force Dimension test's
  const IdentifyResult id = identify(config, params, "test");
  EXPECT_NEAR(id.fit.mass.value, fake_haply::kMass, 0.01 * fake_haply::kMass);
  EXPECT_NEAR(id.fit.damping.value, fake_haply::kDamping, 0.01 * fake_haply::kDamping);
  EXPECT_LT(predicted_against_measured(config, params, id, {1.0, 5.0, 20.0}), 0.10);
  service.stop();
}
#endif

TEST(LabIdentify, AnAxisThatIsNoMassDamperIsSaidToBeOneNotToUse) {
  // 004's joystick along z at 2 N: its shaft's sleeve friction (5.66 N) holds it through most of
  // each period, and its cable and motor lag are no mass-damper; the fit's residual says so.
  const v1::ServerConfig config =
      config::load_config_file(std::string(HAPTIC_SOURCE_DIR) + "/config/joystick_004.json");
  IdentifyParams params = light_excitation(2.0);
  params.axis = 2;
  params.signal.periods = 4;
  const IdentifyResult id = identify(config, params, "test");
  EXPECT_GT(id.fit.relative_residual, 0.2);
  const std::string report = identify_report(id, params, "test");
  EXPECT_NE(report.find("**Not a mass-damper along this direction**"), std::string::npos) << report;
  // The point mass's report says no such thing.
  const IdentifyParams light = light_excitation(0.02);
  const std::string clean =
      identify_report(identify(config::parse_config(R"({"time_mode": "LOCKSTEP"})", "test"), light, "test"), light, "test");
  EXPECT_EQ(clean.find("Not a mass-damper"), std::string::npos) << clean;
}

}  // namespace
}  // namespace haptic::lab
