// Mesh rendering cost (Google Benchmark): the god-object proxy's per-tick update on 10,000-
// triangle meshes with the tool sliding over them (pressed in below the surface), the same in
// free space, the BVH queries alone, and the hierarchy's build (off the loop). Target from the
// scene issue: < 20 us per tick. BM_ProxyTickPercentiles times every tick of a 20,000-tick slide
// and reports p50/p99/max as counters (the clock read adds about 20-40 ns to each).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "engine/scene/god_object.hpp"
#include "engine/scene/mesh.hpp"

using namespace haptic::engine;

namespace {

constexpr double kPi = 3.14159265358979323846;

/// Height field z = h(x, y) over a 0.2 m square, cells x cells quads (2 * cells^2 triangles),
/// bumps of 5 mm amplitude and 50 mm wavelength.
double height(double x, double y) {
  return 0.005 * std::sin(2 * kPi * x / 0.05) * std::sin(2 * kPi * y / 0.05);
}

Mesh height_field(int cells) {
  Mesh m;
  const double size = 0.2;
  for (int j = 0; j <= cells; ++j) {
    for (int i = 0; i <= cells; ++i) {
      const double x = -size / 2 + size * i / cells;
      const double y = -size / 2 + size * j / cells;
      m.vertices_O.push_back({x, y, height(x, y)});
    }
  }
  const auto at = [&](int i, int j) { return static_cast<std::uint32_t>(j * (cells + 1) + i); };
  for (int j = 0; j < cells; ++j) {
    for (int i = 0; i < cells; ++i) {
      m.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      m.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  }
  return m;
}

/// Closed UV sphere: stacks x slices, 2 * slices * (stacks - 1) triangles.
Mesh uv_sphere(double radius, int stacks, int slices) {
  Mesh m;
  m.vertices_O.push_back({0, 0, radius});
  for (int s = 1; s < stacks; ++s) {
    const double theta = kPi * s / stacks;
    for (int k = 0; k < slices; ++k) {
      const double phi = 2 * kPi * k / slices;
      m.vertices_O.push_back({radius * std::sin(theta) * std::cos(phi),
                              radius * std::sin(theta) * std::sin(phi), radius * std::cos(theta)});
    }
  }
  m.vertices_O.push_back({0, 0, -radius});
  const auto ring = [&](int s, int k) {
    return static_cast<std::uint32_t>(1 + (s - 1) * slices + (k % slices));
  };
  const auto bottom = static_cast<std::uint32_t>(m.vertices_O.size() - 1);
  for (int k = 0; k < slices; ++k) m.triangles.push_back({0, ring(1, k), ring(1, k + 1)});
  for (int s = 1; s < stacks - 1; ++s) {
    for (int k = 0; k < slices; ++k) {
      m.triangles.push_back({ring(s, k), ring(s + 1, k), ring(s + 1, k + 1)});
      m.triangles.push_back({ring(s, k), ring(s + 1, k + 1), ring(s, k + 1)});
    }
  }
  for (int k = 0; k < slices; ++k) {
    m.triangles.push_back({ring(stacks - 1, k), bottom, ring(stacks - 1, k + 1)});
  }
  return m;
}

/// Stops the benchmark if a generated mesh breaks the validation rules.
const Mesh& checked(const Mesh& m) {
  const std::string error = validate_mesh(m, 20000);
  if (!error.empty()) {
    std::fprintf(stderr, "mesh_bench: invalid mesh: %s\n", error.c_str());
    std::abort();
  }
  return m;
}

const Mesh& terrain() {
  static const Mesh m = checked(height_field(71));  // 10,082 triangles
  return m;
}
const Mesh& sphere() {
  static const Mesh m = checked(uv_sphere(0.05, 50, 100));  // 9,800 triangles
  return m;
}

/// Tool path number `tick`: sliding over the terrain in a 60 mm circle, 2 mm under the surface,
/// 0.5 mm per tick (0.5 m/s at 1 kHz).
Vec3 terrain_tool(long tick, double depth) {
  const double a = tick * (0.0005 / 0.03);
  const double x = 0.03 * std::cos(a);
  const double y = 0.03 * std::sin(a);
  return {x, y, height(x, y) - depth};
}

/// Sliding round the sphere on a tilted great circle, 3 mm inside, 0.5 mm per tick.
Vec3 sphere_tool(long tick, double depth) {
  const double a = tick * (0.0005 / 0.05);
  const Vec3 dir{std::cos(a), 0.8 * std::sin(a), 0.6 * std::sin(a)};
  return (0.05 - depth) * dir;
}

GodObjectParams material() {
  GodObjectParams p;
  p.stiffness = 1000.0;
  p.damping = 1.0;
  return p;
}

template <class Path>
void proxy_ticks(benchmark::State& state, const Mesh& mesh, Path path, double depth) {
  const MeshBvh bvh = MeshBvh::build(mesh);
  const MeshPose pose;
  GodObjectState proxy;
  const GodObjectParams params = material();
  // Start from outside so the proxy lands on the surface the first time.
  update_god_object(proxy, bvh, pose, params, path(0, -0.02), {});
  long tick = 0;
  double iterations = 0.0;
  double contacts = 0.0;
  for (auto _ : state) {
    const GodObjectOutput out = update_god_object(proxy, bvh, pose, params, path(tick, depth), {});
    benchmark::DoNotOptimize(out);
    iterations += out.iterations;
    contacts += out.in_contact ? 1.0 : 0.0;
    ++tick;
  }
  state.counters["triangles"] = static_cast<double>(mesh.triangles.size());
  state.counters["traces_per_tick"] = iterations / std::max(1L, tick);
  state.counters["contact_fraction"] = contacts / std::max(1L, tick);
}

void BM_ProxyTick_Terrain(benchmark::State& state) {
  proxy_ticks(state, terrain(), terrain_tool, 0.002);
}
void BM_ProxyTick_Sphere(benchmark::State& state) {
  proxy_ticks(state, sphere(), sphere_tool, 0.003);
}
void BM_ProxyTick_TerrainFree(benchmark::State& state) {
  proxy_ticks(state, terrain(), terrain_tool, -0.01);  // 10 mm above: free space
}

void BM_ProxyTickPercentiles(benchmark::State& state) {
  const MeshBvh bvh = MeshBvh::build(terrain());
  const MeshPose pose;
  const GodObjectParams params = material();
  constexpr long kTicks = 20000;
  std::vector<double> ns(kTicks);
  for (auto _ : state) {
    GodObjectState proxy;
    update_god_object(proxy, bvh, pose, params, terrain_tool(0, -0.02), {});
    for (long tick = 0; tick < kTicks; ++tick) {
      const Vec3 p_WT = terrain_tool(tick, 0.002);
      const auto begin = std::chrono::steady_clock::now();
      const GodObjectOutput out = update_god_object(proxy, bvh, pose, params, p_WT, {});
      const auto end = std::chrono::steady_clock::now();
      benchmark::DoNotOptimize(out);
      ns[tick] = std::chrono::duration<double, std::nano>(end - begin).count();
    }
  }
  std::sort(ns.begin(), ns.end());
  state.counters["p50_us"] = ns[kTicks / 2] * 1e-3;
  state.counters["p99_us"] = ns[kTicks * 99 / 100] * 1e-3;
  state.counters["max_us"] = ns.back() * 1e-3;
}

void BM_ClosestPoint(benchmark::State& state) {
  const MeshBvh bvh = MeshBvh::build(terrain());
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.1, 0.1);
  std::uniform_real_distribution<double> dz(-0.01, 0.01);
  std::vector<Vec3> points(4096);
  for (Vec3& p : points) {
    p = {u(rng), u(rng), 0.0};
    p.z = height(p.x, p.y) + dz(rng);
  }
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(bvh.closest_point(points[i++ & 4095], 0.02));
  }
}

void BM_FirstHit(benchmark::State& state) {
  const MeshBvh bvh = MeshBvh::build(terrain());
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.1, 0.1);
  std::uniform_real_distribution<double> step(-0.002, 0.002);
  std::vector<std::pair<Vec3, Vec3>> segments(4096);
  for (auto& s : segments) {  // 2 mm steps across the surface, as the proxy makes them
    const Vec3 p{u(rng), u(rng), 0.0};
    s.first = {p.x, p.y, height(p.x, p.y) + 0.001};
    s.second = s.first + Vec3{step(rng), step(rng), -0.003};
  }
  std::size_t i = 0;
  for (auto _ : state) {
    const auto& s = segments[i++ & 4095];
    benchmark::DoNotOptimize(bvh.first_hit(s.first, s.second));
  }
}

void BM_BuildBvh(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(MeshBvh::build(terrain()));
}

void BM_ValidateMesh(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(validate_mesh(terrain(), 20000));
}

}  // namespace

BENCHMARK(BM_ProxyTick_Terrain);
BENCHMARK(BM_ProxyTick_Sphere);
BENCHMARK(BM_ProxyTick_TerrainFree);
BENCHMARK(BM_ProxyTickPercentiles)->Iterations(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ClosestPoint);
BENCHMARK(BM_FirstHit);
BENCHMARK(BM_BuildBvh)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ValidateMesh)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
