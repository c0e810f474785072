// The snapshot codec and chunk assembly: round trip, and truncated or corrupt input refused.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>

#include "csculpt/error.h"
#include "pieces.h"
#include "snapshot.h"

namespace {

using namespace csculpt;
using namespace csculpt::peer;
using namespace csculpt::peer::testing;

std::map<PeerId, std::vector<float>> sample_attribution(std::size_t n) {
  std::map<PeerId, std::vector<float>> a;
  for (PeerId p : {PeerId{3}, PeerId{900001}}) {
    std::vector<float>& v = a[p];
    for (std::size_t i = 0; i < n; ++i) v.push_back(float(i % 17) * 0.25f + float(p % 5));
  }
  return a;
}

MergeFrame sample_frame() {
  MergeFrame f;
  f.center = {0.5f, -1.f, 2.f};
  f.scale = 3.5f;
  return f;
}

TEST(SnapshotCodec, RoundTripsMeshFrameAndAttributionBitForBit) {
  const Mesh& m = sphere();
  ASSERT_FALSE(m.channels.empty());
  const auto attribution = sample_attribution(m.vertex_count());
  const Snapshot s = decode_snapshot(encode_snapshot(m, sample_frame(), attribution));
  EXPECT_EQ(s.mesh.positions.size(), m.positions.size());
  EXPECT_EQ(0, std::memcmp(s.mesh.positions.data(), m.positions.data(),
                           m.positions.size() * sizeof(Vec3f)));
  EXPECT_EQ(s.mesh.triangles, m.triangles);
  ASSERT_EQ(s.mesh.channels.size(), m.channels.size());
  for (std::size_t c = 0; c < m.channels.size(); ++c) {
    EXPECT_EQ(s.mesh.channels[c].desc, m.channels[c].desc);
    EXPECT_EQ(s.mesh.channels[c].values, m.channels[c].values);
  }
  EXPECT_EQ(s.frame.center.x, 0.5f);
  EXPECT_EQ(s.frame.center.z, 2.f);
  EXPECT_EQ(s.frame.scale, 3.5f);
  EXPECT_EQ(s.attribution, attribution);
}

TEST(SnapshotCodec, RoundTripsAMeshWithoutChannelsOrAttribution) {
  const Mesh m = make_sphere(80);
  const Snapshot s = decode_snapshot(encode_snapshot(m, sample_frame(), {}));
  EXPECT_EQ(s.mesh.vertex_count(), m.vertex_count());
  EXPECT_TRUE(s.mesh.channels.empty());
  EXPECT_TRUE(s.attribution.empty());
}

std::string refusal(std::span<const std::uint8_t> bytes) {
  try {
    decode_snapshot(bytes);
  } catch (const InvalidInput& e) {
    return e.what();
  }
  return "accepted";
}

TEST(SnapshotCodec, RefusesTruncatedInput) {
  const auto bytes =
      encode_snapshot(sphere(), sample_frame(), sample_attribution(sphere().vertex_count()));
  for (std::size_t n :
       {std::size_t{0}, std::size_t{4}, std::size_t{64}, bytes.size() / 2, bytes.size() - 1})
    EXPECT_EQ(refusal(std::span(bytes).first(n)), "snapshot failed FlatBuffers verification")
        << n << " bytes";
}

TEST(SnapshotCodec, RefusesCorruptInput) {
  std::vector<std::uint8_t> garbage(4096);
  for (std::size_t i = 0; i < garbage.size(); ++i) garbage[i] = static_cast<std::uint8_t>(i * 131);
  EXPECT_NE(refusal(garbage), "accepted");
  // Well-formed FlatBuffers whose content is wrong.
  Mesh bad_index = sphere();
  bad_index.triangles[5][1] = static_cast<std::uint32_t>(bad_index.vertex_count() + 3);
  EXPECT_NE(refusal(encode_snapshot(bad_index, sample_frame(), {})), "accepted");
  MergeFrame flat = sample_frame();
  flat.scale = 0;
  EXPECT_EQ(refusal(encode_snapshot(sphere(), flat, {})), "snapshot frame missing or invalid");
  auto short_attribution = sample_attribution(sphere().vertex_count());
  short_attribution.begin()->second.pop_back();
  EXPECT_EQ(refusal(encode_snapshot(sphere(), sample_frame(), short_attribution)),
            "snapshot attribution has the wrong size");
  Mesh wide = sphere();
  wide.channels[0].desc.width = 5;
  wide.channels[0].values.resize(wide.vertex_count() * 5);
  EXPECT_NE(refusal(encode_snapshot(wide, sample_frame(), {})).find("width outside 1..4"),
            std::string::npos);
}

TEST(SnapshotAssembly, CollectsChunksInAnyOrder) {
  const auto bytes = encode_snapshot(sphere(), sample_frame(), {});
  const std::size_t chunk = 1000;
  std::vector<std::size_t> offsets;
  for (std::size_t o = 0; o < bytes.size(); o += chunk) offsets.push_back(o);
  std::reverse(offsets.begin(), offsets.end());
  SnapshotAssembly a;
  bool complete = false;
  for (std::size_t i = 0; i < offsets.size(); ++i) {
    const std::size_t n = std::min(chunk, bytes.size() - offsets[i]);
    complete = a.add(7, 77, offsets[i], bytes.size(), std::span(bytes).subspan(offsets[i], n));
    EXPECT_EQ(complete, i + 1 == offsets.size());
  }
  EXPECT_EQ(a.version(), 7u);
  EXPECT_EQ(a.chain(), 77u);
  EXPECT_EQ(a.take(), bytes);
}

// Two answers at two versions, interleaved, used to restart each other for ever (a peer behind a
// merger publishing every 10 ms asked once per version): the first one is finished first.
TEST(SnapshotAssembly, FinishesOneSnapshotBeforeAnotherAndCountsARepeatOnce) {
  const std::vector<std::uint8_t> data(10, 1);
  SnapshotAssembly a;
  EXPECT_FALSE(a.add(1, 0, 0, 20, data));
  EXPECT_FALSE(a.add(2, 0, 0, 20, data));  // another version while 1 is under way: ignored
  EXPECT_FALSE(a.add(1, 0, 0, 20, data));  // a repeat: still half
  EXPECT_TRUE(a.add(1, 0, 10, 20, data));
  EXPECT_EQ(a.version(), 1u);
  a.take();
  EXPECT_FALSE(a.add(2, 0, 0, 20, data));  // the next one starts once the first is taken
  a.reset();                               // its sender went quiet
  EXPECT_FALSE(a.add(3, 0, 0, 20, data));
  EXPECT_TRUE(a.add(3, 0, 10, 20, data));
  EXPECT_EQ(a.version(), 3u);
}

TEST(SnapshotAssembly, RefusesChunksOutsideTheBuffer) {
  const std::vector<std::uint8_t> data(10, 1);
  SnapshotAssembly a;
  EXPECT_THROW(a.add(3, 0, 15, 20, data), InvalidInput);
  EXPECT_THROW(a.add(3, 0, 21, 20, {}), InvalidInput);
  EXPECT_THROW(a.add(3, 0, ~std::uint64_t{0}, 20, data), InvalidInput);
}

}  // namespace
