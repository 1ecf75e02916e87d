// Fuzz entry point: triangle meshes, built from the bytes so that most of them are meshes at all
// (vertices on a millimetre grid, indices mostly in range) and some carry any double (NaN,
// infinities, subnormals) or an index out of range, then validated and given their hierarchy as
// CreateObject does. Either refused with a message naming the mesh, or accepted and compiled.
//   byte 0: vertex count (4 ... 67); then per vertex 6 bytes, three signed 16-bit grid
//   coordinates (mm), or, when the vertex's first byte is 0xff, 24 bytes of raw doubles; the rest
//   are indices, one byte each, modulo (vertex count + 1) so one value is always out of range.
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "engine/scene/compiled_scene.hpp"
#include "fuzz/fuzz_seeds.hpp"
#include "haptic/v1/scene.pb.h"
#include "schema/scene_specs.hpp"

namespace haptic::fuzz {
std::vector<std::string> seeds() {
  // A tetrahedron, 100 mm edges: 4 vertices, then the 12 indices of its four faces.
  std::string tetrahedron(1, '\0');
  for (const std::int16_t c : {0, 0, 0, 100, 0, 0, 0, 100, 0, 0, 0, 100}) {
    tetrahedron += static_cast<char>(c & 0xff);
    tetrahedron += static_cast<char>((c >> 8) & 0xff);
  }
  for (const char i : {0, 2, 1, 0, 1, 3, 1, 2, 3, 0, 3, 2}) tetrahedron += i;
  return {tetrahedron};
}
}  // namespace haptic::fuzz

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  std::size_t at = 0;
  const std::size_t vertices = 4 + data[at++] % 64;
  haptic::v1::Object object;
  object.mutable_impedance()->set_stiffness(1000.0);
  auto* mesh = object.mutable_mesh();
  for (std::size_t v = 0; v < vertices; ++v) {
    double xyz[3] = {0, 0, 0};
    if (at < size && data[at] == 0xff && at + 25 <= size) {
      ++at;
      for (double& c : xyz) {
        std::uint64_t bits = 0;
        std::memcpy(&bits, data + at, 8);
        c = std::bit_cast<double>(bits);
        at += 8;
      }
    } else {
      for (double& c : xyz) {
        std::int16_t grid = 0;
        if (at + 2 <= size) {
          grid = static_cast<std::int16_t>(data[at] | (data[at + 1] << 8));
          at += 2;
        }
        c = 1e-3 * grid;
      }
    }
    haptic::v1::Vec3* out = mesh->add_vertices();
    out->set_x(xyz[0]);
    out->set_y(xyz[1]);
    out->set_z(xyz[2]);
  }
  for (; at < size; ++at) mesh->add_indices(data[at] % (vertices + 1));
  haptic::engine::ObjectSpec spec;
  const std::string error = haptic::schema::to_object_spec(object, "object", haptic::schema::SceneLimits{}, spec);
  if (!error.empty()) {
    if (error.rfind("object.", 0) != 0) std::abort();
    return 0;
  }
  // Accepted: it compiles into a scene and a tool anywhere near it gets a finite force.
  haptic::engine::SceneDescription description;
  haptic::engine::ItemMeta meta;
  meta.id = 1;
  description.objects.push_back(haptic::engine::ObjectEntry{meta, spec});
  const haptic::engine::CompiledScene scene = haptic::engine::compile_scene(description, 1, 1);
  for (const double z : {-0.05, 0.0, 0.02, 0.05}) {
    const haptic::engine::SceneForce force = haptic::engine::evaluate_scene(scene, {0.01, 0.01, z}, {}, 10);
    if (!std::isfinite(force.F_T_W.x) || !std::isfinite(force.F_T_W.y) || !std::isfinite(force.F_T_W.z)) {
      std::abort();
    }
  }
  return 0;
}
