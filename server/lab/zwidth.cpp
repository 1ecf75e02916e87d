#include "lab/zwidth.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <deque>
#include <limits>
#include <stdexcept>
#include <string>

#include "engine/device/point_mass_plant.hpp"
#include "lab/device_model.hpp"

namespace haptic::lab {
namespace {

void require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument(message);
}

/// (c): the wall in permanent contact (it may pull, as the linear theory assumes), the device
/// stepped exactly, the hand as a continuous spring-damper-mass; stable if the last half second's
/// largest excursion is below the 1 mm the run starts from: a verdict by growth (the amplitude
/// after 3 s against the amplitude at the start), which sees a slow ring-up — a pole at 1.001 a
/// tick grows 20× in 3 s at 1 kHz — and places the boundary within 0.5 % of the eigenvalues'.
bool simulate(const ZWidthParams& p, double K, double B) {
  engine::PointMassParams device;
  device.mass = p.mass;
  device.damping = p.damping;
  device.workspace_min = {-1e3, -1e3, -1e3};
  device.workspace_max = {1e3, 1e3, 1e3};
  engine::PointMassPlant plant(device, {{0.0, 0.0, -0.001}, {}});
  plant.set_added_mass(p.hand_mass);
  engine::ImpedanceFilter wall(engine::ImpedanceParams{K, B, 0.0}, p.discretization, p.period);
  wall.reset(0.001);
  std::deque<double> pending(p.delay_ticks, 0.0);
  const auto ticks = static_cast<int>(std::llround(p.seconds / p.period));
  const int tail = static_cast<int>(std::llround(0.5 / p.period));
  double largest = 0.0;
  for (int k = 0; k < ticks; ++k) {
    const double d = -plant.state().p_WT.z;  // penetration. Unit: m.
    double force = wall.update(d);           // > 0 pushes out (+z)
    if (p.delay_ticks > 0) {
      pending.push_back(force);
      force = pending.front();
      pending.pop_front();
    }
    plant.step({0.0, 0.0, force}, p.period, [&](const engine::Vec3& x, const engine::Vec3& v) {
      return engine::Vec3{0.0, 0.0, -p.hand_stiffness * (x.z + 0.001) - p.hand_damping * v.z};
    });
    const double z = plant.state().p_WT.z;
    if (!std::isfinite(z) || std::abs(z) > 1.0) return false;  // diverged
    if (k >= ticks - tail) largest = std::max(largest, std::abs(z));
  }
  return largest < 0.001;
}

/// The largest K whose simulated run settles, by bisection to 1e-6 relative, starting from a
/// bracket around `guess` (the eigenvalues' K'); 0 when even guess / 1e3 grows, inf when 1e3 guess
/// settles.
double simulated_boundary(const ZWidthParams& p, double B, double guess) {
  if (!std::isfinite(guess) || guess <= 0.0) guess = 1.0;
  double lo = guess, hi = guess;
  while (!simulate(p, lo, B)) {
    lo /= 2.0;
    if (lo < guess * 1e-3) return 0.0;
  }
  hi = std::max(hi, lo * 2.0);
  while (simulate(p, hi, B)) {
    lo = hi;
    hi *= 2.0;
    if (hi > guess * 1e3) return std::numeric_limits<double>::infinity();
  }
  while (hi - lo > 1e-6 * hi) {
    const double mid = 0.5 * (lo + hi);
    (simulate(p, mid, B) ? lo : hi) = mid;
  }
  return lo;
}

}  // namespace

ZWidthReport zwidth(const ZWidthParams& p) {
  require_device_model(p.mass, p.damping, p.period);
  require(p.delay_ticks <= 100, "delay: must be 0 to 100 ticks");
  require(p.hand_mass >= 0.0 && p.hand_stiffness >= 0.0 && p.hand_damping >= 0.0,
          "hand: mass, stiffness and damping must be >= 0");
  require(p.k_min > 0.0 && p.k_max > p.k_min && p.b_max > 0.0, "grid: needs 0 < k_min < k_max and b_max > 0");
  require(p.k_points >= 2 && p.b_points >= 2 && p.k_points * p.b_points <= 10000,
          "grid: needs at least 2 x 2 and at most 10000 cells");
  require(p.seconds > 0.5 && p.seconds <= 60.0, "seconds: must be in (0.5, 60]");
  ZWidthReport report;
  report.theory_applies = p.hand_mass == 0.0 && p.hand_stiffness == 0.0 && p.hand_damping == 0.0;
  report.passivity_applies = p.delay_ticks == 0;
  const engine::MassDamperDevice device{p.mass, p.damping};
  for (int i = 0; i < p.k_points; ++i) {
    const double K = p.k_min * std::pow(p.k_max / p.k_min, static_cast<double>(i) / (p.k_points - 1));
    for (int j = 0; j < p.b_points; ++j) {
      const double B = j == 0 ? 0.0 : p.b_max * std::pow(1e-3, static_cast<double>(p.b_points - 1 - j) / (p.b_points - 2 > 0 ? p.b_points - 2 : 1));
      ZWidthCell cell{K, B, report.passivity_applies && p.damping > engine::colgate_bound(K, B, p.period),
                      false, false};
      cell.eigen_stable = engine::sampled_wall_margin(engine::ImpedanceParams{K, B, 0.0}, p.discretization,
                                                      device, p.period, p.delay_ticks)
                              .stable;
      cell.simulation_stable = simulate(p, K, B);
      report.cells.push_back(cell);
    }
  }
  for (int j = 0; j < p.b_points; ++j) {
    const double B = report.cells[static_cast<std::size_t>(j)].damping;
    ZWidthBoundary edge;
    edge.damping = B;
    edge.k_max_colgate = report.passivity_applies
                             ? std::max(0.0, 2.0 * (p.damping - std::abs(B)) / p.period)
                             : std::numeric_limits<double>::quiet_NaN();
    edge.k_max_eigen = engine::sampled_wall_margin(engine::ImpedanceParams{1.0, B, 0.0}, p.discretization,
                                                   device, p.period, p.delay_ticks)
                           .max_stable_stiffness;
    edge.k_max_simulation = simulated_boundary(p, B, edge.k_max_eigen);
    report.boundary.push_back(edge);
  }
  return report;
}

void write_csv(const ZWidthReport& report, std::ostream& out) {
  out << "stiffness_n_m,damping_n_s_m,passive,eigen_stable,simulation_stable\n";
  for (const ZWidthCell& c : report.cells) {
    out << c.stiffness << ',' << c.damping << ',';
    if (report.passivity_applies) {
      out << c.passive;
    } else {
      out << "n/a";
    }
    out << ',' << c.eigen_stable << ',' << c.simulation_stable << '\n';
  }
}

void write_markdown(const ZWidthParams& p, const ZWidthReport& report, std::ostream& out) {
  std::size_t agree = 0, passive_not_stable = 0;
  for (const ZWidthCell& c : report.cells) {
    if (c.eigen_stable == c.simulation_stable) ++agree;
    if (c.passive && !c.eigen_stable) ++passive_not_stable;
  }
  out << "# Z-width\n\nDevice m = " << p.mass << " kg, b = " << p.damping << " N·s/m, T = " << p.period
      << " s, delay " << p.delay_ticks << " ticks; hand m = " << p.hand_mass << " kg, k = " << p.hand_stiffness
      << " N/m, b = " << p.hand_damping << " N·s/m.\n\n"
      << "Eigenvalues and simulation agree on " << agree << " of " << report.cells.size() << " cells";
  if (!report.theory_applies) {
    out << " — the eigenvalue test does not model the hand, so disagreement is expected here";
  }
  if (p.delay_ticks > 0) {
    out << " (both model the " << p.delay_ticks << "-tick delay: the eigenvalues as z^-" << p.delay_ticks
        << " on the wall's force)";
  }
  if (report.passivity_applies) {
    out << ". Passive by Colgate's bound but unstable by eigenvalues: " << passive_not_stable
        << " (the bound is sufficient, so this should be 0).\n\n";
  } else {
    out << ". Colgate's bound, b > KT/2 + |B|, assumes no delay: not applied here (no cell is "
           "marked passive).\n\n";
  }
  out
      << "Map (rows K, columns B): P passive (and stable), S stable, s stable in simulation only, "
         "e stable by eigenvalues only, . unstable.\n\n```\n";
  const std::size_t columns = static_cast<std::size_t>(p.b_points);
  for (std::size_t row = 0; row * columns < report.cells.size(); ++row) {
    char line[32];
    std::snprintf(line, sizeof line, "K %9.3g  ", report.cells[row * columns].stiffness);
    out << line;
    for (std::size_t col = 0; col < columns; ++col) {
      const ZWidthCell& c = report.cells[row * columns + col];
      out << (c.passive ? 'P' : c.eigen_stable && c.simulation_stable ? 'S' : c.simulation_stable ? 's' : c.eigen_stable ? 'e' : '.');
    }
    out << '\n';
  }
  out << "```\n\nBoundary: the largest stiffness K each test allows at each damping B (the eigenvalues' by "
         "bisection to 1e-9, the simulation's to 1e-6, relative):\n\n"
      << "| B (N·s/m) | Colgate 2(b − |B|)/T (N/m) | eigenvalues (N/m) | simulation (N/m) |\n"
      << "|---:|---:|---:|---:|\n";
  for (const ZWidthBoundary& edge : report.boundary) {
    char line[160];
    if (std::isnan(edge.k_max_colgate)) {
      std::snprintf(line, sizeof line, "| %.6g | n/a (delay) | %.7g | %.7g |\n", edge.damping,
                    edge.k_max_eigen, edge.k_max_simulation);
    } else {
      std::snprintf(line, sizeof line, "| %.6g | %.7g | %.7g | %.7g |\n", edge.damping, edge.k_max_colgate,
                    edge.k_max_eigen, edge.k_max_simulation);
    }
    out << line;
  }
}

}  // namespace haptic::lab
