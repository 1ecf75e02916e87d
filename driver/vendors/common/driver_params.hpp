#pragma once
// The "params" object hapticd hands a vendor driver's create() (JSON text), read for the flat keys
// a driver takes: numbers, booleans, strings and [a, b, c] triples. Header-only and free of any
// library, so a driver stays built against <haptic/driver.h> alone. Unknown keys are refused, so
// a misspelt option is an error at start rather than a silent default.

#include <array>
#include <cctype>
#include <cstdlib>
#include <initializer_list>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>

namespace haptic::vendor {

/// Thrown with a message that names the key and what was wrong ("params.index: expected a number").
class ParamsError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class DriverParams {
 public:
  /// Parses `json` (an object of flat values) and refuses any key not in `known`.
  DriverParams(const std::string& json, std::initializer_list<const char*> known) {
    std::size_t at = skip(json, 0);
    if (at >= json.size() || json[at] != '{') throw ParamsError("params: expected a JSON object");
    at = skip(json, at + 1);
    while (at < json.size() && json[at] != '}') {
      const std::string key = string_at(json, at);
      at = skip(json, at);
      if (at >= json.size() || json[at] != ':') throw ParamsError("params." + key + ": expected ':'");
      at = skip(json, at + 1);
      const std::size_t start = at;
      if (json[at] == '"') {
        (void)string_at(json, at);
      } else if (json[at] == '[' || json[at] == '{') {
        const char close = json[at] == '[' ? ']' : '}';
        at = json.find(close, at);
        if (at == std::string::npos) throw ParamsError("params." + key + ": unterminated value");
        ++at;
      } else {
        while (at < json.size() && json[at] != ',' && json[at] != '}') ++at;
      }
      std::string value = json.substr(start, at - start);
      while (!value.empty() && std::isspace(static_cast<unsigned char>(value.back()))) value.pop_back();
      values_[key] = value;
      at = skip(json, at);
      if (at < json.size() && json[at] == ',') at = skip(json, at + 1);
    }
    for (const auto& [key, value] : values_) {
      bool listed = false;
      for (const char* name : known) listed = listed || key == name;
      if (!listed) {
        std::string names;
        for (const char* name : known) names += std::string(names.empty() ? "" : ", ") + name;
        throw ParamsError("params." + key + ": not an option of this driver (it takes " + names + ")");
      }
    }
  }

  bool has(const std::string& key) const { return values_.count(key) != 0; }

  std::optional<double> number(const std::string& key) const {
    const auto found = values_.find(key);
    if (found == values_.end()) return std::nullopt;
    char* end = nullptr;
    const double value = std::strtod(found->second.c_str(), &end);
    if (end == found->second.c_str() || *end != '\0') throw ParamsError("params." + key + ": expected a number");
    return value;
  }
  std::optional<bool> boolean(const std::string& key) const {
    const auto found = values_.find(key);
    if (found == values_.end()) return std::nullopt;
    if (found->second == "true") return true;
    if (found->second == "false") return false;
    throw ParamsError("params." + key + ": expected true or false");
  }
  std::optional<std::string> text(const std::string& key) const {
    const auto found = values_.find(key);
    if (found == values_.end()) return std::nullopt;
    if (found->second.size() < 2 || found->second.front() != '"') {
      throw ParamsError("params." + key + ": expected a string");
    }
    std::size_t at = 0;
    return string_at(found->second, at);
  }
  std::optional<std::array<double, 3>> triple(const std::string& key) const {
    const auto found = values_.find(key);
    if (found == values_.end()) return std::nullopt;
    const std::string& v = found->second;
    std::array<double, 3> out{};
    const char* at = v.c_str();
    if (*at != '[') throw ParamsError("params." + key + ": expected [x, y, z]");
    ++at;
    for (double& value : out) {
      char* end = nullptr;
      value = std::strtod(at, &end);
      if (end == at) throw ParamsError("params." + key + ": expected [x, y, z] (three numbers)");
      at = end;
      while (*at == ' ' || *at == ',') ++at;
    }
    if (*at != ']') throw ParamsError("params." + key + ": expected [x, y, z] (three numbers)");
    return out;
  }

 private:
  static std::size_t skip(const std::string& s, std::size_t at) {
    while (at < s.size() && std::isspace(static_cast<unsigned char>(s[at]))) ++at;
    return at;
  }
  /// The string starting at s[at] == '"' (escapes \" and \\ only); `at` ends past its quote.
  static std::string string_at(const std::string& s, std::size_t& at) {
    if (at >= s.size() || s[at] != '"') throw ParamsError("params: expected a quoted key or string");
    std::string out;
    for (++at; at < s.size() && s[at] != '"'; ++at) {
      if (s[at] == '\\' && at + 1 < s.size()) ++at;
      out += s[at];
    }
    if (at >= s.size()) throw ParamsError("params: unterminated string");
    ++at;
    return out;
  }

  std::map<std::string, std::string> values_;
};

}  // namespace haptic::vendor
