#pragma once
// Sites joined by a delay line with seeded loss, for lockstep tests of whole sites (loop and
// relay): what a site publishes while the network is at tick k reaches every other site at tick
// k + delay, unless the seeded draw loses it. The test advances the network once per tick. Like
// DDS with each site's writers in its own partition, every sample arrives with the name of the
// site that published it (writer_site), whatever site it names.

#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "federation/transport.hpp"

namespace haptic::test {

class DelayLineNetwork {
 public:
  DelayLineNetwork(std::uint64_t delay_ticks, double loss, std::uint32_t seed = 30)
      : delay_(delay_ticks), loss_(loss), random_(seed) {}

  /// Site `name`'s end of the network (made on first use; kept by the network).
  federation::Transport& site(const std::string& name) {
    auto& end = ends_[name];
    if (!end) end = std::make_unique<End>(*this, name);
    return *end;
  }
  void advance() { ++now_; }
  std::uint64_t now() const { return now_; }

 private:
  template <class Sample>
  struct Message {
    Sample sample;
    std::uint64_t arrives = 0;
  };

  class End final : public federation::Transport {
   public:
    End(DelayLineNetwork& network, std::string name) : network_(network), name_(std::move(name)) {}
    bool publish_tool(const federation::ToolState& tool) override {
      federation::ToolState sent = tool;
      sent.writer_site = name_;
      network_.send(name_, sent, &End::tools_);
      return true;
    }
    bool publish_mass(const federation::MassState& mass) override {
      federation::MassState sent = mass;
      sent.writer_site = name_;
      network_.send(name_, sent, &End::masses_);
      return true;
    }
    void take_tools(std::vector<federation::ToolState>& out) override { deliver(tools_, out); }
    void take_masses(std::vector<federation::MassState>& out) override { deliver(masses_, out); }
    std::string error() const override { return {}; }

    std::deque<Message<federation::ToolState>> tools_;
    std::deque<Message<federation::MassState>> masses_;

   private:
    template <class Sample>
    void deliver(std::deque<Message<Sample>>& queue, std::vector<Sample>& out) {
      while (!queue.empty() && queue.front().arrives <= network_.now_) {
        out.push_back(std::move(queue.front().sample));
        queue.pop_front();
      }
    }
    DelayLineNetwork& network_;
    std::string name_;
  };

  /// Queues `sample` at every other site, each copy lost or not by its own draw.
  template <class Sample>
  void send(const std::string& from, const Sample& sample, std::deque<Message<Sample>> End::*queue) {
    for (auto& [name, end] : ends_) {
      if (name == from) continue;
      if (uniform_(random_) < loss_) continue;
      (end.get()->*queue).push_back({sample, now_ + delay_});
    }
  }

  std::uint64_t delay_;
  double loss_;
  std::mt19937 random_;
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};
  std::uint64_t now_ = 0;
  std::map<std::string, std::unique_ptr<End>> ends_;
};

}  // namespace haptic::test
