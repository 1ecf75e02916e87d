#include "app/replay_server.hpp"

#include "app/server.hpp"
#include "config/server_config.hpp"

namespace haptic::app {
namespace {

class ServerToReplayOn final : public recording::ReplayServer {
 public:
  explicit ServerToReplayOn(const v1::ServerConfig& config) : server_(config) { server_.start(); }
  std::uint16_t grpc_port() const override { return server_.grpc_port(); }
  std::size_t device_ports() const override { return server_.device_ports(); }
  const runtime::SampleRing& samples(std::size_t port) const override { return server_.samples(port); }
  void shutdown() override { server_.shutdown(); }

 private:
  Server server_;
};

}  // namespace

recording::ReplayServers replay_servers() {
  return {
      .validate = [](const v1::ServerConfig& config) { return config::validate(config); },
      .start = [](const v1::ServerConfig& config) -> std::unique_ptr<recording::ReplayServer> {
        return std::make_unique<ServerToReplayOn>(config);
      },
  };
}

}  // namespace haptic::app
