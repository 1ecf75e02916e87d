#include "recording/run_recorder.hpp"

#include <spdlog/spdlog.h>

#include "recording/recording_file.hpp"
#include "schema/scene_specs.hpp"

namespace haptic::recording {
namespace {

constexpr auto kRound = std::chrono::milliseconds(2);  // a round per 2 ticks at 1 kHz; the ring holds 1024
// The writer hands the file whole blocks every 64 kB of records (one to six seconds of a device
// at 1 kHz); at least this often too, so that a recorder killed loses at most this much.
constexpr auto kFlushPeriod = std::chrono::seconds(1);

}  // namespace

RunRecorder::RunRecorder(std::function<std::uint64_t()> completed_ticks,
                   std::vector<const runtime::SampleRing*> rings)
    : completed_ticks_(std::move(completed_ticks)), rings_(std::move(rings)) {}

RunRecorder::~RunRecorder() { stop("shutdown"); }

std::string RunRecorder::start(const std::string& path, const v1::ServerConfig& config) {
  std::unique_lock lock(mutex_);
  if (writer_) return "already recording to '" + writer_->path() + "'";
  std::unique_ptr<RecordingWriter> writer;
  try {
    writer = std::make_unique<RecordingWriter>(path);
  } catch (const std::exception& error) {
    return error.what();
  }
  const std::uint64_t start_tick = completed_ticks_();
  v1::Record header;
  v1::RecordHeader& h = *header.mutable_header();
  h.set_format("hapticd-recording");
  h.set_version(1);
  *h.mutable_config() = config;
  h.mutable_config()->clear_security();  // no secrets in a recording
  h.set_start_tick(start_tick);
  h.set_device_ports(static_cast<std::uint32_t>(rings_.size()));
  if (!writer->write(header)) return writer->error();
  writer_ = std::move(writer);
  queued_.clear();
  totals_.Clear();
  next_tick_ = start_tick + 1;
  flushed_at_ = std::chrono::steady_clock::now();
  unflushed_ = true;  // the header: in the file within kFlushPeriod, were nothing else to come
  write_failed_ = false;
  start_tick_.store(start_tick, std::memory_order_release);
  written_through_.store(start_tick, std::memory_order_release);
  stopping_ = false;
  active_.store(true, std::memory_order_release);
  if (thread_.joinable()) thread_.join();  // a previous recording's, already finished
  thread_ = std::thread([this] { run(); });
  spdlog::info("recording to '{}' from tick {}", path, start_tick + 1);
  return {};
}

std::optional<v1::RecordEnd> RunRecorder::stop(const std::string& why) {
  {
    std::lock_guard lock(mutex_);
    if (!writer_ || stopping_) return std::nullopt;
    stopping_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
  std::lock_guard lock(mutex_);
  totals_.set_stopped_because(why);
  v1::Record end;
  *end.mutable_end() = totals_;
  writer_->write(end);
  writer_->close();
  // What a failed write cost: known only now (the end record is among it), so in the RecordEnd
  // reported, not in the file, which ends before its end record then.
  totals_.set_records_not_written(writer_->records_not_written());
  totals_.set_write_error(writer_->error());
  if (writer_->error().empty()) {
    spdlog::info("recording '{}' {}: {} samples ({} missed), {} changes", writer_->path(), why,
                 totals_.samples(), totals_.samples_missed(), totals_.changes());
  } else {
    spdlog::error("recording '{}' {}: {} samples ({} missed), {} changes; {} records not written "
                  "({}): the file ends before them",
                  writer_->path(), why, totals_.samples(), totals_.samples_missed(),
                  totals_.changes(), totals_.records_not_written(), totals_.write_error());
  }
  writer_.reset();
  active_.store(false, std::memory_order_release);
  return totals_;
}

std::string RunRecorder::path() const {
  std::lock_guard lock(mutex_);
  return writer_ ? writer_->path() : std::string();
}

void RunRecorder::record(v1::RecordedChange change) {
  if (!active()) return;
  std::lock_guard lock(mutex_);
  if (!writer_) return;
  // Under the lock the recorder thread takes the completed tick with: a change stamped with tick
  // T is always written before the samples after T.
  change.set_after_tick(completed_ticks_());
  queued_.push_back(std::move(change));
}

bool RunRecorder::wait_written_through(std::uint64_t tick, std::chrono::milliseconds timeout) const {
  const auto give_up = std::chrono::steady_clock::now() + timeout;
  while (active() && written_through_.load(std::memory_order_acquire) < tick) {
    if (std::chrono::steady_clock::now() > give_up) return false;
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  return true;
}

void RunRecorder::run() {
  std::unique_lock lock(mutex_);
  while (!stopping_) {
    wake_.wait_for(lock, kRound, [this] { return stopping_; });
    lock.unlock();
    write_due();
    lock.lock();
  }
  lock.unlock();
  write_due();  // what was due when stop() came
}

void RunRecorder::write_due() {
  std::vector<v1::RecordedChange> changes;
  std::uint64_t completed = 0;
  {
    std::lock_guard lock(mutex_);
    completed = completed_ticks_();
    changes.swap(queued_);
  }
  // The writer is only replaced under stop(), after this thread has ended.
  RecordingWriter& writer = *writer_;
  v1::Record record;
  for (v1::RecordedChange& change : changes) {
    *record.mutable_change() = std::move(change);
    writer.write(record);
    totals_.set_changes(totals_.changes() + 1);
  }
  runtime::TickSample sample;
  const std::uint64_t first_tick = next_tick_;
  for (; next_tick_ <= completed; ++next_tick_) {
    for (std::size_t port = 0; port < rings_.size(); ++port) {
      if (!rings_[port]->read(next_tick_, sample)) {
        totals_.set_samples_missed(totals_.samples_missed() + 1);
        continue;
      }
      v1::RecordedSample& out = *record.mutable_sample();
      out.set_tick(sample.tick);
      out.set_port(static_cast<std::uint32_t>(port));
      *out.mutable_position() = schema::to_proto(sample.p_WT);
      *out.mutable_velocity() = schema::to_proto(sample.v_WT);
      *out.mutable_force() = schema::to_proto(sample.F_T_W);
      out.set_flags(sample.flags);
      writer.write(record);
      totals_.set_samples(totals_.samples() + 1);
    }
  }
  if (!write_failed_ && !writer.error().empty()) {
    write_failed_ = true;  // said once, now; stop() says what it cost
    spdlog::error("recording '{}': {}: nothing more is written to it (the records not written "
                  "are counted)",
                  writer.path(), writer.error());
  }
  if (!changes.empty() || next_tick_ > first_tick) unflushed_ = true;
  if (unflushed_ && std::chrono::steady_clock::now() - flushed_at_ >= kFlushPeriod) {
    writer.flush();
    flushed_at_ = std::chrono::steady_clock::now();
    unflushed_ = false;
  }
  written_through_.store(completed, std::memory_order_release);
}

}  // namespace haptic::recording
