// A joined session's mesh made ready off the UI thread (reference-app/mesh_preparation.h):
// the document it hands over holds the mesh's arrays with current normals, a BVH built over
// them and its copy for the session worker, and the draw clusters the UI thread would build;
// a missing mesh fails with a message; one destroyed before it is taken waits for its thread.
// Also run under TSan.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "bvh.h"
#include "draw_clusters.h"
#include "mesh_document.h"
#include "mesh_preparation.h"

namespace {

void wait_until_ready(const MeshPreparation& preparation) {
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (!preparation.ready() && std::chrono::steady_clock::now() < give_up)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  ASSERT_TRUE(preparation.ready());
}

TEST(AppMeshPreparation, HandsOverTheMeshWithItsNormalsAndItsBvh) {
  MeshDocument source;
  source.make_sphere(20000);
  std::string error;
  csc_mesh* mesh = source.to_csc_mesh(error);
  ASSERT_NE(mesh, nullptr) << error;
  MeshPreparation preparation(mesh);
  wait_until_ready(preparation);
  PreparedMesh prepared;
  ASSERT_TRUE(preparation.take(prepared, error)) << error;
  const MeshDocument& document = prepared.document;
  const TriangleBvh& bvh = prepared.bvh;
  EXPECT_EQ(document.positions, source.positions);
  EXPECT_EQ(document.triangles, source.triangles);
  ASSERT_EQ(document.channels.size(), source.channels.size());
  for (size_t c = 0; c < source.channels.size(); ++c)
    EXPECT_EQ(document.channels[c].values, source.channels[c].values) << source.channels[c].name;
  EXPECT_EQ(document.stale_normals(), 0u);
  // The BVH is over the handed-over arrays: every triangle is in exactly one leaf.
  ASSERT_GT(bvh.node_count(), 0u);
  std::vector<int> seen(document.triangle_count(), 0);
  bvh.for_each_leaf_near(glm::vec3(0.f), 1e3f, [&](uint32_t leaf) {
    for (uint32_t t : bvh.leaf_triangles(leaf)) ++seen[t];
  });
  for (size_t t = 0; t < seen.size(); ++t) ASSERT_EQ(seen[t], 1) << "triangle " << t;
  // The worker's copy: the same tree over the same positions.
  EXPECT_EQ(prepared.worker_positions, document.positions);
  ASSERT_EQ(prepared.worker_bvh.node_count(), bvh.node_count());
  for (uint32_t leaf = 0; leaf < bvh.node_count(); ++leaf) {
    const auto a = bvh.leaf_triangles(leaf), b = prepared.worker_bvh.leaf_triangles(leaf);
    ASSERT_TRUE(std::equal(a.begin(), a.end(), b.begin(), b.end())) << "node " << leaf;
  }
  // The clusters: what the UI thread builds from the same arrays.
  DrawClusters expected;
  expected.build(document.positions, document.triangles);
  EXPECT_EQ(prepared.clusters.draw_order(), expected.draw_order());
  EXPECT_EQ(prepared.clusters.cluster_count(), expected.cluster_count());
}

TEST(AppMeshPreparation, NoMeshFailsWithAMessage) {
  MeshPreparation preparation(nullptr);
  wait_until_ready(preparation);
  PreparedMesh prepared;
  std::string error;
  EXPECT_FALSE(preparation.take(prepared, error));
  EXPECT_FALSE(error.empty());
}

TEST(AppMeshPreparation, DestroyedBeforeItIsTakenWaitsForItsThread) {
  for (int round = 0; round < 20; ++round) {
    MeshDocument source;
    source.make_sphere(2000);
    std::string error;
    MeshPreparation preparation(source.to_csc_mesh(error));
  }
}

}  // namespace
