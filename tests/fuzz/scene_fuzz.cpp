// Fuzz entry point: a scene file (protobuf's JSON mapping of haptic.v1.Scene, as hapticd --scene
// and Client::apply_scene_file read it), then every object and field validated and compiled the
// way the server does (meshes checked in full and their hierarchy built). Either it is refused
// with a message, or every element converts.
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "fuzz/fuzz_seeds.hpp"
#include "haptic/io/scene_file.hpp"
#include "schema/scene_specs.hpp"

namespace haptic::fuzz {
std::vector<std::string> seeds() {
  return {R"({"objects": [{"half_space": {"normal": {"z": 1}}, "impedance": {"stiffness": 1000}}]})",
          R"({"objects": [{"mesh": {"vertices": [{}, {"x": 0.1}, {"y": 0.1}, {"z": 0.1}],
              "indices": [0, 2, 1, 0, 1, 3, 1, 2, 3, 0, 3, 2]}, "impedance": {"stiffness": 500}}]})",
          R"({"fields": [{"potential": {"distance": {"kind": "SPHERE", "radius": 0.02}, "kind": "KHATIB",
              "order": 2, "gain": 1, "influence_distance": 0.05, "min_distance": 0.001}}]})"};
}
}  // namespace haptic::fuzz

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  haptic::v1::Scene scene;
  if (const std::string error = haptic::io::parse_scene_json(text, "fuzz", scene); !error.empty()) return 0;
  haptic::schema::SceneSpecs specs;
  const std::string error = haptic::schema::to_scene_specs(scene, "", haptic::schema::SceneLimits{}, specs);
  if (error.empty() && (specs.objects.size() != static_cast<std::size_t>(scene.objects_size()) ||
                        specs.fields.size() != static_cast<std::size_t>(scene.fields_size()))) {
    std::abort();  // accepted, but not every element came through
  }
  return 0;
}
