// The normals a session version brings, computed on the session worker
// (reference-app/version_normals.h): copied into a document that holds the version's
// positions, they leave no normal that differs by a bit from recomputing them all, and every
// vertex whose normal changed is among those handed over.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

#include "mesh_document.h"
#include "version_normals.h"

namespace {

/** Moves a random `share` of the vertices (a scattered and a clustered part). */
std::vector<uint32_t> move_some(MeshDocument& document, double share, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> offset(-0.02f, 0.02f);
  std::bernoulli_distribution pick(share);
  std::vector<uint32_t> moved;
  for (uint32_t v = 0; v < document.vertex_count(); ++v) {
    const bool clustered = document.positions[3 * size_t{v}] > 0.6f;  // a cap of the sphere
    if (!clustered && !pick(rng)) continue;
    for (int c = 0; c < 3; ++c) document.positions[3 * size_t{v} + size_t(c)] += offset(rng);
    moved.push_back(v);
  }
  return moved;
}

TEST(AppVersionNormals, CopiedNormalsEqualRecomputedOnesBitForBit) {
  for (const double share : {0.0, 0.01, 0.3}) {
    MeshDocument document;
    document.make_sphere(20000);
    const std::vector<float> normals_before = document.normals;
    VersionNormals worker;
    worker.set_topology(document.triangles, document.vertex_count());
    MeshDocument version = document;  // the worker's mirror, moved by a merged version
    ChangedNormals changed;
    changed.moved = move_some(version, share, 7);
    worker.compute(version.positions.data(), changed);
    ASSERT_EQ(changed.face_normals.size(), 3 * changed.triangles.size());
    ASSERT_EQ(changed.normals.size(), 3 * changed.vertices.size());

    document.positions = version.positions;  // the UI takes the version's values
    document.set_normals(changed.triangles, changed.face_normals, changed.vertices,
                         changed.normals);
    EXPECT_EQ(document.stale_normals(), 0u) << "share " << share;
    // Whatever normal changed was handed over (the renderer re-uploads those only).
    std::vector<bool> handed(document.vertex_count(), false);
    for (uint32_t v : changed.vertices) handed[v] = true;
    document.recompute_all_normals();
    for (uint32_t v = 0; v < document.vertex_count(); ++v) {
      const size_t at = 3 * size_t{v};
      const bool same =
          std::equal(&document.normals[at], &document.normals[at + 3], &normals_before[at]);
      ASSERT_TRUE(same || handed[v]) << "vertex " << v << " changed its normal unannounced";
    }
  }
}

TEST(AppVersionNormals, NothingMovedHandsOverNothing) {
  MeshDocument document;
  document.make_sphere(2000);
  VersionNormals worker;
  worker.set_topology(document.triangles, document.vertex_count());
  ChangedNormals changed;
  worker.compute(document.positions.data(), changed);
  EXPECT_TRUE(changed.triangles.empty());
  EXPECT_TRUE(changed.vertices.empty());
}

}  // namespace
