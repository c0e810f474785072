// csculpt/diff.h tested directly: capture_diff (bitwise: no tolerance, so the boundary is one
// ulp and the sign of zero), apply_diff (reproduces the edit bit for bit; a mismatched mesh or a
// malformed diff is refused with a message saying what is wrong, and the mesh is left
// untouched), and digest (stable, sensitive to every captured value, blind to what is not
// captured content, and pinned to known values so a refactor of the hash is proven
// bit-identical).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "csculpt/diff.h"
#include "csculpt/error.h"
#include "csculpt/mesh.h"
#include "csculpt/testkit/generate.h"
#include "test_meshes.h"
#include "test_strokes.h"
#include "test_support.h"

namespace csculpt {
namespace {

using test::first_difference;
using test::invalid_input_message;
using test::make_icosphere_with_channels;

bool contains(const std::string& haystack, const std::string& needle) {
  return haystack.find(needle) != std::string::npos;
}

/// The values of `m`'s channel `name` (const for a const mesh).
template <class M>
auto* channel_values(M& m, const char* name) {
  const int c = m.find_channel(name);
  EXPECT_GE(c, 0) << name;
  return m.channels[static_cast<std::size_t>(c)].values.data();
}

const ChannelDiff& channel_diff(const Diff& d, const std::string& name) {
  for (const ChannelDiff& c : d.channels)
    if (c.desc.name == name) return c;
  ADD_FAILURE() << "no channel " << name << " in the diff";
  static const ChannelDiff none;
  return none;
}

/// `base` after a dozen scripted strokes and one paint stroke (positions and channels).
Mesh sculpted(const Mesh& base, std::uint64_t seed) {
  Mesh m = base;
  for (const Stroke& s : scripted_strokes(base, seed, 12)) apply_stroke(m, s);
  apply_stroke(
      m, test::stroke(Stroke::Kind::paint, base.positions[seed % base.vertex_count()], 0.4f, 0.8f));
  return m;
}

// ---- capture -------------------------------------------------------------------------------

TEST(DiffCapture, AnUnchangedMeshGivesAnEmptyDiffWithEveryChannel) {
  const Mesh base = make_icosphere_with_channels();
  const Mesh copy = base;
  for (const Mesh* edited : {&base, &copy}) {
    const Diff d = capture_diff(base, *edited);
    EXPECT_EQ(d.vertex_count, base.vertex_count());
    EXPECT_TRUE(d.positions.empty());
    EXPECT_TRUE(d.positions.values.empty());
    ASSERT_EQ(d.channels.size(), base.channels.size());
    for (std::size_t c = 0; c < base.channels.size(); ++c) {
      EXPECT_EQ(d.channels[c].desc, base.channels[c].desc) << "in the base's order";
      EXPECT_TRUE(d.channels[c].change.empty()) << base.channels[c].desc.name;
      EXPECT_TRUE(d.channels[c].change.values.empty());
    }
    EXPECT_EQ(d.touched_vertices(), 0u);
  }
}

TEST(DiffCapture, ListsExactlyTheChangedVerticesInIncreasingOrderWithTheirEditedValues) {
  const Mesh base = make_icosphere_with_channels();
  Mesh edited = base;
  edited.positions[40].y += 0.25f;  // changed out of order on purpose
  edited.positions[5].x = -edited.positions[5].x;
  edited.positions[17].z += 1.f;
  channel_values(edited, "tint")[4 * 17 + 3] += 1.f;  // vertex 17 also in positions
  channel_values(edited, "tint")[4 * 2 + 0] += 1.f;
  channel_values(edited, "metallic")[100] = 0.5f;

  const Diff d = capture_diff(base, edited);
  EXPECT_EQ(d.positions.indices, (std::vector<std::uint32_t>{5, 17, 40}));
  std::vector<float> expected;
  for (std::uint32_t v : {5u, 17u, 40u})
    expected.insert(expected.end(),
                    {edited.positions[v].x, edited.positions[v].y, edited.positions[v].z});
  EXPECT_EQ(d.positions.values, expected) << "edited values, not deltas";

  const ChannelDiff& tint = channel_diff(d, "tint");
  EXPECT_EQ(tint.desc.width, 4u);
  EXPECT_EQ(tint.change.indices, (std::vector<std::uint32_t>{2, 17}));
  const float* t = channel_values(edited, "tint");
  EXPECT_EQ(tint.change.values,
            (std::vector<float>{t[8], t[9], t[10], t[11], t[68], t[69], t[70], t[71]}))
      << "every component of a changed vertex";
  EXPECT_EQ(channel_diff(d, "metallic").change.indices, (std::vector<std::uint32_t>{100}));
  EXPECT_EQ(channel_diff(d, "metallic").change.values, (std::vector<float>{0.5f}));
  for (const char* unchanged : {"albedo", "roughness", "uv"})
    EXPECT_TRUE(channel_diff(d, unchanged).change.empty()) << unchanged;
  EXPECT_EQ(d.touched_vertices(), 5u) << "2, 5, 17, 40, 100: vertex 17 counted once";
}

TEST(DiffCapture, AtTheListedVerticesEqualsTheWholeCaptureWhenEveryChangeIsListed) {
  const Mesh base = make_icosphere_with_channels();
  Mesh edited = base;
  edited.positions[40].y += 0.25f;
  edited.positions[17].z += 1.f;
  channel_values(edited, "tint")[4 * 2 + 0] += 1.f;
  channel_values(edited, "metallic")[100] = 0.5f;
  Diff at;
  at.positions.indices = {999};  // reused buffers start from nothing
  capture_diff_at(base, edited, std::vector<std::uint32_t>{2, 3, 17, 40, 100}, at);
  EXPECT_EQ(at, capture_diff(base, edited));
  capture_diff_at(base, edited, std::vector<std::uint32_t>{3, 40}, at);  // 2, 17, 100 unlisted
  EXPECT_EQ(at.positions.indices, (std::vector<std::uint32_t>{40}));
  EXPECT_TRUE(channel_diff(at, "tint").change.empty());
  EXPECT_NE(invalid_input_message([&] {
              capture_diff_at(base, edited, std::vector<std::uint32_t>{3, 3}, at);
            }).find("not strictly increasing"),
            std::string::npos);
  const auto n = static_cast<std::uint32_t>(base.vertex_count());
  EXPECT_NE(invalid_input_message([&] {
              capture_diff_at(base, edited, std::vector<std::uint32_t>{n}, at);
            }).find("vertex " + std::to_string(n) + " out of range"),
            std::string::npos);
}

TEST(DiffCapture, IsBitwiseOneUlpAndTheSignOfZeroAreChanges) {
  Mesh base = make_icosphere_with_channels();
  base.positions[3] = {0.f, 1.f, 0.5f};
  channel_values(base, "roughness")[9] = 0.f;
  Mesh edited = base;
  edited.positions[3].y = std::nextafter(1.f, 2.f);                      // one ulp up
  edited.positions[7].x = std::nextafter(edited.positions[7].x, -10.f);  // one ulp down
  const float same = base.positions[8].z;
  edited.positions[8].z = same;  // rewritten with the same bits: no change
  edited.positions[3].x = -0.f;  // == 0.f, but other bits
  channel_values(edited, "roughness")[9] = -0.f;
  channel_values(edited, "albedo")[3 * 11 + 1] =
      std::nextafter(channel_values(edited, "albedo")[3 * 11 + 1], 0.f);
  channel_values(base, "uv")[2 * 12] = 0.f;
  channel_values(edited, "uv")[2 * 12] = std::numeric_limits<float>::denorm_min();
  channel_values(edited, "uv")[2 * 13] += std::numeric_limits<float>::denorm_min();  // rounds away
  ASSERT_EQ(-0.f, 0.f);

  const Diff d = capture_diff(base, edited);
  EXPECT_EQ(d.positions.indices, (std::vector<std::uint32_t>{3, 7}));
  ASSERT_EQ(d.positions.values.size(), 6u);
  EXPECT_TRUE(std::signbit(d.positions.values[0])) << "-0 kept as -0";
  EXPECT_EQ(d.positions.values[1], std::nextafter(1.f, 2.f));
  EXPECT_EQ(channel_diff(d, "roughness").change.indices, (std::vector<std::uint32_t>{9}));
  EXPECT_EQ(channel_diff(d, "albedo").change.indices, (std::vector<std::uint32_t>{11}));
  EXPECT_EQ(channel_diff(d, "uv").change.indices, (std::vector<std::uint32_t>{12}))
      << "the smallest denormal is a change; a step that rounds away is none";

  Mesh applied = base;
  apply_diff(d, applied);
  EXPECT_EQ(first_difference(applied, edited), "");
}

TEST(DiffCapture, OfRawArraysMatchesTheMeshCaptureAndHonoursTheWidth) {
  const std::vector<float> base = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11};
  std::vector<float> edited = base;
  edited[5] = 50;   // vertex 1 at width 4, vertex 2 at width 2
  edited[11] = -1;  // the last vertex at every width
  const AttributeDiff w4 = capture_attribute(base, edited, 4);
  EXPECT_EQ(w4.indices, (std::vector<std::uint32_t>{1, 2}));
  EXPECT_EQ(w4.values, (std::vector<float>{4, 50, 6, 7, 8, 9, 10, -1}));
  const AttributeDiff w2 = capture_attribute(base, edited, 2);
  EXPECT_EQ(w2.indices, (std::vector<std::uint32_t>{2, 5}));
  EXPECT_EQ(w2.values, (std::vector<float>{4, 50, 10, -1}));
  const AttributeDiff w1 = capture_attribute(base, edited, 1);
  EXPECT_EQ(w1.indices, (std::vector<std::uint32_t>{5, 11}));
  EXPECT_TRUE(capture_attribute(base, base, 3).empty());
}

TEST(DiffCaptureDeathTest, RawArraysOfAnotherLengthOrOfWidthZeroAreRefused) {
  // capture_attribute is the host's entry (raw arrays); arrays that do not describe the same
  // vertices must be refused like a mesh of another layout, not read past the shorter one.
  // The short array is the front of a longer buffer, so reading past it is no memory error
  // here and the test fails cleanly.
  const std::vector<float> base = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11};
  const std::vector<float> storage = {0, 1, 2, 3, 4, 5, 60, 70, 80, 90, 100, 110};
  const std::span<const float> shorter(storage.data(), 6);
  EXPECT_NE(invalid_input_message([&] { capture_attribute(base, shorter, 3); }), "")
      << "6 edited values against 12 base values";
  EXPECT_NE(invalid_input_message([&] { capture_attribute(shorter, base, 3); }), "")
      << "12 edited values against 6 base values";
  EXPECT_NE(invalid_input_message([&] { capture_attribute(base, base, 5); }), "")
      << "12 values are not whole vertices of width 5";
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        try {
          capture_attribute(base, base, 0);
        } catch (const InvalidInput&) {
          std::_Exit(0);
        }
        std::_Exit(1);
      },
      ::testing::ExitedWithCode(0), "")
      << "width 0: refused (not a division by zero)";
}

TEST(DiffCapture, RejectsAnEditOfOtherConnectivityOrChannelLayout) {
  const Mesh base = make_icosphere_with_channels();
  {
    Mesh m = base;
    m.positions.pop_back();
    EXPECT_NE(invalid_input_message([&] { capture_diff(base, m); }), "");
  }
  {
    Mesh m = base;
    std::swap(m.triangles[0][0], m.triangles[0][1]);
    EXPECT_NE(invalid_input_message([&] { capture_diff(base, m); }), "");
  }
  {
    Mesh m = base;
    m.channels.pop_back();
    EXPECT_NE(invalid_input_message([&] { capture_diff(base, m); }), "");
  }
  {
    Mesh m = base;
    std::swap(m.channels[0], m.channels[1]);
    EXPECT_NE(invalid_input_message([&] { capture_diff(base, m); }), "") << "order matters";
  }
}

// ---- capture then apply --------------------------------------------------------------------

TEST(DiffApply, ReproducesTheEditedMeshBitForBit) {
  const Mesh base = make_sphere(3000, true);
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const Mesh edited = sculpted(base, seed);
    const Diff d = capture_diff(base, edited);
    ASSERT_FALSE(d.positions.empty());
    bool painted = false;
    for (const ChannelDiff& c : d.channels) painted = painted || !c.change.empty();
    EXPECT_TRUE(painted);
    Mesh applied = base;
    apply_diff(d, applied);
    EXPECT_EQ(first_difference(applied, edited), "");
    apply_diff(d, applied);  // idempotent: values, not deltas
    EXPECT_EQ(first_difference(applied, edited), "");
    EXPECT_EQ(capture_diff(base, applied), d);
  }
}

TEST(DiffApply, FindsChannelsByNameAndLeavesUnlistedOnesAlone) {
  const Mesh base = make_icosphere_with_channels();
  Mesh edited = base;
  channel_values(edited, "uv")[2 * 6 + 1] = 9.f;
  channel_values(edited, "albedo")[0] = 0.f;
  Diff d = capture_diff(base, edited);

  Mesh reordered = base;  // the same channels in the reverse order
  std::reverse(reordered.channels.begin(), reordered.channels.end());
  apply_diff(d, reordered);
  EXPECT_EQ(channel_values(reordered, "uv")[13], 9.f);
  EXPECT_EQ(channel_values(reordered, "albedo")[0], 0.f);
  std::reverse(reordered.channels.begin(), reordered.channels.end());
  EXPECT_EQ(first_difference(reordered, edited), "");

  // a diff naming only some channels (a host's positions-only diff) touches only those
  std::erase_if(d.channels, [](const ChannelDiff& c) { return c.desc.name != "uv"; });
  Mesh partial = base;
  apply_diff(d, partial);
  EXPECT_EQ(channel_values(partial, "uv")[13], 9.f);
  EXPECT_EQ(channel_values(partial, "albedo")[0], channel_values(base, "albedo")[0]);
}

/// apply_diff(diff, target) must throw InvalidInput whose message starts with "apply_diff"
/// and contains every one of `says`, and leave `target` bit-identical.
void expect_refused(const Diff& diff, const Mesh& target, std::initializer_list<const char*> says,
                    const std::string& what) {
  SCOPED_TRACE(what);
  Mesh m = target;
  const std::string message = invalid_input_message([&] { apply_diff(diff, m); });
  EXPECT_EQ(message.rfind("apply_diff", 0), 0u) << message;
  for (const char* s : says) EXPECT_TRUE(contains(message, s)) << message << "\nlacks: " << s;
  EXPECT_EQ(first_difference(m, target), "") << "the mesh was changed";
}

TEST(DiffApply, AMismatchedMeshIsRefusedAndLeftUntouched) {
  const Mesh base = make_icosphere_with_channels();
  Mesh edited = base;
  edited.positions[1].x += 1.f;
  channel_values(edited, "tint")[4] += 1.f;
  channel_values(edited, "uv")[0] += 1.f;
  const Diff d = capture_diff(base, edited);
  const std::string n = std::to_string(base.vertex_count());

  Mesh fewer = base;
  fewer.positions.resize(base.vertex_count() - 1);
  expect_refused(d, fewer, {n.c_str(), std::to_string(base.vertex_count() - 1).c_str()},
                 "vertex count");

  Mesh no_tint = base;
  no_tint.channels.erase(no_tint.channels.begin() + no_tint.find_channel("tint"));
  expect_refused(d, no_tint, {"'tint'", "does not exist"}, "a missing channel");

  Mesh narrow = base;  // "uv" 1 wide instead of 2
  Channel& uv = narrow.channels[static_cast<std::size_t>(narrow.find_channel("uv"))];
  uv.desc.width = 1;
  uv.values.resize(base.vertex_count());
  expect_refused(d, narrow, {"'uv'", "width 2", "has 1"}, "a channel of another width");

  Mesh bare = base;
  bare.channels.clear();
  expect_refused(d, bare, {"does not exist"}, "no channels at all");
}

TEST(DiffApply, AMalformedDiffIsRefusedBeforeAnythingIsWritten) {
  const Mesh base = make_icosphere_with_channels();
  Mesh edited = base;
  edited.positions[1].x += 1.f;
  edited.positions[2].x += 1.f;
  channel_values(edited, "uv")[2 * 3] += 1.f;
  channel_values(edited, "uv")[2 * 4] += 1.f;
  const Diff good = capture_diff(base, edited);
  const std::uint32_t n = good.vertex_count;
  ASSERT_EQ(good.positions.indices, (std::vector<std::uint32_t>{1, 2}));

  {  // the positions are valid, only the last channel is wrong: nothing may be written
    Diff d = good;
    ChannelDiff& uv = d.channels[static_cast<std::size_t>(base.find_channel("uv"))];
    uv.change.indices.back() = n;
    expect_refused(d, base, {"channel uv", "out of range", std::to_string(n).c_str()},
                   "index one past the end");
  }
  {
    Diff d = good;
    d.positions.indices = {2, 1};
    expect_refused(d, base, {"positions", "strictly increasing"}, "decreasing indices");
  }
  {
    Diff d = good;
    d.positions.indices = {2, 2};
    expect_refused(d, base, {"positions", "strictly increasing"}, "a repeated index");
  }
  {
    Diff d = good;
    d.positions.values.pop_back();
    expect_refused(d, base, {"positions", "2 indices but 5 values"}, "a short value array");
  }
  {
    Diff d = good;
    ChannelDiff& uv = d.channels[static_cast<std::size_t>(base.find_channel("uv"))];
    uv.change.values.push_back(0.f);
    expect_refused(d, base, {"channel uv", "width 2"}, "a long channel value array");
  }
  for (float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                    -std::numeric_limits<float>::infinity()}) {
    Diff d = good;
    d.positions.values[4] = bad;  // vertex 2's y
    expect_refused(d, base, {"positions", "vertex 2", "not finite"}, "a non-finite value");
  }
  {
    Diff d = good;
    d.vertex_count = n + 1;
    expect_refused(d, base, {"diff is for"}, "a diff for another vertex count");
  }
}

TEST(DiffApply, ACapturedNonFiniteEditIsCapturedButNotApplied) {
  const Mesh base = make_icosphere_with_channels();
  Mesh edited = base;
  edited.positions[4].z = std::numeric_limits<float>::quiet_NaN();
  const Diff d = capture_diff(base, edited);  // capture compares bits, it does not judge
  EXPECT_EQ(d.positions.indices, (std::vector<std::uint32_t>{4}));
  expect_refused(d, base, {"vertex 4", "not finite"}, "NaN from the edited mesh");
}

// ---- digest --------------------------------------------------------------------------------

/// A small hand-made diff: two position changes, one albedo change, an empty metallic.
Diff small_diff() {
  Diff d;
  d.vertex_count = 12;
  d.positions.indices = {3, 7};
  d.positions.values = {1.f, 2.f, 3.f, -0.5f, 0.25f, 1e-3f};
  d.channels.push_back({default_channel("albedo", 3), {{5}, {0.1f, 0.2f, 0.3f}}});
  d.channels.push_back({default_channel("metallic", 1), {}});
  return d;
}

/// Odd counts everywhere (index arrays of 12 bytes, a 9-byte name): the hash's tail path.
Diff odd_diff() {
  Diff d;
  d.vertex_count = 1000;
  d.positions.indices = {0, 500, 999};
  d.positions.values.assign(9, 0.5f);
  d.channels.push_back({default_channel("roughness", 1), {{1, 2, 4}, {0.125f, 0.25f, -0.f}}});
  return d;
}

TEST(DiffDigest, PinnedValuesOfSmallFixedDiffs) {
  // Computed when the hash lived in diff.cpp (word-at-a-time multiply-xorshift, seed
  // 1469598103934665603, little-endian), and cross-checked with an independent Python
  // implementation of the same mixing. A refactor of the hash must keep these bits: merges
  // order diffs by it and peers chain it, so a change is a wire and replay incompatibility.
  EXPECT_EQ(digest(Diff{}), 0x8ca69619cacaa00cull);
  EXPECT_EQ(digest(small_diff()), 0x822db59fda77364dull);
  EXPECT_EQ(digest(odd_diff()), 0x57dfd884c23687f5ull);
}

TEST(DiffDigest, IsStableAcrossCallsCopiesAndHowTheDiffWasMade) {
  const Mesh base = make_sphere(2000, true);
  const Mesh edited = sculpted(base, 7);
  const Diff d = capture_diff(base, edited);
  const std::uint64_t h = digest(d);
  EXPECT_EQ(digest(d), h);
  EXPECT_EQ(digest(Diff(d)), h);
  EXPECT_EQ(digest(capture_diff(base, edited)), h);
  Mesh applied = base;
  apply_diff(d, applied);
  EXPECT_EQ(digest(capture_diff(base, applied)), h);
  // a diff built up value by value, with another capacity, is the same content
  Diff rebuilt;
  rebuilt.vertex_count = d.vertex_count;
  rebuilt.positions.indices.reserve(10 * d.positions.size());
  for (std::uint32_t i : d.positions.indices) rebuilt.positions.indices.push_back(i);
  for (float v : d.positions.values) rebuilt.positions.values.push_back(v);
  rebuilt.channels = d.channels;
  for (ChannelDiff& c : rebuilt.channels) c.change.values.shrink_to_fit();
  EXPECT_EQ(digest(rebuilt), h);
}

TEST(DiffDigest, ChangesWhenAnyCapturedValueChanges) {
  const Diff base = small_diff();
  const std::uint64_t h = digest(base);
  auto expect_changes = [&](const std::string& what, auto&& edit) {
    Diff d = base;
    edit(d);
    EXPECT_NE(digest(d), h) << what;
  };
  for (std::size_t i = 0; i < base.positions.values.size(); ++i) {
    expect_changes("position value " + std::to_string(i) + " one ulp up", [i](Diff& d) {
      d.positions.values[i] = std::nextafter(d.positions.values[i], 9.f);
    });
  }
  for (std::size_t i = 0; i < base.positions.indices.size(); ++i) {
    expect_changes("position index " + std::to_string(i),
                   [i](Diff& d) { d.positions.indices[i] += 1; });
  }
  for (std::size_t i = 0; i < 3; ++i) {
    expect_changes("albedo value " + std::to_string(i), [i](Diff& d) {
      float& v = d.channels[0].change.values[i];
      v = std::nextafter(v, -1.f);
    });
  }
  expect_changes("albedo index", [](Diff& d) { d.channels[0].change.indices[0] = 6; });
  expect_changes("vertex count", [](Diff& d) { d.vertex_count = 13; });
  expect_changes("0 to -0", [](Diff& d) { d.positions.values[1] = -0.f; });
  expect_changes("a channel name", [](Diff& d) { d.channels[1].desc.name = "metalness"; });
  expect_changes("a change added to an empty channel", [](Diff& d) {
    d.channels[1].change = {{0}, {1.f}};
  });
  expect_changes("a position change dropped", [](Diff& d) {
    d.positions.indices.pop_back();
    d.positions.values.resize(3);
  });
  expect_changes("the channels swapped", [](Diff& d) { std::swap(d.channels[0], d.channels[1]); });
  expect_changes("an empty channel dropped", [](Diff& d) { d.channels.pop_back(); });
}

TEST(DiffDigest, TellsApartTheSameBytesInAnotherAttribute) {
  // one change, once as a position and once in a 3-wide channel: the byte streams hold the
  // same words, only the boundaries between the arrays differ
  Diff as_position;
  as_position.vertex_count = 10;
  as_position.positions = {{4}, {1.f, 2.f, 3.f}};
  as_position.channels.push_back({{"c", 3}, {}});
  Diff as_channel = as_position;
  std::swap(as_channel.positions, as_channel.channels[0].change);
  EXPECT_NE(digest(as_position), digest(as_channel));
  // a name's bytes moved into the next array are another diff too
  Diff a;
  a.channels = {{{"ab", 1}, {}}, {{"c", 1}, {}}};
  Diff b;
  b.channels = {{{"a", 1}, {}}, {{"bc", 1}, {}}};
  EXPECT_NE(digest(a), digest(b));
}

TEST(DiffDigest, IsBlindToTheChannelDescriptionBeyondItsName) {
  // "the diff's content (indices and value bits)": how a channel is linearised or clamped is
  // the mesh's description, not captured content
  const Diff d = small_diff();
  Diff other = d;
  other.channels[0].desc.linearisation = Linearisation::identity;
  other.channels[0].desc.min_value = -5.f;
  other.channels[0].desc.max_value = 5.f;
  other.channels[1].desc.linearisation = Linearisation::square;
  ASSERT_NE(other.channels[0].desc, d.channels[0].desc);
  EXPECT_EQ(digest(other), digest(d));
}

}  // namespace
}  // namespace csculpt
