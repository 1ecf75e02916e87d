// The sphere stage's broad phase: the grid lists every sphere a point can be inside, and a scene
// evaluated through it gives the same forces, proxy points, counts, ramp flags and energies, bit
// for bit, as the same scene looking at every sphere every tick.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "engine/scene/compiled_scene.hpp"
#include "engine/scene/sphere_grid.hpp"

namespace haptic::engine {
namespace {

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }
bool same_bits(const Vec3& a, const Vec3& b) {
  return same_bits(a.x, b.x) && same_bits(a.y, b.y) && same_bits(a.z, b.z);
}

TEST(SphereGrid, ListsEverySphereAPointIsInsideInAscendingOrder) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> position(-0.05, 0.05), radius(0.001, 0.02);
  std::vector<Vec3> centers;
  std::vector<double> radii;
  for (int i = 0; i < 500; ++i) {
    centers.push_back({position(random), position(random), position(random)});
    radii.push_back(i == 0 ? 0.04 : radius(random));  // one large sphere across many cells
  }
  const SphereGrid grid(centers, radii);
  ASSERT_FALSE(grid.empty());
  std::size_t inside = 0, listed = 0;
  for (int k = 0; k < 20000; ++k) {
    const Vec3 p{position(random), position(random), position(random)};
    const std::span<const std::uint32_t> cell = grid.candidates(p);
    for (std::size_t j = 1; j < cell.size(); ++j) ASSERT_LT(cell[j - 1], cell[j]);
    listed += cell.size();
    for (std::uint32_t i = 0; i < centers.size(); ++i) {
      if (norm(p - centers[i]) < radii[i]) {
        ++inside;
        EXPECT_TRUE(std::binary_search(cell.begin(), cell.end(), i)) << "sphere " << i << " at " << k;
      }
    }
  }
  std::printf("  %zu spheres, cell %.1f mm, %zu entries; a point's cell lists %.1f on average "
              "(inside %.2f)\n",
              centers.size(), 1e3 * grid.cell_size(), grid.entries(),
              static_cast<double>(listed) / 20000.0, static_cast<double>(inside) / 20000.0);
  EXPECT_GT(inside, 1000u);
  EXPECT_LT(static_cast<double>(listed) / 20000.0, 0.1 * centers.size());  // a small part of them
  EXPECT_TRUE(grid.candidates({1.0, 0.0, 0.0}).empty());  // outside every box
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(grid.candidates({nan, 0.0, 0.0}).empty());
  EXPECT_TRUE(SphereGrid().candidates({0.0, 0.0, 0.0}).empty());
}

/// 300 spheres in a 10 cm cube, some of them appearing, removed or replaced during the run, owned
/// by three sessions, beside a wall and a spring (the other stages), for two tools.
SceneDescription random_spheres() {
  std::mt19937 random(11);
  std::uniform_real_distribution<double> position(-0.05, 0.05), radius(0.003, 0.012),
      stiffness(200.0, 2000.0), damping(0.0, 2.0);
  SceneDescription d;
  for (std::uint64_t i = 0; i < 300; ++i) {
    ObjectSpec spec;
    spec.p_WO = {position(random), position(random), position(random)};
    spec.stiffness = stiffness(random);
    spec.damping = damping(random);
    spec.shape = SphereSpec{radius(random)};
    ItemMeta meta;
    meta.session_id = 1 + i % 3;
    meta.id = 10 + i;
    if (i % 17 == 0) meta.fade_begin_tick = 200 + static_cast<std::int64_t>(i) * 5;  // removed
    if (i % 23 == 0) meta.ramps.appear_tick = 100 + static_cast<std::int64_t>(i) * 3;  // added
    if (i % 29 == 0) meta.ramps.superseded_at[0] = 300 + static_cast<std::int64_t>(i);  // replaced
    d.objects.push_back({meta, spec});
  }
  ObjectSpec floor;
  floor.p_WO = {0.0, 0.0, -0.045};
  floor.stiffness = 1000.0;
  floor.damping = 1.0;
  floor.shape = HalfSpaceSpec{{0.0, 0.0, 1.0}};
  d.objects.push_back({{1, 5, kNeverTick, {}}, floor});
  d.fields.push_back({{2, 6, kNeverTick, {}}, FieldSpec{SpringToPointSpec{{0.0, 0.0, 0.0}, 5.0, 0.1, 0.0}}});
  return d;
}

/// A tool wandering through the cube: a Lissajous curve per port; port 1's also jumps 4 cm every
/// 97 ticks (a tool that leaves a sphere and its cell within one tick, so the sphere is looked at
/// again only because it was touched the tick before). Units: m, m/s.
void tool_at(std::uint32_t port, std::int64_t tick, Vec3& p, Vec3& v) {
  const double t = 1e-3 * static_cast<double>(tick);
  const double a = 0.045, w[3] = {2.1 + port, 3.3, 4.7 - port};
  p = {a * std::sin(w[0] * t), a * std::sin(w[1] * t + 0.5), a * std::sin(w[2] * t + 1.0 + port)};
  v = {a * w[0] * std::cos(w[0] * t), a * w[1] * std::cos(w[1] * t + 0.5),
       a * w[2] * std::cos(w[2] * t + 1.0 + port)};
  if (port == 1 && (tick / 97) % 2 == 1) p += Vec3{0.04, -0.03, 0.02};
}

TEST(SphereGrid, ASceneThroughTheGridGivesWhatLookingAtEverySphereGivesBitForBit) {
  constexpr std::uint32_t kPorts = 2;
  const SceneDescription d = random_spheres();
  CompiledScene grid = compile_scene(d, 50, 1, 1e-3, 0.0, kPorts);
  CompiledScene every = compile_scene(d, 50, 1, 1e-3, 0.0, kPorts);
  drop_sphere_grid(every);
  ASSERT_NE(grid.stages & kStageSphereGrid, 0u);
  ASSERT_EQ(every.stages & kStageSphereGrid, 0u);
  ASSERT_NE(every.stages & kStageSpheres, 0u);
  std::size_t contacts = 0, ramping = 0;
  for (std::int64_t tick = 1; tick <= 5000; ++tick) {
    for (std::uint32_t port = 0; port < kPorts; ++port) {
      Vec3 p, v;
      tool_at(port, tick, p, v);
      const SceneForce a = evaluate_scene_port(grid, port, p, v, tick);
      const SceneForce b = evaluate_scene_port(every, port, p, v, tick);
      ASSERT_TRUE(same_bits(a.F_T_W, b.F_T_W)) << "tick " << tick << " port " << port;
      ASSERT_TRUE(same_bits(a.F_fields_W, b.F_fields_W)) << "tick " << tick;
      ASSERT_TRUE(same_bits(a.p_WP, b.p_WP)) << "tick " << tick << " port " << port;
      ASSERT_EQ(a.contact_count, b.contact_count) << "tick " << tick;
      ASSERT_EQ(a.ramping, b.ramping) << "tick " << tick;
      contacts += a.contact_count;
      ramping += a.ramping ? 1 : 0;
    }
    advance_scene(grid);
    advance_scene(every);
  }
  EXPECT_GT(contacts, 2000u);  // the tools were inside spheres for much of the run
  EXPECT_GT(ramping, 100u);    // and items faded out meanwhile
  const std::vector<ItemEnergyTotals> ea = energy_totals(grid), eb = energy_totals(every);
  ASSERT_EQ(ea.size(), eb.size());
  double given = 0.0;
  for (std::size_t i = 0; i < ea.size(); ++i) {
    EXPECT_EQ(ea[i].id, eb[i].id);
    EXPECT_TRUE(same_bits(ea[i].given, eb[i].given)) << ea[i].id;
    EXPECT_TRUE(same_bits(ea[i].absorbed, eb[i].absorbed)) << ea[i].id;
    given += ea[i].given;
  }
  EXPECT_GT(given, 0.0);
}

TEST(SphereGrid, IsCompiledOnlyWhereThereAreEnoughSpheres) {
  SceneDescription few;
  for (std::uint64_t i = 0; i + 1 < kSphereGridMinSpheres; ++i) {
    ObjectSpec spec;
    spec.p_WO = {0.01 * static_cast<double>(i), 0.0, 0.0};
    spec.stiffness = 500.0;
    spec.shape = SphereSpec{0.004};
    few.objects.push_back({{1, 10 + i, kNeverTick, {}}, spec});
  }
  EXPECT_EQ(compile_scene(few, 50, 1).stages & kStageSphereGrid, 0u);
  EXPECT_TRUE(compile_scene(few, 50, 1).state->sphere_active.empty());  // nothing sized for it
  SceneDescription enough = few;
  ObjectSpec one_more = few.objects.front().spec;
  one_more.p_WO = {-0.01, 0.0, 0.0};
  enough.objects.push_back({{1, 1000, kNeverTick, {}}, one_more});
  EXPECT_NE(compile_scene(enough, 50, 1).stages & kStageSphereGrid, 0u);
}

}  // namespace
}  // namespace haptic::engine
