// Hosting's copies of the document's arrays and of the UI's BVH (reference-app/host_staging.h):
// taken into memory prepared on another thread, they take no new memory on the UI thread (new
// pages are what made them slow) and equal what they copy; unprepared, or prepared for another
// shape, the copy is whole all the same.
#include <gtest/gtest.h>

#include <malloc.h>

#include <string>

#include "bvh.h"
#include "host_staging.h"
#include "mesh_document.h"

namespace {

// The bytes this process holds from malloc, mmapped blocks included (glibc).
size_t bytes_in_use() {
  const struct mallinfo2 m = mallinfo2();
  return m.uordblks + m.hblkhd;
}

struct Scene {
  MeshDocument document;
  TriangleBvh bvh;

  explicit Scene(uint32_t faces) {
    document.make_sphere(faces);
    bvh.build(document.positions, document.triangles);
    // A stroke since the build: the copy is of the tree as refitted, not as built.
    std::vector<uint32_t> moved;
    for (uint32_t v = 0; v < document.vertex_count(); ++v)
      if (document.positions[3 * size_t{v}] > 0.8f) {
        document.positions[3 * size_t{v}] += 0.05f;
        moved.push_back(v);
      }
    bvh.refit(document.positions, moved);
  }
};

void expect_whole(const HostCopy& copy, const Scene& scene) {
  const MeshDocument& d = scene.document;
  EXPECT_EQ(copy.content.positions, d.positions);
  EXPECT_EQ(copy.content.triangles, d.triangles);
  ASSERT_EQ(copy.content.channels.size(), d.channels.size());
  for (size_t c = 0; c < d.channels.size(); ++c) {
    EXPECT_EQ(copy.content.channels[c].name, d.channels[c].name);
    EXPECT_EQ(copy.content.channels[c].width, d.channels[c].width);
    EXPECT_EQ(copy.content.channels[c].values, d.channels[c].values);
  }
  ASSERT_EQ(copy.bvh.node_count(), scene.bvh.node_count());
  for (uint32_t n = 0; n < scene.bvh.node_count(); ++n) {
    ASSERT_EQ(copy.bvh.box(n).lo, scene.bvh.box(n).lo) << "node " << n;
    ASSERT_EQ(copy.bvh.box(n).hi, scene.bvh.box(n).hi) << "node " << n;
    const auto a = copy.bvh.leaf_triangles(n), b = scene.bvh.leaf_triangles(n);
    ASSERT_TRUE(std::equal(a.begin(), a.end(), b.begin(), b.end())) << "node " << n;
    if (a.empty()) continue;
    const auto p = copy.bvh.owned_vertices(n), q = scene.bvh.owned_vertices(n);
    ASSERT_TRUE(std::equal(p.begin(), p.end(), q.begin(), q.end())) << "leaf " << n;
  }
  // The copy refits as the original does (its scratch and marks came along).
  TriangleBvh mine = copy.bvh, theirs = scene.bvh;
  std::vector<float> positions = d.positions;
  positions[0] += 0.1f;
  mine.refit(positions, std::vector<uint32_t>{0});
  theirs.refit(positions, std::vector<uint32_t>{0});
  for (uint32_t n = 0; n < theirs.node_count(); ++n)
    ASSERT_TRUE(mine.box(n).lo == theirs.box(n).lo && mine.box(n).hi == theirs.box(n).hi) << n;
}

TEST(AppHostStaging, APreparedCopyTakesNoNewMemoryAndIsWhole) {
  Scene scene(20000);
  HostStaging staging;
  staging.prepare(scene.document, scene.bvh);
  EXPECT_TRUE(staging.prepared_for(scene.document));
  staging.wait();
  const size_t before = bytes_in_use();
  HostCopy copy = staging.copy(scene.document, scene.bvh);
  EXPECT_LE(bytes_in_use(), before) << "the copy took new memory on the UI thread";
  expect_whole(copy, scene);
  EXPECT_FALSE(staging.prepared_for(scene.document));  // taken: the app prepares again
}

TEST(AppHostStaging, AnUnpreparedCopyTakesNewMemoryAndIsWhole) {
  Scene scene(20000);
  HostStaging staging;
  const size_t before = bytes_in_use();
  HostCopy copy = staging.copy(scene.document, scene.bvh);
  // The measure sees what the prepared copy spares: at least the positions and triangles.
  EXPECT_GT(bytes_in_use(),
            before + 4 * (scene.document.positions.size() + scene.document.triangles.size()));
  expect_whole(copy, scene);
}

TEST(AppHostStaging, PreparedForAnotherShapeTheCopyIsStillWhole) {
  Scene small(2000), large(20000);
  HostStaging staging;
  staging.prepare(small.document, small.bvh);
  EXPECT_FALSE(staging.prepared_for(large.document));
  staging.wait();
  expect_whole(staging.copy(large.document, large.bvh), large);
}

}  // namespace
