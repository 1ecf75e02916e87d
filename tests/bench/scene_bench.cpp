// Per-tick cost of engine::evaluate_scene (Google Benchmark) on representative scenes: empty; one
// frictionless wall; 10 mixed objects and 3 fields; 1,000 and 10,648 spheres, each also without
// the sphere stage's broad phase (the ratio is what the grid buys); a 10,082-triangle mesh; 8
// sessions of 10 objects each; the default server scene (one wall, one spring field).
// Each scene is compiled once per run with compile_scene(description, 50, 1, 1e-3).
//
// The tool follows a Lissajous curve through the scene's objects, one sample per 1 ms tick, so
// contacts start, hold and end; ticks increase by one per call. The curve's frequencies are whole
// multiples of 1/(20 s), so the 20,000 precomputed samples (position and velocity, SI units) form
// one closed period and the tool never jumps when the table wraps. Reading it from a table keeps
// the trigonometry out of what is measured.
//
// How to read the output:
//   - Time: Google Benchmark's mean over its timed loop, per tick.
//   - p50_ns, p99_ns: after the timed loop (so not in Time) the same scene, continuing the same
//     path, runs one full period of 20,000 ticks, each timed alone with std::chrono::steady_clock;
//     the samples are sorted and the percentiles read off. Every sample includes one clock read;
//     clock_ns is the median of back-to-back reads, to subtract when comparing small figures.
//     Google Benchmark calls each function several times while it settles on an iteration count;
//     the counters shown are those of the reported run.
//   - items: objects + fields; contacts_mean: mean contact_count per tick over the period;
//     contact_ticks: the fraction of ticks with at least one contact; contacts_max: the most in one
//     tick; speed_m_per_s: the tool's mean speed along the path.
// Targets from the scene issue: < 2 us per tick for 10 objects, < 20 us for 1,000 objects and for
// the 10k-triangle mesh. Compare scenes within one run (the ratios), not absolute times across
// machines; none of this is a ctest assertion.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "engine/scene/compiled_scene.hpp"

using namespace haptic::engine;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDt = 1e-3;              // Tick period. Unit: s.
constexpr std::size_t kPathTicks = 20000;  // One closed period of every path (20 s).
constexpr double kPathPeriod = kDt * static_cast<double>(kPathTicks);  // Unit: s.

// ---------------------------------------------------------------------------------------------
// Tool paths.

struct PathSample {
  Vec3 p_WT;  // Unit: m.
  Vec3 v_WT;  // Unit: m/s.
};

/// p(t) = center + A_i sin(2π n_i t / 20 s + φ_i) per axis; n_i whole, so the path closes.
struct Lissajous {
  Vec3 center_W;                      // Unit: m.
  Vec3 amplitude;                     // Unit: m.
  std::array<int, 3> cycles{7, 9, 11};  // Periods per 20 s, per axis.
  std::array<double, 3> phase{0.0, kPi / 2, 0.0};  // Unit: rad.
};

std::vector<PathSample> sample_path(const Lissajous& curve) {
  std::vector<PathSample> path(kPathTicks);
  const std::array<double, 3> c{curve.center_W.x, curve.center_W.y, curve.center_W.z};
  const std::array<double, 3> a{curve.amplitude.x, curve.amplitude.y, curve.amplitude.z};
  for (std::size_t k = 0; k < kPathTicks; ++k) {
    const double t = kDt * static_cast<double>(k);
    std::array<double, 3> p{}, v{};
    for (int i = 0; i < 3; ++i) {
      const double w = 2 * kPi * curve.cycles[i] / kPathPeriod;  // Unit: rad/s.
      p[i] = c[i] + a[i] * std::sin(w * t + curve.phase[i]);
      v[i] = a[i] * w * std::cos(w * t + curve.phase[i]);
    }
    path[k] = {{p[0], p[1], p[2]}, {v[0], v[1], v[2]}};
  }
  return path;
}

double mean_speed(const std::vector<PathSample>& path) {
  double sum = 0.0;
  for (const PathSample& s : path) sum += norm(s.v_WT);
  return sum / static_cast<double>(path.size());
}

// ---------------------------------------------------------------------------------------------
// Scene building blocks.

struct SceneCase {
  SceneDescription description;
  std::vector<PathSample> path;
  bool without_sphere_grid = false;  // look at every sphere every tick (drop_sphere_grid)
};

class Builder {
 public:
  explicit Builder(SceneDescription& description) : description_(description) {}

  void session(std::uint64_t session_id) { session_id_ = session_id; }

  void object(const ObjectSpec& spec) { description_.objects.push_back({next_meta(), spec}); }
  void field(const FieldSpec& spec) { description_.fields.push_back({next_meta(), spec}); }

 private:
  ItemMeta next_meta() {
    ItemMeta meta;
    meta.session_id = session_id_;
    meta.id = next_id_++;
    return meta;
  }

  SceneDescription& description_;
  std::uint64_t session_id_ = 1;
  std::uint64_t next_id_ = 1;
};

ObjectSpec wall(const Vec3& point_W, const Vec3& normal_W, double stiffness, double damping) {
  ObjectSpec spec;
  spec.p_WO = point_W;
  spec.stiffness = stiffness;
  spec.damping = damping;
  spec.shape = HalfSpaceSpec{normal_W};
  return spec;
}

ObjectSpec sphere(const Vec3& center_W, double radius, double stiffness, double damping) {
  ObjectSpec spec;
  spec.p_WO = center_W;
  spec.stiffness = stiffness;
  spec.damping = damping;
  spec.shape = SphereSpec{radius};
  return spec;
}

ObjectSpec box(const Vec3& center_W, const Quat& R_WO, const Vec3& half_extents, double stiffness,
               double damping) {
  ObjectSpec spec;
  spec.p_WO = center_W;
  spec.R_WO = R_WO;
  spec.stiffness = stiffness;
  spec.damping = damping;
  spec.shape = BoxSpec{half_extents};
  return spec;
}

ObjectSpec capsule(const Vec3& center_W, const Quat& R_WO, double radius, double half_length,
                   double stiffness, double damping) {
  ObjectSpec spec;
  spec.p_WO = center_W;
  spec.R_WO = R_WO;
  spec.stiffness = stiffness;
  spec.damping = damping;
  spec.shape = CapsuleSpec{radius, half_length};
  return spec;
}

/// Rotation by `angle` (rad) about a unit axis.
Quat about(const Vec3& axis, double angle) {
  const double s = std::sin(angle / 2);
  return {std::cos(angle / 2), s * axis.x, s * axis.y, s * axis.z};
}

/// Stops the benchmark if a generated mesh breaks the validation rules.
std::shared_ptr<const MeshModel> model_of(Mesh mesh) {
  const std::string error = validate_mesh(mesh, 20000);
  if (!error.empty()) {
    std::fprintf(stderr, "scene_bench: invalid mesh: %s\n", error.c_str());
    std::abort();
  }
  auto model = std::make_shared<MeshModel>();
  model->mesh = std::move(mesh);
  model->bvh = MeshBvh::build(model->mesh);
  return model;
}

/// A square plate of two triangles in O's z = 0 plane, `half_side` (m) from centre to edge.
std::shared_ptr<const MeshModel> plate(double half_side) {
  Mesh m;
  const double h = half_side;
  m.vertices_O = {{-h, -h, 0.0}, {h, -h, 0.0}, {h, h, 0.0}, {-h, h, 0.0}};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  return model_of(std::move(m));
}

/// Terrain z = h(x, y) of tests/bench/mesh_bench.cpp: bumps of 5 mm amplitude, 50 mm wavelength.
double height(double x, double y) {
  return 0.005 * std::sin(2 * kPi * x / 0.05) * std::sin(2 * kPi * y / 0.05);
}
Vec3 height_gradient(double x, double y) {  // (∂h/∂x, ∂h/∂y, 0), dimensionless
  const double k = 2 * kPi / 0.05;
  return {0.005 * k * std::cos(k * x) * std::sin(k * y), 0.005 * k * std::sin(k * x) * std::cos(k * y),
          0.0};
}

/// The terrain over a 0.2 m square, cells x cells quads: 71 cells give 10,082 triangles. Built
/// once (the BVH takes milliseconds) and shared by every run, as snapshots share it on the server.
std::shared_ptr<const MeshModel> terrain() {
  static const std::shared_ptr<const MeshModel> model = [] {
    constexpr int kCells = 71;
    constexpr double kSize = 0.2;
    Mesh m;
    for (int j = 0; j <= kCells; ++j) {
      for (int i = 0; i <= kCells; ++i) {
        const double x = -kSize / 2 + kSize * i / kCells;
        const double y = -kSize / 2 + kSize * j / kCells;
        m.vertices_O.push_back({x, y, height(x, y)});
      }
    }
    const auto at = [](int i, int j) { return static_cast<std::uint32_t>(j * (kCells + 1) + i); };
    for (int j = 0; j < kCells; ++j) {
      for (int i = 0; i < kCells; ++i) {
        m.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
        m.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
      }
    }
    return model_of(std::move(m));
  }();
  return model;
}

// ---------------------------------------------------------------------------------------------
// The scenes.

/// The path through the middle of the workspace used where the scene spans it: ±50 mm in x and
/// y, ±`z_amplitude` in z (mean speed 0.12–0.17 m/s; the speed_m_per_s counter).
Lissajous workspace_path(double z_center, double z_amplitude) {
  return {{0.0, 0.0, z_center}, {0.05, 0.05, z_amplitude}, {7, 9, 11}, {0.0, kPi / 2, 0.0}};
}

SceneCase empty_scene() { return {{}, sample_path(workspace_path(0.0, 0.05))}; }

/// A frictionless floor at z = 0; the tool dips up to 6 mm into it and rises 10 mm above.
SceneCase one_wall() {
  SceneCase c;
  Builder(c.description).object(wall({0, 0, 0}, {0, 0, 1}, 1000.0, 1.0));
  c.path = sample_path(workspace_path(0.002, 0.008));
  return c;
}

/// The default server scene (tests/bench/tick_bench.cpp's): a floor and a spring to 20 mm above it.
SceneCase default_server() {
  SceneCase c;
  Builder b(c.description);
  b.session(0);
  b.object(wall({0, 0, 0}, {0, 0, 1}, 1000.0, 1.0));
  b.field(FieldSpec{SpringToPointSpec{{0, 0, 0.02}, 20.0, 0.1, 0.0}});
  c.path = sample_path(workspace_path(0.002, 0.008));
  return c;
}

/// Ten objects of every kind and three fields within ±50 mm x ±50 mm x ±30 mm: two walls, three
/// spheres (fast stages), two boxes (one with friction 0.5/0.4), two capsules (one with the exact
/// ZOH law), a two-triangle plate (god object); a spring to a point, a local viscous field and a
/// polynomial potential well.
SceneCase mixed() {
  SceneCase c;
  Builder b(c.description);
  b.object(wall({0, 0, -0.025}, {0, 0, 1}, 1000.0, 1.0));
  b.object(wall({0.045, 0, 0}, {-1, 0, 0}, 800.0, 1.0));
  b.object(sphere({0.02, 0.02, 0.0}, 0.015, 800.0, 0.5));
  b.object(sphere({-0.03, 0.01, 0.01}, 0.01, 1000.0, 0.5));
  b.object(sphere({0.0, -0.03, -0.01}, 0.012, 600.0, 0.0));
  b.object(box({-0.02, -0.02, -0.015}, {}, {0.015, 0.01, 0.008}, 1000.0, 1.0));
  ObjectSpec rough = box({0.02, -0.025, 0.015}, about({0, 0, 1}, kPi / 6), {0.012, 0.012, 0.006},
                         1000.0, 1.0);
  rough.static_friction = 0.5;
  rough.dynamic_friction = 0.4;
  b.object(rough);
  b.object(capsule({-0.025, 0.03, -0.01}, about({1, 0, 0}, kPi / 2), 0.008, 0.015, 800.0, 1.0));
  ObjectSpec zoh = capsule({0.03, 0.0, -0.015}, {}, 0.008, 0.01, 1000.0, 2.0);
  zoh.law = ContactLaw::kExactZoh;
  b.object(zoh);
  ObjectSpec mesh;
  mesh.p_WO = {-0.025, -0.02, 0.02};
  mesh.stiffness = 1000.0;
  mesh.damping = 1.0;
  mesh.shape = MeshShapeSpec{plate(0.02)};
  b.object(mesh);
  b.field(FieldSpec{SpringToPointSpec{{0, 0, 0}, 20.0, 0.1, 2.0}});
  b.field(FieldSpec{ViscousFieldSpec{0.5, {0.02, 0.02, 0.0}, 0.03, 0.01}});
  PotentialFieldSpec well;
  well.distance = point_distance({-0.02, 0.02, 0.0});
  well.kind = PotentialKind::kPolynomial;
  well.order = 2;
  well.gain = 50.0;
  well.offset = 0.03;
  b.field(FieldSpec{well});
  c.path = sample_path(workspace_path(0.0, 0.03));
  return c;
}

/// side³ spheres of 5 mm radius on a lattice of 12 mm pitch, the tool crossing it in all three
/// axes (10: a 113 mm cube of 1,000; 22: a 257 mm cube of 10,648).
SceneCase sphere_lattice(int side) {
  SceneCase c;
  Builder b(c.description);
  constexpr double kPitch = 0.012;
  const double middle = 0.5 * (side - 1);
  for (int i = 0; i < side; ++i) {
    for (int j = 0; j < side; ++j) {
      for (int k = 0; k < side; ++k) {
        const Vec3 center{kPitch * (i - middle), kPitch * (j - middle), kPitch * (k - middle)};
        b.object(sphere(center, 0.005, 800.0, 0.5));
      }
    }
  }
  c.path = sample_path(workspace_path(0.0, 0.05));
  return c;
}
SceneCase sphere_grid() { return sphere_lattice(10); }
SceneCase spheres_10k() { return sphere_lattice(22); }
/// The same scenes looking at every sphere every tick (the broad phase dropped): the ratio of the
/// two, in one run, is what the broad phase buys.
SceneCase sphere_grid_every() {
  SceneCase c = sphere_lattice(10);
  c.without_sphere_grid = true;
  return c;
}
SceneCase spheres_10k_every() {
  SceneCase c = sphere_lattice(22);
  c.without_sphere_grid = true;
  return c;
}

/// The 10,082-triangle terrain, the tool sliding over it within ±60 mm while its height above the
/// local surface swings from +5 mm to −3 mm (starting above, so the god object starts outside).
SceneCase terrain_mesh() {
  SceneCase c;
  ObjectSpec mesh;
  mesh.stiffness = 1000.0;
  mesh.damping = 1.0;
  mesh.shape = MeshShapeSpec{terrain()};
  Builder(c.description).object(mesh);
  // x, y from the Lissajous curve; z = h(x, y) + the curve's z (offset above the surface).
  c.path = sample_path({{0.0, 0.0, 0.001}, {0.06, 0.06, 0.004}, {7, 9, 11}, {0.0, kPi / 2, kPi / 2}});
  for (PathSample& s : c.path) {
    const Vec3 grad = height_gradient(s.p_WT.x, s.p_WT.y);
    s.p_WT.z += height(s.p_WT.x, s.p_WT.y);
    s.v_WT.z += dot(grad, s.v_WT);
  }
  return c;
}

/// A multi-user demo: sessions 1..8 each own 10 objects in one octant of the workspace — a wall
/// closing off the octant's outer corner, five spheres and four boxes (two with friction).
SceneCase eight_users() {
  SceneCase c;
  Builder b(c.description);
  for (std::uint64_t session = 1; session <= 8; ++session) {
    b.session(session);
    const double sx = ((session - 1) & 1) != 0 ? 1.0 : -1.0;
    const double sy = ((session - 1) & 2) != 0 ? 1.0 : -1.0;
    const double sz = ((session - 1) & 4) != 0 ? 1.0 : -1.0;
    const Vec3 corner{sx, sy, sz};
    const Vec3 cell = 0.03 * corner;  // the octant's centre
    // Solid beyond the plane x sx + y sy + z sz = 0.105 m (the tool reaches 0.15 m there).
    b.object(wall(0.035 * corner, -(1.0 / std::sqrt(3.0)) * corner, 1000.0, 1.0));
    for (int k = 0; k < 5; ++k) {
      const double a = 2 * kPi * k / 5;
      b.object(sphere(cell + Vec3{0.015 * std::cos(a), 0.015 * std::sin(a), 0.006 * (k - 2)},
                      0.006, 800.0, 0.5));
    }
    for (int k = 0; k < 4; ++k) {
      const Vec3 offset{0.01 * ((k & 1) ? 1 : -1), 0.01 * ((k & 2) ? 1 : -1), -0.012};
      ObjectSpec spec =
          box(cell + offset, about({0, 0, 1}, 0.3 * k), {0.006, 0.004, 0.003}, 1000.0, 1.0);
      if (k % 2 == 1) {
        spec.static_friction = 0.5;
        spec.dynamic_friction = 0.4;
      }
      b.object(spec);
    }
  }
  c.path = sample_path(workspace_path(0.0, 0.05));
  return c;
}

// ---------------------------------------------------------------------------------------------
// The measurement.

/// Median cost of one steady_clock read, back to back (included once in each timed sample).
double clock_overhead_ns() {
  std::vector<double> ns(1000);
  for (double& d : ns) {
    const auto begin = std::chrono::steady_clock::now();
    const auto end = std::chrono::steady_clock::now();
    d = std::chrono::duration<double, std::nano>(end - begin).count();
  }
  std::nth_element(ns.begin(), ns.begin() + 500, ns.end());
  return ns[500];
}

void BM_EvaluateScene(benchmark::State& state, SceneCase (*make)()) {
  const SceneCase c = make();
  CompiledScene scene = compile_scene(c.description, 50, 1, kDt);
  if (c.without_sphere_grid) drop_sphere_grid(scene);
  const std::vector<PathSample>& path = c.path;
  std::size_t i = 0;
  std::int64_t tick = 0;

  for (auto _ : state) {
    const PathSample& s = path[i];
    if (++i == path.size()) i = 0;
    benchmark::DoNotOptimize(evaluate_scene(scene, s.p_WT, s.v_WT, ++tick, kDt));
  }

  // One full period of the path, every tick timed alone, continuing where the timed loop ended.
  std::vector<double> ns(kPathTicks);
  double contacts = 0.0;
  double contact_ticks = 0.0;
  std::uint32_t contacts_max = 0;
  for (double& sample_ns : ns) {
    const PathSample& s = path[i];
    if (++i == path.size()) i = 0;
    const auto begin = std::chrono::steady_clock::now();
    const SceneForce out = evaluate_scene(scene, s.p_WT, s.v_WT, ++tick, kDt);
    const auto end = std::chrono::steady_clock::now();
    benchmark::DoNotOptimize(out);
    sample_ns = std::chrono::duration<double, std::nano>(end - begin).count();
    contacts += out.contact_count;
    contact_ticks += out.contact_count > 0 ? 1.0 : 0.0;
    contacts_max = std::max(contacts_max, out.contact_count);
  }
  std::sort(ns.begin(), ns.end());
  const auto ticks = static_cast<double>(kPathTicks);
  state.counters["p50_ns"] = ns[kPathTicks / 2];
  state.counters["p99_ns"] = ns[kPathTicks * 99 / 100];
  state.counters["clock_ns"] = clock_overhead_ns();
  state.counters["items"] =
      static_cast<double>(c.description.objects.size() + c.description.fields.size());
  state.counters["contacts_mean"] = contacts / ticks;
  state.counters["contact_ticks"] = contact_ticks / ticks;
  state.counters["contacts_max"] = contacts_max;
  state.counters["speed_m_per_s"] = mean_speed(path);
}

}  // namespace

BENCHMARK_CAPTURE(BM_EvaluateScene, empty, empty_scene);
BENCHMARK_CAPTURE(BM_EvaluateScene, one_wall, one_wall);
BENCHMARK_CAPTURE(BM_EvaluateScene, mixed_10_objects_3_fields, mixed);
BENCHMARK_CAPTURE(BM_EvaluateScene, spheres_1000, sphere_grid);
BENCHMARK_CAPTURE(BM_EvaluateScene, spheres_1000_every_sphere, sphere_grid_every);
BENCHMARK_CAPTURE(BM_EvaluateScene, spheres_10648, spheres_10k);
BENCHMARK_CAPTURE(BM_EvaluateScene, spheres_10648_every_sphere, spheres_10k_every);
BENCHMARK_CAPTURE(BM_EvaluateScene, mesh_10k_triangles, terrain_mesh);
BENCHMARK_CAPTURE(BM_EvaluateScene, users_8x10_objects, eight_users);
BENCHMARK_CAPTURE(BM_EvaluateScene, default_server, default_server);

BENCHMARK_MAIN();
