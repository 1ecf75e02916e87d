// The test harness itself: a server started by a test dies with the test, even when the test
// process is killed or aborts (one once lived on, holding ctest's output pipe for 20 minutes).
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <string>
#include <thread>

#include "integration/server_process.hpp"

namespace haptic {
namespace {

/// True while `pid` is a live process (a zombie waiting for its reaper counts as gone).
bool alive(pid_t pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string text;
  if (!std::getline(stat, text)) return false;
  const auto close = text.rfind(')');
  return close != std::string::npos && close + 2 < text.size() && text[close + 2] != 'Z';
}

TEST(ServerProcess, TheServerDiesWithATestThatAborts) {
  int pipe_fds[2];
  ASSERT_EQ(::pipe(pipe_fds), 0);
  const pid_t test = ::fork();
  ASSERT_GE(test, 0);
  if (test == 0) {  // a test that starts a server and then aborts without any cleanup
    ::close(pipe_fds[0]);
    test::ServerProcess server(test::lockstep_config());
    const pid_t server_pid = server.pid();
    (void)!::write(pipe_fds[1], &server_pid, sizeof server_pid);
    std::abort();
  }
  ::close(pipe_fds[1]);
  pid_t server_pid = 0;
  ASSERT_EQ(::read(pipe_fds[0], &server_pid, sizeof server_pid), static_cast<ssize_t>(sizeof server_pid));
  ::close(pipe_fds[0]);
  int status = 0;
  ASSERT_EQ(::waitpid(test, &status, 0), test);
  EXPECT_TRUE(WIFSIGNALED(status));
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (alive(server_pid) && std::chrono::steady_clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_FALSE(alive(server_pid)) << "hapticd " << server_pid << " outlived its test";
  if (alive(server_pid)) ::kill(server_pid, SIGKILL);
}

}  // namespace
}  // namespace haptic
