#pragma once
// For tests and benchmarks only: holds the recorder's writer back (it drains nothing until
// released or closed), so that a test can fill the queue deterministically and see what is
// dropped; and the recorder's observer made without a Client, for a benchmark of its tap.

#include <memory>

#include "haptic/recorder.hpp"

namespace haptic::detail {

struct RecorderTestAccess {
  static void hold_writer(Recorder& recorder, bool hold);
  /// What Recorder(client, options) attaches to the client, writing `options.path`, its writer
  /// running; `finish` closes it (as Recorder::close) and returns the totals.
  static std::shared_ptr<ReceiveObserver> make_sink(const RecorderOptions& options);
  static RecorderStats finish(ReceiveObserver& sink);
};

}  // namespace haptic::detail
