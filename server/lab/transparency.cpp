#include "lab/transparency.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "lab/device_model.hpp"

namespace haptic::lab {
namespace {

void require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument(message);
}

}  // namespace

TransparencyReport transparency_study(const engine::WallDesignParams& p, double lo, double hi,
                                      int points, double widen_limit) {
  require_device_model(p.mass, p.damping, p.sample_period);
  require(std::isfinite(p.wall_stiffness) && p.wall_stiffness > 0.0, "stiffness: must be finite and > 0");
  require(std::isfinite(p.wall_damping) && p.wall_damping > 0.0, "wall damping: must be finite and > 0");
  require(std::isfinite(p.weight_cutoff) && p.weight_cutoff > 0.0, "w1: must be finite and > 0");
  require(p.mass_uncertainty >= 0.0 && p.mass_uncertainty < 1.0, "alpha: must be in [0, 1)");
  require(p.damping_uncertainty >= 0.0 && p.damping_uncertainty < 1.0, "beta: must be in [0, 1)");
  require(lo > 0.0 && hi > lo && points >= 2, "sweep: needs 0 < lo < hi and at least 2 points");
  TransparencyReport report;
  const double points_per_decade = (points - 1) / std::log10(hi / lo);
  report.optimum = engine::optimise_controller_damping(p, lo, hi);
  auto at_edge = [&] { return report.optimum.controller_damping >= hi * (1.0 - 1e-3); };
  while (at_edge() && hi * 10.0 <= widen_limit) {
    hi *= 10.0;
    points += static_cast<int>(std::lround(points_per_decade));
    report.optimum = engine::optimise_controller_damping(p, lo, hi);
  }
  report.swept_to = hi;
  report.optimum_at_edge = at_edge();
  for (int i = 0; i < points; ++i) {
    const double B_c = lo * std::pow(hi / lo, static_cast<double>(i) / (points - 1));
    report.sweep.push_back({B_c, engine::transparency_index(p, B_c), engine::robust_stability_norm(p, B_c),
                            engine::nominal_loop_stable(p, B_c)});
  }
  for (const engine::HoldModel hold : engine::kHoldModels) {
    engine::WallDesignParams q = p;
    q.hold = hold;
    const double B_c = report.optimum.controller_damping;
    report.holds.push_back({hold, engine::optimise_controller_damping(q, lo, hi),
                            {engine::robust_stability_norm(q, B_c), engine::nominal_loop_stable(q, B_c)}});
    std::vector<HoldPoint>& hold_points = report.sweep_by_hold.emplace_back();
    for (const TransparencyPoint& point : report.sweep) {
      hold_points.push_back({engine::robust_stability_norm(q, point.controller_damping),
                        engine::nominal_loop_stable(q, point.controller_damping)});
    }
  }
  if (!report.optimum.robustly_stable) {
    for (const TransparencyPoint& point : report.sweep) {
      if (point.robust() && (!report.best_robust || point.transparency_index < report.best_robust->transparency_index)) {
        report.best_robust = point;
      }
    }
  }
  return report;
}

namespace {

/// The hold model's name as a CSV column suffix: "second-order" -> "second_order".
std::string column_suffix(engine::HoldModel hold) {
  std::string name = engine::hold_model_name(hold);
  for (char& c : name) {
    if (c == '-') c = '_';
  }
  return name;
}

const char* verdict(const HoldPoint& point) {
  if (!point.nominal_stable) return "nominal loop UNSTABLE";
  return point.robust() ? "robustly stable" : "NOT robustly stable";
}

/// ZOH(s) of each hold model as the report prints it.
const char* hold_formula(engine::HoldModel hold) {
  switch (hold) {
    case engine::HoldModel::kSecondOrder: return "ω_N²/(s² + 2ζω_N s + ω_N²), ζ = π/4";
    case engine::HoldModel::kHalfPeriodDelay: return "e^(−sT/2)";
    case engine::HoldModel::kPade: return "(1 − sT/4)/(1 + sT/4)";
    case engine::HoldModel::kExact: return "(1 − e^(−sT))/(sT)";
  }
  return "?";
}

}  // namespace

void write_csv(const TransparencyReport& report, std::ostream& out) {
  out << "controller_damping_n_s_m,transparency_index,robust_norm,robust_norm_db,nominal_stable,robust";
  for (const HoldVerdict& verdict : report.holds) {
    out << ",robust_norm_db_" << column_suffix(verdict.hold) << ",robust_" << column_suffix(verdict.hold);
  }
  out << '\n';
  for (std::size_t j = 0; j < report.sweep.size(); ++j) {
    const TransparencyPoint& point = report.sweep[j];
    out << point.controller_damping << ',' << point.transparency_index << ',' << point.robust_norm
        << ',' << engine::to_db(point.robust_norm) << ',' << point.nominal_stable << ','
        << point.robust();
    for (const std::vector<HoldPoint>& points : report.sweep_by_hold) {
      out << ',' << engine::to_db(points[j].robust_norm) << ',' << points[j].robust();
    }
    out << '\n';
  }
}

void write_markdown(const engine::WallDesignParams& p, const TransparencyReport& report,
                    std::ostream& out) {
  const engine::OptimalWallDesign& o = report.optimum;
  out << "# Transparency and robust stability (Eom et al., eqs. 11 and 17)\n\n"
      << "Device m = " << p.mass << " kg, b = " << p.damping << " N·s/m; wall K = " << p.wall_stiffness
      << " N/m, B = " << p.wall_damping << " N·s/m; T = " << p.sample_period
      << " s; w1 cut-off " << p.weight_cutoff << " rad/s; α = " << p.mass_uncertainty
      << ", β = " << p.damping_uncertainty << "; hold model " << engine::hold_model_name(p.hold)
      << ", ZOH(s) = " << hold_formula(p.hold) << ".\n\n"
      << "Optimum B_c = " << o.controller_damping << " N·s/m: J = " << o.transparency_index
      << ", ‖L‖∞ = " << engine::to_db(o.robust_stability_norm) << " dB — "
      << (o.robustly_stable ? "robustly stable" : (o.nominal_loop_stable ? "NOT robustly stable"
                                                                        : "nominal loop UNSTABLE"))
      << ".\n\n";
  if (report.best_robust) {
    out << "Best robustly stable B_c on the sweep: " << report.best_robust->controller_damping
        << " N·s/m (J = " << report.best_robust->transparency_index
        << ", ‖L‖∞ = " << engine::to_db(report.best_robust->robust_norm) << " dB).\n\n";
  } else if (!o.robustly_stable) {
    out << "No swept B_c is robustly stable.\n\n";
  }
  if (report.optimum_at_edge) {
    out << "The optimum is at the sweep's upper end (" << report.swept_to
        << " N·s/m): J still falls beyond it.\n\n";
  }
  out << "## Each hold model's verdict\n\n"
      << "The document gives the hold only as a low-pass with unity DC gain and 90° lag at Nyquist; "
         "the verdict near the optimum depends on the model.\n\n"
      << "| hold | ZOH(s) | its optimum B_c [N·s/m] | J | ‖L‖∞ [dB] | verdict | ‖L‖∞ at B_c = "
      << o.controller_damping << " [dB] | verdict there |\n|---|---|---|---|---|---|---|---|\n";
  for (const HoldVerdict& h : report.holds) {
    const HoldPoint own{h.own_optimum.robust_stability_norm, h.own_optimum.nominal_loop_stable};
    out << "| " << engine::hold_model_name(h.hold) << " | " << hold_formula(h.hold) << " | "
        << h.own_optimum.controller_damping << " | " << h.own_optimum.transparency_index << " | "
        << engine::to_db(own.robust_norm) << " | " << verdict(own) << " | "
        << engine::to_db(h.at_report_optimum.robust_norm) << " | " << verdict(h.at_report_optimum)
        << " |\n";
  }
  out << "\n## The sweep (" << engine::hold_model_name(p.hold) << " hold)\n\n";
  out << "| B_c [N·s/m] | J | ‖L‖∞ [dB] | nominal loop | robust |\n|---|---|---|---|---|\n";
  for (const TransparencyPoint& point : report.sweep) {
    out << "| " << point.controller_damping << " | " << point.transparency_index << " | "
        << engine::to_db(point.robust_norm) << " | " << (point.nominal_stable ? "stable" : "UNSTABLE")
        << " | " << (point.robust() ? "yes" : "no") << " |\n";
  }
}

}  // namespace haptic::lab
