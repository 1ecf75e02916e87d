// What a recorder killed with SIGKILL leaves (docs/recorder.md, "What a crash leaves"): child
// processes record to HDF5 and CSV at once, at 1 kHz, through the recorder's own observer (its
// ring, its writer thread, its flushes), and are killed right after the recorders are made (before
// the first sample) and 0.2, 0.7, 1.5 and 3 s in. Each file then opens — with HDF5's C API and with
// h5py, as the page says — and holds every sample handed to the recorder up to a bound before the
// kill, in order and with no gap.
//
// The bound is judged by what the child reports, not by the parent's clock: the child names the
// last sample it handed over at least kCheckedAge before it asks to be killed. kCheckedAge is the
// documented 100 ms with a margin of twice that again, for a loaded machine whose writer thread
// waits its turn; the rows each file lost are printed.
#include <gtest/gtest.h>
#include <hdf5.h>

#include <poll.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <new>
#include <sstream>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "haptic/recorder.hpp"
#include "integration/run_program.hpp"
#include "record_format.hpp"
#include "recorder_test_access.hpp"

namespace haptic::detail {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

// docs/recorder.md: after a crash the files hold every sample handed over up to 100 ms before.
constexpr milliseconds kBound{100};
constexpr milliseconds kCheckedAge = 3 * kBound;
constexpr milliseconds kPeriod{1};          // 1 kHz
constexpr std::uint64_t kMaxSamples = 10000;  // more than the longest child hands over
const char* const kEventMessage = "object 1 created";

std::string folder() {
  return (fs::temp_directory_path() / ("recorder-crash-" + std::to_string(::getpid()))).string();
}

/// The child's count of samples handed to both recorders, where the parent reads it after the kill.
struct Progress {
  std::atomic<std::uint64_t> handed{0};
};

State sample(std::uint64_t i) {
  State s;
  s.tick = i;
  s.sequence = i;
  s.server_time = static_cast<double>(i) * 1e-3;
  s.position = {static_cast<double>(i) * 1e-6, 0.01, -0.02};
  s.force = {0.0, 0.0, static_cast<double>(i) * 1e-3};
  s.received_at = Clock::now();
  return s;
}

void write_all(int fd, std::uint64_t value) {
  if (::write(fd, &value, sizeof value) != static_cast<ssize_t>(sizeof value)) ::_exit(3);
}

/// The child: records to `stem`.h5 and `stem`.csv until killed. With `kill_at` zero it hands over
/// nothing and asks to be killed at once; else it hands over a sample a millisecond and, `kill_at`
/// in, writes to `report` the last sample handed over at least kCheckedAge before, and goes on.
[[noreturn]] void record_until_killed(const std::string& stem, milliseconds kill_at, int report,
                                      Progress* progress) {
  try {
    auto hdf5 = RecorderTestAccess::make_sink({.path = stem + ".h5"});
    auto csv = RecorderTestAccess::make_sink({.path = stem + ".csv"});
    if (kill_at.count() == 0) {
      write_all(report, 0);
      std::this_thread::sleep_for(std::chrono::seconds(30));
      ::_exit(4);  // never killed
    }
    Event event;
    event.kind = Event::Kind::kSceneChanged;
    event.item_id = 1;
    event.message = kEventMessage;
    hdf5->on_event(event);
    csv->on_event(event);
    std::vector<Clock::time_point> handed_at(kMaxSamples + 1);
    const Clock::time_point start = Clock::now();
    bool reported = false;
    for (std::uint64_t i = 1; i <= kMaxSamples; ++i) {
      std::this_thread::sleep_until(start + i * kPeriod);
      const State s = sample(i);
      hdf5->on_sample(s);
      csv->on_sample(s);
      handed_at[i] = Clock::now();
      progress->handed.store(i);
      if (!reported && handed_at[i] - start >= kill_at) {
        std::uint64_t old_enough = i;
        while (old_enough > 0 && handed_at[i] - handed_at[old_enough] < kCheckedAge) --old_enough;
        write_all(report, old_enough);
        reported = true;
      }
    }
  } catch (...) {
    ::_exit(2);
  }
  ::_exit(4);  // never killed
}

struct Child {
  milliseconds kill_at;
  std::string stem;
  pid_t pid = -1;
  int report = -1;
  Progress* progress = nullptr;
  std::uint64_t old_enough = 0;  // what the files must hold: samples 1 ..
  std::uint64_t handed = 0;      // handed over when it was killed
  bool killed = false;
};

/// What one file holds: the rows read in order, where they stop counting 1, 2, 3, ...
struct Held {
  bool opened = false;
  bool opened_plainly = false;  // without SWMR
  std::uint64_t rows = 0;       // HDF5: the shortest column
  std::uint64_t longest = 0;    // HDF5: the longest column
  std::uint64_t counting = 0;   // rows whose tick is their row number (1, 2, ...)
  std::string why;
};

std::uint64_t count_up(const std::vector<std::uint64_t>& ticks) {
  std::uint64_t n = 0;
  while (n < ticks.size() && ticks[n] == n + 1) ++n;
  return n;
}

Held read_hdf5(const std::string& path, std::vector<std::string>* event_messages) {
  Held held;
  hid_t file = -1;
  H5E_BEGIN_TRY {
    file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    held.opened_plainly = file >= 0;
    if (file < 0) file = H5Fopen(path.c_str(), H5F_ACC_RDONLY | H5F_ACC_SWMR_READ, H5P_DEFAULT);
  }
  H5E_END_TRY;
  if (file < 0) {
    held.why = "does not open";
    return held;
  }
  held.opened = true;
  const auto rows_of = [&](const std::string& name) -> std::int64_t {
    hid_t set = -1;
    H5E_BEGIN_TRY { set = H5Dopen2(file, name.c_str(), H5P_DEFAULT); }
    H5E_END_TRY;
    if (set < 0) return -1;
    const hid_t space = H5Dget_space(set);
    hsize_t n = 0;
    H5Sget_simple_extent_dims(space, &n, nullptr);
    H5Sclose(space);
    H5Dclose(set);
    return static_cast<std::int64_t>(n);
  };
  held.rows = UINT64_MAX;
  for (const SampleColumn& column : sample_columns()) {
    const std::int64_t n = rows_of(std::string("/samples/") + column.name);
    if (n < 0) {
      held.why += std::string(" no /samples/") + column.name + ";";
      held.rows = 0;
      continue;
    }
    held.rows = std::min<std::uint64_t>(held.rows, static_cast<std::uint64_t>(n));
    held.longest = std::max<std::uint64_t>(held.longest, static_cast<std::uint64_t>(n));
  }
  for (const char* column : {"received_ns", "kind", "kind_name", "session_id", "server_time_s",
                             "item_id", "message"}) {
    if (rows_of(std::string("/events/") + column) < 0) held.why += std::string(" no /events/") + column + ";";
  }
  if (held.why.empty() && held.rows > 0) {
    std::vector<std::uint64_t> ticks(held.rows);
    std::vector<double> x(held.rows);
    const hsize_t count[1] = {held.rows};
    const hid_t memory = H5Screate_simple(1, count, nullptr);
    for (const auto& [name, type, data] :
         {std::tuple{"/samples/tick", H5T_NATIVE_UINT64, static_cast<void*>(ticks.data())},
          std::tuple{"/samples/position_x_m", H5T_NATIVE_DOUBLE, static_cast<void*>(x.data())}}) {
      const hid_t set = H5Dopen2(file, name, H5P_DEFAULT);
      const hid_t space = H5Dget_space(set);
      const hsize_t start[1] = {0};
      H5Sselect_hyperslab(space, H5S_SELECT_SET, start, nullptr, count, nullptr);
      if (H5Dread(set, type, memory, space, H5P_DEFAULT, data) < 0) held.why += std::string(" cannot read ") + name;
      H5Sclose(space);
      H5Dclose(set);
    }
    H5Sclose(memory);
    held.counting = count_up(ticks);
    for (std::uint64_t r = 0; r < held.counting; ++r) {
      if (x[r] != static_cast<double>(r + 1) * 1e-6) {  // a row whose cells came from elsewhere
        held.counting = r;
        break;
      }
    }
  }
  if (held.why.empty() && event_messages != nullptr) {
    const std::int64_t n = rows_of("/events/message");
    if (n > 0) {
      const hid_t type = H5Tcopy(H5T_C_S1);
      H5Tset_size(type, H5T_VARIABLE);
      H5Tset_cset(type, H5T_CSET_UTF8);
      std::vector<char*> texts(static_cast<std::size_t>(n), nullptr);
      const hid_t set = H5Dopen2(file, "/events/message", H5P_DEFAULT);
      if (H5Dread(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, texts.data()) >= 0) {
        for (char* text : texts) {
          event_messages->emplace_back(text != nullptr ? text : "");
          H5free_memory(text);
        }
      } else {
        held.why += " cannot read /events/message";
      }
      H5Dclose(set);
      H5Tclose(type);
    }
  }
  H5Fclose(file);
  return held;
}

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

/// The CSV's whole lines (a last line without its newline was cut by the kill, and is not counted).
std::vector<std::string> whole_lines(const std::string& text) {
  std::vector<std::string> lines;
  std::size_t from = 0;
  for (std::size_t end; (end = text.find('\n', from)) != std::string::npos; from = end + 1) {
    lines.push_back(text.substr(from, end - from));
  }
  return lines;
}

Held read_csv(const std::string& path) {
  Held held;
  std::error_code error;
  if (!fs::exists(path, error)) {
    held.why = "does not exist";
    return held;
  }
  held.opened = held.opened_plainly = true;
  const std::vector<std::string> lines = whole_lines(read_text(path));
  std::string header;
  for (const SampleColumn& column : sample_columns()) header += (header.empty() ? "" : ",") + std::string(column.name);
  if (lines.empty() || lines[0] != header) {
    held.why = "no header";
    return held;
  }
  held.rows = held.longest = lines.size() - 1;
  std::vector<std::uint64_t> ticks;
  const auto columns = sample_columns();
  std::size_t tick_column = 0;
  while (std::string(columns[tick_column].name) != "tick") ++tick_column;
  for (std::size_t r = 1; r < lines.size(); ++r) {
    std::stringstream fields(lines[r]);
    std::string field;
    for (std::size_t c = 0; c <= tick_column; ++c) std::getline(fields, field, ',');
    ticks.push_back(std::strtoull(field.c_str(), nullptr, 10));
  }
  held.counting = count_up(ticks);
  return held;
}

/// h5py's reading of each file, as docs/recorder.md tells a reader to open one: its row count
/// ("rows N", where its ticks count 1 .. N) or why not.
std::map<std::string, std::string> read_with_h5py(const std::vector<std::string>& paths) {
  const test::Outcome outcome = test::run_program("/usr/bin/python3", [&] {
    std::vector<std::string> args = {RECORDER_CRASH_READ_PY};
    args.insert(args.end(), paths.begin(), paths.end());
    return args;
  }());
  EXPECT_EQ(outcome.exit_code, 0) << outcome.output;
  std::map<std::string, std::string> said;
  std::istringstream lines(outcome.output);
  for (std::string line; std::getline(lines, line);) {
    const std::size_t tab = line.find('\t');
    if (tab != std::string::npos) said[line.substr(0, tab)] = line.substr(tab + 1);
  }
  return said;
}

TEST(RecorderCrash, AFileKilledAtAnyMomentOpensAndHoldsEverySampleHandedOverBeforeTheBound) {
  const std::string dir = folder();
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::vector<Child> children;
  for (const int ms : {0, 200, 700, 1500, 3000}) {
    children.push_back({milliseconds(ms), dir + "/killed-" + std::to_string(ms) + "ms"});
  }

  // Every child is forked before this process starts a thread or opens HDF5; they run side by side.
  const pid_t parent = ::getpid();
  for (Child& child : children) {
    void* shared = ::mmap(nullptr, sizeof(Progress), PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0);
    ASSERT_NE(shared, MAP_FAILED);
    child.progress = new (shared) Progress;
    int fds[2];
    ASSERT_EQ(::pipe(fds), 0);
    child.pid = ::fork();
    ASSERT_GE(child.pid, 0);
    if (child.pid == 0) {
      ::prctl(PR_SET_PDEATHSIG, SIGKILL);  // never outlive the test
      if (::getppid() != parent) ::_exit(127);
      ::close(fds[0]);
      record_until_killed(child.stem, child.kill_at, fds[1], child.progress);
    }
    ::close(fds[1]);
    child.report = fds[0];
  }
  // Killed as each asks (in the order they ask), at once.
  for (Child& child : children) {
    pollfd ready{child.report, POLLIN, 0};
    const bool asked = ::poll(&ready, 1, 30'000) == 1 &&
                       ::read(child.report, &child.old_enough, sizeof child.old_enough) ==
                           static_cast<ssize_t>(sizeof child.old_enough);
    ::kill(child.pid, SIGKILL);
    int status = 0;
    ::waitpid(child.pid, &status, 0);
    child.killed = asked && WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL;
    child.handed = child.progress->handed.load();
    ::munmap(child.progress, sizeof(Progress));
    child.progress = nullptr;
    ::close(child.report);
    EXPECT_TRUE(child.killed) << child.kill_at.count() << " ms: the child ended by itself, status "
                              << status;
  }

  std::vector<std::string> h5_paths;
  for (const Child& child : children) h5_paths.push_back(child.stem + ".h5");
  const std::map<std::string, std::string> h5py_said = read_with_h5py(h5_paths);

  for (const Child& child : children) {
    const std::string when = std::to_string(child.kill_at.count()) + " ms";
    std::vector<std::string> messages;
    const Held h5 = read_hdf5(child.stem + ".h5", &messages);
    const Held csv = read_csv(child.stem + ".csv");
    const auto lost = [&](const Held& held) {
      return std::to_string(child.handed - std::min(child.handed, held.rows)) +
             (held.longest > held.rows ? ", columns up to " + std::to_string(held.longest) + " long" : "") +
             (!held.opened ? ", does not open" : !held.opened_plainly ? ", opened with SWMR read" : "");
    };
    std::printf("killed at %4lld ms: %4llu samples handed over, %4llu must be there; HDF5 %4llu rows "
                "(lost %s), CSV %4llu rows (lost %s)\n",
                static_cast<long long>(child.kill_at.count()), static_cast<unsigned long long>(child.handed),
                static_cast<unsigned long long>(child.old_enough), static_cast<unsigned long long>(h5.rows),
                lost(h5).c_str(), static_cast<unsigned long long>(csv.rows), lost(csv).c_str());
    for (const auto& [format, held] : {std::pair{"HDF5", &h5}, std::pair{"CSV", &csv}}) {
      if (!held->opened) {
        ADD_FAILURE() << when << ", " << format << ": " << held->why;
        continue;
      }
      EXPECT_TRUE(held->why.empty()) << when << ", " << format << ":" << held->why;
      // In order, no gap: every row there counts 1, 2, 3, ...
      EXPECT_EQ(held->counting, held->rows) << when << ", " << format << ": a row out of place";
      EXPECT_GE(held->rows, child.old_enough) << when << ", " << format << ": lost samples older than "
                                              << kCheckedAge.count() << " ms";
      EXPECT_LE(held->longest, child.handed + 1) << when << ", " << format;
    }
    // The one event, handed over before the first sample, is there with its text once that is.
    if (child.old_enough > 0) {
      EXPECT_TRUE(!messages.empty() && messages[0] == kEventMessage) << when << ": the event's text";
      const std::vector<std::string> event_lines = whole_lines(read_text(child.stem + ".events.csv"));
      EXPECT_TRUE(event_lines.size() >= 2 && event_lines[1].find(kEventMessage) != std::string::npos)
          << when << ": the event in the CSV";
    }
    const auto said = h5py_said.find(child.stem + ".h5");
    EXPECT_TRUE(said != h5py_said.end() && said->second == "rows " + std::to_string(h5.rows))
        << when << ": h5py says " << (said != h5py_said.end() ? said->second : "nothing");
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace haptic::detail
