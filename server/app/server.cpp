#include "app/server.hpp"

#include <grpcpp/health_check_service_interface.h>
#include <grpcpp/resource_quota.h>
#include <grpcpp/server_builder.h>
#include <grpcpp/server_posix.h>
#include <sys/resource.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <stdexcept>

#include "app/health_check.hpp"
#include "config/federation_options.hpp"
#include "config/security.hpp"
#include "config/server_config.hpp"
#include "federation/dds_log.hpp"
#include "schema/scene_specs.hpp"
#include "net/prometheus_text.hpp"
#include "net/tls_server_context.hpp"
#include "runtime/realtime.hpp"

namespace haptic::app {
namespace {

/// Raises the soft limit on open files to the hard one (connections are capped below it); returns
/// the soft limit now in force.
std::uint32_t raise_fd_limit() {
  rlimit limit{};
  if (::getrlimit(RLIMIT_NOFILE, &limit) != 0) return 1024;
  if (limit.rlim_cur < limit.rlim_max) {
    limit.rlim_cur = limit.rlim_max;
    (void)::setrlimit(RLIMIT_NOFILE, &limit);
    (void)::getrlimit(RLIMIT_NOFILE, &limit);
  }
  return static_cast<std::uint32_t>(std::min<rlim_t>(limit.rlim_cur, 1u << 30));
}

/// The configured tokens as the control plane checks them.
std::vector<net::Credential> credentials(const v1::AccessTokens& tokens) {
  std::vector<net::Credential> out;
  for (const v1::AccessToken& token : tokens.tokens()) {
    net::Credential credential{token.name(), token.token(), token.role(), std::nullopt};
    if (token.has_expires()) {
      credential.expires = std::chrono::system_clock::time_point(
          std::chrono::duration_cast<std::chrono::system_clock::duration>(
              std::chrono::seconds(token.expires().seconds()) +
              std::chrono::nanoseconds(token.expires().nanos())));
    }
    out.push_back(std::move(credential));
  }
  return out;
}

/// TLS for the control plane, terminated by the control listener; with a client CA, clients must
/// present a certificate it signed.
/// `alpn`: "h2" for gRPC's listener, "http/1.1" for the HTTP face.
std::shared_ptr<const net::TlsServerContext> tls_context(const config::SecurityMaterial& security,
                                                         const std::string& alpn = "h2") {
  if (!security.tls) return nullptr;
  try {
    return std::make_shared<const net::TlsServerContext>(
        net::TlsServerMaterial{security.cert_pem, security.key_pem, security.client_ca_pem, alpn});
  } catch (const std::runtime_error& error) {
    throw config::ConfigError(error.what());  // the files' contents: a configuration error
  }
}

/// The viewer's page: the configured folder; else the installed one (share/hapticd/web beside the
/// binary's bin/); else the build tree's (where a build puts it).
std::filesystem::path viewer_root(const v1::ServerConfig& config) {
  if (!config.viewer_root().empty()) return config.viewer_root();
  std::error_code error;
  const std::filesystem::path binary = std::filesystem::read_symlink("/proc/self/exe", error);
  if (!error) {
    const std::filesystem::path installed = binary.parent_path().parent_path() / "share/hapticd/web";
    if (std::filesystem::is_regular_file(installed / "index.html", error)) return installed;
  }
  return HAPTIC_VIEWER_BUILD_ROOT;
}

/// Control-plane threads for unary calls, beside those the event streams may hold.
constexpr int kUnaryCallThreads = 32;

std::int64_t ms_to_ticks(std::uint32_t ms, double rate_hz) {
  return std::max<std::int64_t>(1, std::llround(static_cast<double>(ms) * 1e-3 * rate_hz));
}

std::vector<std::unique_ptr<runtime::SampleRing>> make_rings(std::size_t ports) {
  std::vector<std::unique_ptr<runtime::SampleRing>> rings;
  for (std::size_t i = 0; i < ports; ++i) rings.push_back(std::make_unique<runtime::SampleRing>());
  return rings;
}

std::vector<runtime::SampleRing*> ring_pointers(
    const std::vector<std::unique_ptr<runtime::SampleRing>>& rings) {
  std::vector<runtime::SampleRing*> out;
  for (const auto& ring : rings) out.push_back(ring.get());
  return out;
}

/// The empty scene the loop runs until the store publishes its first, with every port's state.
std::unique_ptr<const engine::CompiledScene> empty_scene(std::uint32_t ports) {
  return std::make_unique<const engine::CompiledScene>(
      engine::compile_scene(engine::SceneDescription{}, 1, 0, 1e-3, 0.0, ports));
}

}  // namespace

Server::Server(const v1::ServerConfig& config)
    : config_(config),
      devices_(config::make_devices(config)),
      scenes_(empty_scene(static_cast<std::uint32_t>(devices_.size()))),
      samples_(make_rings(devices_.size())),
      sessions_(net::SessionLimits{config.max_sessions(), config.max_sessions_per_peer(),
                                   config.max_sessions_per_token(),
                                   std::chrono::milliseconds(config.lease_timeout_ms()),
                                   config.udp_any_source(), config.session_open_rate_per_peer(),
                                   config.session_open_burst_per_peer()}),
      events_(net::WatchLimits{config.max_event_streams_per_session(), config.max_event_streams(),
                               config.max_event_streams_per_peer(), config.max_event_streams_per_token()}),
      udp_(sessions_, ring_pointers(samples_)) {
  const double rate = config.loop_rate_hz();
  const auto ports = static_cast<std::uint32_t>(devices_.size());
  runtime::TickConfig tick;
  tick.period_s = 1.0 / rate;
  period_s_ = tick.period_s;
  for (const config::PortDevice& port : devices_) descriptions_.push_back(port.device->description());
  tick.output_ramp_ticks = ms_to_ticks(config.removal_ramp_ms(), rate);
  // Each port's force limit and passivity controller follow its own device.
  if (config.has_federation()) {
    for (std::size_t port = 0; port < devices_.size(); ++port) {
      remote_tools_.push_back(std::make_unique<runtime::LatestValue<runtime::RemoteToolSet>>());
      ledgers_.push_back(std::make_unique<runtime::CouplingLedger>());
      if (config.federation().ros2().has_wrench_input()) {
        robot_wrenches_.push_back(std::make_unique<runtime::LatestValue<runtime::RobotWrench>>());
      }
    }
    mass_stage_ = std::make_unique<runtime::SharedMassStage>(
        engine::site_key(config.federation().site()), config::mass_coupling(config.federation()), tick.period_s,
        &remote_masses_, &local_masses_);
    tick.shared_masses = mass_stage_.get();
  }
  const std::vector<runtime::TickPort> tick_ports =
      federated(config::tick_ports(config, devices_, ring_pointers(samples_), tick.period_s));
  runner_ = std::make_unique<runtime::TickRunner>(tick_ports, scenes_, counters_, tick);

  runtime::LoopConfig loop;
  loop.rate_hz = rate;
  loop.mode = config.time_mode() == v1::LOCKSTEP ? runtime::TimeMode::kLockstep
                                                  : runtime::TimeMode::kRealTime;
  loop.use_fifo = config.real_time().use_fifo();
  loop.fifo_priority = config.real_time().fifo_priority();
  loop.spin_ns = static_cast<std::int64_t>(config.real_time().spin_us()) * 1000;
  if (loop.mode == runtime::TimeMode::kRealTime &&
      (config.real_time().use_fifo() || config.real_time().has_cpu())) {
    runtime::LoopCpuChoice cpu = runtime::choose_loop_cpu(
        config.real_time().has_cpu() ? std::optional<int>(config.real_time().cpu()) : std::nullopt,
        static_cast<int>(std::thread::hardware_concurrency()));
    loop.cpu = cpu.cpu;
    loop_cpu_claim_ = std::move(cpu.claim);
    loop_cpu_warning_ = std::move(cpu.warning);
  } else {
    loop.cpu = -1;
  }
  if (runtime::ServoClock* servo = devices_.front().servo) {
    // Device-clocked: the driver's servo loop paces the ticks, at its own rate.
    if (std::abs(servo->rate_hz() - rate) > 1e-9 * rate) {
      throw std::runtime_error("driver.clock DEVICE: the driver's servo runs at " +
                               std::to_string(servo->rate_hz()) + " Hz but loop_rate_hz is " +
                               std::to_string(rate) + "; set loop_rate_hz to the servo rate");
    }
    loop.servo = servo;
  }
  loop_ = std::make_unique<runtime::LoopThread>(*runner_, counters_, lateness_, loop);

  scene_ = std::make_unique<net::SceneStore>(
      scenes_, [this] { return static_cast<std::int64_t>(loop_->completed_ticks() + 1); },
      tick.output_ramp_ticks, config.max_objects_per_session(), tick.period_s,
      config.session_force_budget(), ports,
      net::SceneBudget{config.max_scene_triangles(), config.max_scene_bytes(),
                       config.max_scene_triangles_per_session(), config.max_scene_bytes_per_session(),
                       config.max_scene_triangles_per_peer(), config.max_scene_bytes_per_peer(),
                       [this](std::uint64_t session_id) { return sessions_.peer_of(session_id); }});

  // The initial scene belongs to the server itself (session 0) and never expires.
  schema::SceneLimits limits;
  limits.period_s = tick.period_s;
  // Objects are validated once for all ports: against the least damped port's device.
  const config::DesignDevice design = config::scene_design_device(devices_);
  limits.device_mass = design.mass;
  limits.device_damping = design.damping;
  limits.device_unknown_reason = design.unknown_reason;
  if (auto e = schema::to_scene_specs(config.initial_scene(), "initial_scene.", limits, initial_scene_);
      !e.empty()) {
    throw std::runtime_error(e);
  }
  std::vector<std::uint64_t> object_ids, field_ids;
  if (const grpc::Status status =
          scene_->replace_session_scene(0, initial_scene_.objects, initial_scene_.fields, object_ids,
                                        field_ids, &config.initial_scene());
      !status.ok()) {
    throw std::runtime_error("initial_scene: " + status.error_message());
  }

  if (auto e = schema::to_hand_input(config.initial_operator(), "initial_operator", limits, initial_hand_);
      !e.empty()) {
    throw std::runtime_error(e);
  }
  // Every simulated hand starts with the configured input.
  for (const config::PortDevice& port : devices_) {
    if (port.simulated != nullptr) port.simulated->set_hand(initial_hand_);
  }

  const std::uint32_t udp_port = config.udp_port();
  if (udp_port > 65535) throw std::runtime_error("udp_port: out of range");
  udp_.bind(config.udp_address(), static_cast<std::uint16_t>(udp_port));

  std::vector<net::DevicePort> service_ports;
  for (std::uint32_t i = 0; i < ports; ++i) {
    std::function<void(const engine::HandInput&)> set_hand;  // none for a device without one
    if (devices_[i].simulated != nullptr) {
      // Through devices_ each time: a reset replaces the device.
      set_hand = [this, i](const engine::HandInput& input) {
        std::lock_guard lock(devices_mutex_);
        devices_[i].simulated->set_hand(input);
      };
    }
    service_ports.push_back(net::DevicePort{samples_[i].get(), &descriptions_[i], std::move(set_hand)});
  }
  const config::SecurityMaterial security = config::load_security(config.security());
  std::vector<const runtime::SampleRing*> rings;
  for (const auto& ring : samples_) rings.push_back(ring.get());
  recorder_ = std::make_unique<recording::RunRecorder>([this] { return loop_->completed_ticks(); },
                                             std::move(rings));
  const net::AccessControl access(credentials(security.tokens));
  const int token_count = security.tokens.tokens_size();
  security_summary_ = std::string(!security.tls ? "plaintext"
                                  : security.client_ca_pem.empty() ? "TLS"
                                                                   : "mutual TLS") +
                      ", " +
                      (token_count == 0 ? std::string("no tokens")
                                        : std::to_string(token_count) +
                                              (token_count == 1 ? " token" : " tokens"));
  service_ = std::make_unique<net::HapticService>(net::ServiceDependencies{
      sessions_, *scene_, events_, *loop_, std::move(service_ports), udp_.port(), limits,
      [this] { return stats(); }, access,
      [this](std::uint64_t session_id) { return reset_lockstep(session_id); }, recorder_.get(),
      config.recording_dir(), [this](const std::string& path) { return start_recording(path); },
      config.has_federation(),
      [this](std::uint64_t through_tick, std::chrono::milliseconds timeout) {
        return udp_.wait_sent_through(through_tick, timeout);
      }});
  const std::uint32_t fd_limit = raise_fd_limit();
  // A TLS connection takes three descriptors once served (the TCP socket and both ends of the
  // socket pair to gRPC), a plaintext one one.
  const std::uint32_t fds_per_connection = security.tls ? 3 : 1;
  net::ConnectionLimits connection_limits;
  connection_limits.max_connections =
      config.max_connections() > 0
          ? config.max_connections()
          : std::clamp<std::uint32_t>((fd_limit > 256 ? fd_limit - 128 : fd_limit / 2) / fds_per_connection,
                                      16, 1024);
  connection_limits.max_connections_per_peer =
      config.max_connections_per_peer() > 0 ? config.max_connections_per_peer() : 64;
  connection_limits.handshake_timeout = std::chrono::milliseconds(config.handshake_timeout_ms());
  if (connection_limits.max_connections * fds_per_connection + 64 > fd_limit) {
    spdlog::warn("hapticd: max_connections {} ({} descriptors each) is close to the fd limit {}: "
                 "expect connections refused for want of descriptors",
                 connection_limits.max_connections, fds_per_connection, fd_limit);
  }
  // hapticd accepts every control-plane connection itself, and terminates TLS itself, so the caps,
  // the handshake deadline and the recovery from running out of descriptors hold in both modes
  // (net::ControlListener); gRPC has no listening port of its own.
  listener_ = std::make_unique<net::ControlListener>(connection_limits, tls_context(security));
  listener_->bind(config.grpc_address());
  grpc::ServerBuilder builder;
  // Every call in progress holds a thread of gRPC's sync pool, an event stream for its whole life:
  // cap the pool, so that a flood of calls is refused (RESOURCE_EXHAUSTED) instead of growing it
  // without bound. Room for every allowed stream plus the unary calls of a busy server.
  grpc::ResourceQuota quota("hapticd-control-plane");
  quota.SetMaxThreads(static_cast<int>(config.max_event_streams()) + kUnaryCallThreads);
  builder.SetResourceQuota(quota);
  grpc::EnableDefaultHealthCheckService(true);  // grpc.health.v1, for hapticd --health-check
  grpc_face_ = std::make_unique<net::GrpcFace>(*service_);
  builder.RegisterService(grpc_face_.get());
  grpc_server_ = builder.BuildAndStart();
  if (!grpc_server_) throw std::runtime_error("cannot start the gRPC server");
  grpc_port_ = listener_->port();
  listener_->start([server = grpc_server_.get()](int fd) { grpc::AddInsecureChannelFromFd(server, fd); });
  bind_http_endpoints(access, security);
  join_federation(limits);
}

std::vector<runtime::TickPort> Server::federated(std::vector<runtime::TickPort> ports) const {
  for (std::size_t port = 0; port < ports.size() && port < remote_tools_.size(); ++port) {
    ports[port].remote = remote_tools_[port].get();
    ports[port].ledger = ledgers_[port].get();
    ports[port].avatar = config::avatar_params(config_.federation());
    if (port < robot_wrenches_.size()) {
      ports[port].robot = robot_wrenches_[port].get();
      ports[port].robot_params = config::robot_wrench_params(config_.federation());
    }
  }
  return ports;
}

void Server::join_federation(const schema::SceneLimits& limits) {
  if (!config_.has_federation()) return;
  std::vector<federation::RelayPort> ports;
  for (std::size_t port = 0; port < samples_.size(); ++port) {
    ports.push_back({samples_[port].get(), descriptions_[port].buttons, remote_tools_[port].get(), ledgers_[port].get(),
                     port < robot_wrenches_.size() ? robot_wrenches_[port].get() : nullptr});
  }
  // Cyclone's own lines (a rogue host's failed DDS Security handshakes, twice a second) into this
  // log, identical ones once per 10 s and counted; before the participant, whose domain takes the
  // sink when it is made.
  federation::route_dds_log([](federation::DdsLogLevel level, const std::string& line) {
    if (level == federation::DdsLogLevel::kError) {
      spdlog::error("{}", line);
    } else if (level == federation::DdsLogLevel::kWarning) {
      spdlog::warn("{}", line);
    } else {
      spdlog::info("{}", line);
    }
  });
  federation::RelayOptions relay = config::relay_options(config_.federation(), config_.loop_rate_hz());
  relay.log = [](const std::string& line) { spdlog::warn("{}", line); };
  federated_scene_ = std::make_unique<FederatedScene>(*scene_, limits);
  federation::ReplicatorOptions shared_scene;
  shared_scene.site = relay.site;
  shared_scene.domain = relay.domain;
  shared_scene.log = [](const std::string& line) { spdlog::warn("{}", line); };
  try {
    relay_ = std::make_unique<federation::SampleRelay>(relay, ports, federation::RelayMasses{&local_masses_, &remote_masses_});
    replicator_ = std::make_unique<federation::ItemReplicator>(shared_scene, *federated_scene_, relay_->participant());
  } catch (const std::runtime_error& error) {
    throw config::ConfigError(std::string("federation: ") + error.what());
  }
}

void Server::bind_http_endpoints(const net::AccessControl& access,
                                 const config::SecurityMaterial& security) {
  if (!config_.http_address().empty()) {
    net::HttpFaceOptions options;
    options.allowed_origins.assign(config_.http_allowed_origins().begin(), config_.http_allowed_origins().end());
    options.limits.timeout = std::chrono::milliseconds(config_.handshake_timeout_ms());
    http_face_ = std::make_unique<net::HttpFace>(*service_, std::move(options));
    // With the control plane's TLS (and its client CA: mutual TLS), the face is HTTPS only.
    if (auto tls = tls_context(security, "http/1.1")) http_face_->use_tls(std::move(tls));
    http_face_->bind(config_.http_address());
  }
  if (!config_.metrics_address().empty()) {
    metrics_ = std::make_unique<net::MetricsEndpoint>();
    metrics_->bind(config_.metrics_address());
  }
  if (config_.viewer_address().empty()) return;
  net::ViewerSources sources;
  sources.scene = scene_.get();
  for (std::size_t port = 0; port < samples_.size(); ++port) {
    sources.samples.push_back(samples_[port].get());
    sources.devices.push_back(service_->device_info(static_cast<std::uint32_t>(port)));
  }
  sources.stats = [this](runtime::LatenessHistogram::Counts& lateness_bins) { return stats(&lateness_bins); };
  sources.access = access;
  sources.host_name = config::host_of_address(config_.viewer_address());
  sources.loopback_only = config::is_loopback_host(sources.host_name);
  viewer_ = std::make_unique<net::ViewerEndpoint>(std::move(sources));
  try {
    viewer_->load_page(viewer_root(config_));
  } catch (const std::runtime_error& error) {
    throw config::ConfigError(error.what());  // viewer_root names a folder without the page: exit 2
  }
  viewer_->bind(config_.viewer_address());
}

Server::~Server() { shutdown(); }

std::string Server::start_recording(const std::string& path) {
  if (std::string error = recorder_->start(path, config_); !error.empty()) return error;
  // What clients hold already comes first, after tick start_tick: their sessions, then their live
  // items in id order (a replay numbers them alike unless ids were skipped by deletions).
  for (const net::SessionInfo& session : sessions_.list()) {
    v1::RecordedChange change;
    change.set_session_id(session.id);
    change.mutable_opened()->set_client_name(session.client_name);
    change.mutable_opened()->set_device_index(session.device_index);
    recorder_->record(std::move(change));
  }
  for (const net::SceneEntry& entry : scene_->read(0, true)) {
    if (entry.session_id == 0) continue;  // the server's own scene is in the configuration
    v1::RecordedChange change;
    change.set_session_id(entry.session_id);
    if (entry.source.object) {
      change.mutable_object_created()->set_id(entry.id);
      *change.mutable_object_created()->mutable_object() = *entry.source.object;
    } else if (entry.source.field) {
      change.mutable_field_created()->set_id(entry.id);
      *change.mutable_field_created()->mutable_field() = *entry.source.field;
    }
    recorder_->record(std::move(change));
  }
  return {};
}

std::optional<v1::RecordEnd> Server::stop_recording() { return recorder_->stop("stopped"); }

void Server::start() {
  for (std::size_t i = 0; i < devices_.size(); ++i) {
    if (devices_[i].device->start() != runtime::DeviceStatus::kOk) {
      throw std::runtime_error("device " + std::to_string(i) + " (" +
                               devices_[i].device->description().name + ") failed to start");
    }
  }
  if (!loop_cpu_warning_.empty()) spdlog::warn("loop: {}", loop_cpu_warning_);
  const runtime::RealtimeSetup setup = loop_->start();
  if (loop_->config().mode == runtime::TimeMode::kRealTime && loop_->config().use_fifo) {
    if (!setup.fifo) {
      spdlog::warn("loop: SCHED_FIFO refused ({}); running with normal scheduling, expect more jitter",
                   setup.fifo_error);
    }
    if (!setup.cpu_error.empty()) {
      spdlog::warn("loop: cannot pin to CPU {} ({}); running unpinned", loop_->config().cpu,
                   setup.cpu_error);
    }
    if (!setup.memory_locked) {
      spdlog::warn("loop: mlockall refused ({}); page faults may delay ticks", setup.mlock_error);
    }
  }
  const bool real_time = loop_->config().mode == runtime::TimeMode::kRealTime;
  net::SenderScheduling sender;
  if (real_time) {
    const int cpu = config_.real_time().sender_cpu();
    sender.cpu = cpu == config::kSenderOnLoopCpu ? setup.cpu : cpu;
    sender.priority = config_.real_time().sender_priority();
  }
  const net::SenderSetup sender_setup =
      udp_.start(real_time ? std::optional<std::int64_t>(loop_->start_ns()) : std::nullopt, sender);
  if (!sender_setup.priority_error.empty()) {
    spdlog::warn("udp: the State sender's SCHED_FIFO {} refused ({}); it runs with normal "
                 "scheduling, so busy threads may delay datagrams",
                 sender.priority, sender_setup.priority_error);
  }
  if (!sender_setup.cpu_error.empty()) {
    spdlog::warn("udp: cannot pin the State sender to CPU {} ({}); it runs unpinned", sender.cpu,
                 sender_setup.cpu_error);
  }
  status_last_ns_ = runtime::monotonic_now_ns();
  housekeeping_ = std::thread([this] { housekeeping_loop(); });
  if (relay_) {
    relay_->start();
    replicator_->start();
    if (!relay_->masses_refused().empty()) {
      spdlog::warn("federation: this site's copies of shared masses are not published ({}); it still couples to "
                   "the other sites'", relay_->masses_refused());
    }
    if (!relay_->tools_refused().empty()) {
      spdlog::warn("federation: this site's tools are not published ({}); its users feel the other sites' tools "
                   "and are not felt by them", relay_->tools_refused());
    }
    const v1::FederationConfig& federation = config_.federation();
    for (const std::string& warning : config::federation_warnings(federation)) spdlog::warn("{}", warning);
    spdlog::info("hapticd: federation site \"{}\" in DDS domain {} on {}{}", federation.site(),
                 federation.domain_id(), federation.interface(),
                 federation.has_ros2() ? fmt::format(", ROS 2 topics under {} at {:g} Hz{}",
                                                     federation.ros2().ros_namespace(), federation.ros2().rate_hz(),
                                                     federation.ros2().has_wrench_input()
                                                         ? ", each tool's force from port<N>/" +
                                                               federation.ros2().wrench_input().topic()
                                                         : std::string())
                                       : std::string());
  }
  if (metrics_) {
    metrics_->start([this] { return net::prometheus_text(stats()); });
    spdlog::info("hapticd: metrics at http://{}/metrics (port {})", config_.metrics_address(),
                 metrics_->port());
    if (!config::is_loopback_host(config::host_of_address(config_.metrics_address()))) {
      spdlog::warn("hapticd: the metrics endpoint {} is not on loopback: anyone who reaches it "
                   "reads the counts, client names and hosts (no TLS, no tokens)",
                   config_.metrics_address());
    }
  }
  if (http_face_) {
    http_face_->start();
    spdlog::info("hapticd: the control plane over HTTP at {}://{}/haptic.v1.Haptic/ (docs/http.md)",
                 config_.security().has_tls() ? "https" : "http",
                 local_dial_address(config_.http_address(), http_face_->port()));
  }
  if (viewer_) {
    viewer_->start();
    spdlog::info("hapticd: viewer at http://{}/",
                 local_dial_address(config_.viewer_address(), viewer_->port()));
    if (!config::is_loopback_host(config::host_of_address(config_.viewer_address()))) {
      spdlog::warn("hapticd: the viewer {} is not on loopback: anyone who reaches it {} (plain HTTP)",
                   config_.viewer_address(),
                   config_.security().tokens_size() > 0 || !config_.security().tokens_file().empty()
                       ? "sees the bearer tokens its page sends"
                       : "reads the scene, the tool's motion and the statistics, client names and hosts");
    }
  }
  started_ = true;
  std::string devices = devices_.front().device->description().name;
  for (std::size_t i = 1; i < devices_.size(); ++i) {
    devices += " + port " + std::to_string(i) + ": " + devices_[i].device->description().name;
  }
  const int loop_cpu = loop_->config().cpu;
  spdlog::info("hapticd: {} at {} Hz ({}{}), gRPC {} (port {}, {}), UDP {} (port {})", devices,
               config_.loop_rate_hz(), v1::TimeMode_Name(config_.time_mode()),
               loop_cpu >= 0 ? ", loop on CPU " + std::to_string(loop_cpu) : std::string(),
               config_.grpc_address(), grpc_port_, security_summary_, config_.udp_address(),
               udp_.port());
  const bool remote = !config::is_loopback_host(config::host_of_address(config_.grpc_address())) ||
                     !config::is_loopback_host(config_.udp_address());
  if (remote && !config::secured_for_remote_access(config_.security())) {
    spdlog::warn("hapticd: serving a non-loopback address without {} (insecure_remote_access): "
                 "anyone who reaches it can {}",
                 config_.security().has_tls() ? "tokens" : "TLS",
                 config_.security().has_tls() ? "command forces"
                                              : "read the session keys and tokens on the wire");
  }
}

void Server::shutdown() {
  if (shut_down_.exchange(true)) return;
  // The force first: the output ramps to zero from the next tick, while the control plane closes
  // beside it. gRPC's shutdown may wait out its whole deadline (an idle client connection is
  // enough), and the hand must not be pushed all that time. Requests still in flight (a lockstep
  // Step among them) run against a loop whose output is ramping; the ramp is a gain on the
  // output, so nothing they add can push.
  events_.close();
  // No new connections; those open go on (with TLS the listener carries them) while gRPC's
  // shutdown finishes the calls in flight.
  if (listener_) listener_->stop_accepting();
  if (started_ && recorder_->active()) {
    v1::RecordedChange change;
    change.set_shutdown(true);
    recorder_->record(std::move(change));
  }
  std::thread control_plane_closer;
  if (grpc_server_) {
    control_plane_closer = std::thread([this] {
      grpc_server_->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(1));
    });
  }
  if (started_) {
    loop_->ramp_out_and_stop();
  } else {
    loop_->stop();
  }
  recorder_->stop("shutdown");  // the ramp-out's ticks included
  // The HTTP endpoints only read, so they go after the ramp: each stop waits for its thread's
  // next poll (up to 100 ms) and a reply in progress, which the force must not wait for.
  if (metrics_) metrics_->stop();
  if (viewer_) viewer_->stop();
  if (http_face_) http_face_->stop();
  if (control_plane_closer.joinable()) control_plane_closer.join();
  if (listener_) listener_->stop();
  // With the loop stopped, leave every device in its safe state (motors off, brakes on).
  {
    std::lock_guard devices_lock(devices_mutex_);
    for (const config::PortDevice& port : devices_) {
      port.device->enter_safe_state();
      port.device->stop();
    }
  }
  {
    std::lock_guard lock(housekeeping_mutex_);
    stopping_ = true;
  }
  housekeeping_wake_.notify_all();
  if (housekeeping_.joinable()) housekeeping_.join();
  if (replicator_) replicator_->stop();
  if (relay_) relay_->stop();
  udp_.stop();
  spdlog::info("hapticd: stopped after {} ticks", counters_.ticks.load());
}

grpc::Status Server::reset_lockstep(std::uint64_t session_id) {
  if (loop_->config().mode != runtime::TimeMode::kLockstep) {
    return {grpc::StatusCode::FAILED_PRECONDITION,
            "only a LOCKSTEP server can be reset; this one runs in real time"};
  }
  for (std::size_t i = 0; i < descriptions_.size(); ++i) {
    if (!descriptions_[i].simulated) {
      return {grpc::StatusCode::FAILED_PRECONDITION,
              "device port " + std::to_string(i) + " (" + descriptions_[i].name +
                  ") is hardware: only simulated devices can be put back as they started"};
    }
  }
  grpc::Status status;
  loop_->reset_lockstep([&](const std::function<void()>& restart_loop) {
    std::lock_guard lock(devices_mutex_);
    if (shut_down_) {
      status = {grpc::StatusCode::UNAVAILABLE, "the server is shutting down"};
      return false;
    }
    // Fresh devices first (making them can fail; nothing has changed yet).
    std::vector<config::PortDevice> fresh = config::make_devices(config_);
    const auto discard = [&fresh] {
      for (config::PortDevice& port : fresh) port.device->stop();
    };
    for (std::size_t i = 0; i < fresh.size(); ++i) {
      if (fresh[i].device->start() != runtime::DeviceStatus::kOk) {
        status = {grpc::StatusCode::INTERNAL, "device port " + std::to_string(i) + " failed to start again"};
        discard();
        return false;
      }
      fresh[i].simulated->set_hand(initial_hand_);
    }
    // Every datagram of the old ticks leaves before the ticks start again (a client reading its
    // socket after the reply finds them all there, on one host).
    if (!udp_.wait_sent_through(samples_.back()->newest(), std::chrono::seconds(1))) {
      status = {grpc::StatusCode::UNAVAILABLE, "the data plane did not send the last ticks within 1 s"};
      discard();
      return false;
    }
    // The scene's check, the restart and the new scene under the store's lock: no other
    // session's change lands in between (it would be stamped with the old tick count).
    status = scene_->reset(session_id, initial_scene_.objects, initial_scene_.fields, config_.initial_scene(),
                           [&] {
                             // A recording covers one run: the reset ends it, its samples written.
                             recorder_->stop("lockstep reset");
                             restart_loop();
                             for (config::PortDevice& port : devices_) port.device->stop();
                             devices_ = std::move(fresh);
                             runner_->replace_ports(
                                 federated(config::tick_ports(config_, devices_, ring_pointers(samples_), period_s_)));
                             for (const auto& ring : samples_) ring->restart();
                             sessions_.restart_ticks();
                           });
    if (!status.ok()) {
      discard();
      return false;
    }
    return true;
  });
  return status;
}

void Server::log_status() {
  const std::int64_t now_ns = runtime::monotonic_now_ns();
  const std::uint64_t ticks = counters_.ticks.load(std::memory_order_relaxed);
  const double seconds = static_cast<double>(now_ns - status_last_ns_) * 1e-9;
  const double rate = seconds > 0 ? static_cast<double>(ticks - status_last_ticks_) / seconds : 0.0;
  status_last_ns_ = now_ns;
  status_last_ticks_ = ticks;
  const runtime::LatenessSummary lateness = lateness_.summarize(runtime::monotonic_now_ns());
  spdlog::info(
      "status: rate {:.1f} Hz, lateness p50 {:.0f} us p99 {:.0f} us max {:.0f} us, overruns {}, "
      "clients {}, force faults {}",
      rate, lateness.p50_us, lateness.p99_us, lateness.max_us,
      counters_.overruns.load(std::memory_order_relaxed), sessions_.size(),
      counters_.force_faults.load(std::memory_order_relaxed));
}

void Server::housekeeping_loop() {
  using namespace std::chrono;
  constexpr auto kPeriod = milliseconds(10);
  const auto status_period = seconds(config_.status_period_s());
  auto next_status = steady_clock::now() + status_period;
  std::uint64_t faults_reported = 0;
  std::uint64_t device_faults_reported = 0;
  bool servo_end_reported = false;
  std::uint64_t housekeeping_rounds = 0;
  std::unique_lock lock(housekeeping_mutex_);
  while (!housekeeping_wake_.wait_for(lock, kPeriod, [this] { return stopping_; })) {
    for (const std::uint64_t id : sessions_.expire(steady_clock::now())) {
      leases_expired_.fetch_add(1, std::memory_order_relaxed);
      service_->end_session(id, v1::Event::LEASE_EXPIRED);
    }
    if (++housekeeping_rounds % 100 == 0) service_->end_sessions_of_expired_tokens();  // each second
    if (relay_ && housekeeping_rounds % 100 == 0) federation::flush_dds_log(steady_clock::now());  // counts said
    scene_->compact();
    if (const auto faults = counters_.force_faults.load(std::memory_order_relaxed);
        faults != faults_reported) {
      service_->publish_event(v1::Event::FORCE_FAULT, 0,
                              std::to_string(faults - faults_reported) +
                                  " non-finite forces replaced by zero");
      spdlog::warn("loop: {} non-finite forces replaced by zero", faults - faults_reported);
      faults_reported = faults;
    }
    if (const auto faults = counters_.device_errors.load(std::memory_order_relaxed);
        faults != device_faults_reported) {
      // The device's own words where it has them (a driver's last_error: "unplugged", ...).
      std::string why;
      std::lock_guard devices_lock(devices_mutex_);  // a lockstep reset replaces the devices
      for (std::size_t port = 0; port < devices_.size(); ++port) {
        if (std::string reason = devices_[port].device->fault_reason(); !reason.empty()) {
          why += (why.empty() ? "" : "; ") + std::string("device ") + std::to_string(port) + ": " + reason;
        }
      }
      service_->publish_event(v1::Event::DEVICE_FAULT, 0,
                              std::to_string(faults - device_faults_reported) +
                                  " ticks with a failed or non-finite device reading; zero force" +
                                  (why.empty() ? "" : " (" + why + ")"));
      spdlog::error("device: {} ticks with a failed or non-finite reading; zero force commanded{}",
                    faults - device_faults_reported, why.empty() ? "" : " (" + why + ")");
      device_faults_reported = faults;
    }
    if (!servo_end_reported && loop_->servo_failed()) {
      // Device-clocked: the driver's servo loop returned (or never ran), so no tick will come.
      servo_end_reported = true;
      service_->publish_event(v1::Event::DEVICE_FAULT, 0,
                              "the driver's servo loop ended on its own: the loop has stopped");
      spdlog::error("device 0: the driver's servo loop ended on its own; no more ticks");
    }
    if (status_period.count() > 0 && steady_clock::now() >= next_status) {
      next_status += status_period;
      log_status();
    }
  }
}

}  // namespace haptic::app
