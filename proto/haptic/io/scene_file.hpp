#pragma once
// Reading a scene file: a haptic.v1.Scene in protobuf's JSON mapping (config/scenes/). Shared by
// hapticd (`--scene`, app::load_scene_file) and the SDK (Client::apply_scene_file), which builds
// without the server.

#include <string>

#include "haptic/v1/scene.pb.h"

namespace haptic::io {

/// Parses the file at `path` into `out` (unknown fields are errors). Returns "" on success, else
/// "'<path>': cannot open: <why>", "'<path>': larger than 256 MiB, ..." or "<path>: not a valid
/// Scene: <parser's message>".
std::string read_scene_file(const std::string& path, v1::Scene& out);

/// The same for text already read; `source` names it in the message.
std::string parse_scene_json(const std::string& text, const std::string& source, v1::Scene& out);

/// `scene` as a scene file's text (indented JSON, field names as the files write them): what
/// read_scene_file reads back to the same message.
std::string scene_json(const v1::Scene& scene);

}  // namespace haptic::io
