#include "app/health_check.hpp"

#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/grpcpp.h>

#include <algorithm>
#include <fstream>
#include <future>
#include <regex>
#include <sstream>
#include <vector>

#include "tls_diagnosis.hpp"

namespace haptic::app {

namespace {

std::string read_pem(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  std::stringstream pem;
  pem << file.rdbuf();
  return pem.str();
}

}  // namespace

bool check_health(const std::string& address, std::chrono::milliseconds timeout, std::string& why,
                  const HealthTls& tls) {
  detail::quiet_grpc_log_unless_asked();  // its own failure is said in one line below
  grpc::ChannelArguments arguments;
  // A channel of its own: never a connection shared with (and kept alive by) anyone else.
  arguments.SetInt(GRPC_ARG_USE_LOCAL_SUBCHANNEL_POOL, 1);
  std::shared_ptr<grpc::ChannelCredentials> credentials = grpc::InsecureChannelCredentials();
  if (!tls.ca_file.empty()) {
    grpc::SslCredentialsOptions options;
    options.pem_root_certs = read_pem(tls.ca_file);
    if (!tls.cert_file.empty()) {
      options.pem_cert_chain = read_pem(tls.cert_file);
      options.pem_private_key = read_pem(tls.key_file);
    }
    credentials = grpc::SslCredentials(options);
  }
  const auto channel = grpc::CreateCustomChannel(address, credentials, arguments);
  grpc::GenericStub stub(channel);
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + timeout);
  // HealthCheckRequest{service: ""} is the empty message; HealthCheckResponse{status: SERVING}
  // is field 1 = 1, the two bytes 08 01 (grpc/health/v1/health.proto).
  grpc::Slice empty;  // a buffer holding zero bytes (a default ByteBuffer holds none at all)
  grpc::ByteBuffer request(&empty, 1);
  grpc::ByteBuffer response;
  std::promise<grpc::Status> done;
  stub.UnaryCall(&context, "/grpc.health.v1.Health/Check", grpc::StubOptions(), &request, &response,
                 [&done](grpc::Status status) { done.set_value(std::move(status)); });
  const grpc::Status status = done.get_future().get();
  if (!status.ok()) {
    const std::string said = status.error_message() + " (gRPC code " +
                             std::to_string(static_cast<int>(status.error_code())) + ")";
    // gRPC says "Connection reset by peer" for every TLS mismatch; one handshake of our own says
    // which option to change, in --health-check's terms.
    const detail::TlsSettingNames names{
        "give --health-ca with the CA that signed its certificate", "leave out --health-ca", "--health-ca",
        "--health-cert", "--health-key", "dial it by one of them (HOST in --health-check HOST:PORT)"};
    const std::string cause = detail::diagnose_tls_mismatch(
        {address, !tls.ca_file.empty(), tls.ca_file, tls.cert_file, tls.key_file, {}, names},
        std::min<std::chrono::milliseconds>(timeout, std::chrono::seconds(1)));
    why = cause.empty() ? "no answer from " + address + ": " + said
                        : "no answer from " + address + ": " + cause + " [gRPC: " + said + "]";
    return false;
  }
  std::vector<grpc::Slice> slices;
  (void)response.Dump(&slices);
  std::string bytes;
  for (const grpc::Slice& slice : slices) {
    bytes.append(reinterpret_cast<const char*>(slice.begin()), slice.size());
  }
  if (bytes != std::string("\x08\x01", 2)) {
    why = address + " answers, but not SERVING";
    return false;
  }
  return true;
}

std::string local_dial_address(const std::string& bound_address, std::uint16_t port) {
  const auto colon = bound_address.rfind(':');
  std::string host = colon == std::string::npos ? bound_address : bound_address.substr(0, colon);
  if (host.empty() || host == "0.0.0.0") host = "127.0.0.1";
  if (host == "[::]" || host == "::") host = "[::1]";
  return host + ":" + std::to_string(port);
}

std::string address_from_ready_file(const std::string& path, std::string& why) {
  std::ifstream file(path);
  if (!file) {
    why = "no ready file " + path + " (the server has not finished starting, or writes none)";
    return {};
  }
  std::stringstream text;
  text << file.rdbuf();
  static const std::regex address_field(R"re("grpc_address"\s*:\s*"([^"]+)")re");
  std::smatch match;
  const std::string contents = text.str();
  if (!std::regex_search(contents, match, address_field)) {
    why = "ready file " + path + " has no \"grpc_address\"";
    return {};
  }
  return match[1].str();
}

}  // namespace haptic::app
