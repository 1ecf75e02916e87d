#include "schema/stability.hpp"

#include <fmt/format.h>

#include "engine/analysis/wall_design.hpp"
#include "engine/scene/impedance.hpp"

namespace haptic::schema {

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
  report.set_colgate_min_damping(engine::colgate_bound(spec.stiffness, spec.damping, period_s));
  report.set_device_mass(device.mass);
  report.set_device_damping(device.damping);
  report.set_passive(device.damping > report.colgate_min_damping());
  report.set_device_known(device.mass > 0.0);
  if (!report.device_known() || spec.stiffness <= 0.0) return report;
  const engine::ImpedanceDiscretization discretization = engine::discretization_of(spec.law);
  const engine::SampledWallMargin margin = engine::sampled_wall_margin(
      engine::ImpedanceParams{spec.stiffness, spec.damping, spec.impedance_mass}, discretization,
      engine::MassDamperDevice{device.mass, device.damping}, period_s);
  report.set_stable(margin.stable);
  report.set_max_stable_stiffness(margin.max_stable_stiffness);
  report.set_max_pole_magnitude(margin.max_pole_magnitude);
  if (!margin.stable) {
    report.set_warning(fmt::format(
        "not stable on this device: K = {:g} N/m with B = {:g} N*s/m at {:g} Hz exceeds the largest "
        "stable stiffness, {:g} N/m (closed-loop pole {:.4f}); expect the contact to oscillate "
        "unless the passivity controller damps it",
        spec.stiffness, spec.damping, 1.0 / period_s, margin.max_stable_stiffness,
        margin.max_pole_magnitude));
  }
  return report;
}

}  // namespace haptic::schema
