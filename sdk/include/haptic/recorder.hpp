#pragma once
// haptic::Recorder: the session's samples in a file, as the client received them (docs/recorder.md).
// Link haptic::recorder (it brings HDF5; haptic::sdk alone does not).
//
//   haptic::Client client(config);
//   haptic::Recorder recorder(client, {.path = "session.h5"});
//   ... step or run ...
//   haptic::RecorderStats totals = recorder.close();  // drained, flushed and closed

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "haptic/client.hpp"

namespace haptic {

namespace detail {
class RecorderSink;
struct RecorderTestAccess;
}  // namespace detail

struct RecorderOptions {
  enum class Format {
    kAuto,  ///< by the path's extension: .csv, or .h5 / .hdf5
    kCsv,   ///< the samples in `path`, the events beside it in <stem>.events.csv
    kHdf5,  ///< one file: /samples and /events, one column dataset per field
  };
  /// The file to write. An existing file is refused unless `overwrite`.
  std::string path;
  Format format = Format::kAuto;
  /// Samples the queue between the receive thread and the writer holds (>= 1); a sample that
  /// finds it full is dropped and counted (RecorderStats::dropped). 65536: a minute at 1 kHz.
  std::size_t queue_capacity = 65536;
  /// Record the server's events (on a WatchEvents stream of the recorder's own; the Client's
  /// on_event stays the application's) and the connection's changes.
  bool events = true;
  /// Replace existing files instead of refusing them.
  bool overwrite = false;
};

struct RecorderStats {
  std::uint64_t samples_received = 0;  ///< States the client accepted while recording
  std::uint64_t samples_written = 0;   ///< of those, the ones in the file
  std::uint64_t dropped = 0;           ///< the ones that found the queue full
  std::uint64_t events_written = 0;    ///< server events and connection changes in the file
  std::uint64_t events_dropped = 0;    ///< the ones that found the event queue full
  /// Samples and events that reached the writer but not the file (a failed write: a full disk).
  std::uint64_t write_errors = 0;
  std::string first_error;  ///< the first failure's reason; empty if none
};

/// Records what a Client receives into a CSV or HDF5 file: every State it accepts (not only the
/// newest that on_state is handed), and with RecorderOptions::events the server's events and the
/// connection's changes. The receive thread only copies each sample into a bounded queue; a thread
/// of the recorder's writes it. Move-only; the destructor does what close() does, errors swallowed.
/// It does not take the Client's on_state, on_event or on_connection. Harmless if it outlives its
/// Client (it records nothing more). The writer flushes at least every 50 ms: a process that dies
/// while it records leaves files that open and hold every sample handed over up to 100 ms before
/// (an HDF5 file is written in SWMR mode, and opened with SWMR read after such a death;
/// docs/recorder.md, "What a crash leaves").
class Recorder {
 public:
  /// Creates the file(s) and starts recording. Throws InvalidArgumentError naming the field
  /// ("record: path: ...", "record: queue_capacity: ...") for bad options, a path that exists
  /// (without overwrite) or cannot be created; the server's refusal of the event stream. Nothing
  /// is left behind when it throws.
  Recorder(Client& client, const RecorderOptions& options);
  ~Recorder();
  Recorder(Recorder&& other) noexcept;
  Recorder& operator=(Recorder&& other) noexcept;
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  /// The totals so far (any thread).
  RecorderStats stats() const;
  /// Stops recording, writes what is queued, flushes and closes the file(s), and returns the
  /// totals; later calls return them again. Never throws: a failure is in write_errors and
  /// first_error.
  RecorderStats close() noexcept;
  /// Whether it still records (false after close() and once moved from).
  bool recording() const noexcept;
  /// The samples' file; with kCsv and events, events_path() holds the events.
  const std::string& path() const noexcept;
  /// The events' file: `path` itself for HDF5, <stem>.events.csv for CSV; empty without events.
  const std::string& events_path() const noexcept;

 private:
  friend struct detail::RecorderTestAccess;
  std::shared_ptr<detail::RecorderSink> sink_;
  ObserverHandle observer_;
};

}  // namespace haptic
