// Every tick of a lockstep Step reaches a subscriber that asked for every tick: a Step of 100,000
// ticks is recorded in full (CSV and HDF5), with nothing counted lost anywhere; a reader that
// takes its time only makes the Step slower. Where a sample can still be lost (a client that
// turned flow control off and reads slowly), every loss is a gap in the file's ticks and
// sequence, and the client's lost count says exactly how many.
#include <gtest/gtest.h>
#include <hdf5.h>

#include <haptic/haptic.hpp>
#include <haptic/recorder.hpp>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <string>
#include <thread>
#include <vector>

#include "integration/recording_files.hpp"
#include "integration/sdk_harness.hpp"
#include "integration/server_process.hpp"

namespace haptic {
namespace {

using namespace std::chrono_literals;
using test::config_for;
using test::TempDir;

/// The ticks and sequences of a recording, in file order.
struct Recorded {
  std::vector<std::int64_t> ticks;
  std::vector<std::int64_t> sequences;
};

Recorded read_csv_recording(const std::string& path) {
  const test::Csv csv = test::read_csv(path);
  Recorded out;
  for (const auto& row : csv.rows) {
    out.ticks.push_back(std::stoll(row[csv.column("tick")]));
    out.sequences.push_back(std::stoll(row[csv.column("sequence")]));
  }
  return out;
}

Recorded read_h5_recording(const std::string& path) {
  Recorded out;
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  EXPECT_GE(file, 0) << "cannot open " << path;
  if (file < 0) return out;
  out.ticks = test::h5_column<std::int64_t>(file, "/samples/tick", H5T_NATIVE_INT64);
  out.sequences = test::h5_column<std::int64_t>(file, "/samples/sequence", H5T_NATIVE_INT64);
  H5Fclose(file);
  return out;
}

/// Every tick from `first` to `last`, each once and in order, numbered 1, 2, 3, ...
void expect_every_tick(const Recorded& recorded, std::int64_t first, std::int64_t last, const char* what) {
  ASSERT_EQ(recorded.ticks.size(), static_cast<std::size_t>(last - first + 1)) << what;
  for (std::size_t i = 0; i < recorded.ticks.size(); ++i) {
    ASSERT_EQ(recorded.ticks[i], first + static_cast<std::int64_t>(i)) << what << " row " << i;
    ASSERT_EQ(recorded.sequences[i], recorded.sequences[0] + static_cast<std::int64_t>(i)) << what << " row " << i;
  }
}

/// A receive observer that takes `per_sample` over each State: a reader slower than the loop.
class SlowReader : public ReceiveObserver {
 public:
  explicit SlowReader(std::chrono::microseconds per_sample) : per_sample_(per_sample) {}
  void on_sample(const State&) noexcept override {
    const auto until = std::chrono::steady_clock::now() + per_sample_;
    while (std::chrono::steady_clock::now() < until) {
    }
    seen_.fetch_add(1);
  }
  std::uint64_t seen() const { return seen_.load(); }

 private:
  std::chrono::microseconds per_sample_;
  std::atomic<std::uint64_t> seen_{0};
};

/// Waits until the client has accepted nothing new for `quiet` (what was sent has arrived).
void wait_until_quiet(const Client& client, std::chrono::milliseconds quiet) {
  std::uint64_t last = client.receive_counters().accepted;
  const auto give_up = std::chrono::steady_clock::now() + 30s;
  while (std::chrono::steady_clock::now() < give_up) {
    std::this_thread::sleep_for(quiet);
    const std::uint64_t now = client.receive_counters().accepted;
    if (now == last) return;
    last = now;
  }
}

TEST(LockstepStream, AStepOfAHundredThousandTicksIsRecordedInFull) {
  test::ServerProcess server(test::lockstep_config());
  Client client(config_for(server, "recorder"));
  TempDir dir;
  Recorder csv(client, {.path = dir.file("step.csv"), .events = false});
  Recorder hdf5(client, {.path = dir.file("step.h5"), .events = false});
  const std::uint64_t first = client.step(1) + 1;
  State state;
  // The step(1) State in before the count starts (a loaded machine may hold it past a quiet 50 ms).
  ASSERT_TRUE(client.wait_for_tick(first - 1, state, 10s));
  wait_until_quiet(client, 50ms);
  const std::uint64_t before = client.receive_counters().accepted;
  constexpr std::uint32_t kTicks = 100'000;
  const std::uint64_t last = client.step(kTicks);
  ASSERT_EQ(last, first + kTicks - 1);
  ASSERT_TRUE(client.wait_for_tick(last, state, 30s));
  wait_until_quiet(client, 100ms);
  const RecorderStats csv_stats = csv.close();
  const RecorderStats hdf5_stats = hdf5.close();

  const ReceiveCounters counters = client.receive_counters();
  EXPECT_EQ(counters.accepted - before, kTicks);
  EXPECT_EQ(counters.lost, 0u);
  EXPECT_EQ(csv_stats.dropped, 0u);
  EXPECT_EQ(hdf5_stats.dropped, 0u);
  const Stats stats = client.stats();
  EXPECT_EQ(stats.samples_missed, 0u);
  EXPECT_EQ(stats.samples_skipped, 0u);
  EXPECT_EQ(stats.ack_stalls, 0u);
  ASSERT_EQ(stats.clients.size(), 1u);
  EXPECT_GT(stats.clients[0].ack_window, 0u);

  // The first tick's State may have reached the recorders before or after the step(1) reply:
  // read from the first tick of the long step on.
  for (const auto& [recorded, what] : {std::pair{read_csv_recording(dir.file("step.csv")), "CSV"},
                                       std::pair{read_h5_recording(dir.file("step.h5")), "HDF5"}}) {
    Recorded tail;
    for (std::size_t i = 0; i < recorded.ticks.size(); ++i) {
      if (recorded.ticks[i] < static_cast<std::int64_t>(first)) continue;
      tail.ticks.push_back(recorded.ticks[i]);
      tail.sequences.push_back(recorded.sequences[i]);
    }
    expect_every_tick(tail, static_cast<std::int64_t>(first), static_cast<std::int64_t>(last), what);
  }
}

TEST(LockstepStream, ASlowReaderOnlyMakesTheStepSlower) {
  test::ServerProcess server(test::lockstep_config());
  Client client(config_for(server, "slow"));
  auto reader = std::make_shared<SlowReader>(30us);
  ObserverHandle observing = client.observe(reader);
  TempDir dir;
  Recorder csv(client, {.path = dir.file("slow.csv"), .events = false});
  const std::uint64_t first = client.step(1) + 1;
  wait_until_quiet(client, 50ms);
  constexpr std::uint32_t kTicks = 20'000;
  const std::uint64_t last = client.step(kTicks);
  State state;
  ASSERT_TRUE(client.wait_for_tick(last, state, 30s));  // the last State in, then what trails it
  wait_until_quiet(client, 100ms);
  const RecorderStats stats = csv.close();
  EXPECT_EQ(client.receive_counters().lost, 0u);
  EXPECT_EQ(stats.dropped, 0u);
  Recorded recorded = read_csv_recording(dir.file("slow.csv"));
  std::erase_if(recorded.ticks, [&](std::int64_t tick) { return tick < static_cast<std::int64_t>(first); });
  recorded.sequences.erase(recorded.sequences.begin(),
                           recorded.sequences.end() - static_cast<std::ptrdiff_t>(recorded.ticks.size()));
  expect_every_tick(recorded, static_cast<std::int64_t>(first), static_cast<std::int64_t>(last), "CSV");
}

TEST(LockstepStream, WithoutFlowControlASlowReadersLossesAreGapsAndCountedExactly) {
  test::ServerProcess server(test::lockstep_config());
  ClientConfig config = config_for(server, "slow");
  config.lockstep_flow_control = false;
  Client client(config);
  // Far slower than the loop: a burst of 20,000 overflows any socket buffer.
  auto reader = std::make_shared<SlowReader>(200us);
  ObserverHandle observing = client.observe(reader);
  TempDir dir;
  Recorder csv(client, {.path = dir.file("lossy.csv"), .events = false});
  const std::uint64_t lost_before = client.receive_counters().lost;
  constexpr std::uint32_t kTicks = 20'000;
  const std::uint64_t last = client.step(kTicks);
  wait_until_quiet(client, 100ms);
  // One tick more, read at leisure: its sequence shows any loss at the burst's tail as a gap.
  ASSERT_EQ(client.step(1), last + 1);
  State state;
  ASSERT_TRUE(client.wait_for_tick(last + 1, state, 5s));
  wait_until_quiet(client, 100ms);
  const RecorderStats stats = csv.close();
  const std::uint64_t lost = client.receive_counters().lost - lost_before;
  EXPECT_EQ(client.stats().clients.at(0).ack_window, 0u);

  const Recorded recorded = read_csv_recording(dir.file("lossy.csv"));
  ASSERT_FALSE(recorded.ticks.empty());
  EXPECT_EQ(recorded.ticks.back(), static_cast<std::int64_t>(last + 1));
  EXPECT_EQ(stats.dropped, 0u);
  // The burst overflowed the socket: samples were lost, and each is a gap in the file's ticks and
  // sequence (the stream began at tick 1, numbered 1), all of them counted.
  EXPECT_GT(lost, 0u) << "the reader kept up: the test shows nothing";
  const std::uint64_t due = last + 1;
  EXPECT_EQ(recorded.ticks.size() + lost, due);
  std::uint64_t gaps = 0;
  std::int64_t previous_tick = 0;
  std::int64_t previous_sequence = 0;
  for (std::size_t i = 0; i < recorded.ticks.size(); ++i) {
    ASSERT_EQ(recorded.ticks[i] - previous_tick, recorded.sequences[i] - previous_sequence) << "row " << i;
    gaps += static_cast<std::uint64_t>(recorded.ticks[i] - previous_tick - 1);
    previous_tick = recorded.ticks[i];
    previous_sequence = recorded.sequences[i];
  }
  EXPECT_EQ(gaps, lost);
}

}  // namespace
}  // namespace haptic
