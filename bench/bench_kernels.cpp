// Micro-benchmarks of the merge's kernels (Google Benchmark; --benchmark_format=json).
// The end-to-end figures come from `csculpt bench merge`.
#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

#include "csculpt/hierarchy.h"
#include "csculpt/isometry.h"
#include "csculpt/testkit/generate.h"

namespace {

using namespace csculpt;

std::vector<std::array<double, 9>> near_rotations(std::size_t n) {
  std::vector<std::array<double, 9>> out(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double a = 0.001 * static_cast<double>(i % 997),
                 s = 1.0 + 0.0001 * static_cast<double>(i % 101);
    out[i] = {s * std::cos(a), -std::sin(a), 0.01, std::sin(a), std::cos(a), 0.0, 0.0, 0.02,
              1.0 / s};
  }
  return out;
}

void BM_ClosestRotationNewton(benchmark::State& state) {
  const auto m = near_rotations(4096);
  std::size_t i = 0;
  Quat q;
  for (auto _ : state) {
    benchmark::DoNotOptimize(closest_rotation(m[i++ & 4095].data(), q));
    benchmark::DoNotOptimize(q);
  }
}
BENCHMARK(BM_ClosestRotationNewton);

void BM_ClosestRotationSvd(benchmark::State& state) {
  const auto m = near_rotations(4096);
  std::size_t i = 0;
  Quat q;
  for (auto _ : state) {
    benchmark::DoNotOptimize(closest_rotation_svd(m[i++ & 4095].data(), q));
    benchmark::DoNotOptimize(q);
  }
}
BENCHMARK(BM_ClosestRotationSvd);

void BM_FaceRotation(benchmark::State& state) {
  // a sphere's triangles before and after a grab: the merge's per-face kernel
  const Mesh base = make_sphere(20000);
  Mesh edited = base;
  Stroke s;
  s.kind = Stroke::Kind::twist;
  s.center = {0, 0, 1};
  s.radius = 1.5f;
  s.strength = 0.8f;
  apply_stroke(edited, s);
  std::size_t f = 0;
  Quat q;
  for (auto _ : state) {
    const Triangle& t = base.triangles[f++ % base.triangles.size()];
    benchmark::DoNotOptimize(face_rotation(base.positions[t[0]], base.positions[t[1]],
                                           base.positions[t[2]], edited.positions[t[0]],
                                           edited.positions[t[1]], edited.positions[t[2]], q));
    benchmark::DoNotOptimize(q);
  }
}
BENCHMARK(BM_FaceRotation);

void BM_HierarchyBuild(benchmark::State& state) {
  const Mesh mesh = make_sphere(static_cast<std::uint32_t>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(Hierarchy::build(mesh));
  state.counters["faces"] = static_cast<double>(mesh.face_count());
}
BENCHMARK(BM_HierarchyBuild)->Arg(20000)->Arg(320000)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
