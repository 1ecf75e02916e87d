// What the session recorder costs the SDK's receive thread per sample: the taps' loop UdpLink::take
// runs for each accepted State, with no recorder attached (off) and with one (on: a copy into the
// recorder's ring while its writer thread drains it into an HDF5 or CSV file). Each iteration
// offers one recvmmsg batch (32 States) and is timed alone; between iterations the writer empties
// the ring, as it does between a 1 kHz stream's wake-ups, so nothing is dropped. One State copy is
// timed too, for scale (take() already makes several), and the same ring behind a mutex, the
// design not taken. And the writer thread's own share, per sample: the CSV and HDF5 writers fed a
// 1 kHz stream's batches (5 samples, one wake-up's worth) and flushed every 10 batches (50 ms, the
// recorder's policy) or every 200 (1 s, for comparison). Prints figures only; docs/recorder.md
// quotes one run.
#include <benchmark/benchmark.h>

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <unistd.h>

#include "haptic/recorder.hpp"
#include "record_format.hpp"
#include "recorder_test_access.hpp"

namespace {

using haptic::ReceiveObserver;
using haptic::State;

constexpr int kBatch = 32;  // UdpLink's recvmmsg batch

State sample(std::uint64_t tick) {
  State state;
  state.tick = tick;
  state.sequence = tick;
  state.server_time = static_cast<double>(tick) * 1e-3;
  state.position = {1e-3, 2e-3, 3e-3};
  state.force = {0.1, 0.2, 0.3};
  state.received_at = std::chrono::steady_clock::now();
  return state;
}

// What UdpLink keeps: (id, observer) pairs walked for each State.
using Taps = std::vector<std::pair<std::uint64_t, std::shared_ptr<ReceiveObserver>>>;

void offer_batches(benchmark::State& bench, const Taps& taps) {
  std::vector<State> batch;
  for (int i = 0; i < kBatch; ++i) batch.push_back(sample(static_cast<std::uint64_t>(i + 1)));
  std::uint64_t tick = 0;
  for (auto _ : bench) {
    const auto begin = std::chrono::steady_clock::now();
    for (State& state : batch) {
      state.tick = ++tick;
      for (const auto& tap : taps) tap.second->on_sample(state);
    }
    const auto end = std::chrono::steady_clock::now();
    bench.SetIterationTime(std::chrono::duration<double>(end - begin).count());
    benchmark::DoNotOptimize(batch.data());
    // The writer's turn (untimed): at 1 kHz it has a millisecond per sample.
    if (!taps.empty()) std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  bench.SetItemsProcessed(bench.iterations() * kBatch);
  bench.counters["ns_per_sample"] = benchmark::Counter(
      static_cast<double>(bench.iterations() * kBatch),
      benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

void BM_TapsOff(benchmark::State& bench) { offer_batches(bench, {}); }

void tap_on(benchmark::State& bench, const char* extension) {
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("recorder_bench-" + std::to_string(::getpid()) + extension))
                               .string();
  std::shared_ptr<ReceiveObserver> sink =
      haptic::detail::RecorderTestAccess::make_sink({.path = path, .events = false, .overwrite = true});
  offer_batches(bench, {{1, sink}});
  const haptic::RecorderStats stats = haptic::detail::RecorderTestAccess::finish(*sink);
  bench.counters["dropped"] = static_cast<double>(stats.dropped);
  bench.counters["written"] = static_cast<double>(stats.samples_written);
  std::filesystem::remove(path);
}

void BM_TapOnHdf5(benchmark::State& bench) { tap_on(bench, ".h5"); }
void BM_TapOnCsv(benchmark::State& bench) { tap_on(bench, ".csv"); }

// The alternative the recorder does not use, for comparison: the same ring behind a mutex, drained
// by a thread that takes what is queued under the lock every 5 ms (as the writer does) and drops it.
class MutexRing final : public ReceiveObserver {
 public:
  explicit MutexRing(std::size_t capacity) : slots_(capacity) {
    drainer_ = std::thread([this] {
      std::vector<State> taken;
      taken.reserve(slots_.size());
      std::unique_lock lock(mutex_);
      while (!stop_) {
        wake_.wait_for(lock, std::chrono::milliseconds(5), [this] { return stop_; });
        taken.clear();
        for (; head_ != tail_; ++head_) taken.push_back(slots_[head_ % slots_.size()]);
      }
    });
  }
  ~MutexRing() override {
    {
      std::lock_guard lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    drainer_.join();
  }
  void on_sample(const State& state) noexcept override {
    std::lock_guard lock(mutex_);
    if (tail_ - head_ == slots_.size()) {
      ++dropped_;
      return;
    }
    slots_[tail_++ % slots_.size()] = state;
  }
  std::uint64_t dropped() {
    std::lock_guard lock(mutex_);
    return dropped_;
  }

 private:
  std::vector<State> slots_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::uint64_t head_ = 0, tail_ = 0, dropped_ = 0;
  bool stop_ = false;
  std::thread drainer_;
};

void BM_TapOnMutexRing(benchmark::State& bench) {
  auto ring = std::make_shared<MutexRing>(65536);
  offer_batches(bench, {{1, ring}});
  bench.counters["dropped"] = static_cast<double>(ring->dropped());
}

void BM_StateCopy(benchmark::State& bench) {
  State from = sample(1);
  std::vector<State> to(kBatch);
  for (auto _ : bench) {
    const auto begin = std::chrono::steady_clock::now();
    for (State& slot : to) {
      ++from.tick;
      slot = from;
      benchmark::DoNotOptimize(slot);
    }
    const auto end = std::chrono::steady_clock::now();
    bench.SetIterationTime(std::chrono::duration<double>(end - begin).count());
  }
  bench.counters["ns_per_sample"] = benchmark::Counter(
      static_cast<double>(bench.iterations() * kBatch),
      benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

// The writer thread's work per sample: a batch written (HDF5: appended to each column's cached
// chunk; CSV: formatted and handed to the kernel), and every `batches per flush` batches a flush
// (HDF5: every column's chunk and the metadata that finds it).
void writer_cost(benchmark::State& bench, const char* extension) {
  constexpr std::size_t kWakeUpBatch = 5;  // 1 kHz, a wake-up every 5 ms
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("recorder_bench-writer-" + std::to_string(::getpid()) + extension))
                               .string();
  std::unique_ptr<haptic::detail::RecordWriter> writer =
      std::string(extension) == ".csv" ? haptic::detail::make_csv_writer(path, "", true)
                                       : haptic::detail::make_hdf5_writer(path, false, true, {});
  const auto batches_per_flush = static_cast<std::uint64_t>(bench.range(0));
  std::vector<State> batch;
  for (std::size_t i = 0; i < kWakeUpBatch; ++i) batch.push_back(sample(i + 1));
  std::uint64_t tick = 0, batches = 0, failed = 0;
  std::string error;
  for (auto _ : bench) {
    for (State& state : batch) state.tick = ++tick;
    failed += batch.size() - writer->write_samples(batch, error);
    if (++batches % batches_per_flush == 0 && !writer->flush(error)) ++failed;
  }
  if (!writer->close(error)) ++failed;
  std::filesystem::remove(path);
  bench.counters["failed"] = static_cast<double>(failed);
  bench.counters["ns_per_sample"] = benchmark::Counter(
      static_cast<double>(bench.iterations() * kWakeUpBatch),
      benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

BENCHMARK(BM_TapsOff)->UseManualTime()->Iterations(20000);
BENCHMARK(BM_StateCopy)->UseManualTime()->Iterations(20000);
BENCHMARK(BM_TapOnHdf5)->UseManualTime()->Iterations(20000);
BENCHMARK(BM_TapOnCsv)->UseManualTime()->Iterations(20000);
BENCHMARK(BM_TapOnMutexRing)->UseManualTime()->Iterations(20000);
BENCHMARK_CAPTURE(writer_cost, hdf5, ".h5")->ArgName("batches_per_flush")->Arg(10)->Arg(200)->Iterations(20000);
BENCHMARK_CAPTURE(writer_cost, csv, ".csv")->ArgName("batches_per_flush")->Arg(10)->Arg(200)->Iterations(20000);

}  // namespace

BENCHMARK_MAIN();
