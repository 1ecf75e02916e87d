#include "federation/transport.hpp"

namespace haptic::federation {

DdsTransport::DdsTransport(const Participant& participant, bool masses)
    : tools_out_(participant), tools_in_(participant) {
  if (masses) {
    masses_out_ = std::make_unique<MassPublisher>(participant);
    masses_in_ = std::make_unique<MassSubscriber>(participant);
  }
}

bool DdsTransport::publish_tool(const ToolState& tool) {
  if (tools_out_.publish(tool)) return true;
  error_ = tools_out_.error();
  return false;
}

bool DdsTransport::publish_mass(const MassState& mass) {
  if (!masses_out_) {
    error_ = "the mass topic is not open on this transport";
    return false;
  }
  if (masses_out_->publish(mass)) return true;
  error_ = masses_out_->error();
  return false;
}

}  // namespace haptic::federation
