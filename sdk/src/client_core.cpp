#include "client_core.hpp"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <optional>
#include <sstream>
#include <thread>

#include "haptic/io/loopback.hpp"
#include "haptic/io/session_id.hpp"
#include "conversions.hpp"
#include "status_mapping.hpp"
#include "tls_diagnosis.hpp"

namespace haptic::detail {

std::string host_of(std::string address) {
  for (const char* scheme : {"dns:///", "dns:", "ipv4:", "ipv6:"}) {
    const std::string prefix(scheme);
    if (address.rfind(prefix, 0) == 0) {
      address = address.substr(prefix.size());
      break;
    }
  }
  if (!address.empty() && address.front() == '[') {
    const auto end = address.find(']');
    return end == std::string::npos ? address : address.substr(1, end - 1);
  }
  const auto colon = address.rfind(':');
  return colon == std::string::npos ? address : address.substr(0, colon);
}

bool stays_on_this_host(const std::string& target) {
  // A Unix socket (by path or abstract name) is this machine's.
  for (const char* local : {"unix:", "unix-abstract:"}) {
    if (target.rfind(local, 0) == 0) return true;
  }
  // An address list (ipv4:a:p,b:p or ipv6:[a]:p,[b]:p) stays only if every member does; gRPC
  // may pick any of them.
  for (const char* scheme : {"ipv4:", "ipv6:"}) {
    const std::string prefix(scheme);
    if (target.rfind(prefix, 0) != 0 || target.find(',') == std::string::npos) continue;
    std::size_t start = prefix.size();
    for (;;) {
      const std::size_t comma = target.find(',', start);
      const std::string member = target.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
      if (member.empty() || !io::is_loopback_literal(host_of(prefix + member))) return false;
      if (comma == std::string::npos) return true;
      start = comma + 1;
    }
  }
  // dns:host, dns:///host and a bare host: the host must be a loopback literal. dns://authority/…
  // (another resolver) keeps its "//authority/" in the host and so is never loopback.
  return io::is_loopback_literal(host_of(target));
}

namespace {
/// How an SDK user sets what a TLS diagnosis may tell them to change: ClientConfig's fields, with
/// the options of hapticctl and touch_wall.
const TlsSettingNames& sdk_setting_names() {
  static const TlsSettingNames names{
      "turn it on with ClientConfig::tls, giving the CA that signed its certificate (--ca)",
      "drop ClientConfig::tls (leave out --ca)",
      "tls.ca_file (--ca)",
      "tls.cert_file (--cert)",
      "tls.key_file (--key)",
      "connect by one of them, or give one with tls.server_name (--server-name)"};
  return names;
}
}  // namespace

std::chrono::milliseconds next_reconnect_delay(std::chrono::milliseconds previous,
                                               std::chrono::milliseconds outage, const ClientConfig& config) {
  const auto minimum = config.reconnect_backoff_min;
  const auto maximum = std::max(config.reconnect_backoff_max, minimum);
  const auto doubled = previous.count() <= 0 ? minimum : std::min(previous * 2, maximum);
  if (outage < kFastReconnectWindow) return std::min(doubled, std::max(kFastReconnectPeriod, minimum));
  return doubled;
}

namespace {

/// The port of ClientConfig::udp_address ("host:port" or "[v6]:port").
std::uint16_t udp_port_of(const std::string& address) {
  const auto colon = address.rfind(':');
  const std::string digits = colon == std::string::npos ? "" : address.substr(colon + 1);
  const bool numeric = !digits.empty() && digits.size() <= 5 &&
                       std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; });
  const unsigned long port = numeric ? std::stoul(digits) : 0;
  if (!numeric || port == 0 || port > 65535 || colon == 0) {
    throw InvalidArgumentError("ClientConfig: udp_address: '" + address +
                               "' is not host:port with a port 1 to 65535");
  }
  return static_cast<std::uint16_t>(port);
}

void check_config(const ClientConfig& config) {
  if (config.server_address.empty()) throw InvalidArgumentError("ClientConfig: server_address: must not be empty");
  if (!config.token.empty() && !config.tls && !stays_on_this_host(config.server_address)) {
    if (!config.allow_plaintext_token) {
      throw InvalidArgumentError(
          "ClientConfig: token: would be sent in clear to '" + config.server_address +
          "', where anyone on the network can read it: give tls (TlsOptions with the server's CA), "
          "or set allow_plaintext_token on a network you trust");
    }
    std::fprintf(stderr, "haptic: warning: sending the bearer token in clear to '%s' "
                 "(allow_plaintext_token)\n", config.server_address.c_str());
  }
  if (config.client_name.empty() || config.client_name.size() > 64) {
    throw InvalidArgumentError("ClientConfig: client_name: must be 1 to 64 characters");
  }
  if (config.rpc_timeout.count() <= 0) throw InvalidArgumentError("ClientConfig: rpc_timeout: must be positive");
  if (config.heartbeat_period.count() <= 0) {
    throw InvalidArgumentError("ClientConfig: heartbeat_period: must be positive");
  }
  if (!config.udp_address.empty()) udp_port_of(config.udp_address);  // throws if it names none
  if (config.reconnect_backoff_min.count() <= 0 ||
      config.reconnect_backoff_max < config.reconnect_backoff_min) {
    throw InvalidArgumentError(
        "ClientConfig: reconnect_backoff_min, reconnect_backoff_max: must be positive, the max at "
        "least the min");
  }
}

std::string read_pem(const char* field, const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) {
    throw InvalidArgumentError(std::string("ClientConfig: tls.") + field + ": cannot read '" + path + "': " +
                               std::strerror(errno));
  }
  std::stringstream text;
  text << file.rdbuf();
  return text.str();
}

std::shared_ptr<grpc::Channel> make_channel(const ClientConfig& config) {
  quiet_grpc_log_unless_asked();  // the SDK's errors say it in the user's terms
  grpc::ChannelArguments arguments;
  if (!config.tls) {
    return grpc::CreateCustomChannel(config.server_address, grpc::InsecureChannelCredentials(),
                                     arguments);
  }
  const TlsOptions& tls = *config.tls;
  if (tls.ca_file.empty()) throw InvalidArgumentError("ClientConfig: tls.ca_file: required with tls");
  if (tls.cert_file.empty() != tls.key_file.empty()) {
    throw InvalidArgumentError("ClientConfig: tls.cert_file, tls.key_file: give both (mTLS) or neither");
  }
  grpc::SslCredentialsOptions options;
  options.pem_root_certs = read_pem("ca_file", tls.ca_file);
  if (!tls.cert_file.empty()) {
    options.pem_cert_chain = read_pem("cert_file", tls.cert_file);
    options.pem_private_key = read_pem("key_file", tls.key_file);
  }
  if (!tls.server_name.empty()) arguments.SetSslTargetNameOverride(tls.server_name);
  return grpc::CreateCustomChannel(config.server_address, grpc::SslCredentials(options), arguments);
}

}  // namespace

void ClientCore::authenticate(grpc::ClientContext& context) const {
  if (!config_.token.empty()) context.AddMetadata("authorization", "Bearer " + config_.token);
  std::lock_guard lock(identity_mutex_);
  if (!session_secret_.empty()) context.AddMetadata(io::kSessionSecretMetadataKey, session_secret_);
}

void ClientCore::throw_status(const grpc::Status& status, const char* name) {
  throw_if_failed(status, name);
}

v1::OpenSessionResponse ClientCore::open_session() {
  v1::OpenSessionRequest open;
  open.set_client_name(config_.client_name);
  open.set_api_version(kApiVersion);
  open.set_device_index(config_.device_index);
  auto opened = call<v1::OpenSessionRequest, v1::OpenSessionResponse>(
      "OpenSession", &v1::Haptic::Stub::OpenSession, open);
  if (opened.udp_key().size() != 16) {
    throw Error(ErrorCode::kInternal, "OpenSession: server sent a udp_key that is not 16 bytes");
  }
  return opened;
}

v1::OpenSessionResponse ClientCore::open_session_saying_why() {
  try {
    return open_session();
  } catch (const ConnectionError& error) {
    // gRPC reports a TLS mismatch as a reset, a verify failure or a decryption error; one
    // handshake of our own says which setting to change.
    TlsAttempt attempt{config_.server_address, config_.tls.has_value(), {}, {}, {}, {}, sdk_setting_names()};
    if (config_.tls) {
      attempt.ca_file = config_.tls->ca_file;
      attempt.cert_file = config_.tls->cert_file;
      attempt.key_file = config_.tls->key_file;
      attempt.server_name = config_.tls->server_name;
    }
    const std::string why = diagnose_tls_mismatch(
        attempt, std::min<std::chrono::milliseconds>(config_.rpc_timeout, std::chrono::seconds(1)));
    if (why.empty() && std::string_view(error.what()).find("Connection refused") != std::string_view::npos) {
      throw ConnectionError("cannot connect to " + config_.server_address +
                            ": nothing listens there (is hapticd running, and on that port?) [gRPC: " +
                            error.what() + "]");
    }
    if (why.empty()) throw;
    // The cause and its fix first; gRPC's own words after, for a search or a bug report.
    throw ConnectionError("cannot connect to " + config_.server_address + ": " + why + " [gRPC: " +
                          error.what() + "]");
  }
}

namespace {
wire::Key key_of(const v1::OpenSessionResponse& opened) {
  wire::Key key{};
  std::copy(opened.udp_key().begin(), opened.udp_key().end(), key.begin());
  return key;
}
}  // namespace

std::string ClientCore::udp_host() const {
  return host_of(config_.udp_address.empty() ? config_.server_address : config_.udp_address);
}

std::uint16_t ClientCore::udp_port(const v1::OpenSessionResponse& opened) const {
  return config_.udp_address.empty() ? static_cast<std::uint16_t>(opened.udp_port())
                                     : udp_port_of(config_.udp_address);
}

ClientCore::ClientCore(ClientConfig config) : config_(std::move(config)) {
  check_config(config_);
  stub_ = v1::Haptic::NewStub(make_channel(config_));

  const v1::OpenSessionResponse opened = open_session_saying_why();
  session_id_ = opened.session_id();
  {
    std::lock_guard lock(identity_mutex_);
    session_secret_ = opened.session_secret();
  }
  device_info_ = from_proto(opened.device());
  lease_timeout_ = std::chrono::milliseconds(opened.lease_timeout_ms());
  try {
    udp_ = std::make_unique<UdpLink>(udp_host(), udp_port(opened), session_id_, key_of(opened),
                                     config_.heartbeat_period);
    if (config_.state_decimation > 0) subscribe(config_.state_decimation);
  } catch (...) {
    // Do not leave a half-open session holding a lease; report the first failure, not this one.
    try {
      close_session();
    } catch (...) {
    }
    throw;
  }
  if (config_.reconnect) supervisor_ = std::thread([this] { supervise(); });
}

ClientCore::~ClientCore() {
  stop_supervisor();
  stop_events();
  end_observer_watches();
  try {
    close_session();
  } catch (...) {
    // Destructors never throw; the server's lease cleans up what a failed close leaves.
  }
}

void ClientCore::stop_events() {
  {
    std::lock_guard lock(events_mutex_);
    if (events_context_) events_context_->TryCancel();
  }
  if (events_thread_.joinable()) events_thread_.join();
  std::lock_guard lock(events_mutex_);
  events_context_.reset();
}

void ClientCore::watch_events(std::function<void(const v1::Event&)> callback) {
  stop_events();
  {
    std::lock_guard lock(events_mutex_);
    events_callback_ = callback;  // resumed after a reconnection
  }
  if (!callback) return;
  Watch watch = open_watch(std::move(callback));
  {
    std::lock_guard lock(events_mutex_);
    events_context_ = std::move(watch.context);
  }
  events_thread_ = std::move(watch.thread);
}

ClientCore::Watch ClientCore::open_watch(std::function<void(const v1::Event&)> callback) {
  Watch watch;
  watch.context = std::make_unique<grpc::ClientContext>();
  authenticate(*watch.context);
  v1::WatchEventsRequest request;
  request.set_session_id(session_id_);
  // Opened here, so that a refusal the server gives at once (no session, too many streams)
  // reaches the caller as an error rather than a silent end.
  std::unique_ptr<grpc::ClientReader<v1::Event>> reader =
      stub()->WatchEvents(watch.context.get(), request);
  v1::Event first;
  if (!reader->Read(&first)) throw_status(reader->Finish(), "WatchEvents");
  watch.thread = std::thread(
      [reader = std::move(reader), first = std::move(first), callback = std::move(callback)]() mutable {
        v1::Event event = std::move(first);
        do {
          callback(event);
        } while (reader->Read(&event));
        reader->Finish();  // cancelled, or the session ended: the stream is over either way
      });
  return watch;
}

void ClientCore::end_watch(Watch& watch) {
  if (watch.context) watch.context->TryCancel();
  if (watch.thread.joinable()) watch.thread.join();
  watch.context.reset();
}

std::uint64_t ClientCore::observe(std::shared_ptr<ReceiveObserver> observer, bool events) {
  Observer entry{observer, events, {}};
  if (events) {
    entry.watch = open_watch([observer](const v1::Event& event) { observer->on_event(from_proto(event)); });
  }
  std::uint64_t id = 0;
  {
    std::lock_guard lock(observers_mutex_);
    id = next_observer_id_++;
    observers_.emplace(id, std::move(entry));
  }
  udp_->add_tap(id, std::move(observer));
  return id;
}

void ClientCore::unobserve(std::uint64_t id) noexcept {
  if (udp_) udp_->remove_tap(id);
  std::optional<Observer> removed;
  {
    std::lock_guard lock(observers_mutex_);  // waits out a connection change being told
    const auto found = observers_.find(id);
    if (found == observers_.end()) return;
    removed = std::move(found->second);
    observers_.erase(found);
  }
  end_watch(removed->watch);
}

void ClientCore::resume_observer_watches() {
  std::lock_guard lock(observers_mutex_);
  for (auto& [id, entry] : observers_) {
    if (!entry.events) continue;
    end_watch(entry.watch);
    try {
      entry.watch = open_watch(
          [observer = entry.observer](const v1::Event& event) { observer->on_event(from_proto(event)); });
    } catch (const Error&) {
      // As the application's own stream: off until the observer is attached again.
    }
  }
}

void ClientCore::end_observer_watches() {
  std::lock_guard lock(observers_mutex_);
  for (auto& [id, entry] : observers_) end_watch(entry.watch);
}

void ClientCore::subscribe(std::uint32_t decimation) {
  // A stream started again after a stop is numbered from 1 again.
  if (decimation > 0 && decimation_ == 0) udp_->new_subscription();
  decimation_ = decimation;
  v1::SubscribeStateRequest request;
  request.set_session_id(session_id_);
  request.set_decimation(decimation);
  if (config_.lockstep_flow_control) request.set_ack_window(udp_->ack_window_capacity());
  // The server sends state to where heartbeats come from. Until one has arrived it has no address,
  // so resend and ask again for up to rpc_timeout: a firewall or NAT that eats our UDP becomes a
  // clear error here instead of a silent stream.
  const auto give_up = std::chrono::steady_clock::now() + config_.rpc_timeout;
  for (;;) {
    const auto reply = call<v1::SubscribeStateRequest, v1::SubscribeStateResponse>(
        "SubscribeState", &v1::Haptic::Stub::SubscribeState, request);
    udp_->set_ack_window(reply.ack_window());
    if (decimation == 0 || reply.udp_endpoint_known()) return;
    if (std::chrono::steady_clock::now() > give_up) {
      throw ConnectionError("SubscribeState: UDP heartbeats from this client do not reach the "
                            "server's data-plane port (a firewall or NAT dropping UDP?)");
    }
    udp_->send_heartbeat_soon();
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

bool ClientCore::on_callback_thread() const {
  const auto self = std::this_thread::get_id();
  {
    std::lock_guard lock(events_mutex_);  // watch_events replaces the thread
    if (self == events_thread_.get_id()) return true;
  }
  return self == supervisor_.get_id() || (udp_ && udp_->on_callback_thread());
}

void ClientCore::close_session() {
  stop_supervisor();
  if (closed_) return;
  closed_ = true;
  udp_.reset();
  // The server ended the session itself (an admin, an expired token): nothing is left to close.
  if (connection_state_ == ConnectionChange::State::kEnded) return;
  v1::SessionRef ref;
  ref.set_session_id(session_id_);
  call<v1::SessionRef, v1::Empty>("CloseSession", &v1::Haptic::Stub::CloseSession, ref);
}

std::uint64_t ClientCore::remember(std::uint64_t id, const v1::Object* object, const v1::Field* field) {
  Item item;
  item.is_object = object != nullptr;
  if (object != nullptr) item.object = *object;
  if (field != nullptr) item.field = *field;
  item.server_id = id;
  std::lock_guard lock(items_mutex_);
  const std::uint64_t key = next_key_++;
  items_.emplace(key, std::move(item));
  return key;
}

std::uint64_t ClientCore::server_id(std::uint64_t key) const {
  std::lock_guard lock(items_mutex_);
  const auto found = items_.find(key);
  return found == items_.end() ? 0 : found->second.server_id;
}

std::uint64_t ClientCore::require_server_id(std::uint64_t key, const char* call) const {
  std::lock_guard lock(items_mutex_);
  const auto found = items_.find(key);
  if (found == items_.end()) throw NotFoundError(std::string(call) + ": the client no longer holds this item");
  if (found->second.server_id == 0) {
    throw NotFoundError(std::string(call) + ": the item was not restored when the session was reopened: " +
                        found->second.lost_reason);
  }
  return found->second.server_id;
}

v1::ItemRef ClientCore::send_create(const v1::Object* object, const v1::Field* field) {
  if (object != nullptr) {
    v1::CreateObjectRequest request;
    request.set_session_id(session_id_);
    *request.mutable_object() = *object;
    return call<v1::CreateObjectRequest, v1::ItemRef>("CreateObject",
                                                      &v1::Haptic::Stub::CreateObject, request);
  }
  v1::CreateFieldRequest request;
  request.set_session_id(session_id_);
  *request.mutable_field() = *field;
  return call<v1::CreateFieldRequest, v1::ItemRef>("CreateField", &v1::Haptic::Stub::CreateField,
                                                   request);
}

ClientCore::Created ClientCore::create_object(const v1::Object& object) {
  Created made;
  made.ref = send_create(&object, nullptr);
  made.key = remember(made.ref.id(), &object, nullptr);
  return made;
}

v1::ItemRef ClientCore::update_object(std::uint64_t key, const v1::Object& object) {
  v1::UpdateObjectRequest request;
  request.set_session_id(session_id_);
  request.set_object_id(require_server_id(key, "UpdateObject"));
  *request.mutable_object() = object;
  auto reply = call<v1::UpdateObjectRequest, v1::ItemRef>("UpdateObject",
                                                          &v1::Haptic::Stub::UpdateObject, request);
  std::lock_guard lock(items_mutex_);
  if (const auto found = items_.find(key); found != items_.end()) found->second.object = object;
  return reply;
}

void ClientCore::delete_object(std::uint64_t key) {
  v1::DeleteRequest request;
  request.set_session_id(session_id_);
  request.set_id(require_server_id(key, "DeleteObject"));
  call<v1::DeleteRequest, v1::Empty>("DeleteObject", &v1::Haptic::Stub::DeleteObject, request);
  std::lock_guard lock(items_mutex_);
  items_.erase(key);
}

ClientCore::Created ClientCore::create_field(const v1::Field& field) {
  Created made;
  made.ref = send_create(nullptr, &field);
  made.key = remember(made.ref.id(), nullptr, &field);
  return made;
}

void ClientCore::update_field(std::uint64_t key, const v1::Field& field) {
  v1::UpdateFieldRequest request;
  request.set_session_id(session_id_);
  request.set_field_id(require_server_id(key, "UpdateField"));
  *request.mutable_field() = field;
  call<v1::UpdateFieldRequest, v1::Empty>("UpdateField", &v1::Haptic::Stub::UpdateField, request);
  std::lock_guard lock(items_mutex_);
  if (const auto found = items_.find(key); found != items_.end()) found->second.field = field;
}

void ClientCore::delete_field(std::uint64_t key) {
  v1::DeleteRequest request;
  request.set_session_id(session_id_);
  request.set_id(require_server_id(key, "DeleteField"));
  call<v1::DeleteRequest, v1::Empty>("DeleteField", &v1::Haptic::Stub::DeleteField, request);
  std::lock_guard lock(items_mutex_);
  items_.erase(key);
}

void ClientCore::reset() {
  v1::SessionRef ref;
  ref.set_session_id(session_id_);
  const auto reply = call<v1::SessionRef, v1::ResetResponse>("Reset", &v1::Haptic::Stub::Reset, ref);
  {
    std::lock_guard lock(items_mutex_);
    items_.clear();  // the server removed them all
  }
  ++scene_generation_;
  note_run(reply.run());  // unless a step of ours has seen the new run already
}

void ClientCore::note_run(std::uint64_t run) {
  std::lock_guard lock(run_mutex_);
  // The old run's datagrams all left the server before its reset finished, which was before
  // this step began: restart_ticks() reads what has reached the socket (on one host, all of
  // them) before forgetting, and drops any numbered as one seen already.
  if (known_run_ != run) udp_->restart_ticks();
  known_run_ = run;
}

ClientCore::Applied ClientCore::apply_scene(const v1::Scene& scene) {
  v1::ApplySceneRequest request;
  request.set_session_id(session_id_);
  *request.mutable_scene() = scene;
  Applied applied;
  applied.reply = call<v1::ApplySceneRequest, v1::ApplySceneResponse>(
      "ApplyScene", &v1::Haptic::Stub::ApplyScene, request);
  const v1::ApplySceneResponse& reply = applied.reply;
  if (reply.object_ids_size() != scene.objects_size() ||
      reply.field_ids_size() != scene.fields_size()) {
    throw Error(ErrorCode::kInternal, "ApplyScene: the server returned " +
                                          std::to_string(reply.object_ids_size()) + " object and " +
                                          std::to_string(reply.field_ids_size()) +
                                          " field ids for " + std::to_string(scene.objects_size()) +
                                          " objects and " + std::to_string(scene.fields_size()) +
                                          " fields");
  }
  {
    std::lock_guard lock(items_mutex_);
    items_.clear();  // the server replaced every item of the session, released ones included
  }
  for (int i = 0; i < scene.objects_size(); ++i) {
    applied.object_keys.push_back(remember(reply.object_ids(i), &scene.objects(i), nullptr));
  }
  for (int i = 0; i < scene.fields_size(); ++i) {
    applied.field_keys.push_back(remember(reply.field_ids(i), nullptr, &scene.fields(i)));
  }
  ++scene_generation_;
  return applied;
}

// ---- connection supervision ----

void ClientCore::set_heartbeats_enabled(bool enabled) {
  heartbeats_enabled_ = enabled;
  udp_->set_heartbeats_enabled(enabled);
}

ReceiveCounters ClientCore::counters() const {
  ReceiveCounters out = udp_->counters();
  out.reconnects = reconnects_.load();
  return out;
}

void ClientCore::on_connection(std::function<void(const ConnectionChange&)> callback) {
  std::lock_guard lock(connection_mutex_);
  connection_callback_ = std::move(callback);
}

void ClientCore::announce(ConnectionChange change) {
  connection_state_ = change.state;
  {
    std::lock_guard lock(connection_mutex_);
    if (connection_callback_) connection_callback_(change);
  }
  std::lock_guard lock(observers_mutex_);
  for (const auto& [id, entry] : observers_) entry.observer->on_connection(change);
}

void ClientCore::stop_supervisor() {
  {
    std::lock_guard lock(supervisor_mutex_);
    supervisor_stop_ = true;
  }
  supervisor_wake_.notify_all();
  if (supervisor_.joinable()) supervisor_.join();
}

bool ClientCore::supervisor_wait(std::chrono::milliseconds duration) {
  std::unique_lock lock(supervisor_mutex_);
  return !supervisor_wake_.wait_for(lock, duration, [this] { return supervisor_stop_; });
}

void ClientCore::supervise() {
  const auto period = std::clamp(lease_timeout_ / 4, std::chrono::milliseconds(20),
                                 std::chrono::milliseconds(500));
  while (supervisor_wait(period)) {
    if (!heartbeats_enabled_) continue;  // playing a vanished client: let the lease run out
    std::string why;
    const Probe state = probe(why);
    if (state == Probe::kEnded) {
      announce({ConnectionChange::State::kEnded, session_id_, false, 0, why, {}});
      return;
    }
    if (state != Probe::kAlive && !recover(std::move(why))) return;
  }
}

ClientCore::Probe ClientCore::probe(std::string& why) {
  // Datagrams within half a lease: the server holds the session and reaches us.
  if (const auto heard = udp_->last_heard();
      heard && std::chrono::steady_clock::now() - *heard < lease_timeout_ / 2) {
    return Probe::kAlive;
  }
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() +
                       std::min<std::chrono::milliseconds>(config_.rpc_timeout, lease_timeout_ / 2));
  authenticate(context);
  v1::SessionRef ref;
  ref.set_session_id(session_id_);
  v1::DeviceInfo ignored;
  const grpc::Status status = stub()->GetDeviceInfo(&context, ref, &ignored);
  switch (status.error_code()) {
    case grpc::StatusCode::NOT_FOUND:
      why = "the server no longer knows session " + io::format_session_id(session_id_) + ": " +
            status.error_message();
      return Probe::kSessionGone;
    case grpc::StatusCode::UNAVAILABLE:
    case grpc::StatusCode::DEADLINE_EXCEEDED:
    case grpc::StatusCode::CANCELLED:
      why = "the server does not answer: " + status.error_message();
      return Probe::kUnreachable;
    case grpc::StatusCode::PERMISSION_DENIED:  // every role may ask this: the session was ended
    case grpc::StatusCode::UNAUTHENTICATED:    // the token expired: no reconnection would help
      why = status.error_message();
      return Probe::kEnded;
    default:
      return Probe::kAlive;  // answering (a refusal a reconnection would not change counts too)
  }
}

bool ClientCore::recover(std::string why) {
  const auto lost_at = std::chrono::steady_clock::now();
  announce({ConnectionChange::State::kLost, session_id_, false, 0, why, {}});
  std::chrono::milliseconds backoff{0};
  bool gone = false;
  for (;;) {
    std::string now_why;
    // A fresh channel for each try: gRPC's own reconnection backs off from 1 s up to minutes
    // (and a channel that saw the server go kept failing for 4.5 s after it was back here).
    {
      auto fresh = v1::Haptic::NewStub(make_channel(config_));
      std::lock_guard lock(identity_mutex_);
      stub_ = std::move(fresh);
    }
    const Probe state = gone ? Probe::kSessionGone : probe(now_why);
    if (state == Probe::kEnded) {
      announce({ConnectionChange::State::kEnded, session_id_, false, 0, now_why, {}});
      return false;
    }
    ConnectionChange resumed{ConnectionChange::State::kResumed, 0, false, 0, {}, {}};
    bool done = state == Probe::kAlive;
    if (state == Probe::kSessionGone) {
      gone = true;  // from here on only a new session helps
      try {
        reopen();
        done = true;
        resumed.new_session = true;
        std::lock_guard lock(items_mutex_);
        for (const auto& [key, item] : items_) resumed.items_not_restored += item.server_id == 0 ? 1 : 0;
      } catch (const std::exception& error) {
        now_why = error.what();
      }
    }
    if (done) {
      resumed.session_id = session_id_;
      resumed.outage = std::chrono::duration_cast<std::chrono::milliseconds>(
          std::chrono::steady_clock::now() - lost_at);
      resumed.reason = "after " + std::to_string(resumed.outage.count()) + " ms";
      // What the stream would have carried meanwhile (an estimate: the session's own gaps are
      // counted from its sequence numbers).
      if (const std::uint32_t decimation = decimation_.load(); decimation > 0 && resumed.new_session) {
        udp_->count_lost(static_cast<std::uint64_t>(
            std::chrono::duration<double>(resumed.outage).count() * device_info_.loop_rate_hz /
            decimation));
      }
      ++reconnects_;
      announce(resumed);
      return true;
    }
    backoff = next_reconnect_delay(backoff, std::chrono::duration_cast<std::chrono::milliseconds>(
                                                std::chrono::steady_clock::now() - lost_at),
                                   config_);
    if (!supervisor_wait(backoff)) return false;
  }
}

void ClientCore::reopen() {
  const v1::OpenSessionResponse opened = open_session();
  session_id_ = opened.session_id();
  {
    std::lock_guard lock(identity_mutex_);
    session_secret_ = opened.session_secret();
  }
  udp_->rebind(udp_port(opened), opened.session_id(), key_of(opened));
  {
    // Every item again, in the order they were made; one the new server refuses is kept with
    // the reason (its handle's calls say it), the others go on.
    std::lock_guard lock(items_mutex_);
    for (auto& [key, item] : items_) {
      try {
        item.server_id = send_create(item.is_object ? &item.object : nullptr,
                                     item.is_object ? nullptr : &item.field)
                             .id();
      } catch (const Error& error) {
        item.server_id = 0;
        item.lost_reason = error.what();
      }
    }
  }
  if (const std::uint32_t decimation = decimation_.load(); decimation > 0) {
    try {
      subscribe(decimation);
    } catch (const Error&) {
      // The session is open and holds its items; the stream stays off until subscribe() is
      // called again (a quiet stream alone is no loss: a lockstep server sends nothing unstepped).
    }
  }
  std::function<void(const v1::Event&)> events;
  {
    std::lock_guard lock(events_mutex_);
    events = events_callback_;
  }
  if (events) {
    try {
      watch_events(std::move(events));
    } catch (const Error&) {
    }
  }
  resume_observer_watches();
}

}  // namespace haptic::detail
