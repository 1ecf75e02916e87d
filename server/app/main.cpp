// hapticd: the haptic server. With no arguments it runs the built-in configuration (the simulated
// point-mass device at 1 kHz in real time); --config loads a JSON ServerConfig.

#include <signal.h>
#include <unistd.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>

#include "config/server_config.hpp"
#include "app/health_check.hpp"
#include "app/list_devices.hpp"
#include "runtime/driver_device.hpp"
#include "app/replay_server.hpp"
#include "app/server.hpp"
#include "haptic/driver.h"
#include "haptic/v1/service.pb.h"
#include "haptic/version.hpp"
#include "haptic/wire/datagram.hpp"

namespace {

// Written once the ports are bound, so a script or test can find ephemeral ports without parsing
// logs. Written to a temporary name and renamed, so a reader never sees half a file. In real time
// it also names the CLOCK_MONOTONIC instant of server time 0 (ns), so a process on the same host
// can tell how old a sample's stamp is. "grpc_address" is where a process on the same host reaches
// the control plane (a wildcard bind is reached on loopback): `--health-check --ready-file` dials it.
void write_ready_file(const std::string& path, const haptic::app::Server& server,
                      const std::string& bound_address) {
  const std::string temporary = path + ".tmp";
  {
    std::ofstream out(temporary);
    out << "{\"grpc_port\": " << server.grpc_port() << ", \"udp_port\": " << server.udp_port()
        << ", \"metrics_port\": " << server.metrics_port()
        << ", \"viewer_port\": " << server.viewer_port()
        << ", \"http_port\": " << server.http_port()
        << ", \"grpc_address\": \"" << haptic::app::local_dial_address(bound_address, server.grpc_port())
        << "\"";
    if (const auto origin = server.time_origin_ns()) out << ", \"time_origin_ns\": " << *origin;
    out << "}\n";
  }
  std::filesystem::rename(temporary, path);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{"hapticd: networked haptic server (gRPC control plane, UDP data plane)"};
  cli.set_version_flag("--version", std::string("hapticd ") + HAPTIC_VERSION + " (control API " +
                                        std::to_string(haptic::v1::API_VERSION_CURRENT) + ", wire " +
                                        std::to_string(haptic::wire::kWireVersion) + ", driver ABI " +
                                        std::to_string(HAPTIC_DRIVER_ABI_VERSION) + ")");
  std::string config_path;
  std::string ready_file;
  std::string grpc_address;
  std::string udp_address;
  std::string viewer_address;
  std::string viewer_root;
  int udp_port = -1;
  bool insecure = false;
  bool lockstep = false;
  bool print_config = false;
  cli.add_option("--config", config_path, "JSON file with a haptic.v1.ServerConfig")
      ->check(CLI::ExistingFile);
  std::string scene_path;
  cli.add_option("--scene", scene_path,
                 "JSON file with a haptic.v1.Scene: the server's own scene (replaces initial_scene)")
      ->check(CLI::ExistingFile);
  cli.add_option("--grpc-address", grpc_address, "override grpc_address (host:port; port 0 = any)");
  cli.add_option("--udp-address", udp_address, "override udp_address (the UDP bind address)");
  cli.add_option("--udp-port", udp_port, "override udp_port (0 = any)")->check(CLI::Range(0, 65535));
  std::string metrics_address;
  cli.add_option("--metrics-address", metrics_address,
                 "override metrics_address: serve Prometheus metrics at http://HOST:PORT/metrics");
  cli.add_option("--http", viewer_address,
                 "override viewer_address: serve the read-only web viewer at http://127.0.0.1:PORT/ "
                 "(PORT alone; 0 picks one) or at HOST:PORT (docs/viewer.md)");
  std::string http_address;
  cli.add_option("--http-api", http_address,
                 "override http_address: serve the control plane over HTTP (JSON) at "
                 "http://127.0.0.1:PORT/haptic.v1.Haptic/ (PORT alone; 0 picks one) or at HOST:PORT "
                 "(docs/http.md)");
  cli.add_option("--viewer-root", viewer_root,
                 "override viewer_root: the folder holding the viewer's page (index.html)")
      ->check(CLI::ExistingDirectory);
  cli.add_flag("--insecure", insecure,
               "serve non-loopback addresses without TLS or tokens (insecure_remote_access)");
  cli.add_flag("--lockstep", lockstep, "run in LOCKSTEP time: ticks advance only by the Step RPC");
  cli.add_option("--ready-file", ready_file,
                 "write {\"grpc_port\":..,\"udp_port\":..,\"metrics_port\":..,\"viewer_port\":..,\"http_port\":..,"
                 "\"grpc_address\":..,\"time_origin_ns\":..} here once listening");
  cli.add_flag("--print-config", print_config, "print the effective configuration and exit");
  std::string health_address;
  cli.add_option("--health-check", health_address,
                 "ask the server at HOST:PORT over a fresh connection whether it serves; exit 0 if "
                 "it answers SERVING within 2 s, else 1 (for container and systemd checks). Without "
                 "HOST:PORT, the server that wrote --ready-file")
      ->expected(0, 1);
  haptic::app::HealthTls health_tls;
  CLI::Option* health_ca = cli.add_option("--health-ca", health_tls.ca_file,
                 "with --health-check: speak TLS, trusting this PEM CA (a server with security.tls)")
      ->check(CLI::ExistingFile);
  CLI::Option* health_cert =
      cli.add_option("--health-cert", health_tls.cert_file,
                     "with --health-ca: present this PEM client certificate (a server with mutual "
                     "TLS, security.tls.client_ca_file)")
          ->check(CLI::ExistingFile)
          ->needs(health_ca);
  CLI::Option* health_key = cli.add_option("--health-key", health_tls.key_file,
                                           "with --health-cert: its PEM private key")
                                ->check(CLI::ExistingFile)
                                ->needs(health_cert);
  health_cert->needs(health_key);
  std::string record_path;
  cli.add_option("--record", record_path,
                 "record the run into FILE from its first tick: every change and every tick's "
                 "sample (zstd; hapticd --replay FILE reproduces it)");
  std::string replay_path;
  cli.add_option("--replay", replay_path, haptic::recording::kReplayHelp)
      ->check(CLI::ExistingFile);
  bool list_devices = false;
  cli.add_flag("--list-devices", list_devices,
               "ask every driver library found (installed beside hapticd, in its build tree, in "
               "each --driver-dir) which devices it can open on this host, and exit");
  std::vector<std::string> driver_dirs;
  cli.add_option("--driver-dir", driver_dirs, "with --list-devices: also search this folder")
      ->check(CLI::ExistingDirectory);
  try {
    cli.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    // --help and --version are 0; any mistake on the command line (a missing --config file among
    // them) is 2, a configuration error, whatever number CLI11 gives its kind: the systemd unit
    // does not restart on 2 (RestartPreventExitStatus).
    return cli.exit(error) == 0 ? 0 : 2;
  }

  if (list_devices) {
    return haptic::app::list_devices_command(haptic::runtime::driver_folders(driver_dirs), std::cout);
  }

  if (!replay_path.empty()) {
    spdlog::set_level(spdlog::level::warn);  // the replay's own server need not announce itself
    return haptic::recording::replay_command(replay_path, haptic::app::replay_servers());
  }

  if (cli.count("--health-check") > 0) {
    std::string why;
    if (health_address.empty()) {
      if (ready_file.empty()) {
        std::cerr << "hapticd: --health-check needs HOST:PORT or --ready-file\n";
        return 2;
      }
      health_address = haptic::app::address_from_ready_file(ready_file, why);
      if (health_address.empty()) {
        std::cerr << "hapticd: " << why << "\n";
        return 1;
      }
    }
    if (!haptic::app::check_health(health_address, std::chrono::seconds(2), why, health_tls)) {
      std::cerr << "hapticd: " << why << "\n";
      return 1;
    }
    std::cout << "hapticd at " << health_address << ": serving\n";
    return 0;
  }

  haptic::v1::ServerConfig config;
  try {
    // The command line's overrides go in before the file is validated: together they are the
    // configuration (a file's remote address with --insecure, say).
    const auto apply_overrides = [&](haptic::v1::ServerConfig& edited) {
      if (!grpc_address.empty()) edited.set_grpc_address(grpc_address);
      if (!udp_address.empty()) edited.set_udp_address(udp_address);
      if (!metrics_address.empty()) edited.set_metrics_address(metrics_address);
      if (!viewer_address.empty()) {
        // A port alone is the loopback address's.
        const bool port_only = viewer_address.find_first_not_of("0123456789") == std::string::npos;
        edited.set_viewer_address(port_only ? "127.0.0.1:" + viewer_address : viewer_address);
      }
      if (!viewer_root.empty()) edited.set_viewer_root(viewer_root);
      if (!http_address.empty()) {
        const bool port_only = http_address.find_first_not_of("0123456789") == std::string::npos;
        edited.set_http_address(port_only ? "127.0.0.1:" + http_address : http_address);
      }
      if (insecure) edited.set_insecure_remote_access(true);
      if (udp_port >= 0) edited.set_udp_port(static_cast<std::uint32_t>(udp_port));
      if (lockstep) edited.set_time_mode(haptic::v1::LOCKSTEP);
    };
    if (config_path.empty()) {
      config = haptic::config::default_config();
      apply_overrides(config);
    } else {
      config = haptic::config::load_config_file(config_path, apply_overrides);
    }
    if (!scene_path.empty()) *config.mutable_initial_scene() = haptic::config::load_scene_file(scene_path);
    if (auto error = haptic::config::validate(config); !error.empty()) {
      throw haptic::config::ConfigError("configuration: " + error);
    }
  } catch (const haptic::config::ConfigError& error) {
    std::cerr << "hapticd: " << error.what() << "\n";
    return 2;
  }
  if (print_config) {
    // The configuration may hold secrets: they are never printed.
    for (haptic::v1::AccessToken& token : *config.mutable_security()->mutable_tokens()) {
      token.set_token("<redacted>");
    }
    std::cout << haptic::config::to_json(config);
    return 0;
  }

  // Block the stop signals in every thread; this one waits for them with sigwait.
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);

  try {
    haptic::app::Server server(config);
    if (!record_path.empty()) {
      if (const std::string error = server.start_recording(record_path); !error.empty()) {
        spdlog::error("hapticd: --record: {}", error);
        return 1;
      }
    }
    server.start();
    if (!ready_file.empty()) write_ready_file(ready_file, server, config.grpc_address());
    int signal_number = 0;
    sigwait(&stop_signals, &signal_number);
    spdlog::info("hapticd: {} received, ramping forces to zero", strsignal(signal_number));
    server.shutdown();
  } catch (const haptic::config::ConfigError& error) {
    // Found only at start (unreadable key or token files, a key that is not the certificate's):
    // a configuration error like those above.
    spdlog::error("hapticd: {}", error.what());
    return 2;
  } catch (const std::exception& error) {
    spdlog::error("hapticd: {}", error.what());
    return 1;
  }
  return 0;
}
