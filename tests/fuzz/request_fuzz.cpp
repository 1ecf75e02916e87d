// Fuzz entry point: the control plane's requests as they arrive (protobuf binary), run through
// the validation each RPC runs before anything changes: objects (meshes included) and fields for
// Create/Update, whole scenes for ApplyScene, the operator's input for SetOperator, and the
// stability report of every object accepted. The first byte picks the request; the rest is its
// wire bytes. A message that does not parse is the transport's business; one that does must be
// accepted or refused with a message naming the field.
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "fuzz/fuzz_seeds.hpp"
#include "haptic/v1/service.pb.h"
#include "schema/scene_specs.hpp"
#include "schema/stability.hpp"

namespace {

using namespace haptic;

enum Kind : std::uint8_t { kObject, kField, kScene, kOperator, kKinds };

// The default simulated point mass (docs/devices.md), the device the stability report is for.
constexpr schema::DeviceMassDamper kDevice{0.01, 0.022};

void refused_with_a_message(const std::string& error, const char* path) {
  if (error.rfind(path, 0) != 0) std::abort();  // the message names the field, from the top
}

void check_object(const v1::Object& object, const schema::SceneLimits& limits) {
  engine::ObjectSpec spec;
  const std::string error = schema::to_object_spec(object, "object", limits, spec);
  if (!error.empty()) return refused_with_a_message(error, "object");
  const v1::StabilityReport report =
      schema::stability_report(spec, kDevice, limits.period_s, object.impedance().transparency_optimal_damping(),
                               object.impedance().virtual_coupling());
  if (!std::isfinite(report.colgate_min_damping())) std::abort();  // a report, never a NaN
}

std::string with_kind(Kind kind, const google::protobuf::Message& message) {
  return std::string(1, static_cast<char>(kind)) + message.SerializeAsString();
}

}  // namespace

namespace haptic::fuzz {
std::vector<std::string> seeds() {
  std::vector<std::string> out;
  v1::Object wall;
  wall.mutable_half_space()->mutable_normal()->set_z(1.0);
  wall.mutable_impedance()->set_stiffness(1000.0);
  out.push_back(with_kind(kObject, wall));
  v1::Object ball;
  ball.mutable_sphere()->set_radius(0.02);
  ball.mutable_impedance()->set_stiffness(500.0);
  ball.mutable_dynamics()->set_mass(0.5);
  ball.mutable_dynamics()->set_damping(1.0);
  out.push_back(with_kind(kObject, ball));
  v1::Object mesh;  // a tetrahedron
  for (const auto& [x, y, z] : {std::array{0.0, 0.0, 0.0}, std::array{0.1, 0.0, 0.0}, std::array{0.0, 0.1, 0.0},
                                std::array{0.0, 0.0, 0.1}}) {
    v1::Vec3* v = mesh.mutable_mesh()->add_vertices();
    v->set_x(x);
    v->set_y(y);
    v->set_z(z);
  }
  for (const std::uint32_t i : {0u, 2u, 1u, 0u, 1u, 3u, 1u, 2u, 3u, 0u, 3u, 2u}) mesh.mutable_mesh()->add_indices(i);
  mesh.mutable_impedance()->set_stiffness(800.0);
  out.push_back(with_kind(kObject, mesh));
  v1::Field spring;
  spring.mutable_spring_to_point()->set_stiffness(20.0);
  out.push_back(with_kind(kField, spring));
  v1::Field detent;
  detent.mutable_detent()->set_depth(0.001);
  detent.mutable_detent()->set_radius(0.02);
  out.push_back(with_kind(kField, detent));
  v1::Scene scene;
  *scene.add_objects() = wall;
  *scene.add_objects() = mesh;
  *scene.add_fields() = spring;
  out.push_back(with_kind(kScene, scene));
  v1::OperatorInput hand;
  hand.set_mode(v1::OperatorInput::FOLLOW_TARGET);
  hand.set_grip(v1::OperatorInput::TIGHT);
  out.push_back(with_kind(kOperator, hand));
  return out;
}
}  // namespace haptic::fuzz

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const auto kind = static_cast<Kind>(data[0] % kKinds);
  const void* bytes = data + 1;
  const int length = static_cast<int>(size - 1);
  const schema::SceneLimits limits;
  switch (kind) {
    case kObject: {
      v1::Object object;
      if (object.ParseFromArray(bytes, length)) check_object(object, limits);
      break;
    }
    case kField: {
      v1::Field field;
      engine::FieldSpec spec;
      if (field.ParseFromArray(bytes, length)) {
        const std::string error = schema::to_field_spec(field, "field", limits, spec);
        if (!error.empty()) refused_with_a_message(error, "field");
      }
      break;
    }
    case kScene: {
      v1::Scene scene;
      schema::SceneSpecs specs;
      if (scene.ParseFromArray(bytes, length)) {
        const std::string error = schema::to_scene_specs(scene, "scene.", limits, specs);
        if (!error.empty()) refused_with_a_message(error, "scene.");
        if (error.empty() && specs.objects.size() != static_cast<std::size_t>(scene.objects_size())) std::abort();
      }
      break;
    }
    default: {
      v1::OperatorInput input;
      engine::HandInput hand;
      if (input.ParseFromArray(bytes, length)) {
        const std::string error = schema::to_hand_input(input, "input", limits, hand);
        if (!error.empty()) refused_with_a_message(error, "input");
      }
      break;
    }
  }
  return 0;
}
