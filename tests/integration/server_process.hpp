#pragma once
// Runs the real hapticd binary for a test: ephemeral loopback ports, a JSON config written to a
// temporary file, readiness from --ready-file (never a sleep), SIGTERM and a reaped child at the end.

#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace haptic::test {

/// Where a test's server runs: by default on loopback in this network namespace; or behind a
/// launcher (`ip netns exec NAME`) on an address of that namespace.
struct ServerHost {
  std::vector<std::string> launcher;  ///< run before the binary, e.g. {"ip", "netns", "exec", "srv"}
  std::string address = "127.0.0.1";  ///< the gRPC address's host, and what clients connect to
};

class ServerProcess {
 public:
  /// `config_json` is a haptic.v1.ServerConfig in JSON; ports are forced to ephemeral loopback
  /// (or to `host.address`).
  /// With `fd_limit` > 0 the server runs with at most that many open files (soft and hard).
  /// With `grpc_port` and `udp_port` (not 0) the server binds those: a restart on the same ports.
  explicit ServerProcess(const std::string& config_json, const std::string& extra_arg = {},
                         rlim_t fd_limit = 0, std::uint16_t grpc_port = 0, std::uint16_t udp_port = 0,
                         const ServerHost& host = {})
      : host_address_(host.address) {
    static int counter = 0;
    dir_ = std::filesystem::temp_directory_path() /
           ("hapticd-test-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
    // A test that died leaves its folder, and a later process may get its pid: a stale
    // ready.json there would name a port nobody listens on.
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
    const auto config_path = dir_ / "config.json";
    const auto ready_path = dir_ / "ready.json";
    ready_file_ = ready_path.string();
    std::ofstream(config_path) << config_json;

    // The command line, made before fork: the child of a threaded process must not allocate.
    std::vector<std::string> words = host.launcher;
    for (const std::string& word :
         {std::string(HAPTICD_BINARY), std::string("--config"), config_path.string(),
          std::string("--grpc-address"), host.address + ":" + std::to_string(grpc_port),
          std::string("--udp-port"), std::to_string(udp_port), std::string("--ready-file"),
          ready_path.string()}) {
      words.push_back(word);
    }
    if (!extra_arg.empty()) words.push_back(extra_arg);
    std::vector<char*> argv;
    for (std::string& word : words) argv.push_back(word.data());
    argv.push_back(nullptr);

    const pid_t parent = ::getpid();
    forked_at_ = std::chrono::steady_clock::now();
    pid_ = ::fork();
    if (pid_ < 0) throw std::runtime_error("fork failed");
    if (pid_ == 0) {
      // The server dies with its test (killed, aborted, timed out): it must never live on holding
      // ctest's output pipe. (The signal follows the forking thread: construct on the test's.)
      ::prctl(PR_SET_PDEATHSIG, SIGKILL);
      if (::getppid() != parent) ::_exit(127);  // the test died before the line above ran
      if (fd_limit > 0) {
        const rlimit limit{fd_limit, fd_limit};
        ::setrlimit(RLIMIT_NOFILE, &limit);
      }
      ::execvp(argv[0], argv.data());  // a launcher (ip netns exec) execs the binary in turn
      ::_exit(127);
    }
    // Readiness: the server writes the file only after both ports are bound.
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (!std::filesystem::exists(ready_path)) {
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        throw std::runtime_error("hapticd exited before it was ready");
      }
      if (std::chrono::steady_clock::now() > give_up) throw std::runtime_error("hapticd not ready");
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    ready_at_ = std::chrono::steady_clock::now();
    std::ifstream ready(ready_path);
    std::stringstream text;
    text << ready.rdbuf();
    grpc_port_ = read_port(text.str(), "\"grpc_port\":");
    udp_port_ = read_port(text.str(), "\"udp_port\":");
    metrics_port_ = read_port(text.str(), "\"metrics_port\":");
    viewer_port_ = read_port(text.str(), "\"viewer_port\":");
    http_port_ = read_port(text.str(), "\"http_port\":");
    const std::string origin_key = "\"time_origin_ns\":";
    if (const auto at = text.str().find(origin_key); at != std::string::npos) {
      time_origin_ = std::chrono::steady_clock::time_point(
          std::chrono::nanoseconds(std::stoll(text.str().substr(at + origin_key.size()))));
    }
  }

  ~ServerProcess() {
    stop();
    std::error_code ignored;
    std::filesystem::remove_all(dir_, ignored);
  }

  /// SIGTERM, then wait for a clean exit. Returns the exit status (or -1 if not running).
  int stop() {
    signal_stop();
    return wait();
  }
  /// SIGTERM without waiting (wait() collects the exit).
  void signal_stop() {
    if (pid_ > 0) ::kill(pid_, SIGTERM);
  }
  /// Waits for the process to end. Returns the exit status (or -1 if not running).
  int wait() {
    if (pid_ <= 0) return -1;
    int status = 0;
    ::waitpid(pid_, &status, 0);
    pid_ = -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }

  std::string address() const { return host_address_ + ":" + std::to_string(grpc_port_); }
  pid_t pid() const { return pid_; }
  /// This process's steady clock (CLOCK_MONOTONIC, which the server's time also counts from) just
  /// before the server was started and once it was seen ready: its time 0 lies between the two.
  std::chrono::steady_clock::time_point forked_at() const { return forked_at_; }
  std::chrono::steady_clock::time_point ready_at() const { return ready_at_; }
  std::uint16_t grpc_port() const { return grpc_port_; }
  std::uint16_t udp_port() const { return udp_port_; }
  /// The metrics endpoint's port; 0 when the server has none.
  std::uint16_t metrics_port() const { return metrics_port_; }
  /// The web viewer's port (--http); 0 when the server has none.
  std::uint16_t viewer_port() const { return viewer_port_; }
  /// The control plane's HTTP port (http_address); 0 without one.
  std::uint16_t http_port() const { return http_port_; }
  /// The file the server wrote once listening (--ready-file).
  const std::string& ready_file() const { return ready_file_; }
  /// Real time: this host's steady clock at server time 0 (so a sample stamped t was made at
  /// time_origin() + t). None in lockstep.
  std::optional<std::chrono::steady_clock::time_point> time_origin() const { return time_origin_; }

 private:
  static std::uint16_t read_port(const std::string& text, const std::string& key) {
    const auto at = text.find(key);
    if (at == std::string::npos) throw std::runtime_error("ready file lacks " + key);
    return static_cast<std::uint16_t>(std::stoi(text.substr(at + key.size())));
  }

  std::filesystem::path dir_;
  std::string ready_file_;
  std::string host_address_;
  pid_t pid_ = -1;
  std::chrono::steady_clock::time_point forked_at_;
  std::chrono::steady_clock::time_point ready_at_;
  std::uint16_t grpc_port_ = 0;
  std::uint16_t udp_port_ = 0;
  std::uint16_t metrics_port_ = 0;
  std::uint16_t viewer_port_ = 0;
  std::uint16_t http_port_ = 0;
  std::optional<std::chrono::steady_clock::time_point> time_origin_;
};

/// A lockstep configuration for tests; `extra` is spliced into the JSON object.
inline std::string lockstep_config(const std::string& extra = {}) {
  return std::string(R"({"time_mode": "LOCKSTEP", "udp_address": "127.0.0.1", "status_period_s": 0,
    "real_time": {"use_fifo": false},
    "simulated_point_mass": {"initial_position": {"z": 0.02}})") +
         (extra.empty() ? "" : ", " + extra) + "}";
}

}  // namespace haptic::test
