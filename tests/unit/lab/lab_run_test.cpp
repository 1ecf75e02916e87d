// haptic-lab run: a scene from a configuration, in lockstep, through the server's own TickRunner.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "config/server_config.hpp"
#include "lab/lab_run.hpp"

namespace haptic::lab {
namespace {

std::string last_line(const std::string& text) {
  const auto end = text.find_last_not_of('\n');
  const auto start = text.rfind('\n', end);
  return text.substr(start + 1, end - start);
}

std::string cell(const std::string& line, int index) {
  std::stringstream in(line);
  std::string value;
  for (int i = 0; i <= index; ++i) std::getline(in, value, ',');
  return value;
}

double column(const std::string& line, int index) { return std::stod(cell(line, index)); }

/// The trace's second line: port 0's first tick.
std::string first_row(const std::string& text) {
  const auto start = text.find('\n') + 1;
  return text.substr(start, text.find('\n', start) - start);
}

// Joint columns of the trace (after the 19 of the tool, force, proxy, flags and energy).
constexpr int kQ0 = 19, kQ1 = 20, kQ2 = 21, kQ0Dot = 22, kQ2Dot = 24;
constexpr int kQw = 25, kQz = 28, kTauZ = 31;

TEST(LabRun, AWallUnderAPushSettlesAtForceOverStiffnessAndTheTraceSaysSo) {
  // The default point mass at z = 20 mm, a 1000 N/m wall at z = 0, the hand pushing 2 N down.
  const v1::ServerConfig config = config::parse_config(R"({
    "simulated_point_mass": {"initial_position": {"z": 0.02}},
    "initial_scene": {"objects": [{"impedance": {"stiffness": 1000, "damping": 1},
                                   "half_space": {"normal": {"z": 1}}}]},
    "initial_operator": {"mode": "APPLY_FORCE", "force": {"z": -2}}})", "test");
  std::ostringstream trace;
  const RunSummary summary = run_scene(config, 2.0, trace);
  EXPECT_EQ(summary.ticks, 2000u);
  EXPECT_TRUE(summary.finite);
  EXPECT_EQ(summary.fault_ticks, 0u);
  const std::string text = trace.str();
  EXPECT_EQ(text.rfind("port,tick,time_s,x_m", 0), 0u);
  EXPECT_NE(text.find("energy_from_device_j,q0,q1,q2,q0_dot,q1_dot,q2_dot,qw,qx,qy,qz,tau_x_nm,tau_y_nm,"
                      "tau_z_nm\n"),
            std::string::npos);
  const std::string last = last_line(text);
  EXPECT_EQ(column(last, 1), 2000.0);                // tick
  EXPECT_NEAR(column(last, 5), -0.002, 1e-5);        // z: F/K under the surface
  EXPECT_NEAR(column(last, 11), 2.0, 1e-3);          // F_z
  // The point mass's joints are its Cartesian axes: q2 is z, q2_dot is v_z.
  EXPECT_EQ(column(last, kQ2), column(last, 5));
  EXPECT_EQ(column(last, kQ2Dot), column(last, 8));
  // The wall stored ½ K d² = 2 mJ and took the falling tool's work besides; it gave little back.
  EXPECT_GT(summary.energy_from_device, 0.002);
}

TEST(LabRun, TheSixDofConfigTracesTheHandlesOrientationAndTheSpringsTorque) {
  const v1::ServerConfig config = config::load_config_file(std::string(HAPTIC_SOURCE_DIR) + "/config/six_dof.json");
  std::ostringstream trace;
  const RunSummary summary = run_scene(config, 3.0, trace);
  EXPECT_TRUE(summary.finite);
  const std::string text = trace.str();
  const std::string first = text.substr(text.find('\n') + 1, text.find('\n', text.find('\n') + 1) - text.find('\n') - 1);
  // At the first tick the handle is 0.2 rad about z from the spring's target (identity), at rest:
  // τ_z = −k θ = −0.05 × 0.2 N·m (the exact-ZOH law starts from the measured rate, 0).
  EXPECT_NEAR(column(first, kTauZ), -0.01, 1e-12);
  EXPECT_NEAR(column(first, kQz), std::sin(0.1), 1e-4);
  // Three seconds later it has rung down onto the target.
  const std::string last = last_line(text);
  EXPECT_LT(std::abs(column(last, kQz)), 0.01);
  EXPECT_NEAR(column(last, kQw), 1.0, 1e-4);
}

TEST(LabRun, BadInputIsRefusedBeforeAnyWork) {
  const v1::ServerConfig config = config::default_config();
  std::ostringstream trace;
  EXPECT_THROW(run_scene(config, 0.0, trace), std::invalid_argument);
  EXPECT_THROW(run_scene(config, -1.0, trace), std::invalid_argument);
  v1::ServerConfig bad = config;
  bad.mutable_initial_scene()->add_objects()->mutable_sphere()->set_radius(0.01);  // no impedance
  try {
    run_scene(bad, 1.0, trace);
    FAIL() << "a scene without an impedance ran";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("initial_scene.objects[0].impedance"), std::string::npos);
  }
  EXPECT_TRUE(trace.str().empty());  // nothing was written
}

TEST(LabRun, TheSameSceneTwiceGivesTheSameTrace) {
  const v1::ServerConfig config = config::parse_config(R"({
    "simulated_dc_motor": {"initial_angle": 0.5},
    "initial_operator": {"mode": "APPLY_FORCE", "force": {"y": -1},
                         "profile": {"shape": "SINE", "frequency_hz": 2}}})", "test");
  std::ostringstream a, b;
  run_scene(config, 0.5, a);
  run_scene(config, 0.5, b);
  EXPECT_EQ(a.str(), b.str());
}

TEST(LabRun, TheTraceCarriesEachDocumentDevicesJointState) {
  // 000's link starts at θ_L = 0.5 rad: one joint, the load angle, the other cells empty.
  {
    const v1::ServerConfig config = config::parse_config(R"({"simulated_dc_motor": {"initial_angle": 0.5}})", "test");
    std::ostringstream trace;
    run_scene(config, 0.01, trace);
    const std::string row = first_row(trace.str());
    EXPECT_NEAR(column(row, kQ0), 0.5, 1e-12);
    EXPECT_EQ(column(row, kQ0Dot), 0.0);
    EXPECT_EQ(cell(row, kQ1), "");
    EXPECT_EQ(cell(row, kQ2), "");
  }
  // 003's five-bar starts at home, q = (0, 90°, 180°) (docs/devices.md).
  {
    const v1::ServerConfig config = config::parse_config(R"({"simulated_five_bar": {}})", "test");
    std::ostringstream trace;
    run_scene(config, 0.01, trace);
    const std::string row = first_row(trace.str());
    EXPECT_NEAR(column(row, kQ0), 0.0, 1e-12);
    EXPECT_NEAR(column(row, kQ1), std::numbers::pi / 2, 1e-12);
    EXPECT_NEAR(column(row, kQ2), std::numbers::pi, 1e-12);
  }
  // 004's joystick: θ = Φ = 0 and the shaft at its configured 0.2 m, which is also the handle's z.
  {
    const v1::ServerConfig config =
        config::parse_config(R"({"simulated_joystick": {"initial_shaft_length": 0.2}})", "test");
    std::ostringstream trace;
    run_scene(config, 0.01, trace);
    const std::string row = first_row(trace.str());
    EXPECT_EQ(column(row, kQ0), 0.0);
    EXPECT_EQ(column(row, kQ1), 0.0);
    EXPECT_NEAR(column(row, kQ2), 0.2, 1e-12);
    EXPECT_NEAR(column(row, 5), 0.2, 1e-12);
  }
}

TEST(LabRun, JointStateIsTheSampledInstantsNotTheNextTicks) {
  // The hand pushes 000's link: q0 must move with the published tool position, tick for tick —
  // the tool on its circle of radius l = 0.2 m: p_WT = l (cos q0, sin q0, 0) (000 eq. 3.1a).
  const v1::ServerConfig config = config::parse_config(R"({
    "simulated_dc_motor": {"initial_angle": 0.5},
    "initial_operator": {"mode": "APPLY_FORCE", "force": {"x": -0.5, "y": 0.8}}})", "test");
  std::vector<TickRecord> records;
  simulate_scene(config, 0.2, [&](const TickRecord& r) {
    records.push_back(r);
    return true;
  });
  ASSERT_EQ(records.size(), 200u);
  EXPECT_GT(records.back().joints.q[0] - 0.5, 0.01);  // it moved
  for (const TickRecord& r : records) {
    EXPECT_NEAR(r.sample.p_WT.x, 0.2 * std::cos(r.joints.q[0]), 1e-12) << "tick " << r.sample.tick;
    EXPECT_NEAR(r.sample.p_WT.y, 0.2 * std::sin(r.joints.q[0]), 1e-12) << "tick " << r.sample.tick;
  }
}

TEST(LabRun, TheCallbackCanStopTheRun) {
  const v1::ServerConfig config = config::default_config();
  int calls = 0;
  const RunSummary summary = simulate_scene(config, 1.0, [&](const TickRecord&) { return ++calls < 7; });
  EXPECT_EQ(calls, 7);
  EXPECT_EQ(summary.ticks, 7u);
}

TEST(LabRun, APlantThatBlowsUpIsReportedNotFinite) {
  // 001's device against the plain wall (B = 1 N·s/m oscillates, 001 Fig. 7) with explicit Euler
  // at one sub-step, shaken hard (a ±6 N sine about −5 N: with a gentler shake whether the
  // unstable motion leaves the reach within 0.5 s depends on rounding): the end effector leaves
  // the mechanism's reach within 0.1 s and the state turns NaN. The
  // loop keeps publishing the last good reading; the joint state and the summary say what happened.
  const v1::ServerConfig config = config::parse_config(R"({
    "simulated_parallel_dob": {"integrator": "explicit_euler", "substeps": 1},
    "initial_scene": {"objects": [{"pose": {"position": {"y": 0.25}},
                                   "impedance": {"stiffness": 1000, "damping": 1},
                                   "half_space": {"normal": {"y": 1}}}]},
    "initial_operator": {"mode": "APPLY_FORCE", "force": {"y": 6},
                         "profile": {"shape": "SINE", "frequency_hz": 5, "offset": {"y": -5}}}})", "test");
  std::ostringstream trace;
  RunSummary summary;
  ASSERT_NO_THROW(summary = run_scene(config, 0.5, trace));
  EXPECT_EQ(summary.ticks, 500u);
  EXPECT_FALSE(summary.finite);
  EXPECT_GT(summary.fault_ticks, 0u);
  const std::string last = last_line(trace.str());
  EXPECT_TRUE(std::isfinite(column(last, 4)));  // the published y: the last good reading
  // The joint state shows the blow-up: the first joint's angle or rate is not a number.
  const std::string q0 = cell(last, kQ0), q0_dot = cell(last, kQ0Dot);
  EXPECT_TRUE(q0.find("nan") != std::string::npos || q0_dot.find("nan") != std::string::npos)
      << q0 << ", " << q0_dot;
}

}  // namespace
}  // namespace haptic::lab
