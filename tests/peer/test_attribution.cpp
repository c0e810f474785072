// Attribution without sockets: what a diff touches, its quantised contribution, and a received
// contribution added back (a malformed one cut, never trusted).
#include <gtest/gtest.h>

#include "attribution.h"
#include "csculpt/peer/session.h"
#include "pieces.h"

namespace {

using namespace csculpt;
using namespace csculpt::peer;
using namespace csculpt::peer::testing;

TEST(Attribution, TouchedIsTheUnionOfPositionsAndChannels) {
  Diff d;
  d.vertex_count = 10;
  d.positions.indices = {1, 4};
  d.positions.values.assign(6, 0.f);
  ChannelDiff c;
  c.desc.name = "mask";
  c.change.indices = {0, 4, 9};
  c.change.values.assign(3, 1.f);
  d.channels.push_back(c);
  EXPECT_EQ(touched(d), (std::vector<std::uint32_t>{0, 1, 4, 9}));
}

TEST(Attribution, ContributionRoundTripsWithinItsQuantisation) {
  const Mesh& base = sphere();
  const Diff d = stroke_diff(base, {0, 0, 1}, {0.3f, 0, 0}, true);
  const std::vector<std::uint32_t> vertices = touched(d);
  ASSERT_FALSE(vertices.empty());
  const std::vector<float> exact = change_amounts(d, base, vertices, 2.f);
  const Contribution c = measure_contribution(9, d, base, vertices, 2.f);
  EXPECT_EQ(c.peer, 9u);
  EXPECT_EQ(c.amounts.size(), vertices.size());
  EXPECT_FLOAT_EQ(c.scale, *std::max_element(exact.begin(), exact.end()));
  std::vector<float> sum(base.vertex_count(), 0.f);
  add_contribution(c, sum);
  add_contribution(c, sum);  // sums
  for (std::size_t i = 0; i < vertices.size(); ++i)
    EXPECT_NEAR(sum[vertices[i]], 2 * exact[i], 2 * c.scale / 255.f) << vertices[i];
  std::size_t nonzero = 0;
  for (float v : sum) nonzero += v != 0;
  EXPECT_LE(nonzero, vertices.size());
}

TEST(Attribution, AMalformedListIsCutWhereItGoesWrong) {
  std::vector<float> into(10, 0.f);
  // gaps 2, 3 -> vertices 2, 6; then a gap past the end; then more that must not be read
  Contribution c{1, {2, 3, 50, 0}, {255, 255, 255, 255}, 1.f};
  add_contribution(c, into);
  EXPECT_EQ(into, (std::vector<float>{0, 0, 1, 0, 0, 0, 1, 0, 0, 0}));
  std::vector<float> truncated(10, 0.f);
  add_contribution({1, {1, 0x80}, {255, 255}, 1.f}, truncated);  // a varint cut in half
  EXPECT_EQ(truncated[1], 1.f);
  EXPECT_EQ(std::count(truncated.begin(), truncated.end(), 0.f), 9);
  std::vector<float> fewer(10, 0.f);
  add_contribution({1, {0, 0, 0}, {255}, 1.f}, fewer);  // fewer amounts than indices
  EXPECT_EQ(fewer[0], 1.f);
  EXPECT_EQ(fewer[1], 0.f);
}

TEST(Attribution, ColoursMixByShareAndLeaveUntouchedVerticesGrey) {
  const std::vector<std::pair<PeerId, std::vector<float>>> a = {{1, {0.f, 1.f, 1.f}},
                                                                {2, {0.f, 0.f, 1.f}}};
  const std::vector<float> rgb = attribution_colours(a, 3);
  ASSERT_EQ(rgb.size(), 9u);
  EXPECT_FLOAT_EQ(rgb[0], 0.82f);  // untouched
  EXPECT_FLOAT_EQ(rgb[4], 0.85f);  // peer 1 alone: green
  EXPECT_FLOAT_EQ(rgb[7], 1.f);    // both: green + blue, clamped
  EXPECT_FLOAT_EQ(rgb[8], 1.f);
  EXPECT_FLOAT_EQ(rgb[6], 0.25f);
}

}  // namespace
