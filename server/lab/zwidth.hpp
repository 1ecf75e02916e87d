#pragma once
// haptic-lab's `zwidth`: the region of wall stiffness K and damping B a device can render
// (Colgate & Brown's Z-width), by three tests on a grid:
//   (a) passive by Colgate's bound, b > K T/2 + |B| (Colgate & Schenkel; Madill eq. 2.6);
//   (b) stable by the exact eigenvalues of the sampled loop — the device as a mass-damper under a
//       zero-order hold, the wall's discrete law, and the delay as z^−d on the wall's force
//       (engine/scene/impedance, sampled_wall_margin);
//   (c) stable in simulation: the same device and law, stepped exactly, from a 1 mm penetration,
//       with a chosen operator's hand (mass, stiffness, damping) holding the tool.
// (a) is sufficient, not necessary, so it lies inside (b), and assumes no delay: with one it is not
// applied ("n/a"). (b) and (c) agree where the theory's assumptions hold (linear wall in permanent
// contact, no hand).

#include <cstdint>
#include <ostream>
#include <vector>

#include "engine/scene/impedance.hpp"

namespace haptic::lab {

struct ZWidthParams {
  double mass = 0.01;      // Device mass m. Unit: kg. > 0.
  double damping = 0.022;  // Device damping b. Unit: N·s/m. >= 0.
  double period = 1e-3;    // T. Unit: s. > 0.
  engine::ImpedanceDiscretization discretization = engine::ImpedanceDiscretization::kBackwardDifference;
  std::uint32_t delay_ticks = 0;  // Extra ticks between the reading and the force it causes.
  double hand_mass = 0.0;         // The operator's hand holding the tool. Unit: kg.
  double hand_stiffness = 0.0;    // Unit: N/m.
  double hand_damping = 0.0;      // Unit: N·s/m.
  double k_min = 1.0, k_max = 1e5;  // Unit: N/m. Log-spaced.
  double b_max = 10.0;              // Unit: N·s/m. B from 0, then log-spaced up to b_max.
  int k_points = 16, b_points = 12;
  double seconds = 3.0;             // Simulated time per cell. Unit: s.
};

struct ZWidthCell {
  double stiffness, damping;
  bool passive, eigen_stable, simulation_stable;
};

/// The boundary at one damping B: the largest stiffness each test allows. Unit: N/m.
struct ZWidthBoundary {
  double damping = 0.0;           // B. Unit: N·s/m.
  double k_max_colgate = 0.0;     // 2(b − |B|)/T; 0 when b ≤ |B|; NaN with a delay (not applied)
  double k_max_eigen = 0.0;       // the sampled loop's K' (bisection to 1e-9 relative); inf: none
  double k_max_simulation = 0.0;  // bisection to 1e-6 relative between a settling and a growing run
};

struct ZWidthReport {
  std::vector<ZWidthCell> cells;
  std::vector<ZWidthBoundary> boundary;  // one per grid column (B)
  bool theory_applies = true;    // false with a hand: (b) does not model one
  bool passivity_applies = true; // false with a delay: Colgate's bound assumes none (cells' passive false)
};

/// Throws std::invalid_argument naming a bad parameter.
ZWidthReport zwidth(const ZWidthParams& params);

/// CSV: stiffness_n_m, damping_n_s_m, passive ("n/a" with a delay), eigen_stable, simulation_stable.
void write_csv(const ZWidthReport& report, std::ostream& out);
/// Markdown: the parameters, how often the tests agree, and why where they do not, and a map.
void write_markdown(const ZWidthParams& params, const ZWidthReport& report, std::ostream& out);

}  // namespace haptic::lab
