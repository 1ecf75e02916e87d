#pragma once
// hapticd's service over raw gRPC, for tests that must send exactly what they like (another
// session's id, no secret, a flood): a connection of its own, calls with a deadline and the
// session secret given.

#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <chrono>
#include <memory>
#include <string>

#include "haptic/io/session_secret.hpp"
#include "haptic/v1/service.grpc.pb.h"

namespace haptic::test {

class RawClient {
 public:
  explicit RawClient(const std::string& address) {
    grpc::ChannelArguments arguments;
    arguments.SetInt(GRPC_ARG_USE_LOCAL_SUBCHANNEL_POOL, 1);  // never share another's connection
    channel_ = grpc::CreateCustomChannel(address, grpc::InsecureChannelCredentials(), arguments);
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
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::Haptic::Stub> stub_;
};

}  // namespace haptic::test
