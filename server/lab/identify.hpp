#pragma once
// `haptic-lab identify`: a device port's axis identified from a run on the device itself
// (docs/identification.md). The configuration's device runs in lockstep with a multisine force
// along one axis of W, played through the loop as a command is (runtime/excitation_stage: before
// the force guard), and the recorded command and position are fitted
// (engine/analysis/system_identification): apparent mass, damping, Coulomb friction in each
// direction, delay, the sensor's noise and quantization, each with its 95 % interval. Beside
// them, where the configuration knows one, the device's own model (lab/device_model) to compare.

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "engine/analysis/system_identification.hpp"
#include "engine/core/vec3.hpp"
#include "haptic/v1/config.pb.h"
#include "lab/device_model.hpp"
#include "lab/lab_run.hpp"
#include "runtime/excitation_stage.hpp"

namespace haptic::lab {

struct IdentifyParams {
  std::uint32_t port = 0;  // the device port excited
  int axis = 0;            // of W: 0 x, 1 y, 2 z
  /// Excite and measure along the direction the tool moves when pushed along `axis` (a short
  /// push by the simulated operator, before the run) instead of the axis itself: for a device
  /// whose tool moves on a curve (000's DC motor: its link's tangent), where along an axis of W
  /// the fit sees the mass divided by the direction's cosine squared.
  bool along_motion = false;
  /// The multisine; its sample_period_s is the configuration's loop period (set by identify).
  engine::MultisineParams signal;
  /// Also fit a first-order lag between the command and the force, up to this (an amplifier's
  /// or a motor's time constant: 004's motors, 8.8 ms). Unit: s. 0: none (a pure delay only).
  double max_lag_s = 0.0;
  /// At the excited harmonics (the default), or in time over the stretches where the axis moved:
  /// for a device that friction holds still through part of each period (004's joystick).
  engine::FitMethod fit_method = engine::FitMethod::kHarmonics;
  runtime::ExcitationLimits limits;
  /// A spring and damper about the start added to the excitation (none by default): for a device
  /// that stick and slip walks away from where it started (runtime/excitation_stage).
  runtime::ExcitationCentering centering;
  /// How the device's time passes (lab_run's DeviceTime: its own clock stepped once a tick, or
  /// the ticks paced in real time for hardware): every run of the identification and of its
  /// Z-width check passes it on.
  DeviceTime device_time;
};

struct IdentifyResult {
  engine::AxisIdentification fit;
  engine::Vec3 start_position;   // the tool's position at the first tick. Unit: m.
  engine::Vec3 direction;        // excited and measured along, a unit vector in W
  double duration_s = 0.0;       // the run. Unit: s.
  double period_s = 0.0;         // the loop's. Unit: s.
  /// The device's own mass-damper along the axis, where the configuration gives one (its
  /// description, or the Jacobian at the initial pose): mass (kg), damping (N·s/m).
  std::optional<double> model_mass, model_damping;
  std::string model_method;      // "description", "jacobian" or why there is none
  /// Paced in real time: the excitation's ticks that started more than half a period late (a
  /// late tick holds its force longer than the fit assumes).
  std::uint64_t late_ticks = 0;
  /// The port's force limit, its guard's (the device's description). Unit: N.
  double max_force_n = 0.0;
};

/// Runs the excitation on `config`'s device (`source` names the configuration in messages) and
/// fits it. Throws std::invalid_argument naming what is wrong: a parameter, a stop (the tool left
/// its box or went too fast: lower the amplitude or raise f_min), or a fit that failed.
IdentifyResult identify(const v1::ServerConfig& config, const IdentifyParams& params, const std::string& source);

/// The result as a markdown report: the estimates with their intervals, the model's figures and
/// the errors against them, the delay beyond a perfect loop's, noise, quantization, residual.
std::string identify_report(const IdentifyResult& result, const IdentifyParams& params, const std::string& source);

/// A driver port's profile (DriverConfig.profile) from identifications along x, y and z in turn
/// (`params` as given but for the axis): each axis's mass and damping, and the largest of the
/// three delays beyond the hold and of the three lags (0 unless max_lag_s). Throws what identify
/// throws, or std::invalid_argument when an axis is no mass-damper (a mass not positive, a
/// negative damping).
v1::DeviceProfile identify_profile(const v1::ServerConfig& config, const IdentifyParams& params, const std::string& source);

/// One damping's Z-width, three ways (N/m): predicted by the sampled wall's analysis
/// (engine::sampled_wall_margin, BACKWARD_DIFFERENCE) from the identified mass, damping and delay
/// beyond the hold (fractional ticks); measured on the device itself along the identified
/// direction (lab/device_zwidth); and predicted from the device's own description, where it has one.
///
/// A device that friction holds (the identified friction beyond its interval is a twentieth of
/// the excitation's peak or more) has no linear Z-width: its friction stops small rings and lets
/// large ones grow, so its boundary depends on how hard the wall is pressed. Its walls are pressed
/// with 2.5 times the identified friction, a run that ends still has settled, and the prediction
/// is the same walls run on the identified model itself: a simulated point mass with the
/// identified mass, damping, friction and lag, a sensor of the identified step with the noise
/// beyond the step's own (or the identified noise, where no step was found), and the port's force
/// limit (`friction_model`; the linear analysis's figure is kept in `linear`).
struct ZWidthCheck {
  double damping = 0.0;  // B. Unit: N·s/m.
  double predicted = 0.0, measured = 0.0;
  std::optional<double> described;
  bool friction_model = false;  // predicted by walls on the identified model with its friction
  double linear = 0.0;          // the sampled analysis's figure, without the friction. Unit: N/m.
  /// Walls above the measured figure that settled again (device_settles_above), looked for on a
  /// device read through noise or a step, or held by friction. Unit: N/m. Empty: none.
  std::vector<double> settles_above;
  /// Each wall's runs, on the device and on the model (DeviceWallParams::runs): more than one
  /// where friction holds the device, a step was found and the device's noise can be drawn anew
  /// (16: on the device with its noise drawn anew, on the model from 16 places in a count).
  int runs = 1;
};

/// The check at each of `dampings` (the device's own first ringing wall, walked up to from a guess
/// of three times the prediction: device_zwidth_boundary). `progress` after each damping's
/// boundary: paced in real time each takes a minute or so (some 17 walls of 3 s, four more on a
/// device with a sensor's noise or step, or friction). A simulated device that friction holds,
/// whose readings lie on a lattice and whose sensor has noise to draw anew runs each wall 16
/// times (ZWidthCheck::runs), on itself and on the model: in lockstep, some 10 s a damping for
/// 003's five-bar.
std::vector<ZWidthCheck> check_zwidth(const v1::ServerConfig& config, const IdentifyParams& params,
                                      const IdentifyResult& result, const std::vector<double>& dampings,
                                      const std::function<void(std::size_t done, std::size_t total)>& progress = {});

/// The checks as a markdown table, with each prediction's error against the measurement.
std::string zwidth_report(const std::vector<ZWidthCheck>& checks);

/// One identification of a sweep over the excitation's length and amplitude (docs/numerics.md,
/// "Identification"): its errors against the device's own model and its intervals, relative.
struct IdentifySweepRow {
  double amplitude_n = 0.0;
  std::size_t periods = 0;
  double excitation_s = 0.0;   // the whole run: ramps, settling and fitted periods. Unit: s.
  double cpu_s = 0.0;          // the run's simulation and the fit, on this machine. Unit: s.
  /// |identified − model| / model, and the 95 % intervals' halves over the model; the damping's
  /// NaN where the model has none (004's joystick: its figures below are then the measure).
  double mass_error = 0.0, damping_error = 0.0;
  double mass_half_width = 0.0, damping_half_width = 0.0;
  double damping = 0.0, damping_half_width_abs = 0.0;  // the estimate and its interval. Unit: N·s/m.
  double delay_half_width_s = 0.0;                     // Unit: s.
};

/// identify at every pair of `periods` and `amplitudes_n` (the rest of `params` as given), on a
/// device whose configuration gives its own model. Throws what identify throws, or
/// std::invalid_argument when the device gives no model to measure the errors against (no mass,
/// or no damping figure).
std::vector<IdentifySweepRow> identify_sweep(const v1::ServerConfig& config, const IdentifyParams& params,
                                             const std::vector<std::size_t>& periods,
                                             const std::vector<double>& amplitudes_n, const std::string& source,
                                             const std::function<void(std::size_t done, std::size_t total)>& progress = {});

/// The sweep as CSV, one row per run, for plot_lab.py's identify-sweep chart.
std::string identify_sweep_csv(const std::vector<IdentifySweepRow>& rows);

/// The frequency response, one row per excited harmonic: frequency_hz, measured and model
/// magnitude (m/N) and phase (deg), for plot_lab.py's Bode chart.
std::string identify_response_csv(const IdentifyResult& result);

}  // namespace haptic::lab
