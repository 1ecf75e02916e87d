// The session recorder's parts without a server: the ring refuses when full and keeps order across
// wrap-arounds; the CSV and HDF5 writers read back exactly, extreme values included (NaN, -0,
// the smallest subnormal, the largest double and uint64), and a CSV message keeps its quotes and
// commas.
#include <gtest/gtest.h>
#include <hdf5.h>

#include <sched.h>
#include <sys/mount.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <span>
#include <sstream>
#include <string>
#include <vector>

#include "haptic/error.hpp"

#include "record_format.hpp"
#include "sample_queue.hpp"

namespace haptic::detail {
namespace {

namespace fs = std::filesystem;

std::string temp_file(const std::string& name) {
  return (fs::temp_directory_path() / ("recorder-unit-" + std::to_string(::getpid()) + "-" + name))
      .string();
}

State extreme_state() {
  State s;
  s.tick = std::numeric_limits<std::uint64_t>::max();
  s.sequence = 7;
  s.server_time = 0.1 + 0.2;  // not 0.3: every digit must survive
  s.position = {-0.0, std::numeric_limits<double>::denorm_min(), std::numeric_limits<double>::max()};
  s.velocity = {1.0 / 3.0, -2.0 / 3.0, 1e-300};
  s.force = {-5.000000000000001, 0.0, 123456.789};
  s.proxy = s.position;
  s.contact_count = 2;
  s.flags = kForceSaturated | kRampingOut;
  s.buttons = 0xffffffffu;
  s.orientation = Quaternion{std::sqrt(0.5), 0.0, 0.0, std::sqrt(0.5)};
  s.torque = Vec3{1e-9, -1e-9, 0.0};
  s.received_at = std::chrono::steady_clock::time_point(std::chrono::nanoseconds(123456789012345));
  s.arrived_at = std::chrono::steady_clock::time_point(std::chrono::nanoseconds(123456789000000));
  s.age = std::chrono::nanoseconds(-5);
  return s;
}

State plain_state() {
  State s;
  s.tick = 8;
  s.received_at = std::chrono::steady_clock::time_point(std::chrono::nanoseconds(1));
  return s;  // no orientation, torque or kernel stamp
}

bool same(double a, double b) { return (std::isnan(a) && std::isnan(b)) || (a == b && std::signbit(a) == std::signbit(b)); }

TEST(SampleQueue, RefusesWhenFullAndKeepsOrderAcrossWrapArounds) {
  SampleQueue queue(3);
  std::vector<State> out;
  std::uint64_t next = 1, expected = 1;
  for (int round = 0; round < 10; ++round) {
    for (int i = 0; i < 3; ++i) {
      State s;
      s.tick = next++;
      ASSERT_TRUE(queue.push(s));
    }
    State extra;
    EXPECT_FALSE(queue.push(extra));  // full: refused, nothing stored
    EXPECT_EQ(queue.pop(out, 2), 2u);
    EXPECT_EQ(queue.pop(out, 10), 1u);
    ASSERT_EQ(out.size(), 1u);
    EXPECT_TRUE(queue.empty());
    expected += 3;
    EXPECT_EQ(out[0].tick, expected - 1);
  }
}

TEST(RecordFormat, KindNamesCoverEveryEventAndConnectionChange) {
  EXPECT_STREQ(event_kind_name(static_cast<std::int32_t>(Event::Kind::kWatchStarted)), "watch_started");
  EXPECT_STREQ(event_kind_name(static_cast<std::int32_t>(Event::Kind::kReset)), "reset");
  const EventRecord lost = event_record(
      ConnectionChange{ConnectionChange::State::kLost, 5, false, 0, "gone", {}}, 10);
  EXPECT_EQ(lost.kind, 101);
  EXPECT_STREQ(event_kind_name(lost.kind), "connection_lost");
  EXPECT_TRUE(std::isnan(lost.server_time_s));
  EXPECT_STREQ(event_kind_name(99), "unknown");
}

TEST(CsvWriter, EveryValueReadsBackExactlyAndMessagesKeepTheirQuotes) {
  const std::string path = temp_file("w.csv"), events = temp_file("w.events.csv");
  fs::remove(path);
  fs::remove(events);
  {
    auto writer = make_csv_writer(path, events, false);
    std::string error;
    const std::vector<State> states = {extreme_state(), plain_state()};
    EXPECT_EQ(writer->write_samples(states, error), 2u) << error;
    Event event;
    event.kind = Event::Kind::kSceneChanged;
    event.message = R"(object "a,b" created)";
    const std::vector<EventRecord> records = {event_record(event, 42)};
    EXPECT_EQ(writer->write_events(records, error), 1u) << error;
    EXPECT_TRUE(writer->close(error)) << error;
  }
  std::ifstream in(path);
  std::string header, first, second;
  std::getline(in, header);
  std::getline(in, first);
  std::getline(in, second);
  const auto columns = sample_columns();
  std::vector<std::string> names, cells, plain;
  for (std::stringstream h(header); std::getline(h, names.emplace_back(), ',');) {}
  names.pop_back();
  for (std::stringstream f(first); std::getline(f, cells.emplace_back(), ',');) {}
  cells.pop_back();
  for (std::stringstream f(second); std::getline(f, plain.emplace_back(), ',');) {}
  plain.pop_back();
  ASSERT_EQ(names.size(), columns.size());
  ASSERT_EQ(cells.size(), columns.size());
  ASSERT_EQ(plain.size(), columns.size());
  const State s = extreme_state();
  for (std::size_t i = 0; i < columns.size(); ++i) {
    EXPECT_EQ(names[i], columns[i].name);
    const Cell want = columns[i].read(s);
    switch (columns[i].type) {
      case ColumnType::kDouble:
        // strtod: std::stod throws on a subnormal (strtod's ERANGE) though it reads it exactly.
        EXPECT_TRUE(same(std::strtod(cells[i].c_str(), nullptr), want.f64)) << names[i] << " " << cells[i];
        break;
      case ColumnType::kInt64: EXPECT_EQ(std::stoll(cells[i]), want.i64) << names[i]; break;
      case ColumnType::kUInt64: EXPECT_EQ(std::stoull(cells[i]), want.u64) << names[i]; break;
      case ColumnType::kUInt32: EXPECT_EQ(std::stoul(cells[i]), want.u32) << names[i]; break;
    }
  }
  for (std::size_t i = 0; i < columns.size(); ++i) {
    if (names[i].rfind("orientation_", 0) == 0 || names[i].rfind("torque_", 0) == 0) {
      EXPECT_EQ(plain[i], "NaN") << names[i];
    }
    if (names[i] == "arrived_ns") {
      EXPECT_EQ(plain[i], "-1");
    }
  }
  std::ifstream event_in(events);
  std::string event_header, event_row;
  std::getline(event_in, event_header);
  std::getline(event_in, event_row);
  EXPECT_EQ(event_header, "received_ns,kind,kind_name,session_id,server_time_s,item_id,message");
  EXPECT_EQ(event_row, R"(42,4,scene_changed,0,0,0,"object ""a,b"" created")");
  fs::remove(path);
  fs::remove(events);
}

TEST(CsvWriter, AnExistingFileIsRefusedAndKept) {
  const std::string path = temp_file("kept.csv");
  std::ofstream(path) << "mine";
  EXPECT_THROW(make_csv_writer(path, "", false), InvalidArgumentError);
  std::string kept;
  std::getline(std::ifstream(path), kept);
  EXPECT_EQ(kept, "mine");
  fs::remove(path);
}

TEST(Hdf5Writer, EveryValueReadsBackExactlyInItsNativeType) {
  const std::string path = temp_file("w.h5");
  fs::remove(path);
  {
    auto writer = make_hdf5_writer(path, true, false, RecordingInfo{"unit", "", "", "", 0.0, 0, 1});
    std::string error;
    const std::vector<State> states = {extreme_state(), plain_state()};
    // Two appends, the second past nothing: rows follow each other.
    EXPECT_EQ(writer->write_samples(std::span(states).first(1), error), 1u) << error;
    EXPECT_EQ(writer->write_samples(std::span(states).subspan(1), error), 1u) << error;
    EXPECT_TRUE(writer->close(error)) << error;
  }
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  const State s = extreme_state();
  for (const SampleColumn& column : sample_columns()) {
    const hid_t set = H5Dopen2(file, (std::string("/samples/") + column.name).c_str(), H5P_DEFAULT);
    ASSERT_GE(set, 0) << column.name;
    const hid_t type = H5Dget_type(set);
    const hid_t native = column.type == ColumnType::kDouble   ? H5T_NATIVE_DOUBLE
                         : column.type == ColumnType::kInt64  ? H5T_NATIVE_INT64
                         : column.type == ColumnType::kUInt64 ? H5T_NATIVE_UINT64
                                                              : H5T_NATIVE_UINT32;
    EXPECT_GT(H5Tequal(type, native), 0) << column.name << " is not stored in its native type";
    std::uint64_t raw[2] = {0, 0};  // two rows of up to 8 bytes
    ASSERT_GE(H5Dread(set, native, H5S_ALL, H5S_ALL, H5P_DEFAULT, raw), 0);
    const Cell want = column.read(s);
    switch (column.type) {
      case ColumnType::kDouble: {
        double values[2];
        std::memcpy(values, raw, sizeof values);
        EXPECT_TRUE(same(values[0], want.f64)) << column.name;
        break;
      }
      case ColumnType::kInt64: EXPECT_EQ(static_cast<std::int64_t>(raw[0]), want.i64) << column.name; break;
      case ColumnType::kUInt64: EXPECT_EQ(raw[0], want.u64) << column.name; break;
      case ColumnType::kUInt32: {
        std::uint32_t values[2];
        std::memcpy(values, raw, sizeof values);
        EXPECT_EQ(values[0], want.u32) << column.name;
        break;
      }
    }
    H5Tclose(type);
    H5Dclose(set);
  }
  H5Fclose(file);
  fs::remove(path);
}

/// Descriptors of this process open on `path`.
int descriptors_on(const std::string& path) {
  int count = 0;
  for (const auto& entry : fs::directory_iterator("/proc/self/fd")) {
    std::error_code error;
    if (fs::read_symlink(entry.path(), error) == path) ++count;
  }
  return count;
}

// A device that fails under the recording (the disk fills): the write fails and is said, closing
// fails and is said, and neither the HDF5 file handle nor its descriptor is left open (the
// recorder used to keep both until the process exited). A 96 KiB tmpfs in a mount namespace of
// this test's own stands in for the failing device.
TEST(Hdf5Writer, ADeviceThatFailsLeavesNoHandleOrDescriptorOpen) {
  if (::unshare(CLONE_NEWNS) != 0 || ::mount("none", "/", nullptr, MS_REC | MS_PRIVATE, nullptr) != 0) {
    GTEST_SKIP() << "no mount namespace here (not root?)";
  }
  const std::string dir = temp_file("tiny-device");
  fs::create_directories(dir);
  ASSERT_EQ(::mount("tmpfs", dir.c_str(), "tmpfs", 0, "size=96k"), 0) << std::strerror(errno);
  const std::string path = dir + "/full.h5";
  const ssize_t handles_before = H5Fget_obj_count(H5F_OBJ_ALL, H5F_OBJ_FILE);
  {
    auto writer = make_hdf5_writer(path, false, false, RecordingInfo{"unit", "", "", "", 0.0, 0, 1});
    std::vector<State> batch(256, plain_state());
    std::string error;
    bool failed = false;
    for (int i = 0; i < 400 && !failed; ++i) {  // 100 k samples: far more than 96 KiB holds
      failed = writer->write_samples(batch, error) == 0 || !writer->flush(error);
    }
    ASSERT_TRUE(failed) << "the device never filled";
    EXPECT_FALSE(error.empty());
    std::string closing;
    EXPECT_FALSE(writer->close(closing)) << "closing a file whose flush fails must say so";
    EXPECT_FALSE(closing.empty());
    EXPECT_EQ(H5Fget_obj_count(H5F_OBJ_ALL, H5F_OBJ_FILE), handles_before) << "an HDF5 file handle is left";
    EXPECT_EQ(descriptors_on(path), 0) << "a descriptor on the file is left";
  }
  EXPECT_EQ(H5Fget_obj_count(H5F_OBJ_ALL, H5F_OBJ_FILE), handles_before);
  EXPECT_EQ(descriptors_on(path), 0);
  // A device too full for even the file's layout: refused at once, naming the path, nothing left
  // open and no file left behind.
  fs::remove(path);
  const std::string filler = dir + "/filler";
  {
    std::ofstream fill(filler, std::ios::binary);
    const std::string block(1024, 'x');
    while (fill.write(block.data(), block.size())) {
    }
  }
  fs::resize_file(filler, fs::file_size(filler) - 1024);  // room for the superblock, not the layout
  try {
    (void)make_hdf5_writer(path, true, false, RecordingInfo{"unit", "", "", "", 0.0, 0, 1});
    ADD_FAILURE() << "a file was made on a full device";
  } catch (const InvalidArgumentError& refused) {
    EXPECT_NE(std::string(refused.what()).find("cannot create '" + path + "'"), std::string::npos) << refused.what();
  }
  EXPECT_EQ(H5Fget_obj_count(H5F_OBJ_ALL, H5F_OBJ_FILE), handles_before) << "an HDF5 file handle is left";
  EXPECT_EQ(descriptors_on(path), 0) << "a descriptor on the file is left";
  EXPECT_FALSE(fs::exists(path));
  ::umount2(dir.c_str(), MNT_DETACH);
}

}  // namespace
}  // namespace haptic::detail
