// haptic::Recorder against a lockstep hapticd: every State the client accepts is in the CSV and the
// HDF5 file, every field of every sample the on_state callback saw reads back exactly (by tick);
// the server's events and the recorder's own event stream sit beside the application's; a queue
// that cannot take a sample drops and counts it; a failing disk is counted; bad options are
// refused naming the field, leaving nothing behind.
#include <gtest/gtest.h>
#include <hdf5.h>

#include <haptic/haptic.hpp>
#include <haptic/recorder.hpp>

#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "integration/recording_files.hpp"
#include "integration/sdk_harness.hpp"
#include "integration/server_process.hpp"
#include "recorder_test_access.hpp"

namespace haptic {
namespace {

namespace fs = std::filesystem;
using test::config_for;
using test::Csv;
using test::Row;
using test::TempDir;
using test::csv_rows;
using test::h5_column;
using test::h5_rows;
using test::h5_strings;
using test::h5_text_attribute;
using test::read_csv;
using test::same;
using test::expected_row;

/// Lockstep, the 6-DOF handle (orientation and torque in every State).
std::string six_dof_config() {
  return R"({"time_mode": "LOCKSTEP", "udp_address": "127.0.0.1", "status_period_s": 0,
             "real_time": {"use_fifo": false},
             "simulated_point_mass": {"rotation": {"initial_orientation":
                 {"w": 0.9950041652780258, "z": 0.09983341664682815}}}})";
}

/// What the application's on_state callback saw, by tick.
class Seen {
 public:
  void attach(Client& client) {
    client.on_state([this](const State& state) {
      std::lock_guard lock(mutex_);
      states_[state.tick] = state;
      arrived_.notify_all();
    });
  }
  /// Waits until the callback has seen `tick` (the newest of a step's burst is always handed out).
  bool wait(std::uint64_t tick) {
    std::unique_lock lock(mutex_);
    return arrived_.wait_for(lock, std::chrono::seconds(10), [&] { return states_.count(tick) > 0; });
  }
  std::map<std::uint64_t, State> states() const {
    std::lock_guard lock(mutex_);
    return states_;
  }

 private:
  mutable std::mutex mutex_;
  std::condition_variable arrived_;
  std::map<std::uint64_t, State> states_;
};

/// Steps `chunks` × `ticks`, each time until the callback has the chunk's last tick (so no burst
/// outgrows the socket's buffer).
void step_seen(Client& client, Seen& seen, int chunks, std::uint32_t ticks) {
  for (int i = 0; i < chunks; ++i) {
    const std::uint64_t last = client.step(ticks);
    ASSERT_TRUE(seen.wait(last)) << "the callback never saw tick " << last;
  }
}

/// Polls `done` until it holds or 10 s pass (the event streams are asynchronous).
template <typename Predicate>
bool eventually(Predicate done) {
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (!done()) {
    if (std::chrono::steady_clock::now() > give_up) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return true;
}

// ---- reading back: tests/integration/recording_files.hpp ----

/// Every sample the callback saw is in `rows` (by tick) with every field the same; the file has one
/// row per received sample, in the order received (ticks rising).
void expect_rows_hold(const std::vector<Row>& rows, const std::map<std::uint64_t, State>& seen,
                      const std::string& what) {
  std::map<std::int64_t, const Row*> by_tick;
  std::int64_t previous = 0;
  for (const Row& row : rows) {
    const std::int64_t tick = row.integer.at("tick");
    EXPECT_GT(tick, previous) << what << ": ticks out of order";
    previous = tick;
    by_tick[tick] = &row;
  }
  ASSERT_FALSE(seen.empty());
  for (const auto& [tick, state] : seen) {
    const auto found = by_tick.find(static_cast<std::int64_t>(tick));
    ASSERT_NE(found, by_tick.end()) << what << ": no row for tick " << tick;
    const Row want = expected_row(state);
    for (const auto& [name, value] : want.real) {
      EXPECT_TRUE(same(found->second->real.at(name), value))
          << what << " tick " << tick << " " << name << ": " << found->second->real.at(name) << " vs " << value;
    }
    for (const auto& [name, value] : want.integer) {
      EXPECT_EQ(found->second->integer.at(name), value) << what << " tick " << tick << " " << name;
    }
  }
}

// ---- the tests ----

struct Run {
  RecorderStats csv, hdf5;
  std::uint64_t accepted = 0;
  std::map<std::uint64_t, State> seen;
  std::vector<Event> application_events;
};

/// Records one session to CSV and HDF5 at once, while the application's callbacks watch: a wall,
/// the hand pushing into it, the wall removed.
Run record_session(Client& client, const TempDir& dir) {
  Run run;
  Seen seen;
  seen.attach(client);
  std::mutex events_mutex;
  client.on_event([&](const Event& event) {
    std::lock_guard lock(events_mutex);
    run.application_events.push_back(event);
  });
  const std::uint64_t accepted_before = client.receive_counters().accepted;
  Recorder csv(client, {.path = dir.file("session.csv")});
  Recorder hdf5(client, {.path = dir.file("session.h5")});
  EXPECT_TRUE(csv.recording());
  EXPECT_EQ(csv.events_path(), dir.file("session.events.csv"));
  EXPECT_EQ(hdf5.events_path(), dir.file("session.h5"));

  ObjectHandle wall = client.add_wall({.point = {0, 0, 0}, .normal = {0, 0, 1}, .impedance = {1000, 1}});
  client.set_operator(OperatorInput::push({0.0, 0.0, -5.0}));
  step_seen(client, seen, 8, 25);
  wall.remove();
  step_seen(client, seen, 4, 25);
  // The recorders' streams are their own: wait until each has written the wall's two changes.
  EXPECT_TRUE(eventually([&] { return csv.stats().events_written >= 3 && hdf5.stats().events_written >= 3; }));
  run.accepted = client.receive_counters().accepted - accepted_before;
  run.csv = csv.close();
  run.hdf5 = hdf5.close();
  EXPECT_FALSE(csv.recording());
  client.on_state({});
  client.on_event({});
  run.seen = seen.states();
  return run;
}

void expect_totals(const RecorderStats& stats, std::uint64_t accepted, const char* what) {
  EXPECT_EQ(stats.samples_received, accepted) << what;
  EXPECT_EQ(stats.samples_written, accepted) << what;
  EXPECT_EQ(stats.dropped, 0u) << what;
  EXPECT_EQ(stats.write_errors, 0u) << what;
  EXPECT_EQ(stats.first_error, "") << what;
  EXPECT_GE(stats.events_written, 3u) << what;  // watch started, the wall made and deleted
}

void expect_csv_events(const std::string& path) {
  const Csv events = read_csv(path);
  EXPECT_EQ(events.header, (std::vector<std::string>{"received_ns", "kind", "kind_name", "session_id",
                                                     "server_time_s", "item_id", "message"}));
  ASSERT_GE(events.rows.size(), 3u);
  EXPECT_EQ(events.rows[0][events.column("kind")], std::to_string(static_cast<int>(Event::Kind::kWatchStarted)));
  EXPECT_EQ(events.rows[0][events.column("kind_name")], "watch_started");
  std::vector<std::string> scene;
  for (const auto& row : events.rows) {
    if (row[events.column("kind_name")] == "scene_changed") scene.push_back(row[events.column("message")]);
  }
  ASSERT_EQ(scene.size(), 2u);
  EXPECT_NE(scene[0].find("created"), std::string::npos) << scene[0];
  EXPECT_NE(scene[1].find("deleted"), std::string::npos) << scene[1];
}

void expect_h5_file(const std::string& path, const Run& run, const Client& client) {
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(file, 0) << "cannot open " << path;
  const std::vector<Row> rows = h5_rows(file);
  EXPECT_EQ(rows.size(), run.hdf5.samples_written);
  expect_rows_hold(rows, run.seen, "HDF5");
  EXPECT_EQ(h5_text_attribute(file, "/samples/position_x_m", "unit"), "m");
  EXPECT_EQ(h5_text_attribute(file, "/samples/force_z_N", "unit"), "N");
  EXPECT_EQ(h5_text_attribute(file, "/", "device_name"), client.device_info().name);
  EXPECT_EQ(h5_text_attribute(file, "/", "client_name"), "recorder");
  EXPECT_EQ(h5_text_attribute(file, "/", "server_address"), client.config().server_address);
  const auto kinds = h5_column<std::int32_t>(file, "/events/kind", H5T_NATIVE_INT32);
  const auto names = h5_strings(file, "/events/kind_name");
  const auto messages = h5_strings(file, "/events/message");
  EXPECT_EQ(kinds.size(), run.hdf5.events_written);
  ASSERT_EQ(names.size(), kinds.size());
  ASSERT_EQ(messages.size(), kinds.size());
  ASSERT_FALSE(kinds.empty());
  EXPECT_EQ(kinds[0], static_cast<std::int32_t>(Event::Kind::kWatchStarted));
  EXPECT_EQ(names[0], "watch_started");
  int scene_changes = 0;
  for (std::size_t i = 0; i < kinds.size(); ++i) {
    if (kinds[i] == static_cast<std::int32_t>(Event::Kind::kSceneChanged)) {
      ++scene_changes;
      EXPECT_EQ(names[i], "scene_changed");
      EXPECT_NE(messages[i].find(scene_changes == 1 ? "created" : "deleted"), std::string::npos) << messages[i];
    }
  }
  EXPECT_EQ(scene_changes, 2);
  H5Fclose(file);
}

void expect_session_recorded(Client& client) {
  TempDir dir;
  const Run run = record_session(client, dir);
  EXPECT_GT(run.accepted, 0u);
  // Only the newest of each read was handed to the callback; the files have every sample.
  EXPECT_LE(run.seen.size(), run.accepted);
  expect_totals(run.csv, run.accepted, "CSV");
  expect_totals(run.hdf5, run.accepted, "HDF5");

  const Csv csv = read_csv(dir.file("session.csv"));
  EXPECT_EQ(csv.header.front(), "received_ns");
  EXPECT_EQ(csv.rows.size(), run.csv.samples_written);
  expect_rows_hold(csv_rows(csv), run.seen, "CSV");
  expect_csv_events(dir.file("session.events.csv"));
  expect_h5_file(dir.file("session.h5"), run, client);

  // The application's own event stream went on beside the recorders'.
  ASSERT_FALSE(run.application_events.empty());
  EXPECT_EQ(run.application_events.front().kind, Event::Kind::kWatchStarted);
}

TEST(Recorder, EveryAcceptedSampleOfAPointMassReadsBackAsTheCallbackSawIt) {
  test::ServerProcess server(test::lockstep_config());
  Client client(config_for(server, "recorder"));
  ASSERT_FALSE(client.device_info().capabilities.orientation);
  expect_session_recorded(client);  // orientation and torque NaN
}

TEST(Recorder, EveryAcceptedSampleOfASixDofHandleReadsBackWithItsOrientationAndTorque) {
  test::ServerProcess server(six_dof_config());
  Client client(config_for(server, "recorder"));
  ASSERT_TRUE(client.device_info().capabilities.orientation);
  expect_session_recorded(client);
}

TEST(Recorder, AQueueWithNoRoomDropsAndCountsWhatTheWriterCouldNotTake) {
  test::ServerProcess server(test::lockstep_config());
  Client client(config_for(server, "recorder"));
  Seen seen;
  seen.attach(client);
  TempDir dir;
  const std::uint64_t accepted_before = client.receive_counters().accepted;
  Recorder recorder(client, {.path = dir.file("drops.csv"), .queue_capacity = 1, .events = false});
  // The writer takes nothing until close(): the queue's one slot holds the first sample.
  detail::RecorderTestAccess::hold_writer(recorder, true);
  step_seen(client, seen, 4, 20);
  const std::uint64_t accepted = client.receive_counters().accepted - accepted_before;
  const RecorderStats stats = recorder.close();
  EXPECT_GT(accepted, 1u);
  EXPECT_EQ(stats.samples_received, accepted);
  EXPECT_EQ(stats.samples_written, 1u);
  EXPECT_EQ(stats.dropped, accepted - 1);
  EXPECT_EQ(stats.samples_written + stats.dropped, accepted);
  EXPECT_EQ(read_csv(dir.file("drops.csv")).rows.size(), 1u);
  EXPECT_FALSE(fs::exists(dir.file("drops.events.csv")));  // events off: no events file
}

TEST(Recorder, AWriteThatFailsIsCountedWithItsReason) {
  std::error_code error;
  if (!fs::is_character_file("/dev/full", error)) GTEST_SKIP() << "no /dev/full here";
  test::ServerProcess server(test::lockstep_config());
  Client client(config_for(server, "recorder"));
  Seen seen;
  seen.attach(client);
  Recorder recorder(client, {.path = "/dev/full", .format = RecorderOptions::Format::kCsv,
                             .events = false, .overwrite = true});
  step_seen(client, seen, 2, 10);
  const RecorderStats stats = recorder.close();
  EXPECT_GT(stats.samples_received, 0u);
  EXPECT_EQ(stats.samples_written, 0u);
  EXPECT_EQ(stats.write_errors, stats.samples_received);
  EXPECT_NE(stats.first_error.find("No space left"), std::string::npos) << stats.first_error;
}

TEST(Recorder, BadOptionsAreRefusedNamingTheFieldAndLeaveNothingBehind) {
  test::ServerProcess server(test::lockstep_config());
  Client client(config_for(server, "recorder"));
  TempDir dir;
  const auto refused = [&](RecorderOptions options, const std::string& says) {
    try {
      Recorder recorder(client, options);
      ADD_FAILURE() << "accepted " << options.path;
    } catch (const InvalidArgumentError& error) {
      EXPECT_NE(std::string(error.what()).find(says), std::string::npos) << error.what();
    }
  };
  refused({.path = ""}, "record: path: empty");
  refused({.path = dir.file("session.txt")}, "record: path: '" + dir.file("session.txt") + "' ends in neither");
  refused({.path = dir.file("session.csv"), .queue_capacity = 0}, "record: queue_capacity: must be >= 1");
  refused({.path = dir.file("no/such/dir/session.h5")}, "record: path: the directory");
  refused({.path = dir.file("session.h5"), .format = static_cast<RecorderOptions::Format>(7)},
          "record: format: unknown value 7");
  EXPECT_EQ(dir.entries(), 0u);

  // An existing file is refused and left as it was, for each format; a CSV recording whose events
  // file exists makes no samples file either.
  std::ofstream(dir.file("kept.h5")) << "mine";
  std::ofstream(dir.file("kept.csv")) << "mine";
  std::ofstream(dir.file("other.events.csv")) << "mine";
  refused({.path = dir.file("kept.h5")}, "record: path: '" + dir.file("kept.h5") + "' exists");
  refused({.path = dir.file("kept.csv")}, "exists");
  refused({.path = dir.file("other.csv")}, "record: path: '" + dir.file("other.events.csv") + "' exists");
  EXPECT_FALSE(fs::exists(dir.file("other.csv")));
  EXPECT_EQ(dir.entries(), 3u);
  std::string kept;
  std::getline(std::ifstream(dir.file("kept.h5")), kept);
  EXPECT_EQ(kept, "mine");

  // With overwrite they are replaced.
  Recorder replaced(client, {.path = dir.file("kept.h5"), .overwrite = true});
  EXPECT_EQ(replaced.close().write_errors, 0u);
  EXPECT_GT(H5Fis_hdf5(dir.file("kept.h5").c_str()), 0);

  // A link is not written through, even with overwrite: the file it points at stays as it was.
  std::ofstream(dir.file("precious.txt")) << "mine";
  fs::create_symlink(dir.file("precious.txt"), dir.file("link.csv"));
  fs::create_symlink(dir.file("precious.txt"), dir.file("link.h5"));
  fs::create_symlink(dir.file("precious.txt"), dir.file("linked.events.csv"));
  refused({.path = dir.file("link.csv"), .overwrite = true},
          "record: path: '" + dir.file("link.csv") + "' is a symbolic link");
  refused({.path = dir.file("link.h5"), .overwrite = true}, "is a symbolic link");
  refused({.path = dir.file("linked.csv"), .overwrite = true},
          "record: path: '" + dir.file("linked.events.csv") + "' is a symbolic link");
  std::string precious;
  std::getline(std::ifstream(dir.file("precious.txt")), precious);
  EXPECT_EQ(precious, "mine");
  EXPECT_FALSE(fs::exists(dir.file("linked.csv")));
}

TEST(Recorder, ARecorderThatOutlivesItsClientClosesWhatItHas) {
  test::ServerProcess server(test::lockstep_config());
  TempDir dir;
  std::optional<Recorder> recorder;
  std::uint64_t accepted = 0;
  {
    Client client(config_for(server, "recorder"));
    Seen seen;
    seen.attach(client);
    const std::uint64_t before = client.receive_counters().accepted;
    recorder.emplace(client, RecorderOptions{.path = dir.file("early.h5")});
    Recorder moved = std::move(*recorder);  // move-only: the moved-to one records
    EXPECT_FALSE(recorder->recording());
    EXPECT_TRUE(moved.recording());
    step_seen(client, seen, 2, 10);
    accepted = client.receive_counters().accepted - before;
    *recorder = std::move(moved);
  }
  ASSERT_TRUE(recorder->recording());
  const RecorderStats stats = recorder->close();
  EXPECT_EQ(stats.samples_written, accepted);
  EXPECT_EQ(recorder->close().samples_written, accepted);  // again: the same totals
  const hid_t file = H5Fopen(dir.file("early.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  EXPECT_EQ(h5_column<std::uint64_t>(file, "/samples/tick", H5T_NATIVE_UINT64).size(), accepted);
  H5Fclose(file);
}

TEST(Recorder, AServerRestartIsRecordedAndTheEventsResumeInTheNewSession) {
  auto first = std::make_unique<test::ServerProcess>(test::lockstep_config());
  const std::uint16_t grpc_port = first->grpc_port();
  const std::uint16_t udp_port = first->udp_port();
  TempDir dir;
  test::ConnectionLog log;
  Client client(config_for(*first, "recorder"));
  log.attach(client);  // the application's own callback stays its own
  Recorder recorder(client, {.path = dir.file("restart.csv")});
  const auto kind_count = [&](int kind) {
    const Csv events = read_csv(dir.file("restart.events.csv"));
    int n = 0;
    for (const auto& row : events.rows) n += std::stoi(row[events.column("kind")]) == kind ? 1 : 0;
    return n;
  };
  ASSERT_TRUE(eventually([&] { return recorder.stats().events_written >= 1; }));

  first.reset();  // the server exits, and the session with it
  ASSERT_TRUE(log.wait(1, std::chrono::seconds(5)));
  test::ServerProcess second(test::lockstep_config(), {}, 0, grpc_port, udp_port);
  const auto resumed = log.wait(2, std::chrono::seconds(10));
  ASSERT_TRUE(resumed);
  ASSERT_EQ(resumed->first.state, ConnectionChange::State::kResumed);
  // The recorder's stream was opened again in the new session: it sees this session's wall.
  ObjectHandle wall = client.add_wall({.normal = {0, 0, 1}, .impedance = {500, 1}});
  // watch started, lost, resumed, watch started again, the wall made.
  ASSERT_TRUE(eventually([&] { return recorder.stats().events_written >= 5; }));
  const RecorderStats stats = recorder.close();
  EXPECT_GE(kind_count(static_cast<int>(Event::Kind::kSceneChanged)), 1);
  EXPECT_EQ(stats.write_errors, 0u);
  EXPECT_EQ(kind_count(101), 1);  // connection_lost
  EXPECT_EQ(kind_count(102), 1);  // connection_resumed
  EXPECT_EQ(kind_count(static_cast<int>(Event::Kind::kWatchStarted)), 2);  // each session's stream
  const Csv events = read_csv(dir.file("restart.events.csv"));
  for (const auto& row : events.rows) {
    if (row[events.column("kind_name")] == "connection_resumed") {
      EXPECT_EQ(row[events.column("session_id")], std::to_string(client.session_id()));
      EXPECT_EQ(row[events.column("server_time_s")], "NaN");
    }
  }
}

}  // namespace
}  // namespace haptic
