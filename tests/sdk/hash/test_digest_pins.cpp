// Pins the SDK's digests to known values: the diff digest orders diffs before the merge's
// arithmetic (a changed value reorders merges), and the hierarchy digest reaches hosts through
// the C ABI (csc_hierarchy_digest). A change to the shared hash helpers (csculpt/hash.h) that
// alters either fails here.
#include <gtest/gtest.h>

#include <cstdint>

#include "csculpt/diff.h"
#include "csculpt/hierarchy.h"
#include "csculpt/testkit/generate.h"

namespace {

using namespace csculpt;

/// A diff whose arrays have lengths that exercise every tail length of the word hash.
Diff pinned_diff() {
  Diff d;
  d.vertex_count = 1000;
  for (std::uint32_t i = 0; i < 7; ++i) {
    d.positions.indices.push_back(3 * i + 1);
    for (int c = 0; c < 3; ++c) d.positions.values.push_back(0.25f * float(i) - 0.5f * float(c));
  }
  ChannelDiff mask;
  mask.desc = ChannelDesc{"mask", 1, Linearisation::identity, 0.f, 1.f};
  mask.change.indices = {2, 5, 11};
  mask.change.values = {0.1f, 0.7f, 1.f};
  d.channels.push_back(mask);
  ChannelDiff colour;
  colour.desc = ChannelDesc{"colour_rgb", 3, Linearisation::srgb, 0.f, 1.f};
  colour.change.indices = {4};
  colour.change.values = {0.2f, 0.4f, 0.6f};
  d.channels.push_back(colour);
  return d;
}

TEST(DigestPins, DiffDigestKeepsItsValues) {
  EXPECT_EQ(digest(Diff{}), 0x8ca69619cacaa00cull);
  EXPECT_EQ(digest(pinned_diff()), 0x9b03f5ac741e7cc9ull);
  Diff one;
  one.vertex_count = 3;
  one.positions.indices = {1};
  one.positions.values = {1.f, 2.f, 3.f};
  EXPECT_EQ(digest(one), 0x845133fa0cba8be9ull);
}

TEST(DigestPins, HierarchyDigestKeepsItsValues) {
  const Mesh sphere = make_sphere(320);
  const Hierarchy h =
      Hierarchy::build(static_cast<std::uint32_t>(sphere.vertex_count()), sphere.triangles);
  EXPECT_EQ(h.digest(), 0x5e35e827cda0aaedull);
  EXPECT_EQ(Hierarchy::build(sphere).digest(), 0x5e35e827cda0aaedull);  // with linear precision
  const Mesh larger = make_sphere(2000);
  EXPECT_EQ(Hierarchy::build(static_cast<std::uint32_t>(larger.vertex_count()), larger.triangles)
                .digest(),
            0xd3352f6b61353192ull);
}

}  // namespace
