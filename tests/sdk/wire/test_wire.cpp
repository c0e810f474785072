// The FlatBuffers wire codec (csculpt/wire.h): the stated error bound on spheres under every
// stroke kind and on real meshes, lossless and idempotent modes, dropped zero changes, the
// size target, header fields, every refusal of hostile bytes (each message built with the
// generated API so that it trips exactly one check), and reading messages of a newer schema.
// Also writes (CSCULPT_WRITE_WIRE_CORPUS=dir) and checks the wire fuzzers' seed corpus.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <limits>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "csculpt/diff.h"
#include "csculpt/error.h"
#include "csculpt/hierarchy.h"
#include "csculpt/io.h"
#include "csculpt/mesh.h"
#include "csculpt/testkit/generate.h"
#include "csculpt/testkit/random.h"
#include "csculpt/vec3.h"
#include "csculpt/wire.h"
#include "diff_generated.h"
#include "diff_next_generated.h"
#include "fuzz_base.h"
#include "test_strokes.h"
#include "test_support.h"

namespace csculpt {
namespace {

namespace fs = std::filesystem;
namespace fb = csculpt::wire;
namespace fbn = csculpt::wire_next;
using Bytes = std::vector<std::uint8_t>;
using test::invalid_input_message;

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

// ---- comparing diffs -------------------------------------------------------------------------

bool same_bits(const AttributeDiff& a, const AttributeDiff& b) {
  return a.indices == b.indices && a.values.size() == b.values.size() &&
         (a.values.empty() ||
          std::memcmp(a.values.data(), b.values.data(), a.values.size() * sizeof(float)) == 0);
}

/// Bit-identical content; channels compared by name, so a diff that lists an unchanged channel
/// equals one that leaves it out (the encoder sends only channels with changes).
bool same_bits(const Diff& a, const Diff& b) {
  if (a.vertex_count != b.vertex_count || !same_bits(a.positions, b.positions)) return false;
  auto changed = [](const Diff& d) {
    std::vector<const ChannelDiff*> out;
    for (const ChannelDiff& c : d.channels)
      if (!c.change.empty()) out.push_back(&c);
    std::sort(out.begin(), out.end(), [](const ChannelDiff* x, const ChannelDiff* y) {
      return x->desc.name < y->desc.name;
    });
    return out;
  };
  const auto ca = changed(a), cb = changed(b);
  if (ca.size() != cb.size()) return false;
  for (std::size_t i = 0; i < ca.size(); ++i)
    if (ca[i]->desc.name != cb[i]->desc.name || !same_bits(ca[i]->change, cb[i]->change))
      return false;
  return true;
}

double half_ulp(float a, float b) {
  const float m = std::max(std::abs(a), std::abs(b));
  return 0.5 * (double(std::nextafter(m, kInf)) - double(m));
}

/// Worst error of one attribute, as a fraction of its tolerance.
struct BoundReport {
  double worst_fraction = 0;  ///< max error / absolute tolerance
  std::size_t components = 0;
};

/// Checks every component of `decoded` (as applied to the base) against `original`: within the
/// header's bound (0.8 x tolerance + half a float ulp) everywhere, and within the tolerance
/// itself wherever half an ulp is small beside it (the documented "negligible" case).
/// `tol` is absolute. Returns the worst error over the tolerance.
BoundReport check_attribute(const float* original, const float* decoded, std::size_t n, double tol,
                            const std::string& what) {
  BoundReport r;
  std::size_t failures = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double a = original[i], b = decoded[i];
    const double err = std::abs(a - b);
    const double hu = half_ulp(original[i], decoded[i]);
    // Double arithmetic inside the codec (delta / step, base + q * step) is ~1e-16 relative.
    const double slack = 1e-12 * (std::abs(a) + tol);
    const bool within_formula = err <= 0.8 * tol + hu + slack;
    const bool within_tol = hu > 0.19 * tol || err <= tol;
    if ((!within_formula || !within_tol) && failures++ < 5)
      ADD_FAILURE() << what << " component " << i << ": original " << a << " decoded " << b
                    << " error " << err << " tolerance " << tol << " half ulp " << hu;
    r.worst_fraction = std::max(r.worst_fraction, tol > 0 ? err / tol : err);
  }
  r.components = n;
  EXPECT_EQ(failures, 0u) << what;
  return r;
}

/// The encode options' absolute position tolerance, computed as the encoder does.
double position_tolerance(const Mesh& base, const EncodeOptions& o) {
  double scale = o.position_scale;
  if (scale == 0 && o.position_tolerance > 0) scale = bbox_diagonal(base.positions);
  if (scale == 0) scale = 1;
  return o.position_tolerance * scale;
}

/// Applies both diffs to copies of the base and compares the resulting arrays component by
/// component, so a vertex the encoder dropped is judged by the base value it keeps. Also: the
/// decoded diff lists no vertex the original does not, and passes validate().
BoundReport check_round_trip(const Mesh& base, const Diff& original, const Diff& decoded,
                             const EncodeOptions& o, const std::string& what) {
  EXPECT_NO_THROW(validate(decoded, base, "decoded diff")) << what;
  Mesh want = base, got = base;
  apply_diff(original, want);
  apply_diff(decoded, got);
  auto subset = [](const AttributeDiff& d, const AttributeDiff& of) {
    return std::includes(of.indices.begin(), of.indices.end(), d.indices.begin(), d.indices.end());
  };
  EXPECT_TRUE(subset(decoded.positions, original.positions)) << what << ": invented positions";
  const double ptol = position_tolerance(base, o);
  BoundReport worst = check_attribute(reinterpret_cast<const float*>(want.positions.data()),
                                      reinterpret_cast<const float*>(got.positions.data()),
                                      3 * base.vertex_count(), ptol, what + " positions");
  for (std::size_t c = 0; c < base.channels.size(); ++c) {
    const std::string& name = base.channels[c].desc.name;
    for (const ChannelDiff& dc : decoded.channels) {
      if (dc.desc.name != name) continue;
      for (const ChannelDiff& oc : original.channels) {
        if (oc.desc.name == name) {
          EXPECT_TRUE(subset(dc.change, oc.change)) << what << ": invented changes in " << name;
        }
      }
    }
    const BoundReport r = check_attribute(
        want.channels[c].values.data(), got.channels[c].values.data(),
        want.channels[c].values.size(), o.channel_tolerance, what + " channel " + name);
    worst.worst_fraction = std::max(worst.worst_fraction, r.worst_fraction);
  }
  return worst;
}

/// Encodes and decodes; every round trip also checks that the decoded diff encode_diff gives
/// is what decode_diff reads, bit for bit, in the same layout (every base channel, in order).
Diff round_trip(const Diff& d, const Mesh& base, const EncodeOptions& o, Bytes* bytes = nullptr) {
  Diff from_encoder;
  const Bytes b = encode_diff(d, base, DiffHeader{}, o, &from_encoder);
  if (bytes) *bytes = b;
  Diff decoded = decode_diff(b, base);
  EXPECT_TRUE(same_bits(from_encoder, decoded));
  EXPECT_EQ(from_encoder.channels.size(), decoded.channels.size());
  for (std::size_t c = 0; c < decoded.channels.size() && c < from_encoder.channels.size(); ++c)
    EXPECT_EQ(from_encoder.channels[c].desc.name, decoded.channels[c].desc.name);
  return decoded;
}

// Tolerance pairs (relative position, absolute channel) from coarse to fine.
const std::vector<std::pair<double, double>> kTolerances = {
    {1e-3, 1e-2}, {1e-4, 1e-3}, {1e-5, 1e-4}, {1e-6, 1e-5}};

// ---- round trips on spheres --------------------------------------------------------------------

/// Scripted strokes plus one of each kind the script did not produce (it never makes bend or
/// smooth), each to be applied alone.
std::vector<Stroke> strokes_of_every_kind(const Mesh& base) {
  std::vector<Stroke> strokes = scripted_strokes(base, 11, 24, /*paint=*/true);
  std::set<Stroke::Kind> present;
  for (const Stroke& s : strokes) present.insert(s.kind);
  for (std::uint32_t k = 0; k <= static_cast<std::uint32_t>(Stroke::Kind::paint); ++k) {
    const auto kind = static_cast<Stroke::Kind>(k);
    if (present.count(kind)) continue;
    Stroke s;
    s.kind = kind;
    s.center = base.positions[7 + 31 * k];
    s.axis = unit(s.center);
    s.radius = 0.7f;
    s.strength = kind == Stroke::Kind::smooth ? 0.9f : 0.3f;
    strokes.push_back(s);
  }
  return strokes;
}

TEST(WireRoundTrip, EveryStrokeKindOnASphereStaysWithinTheBound) {
  const Mesh base = make_sphere(20000, /*materials=*/true);
  const Topology topology =
      Topology::build(static_cast<std::uint32_t>(base.vertex_count()), base.triangles);
  std::set<Stroke::Kind> kinds;
  Mesh all = base;
  for (const Stroke& s : strokes_of_every_kind(base)) {
    Mesh edited = base;
    apply_stroke(edited, s, &topology);
    apply_stroke(all, s, &topology);
    const Diff d = capture_diff(base, edited);
    ASSERT_GT(d.touched_vertices(), 0u);
    kinds.insert(s.kind);
    for (const auto& [ptol, ctol] : kTolerances) {
      const EncodeOptions o{ptol, 0, ctol};
      const std::string what = "stroke kind " + std::to_string(static_cast<int>(s.kind)) +
                               " tolerance " + std::to_string(ptol);
      const BoundReport r = check_round_trip(base, d, round_trip(d, base, o), o, what);
      EXPECT_LE(r.worst_fraction, 1.0) << what;
    }
  }
  EXPECT_EQ(kinds.size(), 7u) << "strokes of every kind (grab .. paint)";
  // Many strokes on top of each other: large and small changes in one message.
  const Diff d = capture_diff(base, all);
  for (const auto& [ptol, ctol] : kTolerances) {
    const EncodeOptions o{ptol, 0, ctol};
    check_round_trip(base, d, round_trip(d, base, o), o, "all strokes");
  }
}

TEST(WireRoundTrip, AnExplicitPositionScaleSetsTheBound) {
  const Mesh base = make_sphere(2000, true);
  Mesh edited = base;
  for (const Stroke& s : scripted_strokes(base, 3, 6, true)) apply_stroke(edited, s);
  const Diff d = capture_diff(base, edited);
  for (const double scale : {0.01, 0.5, 40.0}) {
    const EncodeOptions o{1e-4, scale, 1e-3};
    const BoundReport r =
        check_round_trip(base, d, round_trip(d, base, o), o, "scale " + std::to_string(scale));
    // The bound is used, not undershot by orders of magnitude (the step is what it says).
    EXPECT_GT(r.worst_fraction, 0.3) << scale;
  }
}

// ---- round trips on real meshes ----------------------------------------------------------------

/// Moves ~30% of the vertices by amounts spread from 1e-9 to 1e-1 of the diagonal (so some
/// changes round to zero at every tolerance) and changes ~20% of the channel values.
Mesh perturb(const Mesh& base, std::uint64_t seed) {
  Mesh m = base;
  SplitMix64 rng{seed};
  const double diag = bbox_diagonal(base.positions);
  for (Vec3f& p : m.positions) {
    if (rng.uniform() > 0.3) continue;
    const double magnitude = diag * std::pow(10.0, rng.range(-9, -1));
    p.x = static_cast<float>(p.x + magnitude * rng.range(-1, 1));
    p.y = static_cast<float>(p.y + magnitude * rng.range(-1, 1));
    p.z = static_cast<float>(p.z + magnitude * rng.range(-1, 1));
  }
  for (Channel& c : m.channels)
    for (float& v : c.values)
      if (rng.uniform() < 0.2) v = static_cast<float>(v + std::pow(10.0, rng.range(-8, -1)));
  return m;
}

class WireRealMesh : public ::testing::TestWithParam<const char*> {};

std::string model_test_name(const ::testing::TestParamInfo<const char*>& param) {
  std::string n = param.param;
  for (char& c : n)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return n;
}

TEST_P(WireRealMesh, PerturbedVerticesStayWithinTheBound) {
  const fs::path path = fs::path(CSCULPT_TEST_MODELS) / GetParam();
  if (!fs::exists(path)) GTEST_SKIP() << path << " not installed (assimp-testmodels)";
  Mesh base = read_mesh(path.string());
  if (base.channels.empty())
    for (const ChannelDesc& c : material_channels()) base.add_channel(c);
  const double diag = bbox_diagonal(base.positions);
  ASSERT_GT(diag, 0);
  const Diff d = capture_diff(base, perturb(base, 42));
  ASSERT_GT(d.positions.size(), base.vertex_count() / 5);
  for (const auto& [ptol, ctol] : kTolerances) {
    const EncodeOptions o{ptol, 0, ctol};
    Bytes bytes;
    const Diff decoded = round_trip(d, base, o, &bytes);
    const BoundReport r = check_round_trip(base, d, decoded, o, path.filename().string());
    EXPECT_LE(r.worst_fraction, 1.0);
    // The smallest moves (1e-9 of the diagonal) round to zero and are not sent.
    EXPECT_LT(decoded.positions.size(), d.positions.size()) << ptol;
  }
  // Lossless: every bit back.
  const EncodeOptions lossless{0, 0, 0};
  EXPECT_TRUE(same_bits(round_trip(d, base, lossless), d));
}

// Meshes well away from the origin: there half a float ulp is no longer negligible beside
// the tolerance, and the header's bound (0.8 x tolerance + half an ulp) is what holds.
TEST_P(WireRealMesh, FarFromTheOriginTheHalfUlpTermHolds) {
  const fs::path path = fs::path(CSCULPT_TEST_MODELS) / GetParam();
  if (!fs::exists(path)) GTEST_SKIP() << path << " not installed (assimp-testmodels)";
  Mesh base = read_mesh(path.string());
  const float diag = bbox_diagonal(base.positions);
  for (Vec3f& p : base.positions) p = {p.x + 2000 * diag, p.y - 700 * diag, p.z};
  const Diff d = capture_diff(base, perturb(base, 9));
  for (const auto& [ptol, ctol] : kTolerances) {
    const EncodeOptions o{ptol, 0, ctol};
    check_round_trip(base, d, round_trip(d, base, o), o, "far " + path.filename().string());
  }
}

INSTANTIATE_TEST_SUITE_P(AssimpModels, WireRealMesh,
                         ::testing::Values("PLY/Wuson.ply", "PLY/float-color.ply",
                                           "PLY/cube_uv.ply", "OBJ/spider.obj", "OFF/Wuson.off",
                                           "STL/Spider_binary.stl", "STL/sphereWithHole.stl"),
                         model_test_name);

// ---- lossless and idempotent
// ---------------------------------------------------------------------

TEST(WireRoundTrip, MisalignedBytesDecodeTheSameAndPeekPointsIntoTheCallersBuffer) {
  // Sockets and nested vectors hand messages over at any address; FlatBuffers reads 8-byte
  // fields in place, so the decoder must not depend on the caller's alignment.
  const Mesh base = make_sphere(2000, true);
  Mesh edited = base;
  for (const Stroke& s : scripted_strokes(base, 9, 6, true)) apply_stroke(edited, s);
  const Diff d = capture_diff(base, edited);
  DiffHeader h;
  h.author = "misaligned";
  h.base_version = 0x0102030405060708ull;
  const std::vector<std::uint8_t> bytes = encode_diff(d, base, h);
  const Diff expected = decode_diff(bytes, base);
  for (std::size_t shift = 1; shift < 8; ++shift) {
    std::vector<std::uint8_t> buffer(bytes.size() + shift);
    std::copy(bytes.begin(), bytes.end(), buffer.begin() + static_cast<std::ptrdiff_t>(shift));
    const std::span<const std::uint8_t> at(buffer.data() + shift, bytes.size());
    DiffHeader got;
    EXPECT_EQ(decode_diff(at, base, &got), expected) << shift;
    EXPECT_EQ(got.base_version, h.base_version);
    const DiffHeader peeked = peek_diff_header(at);
    EXPECT_EQ(peeked.author, "misaligned");
    EXPECT_GE(reinterpret_cast<const std::uint8_t*>(peeked.author.data()), at.data());
    EXPECT_LE(reinterpret_cast<const std::uint8_t*>(peeked.author.data()) + peeked.author.size(),
              at.data() + at.size());
  }
}

TEST(WireLossless, ZeroTolerancesAreBitExact) {
  const Mesh base = make_sphere(5000, true);
  Mesh edited = base;
  for (const Stroke& s : scripted_strokes(base, 5, 10, true)) apply_stroke(edited, s);
  // A sign-only change (0 -> -0) is a change to a bitwise capture; lossless keeps it.
  std::size_t zero_vertex = base.vertex_count();
  for (std::size_t v = 0; v < base.vertex_count() && zero_vertex == base.vertex_count(); ++v)
    if (std::bit_cast<std::uint32_t>(edited.positions[v].x) == 0) zero_vertex = v;
  ASSERT_LT(zero_vertex, base.vertex_count());
  edited.positions[zero_vertex].x = -0.f;
  // Values near the float limits and subnormals go through untouched too.
  edited.channels[0].values[3] = std::numeric_limits<float>::denorm_min();
  edited.channels[1].values[2] = -std::numeric_limits<float>::max();
  const Diff d = capture_diff(base, edited);
  const Diff decoded = round_trip(d, base, EncodeOptions{0, 0, 0});
  EXPECT_TRUE(same_bits(decoded, d));
  EXPECT_EQ(decoded.positions.indices, d.positions.indices);
  EXPECT_TRUE(std::signbit(
      decoded.positions
          .values[3 * static_cast<std::size_t>(std::lower_bound(decoded.positions.indices.begin(),
                                                                decoded.positions.indices.end(),
                                                                zero_vertex) -
                                               decoded.positions.indices.begin())]));
  // Each attribute can be lossless on its own.
  const Diff positions_exact = round_trip(d, base, EncodeOptions{0, 0, 1e-3});
  EXPECT_TRUE(same_bits(positions_exact.positions, d.positions));
  const Diff channels_exact = round_trip(d, base, EncodeOptions{1e-3, 0, 0});
  for (std::size_t c = 0; c < base.channels.size(); ++c)
    EXPECT_TRUE(same_bits(channels_exact.channels[c].change, d.channels[c].change));
}

// Changes too large for the quantiser (more than ~9e15 steps) are sent as floats instead.
TEST(WireLossless, ChangesBeyondTheQuantiserFallBackToFloats) {
  const Mesh base = make_sphere(500, false);
  Mesh edited = base;
  edited.positions[3].x += 1.0f;
  edited.positions[9].z -= 0.5f;
  const Diff d = capture_diff(base, edited);
  const Diff decoded = round_trip(d, base, EncodeOptions{1e-17, 0, 1e-4});
  EXPECT_TRUE(same_bits(decoded, d));
}

TEST(WireIdempotent, DecodedDiffsEncodeToThemselves) {
  const Mesh base = make_sphere(20000, true);
  const Topology topology =
      Topology::build(static_cast<std::uint32_t>(base.vertex_count()), base.triangles);
  for (const Stroke& s : strokes_of_every_kind(base)) {
    Mesh edited = base;
    apply_stroke(edited, s, &topology);
    const Diff d = capture_diff(base, edited);
    for (const auto& [ptol, ctol] : kTolerances) {
      const EncodeOptions o{ptol, 0, ctol};
      Bytes first, second;
      const Diff once = round_trip(d, base, o, &first);
      const Diff twice = round_trip(once, base, o, &second);
      EXPECT_TRUE(same_bits(twice, once)) << static_cast<int>(s.kind) << " " << ptol;
      // Same quantised numbers, so the same bytes: peers re-sending a decoded diff agree.
      EXPECT_EQ(first, second) << static_cast<int>(s.kind) << " " << ptol;
    }
    const EncodeOptions lossless{0, 0, 0};
    const Diff once = round_trip(d, base, lossless);
    EXPECT_TRUE(same_bits(round_trip(once, base, lossless), once));
  }
}

// ---- zero changes are left out ----------------------------------------------------------------

TEST(WireZeroChanges, ChangesThatRoundToZeroAreLeftOut) {
  const Mesh base = make_sphere(2000, true);
  const EncodeOptions o{1e-4, 1.0, 1e-3};  // absolute position tolerance 1e-4
  Mesh edited = base;
  for (std::uint32_t v = 0; v < 100; ++v) edited.positions[v].y += 0.5e-4f;  // < 0.8 tol
  for (std::uint32_t v = 100; v < 150; ++v) edited.positions[v].y += 3e-4f;
  // One vertex where only one component is big enough: kept, whole.
  edited.positions[150].x += 0.2e-4f;
  edited.positions[150].z -= 5e-4f;
  const int albedo = base.find_channel("albedo"), roughness = base.find_channel("roughness");
  edited.channels[albedo].values[3 * 5 + 1] += 0.5e-3f;
  edited.channels[albedo].values[3 * 6 + 2] += 5e-3f;
  edited.channels[roughness].values[7] -= 0.4e-3f;
  const Diff d = capture_diff(base, edited);
  ASSERT_EQ(d.positions.size(), 151u);

  Bytes bytes;
  const Diff decoded = round_trip(d, base, o, &bytes);
  EXPECT_NO_THROW(validate(decoded, base, "decoded"));
  std::vector<std::uint32_t> kept;
  for (std::uint32_t v = 100; v <= 150; ++v) kept.push_back(v);
  EXPECT_EQ(decoded.positions.indices, kept);
  EXPECT_EQ(decoded.channels[albedo].change.indices, std::vector<std::uint32_t>{6});
  EXPECT_TRUE(decoded.channels[roughness].change.empty());
  EXPECT_EQ(peek_diff_header(bytes).vertex_count, base.vertex_count());
  check_round_trip(base, d, decoded, o, "zero changes");

  // Nothing survives: still a valid message, of an empty diff.
  Mesh tiny = base;
  for (std::uint32_t v = 0; v < 300; ++v) tiny.positions[v].x -= 0.3e-4f;
  tiny.channels[albedo].values[0] += 1e-4f;
  const Diff none = round_trip(capture_diff(base, tiny), base, o, &bytes);
  EXPECT_EQ(none.touched_vertices(), 0u);
  EXPECT_NO_THROW(validate(none, base, "decoded"));
  EXPECT_LT(bytes.size(), 200u);
}

// ---- size ------------------------------------------------------------------------------------

class WireSize : public ::testing::TestWithParam<Stroke::Kind> {
 protected:
  static void SetUpTestSuite() { base_ = new Mesh(make_sphere(320000)); }
  static void TearDownTestSuite() {
    delete base_;
    base_ = nullptr;
  }
  static Mesh* base_;
};
Mesh* WireSize::base_ = nullptr;

std::string kind_test_name(const ::testing::TestParamInfo<Stroke::Kind>& param) {
  return test::kind_name(param.param);
}

TEST_P(WireSize, TenThousandVertexStrokeFitsInSixtyKilobytes) {
  const Mesh& base = *base_;
  ASSERT_GT(base.face_count(), 310000u);
  Stroke s;
  s.kind = GetParam();
  s.center = base.positions[12345];
  s.radius = 0.5f;  // a cap of ~1/16 of the unit sphere: ~10,000 of its 158,762 vertices
  s.axis = unit(s.center);
  s.strength = s.kind == Stroke::Kind::twist ? 0.5f : 0.15f;
  if (s.kind == Stroke::Kind::grab) s.axis = {0.3f, -0.5f, 0.8f};
  Mesh edited = base;
  apply_stroke(edited, s);
  const Diff d = capture_diff(base, edited);
  ASSERT_GE(d.touched_vertices(), 9000u);
  ASSERT_LE(d.touched_vertices(), 11000u);
  const EncodeOptions o{1e-5, 0, 1e-4};
  Bytes bytes;
  const Diff decoded = round_trip(d, base, o, &bytes);
  EXPECT_LE(bytes.size(), 60000u) << d.touched_vertices() << " vertices";
  std::cout << "[ size ] stroke kind " << static_cast<int>(s.kind) << ": " << d.touched_vertices()
            << " vertices -> " << bytes.size() << " bytes ("
            << double(bytes.size()) / double(d.touched_vertices()) << " per vertex)\n";
  RecordProperty("bytes", static_cast<int>(bytes.size()));
  check_round_trip(base, d, decoded, o, "size");
}

INSTANTIATE_TEST_SUITE_P(Kinds, WireSize,
                         ::testing::Values(Stroke::Kind::grab, Stroke::Kind::inflate,
                                           Stroke::Kind::detail, Stroke::Kind::twist),
                         kind_test_name);

// ---- header
// --------------------------------------------------------------------------------------

TEST(WireHeader, FieldsRoundTrip) {
  const Mesh base = fuzz::base_mesh();
  Mesh edited = base;
  edited.positions[2].x += 0.25f;
  const Diff d = capture_diff(base, edited);
  std::string longest;
  for (int i = 0; i < 256; ++i) longest.push_back(static_cast<char>(1 + i % 255));
  const std::vector<std::string> authors = {"", "alice", "Zoë ✓ 彫刻", longest};
  const std::vector<std::pair<std::uint64_t, std::uint64_t>> versions = {
      {0, 0}, {1, 2}, {std::numeric_limits<std::uint64_t>::max(), 1ull << 63}};
  for (const std::string& author : authors) {
    for (const auto& [base_version, sequence] : versions) {
      DiffHeader h;
      h.base_version = base_version;
      h.sequence = sequence;
      h.author = author;
      const Bytes bytes = encode_diff(d, base, h);
      const DiffHeader peeked = peek_diff_header(bytes);
      DiffHeader decoded;
      decode_diff(bytes, base, &decoded);
      for (const DiffHeader& got : {peeked, decoded}) {
        EXPECT_EQ(got.protocol, wire_protocol_version);
        EXPECT_EQ(got.base_version, base_version);
        EXPECT_EQ(got.sequence, sequence);
        EXPECT_EQ(got.author, author);
        EXPECT_EQ(got.vertex_count, base.vertex_count());
      }
    }
  }
  DiffHeader too_long;
  const std::string author(257, 'a');
  too_long.author = author;
  EXPECT_TRUE(contains(invalid_input_message([&] { encode_diff(d, base, too_long); }),
                       "author is 257 bytes"));
}

TEST(WireEncode, RefusesWhatItCannotEncode) {
  const Mesh base = fuzz::base_mesh();
  Mesh edited = base;
  edited.positions[1].y = 3.f;
  const Diff d = capture_diff(base, edited);
  for (const EncodeOptions& o :
       {EncodeOptions{-1e-5, 0, 1e-4}, EncodeOptions{1e-5, -1, 1e-4},
        EncodeOptions{1e-5, 0, std::nan("")}, EncodeOptions{std::nan(""), 0, 0}})
    EXPECT_TRUE(contains(invalid_input_message([&] { encode_diff(d, base, {}, o); }), ">= 0"));
  Diff wrong = d;
  wrong.vertex_count = 41;
  EXPECT_FALSE(invalid_input_message([&] { encode_diff(wrong, base, {}); }).empty());
  Diff nan = d;
  nan.positions.values[0] = kNaN;
  EXPECT_FALSE(invalid_input_message([&] { encode_diff(nan, base, {}); }).empty());
}

// ---- hostile messages --------------------------------------------------------------------------

Bytes varints(std::initializer_list<std::uint64_t> values) {
  Bytes out;
  for (std::uint64_t v : values) {
    while (v >= 0x80) {
      out.push_back(static_cast<std::uint8_t>(v | 0x80));
      v >>= 7;
    }
    out.push_back(static_cast<std::uint8_t>(v));
  }
  return out;
}
std::uint64_t zigzag(std::int64_t v) {
  return (static_cast<std::uint64_t>(v) << 1) ^ static_cast<std::uint64_t>(v >> 63);
}
Bytes float_bytes(std::initializer_list<float> values) {
  Bytes out(values.size() * sizeof(float));
  std::memcpy(out.data(), std::data(values), out.size());
  return out;
}

struct AttrSpec {
  std::uint32_t count = 0;
  std::optional<Bytes> gaps;
  std::uint8_t coding = 0;  // raw, so that unknown codings can be written
  double step = 0;
  std::optional<Bytes> values;
};
struct ChannelSpec {
  std::string name;
  std::uint32_t width = 1;
  AttrSpec changes;
};
/// A message field by field; the defaults make a valid message for fuzz::base_mesh() that
/// moves vertices 3 and 8 (Float32) and changes metallic of vertex 40 (quantised).
struct MessageSpec {
  std::uint32_t protocol = 1;
  std::uint64_t base_version = 3;
  std::optional<std::string> author = std::string("mallory");
  std::uint64_t sequence = 1;
  std::uint32_t vertex_count = 42;
  std::optional<AttrSpec> positions =
      AttrSpec{2, varints({3, 4}), 0, 0, float_bytes({1, 2, 3, 4, 5, 6})};
  std::optional<std::vector<ChannelSpec>> channels = std::vector<ChannelSpec>{
      {"metallic", 1, AttrSpec{1, varints({40}), 1, 0.125, varints({zigzag(4)})}}};
};

Bytes build(const MessageSpec& s) {
  flatbuffers::FlatBufferBuilder b;
  auto attribute = [&](const AttrSpec& a) {
    const auto gaps =
        a.gaps ? b.CreateVector(*a.gaps) : flatbuffers::Offset<flatbuffers::Vector<std::uint8_t>>();
    const auto values = a.values ? b.CreateVector(*a.values)
                                 : flatbuffers::Offset<flatbuffers::Vector<std::uint8_t>>();
    return fb::CreateAttributeChanges(b, a.count, gaps, static_cast<fb::ValueCoding>(a.coding),
                                      a.step, values);
  };
  flatbuffers::Offset<fb::AttributeChanges> positions;
  if (s.positions) positions = attribute(*s.positions);
  flatbuffers::Offset<flatbuffers::Vector<flatbuffers::Offset<fb::ChannelChanges>>> channels;
  if (s.channels) {
    std::vector<flatbuffers::Offset<fb::ChannelChanges>> list;
    for (const ChannelSpec& c : *s.channels) {
      const auto changes = attribute(c.changes);
      list.push_back(fb::CreateChannelChanges(b, b.CreateString(c.name), c.width, changes));
    }
    channels = b.CreateVector(list);
  }
  flatbuffers::Offset<flatbuffers::String> author;
  if (s.author) author = b.CreateString(*s.author);
  fb::FinishDiffMessageBuffer(
      b, fb::CreateDiffMessage(b, s.protocol, s.base_version, author, s.sequence, s.vertex_count,
                               positions, channels));
  return {b.GetBufferPointer(), b.GetBufferPointer() + b.GetSize()};
}

class WireHostile : public ::testing::Test {
 protected:
  /// decode_diff must refuse with InvalidInput whose message contains `needle`.
  void expect_refused(const Bytes& bytes, const std::string& needle,
                      const DecodeLimits& limits = {}) {
    const std::string m =
        invalid_input_message([&] { decode_diff(bytes, base_, nullptr, limits); });
    EXPECT_TRUE(contains(m, needle))
        << "message: \"" << m << "\"\nexpected to contain: \"" << needle << "\"";
  }
  /// Header-level problems: peek_diff_header refuses them too.
  void expect_refused_by_peek(const Bytes& bytes, const std::string& needle,
                              const DecodeLimits& limits = {}) {
    expect_refused(bytes, needle, limits);
    const std::string m = invalid_input_message([&] { peek_diff_header(bytes, limits); });
    EXPECT_TRUE(contains(m, needle)) << "peek message: \"" << m << "\"";
  }
  void expect_refused(const MessageSpec& s, const std::string& needle) {
    expect_refused(build(s), needle);
  }
  const Mesh base_ = fuzz::base_mesh();
};

TEST_F(WireHostile, TheReferenceMessageIsValid) {
  // Every other test here changes one thing of this message.
  // The header's author points into the bytes: they must outlive it.
  const Bytes bytes = build(MessageSpec{});
  DiffHeader h;
  const Diff d = decode_diff(bytes, base_, &h);
  EXPECT_EQ(h.author, "mallory");
  EXPECT_EQ(d.positions.indices, (std::vector<std::uint32_t>{3, 8}));
  EXPECT_EQ(d.positions.values, (std::vector<float>{1, 2, 3, 4, 5, 6}));
  const auto& metallic = d.channels[base_.find_channel("metallic")].change;
  EXPECT_EQ(metallic.indices, std::vector<std::uint32_t>{40});
  EXPECT_EQ(metallic.values, std::vector<float>{0.5f});  // 0 + 4 x 0.125
  EXPECT_NO_THROW(validate(d, base_, "reference"));
  MessageSpec bare;
  bare.author.reset();
  bare.positions.reset();
  bare.channels.reset();
  const Bytes bare_bytes = build(bare);
  const Diff empty = decode_diff(bare_bytes, base_, &h);
  EXPECT_EQ(empty.touched_vertices(), 0u);
  EXPECT_EQ(h.author, "");
}

TEST_F(WireHostile, EmptyShortAndForeignBuffers) {
  expect_refused_by_peek(Bytes{}, "too short (0 bytes)");
  expect_refused_by_peek(Bytes(7, 0), "too short (7 bytes)");
  Bytes foreign = build(MessageSpec{});
  std::memcpy(foreign.data() + 4, "CSD2", 4);
  expect_refused_by_peek(foreign, "file identifier");
  Bytes zeros(64, 0);
  expect_refused_by_peek(zeros, "file identifier");
  Bytes garbage(64, 0);
  std::memcpy(garbage.data() + 4, "CSD1", 4);  // right identifier, nothing behind it
  expect_refused_by_peek(garbage, "FlatBuffers verification");
}

TEST_F(WireHostile, OverTheSizeLimit) {
  const Bytes bytes = build(MessageSpec{});
  DecodeLimits limits;
  limits.max_bytes = bytes.size() - 1;
  expect_refused_by_peek(bytes, "exceeds the limit of " + std::to_string(bytes.size() - 1), limits);
  limits.max_bytes = bytes.size();
  EXPECT_NO_THROW(decode_diff(bytes, base_, nullptr, limits));
}

TEST_F(WireHostile, ProtocolsThisBuildDoesNotRead) {
  for (const std::uint32_t p : {0u, 2u, 0xffffffffu}) {
    MessageSpec s;
    s.protocol = p;
    expect_refused_by_peek(build(s), "protocol " + std::to_string(p));
  }
}

TEST_F(WireHostile, AuthorTooLongOrWithANul) {
  MessageSpec s;
  s.author = std::string(257, 'x');
  expect_refused_by_peek(build(s), "author is 257 bytes");
  s.author = std::string(256, 'x');
  EXPECT_NO_THROW(decode_diff(build(s), base_));
  s.author = std::string("eve\0il", 6);
  expect_refused_by_peek(build(s), "NUL");
}

TEST_F(WireHostile, VertexCountOfAnotherMesh) {
  MessageSpec s;
  s.vertex_count = 41;
  expect_refused(s, "for 41 vertices but the base mesh has 42");
  s.vertex_count = 0;
  s.positions.reset();
  s.channels.reset();
  expect_refused(s, "for 0 vertices");
}

TEST_F(WireHostile, IndicesOutOfRangeOrInconsistent) {
  MessageSpec s;
  s.positions = AttrSpec{1, varints({42}), 0, 0, float_bytes({1, 2, 3})};
  expect_refused(s, "vertex index 42 out of range (42 vertices)");
  s.positions = AttrSpec{2, varints({40, 1}), 0, 0, float_bytes({1, 2, 3, 4, 5, 6})};
  expect_refused(s, "vertex index 42 out of range");
  s.positions = AttrSpec{1, varints({3, 2}), 0, 0, float_bytes({1, 2, 3})};
  expect_refused(s, "positions: bytes left over after 1 indices");
  s.positions = AttrSpec{43, Bytes(43, 0), 0, 0, Bytes(43 * 12, 0)};
  expect_refused(s, "43 changed vertices but the mesh has 42");
  s.positions = AttrSpec{3, varints({1, 1}), 0, 0, float_bytes({1, 2, 3, 4, 5, 6, 7, 8, 9})};
  expect_refused(s, "3 indices in 2 bytes");
  s.positions = AttrSpec{2, std::nullopt, 0, 0, float_bytes({1, 2, 3, 4, 5, 6})};
  expect_refused(s, "indices missing");
  s.positions = AttrSpec{0, varints({1}), 0, 0, std::nullopt};
  expect_refused(s, "index bytes but no changed vertices");
  // A varint of 11 bytes, and one whose 10th byte carries more than the 64th bit.
  s.positions = AttrSpec{1, Bytes(11, 0xff), 0, 0, float_bytes({1, 2, 3})};
  s.positions->gaps->back() = 0x01;
  expect_refused(s, "positions indices: varint longer than 64 bits");
  Bytes ten(10, 0x80);
  ten.back() = 0x02;
  s.positions = AttrSpec{1, ten, 0, 0, float_bytes({1, 2, 3})};
  expect_refused(s, "varint longer than 64 bits");
  s.positions = AttrSpec{2, Bytes{0x05, 0x80}, 0, 0, float_bytes({1, 2, 3, 4, 5, 6})};
  expect_refused(s, "positions indices: truncated varint");
}

// A gap of 2^64 - 3 after index 5 wraps the 64-bit sum back to index 3: a decoder that adds
// without checking returns indices 5, 3 (not increasing, so the diff fails validate()).
TEST_F(WireHostile, IndexGapsThatWrapAroundAreRefused) {
  MessageSpec s;
  s.positions =
      AttrSpec{2, varints({5, std::uint64_t(0) - 3}), 0, 0, float_bytes({1, 2, 3, 4, 5, 6})};
  const Bytes bytes = build(s);
  const std::string m = invalid_input_message([&] {
    const Diff d = decode_diff(bytes, base_);
    ADD_FAILURE() << "decoded indices " << d.positions.indices[0] << ", " << d.positions.indices[1];
    validate(d, base_, "decoded diff");
  });
  EXPECT_TRUE(contains(m, "diff message positions")) << m;
}

TEST_F(WireHostile, Float32ValuesOfTheWrongSizeOrNotFinite) {
  MessageSpec s;
  s.positions = AttrSpec{2, varints({3, 4}), 0, 0, float_bytes({1, 2, 3, 4, 5})};
  expect_refused(s, "20 value bytes for 2 vertices of width 3 (expected 24)");
  s.positions->values->push_back(0);
  expect_refused(s, "21 value bytes");
  s.positions->values.reset();
  expect_refused(s, "0 value bytes");
  for (const float bad : {kNaN, kInf, -kInf}) {
    s.positions = AttrSpec{2, varints({3, 4}), 0, 0, float_bytes({1, 2, 3, 4, bad, 6})};
    expect_refused(s, "value of vertex 8 is not finite");
  }
  s.positions.reset();
  s.channels = {{"tint", 4, AttrSpec{1, varints({9}), 0, 0, float_bytes({0, 1, kNaN, 3})}}};
  expect_refused(s, "channel 'tint': value of vertex 9 is not finite");
}

TEST_F(WireHostile, QuantisedValuesThatCannotBeRead) {
  MessageSpec s;
  auto quantised = [](double step, Bytes values, std::uint8_t coding = 1) {
    return AttrSpec{2, varints({3, 4}), coding, step, std::move(values)};
  };
  const Bytes six = varints({1, 2, 3, 4, 5, 6});
  for (const double step : {0.0, -0.5, std::nan(""), std::numeric_limits<double>::infinity()}) {
    s.positions = quantised(step, six);
    expect_refused(s, "quantisation step");
    s.positions = quantised(step, six, 2);
    expect_refused(s, "quantisation step");
  }
  s.positions = quantised(0.5, varints({1, 2, 3, 4, 5}));
  expect_refused(s, "6 values in 5 bytes");
  s.positions = quantised(0.5, Bytes{1, 2, 3, 4, 5, 0x80});
  expect_refused(s, "positions values: truncated varint");
  s.positions = quantised(0.5, varints({1, 2, 3, 4, 5, 6, 7}));
  expect_refused(s, "positions: bytes left over after 6 values");
  Bytes overflow = varints({1, 2, 3, 4, 5});
  overflow.insert(overflow.end(), 10, 0xff);
  overflow.push_back(0x01);
  s.positions = quantised(0.5, overflow);
  expect_refused(s, "positions values: varint longer than 64 bits");
  // Finite steps and numbers whose product is not finite, or not a float.
  s.positions = quantised(1e300, varints({zigzag(1), zigzag(-1), zigzag(1), 0, 0, 0}));
  expect_refused(s, "is not finite");
  s.positions = quantised(1e35, varints({zigzag(1) << 20, 0, 0, 0, 0, 0}));
  expect_refused(s, "value of vertex 3 is not finite");
  // Predicted: the running sum overflows int64 (wraps) and still must not reach a float.
  s.positions = quantised(1e20,
                          varints({zigzag(std::numeric_limits<std::int64_t>::max()),
                                   zigzag(std::numeric_limits<std::int64_t>::max()), 0, 0, 0, 0}),
                          2);
  expect_refused(s, "is not finite");
  // No changed vertices but value bytes.
  s.positions = AttrSpec{0, std::nullopt, 1, 0.5, varints({1})};
  expect_refused(s, "positions: bytes left over after 0 values");
}

TEST_F(WireHostile, UnknownValueCodings) {
  for (const std::uint8_t coding : {std::uint8_t{3}, std::uint8_t{7}, std::uint8_t{255}}) {
    MessageSpec s;
    s.positions->coding = coding;
    expect_refused(s, "positions: unknown value coding " + std::to_string(coding));
  }
}

TEST_F(WireHostile, ChannelsThatDoNotFitTheBase) {
  MessageSpec s;
  s.channels = {{"bogus", 1, AttrSpec{1, varints({2}), 0, 0, float_bytes({1})}}};
  expect_refused(s, "channel 'bogus' does not exist in the base mesh");
  s.channels = {{"metallic", 1, AttrSpec{1, varints({2}), 0, 0, float_bytes({1})}},
                {"metallic", 1, AttrSpec{1, varints({3}), 0, 0, float_bytes({1})}}};
  expect_refused(s, "channel 'metallic' appears twice");
  s.channels = {{"albedo", 2, AttrSpec{1, varints({2}), 0, 0, float_bytes({1, 1})}}};
  expect_refused(s, "channel 'albedo' has width 2 but the base's has 3");
  s.channels = {{"albedo", 3, AttrSpec{1, varints({50}), 0, 0, float_bytes({1, 1, 1})}}};
  expect_refused(s, "channel 'albedo': vertex index");
  s.channels = {{"", 1, AttrSpec{}}};
  expect_refused(s, "channel '' does not exist");
  // More channels than the base has.
  s.channels = {{"albedo", 3, AttrSpec{}},
                {"metallic", 1, AttrSpec{}},
                {"roughness", 1, AttrSpec{}},
                {"tint", 4, AttrSpec{}},
                {"extra", 1, AttrSpec{}}};
  expect_refused(s, "5 channels");
  Mesh bare = base_;
  bare.channels.clear();
  MessageSpec one;
  const std::string m = invalid_input_message([&] { decode_diff(build(one), bare); });
  EXPECT_TRUE(contains(m, "1 channels; the base mesh has 0")) << m;
}

/// "c0", "c1", ...: built by appending, because GCC 12 at -O3 (the plain Release build) warns
/// falsely (-Wrestrict) on "c" + std::to_string(i).
std::string channel_name(int i) {
  std::string name = "c";
  name += std::to_string(i);
  return name;
}

Mesh mesh_with_channels(int count) {
  Mesh many = fuzz::base_mesh();
  many.channels.clear();
  for (int i = 0; i < count; ++i) {
    ChannelDesc c;
    c.name = channel_name(i);
    many.add_channel(c);
  }
  return many;
}

MessageSpec message_with_channels(int count) {
  MessageSpec s;
  s.channels.emplace();
  for (int i = 0; i < count; ++i) s.channels->push_back({channel_name(i), 1, AttrSpec{}});
  return s;
}

// DecodeLimits::max_channels bounds what a message may carry, whatever the base has.
TEST_F(WireHostile, MoreChannelsThanTheLimitAreRefused) {
  const Mesh many = mesh_with_channels(120);
  EXPECT_NO_THROW(decode_diff(build(message_with_channels(64)), many));
  for (const int count : {65, 100})
    EXPECT_FALSE(invalid_input_message([&] {
                   decode_diff(build(message_with_channels(count)), many);
                 }).empty());
  MessageSpec s = message_with_channels(3);
  const Mesh three = mesh_with_channels(3);
  DecodeLimits limits;
  limits.max_channels = 2;
  EXPECT_FALSE(
      invalid_input_message([&] { decode_diff(build(s), three, nullptr, limits); }).empty());
  limits.max_channels = 3;
  EXPECT_NO_THROW(decode_diff(build(s), three, nullptr, limits));
}

// The refusal names the problem: the count and the limit (not the base's channel count, nor
// "corrupt or truncated" for a well-formed message).
TEST_F(WireHostile, MoreChannelsThanTheLimitNamesTheLimit) {
  const Mesh many = mesh_with_channels(120);
  for (const int count : {65, 100}) {
    const std::string m =
        invalid_input_message([&] { decode_diff(build(message_with_channels(count)), many); });
    EXPECT_TRUE(contains(m, std::to_string(count) + " channels") && contains(m, "64"))
        << count << " channels, default limit 64: \"" << m << "\"";
  }
  DecodeLimits limits;
  limits.max_channels = 2;
  const std::string m = invalid_input_message([&] {
    decode_diff(build(message_with_channels(3)), mesh_with_channels(3), nullptr, limits);
  });
  EXPECT_TRUE(contains(m, "3 channels") && contains(m, "2")) << "limit 2: \"" << m << "\"";
}

/// Valid messages of several shapes, from the encoder and by hand.
std::vector<Bytes> sample_messages(const Mesh& base) {
  std::vector<Bytes> out;
  out.push_back(build(MessageSpec{}));
  Mesh edited = base;
  Stroke grab;
  grab.center = base.positions[0];
  grab.radius = 0.9f;
  apply_stroke(edited, grab);
  Stroke paint;
  paint.kind = Stroke::Kind::paint;
  paint.center = base.positions[20];
  paint.radius = 0.8f;
  paint.strength = 0.7f;
  apply_stroke(edited, paint);
  edited.channels[3].values[4 * 11 + 2] = 9.f;
  const Diff d = capture_diff(base, edited);
  DiffHeader h;
  h.author = "sample";
  out.push_back(encode_diff(d, base, h));
  out.push_back(encode_diff(d, base, h, EncodeOptions{0, 0, 0}));
  out.push_back(encode_diff(d, base, h, EncodeOptions{1e-3, 0, 0}));
  return out;
}

TEST_F(WireHostile, EveryTruncationIsRefused) {
  for (const Bytes& full : sample_messages(base_)) {
    const Diff whole = decode_diff(full, base_);
    for (std::size_t n = 0; n < full.size(); ++n) {
      const Bytes cut(full.begin(), full.begin() + static_cast<std::ptrdiff_t>(n));
      try {
        const Diff d = decode_diff(cut, base_);
        // Only alignment padding may go: the bytes cut are all zero and nothing changed.
        EXPECT_TRUE(std::all_of(full.begin() + static_cast<std::ptrdiff_t>(n), full.end(),
                                [](std::uint8_t b) { return b == 0; }))
            << "truncated to " << n << " of " << full.size() << " bytes and accepted";
        EXPECT_TRUE(same_bits(d, whole)) << n;
      } catch (const InvalidInput& e) {
        EXPECT_TRUE(contains(e.what(), "diff message")) << e.what();
      }
    }
  }
}

TEST_F(WireHostile, SingleByteFlipsNeverCrash) {
  std::size_t refused = 0, accepted = 0;
  for (const Bytes& full : sample_messages(base_)) {
    for (std::size_t i = 0; i < full.size(); ++i) {
      for (const int mask : {0x01, 0x02, 0x10, 0x40, 0x80, 0xff}) {
        Bytes flipped = full;
        flipped[i] = static_cast<std::uint8_t>(flipped[i] ^ mask);
        bool peeked = true;
        try {
          peek_diff_header(flipped);
        } catch (const InvalidInput&) {
          peeked = false;
        }
        try {
          const Diff d = decode_diff(flipped, base_);
          ++accepted;
          EXPECT_TRUE(peeked) << "decoded but peek refused: byte " << i;
          EXPECT_NO_THROW(validate(d, base_, "flipped")) << "byte " << i << " mask " << mask;
          // A decoded diff is always one the encoder can send on.
          EXPECT_NO_THROW(decode_diff(encode_diff(d, base_, {}), base_));
        } catch (const InvalidInput& e) {
          ++refused;
          EXPECT_TRUE(contains(e.what(), "diff message")) << e.what();
        }
      }
    }
  }
  EXPECT_GT(refused, 0u);
  EXPECT_GT(accepted, 0u);  // flips inside values and header numbers are still messages
}

// ---- schema evolution --------------------------------------------------------------------------

TEST(WireSchemaEvolution, MessagesOfANewerSchemaWithAppendedFieldsDecode) {
  const Mesh base = fuzz::base_mesh();
  flatbuffers::FlatBufferBuilder b;
  const Bytes gaps = varints({3, 4});
  const Bytes values = float_bytes({1, 2, 3, 4, 5, 6});
  const std::vector<float> hint{0, 0, 1};
  const auto positions =
      fbn::CreateAttributeChanges(b, 2, b.CreateVector(gaps), fbn::ValueCoding::Float32, 0,
                                  b.CreateVector(values), /*flags=*/0xabcd, b.CreateVector(hint));
  const Bytes channel_gaps = varints({40});
  const Bytes channel_values = varints({zigzag(4)});
  const auto metallic_changes = fbn::CreateAttributeChanges(
      b, 1, b.CreateVector(channel_gaps), fbn::ValueCoding::QuantisedDeltaPredicted, 0.125,
      b.CreateVector(channel_values), 7);
  const auto metallic = fbn::CreateChannelChanges(b, b.CreateString("metallic"), 1,
                                                  metallic_changes, b.CreateString("brushed"));
  const std::vector<flatbuffers::Offset<fbn::Annotation>> notes = {
      fbn::CreateAnnotation(b, b.CreateString("tool"), b.CreateString("clay"))};
  const Bytes signature(64, 0x5a);
  const auto message = fbn::CreateDiffMessage(
      b, 1, 12, b.CreateString("future"), 99, 42, positions,
      b.CreateVector(std::vector<flatbuffers::Offset<fbn::ChannelChanges>>{metallic}),
      /*timestamp_ns=*/1700000000000000000ull, b.CreateVector(notes), b.CreateVector(signature));
  fbn::FinishDiffMessageBuffer(b, message);
  const Bytes bytes(b.GetBufferPointer(), b.GetBufferPointer() + b.GetSize());

  DiffHeader h;
  const Diff d = decode_diff(bytes, base, &h);
  EXPECT_EQ(h.base_version, 12u);
  EXPECT_EQ(h.sequence, 99u);
  EXPECT_EQ(h.author, "future");
  EXPECT_EQ(peek_diff_header(bytes).author, "future");
  EXPECT_EQ(d.positions.indices, (std::vector<std::uint32_t>{3, 8}));
  EXPECT_EQ(d.positions.values, (std::vector<float>{1, 2, 3, 4, 5, 6}));
  const auto& m = d.channels[base.find_channel("metallic")].change;
  EXPECT_EQ(m.indices, std::vector<std::uint32_t>{40});
  EXPECT_EQ(m.values, std::vector<float>{0.5f});
  EXPECT_NO_THROW(validate(d, base, "newer"));

  // And the other way: what this build writes is a valid message for the newer reader, which
  // sees its new fields at their defaults.
  Mesh edited = base;
  edited.positions[5].z += 0.1f;
  const Bytes ours = encode_diff(capture_diff(base, edited), base, DiffHeader{1, 4, 5, "old", 42});
  flatbuffers::Verifier verifier(ours.data(), ours.size());
  ASSERT_TRUE(fbn::VerifyDiffMessageBuffer(verifier));
  const fbn::DiffMessage* newer = fbn::GetDiffMessage(ours.data());
  EXPECT_EQ(newer->base_version(), 4u);
  EXPECT_EQ(newer->timestamp_ns(), 0u);
  EXPECT_EQ(newer->annotations(), nullptr);
  EXPECT_EQ(newer->positions()->count(), 1u);
  EXPECT_EQ(newer->positions()->flags(), 0u);
}

// ---- the wire fuzzers' seed corpus -------------------------------------------------------------

/// Real messages for fuzz::base_mesh(), one per shape the decoder distinguishes: quantised
/// plain and predicted positions, lossless positions, channels of widths 1, 3 and 4 quantised
/// and lossless, an empty diff and a full header.
std::vector<std::pair<std::string, Bytes>> wire_seeds() {
  const Mesh base = fuzz::base_mesh();
  DiffHeader h;
  h.base_version = fuzz::base_version;
  h.sequence = 1;
  h.author = "seed";
  std::vector<std::pair<std::string, Bytes>> seeds;
  auto add = [&](const std::string& name, const Mesh& edited, const EncodeOptions& o) {
    seeds.emplace_back(name, encode_diff(capture_diff(base, edited), base, h, o));
  };
  Mesh grab = base;
  Stroke g;
  g.center = base.positions[0];
  g.radius = 1.2f;
  g.strength = 0.2f;
  apply_stroke(grab, g);
  add("grab_quantised.csd", grab, {});
  add("grab_lossless.csd", grab, EncodeOptions{0, 0, 0});
  Mesh detail = base;
  Stroke dt;
  dt.kind = Stroke::Kind::detail;
  dt.center = base.positions[30];
  dt.radius = 1.5f;
  dt.strength = 0.3f;
  dt.frequency = 30.f;
  apply_stroke(detail, dt);
  add("detail_coarse.csd", detail, EncodeOptions{1e-3, 0, 1e-4});
  Mesh paint = base;
  Stroke p;
  p.kind = Stroke::Kind::paint;
  p.center = base.positions[10];
  p.radius = 1.0f;
  p.strength = 0.8f;
  apply_stroke(paint, p);
  add("paint_quantised.csd", paint, {});
  add("paint_lossless_positions_quantised_channels.csd", paint, EncodeOptions{0, 0, 1e-3});
  Mesh tint = grab;
  const int t = base.find_channel("tint");
  for (std::size_t v = 0; v < base.vertex_count(); v += 3)
    for (std::size_t c = 0; c < 4; ++c)
      tint.channels[t].values[4 * v + c] += 0.01f * static_cast<float>(v + c);
  add("tint_width4.csd", tint, EncodeOptions{1e-4, 0, 1e-3});
  add("tint_width4_lossless.csd", tint, EncodeOptions{0, 0, 0});
  h.author = "";
  add("empty.csd", base, {});
  std::string author;
  for (int i = 0; i < 256; ++i) author.push_back(static_cast<char>('a' + i % 26));
  h.author = author;
  h.sequence = std::numeric_limits<std::uint64_t>::max();
  Mesh one = base;
  one.positions[41] = {0.5f, -0.25f, 2.f};
  add("one_vertex_long_author.csd", one, {});
  return seeds;
}

TEST(WireFuzzCorpus, SeedsAreRealMessagesForTheFuzzBase) {
  if (const char* dir = std::getenv("CSCULPT_WRITE_WIRE_CORPUS")) {
    fs::create_directories(dir);
    for (const auto& [name, bytes] : wire_seeds()) {
      std::ofstream out(fs::path(dir) / name, std::ios::binary);
      out.write(reinterpret_cast<const char*>(bytes.data()),
                static_cast<std::streamsize>(bytes.size()));
    }
  }
  // The seeds must cover every coding and channel width the decoder handles.
  std::set<fb::ValueCoding> codings;
  std::set<std::uint32_t> widths;
  for (const auto& [name, bytes] : wire_seeds()) {
    const fb::DiffMessage* m = fb::GetDiffMessage(bytes.data());
    if (m->positions() && m->positions()->count()) codings.insert(m->positions()->coding());
    if (m->channels())
      for (const fb::ChannelChanges* c : *m->channels()) {
        codings.insert(c->changes()->coding());
        widths.insert(c->width());
      }
  }
  EXPECT_EQ(codings.size(), 3u);
  EXPECT_EQ(widths, (std::set<std::uint32_t>{1, 3, 4}));

  // What is committed: small real messages that decode against the fuzzers' base, at the
  // version csc_diff_decode is given.
  const Mesh base = fuzz::base_mesh();
  std::size_t files = 0;
  for (const auto& entry : fs::directory_iterator(CSCULPT_WIRE_CORPUS)) {
    if (entry.path().extension() != ".csd") continue;
    ++files;
    std::ifstream in(entry.path(), std::ios::binary);
    const Bytes bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    EXPECT_LT(bytes.size(), 20000u) << entry.path();
    DiffHeader h;
    EXPECT_NO_THROW(decode_diff(bytes, base, &h)) << entry.path();
    EXPECT_EQ(h.base_version, fuzz::base_version) << entry.path();
  }
  EXPECT_GE(files, wire_seeds().size());
}

}  // namespace
}  // namespace csculpt
