#include "client_core.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <thread>

#include "conversions.hpp"
#include "status_mapping.hpp"

namespace haptic::detail {
namespace {

/// The host part of "host:port", "[v6]:port" or a gRPC target such as "dns:///host:port" or
/// "ipv4:host:port": the UDP data plane lives on the same host as the control plane.
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

void check_config(const ClientConfig& config) {
  if (config.server_address.empty()) throw InvalidArgumentError("server_address: must not be empty");
  if (config.client_name.empty() || config.client_name.size() > 64) {
    throw InvalidArgumentError("client_name: must be 1 to 64 characters");
  }
  if (config.rpc_timeout.count() <= 0) throw InvalidArgumentError("rpc_timeout: must be positive");
  if (config.heartbeat_period.count() <= 0) {
    throw InvalidArgumentError("heartbeat_period: must be positive");
  }
}

std::string read_pem(const char* field, const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) {
    throw InvalidArgumentError(std::string("tls.") + field + ": cannot read '" + path + "': " +
                               std::strerror(errno));
  }
  std::stringstream text;
  text << file.rdbuf();
  return text.str();
}

std::shared_ptr<grpc::Channel> make_channel(const ClientConfig& config) {
  if (!config.tls) {
    return grpc::CreateChannel(config.server_address, grpc::InsecureChannelCredentials());
  }
  const TlsOptions& tls = *config.tls;
  if (tls.ca_file.empty()) throw InvalidArgumentError("tls.ca_file: required with tls");
  if (tls.cert_file.empty() != tls.key_file.empty()) {
    throw InvalidArgumentError("tls.cert_file, tls.key_file: give both (mTLS) or neither");
  }
  grpc::SslCredentialsOptions options;
  options.pem_root_certs = read_pem("ca_file", tls.ca_file);
  if (!tls.cert_file.empty()) {
    options.pem_cert_chain = read_pem("cert_file", tls.cert_file);
    options.pem_private_key = read_pem("key_file", tls.key_file);
  }
  grpc::ChannelArguments arguments;
  if (!tls.server_name.empty()) arguments.SetSslTargetNameOverride(tls.server_name);
  return grpc::CreateCustomChannel(config.server_address, grpc::SslCredentials(options), arguments);
}

}  // namespace

void ClientCore::authenticate(grpc::ClientContext& context) const {
  if (!config_.token.empty()) context.AddMetadata("authorization", "Bearer " + config_.token);
  if (!session_secret_.empty()) context.AddMetadata(io::kSessionSecretMetadataKey, session_secret_);
}

void ClientCore::throw_status(const grpc::Status& status, const char* name) {
  throw_if_failed(status, name);
}

ClientCore::ClientCore(ClientConfig config) : config_(std::move(config)) {
  check_config(config_);
  channel_ = make_channel(config_);
  stub_ = v1::Haptic::NewStub(channel_);

  v1::OpenSessionRequest open;
  open.set_client_name(config_.client_name);
  open.set_api_version(kApiVersion);
  open.set_device_index(config_.device_index);
  const auto opened = call<v1::OpenSessionRequest, v1::OpenSessionResponse>(
      "OpenSession", &v1::Haptic::Stub::OpenSession, open);
  session_id_ = opened.session_id();
  session_secret_ = opened.session_secret();
  device_info_ = from_proto(opened.device());
  lease_timeout_ = std::chrono::milliseconds(opened.lease_timeout_ms());
  if (opened.udp_key().size() != 16) {
    throw Error(ErrorCode::kInternal, "OpenSession: server sent a udp_key that is not 16 bytes");
  }
  wire::Key key{};
  std::copy(opened.udp_key().begin(), opened.udp_key().end(), key.begin());
  try {
    udp_ = std::make_unique<UdpLink>(host_of(config_.server_address),
                                     static_cast<std::uint16_t>(opened.udp_port()), session_id_, key,
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
}

ClientCore::~ClientCore() {
  stop_events();
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
  if (!callback) return;
  auto context = std::make_unique<grpc::ClientContext>();
  authenticate(*context);
  v1::WatchEventsRequest request;
  request.set_session_id(session_id_);
  // Opened here, so that a refusal the server gives at once (no session, too many streams)
  // reaches the caller as an error rather than a silent end.
  std::unique_ptr<grpc::ClientReader<v1::Event>> reader = stub_->WatchEvents(context.get(), request);
  v1::Event first;
  if (!reader->Read(&first)) throw_status(reader->Finish(), "WatchEvents");
  {
    std::lock_guard lock(events_mutex_);
    events_context_ = std::move(context);
  }
  events_thread_ = std::thread(
      [reader = std::move(reader), first = std::move(first), callback = std::move(callback)]() mutable {
        v1::Event event = std::move(first);
        do {
          callback(event);
        } while (reader->Read(&event));
        reader->Finish();  // cancelled, or the session ended: the stream is over either way
      });
}

void ClientCore::subscribe(std::uint32_t decimation) {
  v1::SubscribeStateRequest request;
  request.set_session_id(session_id_);
  request.set_decimation(decimation);
  // The server sends state to where heartbeats come from. Until one has arrived it has no address,
  // so resend and ask again for up to rpc_timeout: a firewall or NAT that eats our UDP becomes a
  // clear error here instead of a silent stream.
  const auto give_up = std::chrono::steady_clock::now() + config_.rpc_timeout;
  for (;;) {
    const auto reply = call<v1::SubscribeStateRequest, v1::SubscribeStateResponse>(
        "SubscribeState", &v1::Haptic::Stub::SubscribeState, request);
    if (decimation == 0 || reply.udp_endpoint_known()) return;
    if (std::chrono::steady_clock::now() > give_up) {
      throw ConnectionError("SubscribeState: UDP heartbeats from this client do not reach the "
                            "server's data-plane port (a firewall or NAT dropping UDP?)");
    }
    udp_->send_heartbeat_soon();
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

void ClientCore::close_session() {
  if (closed_) return;
  closed_ = true;
  udp_.reset();
  v1::SessionRef ref;
  ref.set_session_id(session_id_);
  call<v1::SessionRef, v1::Empty>("CloseSession", &v1::Haptic::Stub::CloseSession, ref);
}

v1::ItemRef ClientCore::create_object(const v1::Object& object) {
  v1::CreateObjectRequest request;
  request.set_session_id(session_id_);
  *request.mutable_object() = object;
  return call<v1::CreateObjectRequest, v1::ItemRef>("CreateObject", &v1::Haptic::Stub::CreateObject,
                                                    request);
}

v1::ItemRef ClientCore::update_object(std::uint64_t id, const v1::Object& object) {
  v1::UpdateObjectRequest request;
  request.set_session_id(session_id_);
  request.set_object_id(id);
  *request.mutable_object() = object;
  return call<v1::UpdateObjectRequest, v1::ItemRef>("UpdateObject",
                                                    &v1::Haptic::Stub::UpdateObject, request);
}

void ClientCore::delete_object(std::uint64_t id) {
  v1::DeleteRequest request;
  request.set_session_id(session_id_);
  request.set_id(id);
  call<v1::DeleteRequest, v1::Empty>("DeleteObject", &v1::Haptic::Stub::DeleteObject, request);
}

std::uint64_t ClientCore::create_field(const v1::Field& field) {
  v1::CreateFieldRequest request;
  request.set_session_id(session_id_);
  *request.mutable_field() = field;
  return call<v1::CreateFieldRequest, v1::ItemRef>("CreateField", &v1::Haptic::Stub::CreateField,
                                                   request)
      .id();
}

void ClientCore::update_field(std::uint64_t id, const v1::Field& field) {
  v1::UpdateFieldRequest request;
  request.set_session_id(session_id_);
  request.set_field_id(id);
  *request.mutable_field() = field;
  call<v1::UpdateFieldRequest, v1::Empty>("UpdateField", &v1::Haptic::Stub::UpdateField, request);
}

void ClientCore::delete_field(std::uint64_t id) {
  v1::DeleteRequest request;
  request.set_session_id(session_id_);
  request.set_id(id);
  call<v1::DeleteRequest, v1::Empty>("DeleteField", &v1::Haptic::Stub::DeleteField, request);
}

v1::ApplySceneResponse ClientCore::apply_scene(const v1::Scene& scene) {
  v1::ApplySceneRequest request;
  request.set_session_id(session_id_);
  *request.mutable_scene() = scene;
  auto reply = call<v1::ApplySceneRequest, v1::ApplySceneResponse>(
      "ApplyScene", &v1::Haptic::Stub::ApplyScene, request);
  if (reply.object_ids_size() != scene.objects_size() ||
      reply.field_ids_size() != scene.fields_size()) {
    throw Error(ErrorCode::kInternal, "ApplyScene: the server returned " +
                                          std::to_string(reply.object_ids_size()) + " object and " +
                                          std::to_string(reply.field_ids_size()) +
                                          " field ids for " + std::to_string(scene.objects_size()) +
                                          " objects and " + std::to_string(scene.fields_size()) +
                                          " fields");
  }
  ++scene_generation_;
  return reply;
}

}  // namespace haptic::detail
