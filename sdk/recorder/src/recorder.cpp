#include "haptic/recorder.hpp"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

#include "haptic/error.hpp"
#include "record_format.hpp"
#include "recorder_test_access.hpp"
#include "sample_queue.hpp"

namespace haptic {

namespace detail {

namespace {

// The most samples one write takes from the queue (a batch is one HDF5 append per column).
constexpr std::size_t kBatch = 4096;
// The writer wakes this often to drain the queue: the receive thread never signals it (a futex
// wake per sample would cost the receive path a system call).
constexpr auto kWriterPeriod = std::chrono::milliseconds(5);
// What the writer has written is flushed this often (HDF5: the chunks and the metadata that finds
// them; CSV flushes each batch as well). With the writer's period this bounds what a process that
// dies can lose to the samples of its last 100 ms while the writer keeps up (docs/recorder.md,
// "What a crash leaves"): a sample waits up to kWriterPeriod to be written and kFlushPeriod more
// to be flushed, leaving room for a late wake-up and the flush itself.
constexpr auto kFlushPeriod = std::chrono::milliseconds(50);
// At most this many samples queued (each a State, 240 bytes): 4 GB.
constexpr std::size_t kMaxQueueCapacity = std::size_t{1} << 24;

std::string lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

}  // namespace

/// The observer the Client calls (receive thread, event thread, supervisor) and the writer thread
/// that empties its queues into the file.
class RecorderSink final : public ReceiveObserver {
 public:
  RecorderSink(std::unique_ptr<RecordWriter> writer, std::size_t capacity, std::string path,
               std::string events_path)
      : writer_(std::move(writer)),
        queue_(capacity),
        event_capacity_(capacity),
        path_(std::move(path)),
        events_path_(std::move(events_path)) {}

  ~RecorderSink() override { finish(); }

  void start() { thread_ = std::thread([this] { write_loop(); }); }

  // One producer at a time (the UdpLink's lock): plain load and store, no read-modify-write.
  void on_sample(const State& state) noexcept override {
    received_.store(received_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
    if (!queue_.push(state)) {
      dropped_.store(dropped_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
    }
  }

  void on_event(const Event& event) noexcept override {
    push_event(event_record(event, steady_ns(std::chrono::steady_clock::now())));
  }

  void on_connection(const ConnectionChange& change) noexcept override {
    push_event(event_record(change, steady_ns(std::chrono::steady_clock::now())));
  }

  /// Stops the writer after it has written everything queued, and closes the file; once.
  RecorderStats finish() noexcept {
    std::lock_guard finishing(finish_mutex_);
    if (!finished_) {
      {
        std::lock_guard lock(mutex_);
        stop_ = true;
      }
      wake_.notify_all();
      if (thread_.joinable()) thread_.join();
      std::string error;
      if (!writer_->close(error)) note_error(error, 0);
      writer_.reset();
      finished_ = true;
    }
    return stats();
  }

  RecorderStats stats() const {
    RecorderStats out;
    out.samples_received = received_.load(std::memory_order_relaxed);
    out.dropped = dropped_.load(std::memory_order_relaxed);
    out.samples_written = samples_written_.load(std::memory_order_relaxed);
    out.events_written = events_written_.load(std::memory_order_relaxed);
    out.write_errors = write_errors_.load(std::memory_order_relaxed);
    std::lock_guard lock(mutex_);
    out.events_dropped = events_dropped_;
    out.first_error = first_error_;
    return out;
  }

  bool finished() const {
    std::lock_guard lock(finish_mutex_);
    return finished_;
  }
  void hold(bool on) {
    hold_.store(on);
    wake_.notify_all();
  }
  const std::string& path() const noexcept { return path_; }
  const std::string& events_path() const noexcept { return events_path_; }

 private:
  void push_event(EventRecord record) noexcept {
    std::lock_guard lock(mutex_);
    if (events_.size() >= event_capacity_) {
      ++events_dropped_;
      return;
    }
    try {
      events_.push_back(std::move(record));
    } catch (...) {
      ++events_dropped_;
    }
  }

  void note_error(const std::string& error, std::uint64_t records) {
    write_errors_.fetch_add(records, std::memory_order_relaxed);
    std::lock_guard lock(mutex_);
    if (first_error_.empty()) first_error_ = error;
  }

  void write_loop() {
    std::vector<State> batch;
    batch.reserve(std::min(kBatch, queue_.capacity()));
    std::vector<EventRecord> events;
    auto flushed_at = std::chrono::steady_clock::now();
    bool unflushed = false;  // written since flushed_at
    for (;;) {
      bool stopping = false;
      {
        std::unique_lock lock(mutex_);
        wake_.wait_for(lock, kWriterPeriod, [this] { return stop_; });
        stopping = stop_;
        if (hold_.load() && !stopping) continue;
        events.swap(events_);
      }
      std::string error;
      while (queue_.pop(batch, kBatch) > 0) {
        const std::size_t written = writer_->write_samples(batch, error);
        samples_written_.fetch_add(written, std::memory_order_relaxed);
        if (written < batch.size()) note_error(error, batch.size() - written);
        unflushed = true;
      }
      if (!events.empty()) {
        const std::size_t written = writer_->write_events(events, error);
        events_written_.fetch_add(written, std::memory_order_relaxed);
        if (written < events.size()) note_error(error, events.size() - written);
        events.clear();
        unflushed = true;
      }
      if (stopping) return;  // the observer was detached before: nothing more arrives; close flushes
      const auto now = std::chrono::steady_clock::now();
      if (unflushed && now - flushed_at >= kFlushPeriod) {
        if (!writer_->flush(error)) note_error(error, 0);
        flushed_at = now;
        unflushed = false;
      }
    }
  }

  std::unique_ptr<RecordWriter> writer_;  // the writer thread's, until finish()
  SampleQueue queue_;
  const std::size_t event_capacity_;
  const std::string path_;
  const std::string events_path_;

  std::atomic<std::uint64_t> received_{0};
  std::atomic<std::uint64_t> dropped_{0};
  std::atomic<std::uint64_t> samples_written_{0};
  std::atomic<std::uint64_t> events_written_{0};
  std::atomic<std::uint64_t> write_errors_{0};
  std::atomic<bool> hold_{false};

  mutable std::mutex mutex_;
  std::condition_variable wake_;
  bool stop_ = false;                // guarded by mutex_
  std::vector<EventRecord> events_;  // guarded by mutex_
  std::uint64_t events_dropped_ = 0; // guarded by mutex_
  std::string first_error_;          // guarded by mutex_

  mutable std::mutex finish_mutex_;
  bool finished_ = false;  // guarded by finish_mutex_
  std::thread thread_;
};

namespace {

/// Checks the options and makes the sink that writes them (its writer thread not yet started).
/// Throws InvalidArgumentError naming the field; nothing is left behind.
std::shared_ptr<RecorderSink> make_recorder_sink(const RecorderOptions& options,
                                                 const RecordingInfo& info) {
  using Format = RecorderOptions::Format;
  const std::string& path = options.path;
  if (path.empty()) throw InvalidArgumentError("record: path: empty");
  if (options.queue_capacity == 0) throw InvalidArgumentError("record: queue_capacity: must be >= 1");
  if (options.queue_capacity > kMaxQueueCapacity) {
    throw InvalidArgumentError("record: queue_capacity: " + std::to_string(options.queue_capacity) +
                               " is more than " + std::to_string(kMaxQueueCapacity));
  }
  const std::filesystem::path file(path);
  Format format = options.format;
  if (format == Format::kAuto) {
    const std::string extension = lower(file.extension().string());
    if (extension == ".csv") {
      format = Format::kCsv;
    } else if (extension == ".h5" || extension == ".hdf5") {
      format = Format::kHdf5;
    } else {
      throw InvalidArgumentError("record: path: '" + path +
                                 "' ends in neither .csv nor .h5 or .hdf5; name the format "
                                 "(RecorderOptions::format)");
    }
  } else if (format != Format::kCsv && format != Format::kHdf5) {
    throw InvalidArgumentError("record: format: unknown value " +
                               std::to_string(static_cast<int>(format)));
  }
  const std::filesystem::path directory = file.has_parent_path() ? file.parent_path() : ".";
  std::error_code error;
  if (!std::filesystem::is_directory(directory, error)) {
    throw InvalidArgumentError("record: path: the directory '" + directory.string() +
                               "' does not exist");
  }
  std::string events_path;
  if (options.events) {
    events_path = format == Format::kCsv
                      ? (file.parent_path() / (file.stem().string() + ".events.csv")).string()
                      : path;
  }
  // A link is never written through, overwrite or not: "replace my recording" must not truncate
  // whatever file the link points at (another user's, a system file).
  for (const std::string& name : {path, events_path}) {
    if (!name.empty() && std::filesystem::is_symlink(name, error)) {
      throw InvalidArgumentError("record: path: '" + name +
                                 "' is a symbolic link: the recorder does not write through links (give the "
                                 "file's own path, or remove the link)");
    }
  }
  if (!options.overwrite) {
    for (const std::string& name : {path, events_path}) {
      if (!name.empty() && std::filesystem::exists(name, error)) {
        throw InvalidArgumentError("record: path: '" + name +
                                   "' exists (RecorderOptions::overwrite replaces it)");
      }
    }
  }
  std::unique_ptr<RecordWriter> writer =
      format == Format::kCsv ? make_csv_writer(path, events_path, options.overwrite)
                             : make_hdf5_writer(path, options.events, options.overwrite, info);
  return std::make_shared<RecorderSink>(std::move(writer), options.queue_capacity, path, events_path);
}

}  // namespace

void RecorderTestAccess::hold_writer(Recorder& recorder, bool hold) {
  if (recorder.sink_) recorder.sink_->hold(hold);
}

std::shared_ptr<ReceiveObserver> RecorderTestAccess::make_sink(const RecorderOptions& options) {
  auto sink = make_recorder_sink(options, RecordingInfo{});
  sink->start();
  return sink;
}

RecorderStats RecorderTestAccess::finish(ReceiveObserver& sink) {
  return static_cast<RecorderSink&>(sink).finish();
}

}  // namespace detail

Recorder::Recorder(Client& client, const RecorderOptions& options) {
  const DeviceInfo& device = client.device_info();
  const ClientConfig& config = client.config();
  auto sink = detail::make_recorder_sink(
      options, {config.client_name, config.server_address, device.name, device.model,
                device.loop_rate_hz, client.session_id(), config.state_decimation});
  try {
    observer_ = client.observe(sink, ObserveOptions{.events = options.events});
  } catch (...) {
    sink->finish();
    std::error_code error;
    std::filesystem::remove(sink->path(), error);
    if (!sink->events_path().empty()) std::filesystem::remove(sink->events_path(), error);
    throw;
  }
  sink->start();
  sink_ = std::move(sink);
}

Recorder::~Recorder() { close(); }

Recorder::Recorder(Recorder&& other) noexcept
    : sink_(std::move(other.sink_)), observer_(std::move(other.observer_)) {}

Recorder& Recorder::operator=(Recorder&& other) noexcept {
  if (this != &other) {
    close();
    sink_ = std::move(other.sink_);
    observer_ = std::move(other.observer_);
  }
  return *this;
}

RecorderStats Recorder::stats() const { return sink_ ? sink_->stats() : RecorderStats{}; }

RecorderStats Recorder::close() noexcept {
  if (!sink_) return {};
  observer_.detach();  // no call of the sink's runs after this
  return sink_->finish();
}

bool Recorder::recording() const noexcept { return sink_ && !sink_->finished(); }

const std::string& Recorder::path() const noexcept {
  static const std::string none;
  return sink_ ? sink_->path() : none;
}

const std::string& Recorder::events_path() const noexcept {
  static const std::string none;
  return sink_ ? sink_->events_path() : none;
}

}  // namespace haptic
