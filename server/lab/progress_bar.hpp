#pragma once
// A progress bar on standard error for haptic-lab's long work: redrawn in place on a terminal
// ("[=========>          ]  45% 120/260  what"), one line per tenth otherwise (CI logs).

#include <unistd.h>

#include <cstddef>
#include <cstdio>
#include <string>

namespace haptic::lab {

class ProgressBar {
 public:
  /// `label` starts the line printed off a terminal ("haptic-lab study"); disabled: silent.
  ProgressBar(std::string label, bool enabled)
      : label_(std::move(label)), enabled_(enabled), terminal_(isatty(STDERR_FILENO) != 0) {}

  void update(std::size_t done, std::size_t total, const std::string& what = {}) {
    if (!enabled_ || total == 0) return;
    const int percent = static_cast<int>(100 * done / total);
    if (!terminal_) {
      if (percent / 10 > last_tenth_ || done == total) {
        last_tenth_ = percent / 10;
        std::fprintf(stderr, "%s: %3d%% (%zu/%zu)\n", label_.c_str(), percent, done, total);
      }
      return;
    }
    if (percent == last_percent_ && done != total && what.empty()) return;  // nothing new to draw
    last_percent_ = percent;
    constexpr int kWidth = 30;
    const int filled = static_cast<int>(kWidth * done / total);
    std::string bar(static_cast<std::size_t>(filled), '=');
    if (filled < kWidth) bar += '>';
    bar.resize(kWidth, ' ');
    std::fprintf(stderr, "\r[%s] %3d%% %zu/%zu  %-50.50s", bar.c_str(), percent, done, total, what.c_str());
    if (done == total) std::fprintf(stderr, "\n");
    std::fflush(stderr);
  }

 private:
  std::string label_;
  bool enabled_;
  bool terminal_;
  int last_tenth_ = -1;
  int last_percent_ = -1;
};

}  // namespace haptic::lab
