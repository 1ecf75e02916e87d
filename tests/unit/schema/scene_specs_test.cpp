// Bad input at the boundary gets an error that names the field.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <variant>

#include "schema/scene_specs.hpp"

namespace haptic::schema {
namespace {

v1::Object good_wall() {
  v1::Object object;
  object.mutable_impedance()->set_stiffness(1000.0);
  object.mutable_impedance()->set_damping(1.0);
  object.mutable_half_space()->mutable_normal()->set_z(2.0);
  return object;
}

std::string error_of(const v1::Object& object) {
  engine::ObjectSpec spec;
  return to_object_spec(object, "object", SceneLimits{}, spec);
}

TEST(Validation, AcceptsAWallAndKeepsItsValues) {
  engine::ObjectSpec spec;
  ASSERT_EQ(to_object_spec(good_wall(), "object", SceneLimits{}, spec), "");
  EXPECT_EQ(spec.stiffness, 1000.0);
  EXPECT_EQ(spec.damping, 1.0);
  ASSERT_TRUE(std::holds_alternative<engine::HalfSpaceSpec>(spec.shape));
  EXPECT_EQ(spec.R_WO.w, 1.0);  // unset orientation is identity
}

TEST(Validation, NamesTheFieldThatIsWrong) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto with = [](auto change) {
    v1::Object object = good_wall();
    change(object);
    return error_of(object);
  };
  EXPECT_EQ(with([&](v1::Object& o) { o.mutable_impedance()->set_stiffness(nan); })
                .rfind("object.impedance.stiffness:", 0), 0u);
  EXPECT_EQ(with([](v1::Object& o) { o.mutable_impedance()->set_damping(-1.0); })
                .rfind("object.impedance.damping:", 0), 0u);
  EXPECT_EQ(with([](v1::Object& o) { o.mutable_impedance()->set_stiffness(1e12); })
                .rfind("object.impedance.stiffness:", 0), 0u);
  EXPECT_EQ(with([](v1::Object& o) { o.mutable_half_space()->mutable_normal()->set_z(0.0); })
                .rfind("object.half_space.normal:", 0), 0u);
  EXPECT_EQ(with([&](v1::Object& o) { o.mutable_pose()->mutable_position()->set_y(nan); })
                .rfind("object.pose.position.y:", 0), 0u);
  EXPECT_EQ(with([](v1::Object& o) { o.mutable_pose()->mutable_orientation()->set_w(0.5); })
                .rfind("object.pose.orientation:", 0), 0u);
  EXPECT_EQ(with([](v1::Object& o) { o.clear_impedance(); }).rfind("object.impedance:", 0), 0u);
  EXPECT_EQ(with([](v1::Object& o) { o.clear_shape(); }).rfind("object.shape:", 0), 0u);
  EXPECT_EQ(with([](v1::Object& o) { o.mutable_sphere()->set_radius(0.0); })
                .rfind("object.sphere.radius:", 0), 0u);
}

TEST(Validation, FieldsAndOperatorInput) {
  v1::Field field;
  engine::FieldSpec spec;
  EXPECT_EQ(to_field_spec(field, "field", SceneLimits{}, spec).rfind("field.kind:", 0), 0u);
  field.mutable_spring_to_point()->set_stiffness(-3.0);
  EXPECT_EQ(to_field_spec(field, "field", SceneLimits{}, spec)
                .rfind("field.spring_to_point.stiffness:", 0), 0u);
  field.mutable_spring_to_point()->set_stiffness(30.0);
  EXPECT_EQ(to_field_spec(field, "field", SceneLimits{}, spec), "");

  v1::OperatorInput input;
  engine::HandInput hand;
  EXPECT_EQ(to_hand_input(input, "input", SceneLimits{}, hand).rfind("input.mode:", 0), 0u);
  input.set_mode(v1::OperatorInput::APPLY_FORCE);
  input.mutable_force()->set_x(std::numeric_limits<double>::infinity());
  EXPECT_EQ(to_hand_input(input, "input", SceneLimits{}, hand).rfind("input.force.x:", 0), 0u);
  input.set_mode(static_cast<v1::OperatorInput::Mode>(42));
  EXPECT_EQ(to_hand_input(input, "input", SceneLimits{}, hand).rfind("input.mode:", 0), 0u);
}

TEST(Validation, GripPresetsTrajectoriesAndProfiles) {
  v1::OperatorInput input;
  engine::HandInput hand;
  input.set_mode(v1::OperatorInput::FOLLOW_TARGET);
  input.set_grip(v1::OperatorInput::TIGHT);
  input.set_stiffness(-1.0);  // ignored: the preset sets the impedance
  ASSERT_EQ(to_hand_input(input, "input", SceneLimits{}, hand), "");
  EXPECT_EQ(hand.mass, engine::kTightGrip.mass);
  EXPECT_EQ(hand.stiffness, 800.0);
  EXPECT_EQ(hand.damping, 15.0);

  input.set_grip(v1::OperatorInput::CUSTOM);
  input.set_stiffness(100.0);
  input.set_mass(50.0);
  EXPECT_EQ(to_hand_input(input, "input", SceneLimits{}, hand).rfind("input.mass:", 0), 0u);
  input.set_mass(1.0);
  input.mutable_trajectory()->set_shape(v1::TargetTrajectory::LINE);
  EXPECT_EQ(to_hand_input(input, "input", SceneLimits{}, hand)
                .rfind("input.trajectory.duration_s:", 0), 0u);
  input.mutable_trajectory()->set_duration_s(2.0);
  input.mutable_trajectory()->mutable_end()->set_z(-0.01);
  ASSERT_EQ(to_hand_input(input, "input", SceneLimits{}, hand), "");
  EXPECT_EQ(hand.trajectory.shape, engine::TargetTrajectory::Shape::kLine);
  EXPECT_EQ(hand.trajectory.end.z, -0.01);

  v1::OperatorInput push;
  push.set_mode(v1::OperatorInput::APPLY_FORCE);
  push.mutable_force()->set_z(-5.0);
  push.mutable_profile()->set_shape(v1::ForceProfile::RAMP);
  push.mutable_profile()->set_rise_s(-0.5);
  EXPECT_EQ(to_hand_input(push, "input", SceneLimits{}, hand).rfind("input.profile.rise_s:", 0), 0u);
  push.mutable_profile()->set_rise_s(0.5);
  ASSERT_EQ(to_hand_input(push, "input", SceneLimits{}, hand), "");
  EXPECT_EQ(hand.profile.shape, engine::ForceProfile::Shape::kRamp);
  push.mutable_profile()->set_shape(v1::ForceProfile::RECORDED);
  EXPECT_EQ(to_hand_input(push, "input", SceneLimits{}, hand).rfind("input.profile.samples:", 0), 0u);
  for (int i = 0; i < 3; ++i) push.mutable_profile()->add_samples()->set_z(-1.0 * i);
  EXPECT_EQ(to_hand_input(push, "input", SceneLimits{}, hand)
                .rfind("input.profile.sample_period_s:", 0), 0u);
  push.mutable_profile()->set_sample_period_s(0.01);
  push.mutable_profile()->mutable_samples(1)->set_x(std::numeric_limits<double>::quiet_NaN());
  EXPECT_EQ(to_hand_input(push, "input", SceneLimits{}, hand)
                .rfind("input.profile.samples[1]", 0), 0u);
  push.mutable_profile()->mutable_samples(1)->set_x(0.0);
  ASSERT_EQ(to_hand_input(push, "input", SceneLimits{}, hand), "");
  EXPECT_EQ(hand.profile.shape, engine::ForceProfile::Shape::kRecorded);
  EXPECT_EQ(hand.profile.recorded.count, 3u);
  EXPECT_EQ(hand.profile.recorded.samples[2].z, -2.0);
  for (int i = 0; i < 600; ++i) push.mutable_profile()->add_samples();
  EXPECT_EQ(to_hand_input(push, "input", SceneLimits{}, hand).rfind("input.profile.samples:", 0), 0u);
  push.mutable_profile()->set_shape(static_cast<v1::ForceProfile::Shape>(9));
  EXPECT_EQ(to_hand_input(push, "input", SceneLimits{}, hand).rfind("input.profile.shape:", 0), 0u);
}

v1::Object object_with(double stiffness) {
  v1::Object object;
  object.mutable_impedance()->set_stiffness(stiffness);
  return object;
}

TEST(Validation, NewShapesAndMaterialsNameWhatIsWrong) {
  engine::ObjectSpec spec;
  v1::Object box = object_with(1000.0);
  box.mutable_box()->mutable_half_extents()->set_x(0.01);
  box.mutable_box()->mutable_half_extents()->set_y(0.01);
  EXPECT_EQ(to_object_spec(box, "o", SceneLimits{}, spec),
            "o.box.half_extents.z: must be finite and in (0, 10], got 0");
  box.mutable_box()->mutable_half_extents()->set_z(-0.01);  // a size, not a coordinate
  EXPECT_EQ(to_object_spec(box, "o", SceneLimits{}, spec),
            "o.box.half_extents.z: must be finite and in (0, 10], got -0.01");
  box.mutable_box()->mutable_half_extents()->set_z(0.01);
  ASSERT_EQ(to_object_spec(box, "o", SceneLimits{}, spec), "");
  EXPECT_TRUE(std::holds_alternative<engine::BoxSpec>(spec.shape));
  EXPECT_FALSE(spec.shared);
  box.set_shared(true);
  ASSERT_EQ(to_object_spec(box, "o", SceneLimits{}, spec), "");
  EXPECT_TRUE(spec.shared);

  v1::Object capsule = object_with(1000.0);
  capsule.mutable_capsule()->set_radius(0.01);
  capsule.mutable_capsule()->set_half_length(-0.1);
  EXPECT_EQ(to_object_spec(capsule, "o", SceneLimits{}, spec).rfind("o.capsule.half_length", 0), 0u);

  v1::Object rough = box;
  rough.mutable_impedance()->set_static_friction(0.3);
  rough.mutable_impedance()->set_dynamic_friction(0.5);  // more than static
  EXPECT_EQ(to_object_spec(rough, "o", SceneLimits{}, spec).rfind("o.impedance.dynamic_friction", 0), 0u);
  rough.mutable_impedance()->set_dynamic_friction(0.2);
  rough.mutable_impedance()->set_law(v1::Impedance::EXACT_ZOH);
  EXPECT_EQ(to_object_spec(rough, "o", SceneLimits{}, spec),
            "o.impedance.static_friction: friction needs the VELOCITY law");
  rough.mutable_impedance()->set_law(v1::Impedance::VELOCITY);
  ASSERT_EQ(to_object_spec(rough, "o", SceneLimits{}, spec), "");
  EXPECT_EQ(spec.static_friction, 0.3);
  EXPECT_EQ(spec.dynamic_friction, 0.2);

  v1::Object mesh = object_with(1000.0);
  for (const auto& [x, y] : {std::pair{0.0, 0.0}, {0.01, 0.0}, {0.0, 0.01}, {0.01, 0.01}}) {
    auto* v = mesh.mutable_mesh()->add_vertices();
    v->set_x(x);
    v->set_y(y);
  }
  for (std::uint32_t i : {0u, 1u, 2u, 1u, 3u, 2u}) mesh.mutable_mesh()->add_indices(i);
  ASSERT_EQ(to_object_spec(mesh, "o", SceneLimits{}, spec), "");
  const auto& model = std::get<engine::MeshShapeSpec>(spec.shape).model;
  ASSERT_TRUE(model);
  EXPECT_EQ(model->bvh.triangle_count(), 2u);  // built here, off the loop
  SceneLimits one_triangle;
  one_triangle.max_mesh_triangles = 1;
  EXPECT_EQ(to_object_spec(mesh, "o", one_triangle, spec).rfind("o.mesh.indices: 2 triangles exceed", 0), 0u);
  mesh.mutable_mesh()->add_indices(0);
  EXPECT_EQ(to_object_spec(mesh, "o", SceneLimits{}, spec).rfind("o.mesh.indices: must hold three", 0), 0u);
}

TEST(Validation, NewFieldsNameWhatIsWrong) {
  engine::FieldSpec spec;
  v1::Field spring;
  spring.mutable_spring()->mutable_anchor()->set_kind(v1::Distance::LINE);
  spring.mutable_spring()->set_stiffness(10.0);
  EXPECT_EQ(to_field_spec(spring, "f", SceneLimits{}, spec), "f.spring.anchor.axis: must be non-zero");
  spring.mutable_spring()->mutable_anchor()->mutable_axis()->set_x(1.0);
  ASSERT_EQ(to_field_spec(spring, "f", SceneLimits{}, spec), "");
  EXPECT_TRUE(std::holds_alternative<engine::SpringFieldSpec>(spec.kind));

  v1::Field linear;
  linear.mutable_linear()->set_radius(0.05);
  linear.mutable_linear()->set_fade_width(0.01);
  EXPECT_EQ(to_field_spec(linear, "f", SceneLimits{}, spec).rfind("f.linear.jacobian: must have three rows", 0), 0u);
  for (int i = 0; i < 3; ++i) linear.mutable_linear()->add_jacobian();
  linear.mutable_linear()->mutable_jacobian(1)->set_z(std::numeric_limits<double>::infinity());
  EXPECT_EQ(to_field_spec(linear, "f", SceneLimits{}, spec).rfind("f.linear.jacobian[1].z", 0), 0u);

  v1::Field khatib;
  khatib.mutable_potential()->set_kind(v1::PotentialField::KHATIB);
  khatib.mutable_potential()->set_gain(1.0);
  khatib.mutable_potential()->set_influence_distance(0.01);
  khatib.mutable_potential()->set_min_distance(0.001);
  // The protocol says 2 ... 8 and gives no default: an unset (0) order is refused, naming it.
  EXPECT_EQ(to_field_spec(khatib, "f", SceneLimits{}, spec),
            "f.potential.order: must be an integer in [2, 8], got 0");
  khatib.mutable_potential()->set_order(9);
  EXPECT_EQ(to_field_spec(khatib, "f", SceneLimits{}, spec).rfind("f.potential.order:", 0), 0u);
  khatib.mutable_potential()->set_order(2);
  khatib.mutable_potential()->set_min_distance(0.02);  // must be below the influence distance
  EXPECT_EQ(to_field_spec(khatib, "f", SceneLimits{}, spec).rfind("f.potential.min_distance", 0), 0u);
  khatib.mutable_potential()->set_min_distance(0.001);
  EXPECT_EQ(to_field_spec(khatib, "f", SceneLimits{}, spec), "");
}

TEST(Validation, RefusesAnOrientationWithANanComponentNamingIt) {
  // A NaN component makes the norm NaN, which no "within 1e-3 of 1" comparison refuses: only the
  // finiteness check stops it.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  using Setter = void (v1::Quaternion::*)(double);
  for (const auto& [axis, set] :
       {std::pair<std::string, Setter>{"w", &v1::Quaternion::set_w}, {"x", &v1::Quaternion::set_x},
        {"y", &v1::Quaternion::set_y}, {"z", &v1::Quaternion::set_z}}) {
    v1::Object object = good_wall();
    v1::Quaternion* q = object.mutable_pose()->mutable_orientation();
    q->set_w(1.0);
    (q->*set)(nan);
    const std::string error = error_of(object);
    EXPECT_EQ(error.rfind("object.pose.orientation." + axis + ": must be finite, got ", 0), 0u)
        << axis << ": \"" << error << "\"";
  }
  // Through a whole scene, the path names the object too.
  v1::Scene scene;
  *scene.add_objects() = good_wall();
  scene.mutable_objects(0)->mutable_pose()->mutable_orientation()->set_w(1.0);
  scene.mutable_objects(0)->mutable_pose()->mutable_orientation()->set_y(nan);
  SceneSpecs specs;
  EXPECT_EQ(to_scene_specs(scene, "scene.", SceneLimits{}, specs)
                .rfind("scene.objects[0].pose.orientation.y: must be finite, got ", 0),
            0u);
  EXPECT_TRUE(specs.objects.empty());  // all or nothing
}

v1::Object tangent_plane_with(double tangential_stiffness) {
  v1::Object object = object_with(1000.0);
  v1::TangentPlane* plane = object.mutable_tangent_plane();
  plane->mutable_normal()->set_z(1.0);
  plane->set_tangential_stiffness(tangential_stiffness);
  plane->set_tangential_damping(1.0);
  return object;
}

TEST(Validation, RefusesATangentPlaneStiffnessAboveTheLimit) {
  engine::ObjectSpec spec;
  ASSERT_EQ(to_object_spec(tangent_plane_with(1.0e6), "o", SceneLimits{}, spec), "");  // at the limit
  ASSERT_TRUE(std::holds_alternative<engine::TangentPlaneSpec>(spec.shape));
  EXPECT_EQ(std::get<engine::TangentPlaneSpec>(spec.shape).tangential_stiffness, 1.0e6);
  EXPECT_EQ(to_object_spec(tangent_plane_with(2.0e6), "o", SceneLimits{}, spec),
            "o.tangent_plane.tangential_stiffness: must be finite and in [0, 1e+06], got 2e+06");
  // The bound is the server's limit, not a constant.
  SceneLimits soft;
  soft.max_stiffness = 5000.0;
  EXPECT_EQ(to_object_spec(tangent_plane_with(5000.0), "o", soft, spec), "");
  EXPECT_EQ(to_object_spec(tangent_plane_with(5001.0), "o", soft, spec),
            "o.tangent_plane.tangential_stiffness: must be finite and in [0, 5000], got 5001");
}

TEST(Validation, RefusesACustomOperatorStiffnessAboveTheLimit) {
  v1::OperatorInput input;
  input.set_mode(v1::OperatorInput::FOLLOW_TARGET);
  input.set_grip(v1::OperatorInput::CUSTOM);
  input.set_damping(10.0);
  input.set_mass(1.0);
  engine::HandInput hand;
  input.set_stiffness(1.0e6);  // at the limit
  ASSERT_EQ(to_hand_input(input, "input", SceneLimits{}, hand), "");
  EXPECT_EQ(hand.stiffness, 1.0e6);
  input.set_stiffness(2.0e6);
  EXPECT_EQ(to_hand_input(input, "input", SceneLimits{}, hand),
            "input.stiffness: must be finite and in [0, 1e+06], got 2e+06");
  SceneLimits soft;
  soft.max_stiffness = 800.0;
  input.set_stiffness(800.0);
  EXPECT_EQ(to_hand_input(input, "input", soft, hand), "");
  input.set_stiffness(801.0);
  EXPECT_EQ(to_hand_input(input, "input", soft, hand),
            "input.stiffness: must be finite and in [0, 800], got 801");
}

}  // namespace
}  // namespace haptic::schema
