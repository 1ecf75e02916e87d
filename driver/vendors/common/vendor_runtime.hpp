#pragma once
// What every vendor driver does with its vendor's runtime library and its readings, written once:
// loading the library under its usual names (saying which were tried), and a rotation matrix as
// the quaternion hapticd's reading takes. Header-only, free of any library but libdl (and the JSON
// library driver_params.hpp reads params with).

#include <dlfcn.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "common/driver_params.hpp"

namespace haptic::vendor {

/// dlopens the first of `names` that loads (RTLD_NOW | RTLD_LOCAL). On failure returns nullptr
/// and sets `tried` to the names tried, each absent one by its name and one that is there but
/// cannot load (a dependency missing, say) by dlerror's reason.
inline void* load_first(const std::vector<std::string>& names, std::string& tried) {
  tried.clear();
  for (const std::string& name : names) {
    if (void* handle = dlopen(name.c_str(), RTLD_NOW | RTLD_LOCAL)) return handle;
    const char* why = dlerror();
    const std::string reason = why != nullptr ? why : "";
    const bool absent = reason.rfind(name + ": cannot open shared object file", 0) == 0;
    tried += (tried.empty() ? "" : ", ") + (absent || reason.empty() ? name : reason);
  }
  return nullptr;
}

/// A runtime loaded: dlclosed however the scope that holds it ends.
struct LibraryCloser {
  void operator()(void* library) const { dlclose(library); }
};
using LoadedLibrary = std::unique_ptr<void, LibraryCloser>;

/// Where a vendor's runtime is looked for, and what to say when it is not there.
struct RuntimeSearch {
  std::vector<std::string> defaults;  // names dlopen tries in order when params.library is not given
  std::string runtime;                // for people: "Force Dimension runtime"
  std::string install;                // what to install: "install the Force Dimension SDK (...)"
};

/// Loads a vendor's runtime: `wanted` (params.library) alone when given, else the first of
/// `search.defaults` that loads; then resolves its function table `api` with
/// `resolve(library, api)`, which returns the first required function missing ("" when none).
/// Throws Refusal: for the defaults, that the runtime was not found, what was tried and what to
/// install; for `wanted`, that it cannot load and why; for a missing function, which.
template <typename Api, typename Resolve>
LoadedLibrary open_runtime(const std::string& wanted, const RuntimeSearch& search, Api& api, Resolve&& resolve) {
  std::string tried;
  LoadedLibrary library(load_first(wanted.empty() ? search.defaults : std::vector<std::string>{wanted}, tried));
  if (library == nullptr) {
    throw Refusal(wanted.empty() ? "the " + search.runtime + " was not found (tried " + tried + "): " +
                                       search.install + ", or set params.library to it"
                                 : "params.library: cannot load " + tried);
  }
  if (const std::string missing = resolve(library.get(), api); !missing.empty()) {
    throw Refusal("the " + search.runtime + " lacks " + missing);
  }
  return library;
}

/// A function table's member from a list entry X(return type, name, parameters) (each driver
/// lists its runtime's functions once and makes the table's members and their lookup from it).
#define HAPTIC_RUNTIME_FUNCTION(type, name, params) type(*name) params = nullptr;

/// Looks a runtime's functions up by name into typed pointers, remembering the first one missing.
class Symbols {
 public:
  explicit Symbols(void* library) : library_(library) {}
  /// Required: a missing one is remembered (the first, for the refusal).
  template <typename Function>
  void need(Function& slot, const char* name) {
    slot = reinterpret_cast<Function>(dlsym(library_, name));
    if (slot == nullptr && missing_.empty()) missing_ = name;
  }
  /// Optional: left null when absent.
  template <typename Function>
  void may(Function& slot, const char* name) {
    slot = reinterpret_cast<Function>(dlsym(library_, name));
  }
  /// The first required function not found; empty when all were.
  const std::string& missing() const { return missing_; }

 private:
  void* library_;
  std::string missing_;
};

/// A rotation matrix, m[i][j] = R(i, j), as a unit quaternion q = (w, x, y, z) (Shepperd's
/// method: the largest of the four candidates as the divisor, so it stays accurate at every angle).
inline void quaternion_of(const double m[3][3], double q[4]) {
  const double trace = m[0][0] + m[1][1] + m[2][2];
  if (trace > 0.0) {
    const double s = 2.0 * std::sqrt(1.0 + trace);
    q[0] = 0.25 * s;
    q[1] = (m[2][1] - m[1][2]) / s;
    q[2] = (m[0][2] - m[2][0]) / s;
    q[3] = (m[1][0] - m[0][1]) / s;
  } else if (m[0][0] > m[1][1] && m[0][0] > m[2][2]) {
    const double s = 2.0 * std::sqrt(1.0 + m[0][0] - m[1][1] - m[2][2]);
    q[0] = (m[2][1] - m[1][2]) / s;
    q[1] = 0.25 * s;
    q[2] = (m[0][1] + m[1][0]) / s;
    q[3] = (m[0][2] + m[2][0]) / s;
  } else if (m[1][1] > m[2][2]) {
    const double s = 2.0 * std::sqrt(1.0 + m[1][1] - m[0][0] - m[2][2]);
    q[0] = (m[0][2] - m[2][0]) / s;
    q[1] = (m[0][1] + m[1][0]) / s;
    q[2] = 0.25 * s;
    q[3] = (m[1][2] + m[2][1]) / s;
  } else {
    const double s = 2.0 * std::sqrt(1.0 + m[2][2] - m[0][0] - m[1][1]);
    q[0] = (m[1][0] - m[0][1]) / s;
    q[1] = (m[0][2] + m[2][0]) / s;
    q[2] = (m[1][2] + m[2][1]) / s;
    q[3] = 0.25 * s;
  }
}

}  // namespace haptic::vendor
