#pragma once
// hapticd assembled: devices (one per device port), loop, scene store, sessions, UDP data plane, gRPC control plane and
// the housekeeping thread (leases, scene compaction, status line, events). Used by main() and by
// tests that want a whole server in-process.

#include <grpcpp/server.h>

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "haptic/v1/config.pb.h"
#include "net/control_listener.hpp"
#include "net/event_hub.hpp"
#include "net/grpc_face.hpp"
#include "net/haptic_service.hpp"
#include "net/http_face.hpp"
#include "net/metrics_endpoint.hpp"
#include "net/scene_store.hpp"
#include "net/session_registry.hpp"
#include "app/federated_scene.hpp"
#include "federation/item_replicator.hpp"
#include "federation/sample_relay.hpp"
#include "net/udp_endpoint.hpp"
#include "net/viewer_endpoint.hpp"
#include "recording/run_recorder.hpp"
#include "runtime/loop_cpu.hpp"
#include "runtime/loop_thread.hpp"
#include "config/devices.hpp"
#include "config/security.hpp"
#include "runtime/tick_runner.hpp"

namespace haptic::app {

class Server {
 public:
  /// Builds everything and binds the ports. Throws std::runtime_error naming what failed.
  explicit Server(const v1::ServerConfig& config);
  ~Server();
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  /// Starts the loop, the data plane, the control plane and housekeeping.
  void start();
  /// Ramps forces to zero, then stops everything. Idempotent.
  void shutdown();

  std::uint16_t grpc_port() const { return grpc_port_; }
  /// The metrics endpoint's port; 0 without one (metrics_address empty).
  std::uint16_t metrics_port() const { return metrics_ ? metrics_->port() : 0; }
  /// The web viewer's port; 0 without one (viewer_address empty).
  std::uint16_t viewer_port() const { return viewer_ ? viewer_->port() : 0; }
  /// The control plane's HTTP port (http_address); 0 without one.
  std::uint16_t http_port() const { return http_face_ ? http_face_->port() : 0; }
  std::uint16_t udp_port() const { return udp_.port(); }
  /// Device port `port`'s tick samples (the replay compares them with a recording's).
  const runtime::SampleRing& samples(std::size_t port) const { return *samples_.at(port); }
  std::size_t device_ports() const { return samples_.size(); }
  /// GetStats' figures; with `lateness_bins`, also the lateness histogram they summarize, bin by
  /// bin, from the same reading (the web viewer's plot).
  v1::Stats stats(runtime::LatenessHistogram::Counts* lateness_bins = nullptr) const;
  /// The federation's part of the stats (with a federation).
  void federation_stats(v1::FederationStats& out) const;
  /// Starts recording the run into `path` (recording::RunRecorder): before start(), from the first tick.
  /// Returns "" or why not.
  std::string start_recording(const std::string& path);
  /// Stops a recording; its totals, or nullopt when none ran.
  std::optional<v1::RecordEnd> stop_recording();
  /// Lockstep with simulated devices only: puts the devices, their simulated operators, the loop
  /// and the scene back as they started (the caller's items go, the server's own scene comes
  /// back, ids and ticks count from 1), so the same calls reproduce the same run. Sessions and
  /// their subscriptions stay. FAILED_PRECONDITION (nothing changed) in real time, with a
  /// hardware device, or while another session holds items.
  grpc::Status reset_lockstep(std::uint64_t session_id);
  /// Server time now (what samples are stamped with). Unit: ns.
  std::int64_t server_time_ns() const { return loop_->server_time_ns(); }
  /// CLOCK_MONOTONIC time of server time 0, in real time; none in lockstep. Unit: ns.
  std::optional<std::int64_t> time_origin_ns() const {
    if (loop_->config().mode != runtime::TimeMode::kRealTime) return std::nullopt;
    return loop_->start_ns();
  }

 private:
  void housekeeping_loop();
  /// The metrics endpoint and the viewer, when configured (`access`: the control plane's tokens).
  /// With a federation section: joins its DDS domain and makes the relay (started with the loop).
  void join_federation(const schema::SceneLimits& limits);
  void bind_http_endpoints(const net::AccessControl& access, const config::SecurityMaterial& security);
  void log_status();

  v1::ServerConfig config_;
  std::mutex devices_mutex_;  // guards devices_ against a reset replacing them
  std::vector<config::PortDevice> devices_;  // per device port: the device, its model, its operator
  std::vector<runtime::DeviceDescription> descriptions_;  // each port's, as the service sees it
  schema::SceneSpecs initial_scene_;  // the server's own scene (session 0), validated
  engine::HandInput initial_hand_;    // what every simulated operator starts with
  double period_s_ = 1e-3;            // Unit: s.
  runtime::SceneExchange scenes_;
  std::vector<std::unique_ptr<runtime::SampleRing>> samples_;  // per device port
  runtime::LoopCounters counters_;
  runtime::LatenessHistogram lateness_;
  std::unique_ptr<runtime::TickRunner> runner_;
  std::unique_ptr<runtime::LoopThread> loop_;
  /// The host-wide claim on the loop's CPU (real time with SCHED_FIFO), held while this server
  /// lives, and what to say about the choice when the loop starts.
  std::optional<runtime::LoopCpuClaim> loop_cpu_claim_;
  std::string loop_cpu_warning_;
  net::SessionRegistry sessions_;
  std::unique_ptr<net::SceneStore> scene_;
  net::EventHub events_;
  net::UdpEndpoint udp_;
  std::unique_ptr<net::HapticService> service_;
  std::unique_ptr<net::GrpcFace> grpc_face_;  // the service over gRPC
  std::unique_ptr<net::ControlListener> listener_;  // accepts gRPC's connections for it
  std::unique_ptr<grpc::Server> grpc_server_;
  std::uint16_t grpc_port_ = 0;
  /// The control plane's security for the start line: "mutual TLS, 3 tokens", "plaintext, no tokens".
  std::string security_summary_;
  std::unique_ptr<net::MetricsEndpoint> metrics_;  // when metrics_address is set
  std::unique_ptr<net::ViewerEndpoint> viewer_;    // when viewer_address is set
  std::unique_ptr<net::HttpFace> http_face_;       // when http_address is set: the service over HTTP
  std::unique_ptr<recording::RunRecorder> recorder_;
  std::unique_ptr<federation::SampleRelay> relay_;  // when federation is configured
  /// The shared scene across sites (with the federation; after relay_, whose participant owns
  /// the domain, so it goes first).
  std::unique_ptr<FederatedScene> federated_scene_;
  std::unique_ptr<federation::ItemReplicator> replicator_;
  /// Federation: each port's mailbox of other sites' tools and its couplings' ledger.
  std::vector<std::unique_ptr<runtime::LatestValue<runtime::RemoteToolSet>>> remote_tools_;
  std::vector<std::unique_ptr<runtime::CouplingLedger>> ledgers_;
  /// Federation with ros2.wrench_input: each port's mailbox of a ROS 2 node's wrench.
  std::vector<std::unique_ptr<runtime::LatestValue<runtime::RobotWrench>>> robot_wrenches_;
  /// Federation: masses shared across sites — the other sites' copies in, this site's out, and the
  /// loop's stage that couples them.
  runtime::LatestValue<runtime::RemoteMassTable> remote_masses_;
  runtime::LatestValue<runtime::LocalMassTable> local_masses_;
  std::unique_ptr<runtime::SharedMassStage> mass_stage_;
  /// The loop's ports with the federation's mailboxes and ledgers (none without a federation).
  std::vector<runtime::TickPort> federated(std::vector<runtime::TickPort> ports) const;

  std::thread housekeeping_;
  std::mutex housekeeping_mutex_;
  std::condition_variable housekeeping_wake_;
  bool stopping_ = false;  // guarded by housekeeping_mutex_
  std::atomic<std::uint64_t> leases_expired_{0};
  bool started_ = false;
  std::atomic<bool> shut_down_{false};  // read by a reset on a control-plane thread

  // Status-line bookkeeping (housekeeping thread only).
  std::uint64_t status_last_ticks_ = 0;
  std::int64_t status_last_ns_ = 0;
};

}  // namespace haptic::app
