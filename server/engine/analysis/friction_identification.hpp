#pragma once
// Friction identification from proportional-control step responses (Madill 1998, §5.3.2,
// L2549–2660, Fig. 5.6, Table 5.4). Offline analysis: nothing here runs on the loop.
//
// Under u = K (r − y) the joint P(s) = 1/(J s² + B s) with Coulomb friction f sgn(ẏ) moves with
// ẏ > 0 up to its first peak, so the friction is the constant f there and the loop is linear with
// the reference r̄ = r − f/K (L2573). Hence, for steps r_i:
//   y_p = α (r − f/K),   α = 1 + exp(−ζπ / √(1 − ζ²))                (L2603–2611)
//   t_p = π / (ω_n √(1 − ζ²)),  ω_n = √(K/J),  ζ = B / (2√(KJ))      (eq. 5.7, L2589–2599)
// A regression of y_p on r gives the slope α and the r-intercept r0; then
//   f = K r0                                                          (eq. 5.6)
//   β = −ln(α − 1),  ζ = β / √(π² + β²)                               (eq. 5.8)
//   ω_n = π / (t_p √(1 − ζ²))                                         (eq. 5.9)
//   J = K / ω_n²,  B = 2ζ√(KJ)                                        (L2643–2649)
// The thesis reads t_p as the average over the steps (L2641).

#include <cstddef>
#include <span>

#include "engine/core/integrator.hpp"
#include "engine/device/single_joint_plant.hpp"

namespace haptic::engine {

/// One step experiment's first peak.
struct StepPeak {
  double reference = 0.0;  // r. Unit: rad.
  double peak = 0.0;       // y_p, the first maximum of y. Unit: rad.
  double peak_time = 0.0;  // t_p, from the step. Unit: s.
};

/// How the step experiments are run.
struct StepExperimentSettings {
  double gain = 3.7;  // K of u = K (r − y). Unit: N·m/rad. > 0. Table 5.4's rows imply
                      // K ≈ 3.6–3.74 (K = J ω_n² and K = f / r0, inferred; not printed).
  /// Period of the P controller. 0: an analog loop (u re-evaluated at every integration stage),
  /// which is what eqs. 5.6–5.9 assume. > 0: a sampled loop with a zero-order hold, y sampled at
  /// the same period (sample_period is then unused); the hold's delay of about T/2 acts as a
  /// negative damping ≈ K T/2 (first order in T; inferred, not in the thesis), so the identified
  /// B comes out low by about that much. Unit: s. >= 0.
  double control_period = 0.0;
  /// Analog loop only: the period at which y is sampled for the peak (and the plant stepped).
  /// Either way y_p is the vertex of a parabola through the largest sample and its two
  /// neighbours, and t_p where the simulated rate, extrapolated from the last two samples
  /// before it stops, reaches zero.
  /// Unit: s. > 0.
  double sample_period = 1e-3;
  double max_duration = 10.0;  // Give up looking for the peak after this long. Unit: s. > 0.
  IntegrationSettings integration{Integrator::kRk4, 10};
};

/// What eqs. 5.6–5.9 recover.
struct FrictionIdentification {
  double slope = 0.0;        // α, of y_p against r. Dimensionless.
  double r_intercept = 0.0;  // r0 = f/K. Unit: rad.
  double peak_time = 0.0;    // t_p (mean). Unit: s.
  double natural_frequency = 0.0;  // ω_n. Unit: rad/s.
  double damping_ratio = 0.0;      // ζ. Dimensionless.
  double inertia = 0.0;      // J. Unit: kg·m².
  double damping = 0.0;      // B. Unit: N·m·s/rad.
  double coulomb = 0.0;      // f. Unit: N·m.
};

/// The first peak of the closed loop's response to a step r (rad) from rest at y = 0. Returns a
/// peak of NaN when none is found within max_duration (e.g. r ≤ f/K: the joint never moves).
StepPeak simulate_step_peak(const SingleJointParams& joint, double reference,
                            const StepExperimentSettings& settings);

/// Eqs. 5.6–5.9 from a slope α (must be in (1, 2)), an r-intercept r0 (rad), a time to peak t_p
/// (s) and the loop gain K (N·m/rad).
FrictionIdentification identify_from_line(double slope, double r_intercept, double peak_time,
                                          double gain);

/// Least-squares line y_p = α r + c through the peaks (at least two distinct r), r0 = −c/α, t_p
/// their mean, then identify_from_line.
FrictionIdentification identify_from_peaks(std::span<const StepPeak> peaks, double gain);

/// The forward direction, for checking a table row: ω_n, ζ, α, t_p and r0 of a joint (J, B, f)
/// under gain K (eq. 5.7, L2599–2611). Fills every field.
FrictionIdentification predicted_identification(double inertia, double damping, double coulomb,
                                                double gain);

/// The whole experiment: one simulated step per reference (writes peaks[i] for references[i];
/// the spans have the same size), then identify_from_peaks.
FrictionIdentification identify_joint(const SingleJointParams& joint,
                                      std::span<const double> references,
                                      const StepExperimentSettings& settings,
                                      std::span<StepPeak> peaks);

}  // namespace haptic::engine
