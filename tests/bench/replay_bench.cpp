// How fast a recording is read back, in one run: an in-process lockstep hapticd records a run
// (one client, a wall it is pushed into along a line, TICKS ticks), then the file is
//   read     read through with RecordingReader alone (decompression and parsing), and
//   replay   replayed whole (replay_recording: the lockstep server, one Step per 512 ticks, every
//            sample compared),
// each timed, as records a second. A benchmark: it prints figures, asserts nothing.
//
// Usage: replay_bench [--ticks N=200000] [--rounds R=3] [--keep FILE]
//   --keep: record into FILE and leave it there (default: a temporary file, removed).

#include <haptic/haptic.hpp>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "app/replay_server.hpp"
#include "app/server.hpp"
#include "config/server_config.hpp"
#include "recording/recording_file.hpp"

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

void record_run(const std::string& path, std::uint64_t ticks) {
  haptic::v1::ServerConfig config = haptic::config::default_config();
  config.set_time_mode(haptic::v1::LOCKSTEP);
  config.set_grpc_address("127.0.0.1:0");
  config.set_udp_address("127.0.0.1");
  config.set_udp_port(0);
  config.set_status_period_s(0);
  config.mutable_simulated_point_mass()->mutable_initial_position()->set_z(0.02);
  haptic::app::Server server(config);
  if (const std::string error = server.start_recording(path); !error.empty()) {
    std::fprintf(stderr, "replay_bench: %s\n", error.c_str());
    std::exit(2);
  }
  server.start();
  {
    haptic::ClientConfig client_config;
    client_config.server_address = "127.0.0.1:" + std::to_string(server.grpc_port());
    client_config.client_name = "replay_bench";
    haptic::Client client(client_config);
    haptic::ObjectHandle wall =
        client.add_wall(haptic::WallSpec{{0, 0, 0}, {0, 0, 1}, {1000.0, 1.0}});
    client.set_operator(haptic::OperatorInput::follow_line({0, 0, 0.02}, {0, 0, -0.01}, 1.5,
                                                           haptic::OperatorInput::Grip::kLoose));
    for (std::uint64_t done = 0; done < ticks;) {
      const auto piece = static_cast<std::uint32_t>(std::min<std::uint64_t>(ticks - done, 100'000));
      (void)client.step(piece);
      done += piece;
    }
  }
  server.shutdown();
}

}  // namespace

int main(int argc, char** argv) {
  std::uint64_t ticks = 200'000;
  int rounds = 3;
  std::string keep;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--ticks" && i + 1 < argc) {
      ticks = std::strtoull(argv[++i], nullptr, 10);
    } else if (arg == "--rounds" && i + 1 < argc) {
      rounds = std::max(1, std::atoi(argv[++i]));
    } else if (arg == "--keep" && i + 1 < argc) {
      keep = argv[++i];
    } else {
      std::fprintf(stderr, "usage: replay_bench [--ticks N] [--rounds R] [--keep FILE]\n");
      return 2;
    }
  }
  const std::string path =
      !keep.empty() ? keep
                    : (std::filesystem::temp_directory_path() /
                       ("replay_bench-" + std::to_string(::getpid()) + ".hrec"))
                          .string();
  const auto recording = Clock::now();
  record_run(path, ticks);
  std::printf("recorded %llu ticks in %.2f s: %s, %llu bytes\n",
              static_cast<unsigned long long>(ticks), seconds_since(recording), path.c_str(),
              static_cast<unsigned long long>(std::filesystem::file_size(path)));

  std::uint64_t records = 0;
  std::vector<double> read_s;
  std::vector<double> replay_s;
  for (int round = 0; round < rounds; ++round) {
    const auto reading = Clock::now();
    haptic::recording::RecordingReader reader(path);
    haptic::v1::Record record;
    std::uint64_t count = 0;
    while (reader.next(record)) ++count;
    read_s.push_back(seconds_since(reading));
    if (!reader.error().empty()) {
      std::fprintf(stderr, "replay_bench: %s\n", reader.error().c_str());
      return 1;
    }
    records = count;

    const auto replaying = Clock::now();
    const haptic::recording::ReplayReport report =
        haptic::recording::replay_recording(path, haptic::app::replay_servers());
    replay_s.push_back(seconds_since(replaying));
    if (!report.identical()) {
      std::fprintf(stderr, "replay_bench: the replay differs: %s\n", report.first_difference.c_str());
      return 1;
    }
  }
  const auto print = [&](const char* what, std::vector<double> times) {
    std::sort(times.begin(), times.end());
    const double median = times[times.size() / 2];
    std::printf("%-7s %llu records: best %.3f s, median %.3f s = %.0f records/s (median; best %.0f)\n",
                what, static_cast<unsigned long long>(records), times.front(), median,
                static_cast<double>(records) / median, static_cast<double>(records) / times.front());
  };
  print("read", read_s);
  print("replay", replay_s);
  if (keep.empty()) std::filesystem::remove(path);
  return 0;
}
