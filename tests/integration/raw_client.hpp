#pragma once
// hapticd's service over raw gRPC, for tests that must send exactly what they like (another
// session's id, no secret, a flood): a connection of its own, calls with a deadline and the
// session secret given.

#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>

#include "haptic/io/session_secret.hpp"
#include "haptic/v1/service.grpc.pb.h"

namespace haptic::test {

/// TLS for a RawClient: PEM files (a client certificate for mutual TLS), and the name the
/// server's certificate must carry when the address is not it.
struct RawTls {
  std::string ca_file;
  std::string cert_file, key_file;  // empty: no client certificate
  std::string server_name = "localhost";
};

inline std::string read_pem(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  std::stringstream text;
  text << file.rdbuf();
  return text.str();
}

class RawClient {
 public:
  explicit RawClient(const std::string& address, const std::optional<RawTls>& tls = std::nullopt,
                     const std::string& token = {})
      : token_(token) {
    grpc::ChannelArguments arguments;
    arguments.SetInt(GRPC_ARG_USE_LOCAL_SUBCHANNEL_POOL, 1);  // never share another's connection
    std::shared_ptr<grpc::ChannelCredentials> credentials = grpc::InsecureChannelCredentials();
    if (tls) {
      grpc::SslCredentialsOptions options;
      options.pem_root_certs = read_pem(tls->ca_file);
      if (!tls->cert_file.empty()) {
        options.pem_cert_chain = read_pem(tls->cert_file);
        options.pem_private_key = read_pem(tls->key_file);
      }
      credentials = grpc::SslCredentials(options);
      arguments.SetSslTargetNameOverride(tls->server_name);
    }
    channel_ = grpc::CreateCustomChannel(address, credentials, arguments);
    stub_ = v1::Haptic::NewStub(channel_);
  }

  /// One unary call carrying `secret` as the session secret (none when empty).
  template <typename Method, typename Request, typename Response>
  grpc::Status call(Method method, const Request& request, Response& response,
                    const std::string& secret,
                    std::chrono::milliseconds deadline = std::chrono::seconds(5)) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + deadline);
    if (!secret.empty()) context.AddMetadata(io::kSessionSecretMetadataKey, secret);
    if (!token_.empty()) context.AddMetadata("authorization", "Bearer " + token_);
    return ((*stub_).*method)(&context, request, &response);
  }

  grpc::Status open(v1::OpenSessionResponse& session, const std::string& name = "raw",
                    std::chrono::milliseconds deadline = std::chrono::seconds(5)) {
    v1::OpenSessionRequest request;
    request.set_client_name(name);
    request.set_api_version(v1::API_VERSION_CURRENT);
    return call(&v1::Haptic::Stub::OpenSession, request, session, "", deadline);
  }

  /// GetStats as `session` (a failure is a test failure).
  v1::Stats stats(const v1::OpenSessionResponse& session) {
    v1::SessionRef ref;
    ref.set_session_id(session.session_id());
    v1::Stats out;
    EXPECT_TRUE(call(&v1::Haptic::Stub::GetStats, ref, out, session.session_secret()).ok());
    return out;
  }

  v1::Haptic::Stub& stub() { return *stub_; }

 private:
  std::string token_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::Haptic::Stub> stub_;
};

}  // namespace haptic::test
