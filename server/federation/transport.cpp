#include "federation/transport.hpp"

#include <stdexcept>

namespace haptic::federation {

DdsTransport::DdsTransport(const Participant& participant, const std::string& site, bool tools, bool masses) {
  if (masses) {
    masses_in_ = std::make_unique<MassSubscriber>(participant);
    try {
      masses_out_ = std::make_unique<MassPublisher>(participant, site);
    } catch (const std::runtime_error& error) {
      // An observer's permissions refuse it: this site's copies are not published, but it still
      // takes the others' (and its relay couples to them).
      masses_refused_ = error.what();
    }
  }
  if (tools) {
    tools_in_ = std::make_unique<ToolSubscriber>(participant);
    try {
      tools_out_ = std::make_unique<ToolPublisher>(participant, site);
    } catch (const std::runtime_error& error) {
      // An observer's permissions refuse it too: its users feel the others' tools, and are not
      // felt (members act on what the tool topic carries).
      tools_refused_ = error.what();
    }
  }
}

bool DdsTransport::publish_tool(const ToolState& tool) {
  if (!tools_out_) {
    error_ = tools_refused_.empty() ? "the tool topic is not open on this transport"
                                    : "the tool topic's writer was refused: " + tools_refused_;
    return false;
  }
  if (tools_out_->publish(tool)) return true;
  error_ = tools_out_->error();
  return false;
}

bool DdsTransport::publish_mass(const MassState& mass) {
  if (!masses_out_) {
    error_ = masses_refused_.empty() ? "the mass topic is not open on this transport"
                                     : "the mass topic's writer was refused: " + masses_refused_;
    return false;
  }
  if (masses_out_->publish(mass)) return true;
  error_ = masses_out_->error();
  return false;
}

}  // namespace haptic::federation
