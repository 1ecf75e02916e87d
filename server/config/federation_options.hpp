#pragma once
// The configuration's federation section (haptic.v1.FederationConfig) → the federation's options:
// defaults, validation naming the field ("federation.domain_id: …"), and what a SampleRelay takes.

#include <string>
#include <vector>

#include "federation/options.hpp"
#include "runtime/remote_tools.hpp"
#include "runtime/robot_wrench.hpp"
#include "runtime/shared_masses.hpp"
#include "haptic/v1/config.pb.h"

namespace haptic::config {

/// Fills the federation section's defaults (interface "lo", the ROS 2 namespace, rate and frame).
void fill_federation_defaults(v1::FederationConfig& federation);

/// "" or one message naming the bad field. loop_rate_hz: the loop's rate (the ROS 2 rate is at most it).
std::string validate_federation(const v1::FederationConfig& federation, double loop_rate_hz);

/// The relay's options from a valid, defaulted section, for a loop at loop_rate_hz.
federation::RelayOptions relay_options(const v1::FederationConfig& federation, double loop_rate_hz);
/// What a valid federation section does that its writer may not mean, one line each, for hapticd
/// to log as warnings at start: allow_insecure on an interface off this host (the domain in the
/// clear), and a loopback interface with peers elsewhere (they are never reached).
std::vector<std::string> federation_warnings(const v1::FederationConfig& federation);

/// How other sites' tools are rendered, and the couplings of shared masses, from a valid,
/// defaulted section.
runtime::AvatarParams avatar_params(const v1::FederationConfig& federation);
runtime::MassCouplingParams mass_coupling(const v1::FederationConfig& federation);
/// How a ROS 2 node's wrench is rendered (ros2.wrench_input), from a valid, defaulted section.
runtime::RobotWrenchParams robot_wrench_params(const v1::FederationConfig& federation);

}  // namespace haptic::config
