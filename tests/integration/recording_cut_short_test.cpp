// A recording cut short: hapticd killed with SIGKILL while it records, and a whole recording cut
// at chosen bytes. The replay runs every whole record there, says where the recording stops (its
// last whole record's number and tick, the byte) and why, and exits with a status of its own (3):
// neither the success of a whole run nor a refusal.
#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <haptic/haptic.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <regex>
#include <string>
#include <vector>

#include "app/replay_server.hpp"
#include "integration/run_program.hpp"
#include "integration/sdk_harness.hpp"
#include "integration/server_process.hpp"
#include "support/zstd_blocks.hpp"

namespace haptic {
namespace {

std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() /
          ("hapticd-" + name + "-" + std::to_string(::getpid()) + ".hrec"))
      .string();
}

/// hapticd --replay as main() runs it (recording::replay_command), in this process: the exit status and
/// what it printed to stdout and to stderr.
struct Replayed {
  int status = -1;
  std::string out;
  std::string err;
};

std::string read_back(std::FILE* file) {
  std::rewind(file);
  std::string text;
  char buffer[4096];
  for (std::size_t n; (n = std::fread(buffer, 1, sizeof buffer, file)) > 0;) text.append(buffer, n);
  std::fclose(file);
  return text;
}

Replayed replay(const std::string& path) {
  std::FILE* out = std::tmpfile();
  std::FILE* err = std::tmpfile();
  Replayed replayed;
  replayed.status = recording::replay_command(path, app::replay_servers(), out, err);
  replayed.out = read_back(out);
  replayed.err = read_back(err);
  return replayed;
}

/// Where the replay says the recording stops.
struct Stop {
  std::uint64_t record = 0;
  std::uint64_t tick = 0;
  std::uint64_t byte = 0;
  std::string why;
};

std::optional<Stop> stop_of(const std::string& said) {
  static const std::regex where(
      R"(is cut short: it stops after record (\d+) \(the sample of tick (\d+) port 0\), at byte (\d+) of its records \(\d+ bytes of file\): recording '[^']*': (.*); replayed as far as it goes)");
  std::smatch match;
  if (!std::regex_search(said, match, where)) return std::nullopt;
  return Stop{std::stoull(match[1]), std::stoull(match[2]), std::stoull(match[3]), match[4]};
}


void cut_file(const std::string& from, const std::string& to, std::uintmax_t size) {
  std::filesystem::copy_file(from, to, std::filesystem::copy_options::overwrite_existing);
  std::filesystem::resize_file(to, size);
}

TEST(RecordingCutShort, AServerKilledWhileRecordingReplaysToItsLastWholeRecordAndSaysWhere) {
  const std::string path = temp_path("killed");
  std::uint64_t stepped = 0;
  {
    test::ServerProcess server(test::lockstep_config(), "--record=" + path);
    {
      Client client(test::config_for(server, "killed"));
      ObjectHandle wall = client.add_wall(WallSpec{{0, 0, 0}, {0, 0, 1}, {1000.0, 1.0}});
      client.set_operator(
          OperatorInput::follow_line({0, 0, 0.02}, {0, 0, -0.01}, 1.5, OperatorInput::Grip::kLoose));
      (void)client.step(2000);
      wall.update(WallSpec{{0, 0, 0.001}, {0, 0, 1}, {1500.0, 2.0}});
      stepped = client.step(20'000);  // the recorder has every tick's sample when Step returns
      ASSERT_EQ(::kill(server.pid(), SIGKILL), 0);
      EXPECT_EQ(server.wait(), 128 + SIGKILL);
    }
  }
  ASSERT_EQ(stepped, 22'000u);

  const Replayed replayed = replay(path);
  EXPECT_EQ(replayed.status, recording::kReplayCutShort) << replayed.out << replayed.err;
  EXPECT_EQ(recording::kReplayCutShort, 3);
  const std::optional<Stop> stop = stop_of(replayed.err);
  ASSERT_TRUE(stop.has_value()) << replayed.err;
  // The writer hands the file whole blocks of records every 64 kB of them and every second: what
  // was not yet handed over died with the server. Most of the second Step is there.
  EXPECT_LE(stop->tick, stepped);
  EXPECT_GT(stop->tick, 12'000u) << replayed.err;
  // The header and 4 changes (the session opened, the wall, the operator input, the wall's
  // change) beside the samples.
  EXPECT_EQ(stop->record, stop->tick + 5) << replayed.err;
  EXPECT_GT(stop->byte, 0u);
  EXPECT_NE(stop->why.find("the file ends in the middle of "), std::string::npos) << stop->why;
  EXPECT_NE(stop->why.find("cut short (its writer killed?)"), std::string::npos) << stop->why;
  // Every tick there was replayed and compared; nothing claims a whole run.
  EXPECT_NE(replayed.out.find(": " + std::to_string(stop->tick) + " ticks, 4 changes, " +
                              std::to_string(stop->tick) + " samples compared, 0 differ; the "
                              "recording was cut short"),
            std::string::npos)
      << replayed.out;
  EXPECT_EQ(replayed.out.find("every force and position is the same"), std::string::npos) << replayed.out;

  // hapticd --replay itself: never the success of a whole run, a status of its own (3); where it
  // stops, said on stderr.
  const test::Outcome outcome = test::run_program(HAPTICD_BINARY, {"--replay", path});
  EXPECT_EQ(outcome.exit_code, 3) << outcome.output;
  EXPECT_NE(outcome.output.find("is cut short: it stops after record " + std::to_string(stop->record)),
            std::string::npos)
      << outcome.output;
  EXPECT_EQ(outcome.output.find("every force and position is the same"), std::string::npos);
  std::filesystem::remove(path);
}

// A whole recording (SIGTERM, end record), cut at chosen bytes: right after a whole record, inside
// a compressed block, inside a record. Each replays as far as it goes and exits 3, saying so.
TEST(RecordingCutShort, AWholeRecordingCutAtAnyByteIsReplayedAsFarAsItGoes) {
  const std::string path = temp_path("whole");
  {
    test::ServerProcess server(test::lockstep_config(), "--record=" + path);
    {
      Client client(test::config_for(server, "whole"));
      ObjectHandle wall = client.add_wall(WallSpec{{0, 0, 0}, {0, 0, 1}, {1000.0, 1.0}});
      client.set_operator(
          OperatorInput::follow_line({0, 0, 0.02}, {0, 0, -0.01}, 1.5, OperatorInput::Grip::kLoose));
      (void)client.step(6000);
    }
    ASSERT_EQ(server.stop(), 0);
  }
  ASSERT_EQ(replay(path).status, recording::kReplaySame);
  std::string bytes;
  {
    std::ifstream file(path, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(file), {});
  }
  const std::vector<std::size_t> blocks = test::zstd_block_ends(bytes);
  ASSERT_GE(blocks.size(), 4u);
  ASSERT_EQ(blocks.back(), bytes.size() - 4);  // then the checksum
  const std::string cut = temp_path("whole-cut");

  // Inside a compressed block (the second, one in the middle, the last): what it holds is lost.
  std::uint64_t previous_tick = 0;
  for (const std::size_t block : {std::size_t{1}, blocks.size() / 2, blocks.size() - 1}) {
    const std::size_t at = (blocks[block - 1] + blocks[block]) / 2;
    cut_file(path, cut, at);
    const Replayed replayed = replay(cut);
    EXPECT_EQ(replayed.status, recording::kReplayCutShort) << at << ": " << replayed.out << replayed.err;
    const std::optional<Stop> stop = stop_of(replayed.err);
    ASSERT_TRUE(stop.has_value()) << at << ": " << replayed.err;
    EXPECT_GT(stop->tick, previous_tick);
    previous_tick = stop->tick;
    EXPECT_NE(replayed.out.find(std::to_string(stop->tick) + " samples compared, 0 differ"),
              std::string::npos)
        << replayed.out;
    EXPECT_NE(stop->why.find("ends in the middle of a compressed block ("), std::string::npos)
        << at << ": " << stop->why;
  }

  // Right after a whole record: where a block ends (the writer hands the file whole blocks of
  // whole records).
  cut_file(path, cut, blocks[blocks.size() / 2]);
  const Replayed replayed = replay(cut);
  EXPECT_EQ(replayed.status, recording::kReplayCutShort) << replayed.out << replayed.err;
  const std::optional<Stop> stop = stop_of(replayed.err);
  ASSERT_TRUE(stop.has_value()) << replayed.err;
  EXPECT_EQ(stop->why,
            "the file ends in the middle of its compressed stream, at the end of a block, after a "
            "whole record: cut short (its writer killed?)");

  // Without the last 1 to 4 bytes, the checksum: every record is there, the end record too, but
  // nothing says they are the ones written (it replayed "bit for bit" with exit 0 before; zstd -t
  // calls it premature). And with a wrong checksum the file is damaged.
  for (const std::size_t missing : {1, 2, 4}) {
    cut_file(path, cut, bytes.size() - missing);
    const Replayed short_of_checksum = replay(cut);
    EXPECT_EQ(short_of_checksum.status, recording::kReplayCutShort)
        << missing << ": " << short_of_checksum.out << short_of_checksum.err;
    EXPECT_NE(short_of_checksum.err.find("ends after its end record"), std::string::npos) << short_of_checksum.err;
    EXPECT_NE(short_of_checksum.err.find("before its compressed stream's end and checksum"), std::string::npos)
        << short_of_checksum.err;
  }
  {
    std::string wrong = bytes;
    wrong.back() = static_cast<char>(wrong.back() ^ 0x5a);
    std::ofstream(cut, std::ios::binary) << wrong;
  }
  const Replayed wrong_checksum = replay(cut);
  EXPECT_EQ(wrong_checksum.status, recording::kReplayRefused) << wrong_checksum.out << wrong_checksum.err;
  EXPECT_NE(wrong_checksum.err.find("is damaged"), std::string::npos) << wrong_checksum.err;
  EXPECT_NE(wrong_checksum.err.find("checksum"), std::string::npos) << wrong_checksum.err;
  std::filesystem::remove(cut);
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace haptic
