#pragma once
// How a session id is written for people: 16 lower-case hex digits, the same in the server's log,
// in event messages and in hapticctl, so a line from one can be searched for in the others.

#include <cstdint>
#include <cstdio>
#include <string>

namespace haptic::io {

/// "session 00000000075bcd15" style: 16 hex digits, zero-padded.
inline std::string format_session_id(std::uint64_t id) {
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(id));
  return text;
}

/// Reads an id written by format_session_id (any hex of 1–16 digits, "0x" allowed); false, `id`
/// untouched, when `text` is not one.
inline bool parse_session_id(const std::string& text, std::uint64_t& id) {
  std::string digits = text;
  if (digits.rfind("0x", 0) == 0 || digits.rfind("0X", 0) == 0) digits = digits.substr(2);
  if (digits.empty() || digits.size() > 16) return false;
  std::uint64_t value = 0;
  for (const char c : digits) {
    int nibble;
    if (c >= '0' && c <= '9') nibble = c - '0';
    else if (c >= 'a' && c <= 'f') nibble = c - 'a' + 10;
    else if (c >= 'A' && c <= 'F') nibble = c - 'A' + 10;
    else return false;
    value = (value << 4) | static_cast<std::uint64_t>(nibble);
  }
  id = value;
  return true;
}

}  // namespace haptic::io
