#pragma once
// The Z-width of a device itself (docs/identification.md): walls of increasing stiffness run on
// the configuration's own device in lockstep, through the server's own loop (lab/lab_run), and
// the first stiffness whose run does not settle, going up, found at a given damping. The ground
// truth an identified model's prediction (engine::sampled_wall_margin) is checked against.
//
// Each run: a half-space wall through where the tool starts, its outward normal along the axis,
// the wall's law BACKWARD_DIFFERENCE (the sampled analysis's own), the passivity controller off
// (it exists to hide this boundary), and a constant force field pressing the tool into the wall
// (through the command, as on any port: a driver's has no simulated operator). The tool starts at the surface, falls in towards its equilibrium
// d = F/K, and rings: it settles if the envelope of its distance from the equilibrium decays
// (engine::envelope_growth's rate < 0, fitted from the first window on: near the boundary a run
// decays or grows slowly, and the rate's sign tells which side it is on) and ends below where it
// began (a run that grew into the device's force limit rings on in a cycle whose envelope is
// flat).

#include <cstdint>
#include <functional>
#include <vector>

#include "engine/core/vec3.hpp"
#include "haptic/v1/config.pb.h"
#include "lab/lab_run.hpp"

namespace haptic::lab {

struct DeviceWallParams {
  std::uint32_t port = 0;
  /// The wall's outward normal, the push against it and the distance measured along it: a unit
  /// vector in W (an identification's direction).
  engine::Vec3 direction{1.0, 0.0, 0.0};
  double push_n = 0.5;     // the force pressing into the wall. Unit: N. > 0.
  /// A device measured with noise or quantization: distances from the equilibrium at or under
  /// this are the sensor's, not the wall's, and count as settled. Unit: m. >= 0.
  double noise_floor_m = 0.0;
  /// When > 0, the push is K times this instead (at most push_n): the equilibrium this far
  /// inside the wall at every K, so that the fall in stands above the noise floor however stiff
  /// the wall. Unit: m.
  double penetration_m = 0.0;
  /// A device that friction holds: the push is at least this, so that the tool moves into the
  /// wall at every K (under its friction it would not move at all). Unit: N. >= 0.
  double min_push_n = 0.0;
  /// A device that friction holds: a run that ends still (its last window's motion within the
  /// noise floor) has settled, wherever the friction stopped it (within c/K of the equilibrium).
  bool still_settles = false;
  /// Each wall runs this many times, `vary` changing the configuration before every run but the
  /// first (its argument the run, 1 …); the wall settles only where every run does. A device
  /// that friction holds and counts read settles or rings by where in a count it rests and by
  /// what its noise draws as it crosses one (003's five-bar along x at B = 1 N·s/m: its first
  /// ringing wall 16 to 39 kN/m over 16 noise seeds), so one run per wall overstates what a user
  /// can count on. >= 1.
  int runs = 1;
  std::function<void(v1::ServerConfig& config, int run)> vary;
  double seconds = 3.0;    // each run. Unit: s.
  double window_s = 0.1;   // the envelope's windows (the first, the fall in, left out). Unit: s.
  DeviceTime device_time;  // how the device's time passes (lab_run)
};

/// Whether a wall (K N/m, B N·s/m) on the device settles, as above, in each of `params.runs`.
/// Throws std::invalid_argument for a configuration or parameters that cannot run.
bool device_wall_settles(const v1::ServerConfig& config, const DeviceWallParams& params, double stiffness,
                         double damping);

/// The first K that does not settle at damping B, going up: from guess / 16 (rounded down to the
/// grid 2^(k/4) N/m, halved until a wall settles) up that grid's quarter octaves to the first
/// that does not, then bisecting between the two (in the logarithm) to `tolerance` relative;
/// the last K that settled is returned. 0 when even guess / 1e3 does not settle, infinity when
/// guess × 1e3 does. About 17 walls from a guess of three times the boundary: one to start, ten
/// up to it, six to bisect.
///
/// The walk, not a doubling bracket: a device held by friction and read through counts may ring
/// at a K and settle again at one above it (003's five-bar at B = 5 N·s/m rings at 37 and 44 kN/m
/// and settles at 53), and a bisection between a settled K and a doubled one can land on such an
/// island. What a user can count on is every wall under the figure settling: the first crossing.
double device_zwidth_boundary(const v1::ServerConfig& config, const DeviceWallParams& params, double damping,
                              double guess, double tolerance = 0.005);

/// The walls above a boundary that settle again: K = boundary × 2^(j/4) for j = 1 … `count`,
/// each run as device_wall_settles does. Empty for a device whose stability changes once along K
/// (and for a boundary of 0 or infinity). One that friction holds and counts read may settle
/// again above its first ring (003's five-bar); the report says so, since its figure is then a
/// first crossing rather than a boundary.
std::vector<double> device_settles_above(const v1::ServerConfig& config, const DeviceWallParams& params,
                                         double damping, double boundary, int count = 4);

/// Port `port`'s device run again with its sensor's noise drawn anew: the seed of its point
/// mass's sensor or of its encoders mixed with `run`, as a wall run again on the bench meets
/// other noise. Port 0 is the configuration's own device, port i its extra device i − 1. Returns
/// false, changing nothing, where that port's device reads without noise, is no simulated device
/// (a driver's port: its runs would be the same run) or does not exist.
bool redraw_sensor_noise(v1::ServerConfig& config, std::uint32_t port, int run);

/// Whether redraw_sensor_noise has a noise to draw anew on port `port`.
bool reads_through_noise(const v1::ServerConfig& config, std::uint32_t port);

}  // namespace haptic::lab
