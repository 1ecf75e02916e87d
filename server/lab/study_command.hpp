#pragma once
// `haptic-lab study`: the command-line face of the study (study.hpp) — which cases, schemes and
// steps, how many threads, where the CSV and markdown go, and a progress bar on standard error.

#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace haptic::lab {

struct StudyCommandOptions {
  bool short_suite = false;          // The ctest-sized suite (three decades, fewer points).
  std::string out_dir = "study-out"; // Gets study.csv, references.csv, cases.csv and study.md.
  unsigned threads = 0;              // 0: one per hardware thread.
  std::vector<std::string> cases;    // Case names or groups ("schemes", "fidelity"); empty: all.
  std::vector<std::string> schemes;  // Scheme names; empty: each case's own.
  std::vector<double> steps_s;       // Replace every case's steps; empty: each case's own.
  double min_cpu_s = -1.0;           // Timing floor per run; < 0: 0.02 s (0.002 s for --short).
  bool list = false;                 // Print the cases and stop.
  bool progress = true;
};

/// Adds the `study` subcommand and its options to `cli`.
CLI::App* add_study_command(CLI::App& cli, StudyCommandOptions& options);

/// Runs it: 0 when done, 2 (with a message on standard error) for bad options — unknown cases or
/// schemes, steps that are not positive or do not divide a case's output period — found before
/// any run starts.
int run_study_command(const StudyCommandOptions& options);

}  // namespace haptic::lab
