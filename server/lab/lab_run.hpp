#pragma once
// haptic-lab's `run`: one scene — a hapticd configuration (device ports, operator, objects,
// fields, rate, integrators) — run in lockstep time, in-process, through the same TickRunner as
// the server's loop, with a trace of every tick. The base every study is built on, and the way
// to reproduce any figure.

#include <cstdint>
#include <ostream>
#include <string>

#include "haptic/v1/config.pb.h"

namespace haptic::lab {

struct RunSummary {
  std::uint64_t ticks = 0;
  double energy_to_device = 0.0;    // Work the scene's force did on the tool. Unit: J.
  double energy_from_device = 0.0;  // Work the tool did against it. Unit: J.
  std::uint64_t fault_ticks = 0;    // Ticks with a force or device fault flag.
  bool finite = true;               // Every published state was finite.
};

/// Runs `config` (validated; its time mode is ignored: the run is always lockstep) for
/// `duration_s` of simulated time and writes one CSV row per tick and port to `trace`:
/// port, tick, time (s), tool position and velocity (m, m/s), force (N), proxy (m), contacts,
/// flags, and the energy given to and taken from the device so far (J, trapezoidal on F·v).
/// Throws std::invalid_argument naming what is wrong before any work starts.
RunSummary run_scene(const v1::ServerConfig& config, double duration_s, std::ostream& trace);

}  // namespace haptic::lab
