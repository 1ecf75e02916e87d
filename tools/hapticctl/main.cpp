// hapticctl: look at and administer a running hapticd. Built on the SDK alone; it opens a session
// of its own (no state stream) and needs the admin role where the server has tokens.
//
//   hapticctl [--server HOST:PORT] [--token T | --token-file F]
//             [--ca CA.pem [--cert C.pem --key K.pem] [--server-name NAME]] COMMAND
//   status | sessions | stats [--watch] | events | scene [--all] [--json] | kick SESSION
//   record start NAME | record stop
//
// Exit status: 0 done; 1 the server refused or could not be reached (its message on stderr);
// 2 a bad command line.

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <haptic/haptic.hpp>

#include <chrono>
#include <condition_variable>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <mutex>
#include <sstream>
#include <thread>

#include "haptic/version.hpp"
#include "haptic/wire/datagram.hpp"
#include "views.hpp"

namespace {

std::atomic<bool> interrupted{false};

void on_interrupt(int) { interrupted.store(true); }

/// Sleeps up to `duration`, waking early on Ctrl-C.
void sleep_interruptible(std::chrono::duration<double> duration) {
  const auto until = std::chrono::steady_clock::now() + duration;
  while (!interrupted.load() && std::chrono::steady_clock::now() < until) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

bool parse_session(const std::string& text, std::uint64_t& id) {
  std::string digits = text.rfind("0x", 0) == 0 ? text.substr(2) : text;
  if (digits.empty() || digits.size() > 16 ||
      digits.find_first_not_of("0123456789abcdefABCDEF") != std::string::npos) {
    return false;
  }
  id = std::stoull(digits, nullptr, 16);
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{"hapticctl: look at and administer a running hapticd (the admin role where the "
               "server has tokens)"};
  cli.require_subcommand(1);
  cli.set_version_flag("--version", std::string("hapticctl ") + HAPTIC_VERSION + " (control API " +
                                        std::to_string(haptic::kApiVersion) + ", wire " +
                                        std::to_string(haptic::wire::kWireVersion) + ")");
  haptic::ClientConfig config;
  config.client_name = "hapticctl";
  config.state_decimation = 0;  // it reads the server, not the device
  config.reconnect = false;
  cli.add_option("--server", config.server_address, "hapticd's gRPC address")
      ->capture_default_str()
      ->envname("HAPTICCTL_SERVER");
  cli.add_option("--token", config.token, "bearer token (its role must allow the command)")
      ->envname("HAPTICCTL_TOKEN");
  std::string token_file;
  cli.add_option("--token-file", token_file, "read the bearer token from this file (first line)")
      ->check(CLI::ExistingFile)
      ->envname("HAPTICCTL_TOKEN_FILE");
  std::string ca_file;
  cli.add_option("--ca", ca_file, "speak TLS, trusting this PEM CA (a server with security.tls)")
      ->check(CLI::ExistingFile)
      ->envname("HAPTICCTL_CA");
  haptic::TlsOptions tls;
  CLI::Option* cert = cli.add_option("--cert", tls.cert_file,
                                     "with --ca: present this PEM client certificate (a server with "
                                     "mutual TLS)")
                          ->check(CLI::ExistingFile)
                          ->envname("HAPTICCTL_CERT");
  CLI::Option* key = cli.add_option("--key", tls.key_file, "with --cert: its PEM private key")
                         ->check(CLI::ExistingFile)
                         ->envname("HAPTICCTL_KEY")
                         ->needs(cert);
  cert->needs(key);
  cli.add_option("--server-name", tls.server_name,
                 "with --ca: the name the server's certificate must carry (default: the host of "
                 "--server)")
      ->envname("HAPTICCTL_SERVER_NAME");
  cli.add_flag("--allow-plaintext-token", config.allow_plaintext_token,
               "send the token without TLS to another host all the same (a network you trust; "
               "refused otherwise, since anyone on it could read the token)");
  int timeout_ms = 2000;
  cli.add_option("--timeout-ms", timeout_ms, "deadline of each call")
      ->capture_default_str()
      ->check(CLI::Range(1, 600000));

  CLI::App* status = cli.add_subcommand("status", "the loop, the scene, the traffic and the faults");
  CLI::App* sessions = cli.add_subcommand("sessions", "every open session");

  CLI::App* stats = cli.add_subcommand("stats", "each client's stream: sent, received, lost, round trip");
  bool watch = false;
  double interval_s = 1.0;
  int count = 0;
  stats->add_flag("--watch,-w", watch, "refresh until Ctrl-C (a live table on a terminal)");
  stats->add_option("--interval", interval_s, "seconds between refreshes")
      ->capture_default_str()
      ->check(CLI::Range(0.05, 3600.0));
  stats->add_option("--count", count, "with --watch: stop after this many tables (0: never)")
      ->check(CLI::NonNegativeNumber);

  CLI::App* events = cli.add_subcommand("events", "print the server's events as they happen");
  int event_count = 0;
  double event_seconds = 0.0;
  events->add_option("--count", event_count, "stop after this many events (0: never)")
      ->check(CLI::NonNegativeNumber);
  events->add_option("--for", event_seconds, "stop after this many seconds (0: never)")
      ->check(CLI::NonNegativeNumber);

  CLI::App* scene = cli.add_subcommand("scene", "the registered scene: this table, or a scene file");
  bool all_sessions = true;
  bool as_json = false;
  scene->add_flag("--all,!--own", all_sessions, "every session's items and the server's (default)");
  scene->add_flag("--json", as_json,
                  "print a scene file (hapticd --scene and Client::apply_scene_file read it)");

  CLI::App* kick = cli.add_subcommand("kick", "end a session: its objects ramp out, its client is told");
  std::string target_text;
  std::string reason;
  kick->add_option("SESSION", target_text, "the session id, as hapticctl sessions shows it (hex)")
      ->required();
  kick->add_option("--reason", reason, "shown to the client and in the event (up to 256 characters)");

  CLI::App* record = cli.add_subcommand("record", "record the run on the server, for hapticd --replay");
  record->require_subcommand(1);
  CLI::App* record_start = record->add_subcommand(
      "start", "start recording into NAME in the server's recording_dir (every change and tick)");
  std::string record_name;
  record_start->add_option("NAME", record_name, "the file's name (A-Z a-z 0-9 . _ -)")->required();
  CLI::App* record_stop = record->add_subcommand("stop", "stop the recording and show its totals");

  try {
    cli.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    // --help and --version are 0; any mistake on the command line is 2, whatever number CLI11
    // gives its kind of error.
    return cli.exit(error) == 0 ? 0 : 2;
  }

  std::uint64_t target = 0;
  if (kick->parsed() && !parse_session(target_text, target)) {
    std::cerr << "hapticctl kick: SESSION: '" << target_text
              << "' is not a session id (up to 16 hex digits, as hapticctl sessions shows it)\n";
    return 2;
  }
  if (!token_file.empty()) {
    std::ifstream file(token_file);
    std::getline(file, config.token);
  }
  if (!ca_file.empty()) {
    tls.ca_file = ca_file;
    config.tls = tls;
  } else if (!tls.cert_file.empty() || !tls.server_name.empty()) {
    std::cerr << "hapticctl: --cert, --key and --server-name need --ca (TLS)\n";
    return 2;
  }
  config.rpc_timeout = std::chrono::milliseconds(timeout_ms);
  std::signal(SIGINT, on_interrupt);
  std::signal(SIGTERM, on_interrupt);

  try {
    haptic::Client client(config);
    const std::uint64_t own = client.session_id();
    if (status->parsed()) {
      std::cout << hapticctl::status_view(client.stats());
    } else if (sessions->parsed()) {
      std::cout << hapticctl::sessions_view(client.sessions(), own);
    } else if (stats->parsed()) {
      const bool live = watch && ::isatty(STDOUT_FILENO);
      for (int shown = 0;;) {
        const std::string view = hapticctl::clients_view(client.stats(), own);
        if (live) std::cout << "\x1b[H\x1b[2J";  // a live table: redraw in place
        std::cout << view;
        if (watch && !live) std::cout << "\n";
        std::cout.flush();
        if (!watch || ++shown == count || interrupted.load()) break;
        sleep_interruptible(std::chrono::duration<double>(interval_s));
        if (interrupted.load()) break;
      }
    } else if (events->parsed()) {
      std::mutex mutex;
      std::condition_variable arrived;
      int seen = 0;
      client.on_event([&](const haptic::Event& event) {
        std::lock_guard lock(mutex);
        if (event.kind == haptic::Event::Kind::kWatchStarted) {
          // On stderr, so that a pipe reads events alone: a quiet server shows it is listening.
          std::cerr << "hapticctl: watching " << config.server_address << "'s events"
                    << (event_count == 0 && event_seconds == 0.0 ? "; Ctrl-C ends" : "") << std::endl;
          return;
        }
        std::cout << hapticctl::event_line(event) << std::endl;
        ++seen;
        arrived.notify_all();
      });
      const auto until = std::chrono::steady_clock::now() +
                         std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                             std::chrono::duration<double>(event_seconds));
      std::unique_lock lock(mutex);
      while (!interrupted.load() && (event_count == 0 || seen < event_count) &&
             (event_seconds == 0.0 || std::chrono::steady_clock::now() < until)) {
        arrived.wait_for(lock, std::chrono::milliseconds(50));
      }
      lock.unlock();
      client.on_event({});
    } else if (scene->parsed()) {
      const haptic::RegisteredScene registered = client.scene(all_sessions);
      std::cout << (as_json ? haptic::scene_json(registered.scene) + "\n"
                            : hapticctl::scene_view(registered));
    } else if (record_start->parsed()) {
      const haptic::RecordingStatus started = client.start_recording(record_name);
      std::cout << "recording into " << started.path << " on the server from tick "
                << started.start_tick + 1
                << (started.start_tick == 0 ? " (replayable: hapticd --replay)\n"
                                            : " (begun mid-run: hapticd --replay cannot reproduce it)\n");
    } else if (record_stop->parsed()) {
      const haptic::RecordingStatus stopped = client.stop_recording();
      std::cout << "recording " << stopped.path << " stopped: " << stopped.samples << " samples ("
                << stopped.samples_missed << " missed), " << stopped.changes << " changes\n";
      if (stopped.records_not_written > 0) {  // the file is cut short: a script must notice
        std::cerr << "hapticctl: the recording is incomplete: " << stopped.records_not_written
                  << " records not written (" << stopped.write_error << ")\n";
        client.close();
        return 1;
      }
    } else if (kick->parsed()) {
      client.kick_session(target, reason);
      std::cout << "session " << haptic::session_id_text(target) << " ended\n";
    }
    client.close();
  } catch (const haptic::Error& error) {
    std::cerr << "hapticctl: " << error.what() << "\n";
    return 1;
  }
  return 0;
}
