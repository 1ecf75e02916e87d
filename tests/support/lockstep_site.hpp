// One site's loop for the lockstep tests of the federation (tests/unit/runtime/remote_tools_test,
// shared_masses_test, tests/unit/federation/lockstep_sites_test): the server's own TickRunner over
// a simulated point-mass device held by a scripted hand, with the port's mailbox of remote tools
// and ledger and the SharedMassStage where a test asks for them. The tests step the sites together
// on simulated time and carry what goes between them themselves.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <utility>

#include "runtime/cartesian_model.hpp"
#include "runtime/remote_tools.hpp"
#include "runtime/shared_masses.hpp"
#include "runtime/simulated_point_mass_device.hpp"
#include "runtime/tick_runner.hpp"

namespace haptic::test {

/// A scripted hand's target from `at_s` on (simulated time). Unit: s, m.
struct Phase {
  double at_s;
  engine::Vec3 target;
};

/// A hand that takes the tool from `from` to `to` on a line over 1.5 s (200 N/m, 2 N·s/m).
inline engine::HandInput hand_towards(const engine::Vec3& from, const engine::Vec3& to) {
  engine::HandInput hand;
  hand.mode = engine::HandInput::Mode::kFollowTarget;
  hand.target = from;
  hand.stiffness = 200.0;
  hand.damping = 2.0;
  hand.trajectory.shape = engine::TargetTrajectory::Shape::kLine;
  hand.trajectory.end = to;
  hand.trajectory.duration_s = 1.5;
  return hand;
}

/// The sphere shared across sites (0.5 kg, 500 N/m) as site `site` compiles it: site 0 made it
/// (item 1); the others hold it as item 40 + site, a copy of site `origin`'s item 1.
inline std::unique_ptr<const engine::CompiledScene> shared_sphere_at(int site, const std::string& origin,
                                                                     double radius_m, double period_s) {
  engine::ObjectSpec sphere;
  sphere.shape = engine::SphereSpec{radius_m};
  sphere.stiffness = 500.0;
  sphere.object_mass = 0.5;
  sphere.object_damping = 1.0;
  sphere.across_sites = true;
  if (site != 0) {
    sphere.origin_site = engine::site_key(origin);
    sphere.origin_id = 1;
  }
  engine::SceneDescription description;
  engine::ItemMeta meta;
  meta.id = site == 0 ? 1 : 40 + static_cast<std::uint64_t>(site);  // its id here
  description.objects.push_back(engine::ObjectEntry{meta, sphere});
  return std::make_unique<const engine::CompiledScene>(engine::compile_scene(description, 50, 1, period_s));
}

/// What a site's loop has besides its device and scene.
struct LockstepSiteOptions {
  double period_s = 1e-3;
  double max_force_N = 20.0;
  /// The port's mailbox of remote tools and its ledger, rendered as avatars of this radius (m).
  bool remote_tools = false;
  double avatar_radius_m = 0.01;
  bool shared_masses = false;  // the SharedMassStage, fed from `in`, writing `out`
};

/// One site's loop. Its hand holds the tool where it starts until the test moves it.
struct LockstepSite {
  LockstepSite(engine::SiteKey site, const engine::Vec3& start, std::unique_ptr<const engine::CompiledScene> scene,
               const LockstepSiteOptions& options)
      : key(site),
        device(device_params(), engine::PointMassState{start, {}}, options.max_force_N),
        scenes(std::move(scene)),
        stage(key, runtime::MassCouplingParams{}, options.period_s, &in, &out),
        runner({runtime::TickPort{&device, &model, &samples, engine::force_limits_for(options.max_force_N),
                                  std::nullopt, options.remote_tools ? &remote : nullptr,
                                  options.remote_tools ? &ledger : nullptr,
                                  runtime::AvatarParams{options.avatar_radius_m, 1000.0, 0.0}}},
               scenes, counters,
               runtime::TickConfig{options.period_s, {}, 50, {}, options.shared_masses ? &stage : nullptr}) {
    device.set_hand(hand_towards(start, start));
  }
  static engine::PointMassParams device_params() {
    engine::PointMassParams p;
    p.mass = 0.05;
    p.damping = 0.1;
    p.workspace_min = {-1, -1, -1};
    p.workspace_max = {1, 1, 1};
    return p;
  }

  engine::SiteKey key;
  runtime::SimulatedPointMassDevice device;
  runtime::CartesianModel model;
  runtime::SceneExchange scenes;
  runtime::SampleRing samples;
  runtime::LoopCounters counters;
  runtime::LatestValue<runtime::RemoteToolSet> remote;
  runtime::CouplingLedger ledger;
  runtime::LatestValue<runtime::RemoteMassTable> in;
  runtime::LatestValue<runtime::LocalMassTable> out;
  runtime::SharedMassStage stage;
  runtime::TickRunner runner;
};

}  // namespace haptic::test
