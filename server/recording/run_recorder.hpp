#pragma once
// recording::RunRecorder records a run on the server to a file (recording_file.hpp; hapticd --record,
// StartRecording), not the SDK's haptic::Recorder, which records what one client receives: the
// changes clients make, stamped with the tick after which they take effect, and every tick's
// sample of every device port. The loop is not
// touched: the recorder's own thread reads the samples from the rings the loop already publishes
// (as the UDP sender does) and does all the encoding, compression and writing; a change is queued
// by the control-plane thread that made it. A sample the ring overwrote before the recorder read
// it is counted as missed (a lockstep Step waits for the recorder instead: see wait_written_through).
// A write that fails (a full disk) ends what reaches the file: it is logged at once, and the
// records not written and the first error are in the RecordEnd that stop() returns and logs.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "haptic/v1/recording.pb.h"
#include "runtime/sample_ring.hpp"

namespace haptic::recording {

class RecordingWriter;

class RunRecorder {
 public:
  /// `completed_ticks`: the loop's count of ticks completed (LoopThread::completed_ticks: a
  /// tick's samples are in the rings before it counts). `rings`: each device port's samples, in
  /// port order.
  RunRecorder(std::function<std::uint64_t()> completed_ticks,
           std::vector<const runtime::SampleRing*> rings);
  ~RunRecorder();
  RunRecorder(const RunRecorder&) = delete;
  RunRecorder& operator=(const RunRecorder&) = delete;

  /// Starts recording into `path` (created or truncated), the header holding `config` (without
  /// its security section). Returns "" on success, else why not (already recording, the file).
  std::string start(const std::string& path, const v1::ServerConfig& config);
  /// Stops: what is due is written, then the end record; the file is closed. `why` goes into the
  /// end record. Returns the end record (with the records a failed write kept out of the file and
  /// its error, which the file's own end record cannot hold); nullopt when not recording.
  std::optional<v1::RecordEnd> stop(const std::string& why);
  bool active() const { return active_.load(std::memory_order_acquire); }
  /// The file being written ("" when not recording).
  std::string path() const;
  /// Ticks completed when the recording began (its header's start_tick).
  std::uint64_t start_tick() const { return start_tick_.load(std::memory_order_acquire); }

  /// Queues a change made now (stamped with the ticks completed so far). Nothing when not active.
  void record(v1::RecordedChange change);

  /// Waits (up to `timeout`) until the samples through `tick` are written; true when they are or
  /// nothing is being recorded.
  bool wait_written_through(std::uint64_t tick, std::chrono::milliseconds timeout) const;

 private:
  void run();
  /// One round on the recorder's thread: queued changes, then samples through the ticks
  /// completed when they were taken.
  void write_due();

  std::function<std::uint64_t()> completed_ticks_;
  std::vector<const runtime::SampleRing*> rings_;

  mutable std::mutex mutex_;  // guards everything below but the atomics
  std::condition_variable wake_;
  std::unique_ptr<RecordingWriter> writer_;
  std::vector<v1::RecordedChange> queued_;
  bool stopping_ = false;
  std::uint64_t next_tick_ = 1;  // the recorder thread's: the next tick whose samples are due
  std::chrono::steady_clock::time_point flushed_at_;  // the recorder thread's: its last flush()
  bool unflushed_ = false;       // the recorder thread's: records written since
  bool write_failed_ = false;    // the recorder thread's: a write failed (and that was logged)
  v1::RecordEnd totals_;
  std::atomic<bool> active_{false};
  std::atomic<std::uint64_t> written_through_{0};
  std::atomic<std::uint64_t> start_tick_{0};
  std::thread thread_;
};

}  // namespace haptic::recording
