// HDF5 (the C API): one file, the samples under /samples and the events under /events, one 1-D
// dataset per column (what MATLAB's h5read and h5py read most simply: h5read(f, '/samples/tick')),
// each chunked and extendible, appended a batch at a time. Units in each dataset's "unit"
// attribute; who and what was recorded in the root's attributes. HDF5's own error printing is
// held off around every call (H5E_BEGIN_TRY): a failure comes back as the recorder's error.
//
// Written in SWMR mode (single writer, multiple readers; HDF5 1.10's file format): once the layout
// is made, H5Fstart_swmr_write flushes it and from then on HDF5 writes in an order that keeps the
// file whole for a reader at every moment — a chunk before the index that finds it, the index
// before the length that counts it. So a process killed at any point leaves a file that opens
// (with SWMR read; HDF5 marks it open for writing until H5Fclose) and holds what the last flush
// made durable; the recorder flushes often (recorder.cpp, kFlushPeriod). docs/recorder.md, "What a
// crash leaves".
#include <hdf5.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <vector>

#include "haptic/client.hpp"
#include "haptic/error.hpp"
#include "haptic/version.hpp"
#include "record_format.hpp"

namespace haptic::detail {

namespace {

constexpr hsize_t kChunkRows = 1024;

// The innermost message of the HDF5 error stack (why, rather than which call).
std::string hdf5_error() {
  std::string last;
  H5Ewalk2(
      H5E_DEFAULT, H5E_WALK_UPWARD,
      [](unsigned, const H5E_error2_t* entry, void* data) -> herr_t {
        auto& text = *static_cast<std::string*>(data);
        if (text.empty() && entry->desc != nullptr) text = entry->desc;
        return 0;
      },
      &last);
  return last.empty() ? "HDF5 error" : last;
}

hid_t native(ColumnType type) {
  switch (type) {
    case ColumnType::kInt64: return H5T_NATIVE_INT64;
    case ColumnType::kUInt64: return H5T_NATIVE_UINT64;
    case ColumnType::kUInt32: return H5T_NATIVE_UINT32;
    case ColumnType::kDouble: return H5T_NATIVE_DOUBLE;
  }
  return H5T_NATIVE_DOUBLE;
}

std::size_t cell_size(ColumnType type) { return type == ColumnType::kUInt32 ? 4 : 8; }

class Hdf5Writer final : public RecordWriter {
 public:
  Hdf5Writer(const std::string& path, bool events, bool overwrite, const RecordingInfo& info)
      : path_(path) {
    bool ok = false;
    std::string why;
    std::error_code ignored;
    // What a failed creation removes: a file it made (HDF5 may make one and then fail to write
    // its superblock, a full device), or one `overwrite` had already truncated; never one it was
    // told not to touch.
    const bool was_there = std::filesystem::exists(path, ignored);
    H5E_BEGIN_TRY {
      string_type_ = H5Tcopy(H5T_C_S1);
      H5Tset_size(string_type_, H5T_VARIABLE);
      H5Tset_cset(string_type_, H5T_CSET_UTF8);
      // SWMR needs 1.10's format; named rather than H5F_LIBVER_LATEST, so that a newer HDF5 writes
      // files that 1.10 still reads.
      const hid_t access = H5Pcreate(H5P_FILE_ACCESS);
      H5Pset_libver_bounds(access, H5F_LIBVER_V110, H5F_LIBVER_V110);
      file_ = H5Fcreate(path.c_str(), overwrite ? H5F_ACC_TRUNC : H5F_ACC_EXCL, H5P_DEFAULT, access);
      H5Pclose(access);
      if (file_ < 0) {
        why = std::filesystem::exists(path) && !overwrite
                  ? "exists (RecorderOptions::overwrite replaces it)"
                  : hdf5_error();
      } else {
        // The layout made and flushed before the first sample: a file killed from here on opens,
        // with every dataset.
        ok = make_layout(events, info) && H5Fstart_swmr_write(file_) >= 0;
        if (!ok) why = hdf5_error();
      }
    }
    H5E_END_TRY;
    if (!ok) {
      release();
      if (!(was_there && !overwrite) && std::filesystem::exists(path, ignored)) {
        std::filesystem::remove(path, ignored);
      }
      throw InvalidArgumentError("record: path: cannot create '" + path + "': " + why);
    }
  }

  ~Hdf5Writer() override { release(); }

  std::size_t write_samples(std::span<const State> samples, std::string& error) override {
    if (samples.empty()) return 0;
    const auto columns = sample_columns();
    bool ok = true;
    H5E_BEGIN_TRY {
      for (std::size_t c = 0; c < columns.size() && ok; ++c) {
        const std::size_t size = cell_size(columns[c].type);
        buffer_.resize(samples.size() * size);
        for (std::size_t r = 0; r < samples.size(); ++r) {
          const Cell cell = columns[c].read(samples[r]);
          std::memcpy(buffer_.data() + r * size, &cell, size);  // the union's first bytes
        }
        ok = append(sample_sets_[c], samples_rows_, samples.size(), native(columns[c].type),
                    buffer_.data());
      }
      if (!ok) error = "write: " + hdf5_error();
    }
    H5E_END_TRY;
    // A batch whose columns did not all go in is kept out: every column stays as long as the rows.
    if (!ok) return 0;
    samples_rows_ += samples.size();
    return samples.size();
  }

  std::size_t write_events(std::span<const EventRecord> events, std::string& error) override {
    if (events.empty() || event_sets_.empty()) return 0;
    const std::size_t n = events.size();
    std::vector<std::int64_t> received(n);
    std::vector<std::int32_t> kind(n);
    std::vector<const char*> kind_name(n);
    std::vector<std::uint64_t> session(n);
    std::vector<double> server_time(n);
    std::vector<std::uint64_t> item(n);
    std::vector<const char*> message(n);
    for (std::size_t i = 0; i < n; ++i) {
      received[i] = events[i].received_ns;
      kind[i] = events[i].kind;
      kind_name[i] = event_kind_name(events[i].kind);
      session[i] = events[i].session_id;
      server_time[i] = events[i].server_time_s;
      item[i] = events[i].item_id;
      message[i] = events[i].message.c_str();
    }
    bool ok = true;
    H5E_BEGIN_TRY {
      ok = append(event_sets_[0], events_rows_, n, H5T_NATIVE_INT64, received.data()) &&
           append(event_sets_[1], events_rows_, n, H5T_NATIVE_INT32, kind.data()) &&
           append(event_sets_[2], events_rows_, n, string_type_, kind_name.data()) &&
           append(event_sets_[3], events_rows_, n, H5T_NATIVE_UINT64, session.data()) &&
           append(event_sets_[4], events_rows_, n, H5T_NATIVE_DOUBLE, server_time.data()) &&
           append(event_sets_[5], events_rows_, n, H5T_NATIVE_UINT64, item.data()) &&
           append(event_sets_[6], events_rows_, n, string_type_, message.data());
      if (!ok) error = "write: " + hdf5_error();
    }
    H5E_END_TRY;
    if (!ok) return 0;
    events_rows_ += n;
    return n;
  }

  bool flush(std::string& error) override {
    herr_t status = 0;
    H5E_BEGIN_TRY {
      // Every dataset's cached chunks, then the metadata that finds them, in SWMR's order.
      status = H5Fflush(file_, H5F_SCOPE_LOCAL);
      if (status < 0) error = "flush: " + hdf5_error();
    }
    H5E_END_TRY;
    return status >= 0;
  }

  bool close(std::string& error) override {
    bool ok = flush(error);
    herr_t status = 0;
    H5E_BEGIN_TRY {
      for (hid_t set : sample_sets_) H5Dclose(set);
      for (hid_t set : event_sets_) H5Dclose(set);
      sample_sets_.clear();
      event_sets_.clear();
      status = H5Fclose(file_);
      if (status < 0 && ok) error = "close: " + hdf5_error();
    }
    H5E_END_TRY;
    file_ = -1;
    return ok && status >= 0;
  }

 private:
  bool make_layout(bool events, const RecordingInfo& info) {
    const hid_t root = file_;
    const bool attributes =
        put_text(root, "format", "hapticd session recording") &&
        put_number(root, "format_version", H5T_NATIVE_UINT32, std::uint32_t{1}) &&
        put_text(root, "sdk_version", HAPTIC_VERSION) &&
        put_number(root, "api_version", H5T_NATIVE_UINT32, kApiVersion) &&
        put_text(root, "client_name", info.client_name) &&
        put_text(root, "server_address", info.server_address) &&
        put_text(root, "device_name", info.device_name) &&
        put_text(root, "device_model", info.device_model) &&
        put_number(root, "loop_rate_hz", H5T_NATIVE_DOUBLE, info.loop_rate_hz) &&
        put_number(root, "session_id", H5T_NATIVE_UINT64, info.session_id) &&
        put_number(root, "state_decimation", H5T_NATIVE_UINT32, info.state_decimation) &&
        put_text(root, "time_base",
                 "received_ns, arrived_ns: this host's steady clock (CLOCK_MONOTONIC); "
                 "server_time_s: the server's clock");
    if (!attributes) return false;
    const hid_t samples = H5Gcreate2(file_, "samples", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    if (samples < 0) return false;
    bool ok = true;
    for (const SampleColumn& column : sample_columns()) {
      const hid_t set = make_column(samples, column.name, native(column.type), column.unit);
      if (set < 0) {
        ok = false;
        break;
      }
      sample_sets_.push_back(set);
    }
    H5Gclose(samples);
    if (!ok || !events) return ok;
    const hid_t group = H5Gcreate2(file_, "events", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    if (group < 0) return false;
    const struct {
      const char* name;
      hid_t type;
      const char* unit;
    } event_columns[] = {{"received_ns", H5T_NATIVE_INT64, "ns"},   {"kind", H5T_NATIVE_INT32, ""},
                         {"kind_name", string_type_, ""},           {"session_id", H5T_NATIVE_UINT64, ""},
                         {"server_time_s", H5T_NATIVE_DOUBLE, "s"}, {"item_id", H5T_NATIVE_UINT64, ""},
                         {"message", string_type_, ""}};
    for (const auto& column : event_columns) {
      const hid_t set = make_column(group, column.name, column.type, column.unit);
      if (set < 0) {
        ok = false;
        break;
      }
      event_sets_.push_back(set);
    }
    H5Gclose(group);
    return ok;
  }

  // An empty 1-D dataset that grows without limit, in chunks of kChunkRows.
  hid_t make_column(hid_t group, const char* name, hid_t type, const char* unit) {
    const hsize_t dims[1] = {0};
    const hsize_t max_dims[1] = {H5S_UNLIMITED};
    const hid_t space = H5Screate_simple(1, dims, max_dims);
    const hid_t properties = H5Pcreate(H5P_DATASET_CREATE);
    const hsize_t chunk[1] = {kChunkRows};
    H5Pset_chunk(properties, 1, chunk);
    const hid_t set = H5Dcreate2(group, name, type, space, H5P_DEFAULT, properties, H5P_DEFAULT);
    H5Pclose(properties);
    H5Sclose(space);
    if (set >= 0 && unit[0] != '\0' && !put_text(set, "unit", unit)) {
      H5Dclose(set);
      return -1;
    }
    return set;
  }

  bool put_text(hid_t owner, const char* name, const std::string& value) {
    const hid_t space = H5Screate(H5S_SCALAR);
    const hid_t attribute = H5Acreate2(owner, name, string_type_, space, H5P_DEFAULT, H5P_DEFAULT);
    const char* text = value.c_str();
    const bool ok = attribute >= 0 && H5Awrite(attribute, string_type_, &text) >= 0;
    if (attribute >= 0) H5Aclose(attribute);
    H5Sclose(space);
    return ok;
  }

  template <typename Number>
  bool put_number(hid_t owner, const char* name, hid_t type, Number value) {
    const hid_t space = H5Screate(H5S_SCALAR);
    const hid_t attribute = H5Acreate2(owner, name, type, space, H5P_DEFAULT, H5P_DEFAULT);
    const bool ok = attribute >= 0 && H5Awrite(attribute, type, &value) >= 0;
    if (attribute >= 0) H5Aclose(attribute);
    H5Sclose(space);
    return ok;
  }

  // Grows `set` from `rows` to rows + n and writes the n new cells from `data`.
  static bool append(hid_t set, hsize_t rows, std::size_t n, hid_t type, const void* data) {
    const hsize_t size[1] = {rows + n};
    if (H5Dset_extent(set, size) < 0) return false;
    const hid_t file_space = H5Dget_space(set);
    const hsize_t start[1] = {rows};
    const hsize_t count[1] = {n};
    const hid_t memory_space = H5Screate_simple(1, count, nullptr);
    const bool ok = file_space >= 0 && memory_space >= 0 &&
                    H5Sselect_hyperslab(file_space, H5S_SELECT_SET, start, nullptr, count, nullptr) >= 0 &&
                    H5Dwrite(set, type, memory_space, file_space, H5P_DEFAULT, data) >= 0;
    if (memory_space >= 0) H5Sclose(memory_space);
    if (file_space >= 0) H5Sclose(file_space);
    return ok;
  }

  void release() noexcept {
    H5E_BEGIN_TRY {
      for (hid_t set : sample_sets_) H5Dclose(set);
      for (hid_t set : event_sets_) H5Dclose(set);
      sample_sets_.clear();
      event_sets_.clear();
      if (file_ >= 0) H5Fclose(file_);
      if (string_type_ >= 0) H5Tclose(string_type_);
    }
    H5E_END_TRY;
    file_ = -1;
    string_type_ = -1;
  }

  std::string path_;
  hid_t file_ = -1;
  hid_t string_type_ = -1;
  std::vector<hid_t> sample_sets_;
  std::vector<hid_t> event_sets_;
  hsize_t samples_rows_ = 0;
  hsize_t events_rows_ = 0;
  std::vector<unsigned char> buffer_;  // one column of a batch
};

}  // namespace

std::unique_ptr<RecordWriter> make_hdf5_writer(const std::string& path, bool events, bool overwrite,
                                               const RecordingInfo& info) {
  return std::make_unique<Hdf5Writer>(path, events, overwrite, info);
}

}  // namespace haptic::detail
