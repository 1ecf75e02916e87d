#pragma once
// Reading a whole file that a person names (a configuration, a scene, a tokens or PEM file) with
// an upper bound on its size, so that a wrong path (/dev/zero, a log, a disk image) is refused in
// a moment instead of read until memory runs out.

#include <cstddef>
#include <string>

namespace haptic::io {

/// The bounds, each above any file of its kind a lab writes. Unit: bytes.
inline constexpr std::size_t kMaxConfigFileBytes = 256u << 20;  // may hold an initial scene's meshes
inline constexpr std::size_t kMaxSceneFileBytes = 256u << 20;   // 200,000 triangles as JSON: ~40 MB
inline constexpr std::size_t kMaxSecretFileBytes = 1u << 20;    // tokens and PEM files

/// Reads the file at `path` into `out`. Returns "" on success, else why not, naming the path:
/// "'<path>': cannot open: <errno text>" or "'<path>': larger than <n> MiB, the most read for
/// <what>" (`what`: "a configuration file", ...).
std::string read_bounded_file(const std::string& path, std::size_t max_bytes, const std::string& what,
                              std::string& out);

}  // namespace haptic::io
