#pragma once
// What the tests that compare touch_wall's ports (C, C#) with the C++ program compare.

#include <regex>
#include <string>

namespace haptic::test {

/// touch_wall's output with the count of datagrams received blanked: how many State datagrams
/// arrived by the end depends on the network's timing even in lockstep (the program says so).
inline std::string without_datagram_count(const std::string& output) {
  return std::regex_replace(output, std::regex("[0-9]+ datagrams received"), "N datagrams received");
}

}  // namespace haptic::test
