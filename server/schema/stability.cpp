#include "schema/stability.hpp"

#include <fmt/format.h>

#include "engine/analysis/wall_design.hpp"
#include "engine/scene/impedance.hpp"

namespace haptic::schema {

namespace {

/// The units a report's warning speaks in: a contact's, or an orientation spring's.
struct Units {
  const char* stiffness;  // "N/m"
  const char* damping;    // "N*s/m"
  const char* outcome;    // what to expect past the margin
};
constexpr Units kTranslational{"N/m", "N*s/m",
                               "expect the contact to oscillate unless the passivity controller damps it"};
constexpr Units kRotational{"N*m/rad", "N*m*s/rad",
                            "expect the handle to oscillate (the passivity controller watches contact "
                            "forces, not torques): lower the stiffness or add damping"};

/// Colgate's bound, the device's model and, where the device is known, the sampled margin (and
/// a warning past it) of the law (K, B, M) on the mass-damper `device` at period_s.
void add_margin(v1::StabilityReport& report, const engine::ImpedanceParams& law_params,
                engine::ContactLaw law, const DeviceMassDamper& device, double period_s,
                const Units& units) {
  report.set_colgate_min_damping(engine::colgate_bound(law_params.stiffness, law_params.damping, period_s));
  report.set_device_mass(device.mass);
  report.set_device_damping(device.damping);
  report.set_passive(device.damping > report.colgate_min_damping());
  report.set_device_known(device.mass > 0.0);
  if (!report.device_known() || law_params.stiffness <= 0.0) return;
  const engine::SampledWallMargin margin = engine::sampled_wall_margin(
      law_params, engine::discretization_of(law),
      engine::MassDamperDevice{device.mass, device.damping, device.actuator_lag_s},
      period_s, device.delay_s > 0.0 ? device.delay_s / period_s : 0.0);
  report.set_stable(margin.stable);
  report.set_max_stable_stiffness(margin.max_stable_stiffness);
  report.set_max_pole_magnitude(margin.max_pole_magnitude);
  if (!margin.stable) {
    report.set_warning(fmt::format(
        "not stable on this device: K = {:g} {} with B = {:g} {} at {:g} Hz exceeds the largest "
        "stable stiffness, {:g} {} (closed-loop pole {:.4f}); {}",
        law_params.stiffness, units.stiffness, law_params.damping, units.damping, 1.0 / period_s,
        margin.max_stable_stiffness, units.stiffness, margin.max_pole_magnitude, units.outcome));
  }
}

}  // namespace

v1::StabilityReport stability_report(const engine::ObjectSpec& spec, const DeviceMassDamper& device,
                                     double period_s, bool optimal_damping, bool virtual_coupling) {
  v1::StabilityReport report;
  if (optimal_damping && device.mass > 0.0) {
    engine::WallDesignParams design;
    design.mass = device.mass;
    design.damping = device.damping;
    design.wall_stiffness = spec.stiffness;
    design.wall_damping = spec.damping;
    design.sample_period = period_s;
    report.set_chosen_damping(spec.damping);
    report.set_robustly_stable(engine::robust_stability_norm(design, spec.damping) <= 1.0);
  }
  if (virtual_coupling) {
    report.set_chosen_stiffness(spec.stiffness);
    report.set_chosen_damping(spec.damping);
  }
  add_margin(report, engine::ImpedanceParams{spec.stiffness, spec.damping, spec.impedance_mass},
             spec.law, device, period_s, kTranslational);
  return report;
}

v1::StabilityReport stability_report(const engine::OrientationSpringSpec& spec,
                                     const DeviceMassDamper& handle, double period_s) {
  v1::StabilityReport report;
  add_margin(report, engine::ImpedanceParams{spec.stiffness, spec.damping, 0.0}, spec.law, handle,
             period_s, kRotational);
  return report;
}

}  // namespace haptic::schema
