#include "lab/study_command.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <thread>

#include "lab/progress_bar.hpp"
#include "lab/study.hpp"

namespace haptic::lab {
namespace {

/// The suite the options select, with their scheme and step overrides applied.
std::vector<StudyCase> select_cases(const StudyCommandOptions& options) {
  std::vector<StudyCase> all = ode_cases(options.short_suite);
  for (StudyCase& c : device_cases(options.short_suite)) all.push_back(std::move(c));
  std::vector<StudyCase> chosen;
  for (const std::string& wanted : options.cases) {
    const bool known = std::any_of(all.begin(), all.end(), [&](const StudyCase& c) {
      return c.name == wanted || c.group == wanted;
    });
    if (!known) {
      std::string names;
      for (const StudyCase& c : all) names += (names.empty() ? "" : ", ") + c.name;
      throw std::invalid_argument("--case: no case or group \"" + wanted + "\"; cases: " + names +
                                  "; groups: schemes, fidelity");
    }
  }
  std::vector<Scheme> schemes;
  for (const std::string& name : options.schemes) {
    const auto scheme = scheme_from_name(name);
    if (!scheme) {
      std::string names;
      for (const Scheme s : kAllSchemes) names += (names.empty() ? "" : ", ") + std::string(scheme_name(s));
      throw std::invalid_argument("--scheme: unknown scheme \"" + name + "\"; expected one of " + names);
    }
    schemes.push_back(*scheme);
  }
  for (StudyCase& c : all) {
    const bool selected = options.cases.empty() ||
                          std::any_of(options.cases.begin(), options.cases.end(), [&](const std::string& w) {
                            return c.name == w || c.group == w;
                          });
    if (!selected) continue;
    if (!schemes.empty()) {
      std::vector<Scheme> kept;
      for (const Scheme s : schemes) {
        if (std::find(c.schemes.begin(), c.schemes.end(), s) != c.schemes.end()) kept.push_back(s);
      }
      if (kept.empty()) continue;  // none of the asked schemes applies to this case
      c.schemes = kept;
    }
    if (!options.steps_s.empty()) c.steps_s = options.steps_s;
    chosen.push_back(std::move(c));
  }
  if (chosen.empty()) throw std::invalid_argument("--scheme: no selected case can run the schemes asked for");
  return chosen;
}

std::ofstream open_for_writing(const std::filesystem::path& path) {
  std::ofstream out(path);
  if (!out) throw std::invalid_argument(path.string() + ": cannot write");
  return out;
}

}  // namespace

CLI::App* add_study_command(CLI::App& cli, StudyCommandOptions& options) {
  CLI::App* study = cli.add_subcommand(
      "study", "error against run time for every scheme and step on the study's cases (docs/numerics.md)");
  study->add_flag("--short", options.short_suite, "the short suite (ctest's): fewer steps, shorter runs");
  study->add_option("--out", options.out_dir, "directory for study.csv, references.csv, cases.csv, study.md")
      ->capture_default_str();
  study->add_option("--threads", options.threads, "runs in parallel (default: one per hardware thread)");
  study->add_option("--case", options.cases, "only these cases or groups (schemes, fidelity); repeatable");
  study->add_option("--scheme", options.schemes,
                    "only these schemes: explicit_euler, semi_implicit_euler, trapezoidal, rk4, "
                    "implicit_euler, exact_zoh; repeatable");
  study->add_option("--steps", options.steps_s, "replace every case's step sizes, s")->delimiter(',');
  study->add_option("--min-cpu", options.min_cpu_s, "repeat each run until it has used this much CPU, s");
  study->add_flag("--list", options.list, "list the cases and stop");
  study->add_flag("!--no-progress", options.progress, "no progress bar");
  return study;
}

int run_study_command(const StudyCommandOptions& options) {
  try {
    const std::vector<StudyCase> cases = select_cases(options);
    validate_cases(cases);  // every error before any work
    if (options.list) {
      for (const StudyCase& c : cases) {
        std::printf("%-28s %-9s %s\n", c.name.c_str(), c.group.c_str(), c.title.c_str());
      }
      return 0;
    }
    const std::filesystem::path dir(options.out_dir);
    std::error_code error;
    std::filesystem::create_directories(dir, error);
    if (error) throw std::invalid_argument(options.out_dir + ": cannot create (" + error.message() + ")");
    auto study_csv = open_for_writing(dir / "study.csv");
    auto references_csv = open_for_writing(dir / "references.csv");
    auto cases_csv = open_for_writing(dir / "cases.csv");
    auto markdown = open_for_writing(dir / "study.md");

    StudyOptions run;
    run.threads = options.threads > 0 ? options.threads : std::max(1u, std::thread::hardware_concurrency());
    run.min_cpu_s = options.min_cpu_s >= 0.0 ? options.min_cpu_s : (options.short_suite ? 0.002 : 0.02);
    ProgressBar bar("haptic-lab study", options.progress);
    run.progress = [&bar](std::size_t done, std::size_t total, const std::string& what) {
      bar.update(done, total, what);
    };
    const auto start = std::chrono::steady_clock::now();
    const StudyReport report = run_study(cases, run);
    const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

    write_study_csv(cases, report, study_csv);
    write_references_csv(report, references_csv);
    write_cases_csv(cases, cases_csv);
    std::size_t unstable = 0;
    for (const StudyResult& r : report.results) unstable += r.stable ? 0 : 1;
    markdown << "# haptic-lab study" << (options.short_suite ? " (short suite)" : "") << "\n\n"
             << report.results.size() << " runs on " << cases.size() << " cases, " << unstable
             << " of them unstable, in " << static_cast<int>(wall_s) << " s on " << run.threads
             << " threads. Errors are the largest distance from the reference over the samples; CPU "
                "time is this thread's, per simulated second. Charts: scripts/plot_study.py.\n\n";
    write_study_markdown(cases, report, markdown);
    std::fprintf(stderr, "haptic-lab study: %zu runs, %zu unstable, %.1f s; wrote %s/{study.csv,references.csv,cases.csv,study.md}\n",
                 report.results.size(), unstable, wall_s, options.out_dir.c_str());
    return 0;
  } catch (const std::invalid_argument& e) {
    std::cerr << "haptic-lab study: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "haptic-lab study: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace haptic::lab
