// CSV: one file of samples (a header row, one row per State), and one of events beside it. Doubles
// as %.17g, so that each reads back to the same double; NaN as "NaN" (pandas, MATLAB and Python's
// float() read it). The header rows are flushed when the files are made, and each batch as soon as
// it is written: a failed write is the batch's own, and a process that dies leaves every batch
// written before (docs/recorder.md, "What a crash leaves").
#include <cerrno>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "haptic/error.hpp"
#include "record_format.hpp"

namespace haptic::detail {

namespace {

void put_cell(std::FILE* file, ColumnType type, Cell cell) {
  switch (type) {
    case ColumnType::kInt64: std::fprintf(file, "%" PRId64, cell.i64); break;
    case ColumnType::kUInt64: std::fprintf(file, "%" PRIu64, cell.u64); break;
    case ColumnType::kUInt32: std::fprintf(file, "%" PRIu32, cell.u32); break;
    case ColumnType::kDouble:
      if (std::isnan(cell.f64)) {
        std::fputs("NaN", file);
      } else {
        std::fprintf(file, "%.17g", cell.f64);
      }
      break;
  }
}

// RFC 4180: quoted, with inner quotes doubled.
void put_text(std::FILE* file, const std::string& text) {
  std::fputc('"', file);
  for (const char c : text) {
    if (c == '"') std::fputc('"', file);
    std::fputc(c, file);
  }
  std::fputc('"', file);
}

std::FILE* create(const std::string& path, bool overwrite) {
  // "x": created exclusively, so a file made since the caller looked is not overwritten either.
  std::FILE* file = std::fopen(path.c_str(), overwrite ? "w" : "wx");
  if (file == nullptr) {
    const std::string why = errno == EEXIST ? "exists (RecorderOptions::overwrite replaces it)"
                                            : std::strerror(errno);
    throw InvalidArgumentError("record: path: cannot create '" + path + "': " + why);
  }
  return file;
}

class CsvWriter final : public RecordWriter {
 public:
  CsvWriter(const std::string& path, const std::string& events_path, bool overwrite) {
    samples_ = create(path, overwrite);
    if (!events_path.empty()) {
      try {
        events_ = create(events_path, overwrite);
      } catch (...) {
        std::fclose(samples_);
        std::error_code ignored;
        std::filesystem::remove(path, ignored);
        throw;
      }
    }
    // Whole batches go out at once; the writer flushes after each.
    std::setvbuf(samples_, nullptr, _IOFBF, 1 << 20);
    const auto columns = sample_columns();
    for (std::size_t i = 0; i < columns.size(); ++i) {
      std::fprintf(samples_, i == 0 ? "%s" : ",%s", columns[i].name);
    }
    std::fputc('\n', samples_);
    if (events_ != nullptr) {
      std::fputs("received_ns,kind,kind_name,session_id,server_time_s,item_id,message\n", events_);
    }
    // A file with its header from the start, whenever the process dies. A failure here (a full
    // disk) is left to the first batch's flush to report.
    std::string ignored;
    flush(ignored);
  }

  ~CsvWriter() override {
    if (samples_ != nullptr) std::fclose(samples_);
    if (events_ != nullptr) std::fclose(events_);
  }

  std::size_t write_samples(std::span<const State> samples, std::string& error) override {
    const auto columns = sample_columns();
    for (const State& state : samples) {
      for (std::size_t i = 0; i < columns.size(); ++i) {
        if (i > 0) std::fputc(',', samples_);
        put_cell(samples_, columns[i].type, columns[i].read(state));
      }
      std::fputc('\n', samples_);
    }
    return flushed(samples_, error) ? samples.size() : 0;
  }

  std::size_t write_events(std::span<const EventRecord> events, std::string& error) override {
    if (events_ == nullptr) return 0;
    for (const EventRecord& event : events) {
      std::fprintf(events_, "%" PRId64 ",%" PRId32 ",%s,%" PRIu64 ",", event.received_ns, event.kind,
                   event_kind_name(event.kind), event.session_id);
      put_cell(events_, ColumnType::kDouble, Cell{.f64 = event.server_time_s});
      std::fprintf(events_, ",%" PRIu64 ",", event.item_id);
      put_text(events_, event.message);
      std::fputc('\n', events_);
    }
    return flushed(events_, error) ? events.size() : 0;
  }

  bool flush(std::string& error) override {
    return flushed(samples_, error) && (events_ == nullptr || flushed(events_, error));
  }

  bool close(std::string& error) override {
    bool ok = true;
    for (std::FILE** file : {&samples_, &events_}) {
      if (*file == nullptr) continue;
      if (std::fclose(*file) != 0 && ok) {
        error = std::string("close: ") + std::strerror(errno);
        ok = false;
      }
      *file = nullptr;
    }
    return ok;
  }

 private:
  // After a failed write stdio keeps the error set; clearing it lets a later batch try again
  // (the disk may have room by then).
  static bool flushed(std::FILE* file, std::string& error) {
    if (std::fflush(file) == 0 && std::ferror(file) == 0) return true;
    error = std::string("write: ") + std::strerror(errno);
    std::clearerr(file);
    return false;
  }

  std::FILE* samples_ = nullptr;
  std::FILE* events_ = nullptr;
};

}  // namespace

std::unique_ptr<RecordWriter> make_csv_writer(const std::string& path, const std::string& events_path,
                                              bool overwrite) {
  return std::make_unique<CsvWriter>(path, events_path, overwrite);
}

}  // namespace haptic::detail
