#include "lab/study.hpp"

#include <time.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <exception>
#include <iomanip>
#include <limits>
#include <map>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace haptic::lab {

std::string_view scheme_name(Scheme scheme) {
  switch (scheme) {
    case Scheme::kExplicitEuler: return "explicit_euler";
    case Scheme::kSemiImplicitEuler: return "semi_implicit_euler";
    case Scheme::kTrapezoidal: return "trapezoidal";
    case Scheme::kRk4: return "rk4";
    case Scheme::kImplicitEuler: return "implicit_euler";
    case Scheme::kExactZoh: return "exact_zoh";
  }
  return "unknown";
}

std::optional<Scheme> scheme_from_name(std::string_view name) {
  for (const Scheme scheme : kAllSchemes) {
    if (scheme_name(scheme) == name) return scheme;
  }
  return std::nullopt;
}

std::optional<engine::Integrator> as_integrator(Scheme scheme) {
  switch (scheme) {
    case Scheme::kExplicitEuler: return engine::Integrator::kExplicitEuler;
    case Scheme::kSemiImplicitEuler: return engine::Integrator::kSemiImplicitEuler;
    case Scheme::kTrapezoidal: return engine::Integrator::kTrapezoidal;
    case Scheme::kRk4: return engine::Integrator::kRk4;
    case Scheme::kImplicitEuler: return engine::Integrator::kImplicitEuler;
    case Scheme::kExactZoh: return std::nullopt;
  }
  return std::nullopt;
}

namespace {

/// Whether `step` divides `period` into a whole number of steps (to a part in 1e-9).
bool divides(double step, double period) {
  const double n = period / step;
  return std::abs(n - std::round(n)) <= 1e-9 * n && std::round(n) >= 1.0;
}

std::string format_number(double value) {
  std::ostringstream out;
  out << std::setprecision(6) << value;
  return out.str();
}

double thread_cpu_seconds() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec);
}

/// max_k |a_k − b_k| over the samples both have; +inf when `a` is shorter than `b`.
double max_difference(const std::vector<engine::Vec3>& a, const std::vector<engine::Vec3>& b) {
  if (a.size() < b.size()) return std::numeric_limits<double>::infinity();
  double worst = 0.0;
  for (std::size_t k = 0; k < b.size(); ++k) {
    const double e = engine::norm(a[k] - b[k]);
    if (!std::isfinite(e)) return std::numeric_limits<double>::infinity();
    worst = std::max(worst, e);
  }
  return worst;
}

double max_magnitude(const std::vector<engine::Vec3>& samples) {
  double largest = 0.0;
  for (const engine::Vec3& s : samples) largest = std::max(largest, engine::norm(s));
  return largest;
}

struct Reference {
  Trajectory trajectory;
  ReferenceSummary summary;
};

/// Runs simulate until it has used `min_cpu_s` of this thread's CPU (at least once); returns the
/// last trajectory and the CPU seconds per run.
Trajectory timed(const StudyCase& c, Scheme scheme, double step, const std::string& variant,
                 double min_cpu_s, double& cpu_s_per_run) {
  Trajectory trajectory;
  int runs = 0;
  const double start = thread_cpu_seconds();
  double used = 0.0;
  do {
    trajectory = c.simulate(scheme, step, variant);
    ++runs;
    used = thread_cpu_seconds() - start;
  } while (used < min_cpu_s && runs < 1000);
  cpu_s_per_run = used / runs;
  return trajectory;
}

Reference make_reference(const StudyCase& c) {
  Reference reference;
  reference.summary.case_name = c.name;
  const std::string& model = c.variants.empty() ? std::string() : c.variants.front();
  if (c.exact) {
    reference.trajectory = c.exact();
    reference.summary.exact = true;
  } else {
    reference.trajectory = c.simulate(c.reference_scheme, c.reference_step_s, model);
    const Trajectory coarser = c.simulate(c.reference_scheme, 2.0 * c.reference_step_s, model);
    reference.summary.scheme = c.reference_scheme;
    reference.summary.step_s = c.reference_step_s;
    reference.summary.convergence = max_difference(coarser.samples, reference.trajectory.samples);
  }
  const Trajectory& r = reference.trajectory;
  const auto expected = static_cast<std::size_t>(std::llround(c.duration_s / c.output_period_s)) + 1;
  if (!r.finite || r.diverged || r.samples.size() != expected) {
    throw std::runtime_error(c.name + ": the reference run did not finish (" +
                             std::to_string(r.samples.size()) + " of " + std::to_string(expected) +
                             " samples" + (r.note.empty() ? "" : ", " + r.note) + ")");
  }
  reference.summary.scale = max_magnitude(r.samples);
  return reference;
}

}  // namespace

engine::GrowthFit energy_growth(const StudyCase& c, const Trajectory& trajectory, double floor) {
  return engine::envelope_growth(trajectory.energy, c.output_period_s, 0.5 * c.duration_s, c.duration_s / 16.0, floor);
}

namespace {

StudyResult evaluate(const StudyCase& c, const Reference& reference, const std::string& variant,
                     Scheme scheme, double step, double min_cpu_s) {
  StudyResult row;
  row.case_name = c.name;
  row.variant = variant;
  row.scheme = scheme;
  row.step_s = step;
  double cpu_s = 0.0;
  const Trajectory run = timed(c, scheme, step, variant, min_cpu_s, cpu_s);
  row.cpu_s_per_sim_s = cpu_s / c.duration_s;
  const std::vector<engine::Vec3>& ref = reference.trajectory.samples;
  const double scale = reference.summary.scale > 0.0 ? reference.summary.scale : 1.0;
  row.error = max_difference(run.samples, ref);
  row.relative_error = row.error / scale;
  row.note = run.note;
  auto add_note = [&row](const std::string& text) { row.note += (row.note.empty() ? "" : "; ") + text; };
  const bool complete = run.samples.size() >= ref.size();
  row.stable = run.finite && !run.diverged && complete;
  if (!run.finite) add_note("non-finite at t = " + format_number(c.output_period_s * static_cast<double>(run.samples.size())) + " s");
  if (run.diverged) add_note("left its bound at t = " + format_number(c.output_period_s * static_cast<double>(run.samples.size())) + " s");
  if (row.stable && max_magnitude(run.samples) > 10.0 * scale) {
    row.stable = false;
    add_note("grew past 10x the reference's largest value");
  }
  // Where the variant is another model than the reference's (fidelity cases), its energy may
  // rightly do what the reference's does not: only the reference's own model is judged so.
  const bool reference_model = c.variants.empty() || variant == c.variants.front() || c.group != "fidelity";
  if (row.stable && reference_model && !run.energy.empty() && !reference.trajectory.energy.empty()) {
    // A size criterion alone (10x the reference) misses a slow ring-up: a pole at 1.0014 at 5 ms
    // grows the energy 2.5-3x in 2 s. So the run's energy envelope over its second half is
    // fitted (engine::envelope_growth) and set against the reference's: the energy, not the
    // observable, carries no phase, so a stable scheme's phase error does not read as growth.
    double largest = 0.0;
    for (const double e : reference.trajectory.energy) largest = std::max(largest, std::abs(e));
    // Below a thousandth of the reference's largest energy a run has come to rest (or creeps): a
    // ring-up passes it on its way.
    const double floor = 1e-3 * (largest > 0.0 ? largest : 1.0);
    const engine::GrowthFit growth = energy_growth(c, run, floor);
    const engine::GrowthFit settled = energy_growth(c, reference.trajectory, floor);
    if (engine::rings_up(growth, &settled)) {
      row.stable = false;
      add_note("rings up: its energy grows at " + format_number(growth.rate_per_s) + "/s");
    }
  }
  if (run.fault_ticks > 0) add_note(std::to_string(run.fault_ticks) + " force-fault ticks");

  const std::vector<double>& e = run.energy;
  const std::vector<double>& e_ref = reference.trajectory.energy;
  row.energy_drift = std::numeric_limits<double>::quiet_NaN();
  if (!e.empty() && !e_ref.empty()) {
    if (!complete || e.size() < e_ref.size()) {
      row.energy_drift = std::numeric_limits<double>::infinity();
    } else if (c.conservative) {
      const double e0 = std::abs(e.front()) > 0.0 ? std::abs(e.front()) : 1.0;
      row.energy_drift = (e[e_ref.size() - 1] - e.front()) / e0;
    } else {
      double worst = 0.0, largest = 0.0;
      for (std::size_t k = 0; k < e_ref.size(); ++k) {
        worst = std::max(worst, std::abs(e[k] - e_ref[k]));
        largest = std::max(largest, std::abs(e_ref[k]));
      }
      row.energy_drift = worst / (largest > 0.0 ? largest : 1.0);
    }
    if (!std::isfinite(row.energy_drift)) row.energy_drift = std::numeric_limits<double>::infinity();
  }
  return row;
}

/// Runs job(i) for i in [0, count) on `threads` threads; the first exception is rethrown after
/// all threads have stopped (the others skip their remaining jobs).
template <typename Job>
void parallel_for(std::size_t count, unsigned threads, Job&& job) {
  std::atomic<std::size_t> next{0};
  std::atomic<bool> failed{false};
  std::exception_ptr first_error;
  std::mutex error_mutex;
  auto worker = [&] {
    for (std::size_t i = next++; i < count && !failed; i = next++) {
      try {
        job(i);
      } catch (...) {
        const std::lock_guard lock(error_mutex);
        if (!first_error) first_error = std::current_exception();
        failed = true;
      }
    }
  };
  const unsigned n = std::max(1u, std::min<unsigned>(threads, static_cast<unsigned>(count)));
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < n; ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();
  if (first_error) std::rethrow_exception(first_error);
}

}  // namespace

void validate_cases(const std::vector<StudyCase>& cases) {
  std::map<std::string, int> seen;
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const StudyCase& c = cases[i];
    const std::string where = "case " + (c.name.empty() ? "[" + std::to_string(i) + "]" : "\"" + c.name + "\"");
    if (c.name.empty()) throw std::invalid_argument(where + ": has no name");
    if (seen[c.name]++ > 0) throw std::invalid_argument(where + ": appears twice");
    if (!c.simulate) throw std::invalid_argument(where + ": has no simulation");
    if (c.schemes.empty()) throw std::invalid_argument(where + ": has no schemes");
    if (c.steps_s.empty()) throw std::invalid_argument(where + ": has no steps");
    if (!(std::isfinite(c.output_period_s) && c.output_period_s > 0.0)) {
      throw std::invalid_argument(where + ": output period must be finite and > 0 s, got " + format_number(c.output_period_s));
    }
    if (!(std::isfinite(c.duration_s) && c.duration_s > 0.0) || !divides(c.output_period_s, c.duration_s)) {
      throw std::invalid_argument(where + ": duration " + format_number(c.duration_s) +
                                  " s must be a positive multiple of the output period " +
                                  format_number(c.output_period_s) + " s");
    }
    for (const double step : c.steps_s) {
      if (!(std::isfinite(step) && step > 0.0)) {
        throw std::invalid_argument(where + ": step must be finite and > 0 s, got " + format_number(step));
      }
      if (step < kMinStep) {
        throw std::invalid_argument(where + ": step " + format_number(step) + " s is below the study's " +
                                    format_number(kMinStep) + " s");
      }
      if (c.check_step) {
        if (const std::string why = c.check_step(step); !why.empty()) throw std::invalid_argument(where + ": " + why);
      }
      if (!divides(step, c.output_period_s)) {
        throw std::invalid_argument(where + ": step " + format_number(step) +
                                    " s does not divide the output period " +
                                    format_number(c.output_period_s) + " s");
      }
    }
    if (!c.exact && !(std::isfinite(c.reference_step_s) && c.reference_step_s > 0.0 &&
                      divides(2.0 * c.reference_step_s, c.output_period_s))) {
      throw std::invalid_argument(where + ": reference step " + format_number(c.reference_step_s) +
                                  " s (and twice it) must divide the output period");
    }
  }
}

StudyReport run_study(const std::vector<StudyCase>& cases, const StudyOptions& options) {
  validate_cases(cases);
  struct Job {
    std::size_t case_index;
    std::string variant;
    Scheme scheme;
    double step;
  };
  std::vector<Job> jobs;
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const std::vector<std::string> variants =
        cases[i].variants.empty() ? std::vector<std::string>{""} : cases[i].variants;
    for (const std::string& variant : variants) {
      for (const Scheme scheme : cases[i].schemes) {
        for (const double step : cases[i].steps_s) jobs.push_back({i, variant, scheme, step});
      }
    }
  }
  const std::size_t total = cases.size() + jobs.size();
  std::size_t done = 0;
  std::mutex progress_mutex;
  auto report_progress = [&](const std::string& what) {
    const std::lock_guard lock(progress_mutex);
    ++done;
    if (options.progress) options.progress(done, total, what);
  };

  std::vector<Reference> references(cases.size());
  parallel_for(cases.size(), options.threads, [&](std::size_t i) {
    references[i] = make_reference(cases[i]);
    report_progress(cases[i].name + " reference");
  });
  StudyReport report;
  report.results.resize(jobs.size());
  parallel_for(jobs.size(), options.threads, [&](std::size_t j) {
    const Job& job = jobs[j];
    const StudyCase& c = cases[job.case_index];
    report.results[j] = evaluate(c, references[job.case_index], job.variant, job.scheme, job.step, options.min_cpu_s);
    report_progress(c.name + " " + (job.variant.empty() ? "" : job.variant + " ") +
                    std::string(scheme_name(job.scheme)) + " h=" + format_number(job.step));
  });
  for (const Reference& r : references) report.references.push_back(r.summary);
  return report;
}

namespace {

/// A CSV field: quoted when it holds a comma or a quote.
std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string out = "\"";
  for (const char ch : text) out += ch == '"' ? std::string("\"\"") : std::string(1, ch);
  return out + "\"";
}

std::string group_of(const std::vector<StudyCase>& cases, const std::string& name) {
  for (const StudyCase& c : cases) {
    if (c.name == name) return c.group;
  }
  return "";
}

}  // namespace

void write_study_csv(const std::vector<StudyCase>& cases, const StudyReport& report, std::ostream& out) {
  out << "case,group,variant,scheme,step_s,error,relative_error,cpu_s_per_sim_s,stable,energy_drift,note\n";
  out << std::setprecision(6);
  for (const StudyResult& r : report.results) {
    out << csv_field(r.case_name) << ',' << csv_field(group_of(cases, r.case_name)) << ',' << csv_field(r.variant) << ',' << scheme_name(r.scheme) << ','
        << r.step_s << ',' << r.error << ',' << r.relative_error << ',' << r.cpu_s_per_sim_s << ','
        << (r.stable ? 1 : 0) << ',' << r.energy_drift << ',' << csv_field(r.note) << '\n';
  }
}

void write_references_csv(const StudyReport& report, std::ostream& out) {
  out << "case,exact,scheme,step_s,convergence,scale\n";
  out << std::setprecision(6);
  for (const ReferenceSummary& r : report.references) {
    out << csv_field(r.case_name) << ',' << (r.exact ? 1 : 0) << ','
        << (r.exact ? std::string_view("") : scheme_name(r.scheme)) << ',' << r.step_s << ','
        << r.convergence << ',' << r.scale << '\n';
  }
}

void write_cases_csv(const std::vector<StudyCase>& cases, std::ostream& out) {
  out << "name,title,source,observable,group\n";
  for (const StudyCase& c : cases) {
    out << csv_field(c.name) << ',' << csv_field(c.title) << ',' << csv_field(c.source) << ','
        << csv_field(c.observable) << ',' << csv_field(c.group) << '\n';
  }
}

void write_study_summary(const std::vector<StudyCase>& cases, const StudyReport& report, std::ostream& out) {
  // Per case and scheme (and variant): the largest step below which every step ran stable, and the
  // cheapest run within 1e-3 relative error — the two numbers a choice of scheme and rate needs.
  out << std::setprecision(3);
  out << "| case | variant | scheme | largest stable step (s) | cheapest run within 1e-3: step (s) | its CPU s per s |\n";
  out << "|---|---|---|---:|---:|---:|\n";
  for (const StudyCase& c : cases) {
    const std::vector<std::string> variants = c.variants.empty() ? std::vector<std::string>{""} : c.variants;
    for (const std::string& variant : variants) {
      for (const Scheme scheme : c.schemes) {
        std::vector<const StudyResult*> rows;
        for (const StudyResult& r : report.results) {
          if (r.case_name == c.name && r.variant == variant && r.scheme == scheme) rows.push_back(&r);
        }
        if (rows.empty()) continue;
        std::sort(rows.begin(), rows.end(), [](const StudyResult* a, const StudyResult* b) { return a->step_s < b->step_s; });
        double largest_stable = 0.0;
        for (const StudyResult* r : rows) {
          if (!r->stable) break;
          largest_stable = r->step_s;
        }
        const StudyResult* cheapest = nullptr;
        for (const StudyResult* r : rows) {
          if (r->stable && r->relative_error <= 1e-3 && (cheapest == nullptr || r->cpu_s_per_sim_s < cheapest->cpu_s_per_sim_s)) {
            cheapest = r;
          }
        }
        out << "| " << c.name << " | " << (variant.empty() ? "—" : variant) << " | " << scheme_name(scheme) << " | ";
        if (largest_stable > 0.0) {
          out << (largest_stable == rows.back()->step_s ? "≥ " : "") << largest_stable;
        } else {
          out << "none";
        }
        out << " | ";
        if (cheapest != nullptr) {
          out << cheapest->step_s << " | " << cheapest->cpu_s_per_sim_s;
        } else {
          out << "not reached | —";
        }
        out << " |\n";
      }
    }
  }
  out << "\n";
}

void write_study_markdown(const std::vector<StudyCase>& cases, const StudyReport& report, std::ostream& out) {
  out << "## Summary\n\n";
  write_study_summary(cases, report, out);
  out << "## Cases\n\n";
  out << std::setprecision(3);
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const StudyCase& c = cases[i];
    const ReferenceSummary* ref = nullptr;
    for (const ReferenceSummary& r : report.references) {
      if (r.case_name == c.name) ref = &r;
    }
    out << "### " << c.title << " (`" << c.name << "`)\n\n";
    out << "Source: " << c.source << ". Observable: " << c.observable << ". " << c.duration_s
        << " s simulated, compared every " << c.output_period_s << " s. Reference: ";
    if (ref == nullptr) {
      out << "none.\n\n";
    } else if (ref->exact) {
      out << "the exact solution";
    } else {
      out << scheme_name(ref->scheme) << " at " << ref->step_s << " s (converged to " << ref->convergence
          << " against twice that step)";
    }
    if (ref != nullptr) out << "; largest value " << ref->scale << ".\n\n";
    out << "| variant | scheme | step (s) | max error | relative | CPU s per s | stable | energy drift | note |\n";
    out << "|---|---|---:|---:|---:|---:|---|---:|---|\n";
    for (const StudyResult& r : report.results) {
      if (r.case_name != c.name) continue;
      out << "| " << (r.variant.empty() ? "—" : r.variant) << " | " << scheme_name(r.scheme) << " | "
          << r.step_s << " | " << r.error << " | " << r.relative_error << " | " << r.cpu_s_per_sim_s
          << " | " << (r.stable ? "yes" : "**no**") << " | " << r.energy_drift << " | " << r.note << " |\n";
    }
    out << "\n";
  }
}

}  // namespace haptic::lab
