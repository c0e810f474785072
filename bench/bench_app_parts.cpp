// Micro-benchmarks of csculpt-app's per-frame parts that a landing merged version exercises
// (Google Benchmark; --benchmark_format=json): the draw clusters, the BVH's refit, the ordered
// upload list. Built from the app's own sources; the frame figures come from csculpt-app
// --bench-frames and tools/app_bench_session.sh.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

#include "bvh.h"
#include "draw_clusters.h"
#include "icosphere.h"
#include "marks.h"

namespace {

const TriangleMesh& sphere() {  // 320K faces, 160K vertices: the session benchmarks' mesh
  static const TriangleMesh mesh = make_geodesic_sphere(320000);
  return mesh;
}

// `count` vertices as strokes leave them: runs of 2,000 neighbours in Morton order.
std::vector<uint32_t> moved_vertices(uint32_t count) {
  const uint32_t n = static_cast<uint32_t>(sphere().positions.size() / 3);
  std::mt19937 rng(count);
  std::vector<uint32_t> moved;
  while (moved.size() < count) {
    const auto start = static_cast<uint32_t>(rng() % (n - 2000));
    for (uint32_t i = 0; i < 2000 && moved.size() < count; ++i) moved.push_back(start + i);
  }
  std::sort(moved.begin(), moved.end());
  moved.erase(std::unique(moved.begin(), moved.end()), moved.end());
  return moved;
}

// A version's clusters, refitted at once (what the renderer did) or the per-frame budget.
void BM_ClustersRefit(benchmark::State& state) {
  const TriangleMesh& m = sphere();
  DrawClusters clusters;
  clusters.build(m.positions, m.triangles);
  const std::vector<uint32_t> moved = moved_vertices(static_cast<uint32_t>(state.range(0)));
  const uint32_t budget = state.range(1) ? DrawClusters::kRefitsPerFrame : UINT32_MAX;
  for (auto _ : state) {
    clusters.mark_moved(moved);
    clusters.refit_stale(m.positions, m.triangles, budget);
    state.PauseTiming();
    clusters.refit_stale(m.positions, m.triangles, UINT32_MAX);  // the frames after
    state.ResumeTiming();
  }
}
BENCHMARK(BM_ClustersRefit)
    ->ArgsProduct({{5000, 35000, 70000}, {0, 1}})
    ->Unit(benchmark::kMillisecond);

// The BVH after a version: boxes grown then tightened, or refitted exactly at once.
void BM_BvhRefitAfterVersion(benchmark::State& state) {
  TriangleMesh m = sphere();
  TriangleBvh bvh;
  bvh.build(m.positions, m.triangles);
  const std::vector<uint32_t> moved = moved_vertices(static_cast<uint32_t>(state.range(0)));
  float scale = 1.01f;
  for (auto _ : state) {
    state.PauseTiming();
    for (uint32_t v : moved) m.positions[3 * size_t{v}] *= scale;
    scale = 1.f / scale;
    state.ResumeTiming();
    if (state.range(1)) {
      bvh.refit_exactly(m.positions, m.triangles, moved);
    } else {
      bvh.refit(m.positions, moved);
      bvh.tighten(m.positions, m.triangles);
    }
  }
}
BENCHMARK(BM_BvhRefitAfterVersion)
    ->ArgsProduct({{5000, 35000, 70000}, {0, 1}})
    ->Unit(benchmark::kMillisecond);

// The vertices to upload, in increasing order: sorted, or taken from a bitmap.
void BM_UploadOrder(benchmark::State& state) {
  std::vector<uint32_t> moved = moved_vertices(static_cast<uint32_t>(state.range(0)));
  std::shuffle(moved.begin(), moved.end(), std::mt19937(1));
  Marks marks;
  marks.resize(sphere().positions.size() / 3);
  uint64_t sum = 0;
  for (auto _ : state) {
    if (state.range(1)) {
      for (uint32_t v : moved) marks.mark(v);
      marks.take_in_order([&](uint32_t v) { sum += v; });
    } else {
      std::vector<uint32_t> sorted = moved;
      std::sort(sorted.begin(), sorted.end());
      sum += sorted.front();
    }
  }
  benchmark::DoNotOptimize(sum);
}
BENCHMARK(BM_UploadOrder)
    ->ArgsProduct({{5000, 35000, 70000}, {0, 1}})
    ->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
