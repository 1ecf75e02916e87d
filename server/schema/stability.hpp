#pragma once
// What the server can say about an object's impedance on a device (docs/scene.md): Colgate's
// passivity bound b > K T / 2 + |B| against the device's own damping, and the sampled stability
// margin of the wall on the device modelled as a mass-damper behind a zero-order hold; with the
// design choices an impedance may ask for (001's transparency-optimal damping, a passive virtual
// coupling), what was chosen.

#include "engine/scene/scene_spec.hpp"
#include "haptic/v1/service.pb.h"

namespace haptic::schema {

/// A device's tool point as a mass-damper (DeviceDescription::apparent_*); mass 0: unknown.
struct DeviceMassDamper {
  double mass = 0.0;     // Unit: kg.
  double damping = 0.0;  // Unit: N*s/m.
  /// The delay between a command and its effect beyond a perfect loop's half tick, where known
  /// (a measured profile): the margin counts it. Unit: s.
  double delay_s = 0.0;
  /// The force's first-order lag behind the command, where known: the margin samples it. Unit: s.
  double actuator_lag_s = 0.0;
};

/// The report for `spec` (already converted: its damping or gains are the chosen ones) at loop
/// period `period_s` (s). The VELOCITY law uses the device's measured velocity; the margin models
/// it by the backward difference, the discrete law closest to it. A contact past the margin gets
/// a warning saying by how much.
v1::StabilityReport stability_report(const engine::ObjectSpec& spec, const DeviceMassDamper& device,
                                     double period_s, bool optimal_damping = false,
                                     bool virtual_coupling = false);

/// The report for an orientation spring on a device's handle, modelled about each axis as an
/// inertia-damper (DeviceDescription::apparent_inertia, apparent_rotational_damping; inertia 0:
/// unknown) — the same analysis, with the report's "mass" an inertia (kg·m²), its stiffnesses in
/// N·m/rad and its dampings in N·m·s/rad.
v1::StabilityReport stability_report(const engine::OrientationSpringSpec& spec,
                                     const DeviceMassDamper& handle, double period_s);

}  // namespace haptic::schema
