// hapticd --record and --replay: a lockstep run with several clients, every kind of change, a Step
// longer than the sample ring and the shutdown ramp, replayed bit for bit; a recording whose force
// was changed by one unit in the last place, one begun mid-run, and a file that is no recording
// are each refused with the reason.
#include <gtest/gtest.h>
#include <unistd.h>

#include <haptic/haptic.hpp>

#include <bit>
#include <filesystem>
#include <fstream>
#include <string>

#include "integration/run_program.hpp"
#include "integration/sdk_harness.hpp"
#include "integration/server_process.hpp"
#include "recording/recording_file.hpp"

namespace haptic {
namespace {

using test::Outcome;

std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() /
          ("hapticd-" + name + "-" + std::to_string(::getpid()) + ".hrec"))
      .string();
}

Outcome replay(const std::string& path) { return test::run_program(HAPTICD_BINARY, {"--replay", path}); }

/// A lockstep run recorded into `path`: two clients, every kind of change, then SIGTERM.
void record_a_run(const std::string& path) {
  test::ServerProcess server(test::lockstep_config(), "--record=" + path);
  Client first(test::config_for(server, "first"));
  Client second(test::config_for(server, "second"));
  ObjectHandle wall = first.add_wall(WallSpec{{0, 0, 0}, {0, 0, 1}, {1000.0, 1.0}});
  FieldHandle spring = first.add_spring_field(SpringFieldSpec{{0, 0, 0.02}, 20.0, 0.1});
  first.set_operator(OperatorInput::follow_line({0, 0, 0.02}, {0, 0, -0.01}, 1.5, OperatorInput::Grip::kLoose));
  (void)first.step(700);
  wall.update(WallSpec{{0, 0, 0.001}, {0, 0, 1}, {1500.0, 2.0}});
  (void)second.step(3);
  SceneSpec scene;
  scene.objects.push_back(SphereSpec{{0.0, 0.0, -0.004}, 0.003, {800.0, 0.5}});
  AppliedScene applied = second.apply_scene(scene);
  (void)second.step(5000);  // longer than the recorder's ring: the Step waits for it in pieces
  spring.remove();
  second.close();  // its sphere ramps out
  (void)first.step(300);
  ASSERT_EQ(server.stop(), 0);  // SIGTERM: the shutdown ramp is recorded too
}

TEST(RecordReplay, ALockstepRunIsReproducedBitForBit) {
  const std::string path = temp_path("run");
  record_a_run(path);
  const Outcome replayed = replay(path);
  EXPECT_EQ(replayed.exit_code, 0) << replayed.output;
  // 6003 ticks stepped, then the shutdown ramp's 51 (50 ms, and the tick at zero); every one compared.
  EXPECT_NE(replayed.output.find(": 6054 ticks, "), std::string::npos) << replayed.output;
  EXPECT_NE(replayed.output.find("6054 samples compared, 0 differ; the recording shutdown, 0 samples "
                                 "missed in it"),
            std::string::npos)
      << replayed.output;
  EXPECT_NE(replayed.output.find("every force and position is the same, bit for bit"), std::string::npos);
  std::filesystem::remove(path);
}

TEST(RecordReplay, AForceChangedByOneUlpIsFoundAndNamed) {
  const std::string path = temp_path("tampered-source");
  record_a_run(path);
  // Copy the recording, nudging the force of tick 1000 by one unit in the last place.
  const std::string tampered = temp_path("tampered");
  std::string recorded_z;
  {
    recording::RecordingReader reader(path);
    recording::RecordingWriter writer(tampered);
    v1::Record record;
    while (reader.next(record)) {
      if (record.has_sample() && record.sample().tick() == 1000) {
        const double z = record.sample().force().z();
        ASSERT_NE(z, 0.0);  // in contact: a force worth changing
        record.mutable_sample()->mutable_force()->set_z(std::bit_cast<double>(std::bit_cast<std::uint64_t>(z) + 1));
      }
      ASSERT_TRUE(writer.write(record));
    }
    ASSERT_EQ(reader.error(), "");
    ASSERT_TRUE(writer.close());
  }
  const Outcome replayed = replay(tampered);
  EXPECT_EQ(replayed.exit_code, 1) << replayed.output;
  EXPECT_NE(replayed.output.find("6054 samples compared, 1 differ"), std::string::npos) << replayed.output;
  EXPECT_NE(replayed.output.find("first difference: tick 1000 port 0: force recorded"), std::string::npos)
      << replayed.output;
  std::filesystem::remove(path);
  std::filesystem::remove(tampered);
}

TEST(RecordReplay, WhatCannotBeReplayedIsRefusedSayingWhy) {
  const std::string path = temp_path("refused");
  {
    recording::RecordingWriter writer(path);
    v1::Record header;
    header.mutable_header()->set_format("hapticd-recording");
    header.mutable_header()->set_version(1);
    header.mutable_header()->set_start_tick(250);
    ASSERT_TRUE(writer.write(header));
    ASSERT_TRUE(writer.close());
  }
  Outcome outcome = replay(path);
  EXPECT_EQ(outcome.exit_code, 2);
  EXPECT_NE(outcome.output.find("begins at tick 251 of its run: the device's state then is not in it"),
            std::string::npos)
      << outcome.output;

  std::ofstream(path, std::ios::trunc) << "not a recording";
  outcome = replay(path);
  EXPECT_EQ(outcome.exit_code, 2);
  EXPECT_NE(outcome.output.find("is not a hapticd recording"), std::string::npos) << outcome.output;

  const Outcome missing = replay("/nonexistent/run.hrec");
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_NE(missing.output.find("/nonexistent/run.hrec"), std::string::npos) << missing.output;
  std::filesystem::remove(path);
}

// A reset starts a new run: the recording ends there, its samples written, and replays alone.
TEST(RecordReplay, AResetEndsTheRecordingWhichStillReplays) {
  const std::string path = temp_path("reset");
  {
    test::ServerProcess server(test::lockstep_config(), "--record=" + path);
    Client client(test::config_for(server, "resetter"));
    {
      ObjectHandle wall = client.add_wall(WallSpec{{0, 0, 0.005}, {0, 0, 1}, {1000.0, 1.0}});
      (void)client.step(400);
    }
    client.reset();
    (void)client.step(100);
  }
  const Outcome replayed = replay(path);
  EXPECT_EQ(replayed.exit_code, 0) << replayed.output;
  EXPECT_NE(replayed.output.find(": 400 ticks, "), std::string::npos) << replayed.output;
  EXPECT_NE(replayed.output.find("the recording lockstep reset"), std::string::npos) << replayed.output;
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace haptic
