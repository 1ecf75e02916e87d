#pragma once
// The "params" object hapticd hands a vendor driver's create() (JSON text), read for the flat keys
// a driver takes: numbers, booleans, strings and [a, b, c] triples. Parsed with nlohmann/json
// (header-only, as hapticd's own configuration is), so a nested value, an escape or a bracket
// inside a string reads as JSON says. Unknown keys are refused, so a misspelt option is an error
// at start rather than a silent default; a value of the wrong kind is refused naming its key.

#include <array>
#include <cstddef>
#include <initializer_list>
#include <optional>
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

namespace haptic::vendor {

/// Why a driver refuses to open a device (or to list them), in words hapticd shows as they are.
class Refusal : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Thrown with a message that names the key and what was wrong ("params.index: expected a number").
class ParamsError : public Refusal {
 public:
  using Refusal::Refusal;
};

class DriverParams {
 public:
  /// Parses `json` (an object of flat values) and refuses any key not in `known`.
  DriverParams(const std::string& json, std::initializer_list<const char*> known)
      : DriverParams(json, known.begin(), known.end()) {}
  template <std::size_t N>
  DriverParams(const std::string& json, const char* const (&known)[N]) : DriverParams(json, known, known + N) {}

  DriverParams(const std::string& json, const char* const* known_begin, const char* const* known_end) {
    values_ = nlohmann::json::parse(json, nullptr, /*allow_exceptions=*/false);
    if (values_.is_discarded()) throw ParamsError("params: not valid JSON: " + json.substr(0, 200));
    if (!values_.is_object()) throw ParamsError("params: expected a JSON object");
    for (const auto& [key, value] : values_.items()) {
      bool listed = false;
      for (auto name = known_begin; name != known_end; ++name) listed = listed || key == *name;
      if (!listed) {
        std::string names;
        for (auto name = known_begin; name != known_end; ++name) {
          names += std::string(names.empty() ? "" : ", ") + *name;
        }
        throw ParamsError("params." + key + ": not an option of this driver (it takes " + names + ")");
      }
    }
  }

  bool has(const std::string& key) const { return values_.contains(key); }

  std::optional<double> number(const std::string& key) const {
    const nlohmann::json* value = find(key);
    if (value == nullptr) return std::nullopt;
    if (!value->is_number()) throw ParamsError("params." + key + ": expected a number");
    return value->get<double>();
  }
  std::optional<bool> boolean(const std::string& key) const {
    const nlohmann::json* value = find(key);
    if (value == nullptr) return std::nullopt;
    if (!value->is_boolean()) throw ParamsError("params." + key + ": expected true or false");
    return value->get<bool>();
  }
  std::optional<std::string> text(const std::string& key) const {
    const nlohmann::json* value = find(key);
    if (value == nullptr) return std::nullopt;
    if (!value->is_string()) throw ParamsError("params." + key + ": expected a string");
    return value->get<std::string>();
  }
  std::optional<std::array<double, 3>> triple(const std::string& key) const {
    const nlohmann::json* value = find(key);
    if (value == nullptr) return std::nullopt;
    if (!value->is_array() || value->size() != 3) {
      throw ParamsError("params." + key + ": expected [x, y, z] (three numbers)");
    }
    std::array<double, 3> out{};
    for (std::size_t i = 0; i < 3; ++i) {
      if (!(*value)[i].is_number()) throw ParamsError("params." + key + ": expected [x, y, z] (three numbers)");
      out[i] = (*value)[i].get<double>();
    }
    return out;
  }

 private:
  const nlohmann::json* find(const std::string& key) const {
    const auto found = values_.find(key);
    return found == values_.end() ? nullptr : &*found;
  }

  nlohmann::json values_;
};

}  // namespace haptic::vendor
