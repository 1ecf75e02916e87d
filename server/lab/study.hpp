#pragma once
// haptic-lab's `study`: error against run time for every way the project discretizes or
// integrates, on a suite of cases (docs/numerics.md). A case is a simulation that can be run with
// any scheme at any step; the study runs it with each scheme at each step, compares what it
// produced with a reference (the exact solution where one exists, otherwise the same case at a
// much finer step, whose own convergence is reported), and records the CPU time per simulated
// second, whether the run stayed stable, and how far its energy drifted. Unstable runs are
// results, never crashes: a case's simulation stops on the first non-finite value or on leaving
// its bound and says so.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

#include "engine/analysis/growth.hpp"
#include "engine/core/exact_zoh.hpp"
#include "engine/core/integrator.hpp"
#include "engine/core/vec3.hpp"

namespace haptic::lab {

/// The schemes a case can be run with: the plants' five integrators (engine/core/integrator.hpp)
/// and, where the part is linear, its exact zero-order-hold discretization (the matrix
/// exponential over one step with the input held).
enum class Scheme : std::uint8_t {
  kExplicitEuler,
  kSemiImplicitEuler,
  kTrapezoidal,
  kRk4,
  kImplicitEuler,
  kExactZoh,
};

inline constexpr Scheme kAllSchemes[] = {Scheme::kExplicitEuler, Scheme::kSemiImplicitEuler,
                                         Scheme::kTrapezoidal,   Scheme::kRk4,
                                         Scheme::kImplicitEuler, Scheme::kExactZoh};
/// The integrators alone (for cases that are not linear).
inline constexpr Scheme kIntegratorSchemes[] = {Scheme::kExplicitEuler, Scheme::kSemiImplicitEuler,
                                                Scheme::kTrapezoidal, Scheme::kRk4,
                                                Scheme::kImplicitEuler};

std::string_view scheme_name(Scheme scheme);
std::optional<Scheme> scheme_from_name(std::string_view name);
/// The engine integrator a scheme is; nullopt for kExactZoh.
std::optional<engine::Integrator> as_integrator(Scheme scheme);

/// What one simulation of a case produced, sampled at t_k = k · output_period_s for
/// k = 0 … duration / output_period (t = 0 included). A run that diverges stops early: its
/// samples end where it did, and `finite` or `diverged` says why.
struct Trajectory {
  std::vector<engine::Vec3> samples;  // The case's observable (scalar cases use x). Unit: the case's.
  std::vector<double> energy;         // The case's energy at the same instants (J); empty: none.
  bool finite = true;                 // false: a value became non-finite.
  bool diverged = false;              // true: the observable left the case's bound.
  std::uint64_t fault_ticks = 0;      // Ticks the server's safety stage refused a force.
  std::string note;                   // Anything a reader should know ("watchdog tripped at 0.31 s").
};

/// One case of the study.
struct StudyCase {
  std::string name;        // File-safe identifier, used for charts: "linear_wall".
  std::string title;       // One line for tables and charts.
  std::string source;      // Where its physics and numbers come from ("000 eq. 7.1").
  std::string observable;  // What is compared, with its unit ("tool position, m").
  std::string group = "schemes";  // "schemes" or "fidelity" (model choices at a fixed scheme).
  double duration_s = 0.5;        // Simulated time of each run.
  double output_period_s = 0.01;  // Sample spacing; every step in steps_s divides it.
  std::vector<Scheme> schemes;    // Schemes to run.
  std::vector<double> steps_s;    // Step sizes (s), over at least three decades in the full suite.
  /// Model variants (fidelity cases: "full", "no inductance", …); the first is the reference's
  /// model. Empty: one unnamed variant.
  std::vector<std::string> variants;
  /// Runs the case once, for duration_s, sampling every output_period_s (the closure holds its
  /// own copy of both: change them by building the case anew, not by editing the fields). Must throw std::invalid_argument for a step it cannot take (before any
  /// work) and otherwise return, however the run went.
  std::function<Trajectory(Scheme scheme, double step_s, const std::string& variant)> simulate;
  /// Optional: "" when the case can take `step_s`, else why not (checked with the other
  /// validation, before any run; e.g. a device case's step must divide its tick).
  std::function<std::string(double step_s)> check_step;
  /// The exact solution, where one exists; empty: the reference is `reference_scheme` at
  /// `reference_step_s` (and, to show it has converged, also at twice that step).
  std::function<Trajectory()> exact;
  Scheme reference_scheme = Scheme::kRk4;
  double reference_step_s = 1e-6;
  bool conservative = false;  // Energy should stay constant (no damping): drift is against E(0).
};

/// One run's row.
struct StudyResult {
  std::string case_name;
  std::string variant;
  Scheme scheme = Scheme::kRk4;
  double step_s = 0.0;
  double error = 0.0;           // max over samples of |observable − reference|; +inf if the run
                                // did not finish. Unit: the case's.
  double relative_error = 0.0;  // error / max |reference|.
  double cpu_s_per_sim_s = 0.0; // CPU seconds per simulated second (thread CPU time).
  bool stable = true;           // Finished, finite and within bound.
  double energy_drift = 0.0;    // Conservative cases: (E_end − E_0) / E_0; others: the largest
                                // |E − E_reference| / max |E_reference|. NaN: no energy.
  std::string note;
};

/// How a case's reference was obtained.
struct ReferenceSummary {
  std::string case_name;
  bool exact = false;           // Analytic; otherwise converged fine step.
  Scheme scheme = Scheme::kRk4; // For a converged reference.
  double step_s = 0.0;
  double convergence = 0.0;     // max |ref(step) − ref(2 step)|: how well the reference has
                                // converged (0 for an exact one). Unit: the case's.
  double scale = 0.0;           // max |reference|, the denominator of relative errors.
};

struct StudyReport {
  std::vector<ReferenceSummary> references;
  std::vector<StudyResult> results;
};

/// The finest step the study takes: below it a single run of a case would take minutes. Unit: s.
inline constexpr double kMinStep = 1e-7;

struct StudyOptions {
  unsigned threads = 1;         // Runs in parallel (each run on one thread).
  double min_cpu_s = 0.02;      // Repeat a run until it has used this much CPU, for its timing.
  /// Called after each run, under a lock, from whichever thread finished it.
  std::function<void(std::size_t done, std::size_t total, const std::string& what)> progress;
};

/// The suite: the ODE cases (linear wall, 000 eq. 7.1, stiff and extreme cases, 003's joint with
/// friction, friction models) and the document devices' cases. `short_suite` keeps three decades
/// of steps with fewer points and shorter runs, for ctest.
std::vector<StudyCase> ode_cases(bool short_suite);
std::vector<StudyCase> device_cases(bool short_suite);

/// Checks every case (a name, schemes, steps that are positive, finite, at least kMinStep and
/// divide the output period, the case's own check_step, a duration the output period divides, a
/// simulate function) and throws std::invalid_argument naming the first problem, before any work.
void validate_cases(const std::vector<StudyCase>& cases);

/// Runs the cases (validated first) and returns one row per case × variant × scheme × step.
StudyReport run_study(const std::vector<StudyCase>& cases, const StudyOptions& options);

/// How fast `trajectory`'s energy envelope grows over the case's second half (in eighths of it;
/// engine::envelope_growth, windows at or below `floor` J left out): a run whose rate exceeds its
/// reference's (or 0) by engine::kRingUpRate is unstable.
engine::GrowthFit energy_growth(const StudyCase& c, const Trajectory& trajectory, double floor);

/// The rows as CSV (header: case,group,variant,scheme,step_s,error,relative_error,
/// cpu_s_per_sim_s,stable,energy_drift,note; stable 1/0; error inf for a run that did not finish).
void write_study_csv(const std::vector<StudyCase>& cases, const StudyReport& report, std::ostream& out);
/// The references (case,exact,scheme,step_s,convergence,scale) and the cases
/// (name,title,source,observable,group), for the charts (scripts/plot_study.py).
void write_references_csv(const StudyReport& report, std::ostream& out);
void write_cases_csv(const std::vector<StudyCase>& cases, std::ostream& out);
/// The decision table: per case, scheme and variant, the largest step at and below which every
/// run was stable, and the cheapest run within 1e-3 relative error (its step and CPU time).
void write_study_summary(const std::vector<StudyCase>& cases, const StudyReport& report, std::ostream& out);
/// A markdown report: the summary, then per case its description, its reference, and a table of the rows.
void write_study_markdown(const std::vector<StudyCase>& cases, const StudyReport& report,
                          std::ostream& out);

}  // namespace haptic::lab
