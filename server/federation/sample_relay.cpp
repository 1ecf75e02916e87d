#include "federation/sample_relay.hpp"

#include <chrono>

namespace haptic::federation {

SampleRelay::SampleRelay(const RelayOptions& options, const std::vector<RelayPort>& ports)
    : options_(options), ports_(ports), participant_(std::make_unique<Participant>(options.domain)) {
  last_tick_.assign(ports_.size(), 0);
  if (options_.ros2) {
    for (std::size_t port = 0; port < ports_.size(); ++port) {
      Ros2Options ros2 = *options_.ros2;
      ros2.ros_namespace += "/port" + std::to_string(port);
      ros2.buttons = ports_[port].buttons;
      ros2_.push_back(std::make_unique<Ros2ToolPublisher>(*participant_, ros2));
    }
  }
}

SampleRelay::~SampleRelay() { stop(); }

void SampleRelay::start() {
  if (thread_.joinable()) return;
  stopping_.store(false, std::memory_order_release);
  thread_ = std::thread([this] { run(); });
}

void SampleRelay::stop() {
  stopping_.store(true, std::memory_order_release);
  if (thread_.joinable()) thread_.join();
}

void SampleRelay::run() {
  const auto period = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(1.0 / options_.rate_hz));
  auto next = std::chrono::steady_clock::now();
  while (!stopping_.load(std::memory_order_acquire)) {
    for (std::size_t port = 0; port < ports_.size(); ++port) {
      const std::uint64_t newest = ports_[port].samples->newest();
      if (newest == 0 || newest == last_tick_[port]) continue;  // nothing new: nothing converted
      runtime::TickSample sample;
      if (!ports_[port].samples->read(newest, sample)) continue;  // overwritten meanwhile: next period
      last_tick_[port] = newest;
      ToolState tool;
      tool.site = options_.site;
      tool.port = static_cast<std::uint32_t>(port);
      tool.tick = sample.tick;
      tool.time_ns = sample.time_ns;
      tool.p_WT = sample.p_WT;
      tool.v_WT = sample.v_WT;
      tool.F_T_W = sample.F_T_W;
      tool.R_WT = sample.R_WT;
      tool.buttons = sample.buttons;
      if (!ros2_.empty()) {
        if (ros2_[port]->publish(tool)) {
          published_.fetch_add(1, std::memory_order_relaxed);
        } else {
          failed_.fetch_add(1, std::memory_order_relaxed);
        }
      }
    }
    next += period;
    const auto now = std::chrono::steady_clock::now();
    if (next < now) next = now;  // behind (a slow host): skip, never burst
    std::this_thread::sleep_until(next);
  }
}

}  // namespace haptic::federation
