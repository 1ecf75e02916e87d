#include "runtime/loop_cpu.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

namespace haptic::runtime {
namespace {

/// /run/hapticd, which the installed tmpfiles.d entry makes at boot and hapticd.service keeps as
/// its RuntimeDirectory (writable there under ProtectSystem=strict, where /run/lock is not).
constexpr const char* kRuntimeDirectory = "/run/hapticd";

pid_t read_pid(int fd) {
  char text[32] = {};
  const ssize_t n = ::pread(fd, text, sizeof text - 1, 0);
  return n > 0 ? static_cast<pid_t>(std::atol(text)) : 0;
}

}  // namespace

std::string lock_directory_among(const std::vector<std::string>& candidates) {
  for (const std::string& directory : candidates) {
    if (::access(directory.c_str(), W_OK) == 0) return directory;
  }
  std::error_code error;
  const std::filesystem::path temp = std::filesystem::temp_directory_path(error);
  return error ? "/tmp" : temp.string();
}

std::string LoopCpuClaim::lock_path(int cpu) {
  // The first of these every hapticd on the host can write, so that all of them find one
  // another's claims: /run/hapticd where installed, else /run/lock (a tmpfs every user may write
  // on Debian), else the temporary directory.
  static const std::string directory = lock_directory_among({kRuntimeDirectory, "/run/lock"});
  return directory + "/hapticd-loop-cpu" + std::to_string(cpu) + ".lock";
}

std::optional<LoopCpuClaim> LoopCpuClaim::try_claim(int cpu, pid_t* holder) {
  if (holder != nullptr) *holder = 0;
  const std::string path = lock_path(cpu);
  int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0666);
  if (fd >= 0) {
    (void)::fchmod(fd, 0666);  // whoever made it, any user's server may claim it next (umask aside)
  } else {
    fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);  // another user's file: a lock needs no write
  }
  if (fd < 0) return std::nullopt;  // cannot even mark it: treat it as taken, say nothing of whom
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    if (holder != nullptr) *holder = read_pid(fd);
    ::close(fd);
    return std::nullopt;
  }
  const std::string pid = std::to_string(::getpid()) + "\n";
  if (::ftruncate(fd, 0) == 0) (void)!::pwrite(fd, pid.data(), pid.size(), 0);
  return LoopCpuClaim(cpu, fd);
}

LoopCpuClaim::LoopCpuClaim(LoopCpuClaim&& other) noexcept : cpu_(other.cpu_), fd_(other.fd_) {
  other.fd_ = -1;
}

LoopCpuClaim& LoopCpuClaim::operator=(LoopCpuClaim&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    cpu_ = other.cpu_;
    fd_ = other.fd_;
    other.fd_ = -1;
  }
  return *this;
}

LoopCpuClaim::~LoopCpuClaim() {
  if (fd_ >= 0) ::close(fd_);  // closing the descriptor drops the lock
}

LoopCpuChoice choose_loop_cpu(std::optional<int> configured, int cpus,
                              const std::function<std::optional<LoopCpuClaim>(int, pid_t*)>& claim) {
  LoopCpuChoice choice;
  if (configured) {
    choice.cpu = *configured;
    if (choice.cpu < 0) return choice;
    pid_t holder = 0;
    choice.claim = claim(choice.cpu, &holder);
    if (!choice.claim) {
      choice.warning = "real_time.cpu " + std::to_string(choice.cpu) + " already runs the loop of " +
                       (holder > 0 ? "another hapticd (pid " + std::to_string(holder) + ")"
                                   : std::string("another hapticd")) +
                       ": the two loops share it and delay each other's ticks; give each server a "
                       "CPU of its own";
    }
    return choice;
  }
  if (cpus <= 1) return choice;  // nothing to keep apart
  for (int cpu = cpus - 1; cpu >= 0; --cpu) {
    if (auto held = claim(cpu, nullptr)) {
      choice.cpu = cpu;
      choice.claim = std::move(held);
      return choice;
    }
  }
  choice.cpu = cpus - 1;
  choice.warning = "every CPU (0 to " + std::to_string(cpus - 1) +
                   ") already runs another hapticd's loop: this one shares CPU " +
                   std::to_string(choice.cpu) +
                   ", and the loops delay each other's ticks; set real_time.cpu, or run fewer servers";
  return choice;
}

}  // namespace haptic::runtime
