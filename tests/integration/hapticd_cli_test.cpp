// hapticd's command line: what it refuses before binding anything, and the overrides it takes.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <string>
#include <vector>

namespace haptic {
namespace {

struct Outcome {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
};

/// Runs hapticd with `args` to completion (every call here exits at once: --print-config or a
/// refusal), capturing what it prints.
Outcome run_hapticd(const std::vector<std::string>& args) {
  int pipe_fds[2];
  if (::pipe(pipe_fds) != 0) return {};
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);  // never outlive the test
    if (::getppid() != parent) ::_exit(127);
    ::dup2(pipe_fds[1], STDOUT_FILENO);
    ::dup2(pipe_fds[1], STDERR_FILENO);
    ::close(pipe_fds[0]);
    std::vector<char*> argv;
    std::string binary = HAPTICD_BINARY;
    argv.push_back(binary.data());
    std::vector<std::string> copies = args;
    for (std::string& arg : copies) argv.push_back(arg.data());
    argv.push_back(nullptr);
    ::execv(binary.c_str(), argv.data());
    ::_exit(127);
  }
  ::close(pipe_fds[1]);
  Outcome outcome;
  std::array<char, 4096> buffer{};
  for (ssize_t n; (n = ::read(pipe_fds[0], buffer.data(), buffer.size())) > 0;) {
    outcome.output.append(buffer.data(), static_cast<std::size_t>(n));
  }
  ::close(pipe_fds[0]);
  int status = 0;
  ::waitpid(pid, &status, 0);
  outcome.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return outcome;
}

TEST(HapticdCli, ANonLoopbackAddressIsRefusedWithoutInsecureNamingTheAddress) {
  const Outcome grpc = run_hapticd({"--grpc-address", "0.0.0.0:0", "--print-config"});
  EXPECT_EQ(grpc.exit_code, 2);
  EXPECT_NE(grpc.output.find("grpc_address: '0.0.0.0:0' is not a loopback address"),
            std::string::npos)
      << grpc.output;
  const Outcome udp = run_hapticd({"--udp-address", "0.0.0.0", "--print-config"});
  EXPECT_EQ(udp.exit_code, 2);
  EXPECT_NE(udp.output.find("udp_address: '0.0.0.0' is not a loopback address"), std::string::npos)
      << udp.output;
}

TEST(HapticdCli, InsecureAcceptsRemoteAddressesAndTheOverridesReachTheConfiguration) {
  const Outcome accepted = run_hapticd(
      {"--grpc-address", "0.0.0.0:0", "--udp-address", "0.0.0.0", "--insecure", "--print-config"});
  EXPECT_EQ(accepted.exit_code, 0) << accepted.output;
  EXPECT_NE(accepted.output.find(R"("grpc_address": "0.0.0.0:0")"), std::string::npos);
  EXPECT_NE(accepted.output.find(R"("udp_address": "0.0.0.0")"), std::string::npos);
  EXPECT_NE(accepted.output.find(R"("insecure_remote_access": true)"), std::string::npos);
}

TEST(HapticdCli, TheBuiltInDefaultsListenOnLoopbackOnly) {
  const Outcome defaults = run_hapticd({"--print-config"});
  EXPECT_EQ(defaults.exit_code, 0) << defaults.output;
  EXPECT_NE(defaults.output.find(R"("grpc_address": "127.0.0.1:50051")"), std::string::npos);
  EXPECT_NE(defaults.output.find(R"("udp_address": "127.0.0.1")"), std::string::npos);
  EXPECT_NE(defaults.output.find(R"("insecure_remote_access": false)"), std::string::npos);
}

}  // namespace
}  // namespace haptic
