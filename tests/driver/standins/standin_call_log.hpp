#pragma once
// The call log the vendor runtimes' stand-ins share (fake_dhd_calls, fake_hd_calls; README.md):
// one line per call, a repeat of the previous countable line counted instead of written again,
// calls beyond kMaxEntries lines only counted. Guarded by the stand-in's own lock. It also throws
// where a test asked (`throw FUNCTION`): a vendor runtime that throws a C++ exception out of its C
// functions, for a driver's test that nothing thrown crosses hapticd's C ABI.

#include <cstdio>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace standin {

class CallLog {
 public:
  static constexpr std::size_t kMaxEntries = 50000;  // beyond this, calls are only counted

  /// Logs `line` (a call: the function's name, a space, its arguments), then throws if the test
  /// asked calls of that function to throw.
  void add(std::string line, bool countable) {
    const bool throws = asked_to_throw(line);
    record(std::move(line), countable);
    if (throws) throw std::runtime_error(throwing_ + " threw (the stand-in's `throw`)");
  }

  /// From now on every call of `function` throws after it is logged ("": none does).
  void throw_from(std::string function) { throwing_ = std::move(function); }
  /// Whether a call logged as `line` is one that throws.
  bool asked_to_throw(const std::string& line) const {
    return !throwing_.empty() && line.compare(0, throwing_.size(), throwing_) == 0 &&
           (line.size() == throwing_.size() || line[throwing_.size()] == ' ');
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
  void record(std::string line, bool countable) {
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

  struct Entry {
    std::string line;
    long count;
    bool countable;
  };
  std::vector<Entry> entries_;
  long dropped_ = 0;
  std::string text_;
  std::string throwing_;  // the function whose calls throw ("": none)
};

}  // namespace standin
