// The study's document-device cases (lab/study_devices.cpp): they run, sample where they say,
// converge at the reference step, refuse steps they cannot take, report an unstable scheme as a
// result, and are what their files under config/lab/ run.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "config/server_config.hpp"
#include "lab/lab_run.hpp"
#include "lab/study.hpp"

namespace haptic::lab {
namespace {

const StudyCase& find(const std::vector<StudyCase>& cases, const std::string& name) {
  for (const StudyCase& c : cases) {
    if (c.name == name) return c;
  }
  throw std::runtime_error("no case " + name);
}

/// max_k |a_k − b_k| over the samples both have. Unit: m.
double max_difference(const Trajectory& a, const Trajectory& b) {
  double worst = 0.0;
  for (std::size_t k = 0; k < std::min(a.samples.size(), b.samples.size()); ++k) {
    worst = std::max(worst, engine::norm(a.samples[k] - b.samples[k]));
  }
  return worst;
}

/// How far the tool moved from its start: max_k |p_k − p_0| (the samples are displacements, so
/// p_0 = 0). Unit: m.
double motion(const Trajectory& t) {
  double worst = 0.0;
  for (const engine::Vec3& p : t.samples) worst = std::max(worst, engine::norm(p - t.samples.front()));
  return worst;
}

/// The tool positions a configuration file gives when run as `haptic-lab run` does, sampled
/// every `every` ticks from t = 0 to t = duration.
std::vector<engine::Vec3> run_file(const std::string& file, double duration_s, int every) {
  const v1::ServerConfig config = config::load_config_file(std::string(HAPTIC_SOURCE_DIR) + "/" + file);
  std::vector<engine::Vec3> out;
  simulate_scene(config, duration_s + 1e-3, [&](const TickRecord& r) {
    if ((r.sample.tick - 1) % every == 0) out.push_back(r.sample.p_WT);
    return true;
  });
  return out;
}

TEST(StudyDevices, EveryCaseRunsAndSamplesEveryOutputPeriod) {
  const std::vector<StudyCase> cases = device_cases(true);
  ASSERT_EQ(cases.size(), 7u);
  for (const StudyCase& c : cases) {
    SCOPED_TRACE(c.name);
    EXPECT_FALSE(c.title.empty());
    EXPECT_NE(c.source.find("config/lab/"), std::string::npos);
    EXPECT_NE(c.observable.find(", m"), std::string::npos);
    const std::string variant = c.variants.empty() ? "" : c.variants.front();
    const Trajectory t = c.simulate(Scheme::kRk4, 1e-3, variant);
    const auto expected = static_cast<std::size_t>(std::llround(c.duration_s / c.output_period_s)) + 1;
    EXPECT_EQ(t.samples.size(), expected);
    // Energy where the scene has something to exert a force; the swing scenes have nothing.
    EXPECT_EQ(t.energy.size(), c.name.rfind("five_bar_", 0) == 0 && c.group == "fidelity" ? 0u : expected);
    EXPECT_TRUE(t.finite);
    EXPECT_FALSE(t.diverged);
    EXPECT_EQ(t.fault_ticks, 0u);
    // Nothing to report but, for 000's full motor model, the finer step the plant chose.
    if (variant == "with_inductance") {
      EXPECT_EQ(t.note.rfind("the inductance model took ", 0), 0u) << t.note;
    } else {
      EXPECT_TRUE(t.note.empty()) << t.note;
    }
    EXPECT_GT(motion(t), 1e-3);  // every scene moves its tool by millimetres at least
    EXPECT_EQ(engine::norm(t.samples.front()), 0.0);  // displacements from the start
    for (double h : c.steps_s) {
      const double ticks_per_output = c.output_period_s / h;
      EXPECT_NEAR(ticks_per_output, std::round(ticks_per_output), 1e-9 * ticks_per_output);
    }
  }
  // Three decades of steps for every scheme case, in both suites; every integrator.
  for (bool short_suite : {true, false}) {
    for (const StudyCase& c : device_cases(short_suite)) {
      if (c.group != "schemes") continue;
      const auto [lo, hi] = std::minmax_element(c.steps_s.begin(), c.steps_s.end());
      EXPECT_GE(*hi / *lo, 999.0) << c.name;
      EXPECT_EQ(c.schemes.size(), std::size(kIntegratorSchemes)) << c.name;
    }
  }
}

TEST(StudyDevices, TheReferenceHasConverged) {
  // RK4 at the reference step and at twice it agree to a millionth of the tool's motion (003's
  // encoders make its reading agree exactly: the difference is far below one count).
  for (const StudyCase& c : device_cases(true)) {
    if (c.group != "schemes") continue;
    SCOPED_TRACE(c.name);
    const Trajectory fine = c.simulate(c.reference_scheme, c.reference_step_s, "");
    const Trajectory coarse = c.simulate(c.reference_scheme, 2.0 * c.reference_step_s, "");
    ASSERT_EQ(fine.samples.size(), coarse.samples.size());
    EXPECT_LT(max_difference(fine, coarse), 1e-6 * motion(fine));
  }
}

TEST(StudyDevices, StepsAndSchemesItCannotTakeAreRefusedBeforeAnyWork) {
  const std::vector<StudyCase> cases = device_cases(true);
  const StudyCase& c = find(cases, "dc_motor_mass_000");
  for (double h : {3e-4, 0.0, -1e-4, std::nan(""), 2e-3, 1e-8, 1.5e-3}) {
    try {
      c.simulate(Scheme::kRk4, h, "");
      ADD_FAILURE() << "step " << h << " was taken";
    } catch (const std::invalid_argument& error) {
      EXPECT_NE(std::string(error.what()).find("dc_motor_mass_000: step_s"), std::string::npos) << error.what();
    }
  }
  EXPECT_THROW(c.simulate(Scheme::kExactZoh, 1e-4, ""), std::invalid_argument);
  EXPECT_THROW(c.simulate(Scheme::kRk4, 1e-4, "no such variant"), std::invalid_argument);
  EXPECT_THROW(find(cases, "dc_motor_inductance_000").simulate(Scheme::kRk4, 1e-4, "rigid"),
               std::invalid_argument);
  EXPECT_NO_THROW(c.simulate(Scheme::kRk4, 2.5e-4, ""));  // four sub-steps
}

TEST(StudyDevices, ExplicitEulerAtOneSubStepOnTheStiffTransmissionIsAResult) {
  // 004's cable: ω = √(k_t (1/M_m + 1/M_s)) ≈ 1011 rad/s with ζ ≈ 0.28, so at h = 1 ms explicit
  // Euler's |1 + hλ| ≈ 1.21 (unstable for the free mode). In this scene the shaft slides against
  // the sleeve's Coulomb friction, whose stick band the plant widens to F_d h / M_s ≈ 51 mm/s at
  // h = 1 ms: each sub-step sets the slow shaft to rest and the growth never starts. Either way
  // the run must come back as a result — diverged, non-finite, or far off — never a crash.
  const std::vector<StudyCase> cases = device_cases(true);
  const StudyCase& c = find(cases, "joystick_shaft_004");
  const Trajectory reference = c.simulate(Scheme::kRk4, 1e-5, "");
  Trajectory coarse;
  ASSERT_NO_THROW(coarse = c.simulate(Scheme::kExplicitEuler, 1e-3, ""));
  ASSERT_FALSE(coarse.samples.empty());
  if (coarse.finite && !coarse.diverged) {
    EXPECT_GT(max_difference(coarse, reference), 0.2 * motion(reference));  // hω ≈ 1: unresolved
  }
  // Resolving the mode (hω ≈ 0.1) brings it within 1 % of the motion.
  const Trajectory fine = c.simulate(Scheme::kExplicitEuler, 1e-4, "");
  EXPECT_TRUE(fine.finite && !fine.diverged);
  EXPECT_LT(max_difference(fine, reference), 0.01 * motion(reference));
}

TEST(StudyDevices, TheInductanceChangesTheMotionALittle) {
  // 000's t_e = L_m / R_m ≪ t_m: dropping the inductance (eq. 3.9) moves the tool by well under a
  // percent of its motion — but by more than rounding.
  const std::vector<StudyCase> cases = device_cases(true);
  const StudyCase& c = find(cases, "dc_motor_inductance_000");
  ASSERT_EQ(c.variants.front(), "with_inductance");
  const Trajectory full = c.simulate(Scheme::kRk4, 1e-4, "with_inductance");
  const Trajectory reduced = c.simulate(Scheme::kRk4, 1e-4, "without_inductance");
  const double difference = max_difference(full, reduced);
  EXPECT_GT(difference, 1e-4 * motion(full));
  EXPECT_LT(difference, 1e-2 * motion(full));
}

TEST(StudyDevices, TheFilesUnderConfigLabAreWhatTheCasesRun) {
  // Running a case's file as `haptic-lab run --scene config/lab/<file>` does (RK4, 10 sub-steps
  // as the file says) gives the case's own trajectory at h = 0.1 ms, to the bit.
  const std::vector<StudyCase> cases = device_cases(true);
  struct Check {
    const char* case_name;
    const char* variant;  // The variant that is the file as it is.
    const char* file;
  };
  for (const Check& check : {Check{"dc_motor_mass_000", "", "config/lab/dc_motor_mass_000.json"},
                             Check{"parallel_dob_wall_001", "", "config/lab/parallel_dob_wall_001.json"},
                             Check{"five_bar_wall_003", "", "config/lab/five_bar_wall_003.json"},
                             Check{"joystick_shaft_004", "", "config/lab/joystick_shaft_004.json"},
                             Check{"dc_motor_inductance_000", "without_inductance",
                                   "config/lab/dc_motor_mass_000.json"},
                             Check{"five_bar_flexible_003", "rigid", "config/lab/five_bar_swing_003.json"},
                             Check{"five_bar_coriolis_003", "coriolis", "config/lab/five_bar_swing_003.json"}}) {
    SCOPED_TRACE(check.case_name);
    const StudyCase& c = find(cases, check.case_name);
    const Trajectory t = c.simulate(Scheme::kRk4, 1e-4, check.variant);
    const std::vector<engine::Vec3> file =
        run_file(check.file, c.duration_s, static_cast<int>(std::llround(c.output_period_s / 1e-3)));
    ASSERT_EQ(file.size(), t.samples.size());
    for (std::size_t k = 0; k < file.size(); ++k) {  // the case samples p_WT(t) − p_WT(0)
      EXPECT_EQ(file[k].x - file[0].x, t.samples[k].x);
      EXPECT_EQ(file[k].y - file[0].y, t.samples[k].y);
      EXPECT_EQ(file[k].z - file[0].z, t.samples[k].z);
    }
  }
}

}  // namespace
}  // namespace haptic::lab
