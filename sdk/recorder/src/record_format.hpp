#pragma once
// What a recording holds, once for both formats: the samples' columns (name with its unit, type,
// and how each is read from a State) and the events' records; and the writer interface the CSV and
// HDF5 writers implement (docs/recorder.md lists the columns).

#include <chrono>
#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "haptic/types.hpp"

namespace haptic::detail {

/// A column's type in the file: HDF5's native type, CSV's number format.
enum class ColumnType { kInt64, kUInt64, kUInt32, kDouble };

/// One cell, as its column's type says.
union Cell {
  std::int64_t i64;
  std::uint64_t u64;
  std::uint32_t u32;
  double f64;
};

struct SampleColumn {
  const char* name;  ///< with its unit where it has one: position_x_m
  const char* unit;  ///< SI, as the HDF5 attribute "unit" says it; "" for counts and bits
  ColumnType type;
  Cell (*read)(const State& state);
};

/// The samples' columns, in file order.
std::span<const SampleColumn> sample_columns();

/// Steady-clock nanoseconds of a time point (the recording's received_ns, arrived_ns).
std::int64_t steady_ns(std::chrono::steady_clock::time_point at);

/// One row of the events table: a server event or a change of the connection.
struct EventRecord {
  std::int64_t received_ns = 0;  ///< local steady clock when the SDK handed it over
  std::int32_t kind = 0;         ///< Event::Kind's value; 100 + ConnectionChange::State's
  std::uint64_t session_id = 0;
  double server_time_s = 0.0;    ///< NaN for a connection change (the server did not stamp it)
  std::uint64_t item_id = 0;
  std::string message;           ///< Event::message, or ConnectionChange::reason
};

/// The code of connection changes in EventRecord::kind: 100 + the state's value.
inline constexpr std::int32_t kConnectionKindBase = 100;
EventRecord event_record(const Event& event, std::int64_t received_ns);
EventRecord event_record(const ConnectionChange& change, std::int64_t received_ns);
/// "scene_changed", "connection_lost", ...; "unknown" for codes it does not know.
const char* event_kind_name(std::int32_t kind);

/// Who and what was recorded: written once, as the files' attributes (HDF5) or nowhere (CSV).
struct RecordingInfo {
  std::string client_name;
  std::string server_address;
  std::string device_name;
  std::string device_model;
  double loop_rate_hz = 0.0;
  std::uint64_t session_id = 0;
  std::uint32_t state_decimation = 0;
};

/// Writes the records to a file. Used by one thread at a time (the recorder's writer). Each call
/// returns how many records reached the file; the rest failed and `error` says why.
class RecordWriter {
 public:
  virtual ~RecordWriter() = default;
  virtual std::size_t write_samples(std::span<const State> samples, std::string& error) = 0;
  virtual std::size_t write_events(std::span<const EventRecord> events, std::string& error) = 0;
  /// Makes what was written durable enough to read back from another process.
  virtual bool flush(std::string& error) = 0;
  /// Flushes and closes; false (with `error`) if that failed. Called once.
  virtual bool close(std::string& error) = 0;
};

/// The writer for `path` (CSV: `events_path` too, when not empty). Creates the files exclusively
/// unless `overwrite`; throws InvalidArgumentError("record: path: ...") when it cannot, having
/// removed whatever it created.
std::unique_ptr<RecordWriter> make_csv_writer(const std::string& path, const std::string& events_path,
                                              bool overwrite);
std::unique_ptr<RecordWriter> make_hdf5_writer(const std::string& path, bool events, bool overwrite,
                                               const RecordingInfo& info);

}  // namespace haptic::detail
