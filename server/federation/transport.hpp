#pragma once
// What the relay sends to and takes from the other sites, at loop rate: tools and shared masses'
// copies (docs/federation.md). Over DDS in a server (DdsTransport); over a delay line with seeded
// loss in the lockstep tests, which step whole sites' loops and relays together.

#include <memory>
#include <string>
#include <vector>

#include "federation/dds_participant.hpp"
#include "federation/mass_topic.hpp"
#include "federation/tool_topic.hpp"

namespace haptic::federation {

class Transport {
 public:
  virtual ~Transport() = default;
  /// Sends one sample to every other site; false (and error() says why) when refused.
  virtual bool publish_tool(const ToolState& tool) = 0;
  virtual bool publish_mass(const MassState& mass) = 0;
  /// Appends what arrived from the other sites since the last take, oldest first (never this
  /// site's own samples).
  virtual void take_tools(std::vector<ToolState>& out) = 0;
  virtual void take_masses(std::vector<MassState>& out) = 0;
  virtual std::string error() const = 0;
};

/// The tool and mass topics on a participant.
class DdsTransport final : public Transport {
 public:
  /// tools, masses: make that topic's endpoints (without them, nothing is taken and a publication
  /// is refused). An observer's permissions may refuse the mass topic's writer: the reader is
  /// still made, masses_refused() says why, and every mass publication is refused. Throws
  /// std::runtime_error naming anything else Cyclone refused.
  /// Its writers publish `site`'s samples only (dds_endpoint's in_site_partition). An observer's
  /// permissions refuse the tool topic's writer too: tools_refused() says why, and every tool
  /// publication is refused.
  DdsTransport(const Participant& participant, const std::string& site, bool tools, bool masses);

  bool publish_tool(const ToolState& tool) override;
  bool publish_mass(const MassState& mass) override;
  void take_tools(std::vector<ToolState>& out) override {
    if (tools_in_) tools_in_->take(out);
  }
  void take_masses(std::vector<MassState>& out) override {
    if (masses_in_) masses_in_->take(out);
  }
  std::string error() const override { return error_; }
  /// Why the mass topic's writer was refused ("" when it was made, or masses were not asked for).
  const std::string& masses_refused() const { return masses_refused_; }
  /// Why the tool topic's writer was refused ("" when it was made, or tools were not asked for).
  const std::string& tools_refused() const { return tools_refused_; }

 private:
  std::unique_ptr<ToolPublisher> tools_out_;
  std::unique_ptr<ToolSubscriber> tools_in_;
  std::unique_ptr<MassPublisher> masses_out_;
  std::unique_ptr<MassSubscriber> masses_in_;
  std::string masses_refused_;
  std::string tools_refused_;
  std::string error_;  // the last refusal's
};

}  // namespace haptic::federation
