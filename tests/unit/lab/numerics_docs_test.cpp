// docs/numerics.md quotes docs/numerics/study.csv; this checks that the committed file is what the
// study computes now, for every case that runs without a device (all of them but the document
// devices', which take a minute): same rows, same errors, same verdicts. Timing columns differ
// run to run and are not compared. After changing a case, regenerate with scripts/numerics.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "lab/study.hpp"

namespace haptic::lab {
namespace {

/// Splits one CSV line (fields with commas are quoted, quotes doubled).
std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> fields(1);
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted && c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
      fields.back() += '"';
      ++i;
    } else if (c == '"') {
      quoted = !quoted;
    } else if (c == ',' && !quoted) {
      fields.emplace_back();
    } else {
      fields.back() += c;
    }
  }
  return fields;
}

TEST(NumericsDocs, TheCommittedStudyIsWhatTheStudyComputesForEveryCaseWithoutADevice) {
  std::ifstream file(std::string(HAPTIC_SOURCE_DIR) + "/docs/numerics/study.csv");
  ASSERT_TRUE(file) << "docs/numerics/study.csv is missing: run scripts/numerics";
  std::string line;
  std::getline(file, line);
  ASSERT_EQ(line, "case,group,variant,scheme,step_s,error,relative_error,cpu_s_per_sim_s,stable,energy_drift,note");
  std::map<std::string, std::vector<std::string>> committed;  // key: case|variant|scheme|step
  while (std::getline(file, line)) {
    const std::vector<std::string> f = split_csv(line);
    ASSERT_EQ(f.size(), 11u) << line;
    committed[f[0] + "|" + f[2] + "|" + f[3] + "|" + f[4]] = f;
  }

  StudyOptions options;
  options.min_cpu_s = 0.0;
  options.threads = 2;
  const std::vector<StudyCase> cases = ode_cases(false);
  const StudyReport report = run_study(cases, options);
  std::ostringstream csv;
  write_study_csv(cases, report, csv);
  std::istringstream rows(csv.str());
  std::getline(rows, line);
  int compared = 0;
  while (std::getline(rows, line)) {
    const std::vector<std::string> now = split_csv(line);
    const std::string key = now[0] + "|" + now[2] + "|" + now[3] + "|" + now[4];
    const auto it = committed.find(key);
    ASSERT_NE(it, committed.end()) << "docs/numerics/study.csv has no row " << key << ": run scripts/numerics";
    const std::vector<std::string>& then = it->second;
    // error (m or rad), relative_error, energy_drift: to the file's 6 digits, and to an absolute
    // floor at rounding level (exact ZOH's 1e-13 errors are rounding, not physics).
    for (const auto& [column, floor] : {std::pair{5, 1e-14}, std::pair{6, 1e-11}, std::pair{9, 1e-11}}) {
      const double a = std::stod(now[static_cast<std::size_t>(column)]);
      const double b = std::stod(then[static_cast<std::size_t>(column)]);
      if (std::isfinite(a) || std::isfinite(b)) {
        EXPECT_NEAR(a, b, 1e-5 * std::abs(b) + floor) << key << " column " << column;
      } else {
        EXPECT_EQ(std::isnan(a), std::isnan(b)) << key << " column " << column;
      }
    }
    EXPECT_EQ(now[8], then[8]) << key << ": stable";
    EXPECT_EQ(now[10], then[10]) << key << ": note";
    ++compared;
  }
  EXPECT_GT(compared, 700);
}

}  // namespace
}  // namespace haptic::lab
