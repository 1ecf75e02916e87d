// The control plane's unary latency over plaintext, TLS and mutual TLS, and over the HTTP face
// (JSON and binary protobuf bodies, plain HTTP/1.1 kept alive), in one run: an in-process hapticd
// (lockstep time, so the loop takes no CPU) and one client calling GetDeviceInfo back to back on
// one connection. Prints p50 / p99 / p99.9 per mode and each mode's ratio to the plaintext gRPC
// one measured beside it. A benchmark: it prints figures, asserts nothing.
//
// Usage: control_latency_bench [--calls N] [--rounds R] [--certs DIR]
//   --certs: the folder make_test_certs.sh fills (default: the build tree's test certificates).

#include <grpcpp/grpcpp.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "app/server.hpp"
#include "config/server_config.hpp"
#include "haptic/io/session_secret.hpp"
#include "haptic/v1/service.grpc.pb.h"
#include "net/http_face.hpp"
#include "net/proto_json.hpp"
#include "support/http_client.hpp"

namespace {

std::string read_file(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) {
    std::fprintf(stderr, "control_latency_bench: cannot read %s\n", path.c_str());
    std::exit(2);
  }
  std::stringstream text;
  text << file.rdbuf();
  return text.str();
}

enum class Mode { kPlaintext, kTls, kMutualTls, kHttpJson, kHttpProto };

const char* name_of(Mode mode) {
  switch (mode) {
    case Mode::kPlaintext: return "plaintext";
    case Mode::kTls: return "TLS";
    case Mode::kMutualTls: return "mutual TLS";
    case Mode::kHttpJson: return "HTTP JSON";
    case Mode::kHttpProto: return "HTTP proto";
  }
  return "?";
}

haptic::v1::ServerConfig server_config(Mode mode, const std::string& certs) {
  haptic::v1::ServerConfig config = haptic::config::default_config();
  config.set_time_mode(haptic::v1::LOCKSTEP);
  config.set_grpc_address("127.0.0.1:0");
  config.set_udp_address("127.0.0.1");
  config.set_udp_port(0);
  config.set_status_period_s(0);
  if (mode == Mode::kHttpJson || mode == Mode::kHttpProto) config.set_http_address("127.0.0.1:0");
  if (mode == Mode::kTls || mode == Mode::kMutualTls) {
    auto* tls = config.mutable_security()->mutable_tls();
    tls->set_cert_file(certs + "/server.pem");
    tls->set_key_file(certs + "/server.key");
    if (mode == Mode::kMutualTls) tls->set_client_ca_file(certs + "/ca.pem");
  }
  return config;
}

std::shared_ptr<grpc::ChannelCredentials> client_credentials(Mode mode, const std::string& certs) {
  if (mode == Mode::kPlaintext) return grpc::InsecureChannelCredentials();
  grpc::SslCredentialsOptions options;
  options.pem_root_certs = read_file(certs + "/ca.pem");
  if (mode == Mode::kMutualTls) {
    options.pem_private_key = read_file(certs + "/client.key");
    options.pem_cert_chain = read_file(certs + "/client.pem");
  }
  return grpc::SslCredentials(options);
}

struct Figures {
  double p50_us = 0, p99_us = 0, p999_us = 0;
};

double quantile(std::vector<double>& sorted, double q) {
  const auto index = static_cast<std::size_t>(q * static_cast<double>(sorted.size() - 1));
  return sorted[index];
}

/// One call on a kept-alive connection to the face: the reply's status, its body in `reply`.
int http_call(haptic::test::HttpConnection& connection, const std::string& call, const std::string& body,
              const std::string& content_type, const std::string& headers, std::string& reply) {
  connection.send("POST /haptic.v1.Haptic/" + call + " HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: " +
                  content_type + "\r\nContent-Length: " + std::to_string(body.size()) + "\r\n" + headers +
                  "\r\n" + body);
  haptic::test::HttpReply got = connection.read_reply();
  reply = std::move(got.body);
  return got.status;
}

Figures measure_http(haptic::app::Server& server, Mode mode, int calls) {
  haptic::test::HttpConnection caller(server.http_port());
  haptic::v1::OpenSessionRequest open;
  open.set_client_name("latency-bench");
  open.set_api_version(haptic::v1::API_VERSION_CURRENT);
  std::string reply;
  if (http_call(caller, "OpenSession", haptic::net::to_json(open), "application/json", {}, reply) != 200) {
    std::fprintf(stderr, "control_latency_bench: HTTP OpenSession: %s\n", reply.c_str());
    std::exit(1);
  }
  haptic::v1::OpenSessionResponse session;
  haptic::net::from_json(reply, session);
  const std::string secret =
      "haptic-session-secret-bin: " + haptic::net::encode_base64(session.session_secret()) + "\r\n";
  haptic::v1::SessionRef ref;
  ref.set_session_id(session.session_id());
  const bool json = mode == Mode::kHttpJson;
  const std::string body = json ? haptic::net::to_json(ref) : ref.SerializeAsString();
  const std::string type = json ? "application/json" : "application/proto";
  std::vector<double> latencies_us;
  latencies_us.reserve(static_cast<std::size_t>(calls));
  const int warm_up = std::max(calls / 10, 10);
  for (int i = 0; i < warm_up + calls; ++i) {
    const auto start = std::chrono::steady_clock::now();
    const int status = http_call(caller, "GetDeviceInfo", body, type, secret, reply);
    // The reply decoded, as a client must before it has the answer.
    haptic::v1::DeviceInfo info;
    const bool decoded = json ? haptic::net::from_json(reply, info).empty() : info.ParseFromString(reply);
    const auto end = std::chrono::steady_clock::now();
    if (status != 200 || !decoded) {
      std::fprintf(stderr, "control_latency_bench: %s: GetDeviceInfo: %d %s\n", name_of(mode), status, reply.c_str());
      std::exit(1);
    }
    if (i >= warm_up) latencies_us.push_back(std::chrono::duration<double, std::micro>(end - start).count());
  }
  server.shutdown();
  std::sort(latencies_us.begin(), latencies_us.end());
  return {quantile(latencies_us, 0.5), quantile(latencies_us, 0.99), quantile(latencies_us, 0.999)};
}

Figures measure(Mode mode, const std::string& certs, int calls) {
  haptic::app::Server server(server_config(mode, certs));
  server.start();
  if (mode == Mode::kHttpJson || mode == Mode::kHttpProto) return measure_http(server, mode, calls);
  grpc::ChannelArguments arguments;
  arguments.SetInt(GRPC_ARG_USE_LOCAL_SUBCHANNEL_POOL, 1);
  if (mode != Mode::kPlaintext) arguments.SetSslTargetNameOverride("localhost");
  const auto channel = grpc::CreateCustomChannel("127.0.0.1:" + std::to_string(server.grpc_port()),
                                                 client_credentials(mode, certs), arguments);
  const auto stub = haptic::v1::Haptic::NewStub(channel);

  haptic::v1::OpenSessionRequest open;
  open.set_client_name("latency-bench");
  open.set_api_version(haptic::v1::API_VERSION_CURRENT);
  haptic::v1::OpenSessionResponse session;
  {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(5));
    const grpc::Status status = stub->OpenSession(&context, open, &session);
    if (!status.ok()) {
      std::fprintf(stderr, "control_latency_bench: %s: OpenSession: %s\n", name_of(mode),
                   status.error_message().c_str());
      std::exit(1);
    }
  }
  haptic::v1::SessionRef ref;
  ref.set_session_id(session.session_id());
  std::vector<double> latencies_us;
  latencies_us.reserve(static_cast<std::size_t>(calls));
  const int warm_up = std::max(calls / 10, 10);
  for (int i = 0; i < warm_up + calls; ++i) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(5));
    context.AddMetadata(haptic::io::kSessionSecretMetadataKey, session.session_secret());
    haptic::v1::DeviceInfo info;
    const auto start = std::chrono::steady_clock::now();
    const grpc::Status status = stub->GetDeviceInfo(&context, ref, &info);
    const auto end = std::chrono::steady_clock::now();
    if (!status.ok()) {
      std::fprintf(stderr, "control_latency_bench: %s: GetDeviceInfo: %s\n", name_of(mode),
                   status.error_message().c_str());
      std::exit(1);
    }
    if (i >= warm_up) {
      latencies_us.push_back(std::chrono::duration<double, std::micro>(end - start).count());
    }
  }
  server.shutdown();
  std::sort(latencies_us.begin(), latencies_us.end());
  return {quantile(latencies_us, 0.5), quantile(latencies_us, 0.99), quantile(latencies_us, 0.999)};
}

}  // namespace

int main(int argc, char** argv) {
  int calls = 5000;
  int rounds = 2;
  std::string certs = HAPTIC_BENCH_CERTS;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--calls" && i + 1 < argc) calls = std::atoi(argv[++i]);
    else if (arg == "--rounds" && i + 1 < argc) rounds = std::atoi(argv[++i]);
    else if (arg == "--certs" && i + 1 < argc) certs = argv[++i];
    else {
      std::fprintf(stderr, "usage: control_latency_bench [--calls N] [--rounds R] [--certs DIR]\n");
      return 2;
    }
  }
  if (calls < 100 || rounds < 1) {
    std::fprintf(stderr, "control_latency_bench: --calls must be >= 100 and --rounds >= 1\n");
    return 2;
  }
  std::printf("GetDeviceInfo, one connection, %d calls per case (after %d to warm up), lockstep server\n",
              calls, std::max(calls / 10, 10));
  std::printf("%-6s %-11s %9s %9s %9s %12s %12s\n", "round", "mode", "p50_us", "p99_us", "p99.9_us",
              "p50/plain", "p99/plain");
  for (int round = 1; round <= rounds; ++round) {
    Figures plain{};
    for (const Mode mode : {Mode::kPlaintext, Mode::kTls, Mode::kMutualTls, Mode::kHttpJson, Mode::kHttpProto}) {
      const Figures f = measure(mode, certs, calls);
      if (mode == Mode::kPlaintext) plain = f;
      std::printf("%-6d %-11s %9.1f %9.1f %9.1f %12.2f %12.2f\n", round, name_of(mode), f.p50_us,
                  f.p99_us, f.p999_us, f.p50_us / plain.p50_us, f.p99_us / plain.p99_us);
      std::fflush(stdout);
    }
  }
  return 0;
}
