// hapticctl against a real hapticd: every command's output, the scene it dumps read back as the
// same scene, a kick that ends a client, the admin role it needs, and clear refusals.
#include <gtest/gtest.h>
#include <unistd.h>

#include <haptic/haptic.hpp>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <future>
#include <string>
#include <thread>
#include <vector>

#include "integration/run_program.hpp"
#include "integration/sdk_harness.hpp"
#include "integration/server_process.hpp"
#include "support/dds_domain.hpp"

namespace haptic {
namespace {

using test::Outcome;

std::string hex(std::uint64_t id) {
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(id));
  return text;
}

Outcome hapticctl(const test::ServerProcess& server, std::vector<std::string> args) {
  args.insert(args.begin(), {"--server", server.address()});
  return test::run_program(HAPTICCTL_BINARY, args);
}

std::size_t count_of(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

TEST(Hapticctl, StatusSessionsAndStatsShowTheServer) {
  test::ServerProcess server(test::lockstep_config());
  Client viewer(test::config_for(server, "viewer"));
  (void)viewer.step(10);

  const Outcome status = hapticctl(server, {"status"});
  EXPECT_EQ(status.exit_code, 0) << status.output;
  EXPECT_NE(status.output.find("loop      10 ticks"), std::string::npos) << status.output;
  EXPECT_NE(status.output.find("sessions  2 open"), std::string::npos) << status.output;  // with its own
  EXPECT_EQ(status.output.find("federation"), std::string::npos) << status.output;  // none

  const Outcome sessions = hapticctl(server, {"sessions"});
  EXPECT_EQ(sessions.exit_code, 0) << sessions.output;
  EXPECT_EQ(sessions.output.rfind("SESSION ", 0), 0u) << sessions.output;
  EXPECT_NE(sessions.output.find(hex(viewer.session_id()) + "   viewer"), std::string::npos)
      << sessions.output;
  EXPECT_NE(sessions.output.find("*  hapticctl"), std::string::npos) << sessions.output;

  // Two tables, then it stops by itself; each names every client.
  const Outcome stats = hapticctl(server, {"stats", "--watch", "--count", "2", "--interval", "0.05"});
  EXPECT_EQ(stats.exit_code, 0) << stats.output;
  EXPECT_EQ(count_of(stats.output, "SESSION "), 2u) << stats.output;
  EXPECT_EQ(count_of(stats.output, hex(viewer.session_id())), 2u) << stats.output;
}

// A site of a federation (alone in its DDS domain): status adds the federation's block.
TEST(Hapticctl, StatusShowsTheFederationOfASite) {
  const std::uint32_t domain = test::unique_dds_domain();
  test::ServerProcess server(test::lockstep_config(R"("federation": {"site": "ctl-a", "domain_id": )" +
                                                   std::to_string(domain) + R"(, "peers": ["127.0.0.1"]})"));
  const Outcome status = hapticctl(server, {"status"});
  EXPECT_EQ(status.exit_code, 0) << status.output;
  EXPECT_NE(status.output.find("\nfederation  "), std::string::npos) << status.output;
  EXPECT_NE(status.output.find("\n  no coupling across the network\n"), std::string::npos) << status.output;
}

TEST(Hapticctl, TheSceneItDumpsReadsBackAsTheSameScene) {
  test::ServerProcess server(test::lockstep_config());
  Client author(test::config_for(server, "author"));
  SceneSpec scene;
  scene.objects.push_back(WallSpec{{0, 0, -0.01}, {0, 0.6, 0.8}, {800.0, 2.0}});
  scene.objects.push_back(SphereSpec{{0.02, 0, 0}, 0.005, {500.0, 1.0}});
  scene.fields.push_back(ViscousFieldSpec{});
  std::get<ViscousFieldSpec>(scene.fields[0]).damping = 0.5;
  AppliedScene applied = author.apply_scene(scene);

  const Outcome table = hapticctl(server, {"scene"});
  EXPECT_EQ(table.exit_code, 0) << table.output;
  EXPECT_NE(table.output.find("wall at (0.000, 0.000, -0.010) normal (0.000, 0.600, 0.800) K 800 N/m"),
            std::string::npos)
      << table.output;
  EXPECT_NE(table.output.find("viscous field"), std::string::npos) << table.output;

  const Outcome json = hapticctl(server, {"scene", "--json"});
  ASSERT_EQ(json.exit_code, 0) << json.output;
  const auto file = std::filesystem::temp_directory_path() /
                    ("hapticctl-scene-" + std::to_string(::getpid()) + ".json");
  std::ofstream(file) << json.output;
  Client copier(test::config_for(server, "copier"));
  AppliedScene copied = copier.apply_scene_file(file.string());
  std::filesystem::remove(file);
  EXPECT_EQ(copier.scene().scene.objects, author.scene().scene.objects);
  EXPECT_EQ(copier.scene().scene.fields, author.scene().scene.fields);
}

TEST(Hapticctl, EventsArePrintedAsTheyHappen) {
  test::ServerProcess server(test::lockstep_config());
  Client actor(test::config_for(server, "actor"));
  auto printed = std::async(std::launch::async, [&] {
    return hapticctl(server, {"events", "--count", "2", "--for", "20"});
  });
  // Change the scene until hapticctl has seen two events and left (its watch starts a moment
  // after it does: the changes before that are not its to see).
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (printed.wait_for(std::chrono::milliseconds(50)) != std::future_status::ready &&
         std::chrono::steady_clock::now() < give_up) {
    ObjectHandle wall = actor.add_wall(WallSpec{{0, 0, -0.05}, {0, 0, 1}, {100.0, 0.0}});
    wall.remove();
  }
  const Outcome events = printed.get();
  EXPECT_EQ(events.exit_code, 0) << events.output;
  EXPECT_EQ(count_of(events.output, "  SCENE_CHANGED  " + hex(actor.session_id()) + "  object "), 2u)
      << events.output;
}

TEST(Hapticctl, KickEndsASessionAndBadInputIsRefusedNamingIt) {
  test::ServerProcess server(test::lockstep_config());
  Client victim(test::config_for(server, "victim"));
  const Outcome kicked = hapticctl(server, {"kick", hex(victim.session_id()), "--reason", "demo over"});
  EXPECT_EQ(kicked.exit_code, 0) << kicked.output;
  EXPECT_EQ(kicked.output, "session " + hex(victim.session_id()) + " ended\n");
  try {
    (void)victim.step(1);
    ADD_FAILURE() << "a kicked session stepped";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("ended by an admin: demo over"), std::string::npos)
        << error.what();
  }

  const Outcome not_an_id = hapticctl(server, {"kick", "zz"});
  EXPECT_EQ(not_an_id.exit_code, 2);
  EXPECT_EQ(not_an_id.output, "hapticctl kick: SESSION: 'zz' is not a session id (up to 16 hex "
                              "digits, as hapticctl sessions shows it)\n");
  const Outcome unknown = hapticctl(server, {"kick", "12"});
  EXPECT_EQ(unknown.exit_code, 1);
  EXPECT_EQ(unknown.output,
            "hapticctl: KickSession: target_session_id: no open session 0000000000000012\n");
  const Outcome no_command = test::run_program(HAPTICCTL_BINARY, {});
  EXPECT_EQ(no_command.exit_code, 2) << no_command.output;  // a command-line error, whatever its kind
  EXPECT_NE(no_command.output.find("A subcommand is required"), std::string::npos) << no_command.output;
  const Outcome version = test::run_program(HAPTICCTL_BINARY, {"--version"});
  EXPECT_EQ(version.exit_code, 0) << version.output;
  EXPECT_EQ(version.output.rfind("hapticctl ", 0), 0u) << version.output;
  EXPECT_NE(version.output.find("(control API " + std::to_string(haptic::kApiVersion) + ", wire "),
            std::string::npos) << version.output;
  const Outcome cert_without_ca =
      test::run_program(HAPTICCTL_BINARY, {"--cert", HAPTICCTL_BINARY, "--key", HAPTICCTL_BINARY, "status"});
  EXPECT_EQ(cert_without_ca.exit_code, 2) << cert_without_ca.output;
  EXPECT_NE(cert_without_ca.output.find("need --ca"), std::string::npos) << cert_without_ca.output;
  const Outcome nobody = test::run_program(HAPTICCTL_BINARY, {"--server", "127.0.0.1:1",
                                                              "--timeout-ms", "300", "status"});
  EXPECT_EQ(nobody.exit_code, 1);
  EXPECT_EQ(nobody.output.rfind("hapticctl: ", 0), 0u) << nobody.output;
}

TEST(Hapticctl, WithTokensItNeedsTheAdminRole) {
  test::ServerProcess server(R"({"time_mode": "LOCKSTEP", "security": {"tokens": [
      {"name": "watcher", "token": "observer-token-0123456789", "role": "OBSERVER"},
      {"name": "root", "token": "admin-token-0123456789ab", "role": "ADMIN"}]}})");
  const Outcome observer = hapticctl(server, {"--token", "observer-token-0123456789", "status"});
  EXPECT_EQ(observer.exit_code, 1);
  EXPECT_NE(observer.output.find("hapticctl: GetStats: needs role ADMIN or above; token 'watcher' has role OBSERVER"),
            std::string::npos)
      << observer.output;
  const Outcome none = hapticctl(server, {"status"});
  EXPECT_EQ(none.exit_code, 1);
  const Outcome admin = hapticctl(server, {"--token", "admin-token-0123456789ab", "sessions"});
  EXPECT_EQ(admin.exit_code, 0) << admin.output;
  EXPECT_NE(admin.output.find("hapticctl  0       127.0.0.1  root   admin"), std::string::npos)
      << admin.output;
}

// A recording started and stopped from hapticctl, with a client's wall already there, replays bit
// for bit; names outside the folder and a server without one are refused saying why.
TEST(Hapticctl, RecordStartAndStopMakeAReplayableRecording) {
  const auto dir = std::filesystem::temp_directory_path() / ("hapticctl-rec-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  test::ServerProcess server(test::lockstep_config(R"("recording_dir": ")" + dir.string() + "\""));
  Client driver(test::config_for(server, "driver"));
  ObjectHandle wall = driver.add_wall(WallSpec{{0, 0, 0.002}, {0, 0, 1}, {1200.0, 1.5}});
  driver.set_operator(OperatorInput::push({0, 0, -1.0}));

  const Outcome started = hapticctl(server, {"record", "start", "run.hrec"});
  EXPECT_EQ(started.exit_code, 0) << started.output;
  EXPECT_EQ(started.output, "recording into " + (dir / "run.hrec").string() +
                                " on the server from tick 1 (replayable: hapticd --replay)\n");
  driver.set_operator(OperatorInput::push({0, 0, -2.0}));
  (void)driver.step(800);
  const Outcome stopped = hapticctl(server, {"record", "stop"});
  EXPECT_EQ(stopped.exit_code, 0) << stopped.output;
  EXPECT_NE(stopped.output.find("stopped: 800 samples (0 missed), "), std::string::npos) << stopped.output;

  const Outcome replayed = test::run_program(HAPTICD_BINARY, {"--replay", (dir / "run.hrec").string()});
  EXPECT_EQ(replayed.exit_code, 0) << replayed.output;
  EXPECT_NE(replayed.output.find("800 samples compared, 0 differ"), std::string::npos) << replayed.output;

  const Outcome none_running = hapticctl(server, {"record", "stop"});
  EXPECT_EQ(none_running.exit_code, 1);
  EXPECT_EQ(none_running.output, "hapticctl: StopRecording: no recording is running\n");
  const Outcome escape = hapticctl(server, {"record", "start", "../outside.hrec"});
  EXPECT_EQ(escape.exit_code, 1);
  EXPECT_NE(escape.output.find("name: 1 to 64 of A-Z a-z 0-9 . _ - not starting with '.', got "
                               "'../outside.hrec'"),
            std::string::npos)
      << escape.output;
  std::filesystem::remove_all(dir);

  test::ServerProcess without(test::lockstep_config());
  const Outcome refused = hapticctl(without, {"record", "start", "run.hrec"});
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_NE(refused.output.find("this server has no recording_dir"), std::string::npos) << refused.output;
}


// A recording whose writes fail (its name in recording_dir leads to /dev/full: a full disk) is
// reported incomplete by StopRecording, with the count and the reason, and hapticctl exits 1.
TEST(Hapticctl, RecordStopSaysARecordingIsIncompleteWhenItsWritesFailed) {
  const auto dir = std::filesystem::temp_directory_path() / ("hapticctl-full-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::filesystem::create_symlink("/dev/full", dir / "full.hrec");
  test::ServerProcess server(test::lockstep_config(R"("recording_dir": ")" + dir.string() + "\""));
  Client driver(test::config_for(server, "driver"));
  const Outcome started = hapticctl(server, {"record", "start", "full.hrec"});
  ASSERT_EQ(started.exit_code, 0) << started.output;
  (void)driver.step(2000);
  const Outcome stopped = hapticctl(server, {"record", "stop"});
  EXPECT_EQ(stopped.exit_code, 1) << stopped.output;
  EXPECT_NE(stopped.output.find("stopped: 2000 samples (0 missed), "), std::string::npos) << stopped.output;
  EXPECT_NE(stopped.output.find("hapticctl: the recording is incomplete: "), std::string::npos)
      << stopped.output;
  EXPECT_NE(stopped.output.find(" records not written (writing '" + (dir / "full.hrec").string() +
                                "': No space left on device)"),
            std::string::npos)
      << stopped.output;
  std::filesystem::remove_all(dir);
}
TEST(Hapticctl, EveryCommandHasHelp) {
  for (const char* command : {"status", "sessions", "stats", "events", "scene", "kick", "record"}) {
    const Outcome help = test::run_program(HAPTICCTL_BINARY, {command, "--help"});
    EXPECT_EQ(help.exit_code, 0) << command;
    EXPECT_NE(help.output.find(std::string("hapticctl ") + command), std::string::npos) << help.output;
  }
  const Outcome top = test::run_program(HAPTICCTL_BINARY, {"--help"});
  EXPECT_EQ(top.exit_code, 0);
  for (const char* command : {"status", "sessions", "stats", "events", "scene", "kick", "record"}) {
    EXPECT_NE(top.output.find(std::string("  ") + command + " "), std::string::npos) << top.output;
  }
}

}  // namespace
}  // namespace haptic
