#pragma once
// What a Client and its handles share: the gRPC stub, the session, and the UDP link. Handles keep
// a weak_ptr to it, so one that outlives its Client finds it gone and does nothing.

#include <grpcpp/grpcpp.h>

#include <atomic>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "haptic/client.hpp"
#include "haptic/io/session_secret.hpp"
#include "haptic/v1/service.grpc.pb.h"
#include "udp_link.hpp"

namespace haptic::detail {

class ClientCore {
 public:
  explicit ClientCore(ClientConfig config);
  ~ClientCore();

  /// Runs one unary RPC with the configured deadline; throws the mapped haptic::Error.
  template <typename Request, typename Response, typename Method>
  Response call(const char* name, Method method, Request request) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + config_.rpc_timeout);
    authenticate(context);
    Response response;
    throw_status(((*stub_).*method)(&context, request, &response), name);
    return response;
  }

  v1::ItemRef create_object(const v1::Object& object);
  /// Replaces the object; returns the stability report of its new impedance.
  v1::ItemRef update_object(std::uint64_t id, const v1::Object& object);
  void delete_object(std::uint64_t id);
  std::uint64_t create_field(const v1::Field& field);
  void update_field(std::uint64_t id, const v1::Field& field);
  void delete_field(std::uint64_t id);
  /// Replaces the session's scene; on success bumps the scene generation, staling older handles.
  v1::ApplySceneResponse apply_scene(const v1::Scene& scene);
  std::uint64_t scene_generation() const { return scene_generation_.load(); }
  /// Sets the state decimation; for n > 0 waits until the server knows our UDP address.
  void subscribe(std::uint32_t decimation);
  void close_session();
  /// Streams WatchEvents on a thread of its own and calls `callback` with each event (the first
  /// is WATCH_STARTED); a new callback replaces the stream, an empty one ends it.
  void watch_events(std::function<void(const v1::Event&)> callback);

  std::uint64_t session_id() const { return session_id_; }
  const DeviceInfo& device_info() const { return device_info_; }
  std::chrono::milliseconds lease_timeout() const { return lease_timeout_; }
  const ClientConfig& config() const { return config_; }
  UdpLink& udp() { return *udp_; }

 private:
  static void throw_status(const grpc::Status& status, const char* name);
  /// Adds what every call carries: the bearer token (if any) and the session secret (once open).
  void authenticate(grpc::ClientContext& context) const;

  ClientConfig config_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::Haptic::Stub> stub_;
  std::uint64_t session_id_ = 0;
  std::string session_secret_;  // OpenSession's; empty until then
  bool closed_ = false;
  DeviceInfo device_info_;
  std::chrono::milliseconds lease_timeout_{0};
  std::atomic<std::uint64_t> scene_generation_{0};
  std::unique_ptr<UdpLink> udp_;
  // The event stream: its thread, and its context (cancelled from here to end it).
  std::mutex events_mutex_;
  std::unique_ptr<grpc::ClientContext> events_context_;
  std::thread events_thread_;
  void stop_events();
};

}  // namespace haptic::detail
