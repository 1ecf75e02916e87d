// haptic-lab run: a scene from a configuration, in lockstep, through the server's own TickRunner.
#include <gtest/gtest.h>

#include <sstream>
#include <stdexcept>
#include <string>

#include "app/config.hpp"
#include "lab/lab_run.hpp"

namespace haptic::lab {
namespace {

std::string last_line(const std::string& text) {
  const auto end = text.find_last_not_of('\n');
  const auto start = text.rfind('\n', end);
  return text.substr(start + 1, end - start);
}

double column(const std::string& line, int index) {
  std::stringstream in(line);
  std::string cell;
  for (int i = 0; i <= index; ++i) std::getline(in, cell, ',');
  return std::stod(cell);
}

TEST(LabRun, AWallUnderAPushSettlesAtForceOverStiffnessAndTheTraceSaysSo) {
  // The default point mass at z = 20 mm, a 1000 N/m wall at z = 0, the hand pushing 2 N down.
  const v1::ServerConfig config = app::parse_config(R"({
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
  const std::string last = last_line(text);
  EXPECT_EQ(column(last, 1), 2000.0);                // tick
  EXPECT_NEAR(column(last, 5), -0.002, 1e-5);        // z: F/K under the surface
  EXPECT_NEAR(column(last, 11), 2.0, 1e-3);          // F_z
  // The wall stored ½ K d² = 2 mJ and took the falling tool's work besides; it gave little back.
  EXPECT_GT(summary.energy_from_device, 0.002);
}

TEST(LabRun, BadInputIsRefusedBeforeAnyWork) {
  const v1::ServerConfig config = app::default_config();
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
  const v1::ServerConfig config = app::parse_config(R"({
    "simulated_dc_motor": {"initial_angle": 0.5},
    "initial_operator": {"mode": "APPLY_FORCE", "force": {"y": -1},
                         "profile": {"shape": "SINE", "frequency_hz": 2}}})", "test");
  std::ostringstream a, b;
  run_scene(config, 0.5, a);
  run_scene(config, 0.5, b);
  EXPECT_EQ(a.str(), b.str());
}

}  // namespace
}  // namespace haptic::lab
