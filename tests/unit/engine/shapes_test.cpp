// Primitive shapes (signed distance, closest point, normal, bounds, validation), the quaternion
// helpers, and the contact proxy with Coulomb friction.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "engine/scene/contact_proxy.hpp"
#include "engine/scene/shapes.hpp"
#include "support/allocation_counter.hpp"

namespace haptic::engine {
namespace {

constexpr double kPi = std::numbers::pi;

#define EXPECT_VEC_NEAR(a, b, tol)   \
  do {                               \
    const Vec3 va_ = (a);            \
    const Vec3 vb_ = (b);            \
    EXPECT_NEAR(va_.x, vb_.x, tol);  \
    EXPECT_NEAR(va_.y, vb_.y, tol);  \
    EXPECT_NEAR(va_.z, vb_.z, tol);  \
  } while (0)

Vec3 random_vec(std::mt19937_64& rng, double lo, double hi) {
  std::uniform_real_distribution<double> u(lo, hi);
  const double x = u(rng);
  const double y = u(rng);
  const double z = u(rng);
  return {x, y, z};
}

Quat random_rotation(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> angle(-kPi, kPi);
  return quat_from_axis_angle(random_vec(rng, -1.0, 1.0), angle(rng));
}

// A pose used throughout: rotated about a skew axis, off the origin.
const ObjectPose kSkewPose{{0.1, -0.2, 0.3}, quat_from_axis_angle({1.0, 2.0, -0.5}, 0.7)};

// ---------------------------------------------------------------------------------------------
// Quaternions

TEST(Quaternion, AxisAngleFollowsTheRightHandRule) {
  const Quat q = quat_from_axis_angle({0.0, 0.0, 2.0}, kPi / 2);  // axis length is ignored
  EXPECT_TRUE(is_unit(q, 1e-15));
  EXPECT_VEC_NEAR(rotate(q, {1, 0, 0}), (Vec3{0, 1, 0}), 1e-15);
  EXPECT_VEC_NEAR(rotate(q, {0, 1, 0}), (Vec3{-1, 0, 0}), 1e-15);
  EXPECT_VEC_NEAR(rotate_inverse(q, {0, 1, 0}), (Vec3{1, 0, 0}), 1e-15);
  // Degenerate input gives the identity, never NaN.
  const Quat identity{};
  for (const Quat& r : {quat_from_axis_angle({}, 1.0), quat_from_axis_angle({0, 0, 1}, NAN),
                        quat_from_axis_angle({INFINITY, 0, 0}, 1.0)}) {
    EXPECT_EQ(r.w, identity.w);
    EXPECT_EQ(r.x, 0.0);
    EXPECT_EQ(r.y, 0.0);
    EXPECT_EQ(r.z, 0.0);
  }
}

TEST(Quaternion, ProductConjugateAndInverseRoundTrip) {
  std::mt19937_64 rng(7);
  for (int i = 0; i < 200; ++i) {
    const Quat a = random_rotation(rng);
    const Quat b = random_rotation(rng);
    const Vec3 v = random_vec(rng, -1.0, 1.0);
    // R(a b) v = R(a) R(b) v.
    EXPECT_VEC_NEAR(rotate(a * b, v), rotate(a, rotate(b, v)), 1e-14);
    // Rᵀ R v = v, and q* q = identity.
    EXPECT_VEC_NEAR(rotate_inverse(a, rotate(a, v)), v, 1e-14);
    const Quat e = conjugate(a) * a;
    EXPECT_NEAR(e.w, 1.0, 1e-15);
    EXPECT_NEAR(std::fabs(e.x) + std::fabs(e.y) + std::fabs(e.z), 0.0, 1e-15);
    // Poses round-trip through O.
    const ObjectPose X{v, a};
    const Vec3 p_W = b.w * v + Vec3{0.3, 0.0, 0.0};
    EXPECT_VEC_NEAR(to_world(X, to_object(X, p_W)), p_W, 1e-14);
  }
}

TEST(Quaternion, IsUnitRejectsScaledAndNonFiniteAndNormalizedRepairs) {
  EXPECT_TRUE(is_unit(Quat{}));
  EXPECT_TRUE(is_unit(Quat{std::sqrt(0.5), 0.0, std::sqrt(0.5), 0.0}));
  EXPECT_FALSE(is_unit(Quat{1.0 + 1e-5, 0, 0, 0}));
  EXPECT_TRUE(is_unit(Quat{1.0 + 1e-5, 0, 0, 0}, 1e-4));
  EXPECT_FALSE(is_unit(Quat{0, 0, 0, 0}));
  EXPECT_FALSE(is_unit(Quat{NAN, 0, 0, 0}));
  EXPECT_FALSE(is_unit(Quat{1, 0, INFINITY, 0}));
  const Quat n = normalized(Quat{2, 0, 0, 2});
  EXPECT_TRUE(is_unit(n, 1e-15));
  EXPECT_DOUBLE_EQ(n.w, std::sqrt(0.5));
  EXPECT_DOUBLE_EQ(n.z, std::sqrt(0.5));
  const Quat z = normalized(Quat{0, 0, 0, 0});
  EXPECT_EQ(z.w, 1.0);
  EXPECT_EQ(normalized(Quat{NAN, 1, 0, 0}).w, 1.0);
}

// ---------------------------------------------------------------------------------------------
// Queries against hand-computed cases

void expect_query(const ShapeQuery& q, double distance, const Vec3& p_WS, const Vec3& n_W) {
  EXPECT_NEAR(q.signed_distance, distance, 1e-12);
  EXPECT_VEC_NEAR(q.p_WS, p_WS, 1e-12);
  EXPECT_VEC_NEAR(q.n_W, n_W, 1e-12);
}

TEST(Shapes, HalfSpaceDistanceUsesTheNormalisedRotatedNormal) {
  // R = 90° about x maps O's +z to W's −y; normal_O is not unit.
  const ObjectPose X{{1.0, 2.0, 3.0}, quat_from_axis_angle({1, 0, 0}, kPi / 2)};
  const HalfSpaceSpec wall{{0.0, 0.0, 2.0}};
  expect_query(query(wall, X, {1.5, 1.9, 3.0}), 0.1, {1.5, 2.0, 3.0}, {0, -1, 0});
  expect_query(query(wall, X, {0.0, 2.25, -4.0}), -0.25, {0.0, 2.0, -4.0}, {0, -1, 0});
}

TEST(Shapes, SphereDistanceIsRadialInsideAndOutside) {
  const ObjectPose X{{1.0, 0.0, 0.0}, quat_from_axis_angle({0, 1, 0}, 0.3)};
  const SphereSpec ball{0.5};
  expect_query(query(ball, X, {1.0, 0.0, 2.0}), 1.5, {1.0, 0.0, 0.5}, {0, 0, 1});
  expect_query(query(ball, X, {1.3, 0.4, 0.0}), -0.0, {1.3, 0.4, 0.0}, {0.6, 0.8, 0});  // surface
  expect_query(query(ball, X, {0.9, 0.0, 0.0}), -0.4, {0.5, 0.0, 0.0}, {-1, 0, 0});
}

TEST(Shapes, BoxOutsideFaceEdgeAndCornerRegions) {
  const BoxSpec box{{0.1, 0.2, 0.3}};
  const ObjectPose X{};
  expect_query(query(box, X, {0.4, 0.0, 0.0}), 0.3, {0.1, 0.0, 0.0}, {1, 0, 0});    // face
  expect_query(query(box, X, {0.4, 0.6, 0.1}), 0.5, {0.1, 0.2, 0.1}, {0.6, 0.8, 0});  // edge
  expect_query(query(box, X, {-0.3, -0.4, 0.4}), 0.3, {-0.1, -0.2, 0.3},
               {-2.0 / 3, -2.0 / 3, 1.0 / 3});  // corner: offset (−0.2, −0.2, 0.1)
}

TEST(Shapes, BoxInsideTakesTheNearestFace) {
  const BoxSpec box{{0.1, 0.2, 0.3}};
  const ObjectPose X{};
  // Depths x 0.08, y 0.1, z 0.05: the +z face.
  expect_query(query(box, X, {0.02, 0.1, 0.25}), -0.05, {0.02, 0.1, 0.3}, {0, 0, 1});
  // Depths x 0.1, y 0.05, z 0.3: the −y face.
  expect_query(query(box, X, {0.0, -0.15, 0.0}), -0.05, {0.0, -0.2, 0.0}, {0, -1, 0});
}

TEST(Shapes, BoxInsideTiesGoToTheLowestAxisAndThePlusFace) {
  // Binary-exact values so the ties are exact.
  const BoxSpec cube{{0.5, 0.5, 0.5}};
  const ObjectPose X{};
  expect_query(query(cube, X, {0, 0, 0}), -0.5, {0.5, 0, 0}, {1, 0, 0});            // centre
  expect_query(query(cube, X, {0.25, 0.25, 0}), -0.25, {0.5, 0.25, 0}, {1, 0, 0});  // x = y
  expect_query(query(cube, X, {0, -0.25, -0.25}), -0.25, {0, -0.5, -0.25}, {0, -1, 0});  // y = z
  expect_query(query(cube, X, {-0.5, -0.5, -0.5}), 0.0, {-0.5, -0.5, -0.5}, {-1, 0, 0});  // corner
  // The same query twice gives the same answer (no hidden state).
  const ShapeQuery a = query(cube, X, {0.25, 0.25, 0.25});
  const ShapeQuery b = query(cube, X, {0.25, 0.25, 0.25});
  EXPECT_EQ(a.n_W, b.n_W);
  EXPECT_EQ(a.n_W, (Vec3{1, 0, 0}));
}

TEST(Shapes, RotatedBoxVerticalEdgeAndFace) {
  // A unit cube (h = 1) turned 45° about z: its vertical edge at O's (1, −1) lies on W's x axis
  // at x = √2, so the point (2, 0, 0) is 2 − √2 from that edge along +x.
  const BoxSpec cube{{1.0, 1.0, 1.0}};
  const ObjectPose X{{}, quat_from_axis_angle({0, 0, 1}, kPi / 4)};
  expect_query(query(cube, X, {2.0, 0.0, 0.5}), 2.0 - std::sqrt(2.0),
               {std::sqrt(2.0), 0.0, 0.5}, {1, 0, 0});
  // A box turned 90° about z and moved to (1, 0, 0): O's +x face faces W's +y.
  const BoxSpec box{{0.1, 0.2, 0.3}};
  const ObjectPose Y{{1.0, 0.0, 0.0}, quat_from_axis_angle({0, 0, 1}, kPi / 2)};
  expect_query(query(box, Y, {1.0, 0.5, 0.0}), 0.4, {1.0, 0.1, 0.0}, {0, 1, 0});
  expect_query(query(box, Y, {1.0, 0.05, 0.0}), -0.05, {1.0, 0.1, 0.0}, {0, 1, 0});
}

TEST(Shapes, CapsuleSideCapAndInside) {
  const CapsuleSpec capsule{0.1, 0.2};
  const ObjectPose X{};
  expect_query(query(capsule, X, {0.3, 0.0, 0.1}), 0.2, {0.1, 0.0, 0.1}, {1, 0, 0});    // side
  expect_query(query(capsule, X, {0.0, 0.0, 0.5}), 0.2, {0.0, 0.0, 0.3}, {0, 0, 1});    // cap
  expect_query(query(capsule, X, {0.3, 0.0, -0.6}), 0.4, {0.06, 0.0, -0.28}, {0.6, 0, -0.8});
  expect_query(query(capsule, X, {0.0, 0.05, -0.1}), -0.05, {0.0, 0.1, -0.1}, {0, 1, 0});
  // Turned so that O's z axis is W's x axis (90° about y).
  const ObjectPose Y{{0.0, 1.0, 0.0}, quat_from_axis_angle({0, 1, 0}, kPi / 2)};
  expect_query(query(capsule, Y, {0.5, 1.0, 0.0}), 0.2, {0.3, 1.0, 0.0}, {1, 0, 0});
  expect_query(query(capsule, Y, {0.1, 1.0, 0.4}), 0.3, {0.1, 1.0, 0.1}, {0, 0, 1});
}

TEST(Shapes, VariantQueryMatchesTheTypedQuery) {
  const std::vector<PrimitiveShape> shapes{HalfSpaceSpec{{0, 1, 1}}, SphereSpec{0.2},
                                           BoxSpec{{0.1, 0.2, 0.3}}, CapsuleSpec{0.05, 0.1}};
  const Vec3 p{0.13, 0.07, -0.11};
  for (const PrimitiveShape& shape : shapes) {
    const ShapeQuery a = query(shape, kSkewPose, p);
    const ShapeQuery b =
        std::visit([&](const auto& s) { return query(s, kSkewPose, p); }, shape);
    EXPECT_EQ(a.signed_distance, b.signed_distance);
    EXPECT_EQ(a.p_WS, b.p_WS);
    EXPECT_EQ(a.n_W, b.n_W);
  }
}

// ---------------------------------------------------------------------------------------------
// Properties over random points

const std::vector<PrimitiveShape>& all_shapes() {
  static const std::vector<PrimitiveShape> shapes{
      HalfSpaceSpec{{0.3, -1.0, 0.5}}, SphereSpec{0.1}, BoxSpec{{0.05, 0.1, 0.15}},
      CapsuleSpec{0.04, 0.08}, CapsuleSpec{0.06, 0.0}};
  return shapes;
}

TEST(Shapes, SurfacePointIsOnTheSurfaceAndConsistentWithDistanceAndNormal) {
  std::mt19937_64 rng(11);
  for (const PrimitiveShape& shape : all_shapes()) {
    for (int i = 0; i < 500; ++i) {
      const Vec3 p = kSkewPose.p_WO + random_vec(rng, -0.3, 0.3);
      const ShapeQuery q = query(shape, kSkewPose, p);
      EXPECT_NEAR(norm(q.n_W), 1.0, 1e-12);
      EXPECT_NEAR(query(shape, kSkewPose, q.p_WS).signed_distance, 0.0, 1e-12);
      // Q = S + d n: the query point lies on the normal line through S.
      EXPECT_VEC_NEAR(q.p_WS + q.signed_distance * q.n_W, p, 1e-12);
    }
  }
}

// ∇d = n̂ away from the creases where d is not differentiable (a box's inner medial planes, a
// sphere's centre, a capsule's axis). Central difference error is O(h²).
TEST(Shapes, DistanceGradientByCentralDifferencesEqualsTheNormal) {
  std::mt19937_64 rng(12);
  const double h = 1e-5;
  for (const PrimitiveShape& shape : all_shapes()) {
    int tested = 0;
    const int samples = 400;
    for (int i = 0; i < samples; ++i) {
      const Vec3 p = kSkewPose.p_WO + random_vec(rng, -0.3, 0.3);
      const ShapeQuery q = query(shape, kSkewPose, p);
      Vec3 gradient;
      bool crease = false;
      double* g[3] = {&gradient.x, &gradient.y, &gradient.z};
      for (int axis = 0; axis < 3; ++axis) {
        Vec3 e;
        (axis == 0 ? e.x : axis == 1 ? e.y : e.z) = h;
        const ShapeQuery plus = query(shape, kSkewPose, p + e);
        const ShapeQuery minus = query(shape, kSkewPose, p - e);
        // Smooth regions turn the normal by O(h · curvature) ≈ 1e-4 here; a crease by ≥ 45°.
        if (norm(plus.n_W - q.n_W) > 1e-2 || norm(minus.n_W - q.n_W) > 1e-2) crease = true;
        *g[axis] = (plus.signed_distance - minus.signed_distance) / (2 * h);
      }
      if (crease) continue;
      ++tested;
      EXPECT_VEC_NEAR(gradient, q.n_W, 1e-7);
    }
    EXPECT_GT(tested, samples * 9 / 10);  // the crease filter must not empty the test
  }
}

TEST(Shapes, SphereGradientErrorFallsFourfoldWhenTheStepHalves) {
  // d = |p| − r has a non-zero third derivative, so the central-difference error ∝ h².
  const SphereSpec ball{0.1};
  const Vec3 p{0.12, 0.05, -0.07};
  const Vec3 n = query(ball, ObjectPose{}, p).n_W;
  auto error = [&](double h) {
    const double dx = (query(ball, ObjectPose{}, p + Vec3{h, 0, 0}).signed_distance -
                       query(ball, ObjectPose{}, p - Vec3{h, 0, 0}).signed_distance) /
                      (2 * h);
    return std::fabs(dx - n.x);
  };
  const double ratio = error(2e-3) / error(1e-3);
  EXPECT_NEAR(ratio, 4.0, 0.05);
}

TEST(Shapes, DegeneratePointsGiveFixedFiniteNormals) {
  const ObjectPose X = kSkewPose;
  // Sphere centre: O's +z.
  expect_query(query(SphereSpec{0.1}, X, X.p_WO), -0.1, to_world(X, {0, 0, 0.1}),
               rotate(X.R_WO, {0, 0, 1}));
  // Capsule axis, including its end points: O's +x. (In O: a point sent through W and back
  // picks up rounding of ~1e-17 m off the axis, which then decides the direction.)
  const CapsuleSpec capsule{0.05, 0.1};
  for (double z : {-0.1, -0.03, 0.0, 0.1}) {
    const LocalShapeQuery q = query_local(capsule, {0, 0, z});
    EXPECT_EQ(q.signed_distance, -0.05);
    EXPECT_EQ(q.p_OS, (Vec3{0.05, 0, z}));
    EXPECT_EQ(q.n_O, (Vec3{1, 0, 0}));
  }
  expect_query(query(capsule, X, X.p_WO), -0.05, to_world(X, {0.05, 0, 0}),
               rotate(X.R_WO, {1, 0, 0}));
  // Box centre: the + face of the nearest axis (here x, the smallest half extent).
  expect_query(query(BoxSpec{{0.1, 0.2, 0.3}}, X, X.p_WO), -0.1, to_world(X, {0.1, 0, 0}),
               rotate(X.R_WO, {1, 0, 0}));
  // Tiny offsets from the centre, down to the smallest subnormal: still a unit normal.
  for (double tiny : {1e-140, 1e-155, 1e-160, 1e-170, 1e-300, 5e-324}) {
    for (const Vec3& p : {Vec3{tiny, 0, 0}, Vec3{0, tiny, tiny}, Vec3{-tiny, tiny, -tiny}}) {
      const LocalShapeQuery s = query_local(SphereSpec{0.1}, p);
      const LocalShapeQuery c = query_local(capsule, p);
      EXPECT_NEAR(norm(s.n_O), 1.0, 1e-15) << tiny;
      EXPECT_NEAR(norm(c.n_O), 1.0, 1e-15) << tiny;
      EXPECT_TRUE(is_finite(s.p_OS) && is_finite(c.p_OS));
      // Just outside a box face by a subnormal amount.
      const LocalShapeQuery b = query_local(BoxSpec{{0.1, 0.1, 0.1}}, Vec3{0.1, 0, 0} + p);
      EXPECT_NEAR(norm(b.n_O), 1.0, 1e-15) << tiny;
      EXPECT_TRUE(std::isfinite(b.signed_distance));
    }
  }
}

TEST(Shapes, BoundsContainRandomSurfacePointsAndAreTight) {
  std::mt19937_64 rng(13);
  for (int trial = 0; trial < 20; ++trial) {
    const ObjectPose X{random_vec(rng, -1, 1), random_rotation(rng)};
    for (const PrimitiveShape& shape : all_shapes()) {
      const std::optional<ShapeBounds> b = bounds(shape, X);
      if (std::holds_alternative<HalfSpaceSpec>(shape)) {
        EXPECT_FALSE(b.has_value());  // unbounded
        continue;
      }
      ASSERT_TRUE(b.has_value());
      Vec3 hi{-INFINITY, -INFINITY, -INFINITY};
      for (int i = 0; i < 300; ++i) {
        const Vec3 s = query(shape, X, X.p_WO + random_vec(rng, -0.5, 0.5)).p_WS;
        EXPECT_TRUE(contains(*b, s, 1e-12));
        hi = {std::max(hi.x, s.x), std::max(hi.y, s.y), std::max(hi.z, s.z)};
      }
      // Not grossly loose: random surface samples reach within 20% of the extent on each side.
      const Vec3 extent = b->max_W - X.p_WO;
      EXPECT_GT(hi.x - X.p_WO.x, 0.8 * extent.x);
      EXPECT_GT(hi.y - X.p_WO.y, 0.8 * extent.y);
      EXPECT_GT(hi.z - X.p_WO.z, 0.8 * extent.z);
    }
    // Exactly tight for a box: the maximum over its 8 corners is the upper bound.
    const BoxSpec box{{0.05, 0.1, 0.15}};
    const ShapeBounds bb = bounds(box, X);
    Vec3 corner_max{-INFINITY, -INFINITY, -INFINITY};
    for (double sx : {-1.0, 1.0}) {
      for (double sy : {-1.0, 1.0}) {
        for (double sz : {-1.0, 1.0}) {
          const Vec3 c = to_world(X, {sx * 0.05, sy * 0.1, sz * 0.15});
          corner_max = {std::max(corner_max.x, c.x), std::max(corner_max.y, c.y),
                        std::max(corner_max.z, c.z)};
        }
      }
    }
    EXPECT_VEC_NEAR(bb.max_W, corner_max, 1e-12);
  }
  // Hand case: a capsule along W's x (r 0.1, half length 0.2) at (1, 2, 3).
  const ShapeBounds c =
      bounds(CapsuleSpec{0.1, 0.2}, {{1, 2, 3}, quat_from_axis_angle({0, 1, 0}, kPi / 2)});
  EXPECT_VEC_NEAR(c.min_W, (Vec3{0.7, 1.9, 2.9}), 1e-12);
  EXPECT_VEC_NEAR(c.max_W, (Vec3{1.3, 2.1, 3.1}), 1e-12);
}

TEST(Shapes, ValidationNamesTheBadFieldAndValue) {
  EXPECT_EQ(validate(BoxSpec{{0.1, 0.2, 0.3}}), "");
  EXPECT_EQ(validate(BoxSpec{{0.1, 0.0, 0.3}}), "half_extents.y: must be finite and > 0, got 0");
  EXPECT_EQ(validate(BoxSpec{{0.1, 0.2, NAN}}), "half_extents.z: must be finite and > 0, got nan");
  EXPECT_EQ(validate(BoxSpec{{-1.0, 0.2, 0.3}}), "half_extents.x: must be finite and > 0, got -1");
  EXPECT_EQ(validate(CapsuleSpec{0.1, 0.0}), "");
  EXPECT_EQ(validate(CapsuleSpec{0.0, 0.1}), "radius: must be finite and > 0, got 0");
  EXPECT_EQ(validate(CapsuleSpec{0.1, -0.5}), "half_length: must be finite and >= 0, got -0.5");
  EXPECT_EQ(validate(CapsuleSpec{0.1, INFINITY}), "half_length: must be finite and >= 0, got inf");
  EXPECT_EQ(validate(SphereSpec{0.0}), "radius: must be finite and > 0, got 0");
  EXPECT_EQ(validate(HalfSpaceSpec{{0, 0, 0}}),
            "normal_O: must be non-zero with a finite length, got (0, 0, 0)");
  EXPECT_EQ(validate(HalfSpaceSpec{{0, NAN, 1}}), "normal_O.y: must be finite, got nan");
  EXPECT_EQ(validate(PrimitiveShape{BoxSpec{{1, 1, 0}}}),
            "half_extents.z: must be finite and > 0, got 0");
  EXPECT_EQ(validate(ObjectPose{}), "");
  EXPECT_EQ(validate(ObjectPose{{0, INFINITY, 0}, {}}), "p_WO.y: must be finite, got inf");
  const std::string quat = validate(ObjectPose{{}, Quat{1, 0, 0, 1}});
  EXPECT_EQ(quat.rfind("R_WO: must be a finite unit quaternion", 0), 0u) << quat;
  EXPECT_NE(validate(ObjectPose{{}, Quat{NAN, 0, 0, 0}}), "");
  EXPECT_EQ(validate(ContactMaterial{1000, 1, 0.5, 0.3}), "");
  EXPECT_EQ(validate(ContactMaterial{-1, 1, 0.5, 0.3}),
            "stiffness: must be finite and >= 0, got -1");
  EXPECT_EQ(validate(ContactMaterial{1000, 1, 0.4, 0.6}),
            "dynamic_friction: must be finite, >= 0 and <= static_friction (0.4), got 0.6");
  EXPECT_EQ(validate(ContactMaterial{1000, NAN, 0.5, 0.3}),
            "damping: must be finite and >= 0, got nan");
}

// ---------------------------------------------------------------------------------------------
// Contact: penalty law and friction proxy

TEST(Contact, PenaltyIsStiffnessTimesDepthMinusNormalDampingClampedAtZero) {
  const ContactMaterial m{1000.0, 2.0, 0.0, 0.0};
  const HalfSpaceSpec floor{{0, 0, 1}};
  const ObjectPose X{};
  const ContactForce f = penalty_contact(floor, X, m, {0.3, 0.1, -0.003}, {5.0, 0.0, -0.25});
  EXPECT_TRUE(f.in_contact);
  EXPECT_NEAR(f.penetration, 0.003, 1e-15);
  EXPECT_NEAR(f.F_T_W.z, 1000.0 * 0.003 + 2.0 * 0.25, 1e-12);  // tangential velocity ignored
  EXPECT_EQ(f.F_T_W.x, 0.0);
  EXPECT_EQ(f.F_T_W.y, 0.0);
  EXPECT_VEC_NEAR(f.p_WP, (Vec3{0.3, 0.1, 0.0}), 1e-15);
  // Leaving fast: the damper would pull, so the force is zero, not negative.
  EXPECT_EQ(penalty_contact(floor, X, m, {0, 0, -0.003}, {0, 0, 2.0}).F_T_W.z, 0.0);
  // Outside: nothing, proxy at the tool.
  const ContactForce out = penalty_contact(floor, X, m, {0, 0, 0.01}, {});
  EXPECT_FALSE(out.in_contact);
  EXPECT_EQ(out.F_T_W, Vec3{});
  EXPECT_EQ(out.p_WP, (Vec3{0, 0, 0.01}));
}

TEST(Contact, FrictionlessProxyEqualsThePenaltyLawBitForBit) {
  std::mt19937_64 rng(21);
  const ContactMaterial m{800.0, 1.5, 0.0, 0.0};
  for (const PrimitiveShape& shape : all_shapes()) {
    ContactProxy proxy;
    Vec3 p = kSkewPose.p_WO;
    ObjectPose X = kSkewPose;
    for (int tick = 0; tick < 2000; ++tick) {
      p += random_vec(rng, -0.004, 0.004);  // a random walk in and out of the shape
      X.p_WO += random_vec(rng, -0.001, 0.001);  // the object drifts
      const Vec3 v = random_vec(rng, -0.5, 0.5);
      const ContactForce a = proxy.update(shape, X, m, p, v);
      const ContactForce b = penalty_contact(shape, X, m, p, v);
      ASSERT_EQ(a.F_T_W, b.F_T_W) << tick;
      ASSERT_EQ(a.p_WP, b.p_WP) << tick;
      ASSERT_EQ(a.in_contact, b.in_contact);
      EXPECT_FALSE(a.sliding);
    }
  }
}

// A tool pressed 2 mm into the top of a box (K = 1000 N/m: F_n = 2 N) and dragged along +x:
// Coulomb friction (Salisbury et al. 1995 §4) sticks with F_t = −K x until |F_t| = μ_s F_n, then
// slides with |F_t| = μ_d F_n.
TEST(Contact, DraggedToolSticksUntilStaticLimitThenSlidesAtDynamicLimit) {
  const double K = 1000.0;
  const double mu_s = 0.5;
  const double mu_d = 0.3;
  const ContactMaterial m{K, 0.0, mu_s, mu_d};
  const BoxSpec box{{0.05, 0.05, 0.05}};
  const ObjectPose X{};
  const double z = 0.048;  // 2 mm deep
  const double Fn = K * (0.05 - z);
  ContactProxy proxy;
  ContactForce f = proxy.update(box, X, m, {0.0, 0.0, z}, {});
  const Vec3 proxy_start = f.p_WP;
  EXPECT_VEC_NEAR(proxy_start, (Vec3{0, 0, 0.05}), 1e-15);
  const double step = 0.03e-3;  // m per tick; breakaway (x = μ_s F_n / K = 1 mm) falls between
  bool broke_away = false;
  for (int tick = 1; tick <= 100; ++tick) {
    const double x = tick * step;
    f = proxy.update(box, X, m, {x, 0.0, z}, {});
    ASSERT_TRUE(f.in_contact);
    EXPECT_NEAR(f.F_T_W.z, Fn, 1e-12);
    const double Ft = std::hypot(f.F_T_W.x, f.F_T_W.y);
    if (x < mu_s * Fn / K) {
      EXPECT_FALSE(f.sliding) << x;
      EXPECT_EQ(f.p_WP, proxy_start) << x;        // the proxy does not move
      EXPECT_NEAR(f.F_T_W.x, -K * x, 1e-9) << x;  // linear in the drag distance
    } else {
      broke_away = true;
      EXPECT_TRUE(f.sliding) << x;
      EXPECT_NEAR(Ft, mu_d * Fn, 1e-9) << x;
      EXPECT_LT(f.F_T_W.x, 0.0);                  // opposes the motion
      EXPECT_NEAR(f.p_WP.x, x - mu_d * Fn / K, 1e-12);  // trails the tool
      EXPECT_NEAR(f.p_WP.z, 0.05, 1e-15);         // stays on the face
    }
  }
  EXPECT_TRUE(broke_away);
  // Stopping and easing back inside the dynamic cone sticks again; from there it takes the
  // static limit, not the dynamic one, to break away.
  const double x_end = 100 * step;
  const Vec3 held = f.p_WP;
  f = proxy.update(box, X, m, {x_end - 0.1e-3, 0.0, z}, {});
  EXPECT_FALSE(f.sliding);
  EXPECT_EQ(f.p_WP, held);
  f = proxy.update(box, X, m, {held.x + 0.45e-3, 0.0, z}, {});  // |F_t| = 0.45 N < μ_s F_n
  EXPECT_FALSE(f.sliding);
  EXPECT_NEAR(f.F_T_W.x, -0.45, 1e-9);
  f = proxy.update(box, X, m, {held.x + 1.05e-3, 0.0, z}, {});  // 1.05 N > μ_s F_n
  EXPECT_TRUE(f.sliding);
  EXPECT_NEAR(f.F_T_W.x, -mu_d * Fn, 1e-9);
}

TEST(Contact, SlidingDirectionFollowsTheDragInTheTangentPlane) {
  // A diagonal drag on a rotated box face: the friction force opposes the drag direction.
  const ContactMaterial m{500.0, 0.0, 0.6, 0.4};
  const BoxSpec box{{0.1, 0.1, 0.1}};
  const ObjectPose X{{0.2, 0.0, 0.0}, quat_from_axis_angle({1, 1, 0}, 0.4)};
  const Vec3 start_O{0.0, 0.0, 0.097};  // 3 mm deep under O's +z face
  ContactProxy proxy;
  proxy.update(box, X, m, to_world(X, start_O), {});
  ContactForce f;
  for (int tick = 1; tick <= 200; ++tick) {
    f = proxy.update(box, X, m, to_world(X, start_O + tick * Vec3{3e-5, 4e-5, 0}), {});
  }
  ASSERT_TRUE(f.sliding);
  const Vec3 F_O = rotate_inverse(X.R_WO, f.F_T_W);
  EXPECT_NEAR(F_O.z, 500.0 * 0.003, 1e-9);
  EXPECT_NEAR(F_O.x, -0.4 * 1.5 * 0.6, 1e-9);  // μ_d F_n along −(0.6, 0.8)
  EXPECT_NEAR(F_O.y, -0.4 * 1.5 * 0.8, 1e-9);
}

TEST(Contact, MovingBoxCarriesAStickingProxy) {
  const ContactMaterial m{1000.0, 0.0, 0.8, 0.5};
  const BoxSpec box{{0.05, 0.05, 0.05}};
  ObjectPose X{{0.3, 0.1, 0.0}, {}};
  const Vec3 tool_O{0.0005, 0.0, 0.048};  // 2 mm deep, 0.5 mm off the first contact point
  ContactProxy proxy;
  proxy.update(box, X, m, to_world(X, {0.0, 0.0, 0.048}), {});
  const Vec3 p_OP = proxy.p_OP();
  ContactForce f = proxy.update(box, X, m, to_world(X, tool_O), {});
  EXPECT_FALSE(f.sliding);
  // The object translates and turns; the tool moves with it (fixed in O).
  for (int tick = 1; tick <= 300; ++tick) {
    X.p_WO += Vec3{0.001, -0.0005, 0.0002};
    X.R_WO = quat_from_axis_angle({0.2, 0.1, 1.0}, 0.004 * tick);
    f = proxy.update(box, X, m, to_world(X, tool_O), {});
    ASSERT_FALSE(f.sliding) << tick;
    EXPECT_EQ(proxy.p_OP(), p_OP);  // fixed in O
    EXPECT_VEC_NEAR(f.p_WP, to_world(X, p_OP), 1e-15);
    // The force, seen from O, is the same stick force at every tick.
    EXPECT_VEC_NEAR(rotate_inverse(X.R_WO, f.F_T_W), (Vec3{-0.5, 0.0, 2.0}), 1e-9);
  }
  // Now the tool holds still while the box slides on under it: friction drags the tool along
  // +x (force +x rising with the box's travel) until the static limit, then slides.
  X.R_WO = {};
  const Vec3 tool_W = to_world(X, tool_O);
  const Vec3 p_WP_before = to_world(X, p_OP);
  double last = -INFINITY;
  bool slid = false;
  for (int tick = 1; tick <= 80; ++tick) {
    X.p_WO += Vec3{0.0001, 0.0, 0.0};
    f = proxy.update(box, X, m, tool_W, {});
    if (!f.sliding) {
      EXPECT_NEAR(f.p_WP.x, p_WP_before.x + tick * 0.0001, 1e-12);  // carried with the box
      EXPECT_GT(f.F_T_W.x, last);
      last = f.F_T_W.x;
    } else {
      slid = true;
      EXPECT_NEAR(f.F_T_W.x, 0.5 * 2.0, 1e-9);
    }
  }
  EXPECT_TRUE(slid);
  EXPECT_NEAR(last, 0.8 * 2.0, 0.1 + 1e-9);  // broke away within one step of μ_s F_n
}

TEST(Contact, LeavingResetsTheProxyAndANewContactStartsAtTheClosestPoint) {
  const ContactMaterial m{1000.0, 0.0, 1.0, 0.8};
  const SphereSpec ball{0.1};
  const ObjectPose X{};
  ContactProxy proxy;
  proxy.update(ball, X, m, {0, 0, 0.095}, {});
  ContactForce f = proxy.update(ball, X, m, {0.002, 0, 0.095}, {});
  EXPECT_TRUE(proxy.in_contact());
  EXPECT_GT(norm(f.F_T_W - f.penetration * 1000.0 * f.n_W), 1.0);  // a tangential force
  f = proxy.update(ball, X, m, {0, 0, 0.2}, {});
  EXPECT_FALSE(f.in_contact);
  EXPECT_FALSE(proxy.in_contact());
  EXPECT_EQ(f.F_T_W, Vec3{});
  EXPECT_EQ(f.p_WP, (Vec3{0, 0, 0.2}));
  // Re-entering elsewhere: pure normal force, proxy at the closest point.
  f = proxy.update(ball, X, m, {0.095, 0, 0}, {});
  EXPECT_VEC_NEAR(f.p_WP, (Vec3{0.1, 0, 0}), 1e-15);
  EXPECT_VEC_NEAR(f.F_T_W, (Vec3{5.0, 0, 0}), 1e-12);
}

TEST(Contact, ProxyStaysOnACurvedSurfaceWhileSliding) {
  const ContactMaterial m{1000.0, 0.0, 0.3, 0.2};
  const CapsuleSpec capsule{0.05, 0.1};
  const ObjectPose X = kSkewPose;
  ContactProxy proxy;
  int sliding_ticks = 0;
  for (int tick = 0; tick < 400; ++tick) {
    // Round the cylinder, 3 mm deep, while moving along its axis.
    const double a = 0.01 * tick;
    const Vec3 tool_O{0.047 * std::cos(a), 0.047 * std::sin(a), -0.1 + 0.0004 * tick};
    const ContactForce f = proxy.update(capsule, X, m, to_world(X, tool_O), {});
    ASSERT_TRUE(f.in_contact);
    sliding_ticks += f.sliding ? 1 : 0;
    EXPECT_NEAR(query(capsule, X, f.p_WP).signed_distance, 0.0, 1e-12);
    EXPECT_TRUE(is_finite(f.F_T_W));
  }
  EXPECT_GT(sliding_ticks, 300);
}

TEST(Contact, UpdateAndQueriesDoNotAllocate) {
  const ContactMaterial m{1000.0, 1.0, 0.5, 0.3};
  std::vector<ContactProxy> proxies(all_shapes().size());
  std::mt19937_64 rng(31);
  std::vector<Vec3> points;
  for (int i = 0; i < 256; ++i) points.push_back(kSkewPose.p_WO + random_vec(rng, -0.2, 0.2));
  double sum = 0.0;
  test::reset_allocations();
  {
    test::CountAllocations counting;
    for (const Vec3& p : points) {
      for (std::size_t s = 0; s < all_shapes().size(); ++s) {
        const PrimitiveShape& shape = all_shapes()[s];
        sum += proxies[s].update(shape, kSkewPose, m, p, {0.1, 0, 0}).F_T_W.z;
        sum += penalty_contact(shape, kSkewPose, m, p, {}).F_T_W.x;
        sum += query(shape, kSkewPose, p).signed_distance;
        if (const auto b = bounds(shape, kSkewPose)) sum += b->max_W.x;
      }
    }
  }
  EXPECT_EQ(test::allocations(), 0u);
  EXPECT_TRUE(std::isfinite(sum));
}

}  // namespace
}  // namespace haptic::engine
