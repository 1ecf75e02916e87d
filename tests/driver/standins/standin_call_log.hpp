#pragma once
// The call log the vendor runtimes' stand-ins share (fake_dhd_calls, fake_hd_calls; README.md):
// one line per call, a repeat of the previous countable line counted instead of written again,
// calls beyond kMaxEntries lines only counted. Guarded by the stand-in's own lock.

#include <cstdio>
#include <string>
#include <utility>
#include <vector>

namespace standin {

class CallLog {
 public:
  static constexpr std::size_t kMaxEntries = 50000;  // beyond this, calls are only counted

  void add(std::string line, bool countable) {
    if (!entries_.empty() && countable && entries_.back().countable && entries_.back().line == line) {
      ++entries_.back().count;
      return;
    }
    if (entries_.size() >= kMaxEntries) {
      ++dropped_;
      return;
    }
    entries_.push_back({std::move(line), 1, countable});
  }

  void clear() {
    entries_.clear();
    dropped_ = 0;
    text_.clear();
  }

  /// The log as text ("line" or "line xN" per entry), `reader` naming the function in the note of
  /// a full log; valid until the next text() or clear().
  const char* text(const char* reader) {
    std::string text;
    char buf[96];
    for (const Entry& e : entries_) {
      text += e.line;
      if (e.count > 1) {
        std::snprintf(buf, sizeof buf, " x%ld", e.count);
        text += buf;
      }
      text += '\n';
    }
    if (dropped_ > 0) {
      std::snprintf(buf, sizeof buf, "%s: log full, %ld more calls\n", reader, dropped_);
      text += buf;
    }
    text_ = std::move(text);
    return text_.c_str();
  }

 private:
  struct Entry {
    std::string line;
    long count;
    bool countable;
  };
  std::vector<Entry> entries_;
  long dropped_ = 0;
  std::string text_;
};

}  // namespace standin
