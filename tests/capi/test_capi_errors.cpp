// Every function of csculpt.h with bad arguments and bad data, through libcsculpt.so only (no
// SDK header): the specific status, a message naming the problem, out-parameters untouched,
// no crash (and, in the ASan build, no memory error or leak). Then positive behaviour a host
// relies on: accessors, file round trips, order-independent merges, in-place apply, threads.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "csculpt.h"
#include "host_arrays.h"

namespace {

namespace fs = std::filesystem;

const fs::path kModels = CSCULPT_TEST_MODELS;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

// ---- owning wrappers -----------------------------------------------------------------------

struct Destroy {
  void operator()(csc_mesh* p) const { csc_mesh_destroy(p); }
  void operator()(csc_hierarchy* p) const { csc_hierarchy_destroy(p); }
  void operator()(csc_diff* p) const { csc_diff_destroy(p); }
  void operator()(csc_merger* p) const { csc_merger_destroy(p); }
  void operator()(csc_bytes* p) const { csc_bytes_destroy(p); }
};
using MeshPtr = std::unique_ptr<csc_mesh, Destroy>;
using HierarchyPtr = std::unique_ptr<csc_hierarchy, Destroy>;
using DiffPtr = std::unique_ptr<csc_diff, Destroy>;
using MergerPtr = std::unique_ptr<csc_merger, Destroy>;
using BytesPtr = std::unique_ptr<csc_bytes, Destroy>;

/// A handle of another kind, as a confused host would pass it.
template <class To, class From>
To* foreign(From* handle) {
  return reinterpret_cast<To*>(handle);
}

/// A pointer value no call may write into an out-parameter on failure.
template <class T>
T* sentinel() {
  static char storage;
  return reinterpret_cast<T*>(&storage);
}

// ---- error expectations --------------------------------------------------------------------

constexpr const char* kMarker = "csculpt-error-marker";

/// Leaves a known message behind, so a later check sees the failing call's own message.
void mark_error() {
  csc_mesh* m = nullptr;
  const std::string path = std::string("/nonexistent/") + kMarker + ".ply";
  ASSERT_EQ(csc_mesh_read(&m, path.c_str()), CSC_ERROR_IO);
  ASSERT_NE(std::strstr(csc_last_error(), kMarker), nullptr);
}

::testing::AssertionResult fails_with(const char* call, csc_status got, csc_status want,
                                      const char* keyword) {
  const std::string message = csc_last_error();
  if (got != want)
    return ::testing::AssertionFailure()
           << call << " gave " << csc_status_str(got) << " (" << got << "), expected "
           << csc_status_str(want) << "; message: " << message;
  if (message.empty() || message.find(kMarker) != std::string::npos)
    return ::testing::AssertionFailure()
           << call << " set no message of its own: '" << message << "'";
  if (message.find(keyword) == std::string::npos)
    return ::testing::AssertionFailure()
           << call << ": message '" << message << "' does not mention '" << keyword << "'";
  return ::testing::AssertionSuccess();
}

#define EXPECT_FAILS(call, status, keyword)                \
  do {                                                     \
    mark_error();                                          \
    const csc_status got_ = (call);                        \
    EXPECT_TRUE(fails_with(#call, got_, status, keyword)); \
  } while (0)

#define ASSERT_OK(call)                                                                           \
  do {                                                                                            \
    const csc_status got_ = (call);                                                               \
    ASSERT_EQ(got_, CSC_OK) << #call << ": " << csc_status_str(got_) << ": " << csc_last_error(); \
  } while (0)

// ---- meshes made here ----------------------------------------------------------------------

/// An n x n grid over [0,1]^2 with a wave in z, and two channels: "mask" (width 1, identity,
/// [0,1]) and "tint" (width 3, sRGB, [0,1]). Owns the arrays its csc_mesh_desc points into.
struct Grid {
  explicit Grid(std::uint32_t size, bool with_channels = true) : n(size) {
    for (std::uint32_t j = 0; j < n; ++j)
      for (std::uint32_t i = 0; i < n; ++i) {
        const float x = static_cast<float>(i) / static_cast<float>(n - 1);
        const float y = static_cast<float>(j) / static_cast<float>(n - 1);
        positions.insert(positions.end(), {x, y, 0.1f * std::sin(6.f * x) * std::cos(5.f * y)});
        mask.push_back(x * y);
        tint.insert(tint.end(), {x, 0.5f, 1.f - y});
      }
    for (std::uint32_t j = 0; j + 1 < n; ++j)
      for (std::uint32_t i = 0; i + 1 < n; ++i) {
        const std::uint32_t a = j * n + i, b = a + 1, c = a + n, d = c + 1;
        triangles.insert(triangles.end(), {a, b, d, a, d, c});
      }
    if (with_channels) {
      channels = {{"mask", 1, CSC_LINEARISATION_IDENTITY, 0.f, 1.f},
                  {"tint", 3, CSC_LINEARISATION_SRGB, 0.f, 1.f}};
      values = {mask.data(), tint.data()};
    }
  }
  std::uint32_t vertex_count() const { return n * n; }
  csc_mesh_desc desc() const {
    csc_mesh_desc d = CSC_MESH_DESC_INIT;
    d.vertex_count = vertex_count();
    d.positions = positions.data();
    d.triangle_count = static_cast<std::uint32_t>(triangles.size() / 3);
    d.triangles = triangles.data();
    d.channel_count = static_cast<std::uint32_t>(channels.size());
    d.channels = channels.empty() ? nullptr : channels.data();
    d.channel_values = values.empty() ? nullptr : values.data();
    return d;
  }
  MeshPtr make() const {
    csc_mesh* m = nullptr;
    const csc_mesh_desc d = desc();
    const csc_status s = csc_mesh_create(&m, &d);
    EXPECT_EQ(s, CSC_OK) << csc_last_error();
    return MeshPtr(m);
  }

  std::uint32_t n;
  std::vector<float> positions, mask, tint;
  std::vector<std::uint32_t> triangles;
  std::vector<csc_channel_desc> channels;
  std::vector<const float*> values;
};

/// Moves the vertices within `radius` of (cx, cy) by `offset` scaled by a falloff, and paints
/// channel `paint_channel` (if >= 0) there towards `colour`.
void brush(HostArrays& h, std::uint32_t n, float cx, float cy, float radius,
           std::array<float, 3> offset, int paint_channel = -1, float colour = 0.9f) {
  for (std::uint32_t v = 0; v < n * n; ++v) {
    float* p = &h.positions[3 * v];
    const float dx = p[0] - cx, dy = p[1] - cy;
    const float t = 1.f - (dx * dx + dy * dy) / (radius * radius);
    if (t <= 0.f) continue;
    const float w = t * t;
    for (int k = 0; k < 3; ++k) p[k] += w * offset[k];
    if (paint_channel >= 0) {
      const std::uint32_t width = h.widths[paint_channel];
      float* c = &h.channels[paint_channel][std::size_t{width} * v];
      for (std::uint32_t k = 0; k < width; ++k) c[k] += (colour - c[k]) * w;
    }
  }
}

DiffPtr capture(const csc_mesh* base, HostArrays& h) {
  csc_diff* d = nullptr;
  const csc_vertex_arrays a = h.arrays();
  const csc_status s = csc_diff_capture_arrays(&d, base, &a);
  EXPECT_EQ(s, CSC_OK) << csc_last_error();
  return DiffPtr(d);
}

BytesPtr encode(const csc_diff* diff, const csc_mesh* base, std::uint64_t version = 3,
                const char* author = "ann") {
  csc_encode_options o = CSC_ENCODE_OPTIONS_INIT;
  o.base_version = version;
  o.sequence = 11;
  o.author = author;
  csc_bytes* b = nullptr;
  const csc_status s = csc_diff_encode(&b, diff, base, &o);
  EXPECT_EQ(s, CSC_OK) << csc_last_error();
  return BytesPtr(b);
}

std::vector<std::uint8_t> to_vector(const csc_bytes* b) {
  return {csc_bytes_data(b), csc_bytes_data(b) + csc_bytes_size(b)};
}

/// Every array of a diff, for bitwise comparison.
struct DiffContent {
  std::vector<std::uint32_t> indices;
  std::vector<float> values;
  std::vector<std::string> channel_names;
  std::vector<std::vector<std::uint32_t>> channel_indices;
  std::vector<std::vector<float>> channel_values;
  bool operator==(const DiffContent& o) const {
    return indices == o.indices && channel_names == o.channel_names &&
           channel_indices == o.channel_indices && values.size() == o.values.size() &&
           std::memcmp(values.data(), o.values.data(), values.size() * 4) == 0 &&
           std::equal(channel_values.begin(), channel_values.end(), o.channel_values.begin(),
                      o.channel_values.end(), [](const auto& a, const auto& b) {
                        return a.size() == b.size() &&
                               std::memcmp(a.data(), b.data(), a.size() * 4) == 0;
                      });
  }
};

DiffContent content(const csc_diff* d) {
  DiffContent c;
  const std::uint32_t* idx = nullptr;
  const float* val = nullptr;
  std::uint32_t count = 0;
  EXPECT_EQ(csc_diff_positions(d, &idx, &val, &count), CSC_OK);
  c.indices.assign(idx, idx + count);
  c.values.assign(val, val + 3 * count);
  csc_diff_info info = CSC_DIFF_INFO_INIT;
  EXPECT_EQ(csc_diff_get_info(d, &info), CSC_OK);
  for (std::uint32_t k = 0; k < info.channel_count; ++k) {
    const char* name = nullptr;
    std::uint32_t width = 0;
    EXPECT_EQ(csc_diff_channel(d, k, &name, &width, &idx, &val, &count), CSC_OK);
    c.channel_names.emplace_back(name);
    c.channel_indices.emplace_back(idx, idx + count);
    c.channel_values.emplace_back(val, val + std::size_t{width} * count);
  }
  return c;
}

// ---- a fixture with one of every handle ----------------------------------------------------

class Capi : public ::testing::Test {
 protected:
  static constexpr std::uint32_t kN = 12;
  void SetUp() override {
    grid = std::make_unique<Grid>(kN);
    mesh = grid->make();
    ASSERT_TRUE(mesh);
    csc_hierarchy* h = nullptr;
    ASSERT_OK(csc_hierarchy_build(&h, mesh.get(), nullptr));
    hierarchy.reset(h);
    csc_merger* m = nullptr;
    ASSERT_OK(csc_merger_create(&m, hierarchy.get()));
    merger.reset(m);
    host = std::make_unique<HostArrays>(mesh.get());
    HostArrays edit(*host);
    brush(edit, kN, 0.3f, 0.4f, 0.3f, {0.f, 0.f, 0.1f}, 1);
    diff = capture(mesh.get(), edit);
    ASSERT_TRUE(diff);
    bytes = encode(diff.get(), mesh.get());
    ASSERT_TRUE(bytes);
  }

  std::unique_ptr<Grid> grid;
  MeshPtr mesh;
  HierarchyPtr hierarchy;
  MergerPtr merger;
  DiffPtr diff;
  BytesPtr bytes;
  std::unique_ptr<HostArrays> host;
};

// ==== version, status, last error ==========================================================

TEST(CapiVersion, MatchesTheHeader) {
  EXPECT_EQ(csc_version(), static_cast<std::uint32_t>(CSC_VERSION_NUMBER));
  EXPECT_STREQ(csc_version_string(), CSC_VERSION_STRING);
  EXPECT_GE(csc_wire_protocol_version(), 1u);
}

// Unknown enum values stay within the enums' declared range (0 .. 0x7FFFFFFF): a negative one
// would be undefined behaviour in this C++ test itself (and UBSan's enum check says so).
TEST(CapiStatus, EveryStatusHasItsOwnTextAndUnknownValuesSaySo) {
  const std::vector<std::pair<csc_status, const char*>> known = {
      {CSC_OK, "ok"},
      {CSC_ERROR_INVALID_ARGUMENT, "argument"},
      {CSC_ERROR_INVALID_INPUT, "input"},
      {CSC_ERROR_IO, "output"},
      {CSC_ERROR_UNKNOWN_BASE_VERSION, "base version"},
      {CSC_ERROR_OUT_OF_MEMORY, "memory"},
      {CSC_ERROR_INTERNAL, "internal"}};
  std::vector<std::string> seen;
  for (const auto& [status, keyword] : known) {
    const char* s = csc_status_str(status);
    ASSERT_NE(s, nullptr);
    EXPECT_NE(std::string(s).find(keyword), std::string::npos) << s;
    EXPECT_STRNE(s, "unknown status");
    seen.emplace_back(s);
  }
  std::sort(seen.begin(), seen.end());
  EXPECT_EQ(std::unique(seen.begin(), seen.end()), seen.end()) << "two statuses share a text";
  for (std::int64_t unknown : {7LL, 99LL, 0x7FFFFFFFLL})
    EXPECT_STREQ(csc_status_str(static_cast<csc_status>(unknown)), "unknown status") << unknown;
}

TEST(CapiLastError, IsEmptyOnAFreshThreadAndThreadLocal) {
  std::string fresh = "not run";
  std::thread([&] { fresh = csc_last_error(); }).join();
  EXPECT_EQ(fresh, "");

  EXPECT_EQ(csc_mesh_create(nullptr, nullptr), CSC_ERROR_INVALID_ARGUMENT);
  const char* mine = csc_last_error();
  const std::string before = mine;
  ASSERT_NE(before.find("out"), std::string::npos) << before;

  std::string other_before, other_after;
  csc_status other_status = CSC_OK;
  std::thread([&] {
    other_before = csc_last_error();
    csc_mesh* m = nullptr;
    other_status = csc_mesh_read(&m, "/nonexistent/on-another-thread.ply");
    other_after = csc_last_error();
  }).join();
  EXPECT_EQ(other_before, "") << "the other thread saw this thread's message";
  EXPECT_EQ(other_status, CSC_ERROR_IO);
  EXPECT_NE(other_after.find("on-another-thread"), std::string::npos) << other_after;
  EXPECT_EQ(std::string(csc_last_error()), before) << "another thread's failure changed it";
  EXPECT_EQ(csc_last_error(), mine) << "the pointer moved without a failure on this thread";
}

TEST(CapiLastError, ASuccessfulCallKeepsTheLastFailure) {
  EXPECT_EQ(csc_mesh_create(nullptr, nullptr), CSC_ERROR_INVALID_ARGUMENT);
  const std::string before = csc_last_error();
  Grid g(3);
  MeshPtr m = g.make();
  EXPECT_EQ(std::string(csc_last_error()), before);
}

// ==== meshes: creation =====================================================================

TEST(CapiMeshCreate, NullAndStructSize) {
  Grid g(4);
  csc_mesh_desc d = g.desc();
  csc_mesh* out = sentinel<csc_mesh>();
  EXPECT_FAILS(csc_mesh_create(nullptr, &d), CSC_ERROR_INVALID_ARGUMENT, "out");
  EXPECT_FAILS(csc_mesh_create(&out, nullptr), CSC_ERROR_INVALID_ARGUMENT, "desc");
  for (std::uint32_t size : {0u, 4u, static_cast<std::uint32_t>(sizeof(csc_mesh_desc) - 1)}) {
    d.struct_size = size;
    EXPECT_FAILS(csc_mesh_create(&out, &d), CSC_ERROR_INVALID_ARGUMENT, "struct_size");
  }
  d = g.desc();
  d.positions = nullptr;
  EXPECT_FAILS(csc_mesh_create(&out, &d), CSC_ERROR_INVALID_ARGUMENT, "positions");
  d = g.desc();
  d.triangles = nullptr;
  EXPECT_FAILS(csc_mesh_create(&out, &d), CSC_ERROR_INVALID_ARGUMENT, "triangles");
  d = g.desc();
  d.channels = nullptr;
  EXPECT_FAILS(csc_mesh_create(&out, &d), CSC_ERROR_INVALID_ARGUMENT, "channels");
  d = g.desc();
  d.channel_count = 257;
  EXPECT_FAILS(csc_mesh_create(&out, &d), CSC_ERROR_INVALID_ARGUMENT, "channel_count");
  g.channels[1].name = nullptr;
  d = g.desc();
  EXPECT_FAILS(csc_mesh_create(&out, &d), CSC_ERROR_INVALID_ARGUMENT, "name");
  EXPECT_EQ(out, sentinel<csc_mesh>());
}

TEST(CapiMeshCreate, InvalidMeshesAreInvalidInput) {
  csc_mesh* out = sentinel<csc_mesh>();
  auto expect_invalid = [&](const Grid& g, const char* keyword) {
    const csc_mesh_desc d = g.desc();
    EXPECT_FAILS(csc_mesh_create(&out, &d), CSC_ERROR_INVALID_INPUT, keyword);
    EXPECT_EQ(out, sentinel<csc_mesh>());
  };
  {
    Grid g(4);
    g.positions.clear();  // no vertices (vertex_count 0, positions NULL allowed then)
    g.mask.clear();
    g.n = 0;
    expect_invalid(g, "no vertices");
  }
  {
    Grid g(4);
    g.triangles.clear();
    expect_invalid(g, "no faces");
  }
  {
    Grid g(4);
    g.triangles[7] = 16;  // one past the last vertex
    expect_invalid(g, "out of range");
  }
  {
    Grid g(4);
    g.triangles[4] = g.triangles[3];
    expect_invalid(g, "repeats vertex");
  }
  {
    Grid g(4);
    g.positions[5] = kNaN;
    expect_invalid(g, "NaN");
  }
  {
    Grid g(4);
    g.positions[9] = -kInf;
    expect_invalid(g, "vertex 3");
  }
  {
    Grid g(4);
    g.tint[4] = kInf;
    expect_invalid(g, "tint");
  }
  for (std::uint32_t width : {0u, 5u, 1000u}) {
    Grid g(4);
    g.channels[0].width = width;
    expect_invalid(g, "width");
  }
  {
    Grid g(4);
    g.channels[1].name = "mask";
    expect_invalid(g, "twice");
  }
  {
    Grid g(4);
    g.channels[1].name = "";
    expect_invalid(g, "name");
  }
  {
    Grid g(4);
    const std::string long_name(256, 'n');
    g.channels[1].name = long_name.c_str();
    expect_invalid(g, "255");
  }
  {
    Grid g(4);
    g.channels[0].min_value = 2.f;
    expect_invalid(g, "min_value");
  }
  {
    Grid g(4);
    g.channels[0].max_value = kNaN;
    expect_invalid(g, "min_value");
  }
}

TEST(CapiMeshCreate, UnknownLinearisationIsInvalidArgument) {
  for (std::int64_t lin : {3LL, 7LL, 99LL, 0x7FFFFFFFLL}) {
    Grid g(4);
    g.channels[1].linearisation = static_cast<csc_linearisation>(lin);
    const csc_mesh_desc d = g.desc();
    csc_mesh* out = sentinel<csc_mesh>();
    EXPECT_FAILS(csc_mesh_create(&out, &d), CSC_ERROR_INVALID_ARGUMENT, "linearisation");
    EXPECT_EQ(out, sentinel<csc_mesh>());
  }
}

TEST(CapiMeshCreate, ALargerStructFromANewerHeaderIsAccepted) {
  Grid g(4);
  struct Newer {
    csc_mesh_desc desc;
    std::uint64_t appended;
  } newer{g.desc(), 42};
  newer.desc.struct_size = sizeof(Newer);
  csc_mesh* out = nullptr;
  ASSERT_OK(csc_mesh_create(&out, &newer.desc));
  MeshPtr m(out);
  EXPECT_EQ(csc_mesh_vertex_count(out), 16u);
}

// ==== meshes: accessors ====================================================================

TEST_F(Capi, AccessorsOfNullAndForeignHandlesGiveEmptyValues) {
  for (const csc_mesh* bad :
       {static_cast<const csc_mesh*>(nullptr), foreign<const csc_mesh>(diff.get()),
        foreign<const csc_mesh>(hierarchy.get()), foreign<const csc_mesh>(merger.get()),
        foreign<const csc_mesh>(bytes.get())}) {
    EXPECT_EQ(csc_mesh_vertex_count(bad), 0u);
    EXPECT_EQ(csc_mesh_triangle_count(bad), 0u);
    EXPECT_EQ(csc_mesh_channel_count(bad), 0u);
    EXPECT_EQ(csc_mesh_positions(bad), nullptr);
    EXPECT_EQ(csc_mesh_triangles(bad), nullptr);
    EXPECT_EQ(csc_mesh_find_channel(bad, "mask"), -1);
    EXPECT_EQ(csc_mesh_bbox_diagonal(bad), 0.f);
  }
  EXPECT_EQ(csc_mesh_find_channel(mesh.get(), nullptr), -1);
  EXPECT_EQ(csc_mesh_find_channel(mesh.get(), ""), -1);
  EXPECT_EQ(csc_mesh_find_channel(mesh.get(), "albedo"), -1);
  EXPECT_EQ(csc_mesh_find_channel(mesh.get(), "tint"), 1);
}

TEST_F(Capi, MeshChannelBadArguments) {
  csc_channel_view view = CSC_CHANNEL_VIEW_INIT;
  view.values = sentinel<const float>();
  const csc_channel_view before = view;
  auto untouched = [&] {
    EXPECT_EQ(std::memcmp(&view, &before, sizeof view), 0) << "the view was written";
  };
  EXPECT_FAILS(csc_mesh_channel(nullptr, 0, &view), CSC_ERROR_INVALID_ARGUMENT, "mesh");
  EXPECT_FAILS(csc_mesh_channel(foreign<csc_mesh>(diff.get()), 0, &view),
               CSC_ERROR_INVALID_ARGUMENT, "kind");
  for (std::uint32_t index : {2u, 3u, 0xFFFFFFFFu})
    EXPECT_FAILS(csc_mesh_channel(mesh.get(), index, &view), CSC_ERROR_INVALID_ARGUMENT,
                 "out of range");
  untouched();
  EXPECT_FAILS(csc_mesh_channel(mesh.get(), 0, nullptr), CSC_ERROR_INVALID_ARGUMENT, "out");
  for (std::uint32_t size : {0u, static_cast<std::uint32_t>(sizeof(csc_channel_view) - 1)}) {
    csc_channel_view small = view;
    small.struct_size = size;
    const csc_channel_view small_before = small;
    EXPECT_FAILS(csc_mesh_channel(mesh.get(), 0, &small), CSC_ERROR_INVALID_ARGUMENT,
                 "struct_size");
    EXPECT_EQ(std::memcmp(&small, &small_before, sizeof small), 0);
  }
}

TEST(CapiMeshAccessors, RoundTripTheHostArrays) {
  Grid g(7);
  g.channels.push_back({"unbounded", 2, CSC_LINEARISATION_SQUARE, -kInf, kInf});
  g.values.push_back(nullptr);  // filled with zeros
  MeshPtr m = g.make();
  ASSERT_TRUE(m);
  ASSERT_EQ(csc_mesh_vertex_count(m.get()), 49u);
  ASSERT_EQ(csc_mesh_triangle_count(m.get()), g.triangles.size() / 3);
  ASSERT_EQ(csc_mesh_channel_count(m.get()), 3u);
  EXPECT_EQ(std::memcmp(csc_mesh_positions(m.get()), g.positions.data(), g.positions.size() * 4),
            0);
  EXPECT_EQ(std::memcmp(csc_mesh_triangles(m.get()), g.triangles.data(), g.triangles.size() * 4),
            0);
  for (std::uint32_t c = 0; c < 3; ++c) {
    csc_channel_view v = CSC_CHANNEL_VIEW_INIT;
    ASSERT_OK(csc_mesh_channel(m.get(), c, &v));
    EXPECT_EQ(v.struct_size, sizeof(csc_channel_view));
    EXPECT_STREQ(v.desc.name, g.channels[c].name);
    EXPECT_NE(v.desc.name, g.channels[c].name) << "the name was not copied";
    EXPECT_EQ(v.desc.width, g.channels[c].width);
    EXPECT_EQ(v.desc.linearisation, g.channels[c].linearisation);
    EXPECT_EQ(v.desc.min_value, g.channels[c].min_value);
    EXPECT_EQ(v.desc.max_value, g.channels[c].max_value);
    EXPECT_EQ(csc_mesh_find_channel(m.get(), g.channels[c].name), static_cast<std::int32_t>(c));
    const std::size_t n = std::size_t{49} * v.desc.width;
    if (g.values[c] != nullptr)
      EXPECT_EQ(std::memcmp(v.values, g.values[c], n * 4), 0) << g.channels[c].name;
    else
      EXPECT_TRUE(std::all_of(v.values, v.values + n, [](float x) { return x == 0.f; }));
  }
  // The mesh holds copies: changing the host's arrays afterwards changes nothing.
  const std::vector<float> original = g.positions;
  g.positions[0] = 99.f;
  EXPECT_EQ(std::memcmp(csc_mesh_positions(m.get()), original.data(), original.size() * 4), 0);
  EXPECT_NEAR(csc_mesh_bbox_diagonal(m.get()), std::sqrt(2.f + 0.04f), 0.02f);

  MeshPtr no_channels = Grid(3, false).make();
  ASSERT_TRUE(no_channels);
  EXPECT_EQ(csc_mesh_channel_count(no_channels.get()), 0u);
}

// ==== meshes: material channels, clone =====================================================

TEST_F(Capi, AddMaterialChannels) {
  EXPECT_FAILS(csc_mesh_add_material_channels(nullptr), CSC_ERROR_INVALID_ARGUMENT, "mesh");
  EXPECT_FAILS(csc_mesh_add_material_channels(foreign<csc_mesh>(merger.get())),
               CSC_ERROR_INVALID_ARGUMENT, "kind");

  // An "albedo" of another width conflicts: refused, and the mesh keeps its channels.
  Grid g(4);
  g.channels[1].name = "albedo";
  g.channels[1].width = 3;
  g.channels[0].name = "metallic";
  g.channels[0].width = 1;
  Grid conflict(4);
  conflict.channels[0].name = "albedo";  // width 1
  MeshPtr bad = conflict.make();
  ASSERT_TRUE(bad);
  EXPECT_FAILS(csc_mesh_add_material_channels(bad.get()), CSC_ERROR_INVALID_INPUT, "albedo");
  EXPECT_EQ(csc_mesh_channel_count(bad.get()), 2u);

  // Only the missing ones are added, and adding again changes nothing.
  MeshPtr partial = g.make();
  ASSERT_TRUE(partial);
  ASSERT_OK(csc_mesh_add_material_channels(partial.get()));
  EXPECT_EQ(csc_mesh_channel_count(partial.get()), 3u);
  ASSERT_OK(csc_mesh_add_material_channels(partial.get()));
  EXPECT_EQ(csc_mesh_channel_count(partial.get()), 3u);
  const std::int32_t r = csc_mesh_find_channel(partial.get(), "roughness");
  ASSERT_GE(r, 0);
  csc_channel_view v = CSC_CHANNEL_VIEW_INIT;
  ASSERT_OK(csc_mesh_channel(partial.get(), static_cast<std::uint32_t>(r), &v));
  EXPECT_EQ(v.desc.linearisation, CSC_LINEARISATION_SQUARE);
  EXPECT_EQ(v.desc.width, 1u);
}

TEST_F(Capi, CloneBadArgumentsAndDeepCopy) {
  csc_mesh* out = sentinel<csc_mesh>();
  EXPECT_FAILS(csc_mesh_clone(nullptr, mesh.get()), CSC_ERROR_INVALID_ARGUMENT, "out");
  EXPECT_FAILS(csc_mesh_clone(&out, nullptr), CSC_ERROR_INVALID_ARGUMENT, "mesh");
  EXPECT_FAILS(csc_mesh_clone(&out, foreign<csc_mesh>(diff.get())), CSC_ERROR_INVALID_ARGUMENT,
               "kind");
  EXPECT_EQ(out, sentinel<csc_mesh>());
  csc_mesh* c = nullptr;
  ASSERT_OK(csc_mesh_clone(&c, mesh.get()));
  MeshPtr copy(c);
  ASSERT_OK(csc_mesh_apply_diff(copy.get(), diff.get()));
  EXPECT_EQ(HostArrays(mesh.get()), *host) << "applying to the clone changed the original";
  EXPECT_FALSE(HostArrays(copy.get()) == *host);
}

// ==== files ================================================================================

TEST(CapiMeshRead, BadArgumentsAndMissingFiles) {
  csc_mesh* out = sentinel<csc_mesh>();
  EXPECT_FAILS(csc_mesh_read(nullptr, "x.ply"), CSC_ERROR_INVALID_ARGUMENT, "out");
  EXPECT_FAILS(csc_mesh_read(&out, nullptr), CSC_ERROR_INVALID_ARGUMENT, "path");
  EXPECT_FAILS(csc_mesh_read(&out, "/nonexistent/missing.ply"), CSC_ERROR_IO, "missing.ply");
  EXPECT_FAILS(csc_mesh_read(&out, ""), CSC_ERROR_IO, "cannot");
  const std::string dir = fs::temp_directory_path().string();
  EXPECT_FAILS(csc_mesh_read(&out, dir.c_str()), CSC_ERROR_IO, "directory");
  EXPECT_EQ(out, sentinel<csc_mesh>());
}

TEST(CapiMeshRead, MalformedModelsAreInvalidInputNamingTheFile) {
  if (!fs::exists(kModels)) GTEST_SKIP() << "assimp-testmodels not installed";
  csc_mesh* out = sentinel<csc_mesh>();
  std::size_t count = 0;
  for (const auto& e : fs::directory_iterator(kModels / "invalid")) {
    const std::string p = e.path().string();
    EXPECT_FAILS(csc_mesh_read(&out, p.c_str()), CSC_ERROR_INVALID_INPUT, p.c_str());
    ++count;
  }
  EXPECT_GE(count, 10u);
  const std::vector<std::pair<std::string, const char*>> specific = {
      {"invalid/OutOfMemory.off", "353535235358 vertices"},
      {"invalid/empty.ply", "file is empty"},
      {"invalid/malformed.obj", "out of range"},
      {"PLY/points.ply", "no faces"},
      {"OBJ/point_cloud.obj", "no faces"},
      {"OBJ/box_UTF16BE.obj", "UTF-16"},
      {"PLY/pond.0.ply", "header claims 70051 vertex elements"},
      {"OBJ/spider.mtl", "unrecognised file format"}};
  for (const auto& [name, keyword] : specific) {
    const std::string p = (kModels / name).string();
    EXPECT_FAILS(csc_mesh_read(&out, p.c_str()), CSC_ERROR_INVALID_INPUT, keyword);
  }
  EXPECT_EQ(out, sentinel<csc_mesh>());
}

TEST(CapiMeshRead, RealModelsRead) {
  if (!fs::exists(kModels)) GTEST_SKIP() << "assimp-testmodels not installed";
  for (const char* name : {"PLY/cube.ply", "PLY/cube_binary.ply", "OFF/Cube.off", "OBJ/box.obj",
                           "STL/Spider_binary.stl"}) {
    csc_mesh* out = nullptr;
    ASSERT_OK(csc_mesh_read(&out, (kModels / name).string().c_str()));
    MeshPtr m(out);
    EXPECT_GT(csc_mesh_vertex_count(out), 0u) << name;
    EXPECT_GT(csc_mesh_triangle_count(out), 0u) << name;
  }
}

class CapiFiles : public Capi {
 protected:
  void SetUp() override {
    Capi::SetUp();
    dir = fs::temp_directory_path() /
          ("csculpt-capi-" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
           "-" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  void TearDown() override { fs::remove_all(dir); }
  fs::path dir;
};

TEST_F(CapiFiles, WriteBadArgumentsAndUnwritablePaths) {
  const std::string ok_path = (dir / "m.ply").string();
  EXPECT_FAILS(csc_mesh_write(nullptr, ok_path.c_str()), CSC_ERROR_INVALID_ARGUMENT, "mesh");
  EXPECT_FAILS(csc_mesh_write(foreign<csc_mesh>(bytes.get()), ok_path.c_str()),
               CSC_ERROR_INVALID_ARGUMENT, "kind");
  EXPECT_FAILS(csc_mesh_write(mesh.get(), nullptr), CSC_ERROR_INVALID_ARGUMENT, "path");
  EXPECT_FAILS(csc_mesh_write(mesh.get(), "/nonexistent/dir/never.ply"), CSC_ERROR_IO, "never.ply");
  EXPECT_FAILS(csc_mesh_write(mesh.get(), "/proc/csculpt-never.ply"), CSC_ERROR_IO,
               "csculpt-never.ply");
  const std::string unsupported = (dir / "m.xyz").string();
  EXPECT_FAILS(csc_mesh_write(mesh.get(), unsupported.c_str()), CSC_ERROR_INVALID_INPUT, ".xyz");
  // The target is a directory: the rename fails, and no temporary file is left behind.
  fs::create_directory(dir / "taken.ply");
  const std::string taken = (dir / "taken.ply").string();
  EXPECT_FAILS(csc_mesh_write(mesh.get(), taken.c_str()), CSC_ERROR_IO, "taken.ply");
  std::vector<std::string> left;
  for (const auto& e : fs::directory_iterator(dir)) left.push_back(e.path().filename().string());
  EXPECT_EQ(left, std::vector<std::string>{"taken.ply"});
  EXPECT_FALSE(fs::exists(ok_path));
}

/// Writes `m` to `path` and reads it back.
MeshPtr write_and_read(const csc_mesh* m, const std::string& path) {
  EXPECT_EQ(csc_mesh_write(m, path.c_str()), CSC_OK) << csc_last_error();
  csc_mesh* r = nullptr;
  EXPECT_EQ(csc_mesh_read(&r, path.c_str()), CSC_OK) << csc_last_error();
  return MeshPtr(r);
}

/// Positions, triangles, channel names, widths, linearisations and values bit for bit; the
/// ranges too when `ranges` is set.
void expect_same_mesh(const csc_mesh* a, const csc_mesh* b, bool ranges) {
  ASSERT_EQ(csc_mesh_vertex_count(b), csc_mesh_vertex_count(a));
  ASSERT_EQ(csc_mesh_triangle_count(b), csc_mesh_triangle_count(a));
  ASSERT_EQ(csc_mesh_channel_count(b), csc_mesh_channel_count(a));
  const std::size_t n = csc_mesh_vertex_count(a);
  EXPECT_EQ(std::memcmp(csc_mesh_positions(a), csc_mesh_positions(b), 12 * n), 0);
  EXPECT_EQ(std::memcmp(csc_mesh_triangles(a), csc_mesh_triangles(b),
                        std::size_t{12} * csc_mesh_triangle_count(a)),
            0);
  for (std::uint32_t k = 0; k < csc_mesh_channel_count(a); ++k) {
    csc_channel_view x = CSC_CHANNEL_VIEW_INIT, y = CSC_CHANNEL_VIEW_INIT;
    ASSERT_OK(csc_mesh_channel(a, k, &x));
    ASSERT_OK(csc_mesh_channel(b, k, &y));
    SCOPED_TRACE(x.desc.name);
    EXPECT_STREQ(x.desc.name, y.desc.name);
    EXPECT_EQ(x.desc.width, y.desc.width);
    EXPECT_EQ(x.desc.linearisation, y.desc.linearisation);
    if (ranges) {
      EXPECT_EQ(x.desc.min_value, y.desc.min_value);
      EXPECT_EQ(x.desc.max_value, y.desc.max_value);
    }
    EXPECT_EQ(std::memcmp(x.values, y.values, 4 * n * x.desc.width), 0);
  }
}

TEST_F(CapiFiles, PlyWithChannelsRoundTripsBitForBit) {
  // Channels whose description a PLY property can carry: the material channels, and custom
  // channels of every linearisation with the default (unbounded) range.
  Grid g(kN);
  g.channels = {{"mask", 1, CSC_LINEARISATION_IDENTITY, -kInf, kInf},
                {"tint", 3, CSC_LINEARISATION_SRGB, -kInf, kInf},
                {"gloss", 2, CSC_LINEARISATION_SQUARE, -kInf, kInf}};
  std::vector<float> gloss(2 * kN * kN);
  for (std::size_t i = 0; i < gloss.size(); ++i) gloss[i] = std::sqrt(static_cast<float>(i) / 7.f);
  g.values.push_back(gloss.data());
  MeshPtr original = g.make();
  ASSERT_TRUE(original);
  ASSERT_OK(csc_mesh_add_material_channels(original.get()));
  HostArrays edit(original.get());
  brush(edit, kN, 0.6f, 0.3f, 0.4f, {0.013f, -0.007f, 0.1f}, 4, 0.3f);  // values that are not round
  DiffPtr d = capture(original.get(), edit);
  ASSERT_OK(csc_mesh_apply_diff(original.get(), d.get()));

  MeshPtr back = write_and_read(original.get(), (dir / "round.ply").string());
  ASSERT_TRUE(back);
  expect_same_mesh(original.get(), back.get(), true);
  // The mesh read back is the same base: capturing against it finds nothing changed.
  csc_diff* none = nullptr;
  ASSERT_OK(csc_diff_capture(&none, original.get(), back.get()));
  DiffPtr kept(none);
  csc_diff_info info = CSC_DIFF_INFO_INIT;
  ASSERT_OK(csc_diff_get_info(none, &info));
  EXPECT_EQ(info.touched_vertices, 0u);

  // OBJ keeps positions (as text) and faces.
  MeshPtr obj = write_and_read(original.get(), (dir / "round.obj").string());
  ASSERT_TRUE(obj);
  EXPECT_EQ(csc_mesh_vertex_count(obj.get()), kN * kN);
  EXPECT_EQ(std::memcmp(csc_mesh_triangles(obj.get()), csc_mesh_triangles(original.get()),
                        std::size_t{12} * csc_mesh_triangle_count(obj.get())),
            0);
}

// csculpt.h, csc_mesh_write: ".ply (binary, channels as vertex properties; reads back
// bit-identical)". A custom channel's range is part of the mesh (merged values are clamped
// into it), so a peer that loads the base from the file must get it back.
TEST_F(CapiFiles, PlyKeepsTheRangeOfCustomChannels) {
  MeshPtr back = write_and_read(mesh.get(), (dir / "ranges.ply").string());
  ASSERT_TRUE(back);
  expect_same_mesh(mesh.get(), back.get(), true);
  csc_diff* none = nullptr;
  EXPECT_EQ(csc_diff_capture(&none, mesh.get(), back.get()), CSC_OK) << csc_last_error();
  csc_diff_destroy(none);
}

// ==== hierarchy ============================================================================

TEST_F(Capi, HierarchyBadArguments) {
  csc_hierarchy* out = sentinel<csc_hierarchy>();
  EXPECT_FAILS(csc_hierarchy_build(nullptr, mesh.get(), nullptr), CSC_ERROR_INVALID_ARGUMENT,
               "out");
  EXPECT_FAILS(csc_hierarchy_build(&out, nullptr, nullptr), CSC_ERROR_INVALID_ARGUMENT, "mesh");
  EXPECT_FAILS(csc_hierarchy_build(&out, foreign<csc_mesh>(hierarchy.get()), nullptr),
               CSC_ERROR_INVALID_ARGUMENT, "kind");
  csc_hierarchy_options o = CSC_HIERARCHY_OPTIONS_INIT;
  o.struct_size = 0;
  EXPECT_FAILS(csc_hierarchy_build(&out, mesh.get(), &o), CSC_ERROR_INVALID_ARGUMENT,
               "struct_size");
  o = CSC_HIERARCHY_OPTIONS_INIT;
  o.struct_size = sizeof(o) - 1;
  EXPECT_FAILS(csc_hierarchy_build(&out, mesh.get(), &o), CSC_ERROR_INVALID_ARGUMENT,
               "struct_size");
  for (std::uint32_t k : {0u, 33u, 0xFFFFFFFFu}) {
    o = CSC_HIERARCHY_OPTIONS_INIT;
    o.max_parents = k;
    EXPECT_FAILS(csc_hierarchy_build(&out, mesh.get(), &o), CSC_ERROR_INVALID_ARGUMENT,
                 "max_parents");
  }
  EXPECT_EQ(out, sentinel<csc_hierarchy>());

  csc_hierarchy_stats stats = CSC_HIERARCHY_STATS_INIT;
  stats.levels = 12345;
  EXPECT_FAILS(csc_hierarchy_get_stats(nullptr, &stats), CSC_ERROR_INVALID_ARGUMENT, "hierarchy");
  EXPECT_FAILS(csc_hierarchy_get_stats(foreign<csc_hierarchy>(mesh.get()), &stats),
               CSC_ERROR_INVALID_ARGUMENT, "kind");
  EXPECT_FAILS(csc_hierarchy_get_stats(hierarchy.get(), nullptr), CSC_ERROR_INVALID_ARGUMENT,
               "out");
  stats.struct_size = sizeof(stats) - 8;
  EXPECT_FAILS(csc_hierarchy_get_stats(hierarchy.get(), &stats), CSC_ERROR_INVALID_ARGUMENT,
               "struct_size");
  EXPECT_EQ(stats.levels, 12345u) << "a failed call wrote its out-parameter";

  EXPECT_EQ(csc_hierarchy_digest(nullptr), 0u);
  EXPECT_EQ(csc_hierarchy_digest(foreign<csc_hierarchy>(mesh.get())), 0u);
  EXPECT_NE(csc_hierarchy_digest(hierarchy.get()), 0u);
}

TEST_F(Capi, HierarchyStatsAndOptions) {
  csc_hierarchy_stats s = CSC_HIERARCHY_STATS_INIT;
  ASSERT_OK(csc_hierarchy_get_stats(hierarchy.get(), &s));
  EXPECT_EQ(s.struct_size, sizeof(s));
  EXPECT_EQ(s.vertices, kN * kN);
  EXPECT_EQ(s.faces, 2 * (kN - 1) * (kN - 1));
  EXPECT_EQ(s.top_nodes, 1u);
  EXPECT_GT(s.levels, 1u);
  EXPECT_GE(s.nodes, s.vertices);
  // K = 1 (a tree) is a different hierarchy from the default K = 7.
  csc_hierarchy_options o = CSC_HIERARCHY_OPTIONS_INIT;
  o.max_parents = 1;
  csc_hierarchy* tree = nullptr;
  ASSERT_OK(csc_hierarchy_build(&tree, mesh.get(), &o));
  HierarchyPtr t(tree);
  EXPECT_NE(csc_hierarchy_digest(tree), csc_hierarchy_digest(hierarchy.get()));
  csc_hierarchy* again = nullptr;
  ASSERT_OK(csc_hierarchy_build(&again, mesh.get(), nullptr));
  HierarchyPtr a(again);
  EXPECT_EQ(csc_hierarchy_digest(again), csc_hierarchy_digest(hierarchy.get()));
}

// ==== diffs: capture =======================================================================

TEST_F(Capi, CaptureArraysBadArguments) {
  csc_diff* out = sentinel<csc_diff>();
  HostArrays h(*host);
  csc_vertex_arrays a = h.arrays();
  EXPECT_FAILS(csc_diff_capture_arrays(nullptr, mesh.get(), &a), CSC_ERROR_INVALID_ARGUMENT, "out");
  EXPECT_FAILS(csc_diff_capture_arrays(&out, nullptr, &a), CSC_ERROR_INVALID_ARGUMENT, "base");
  EXPECT_FAILS(csc_diff_capture_arrays(&out, foreign<csc_mesh>(diff.get()), &a),
               CSC_ERROR_INVALID_ARGUMENT, "kind");
  EXPECT_FAILS(csc_diff_capture_arrays(&out, mesh.get(), nullptr), CSC_ERROR_INVALID_ARGUMENT,
               "current");
  a.struct_size = 0;
  EXPECT_FAILS(csc_diff_capture_arrays(&out, mesh.get(), &a), CSC_ERROR_INVALID_ARGUMENT,
               "struct_size");
  a = h.arrays();
  a.positions = nullptr;
  EXPECT_FAILS(csc_diff_capture_arrays(&out, mesh.get(), &a), CSC_ERROR_INVALID_ARGUMENT,
               "positions");
  a = h.arrays();
  a.channels = nullptr;
  EXPECT_FAILS(csc_diff_capture_arrays(&out, mesh.get(), &a), CSC_ERROR_INVALID_ARGUMENT,
               "channels");
  EXPECT_EQ(out, sentinel<csc_diff>());
}

// csculpt.h: "Fails with CSC_ERROR_INVALID_INPUT if the counts differ from the base".
TEST_F(Capi, CaptureArraysOfOtherCountsIsInvalidInput) {
  csc_diff* out = sentinel<csc_diff>();
  HostArrays h(*host);
  csc_vertex_arrays a = h.arrays();
  a.vertex_count -= 1;
  EXPECT_FAILS(csc_diff_capture_arrays(&out, mesh.get(), &a), CSC_ERROR_INVALID_INPUT, "vertices");
  a = h.arrays();
  a.channel_count = 1;
  EXPECT_FAILS(csc_diff_capture_arrays(&out, mesh.get(), &a), CSC_ERROR_INVALID_INPUT, "channels");
  EXPECT_EQ(out, sentinel<csc_diff>());
}

TEST_F(Capi, CaptureArraysWithNonFiniteChangesIsInvalidInput) {
  csc_diff* out = sentinel<csc_diff>();
  {
    HostArrays h(*host);
    h.positions[3 * 20 + 1] = kNaN;
    const csc_vertex_arrays a = h.arrays();
    EXPECT_FAILS(csc_diff_capture_arrays(&out, mesh.get(), &a), CSC_ERROR_INVALID_INPUT,
                 "not finite");
  }
  {
    HostArrays h(*host);
    h.positions[3 * 21] += 0.01f;  // a valid change next to the bad one
    h.channels[1][3 * 50 + 2] = kInf;
    const csc_vertex_arrays a = h.arrays();
    EXPECT_FAILS(csc_diff_capture_arrays(&out, mesh.get(), &a), CSC_ERROR_INVALID_INPUT, "tint");
  }
  EXPECT_EQ(out, sentinel<csc_diff>());
  // NULL channel entries are skipped: a NaN there is never read.
  HostArrays h(*host);
  h.channels[1][0] = kNaN;
  h.pointers[1] = nullptr;
  const csc_vertex_arrays a = h.arrays();
  csc_diff* d = nullptr;
  ASSERT_OK(csc_diff_capture_arrays(&d, mesh.get(), &a));
  DiffPtr p(d);
  csc_diff_info info = CSC_DIFF_INFO_INIT;
  ASSERT_OK(csc_diff_get_info(d, &info));
  EXPECT_EQ(info.touched_vertices, 0u);
}

TEST_F(Capi, CaptureOfMeshesBadArgumentsAndMismatches) {
  csc_diff* out = sentinel<csc_diff>();
  EXPECT_FAILS(csc_diff_capture(nullptr, mesh.get(), mesh.get()), CSC_ERROR_INVALID_ARGUMENT,
               "out");
  EXPECT_FAILS(csc_diff_capture(&out, nullptr, mesh.get()), CSC_ERROR_INVALID_ARGUMENT, "base");
  EXPECT_FAILS(csc_diff_capture(&out, mesh.get(), nullptr), CSC_ERROR_INVALID_ARGUMENT, "edited");
  EXPECT_FAILS(csc_diff_capture(&out, foreign<csc_mesh>(bytes.get()), mesh.get()),
               CSC_ERROR_INVALID_ARGUMENT, "kind");
  EXPECT_FAILS(csc_diff_capture(&out, mesh.get(), foreign<csc_mesh>(merger.get())),
               CSC_ERROR_INVALID_ARGUMENT, "kind");
  MeshPtr smaller = Grid(kN - 1).make();
  EXPECT_FAILS(csc_diff_capture(&out, mesh.get(), smaller.get()), CSC_ERROR_INVALID_INPUT,
               "vertices");
  Grid flipped(kN);
  std::swap(flipped.triangles[1], flipped.triangles[2]);
  MeshPtr other = flipped.make();
  EXPECT_FAILS(csc_diff_capture(&out, mesh.get(), other.get()), CSC_ERROR_INVALID_INPUT,
               "triangle 0");
  MeshPtr bare = Grid(kN, false).make();
  EXPECT_FAILS(csc_diff_capture(&out, mesh.get(), bare.get()), CSC_ERROR_INVALID_INPUT, "channels");
  EXPECT_EQ(out, sentinel<csc_diff>());
}

// ==== diffs: apply, inspect ================================================================

TEST_F(Capi, ApplyToMeshBadArgumentsLeaveTheMeshUnchanged) {
  EXPECT_FAILS(csc_mesh_apply_diff(nullptr, diff.get()), CSC_ERROR_INVALID_ARGUMENT, "mesh");
  EXPECT_FAILS(csc_mesh_apply_diff(mesh.get(), nullptr), CSC_ERROR_INVALID_ARGUMENT, "diff");
  EXPECT_FAILS(csc_mesh_apply_diff(foreign<csc_mesh>(diff.get()), diff.get()),
               CSC_ERROR_INVALID_ARGUMENT, "kind");
  EXPECT_FAILS(csc_mesh_apply_diff(mesh.get(), foreign<csc_diff>(mesh.get())),
               CSC_ERROR_INVALID_ARGUMENT, "kind");
  MeshPtr smaller = Grid(kN - 1).make();
  const HostArrays before(smaller.get());
  EXPECT_FAILS(csc_mesh_apply_diff(smaller.get(), diff.get()), CSC_ERROR_INVALID_INPUT, "vertices");
  EXPECT_EQ(HostArrays(smaller.get()), before);
  MeshPtr bare = Grid(kN, false).make();  // the diff paints "tint", which this mesh lacks
  const HostArrays bare_before(bare.get());
  EXPECT_FAILS(csc_mesh_apply_diff(bare.get(), diff.get()), CSC_ERROR_INVALID_INPUT,
               "does not exist");
  EXPECT_EQ(HostArrays(bare.get()), bare_before);
  EXPECT_EQ(HostArrays(mesh.get()), *host);
}

TEST_F(Capi, ApplyToArraysBadArgumentsWriteNothing) {
  HostArrays target(*host);
  csc_vertex_arrays a = target.arrays();
  EXPECT_FAILS(csc_diff_apply_arrays(nullptr, mesh.get(), &a), CSC_ERROR_INVALID_ARGUMENT, "diff");
  EXPECT_FAILS(csc_diff_apply_arrays(foreign<csc_diff>(hierarchy.get()), mesh.get(), &a),
               CSC_ERROR_INVALID_ARGUMENT, "kind");
  EXPECT_FAILS(csc_diff_apply_arrays(diff.get(), nullptr, &a), CSC_ERROR_INVALID_ARGUMENT, "base");
  EXPECT_FAILS(csc_diff_apply_arrays(diff.get(), foreign<csc_mesh>(diff.get()), &a),
               CSC_ERROR_INVALID_ARGUMENT, "kind");
  EXPECT_FAILS(csc_diff_apply_arrays(diff.get(), mesh.get(), nullptr), CSC_ERROR_INVALID_ARGUMENT,
               "target");
  a.struct_size = sizeof(a) - 1;
  EXPECT_FAILS(csc_diff_apply_arrays(diff.get(), mesh.get(), &a), CSC_ERROR_INVALID_ARGUMENT,
               "struct_size");
  a = target.arrays();
  a.positions = nullptr;
  EXPECT_FAILS(csc_diff_apply_arrays(diff.get(), mesh.get(), &a), CSC_ERROR_INVALID_ARGUMENT,
               "positions");
  a = target.arrays();
  a.channels = nullptr;
  EXPECT_FAILS(csc_diff_apply_arrays(diff.get(), mesh.get(), &a), CSC_ERROR_INVALID_ARGUMENT,
               "channels");
  // A diff for another mesh: refused before anything is written.
  Grid small_grid(kN - 1);
  MeshPtr smaller = small_grid.make();
  HostArrays small_host(smaller.get());
  HostArrays small_edit(small_host);
  brush(small_edit, kN - 1, 0.5f, 0.5f, 0.4f, {0.05f, 0.f, 0.f});
  DiffPtr small_diff = capture(smaller.get(), small_edit);
  a = target.arrays();
  EXPECT_FAILS(csc_diff_apply_arrays(small_diff.get(), mesh.get(), &a), CSC_ERROR_INVALID_INPUT,
               "vertices");
  EXPECT_EQ(target, *host) << "a failed apply wrote into the host's arrays";
}

TEST_F(Capi, ApplyToArraysTouchesOnlyListedVertices) {
  // The target holds a pattern unlike the base, so any write outside the diff shows.
  HostArrays target(*host);
  for (std::size_t i = 0; i < target.positions.size(); ++i)
    target.positions[i] = -1000.f - static_cast<float>(i);
  for (auto& c : target.channels)
    for (std::size_t i = 0; i < c.size(); ++i) c[i] = 500.f + static_cast<float>(i);
  const HostArrays before(target);
  const DiffContent d = content(diff.get());
  ASSERT_FALSE(d.indices.empty());
  ASSERT_EQ(d.channel_names, (std::vector<std::string>{"mask", "tint"}));
  ASSERT_TRUE(d.channel_indices[0].empty());
  ASSERT_FALSE(d.channel_indices[1].empty());

  target.pointers[1] = nullptr;  // "tint" not written
  csc_vertex_arrays a = target.arrays();
  ASSERT_OK(csc_diff_apply_arrays(diff.get(), mesh.get(), &a));
  for (std::uint32_t v = 0; v < kN * kN; ++v) {
    const auto it = std::lower_bound(d.indices.begin(), d.indices.end(), v);
    const float* expected = it != d.indices.end() && *it == v
                                ? &d.values[3 * static_cast<std::size_t>(it - d.indices.begin())]
                                : &before.positions[3 * v];
    EXPECT_EQ(std::memcmp(&target.positions[3 * v], expected, 12), 0) << "vertex " << v;
  }
  EXPECT_EQ(target.channels, before.channels) << "NULL channel entry written, or mask touched";

  target.refresh();
  a = target.arrays();
  ASSERT_OK(csc_diff_apply_arrays(diff.get(), mesh.get(), &a));
  for (std::uint32_t v = 0; v < kN * kN; ++v) {
    const auto& idx = d.channel_indices[1];
    const auto it = std::lower_bound(idx.begin(), idx.end(), v);
    const float* expected =
        it != idx.end() && *it == v
            ? &d.channel_values[1][3 * static_cast<std::size_t>(it - idx.begin())]
            : &before.channels[1][3 * v];
    EXPECT_EQ(std::memcmp(&target.channels[1][3 * v], expected, 12), 0) << "tint of vertex " << v;
  }
}

TEST_F(Capi, DiffInspectionBadArgumentsLeaveOutputsAlone) {
  csc_diff_info info = CSC_DIFF_INFO_INIT;
  info.touched_vertices = 777;
  EXPECT_FAILS(csc_diff_get_info(nullptr, &info), CSC_ERROR_INVALID_ARGUMENT, "diff");
  EXPECT_FAILS(csc_diff_get_info(foreign<csc_diff>(mesh.get()), &info), CSC_ERROR_INVALID_ARGUMENT,
               "kind");
  EXPECT_FAILS(csc_diff_get_info(diff.get(), nullptr), CSC_ERROR_INVALID_ARGUMENT, "out");
  info.struct_size = 0;
  EXPECT_FAILS(csc_diff_get_info(diff.get(), &info), CSC_ERROR_INVALID_ARGUMENT, "struct_size");
  EXPECT_EQ(info.touched_vertices, 777u);

  const std::uint32_t* idx = sentinel<const std::uint32_t>();
  const float* val = sentinel<const float>();
  std::uint32_t count = 555, width = 666;
  const char* name = sentinel<const char>();
  auto untouched = [&] {
    EXPECT_EQ(idx, sentinel<const std::uint32_t>());
    EXPECT_EQ(val, sentinel<const float>());
    EXPECT_EQ(name, sentinel<const char>());
    EXPECT_EQ(count, 555u);
    EXPECT_EQ(width, 666u);
  };
  EXPECT_FAILS(csc_diff_positions(nullptr, &idx, &val, &count), CSC_ERROR_INVALID_ARGUMENT, "diff");
  EXPECT_FAILS(csc_diff_positions(foreign<csc_diff>(bytes.get()), &idx, &val, &count),
               CSC_ERROR_INVALID_ARGUMENT, "kind");
  EXPECT_FAILS(csc_diff_positions(diff.get(), nullptr, &val, &count), CSC_ERROR_INVALID_ARGUMENT,
               "indices");
  EXPECT_FAILS(csc_diff_positions(diff.get(), &idx, nullptr, &count), CSC_ERROR_INVALID_ARGUMENT,
               "values");
  EXPECT_FAILS(csc_diff_positions(diff.get(), &idx, &val, nullptr), CSC_ERROR_INVALID_ARGUMENT,
               "count");
  untouched();

  EXPECT_FAILS(csc_diff_channel(nullptr, 0, &name, &width, &idx, &val, &count),
               CSC_ERROR_INVALID_ARGUMENT, "diff");
  EXPECT_FAILS(
      csc_diff_channel(foreign<csc_diff>(merger.get()), 0, &name, &width, &idx, &val, &count),
      CSC_ERROR_INVALID_ARGUMENT, "kind");
  for (std::uint32_t index : {2u, 0xFFFFFFFFu})
    EXPECT_FAILS(csc_diff_channel(diff.get(), index, &name, &width, &idx, &val, &count),
                 CSC_ERROR_INVALID_ARGUMENT, "out of range");
  EXPECT_FAILS(csc_diff_channel(diff.get(), 0, nullptr, &width, &idx, &val, &count),
               CSC_ERROR_INVALID_ARGUMENT, "name");
  EXPECT_FAILS(csc_diff_channel(diff.get(), 0, &name, nullptr, &idx, &val, &count),
               CSC_ERROR_INVALID_ARGUMENT, "width");
  EXPECT_FAILS(csc_diff_channel(diff.get(), 0, &name, &width, nullptr, &val, &count),
               CSC_ERROR_INVALID_ARGUMENT, "indices");
  EXPECT_FAILS(csc_diff_channel(diff.get(), 0, &name, &width, &idx, nullptr, &count),
               CSC_ERROR_INVALID_ARGUMENT, "values");
  EXPECT_FAILS(csc_diff_channel(diff.get(), 0, &name, &width, &idx, &val, nullptr),
               CSC_ERROR_INVALID_ARGUMENT, "count");
  untouched();
}

TEST_F(Capi, OutputStructsOfANewerHeaderKeepTheirTail) {
  struct Newer {
    csc_diff_info info;
    std::uint64_t appended;
  } newer{CSC_DIFF_INFO_INIT, 0xA5A5A5A5A5A5A5A5ull};
  newer.info.struct_size = sizeof(Newer);
  ASSERT_OK(csc_diff_get_info(diff.get(), &newer.info));
  EXPECT_EQ(newer.info.struct_size, sizeof(Newer));
  EXPECT_EQ(newer.appended, 0xA5A5A5A5A5A5A5A5ull) << "the library wrote past its own struct";
  EXPECT_EQ(newer.info.vertex_count, kN * kN);
  EXPECT_GT(newer.info.touched_vertices, 0u);
  EXPECT_EQ(newer.info.channel_count, 2u);
}

// ==== wire: encode =========================================================================

TEST_F(Capi, EncodeBadArguments) {
  csc_bytes* out = sentinel<csc_bytes>();
  EXPECT_FAILS(csc_diff_encode(nullptr, diff.get(), mesh.get(), nullptr),
               CSC_ERROR_INVALID_ARGUMENT, "out");
  EXPECT_FAILS(csc_diff_encode(&out, nullptr, mesh.get(), nullptr), CSC_ERROR_INVALID_ARGUMENT,
               "diff");
  EXPECT_FAILS(csc_diff_encode(&out, diff.get(), nullptr, nullptr), CSC_ERROR_INVALID_ARGUMENT,
               "base");
  EXPECT_FAILS(csc_diff_encode(&out, foreign<csc_diff>(mesh.get()), mesh.get(), nullptr),
               CSC_ERROR_INVALID_ARGUMENT, "kind");
  EXPECT_FAILS(csc_diff_encode(&out, diff.get(), foreign<csc_mesh>(diff.get()), nullptr),
               CSC_ERROR_INVALID_ARGUMENT, "kind");
  csc_encode_options o = CSC_ENCODE_OPTIONS_INIT;
  o.struct_size = sizeof(o) - 8;
  EXPECT_FAILS(csc_diff_encode(&out, diff.get(), mesh.get(), &o), CSC_ERROR_INVALID_ARGUMENT,
               "struct_size");
  for (double bad : {-1e-5, static_cast<double>(kNaN), static_cast<double>(kInf)}) {
    for (int field = 0; field < 3; ++field) {
      o = CSC_ENCODE_OPTIONS_INIT;
      (field == 0   ? o.position_tolerance
       : field == 1 ? o.position_scale
                    : o.channel_tolerance) = bad;
      EXPECT_FAILS(csc_diff_encode(&out, diff.get(), mesh.get(), &o), CSC_ERROR_INVALID_ARGUMENT,
                   "tolerance");
    }
  }
  const std::string long_author(257, 'a');
  o = CSC_ENCODE_OPTIONS_INIT;
  o.author = long_author.c_str();
  EXPECT_FAILS(csc_diff_encode(&out, diff.get(), mesh.get(), &o), CSC_ERROR_INVALID_ARGUMENT,
               "author");
  MeshPtr smaller = Grid(kN - 1).make();
  EXPECT_FAILS(csc_diff_encode(&out, diff.get(), smaller.get(), nullptr), CSC_ERROR_INVALID_INPUT,
               "vertices");
  EXPECT_EQ(out, sentinel<csc_bytes>());

  // 256 bytes is the limit, not past it.
  const std::string max_author(256, 'b');
  o.author = max_author.c_str();
  csc_bytes* b = nullptr;
  ASSERT_OK(csc_diff_encode(&b, diff.get(), mesh.get(), &o));
  BytesPtr kept(b);
  csc_message_info info = CSC_MESSAGE_INFO_INIT;
  ASSERT_OK(csc_diff_peek(csc_bytes_data(b), csc_bytes_size(b), &info));
  EXPECT_EQ(std::string(info.author), max_author);
}

TEST_F(Capi, BytesAccessorsOfNullAndForeignHandles) {
  for (const csc_bytes* bad :
       {static_cast<const csc_bytes*>(nullptr), foreign<const csc_bytes>(mesh.get()),
        foreign<const csc_bytes>(diff.get()), foreign<const csc_bytes>(merger.get())}) {
    EXPECT_EQ(csc_bytes_data(bad), nullptr);
    EXPECT_EQ(csc_bytes_size(bad), 0u);
  }
  EXPECT_NE(csc_bytes_data(bytes.get()), nullptr);
  EXPECT_GT(csc_bytes_size(bytes.get()), 0u);
}

// ==== wire: peek and decode of bad bytes ===================================================

/// A message that says something: "function: " then at least a few words of printable text.
::testing::AssertionResult readable_message(const char* function) {
  const std::string m = csc_last_error();
  const std::string prefix = std::string(function) + ": ";
  if (m.rfind(prefix, 0) != 0)
    return ::testing::AssertionFailure() << "message does not start with '" << prefix << "': " << m;
  const std::string rest = m.substr(prefix.size());
  const auto printable = std::count_if(rest.begin(), rest.end(), [](char ch) {
    return ch == ' ' || std::isalnum(static_cast<unsigned char>(ch));
  });
  if (rest.size() < 10 || rest.find(' ') == std::string::npos ||
      static_cast<std::size_t>(printable) * 10 < rest.size() * 8)
    return ::testing::AssertionFailure() << "message is not words: '" << m << "'";
  return ::testing::AssertionSuccess();
}

/// The receiver's two calls on `data`; every outcome must be a clean status.
void expect_clean_rejection_or_valid(const csc_mesh* base, const std::uint8_t* data,
                                     std::size_t size, bool must_fail, const std::string& what) {
  csc_message_info info = CSC_MESSAGE_INFO_INIT;
  info.sequence = 4242;
  mark_error();
  const csc_status peek = csc_diff_peek(data, size, &info);
  if (must_fail) {
    EXPECT_EQ(peek, CSC_ERROR_INVALID_INPUT) << what;
  }
  if (peek != CSC_OK) {
    EXPECT_TRUE(fails_with("csc_diff_peek", peek, CSC_ERROR_INVALID_INPUT, "")) << what;
    EXPECT_TRUE(readable_message("csc_diff_peek")) << what;
    EXPECT_EQ(info.sequence, 4242u) << what << ": peek wrote info on failure";
  }
  csc_diff* out = sentinel<csc_diff>();
  mark_error();
  const csc_status dec = csc_diff_decode(&out, base, 3, data, size, nullptr);
  if (must_fail) {
    EXPECT_NE(dec, CSC_OK) << what;
  }
  if (dec == CSC_OK) {
    EXPECT_EQ(peek, CSC_OK) << what << ": decoded what peek refused";
    DiffPtr d(out);
    // Whatever decodes is a diff that fits the base.
    csc_mesh* c = nullptr;
    ASSERT_OK(csc_mesh_clone(&c, base));
    MeshPtr copy(c);
    EXPECT_EQ(csc_mesh_apply_diff(copy.get(), d.get()), CSC_OK) << what << csc_last_error();
  } else {
    EXPECT_TRUE(dec == CSC_ERROR_INVALID_INPUT || dec == CSC_ERROR_UNKNOWN_BASE_VERSION)
        << what << ": " << csc_status_str(dec);
    EXPECT_TRUE(fails_with("csc_diff_decode", dec, dec, "")) << what;
    EXPECT_TRUE(readable_message("csc_diff_decode")) << what;
    EXPECT_EQ(out, sentinel<csc_diff>()) << what << ": decode wrote *out on failure";
  }
}

TEST_F(Capi, PeekAndDecodeBadArguments) {
  const auto* data = csc_bytes_data(bytes.get());
  const std::size_t size = csc_bytes_size(bytes.get());
  csc_message_info info = CSC_MESSAGE_INFO_INIT;
  info.sequence = 99;
  EXPECT_FAILS(csc_diff_peek(data, size, nullptr), CSC_ERROR_INVALID_ARGUMENT, "info");
  EXPECT_FAILS(csc_diff_peek(nullptr, size, &info), CSC_ERROR_INVALID_ARGUMENT, "data");
  info.struct_size = sizeof(info) - 1;
  EXPECT_FAILS(csc_diff_peek(data, size, &info), CSC_ERROR_INVALID_ARGUMENT, "struct_size");
  info.struct_size = 0;
  EXPECT_FAILS(csc_diff_peek(data, size, &info), CSC_ERROR_INVALID_ARGUMENT, "struct_size");
  EXPECT_EQ(info.sequence, 99u);
  info.struct_size = sizeof(info);
  EXPECT_FAILS(csc_diff_peek(nullptr, 0, &info), CSC_ERROR_INVALID_INPUT, "");
  EXPECT_EQ(info.sequence, 99u);

  csc_diff* out = sentinel<csc_diff>();
  EXPECT_FAILS(csc_diff_decode(nullptr, mesh.get(), 3, data, size, nullptr),
               CSC_ERROR_INVALID_ARGUMENT, "out");
  EXPECT_FAILS(csc_diff_decode(&out, nullptr, 3, data, size, nullptr), CSC_ERROR_INVALID_ARGUMENT,
               "base");
  EXPECT_FAILS(csc_diff_decode(&out, foreign<csc_mesh>(hierarchy.get()), 3, data, size, nullptr),
               CSC_ERROR_INVALID_ARGUMENT, "kind");
  EXPECT_FAILS(csc_diff_decode(&out, mesh.get(), 3, nullptr, size, nullptr),
               CSC_ERROR_INVALID_ARGUMENT, "data");
  info.struct_size = 4;
  EXPECT_FAILS(csc_diff_decode(&out, mesh.get(), 3, data, size, &info), CSC_ERROR_INVALID_ARGUMENT,
               "struct_size");
  EXPECT_EQ(out, sentinel<csc_diff>());
  EXPECT_EQ(info.sequence, 99u);
}

TEST_F(Capi, DecodeAgainstTheWrongBaseOrMesh) {
  const auto* data = csc_bytes_data(bytes.get());
  const std::size_t size = csc_bytes_size(bytes.get());
  csc_diff* out = sentinel<csc_diff>();
  csc_message_info info = CSC_MESSAGE_INFO_INIT;
  info.sequence = 99;
  for (std::uint64_t version : {0ull, 2ull, 4ull, ~0ull})
    EXPECT_FAILS(csc_diff_decode(&out, mesh.get(), version, data, size, &info),
                 CSC_ERROR_UNKNOWN_BASE_VERSION, "version");
  MeshPtr smaller = Grid(kN - 1).make();
  EXPECT_FAILS(csc_diff_decode(&out, smaller.get(), 3, data, size, &info), CSC_ERROR_INVALID_INPUT,
               "vertices");
  MeshPtr bare = Grid(kN, false).make();  // lacks the channels the message carries
  EXPECT_FAILS(csc_diff_decode(&out, bare.get(), 3, data, size, &info), CSC_ERROR_INVALID_INPUT,
               "channel");
  Grid wide(kN);
  wide.channels[1].width = 2;  // "tint" of another width
  MeshPtr other_width = wide.make();
  EXPECT_FAILS(csc_diff_decode(&out, other_width.get(), 3, data, size, &info),
               CSC_ERROR_INVALID_INPUT, "width");
  EXPECT_EQ(out, sentinel<csc_diff>());
  EXPECT_EQ(info.sequence, 99u);

  ASSERT_OK(csc_diff_decode(&out, mesh.get(), 3, data, size, &info));
  DiffPtr d(out);
  EXPECT_EQ(info.sequence, 11u);
  EXPECT_EQ(info.base_version, 3u);
  EXPECT_STREQ(info.author, "ann");
}

TEST_F(Capi, PeekBorrowsTheAuthorFromTheBytesAndAnAbsentAuthorIsEmpty) {
  const std::uint8_t* data = csc_bytes_data(bytes.get());
  const std::size_t size = csc_bytes_size(bytes.get());
  csc_message_info info = CSC_MESSAGE_INFO_INIT;
  ASSERT_OK(csc_diff_peek(data, size, &info));
  EXPECT_STREQ(info.author, "ann");
  const auto* author = reinterpret_cast<const std::uint8_t*>(info.author);
  EXPECT_TRUE(author >= data && author + 4 <= data + size) << "author not borrowed from data";
  EXPECT_EQ(info.protocol, csc_wire_protocol_version());
  EXPECT_EQ(info.vertex_count, kN * kN);

  csc_encode_options o = CSC_ENCODE_OPTIONS_INIT;
  o.author = nullptr;
  csc_bytes* b = nullptr;
  ASSERT_OK(csc_diff_encode(&b, diff.get(), mesh.get(), &o));
  BytesPtr anonymous(b);
  info = CSC_MESSAGE_INFO_INIT;
  ASSERT_OK(csc_diff_peek(csc_bytes_data(b), csc_bytes_size(b), &info));
  ASSERT_NE(info.author, nullptr);
  EXPECT_STREQ(info.author, "");
  csc_diff* d = nullptr;
  info = CSC_MESSAGE_INFO_INIT;
  ASSERT_OK(csc_diff_decode(&d, mesh.get(), 0, csc_bytes_data(b), csc_bytes_size(b), &info));
  DiffPtr decoded(d);
  ASSERT_NE(info.author, nullptr);
  EXPECT_STREQ(info.author, "");
}

TEST_F(Capi, RandomBytesAreRejectedCleanly) {
  std::mt19937 rng(20240611);
  std::uniform_int_distribution<int> byte(0, 255);
  std::uniform_int_distribution<std::size_t> length(0, 600);
  for (int round = 0; round < 1500; ++round) {
    const std::size_t n = length(rng);
    // Exactly sized heap blocks: a read past the end is an ASan error.
    std::unique_ptr<std::uint8_t[]> buf(new std::uint8_t[n]);
    for (std::size_t i = 0; i < n; ++i) buf[i] = static_cast<std::uint8_t>(byte(rng));
    // Half of them carry the file identifier, so the verifier has to look further.
    if (round % 2 == 1 && n >= 8) std::memcpy(buf.get() + 4, "CSD1", 4);
    expect_clean_rejection_or_valid(mesh.get(), buf.get(), n, true,
                                    "random buffer " + std::to_string(round));
  }
}

TEST_F(Capi, EveryTruncationOfAMessageIsRejected) {
  const std::vector<std::uint8_t> msg = to_vector(bytes.get());
  for (std::size_t len = 0; len < msg.size(); ++len) {
    std::unique_ptr<std::uint8_t[]> buf(new std::uint8_t[len]);
    std::copy(msg.begin(), msg.begin() + static_cast<std::ptrdiff_t>(len), buf.get());
    expect_clean_rejection_or_valid(mesh.get(), buf.get(), len, true,
                                    "cut at " + std::to_string(len));
  }
}

TEST_F(Capi, EveryBitFlipOfASmallMessageIsHandledCleanly) {
  // A 3-vertex move and paint: a message small enough to flip every bit of.
  HostArrays edit(*host);
  for (std::uint32_t v : {5u, 40u, 41u}) {
    edit.positions[3 * v + 2] += 0.01f * static_cast<float>(v);
    edit.channels[0][v] = 0.25f;
  }
  DiffPtr small = capture(mesh.get(), edit);
  BytesPtr small_bytes = encode(small.get(), mesh.get());
  const std::vector<std::uint8_t> msg = to_vector(small_bytes.get());
  RecordProperty("small_message_bytes", static_cast<int>(msg.size()));
  ASSERT_LT(msg.size(), 400u);
  std::size_t decoded = 0, rejected = 0;
  for (std::size_t i = 0; i < msg.size(); ++i)
    for (int bit = 0; bit < 8; ++bit) {
      std::unique_ptr<std::uint8_t[]> buf(new std::uint8_t[msg.size()]);
      std::copy(msg.begin(), msg.end(), buf.get());
      buf[i] ^= static_cast<std::uint8_t>(1u << bit);
      csc_diff* out = nullptr;
      const csc_status s = csc_diff_decode(&out, mesh.get(), 3, buf.get(), msg.size(), nullptr);
      csc_diff_destroy(out);
      (s == CSC_OK ? decoded : rejected) += 1;
      expect_clean_rejection_or_valid(mesh.get(), buf.get(), msg.size(), false,
                                      "byte " + std::to_string(i) + " bit " + std::to_string(bit));
    }
  EXPECT_GT(rejected, 0u);
  RecordProperty("bit_flips_decoded", static_cast<int>(decoded));
  RecordProperty("bit_flips_rejected", static_cast<int>(rejected));
}

TEST_F(Capi, RandomMutationsOfAMessageAreHandledCleanly) {
  const std::vector<std::uint8_t> msg = to_vector(bytes.get());
  std::mt19937 rng(77);
  std::uniform_int_distribution<std::size_t> pos(0, msg.size() - 1);
  std::uniform_int_distribution<int> byte(0, 255), edits(1, 8);
  for (int round = 0; round < 1500; ++round) {
    std::unique_ptr<std::uint8_t[]> buf(new std::uint8_t[msg.size()]);
    std::copy(msg.begin(), msg.end(), buf.get());
    for (int k = edits(rng); k > 0; --k) buf[pos(rng)] = static_cast<std::uint8_t>(byte(rng));
    expect_clean_rejection_or_valid(mesh.get(), buf.get(), msg.size(), false,
                                    "mutation " + std::to_string(round));
  }
}

// ==== merge ================================================================================

TEST(CapiMergeMethods, NamesRoundTripAndUnknownValuesAreRefused) {
  std::vector<std::string> names;
  for (int m = CSC_MERGE_FULL; m <= CSC_MERGE_PAPER_BLEND; ++m) {
    const char* name = csc_merge_method_name(static_cast<csc_merge_method>(m));
    ASSERT_NE(name, nullptr) << m;
    names.emplace_back(name);
    csc_merge_method back = CSC_MERGE_METHOD_MAX_ENUM;
    ASSERT_OK(csc_merge_method_from_name(&back, name));
    EXPECT_EQ(static_cast<int>(back), m) << name;
  }
  EXPECT_EQ(names[0], "full");
  EXPECT_EQ(names[1], "single-parent");
  std::sort(names.begin(), names.end());
  EXPECT_EQ(std::unique(names.begin(), names.end()), names.end());
  for (std::int64_t m : {9LL, 99LL, 0x7FFFFFFFLL})
    EXPECT_EQ(csc_merge_method_name(static_cast<csc_merge_method>(m)), nullptr) << m;

  csc_merge_method out = CSC_MERGE_SUM;
  EXPECT_FAILS(csc_merge_method_from_name(nullptr, "full"), CSC_ERROR_INVALID_ARGUMENT, "out");
  EXPECT_FAILS(csc_merge_method_from_name(&out, nullptr), CSC_ERROR_INVALID_ARGUMENT, "name");
  EXPECT_EQ(out, CSC_MERGE_SUM);
}

// An unknown name is an out-of-range argument (csculpt.h, "Errors"; the same mistake through
// csc_merge_options::method gives CSC_ERROR_INVALID_ARGUMENT).
TEST(CapiMergeMethods, UnknownNameIsInvalidArgument) {
  csc_merge_method out = CSC_MERGE_SUM;
  for (const char* bad : {"", "FULL", "nope", "full "})
    EXPECT_FAILS(csc_merge_method_from_name(&out, bad), CSC_ERROR_INVALID_ARGUMENT, "method");
  EXPECT_EQ(out, CSC_MERGE_SUM);
}

TEST_F(Capi, MergerCreateBadArguments) {
  csc_merger* out = sentinel<csc_merger>();
  EXPECT_FAILS(csc_merger_create(nullptr, hierarchy.get()), CSC_ERROR_INVALID_ARGUMENT, "out");
  EXPECT_FAILS(csc_merger_create(&out, nullptr), CSC_ERROR_INVALID_ARGUMENT, "hierarchy");
  EXPECT_FAILS(csc_merger_create(&out, foreign<csc_hierarchy>(mesh.get())),
               CSC_ERROR_INVALID_ARGUMENT, "kind");
  EXPECT_EQ(out, sentinel<csc_merger>());
}

TEST_F(Capi, MergeBadArguments) {
  const csc_diff* one[1] = {diff.get()};
  csc_diff* out = sentinel<csc_diff>();
  EXPECT_FAILS(csc_merger_merge(nullptr, &out, mesh.get(), one, 1, nullptr),
               CSC_ERROR_INVALID_ARGUMENT, "merger");
  EXPECT_FAILS(
      csc_merger_merge(foreign<csc_merger>(hierarchy.get()), &out, mesh.get(), one, 1, nullptr),
      CSC_ERROR_INVALID_ARGUMENT, "kind");
  EXPECT_FAILS(csc_merger_merge(merger.get(), nullptr, mesh.get(), one, 1, nullptr),
               CSC_ERROR_INVALID_ARGUMENT, "out");
  EXPECT_FAILS(csc_merger_merge(merger.get(), &out, nullptr, one, 1, nullptr),
               CSC_ERROR_INVALID_ARGUMENT, "base");
  EXPECT_FAILS(csc_merger_merge(merger.get(), &out, foreign<csc_mesh>(diff.get()), one, 1, nullptr),
               CSC_ERROR_INVALID_ARGUMENT, "kind");
  EXPECT_FAILS(csc_merger_merge(merger.get(), &out, mesh.get(), nullptr, 1, nullptr),
               CSC_ERROR_INVALID_ARGUMENT, "diffs");
  std::vector<const csc_diff*> many(65, diff.get());
  for (std::uint32_t count : {0u, 65u, 0xFFFFFFFFu})
    EXPECT_FAILS(csc_merger_merge(merger.get(), &out, mesh.get(), many.data(), count, nullptr),
                 CSC_ERROR_INVALID_ARGUMENT, "count");
  const csc_diff* with_null[3] = {diff.get(), nullptr, diff.get()};
  EXPECT_FAILS(csc_merger_merge(merger.get(), &out, mesh.get(), with_null, 3, nullptr),
               CSC_ERROR_INVALID_ARGUMENT, "diffs[1]");
  const csc_diff* with_foreign[2] = {diff.get(), foreign<const csc_diff>(mesh.get())};
  EXPECT_FAILS(csc_merger_merge(merger.get(), &out, mesh.get(), with_foreign, 2, nullptr),
               CSC_ERROR_INVALID_ARGUMENT, "diffs[1]");

  csc_merge_options o = CSC_MERGE_OPTIONS_INIT;
  o.struct_size = 0;
  EXPECT_FAILS(csc_merger_merge(merger.get(), &out, mesh.get(), one, 1, &o),
               CSC_ERROR_INVALID_ARGUMENT, "struct_size");
  for (std::int64_t m : {9LL, 99LL, 0x7FFFFFFFLL}) {
    o = CSC_MERGE_OPTIONS_INIT;
    o.method = static_cast<csc_merge_method>(m);
    EXPECT_FAILS(csc_merger_merge(merger.get(), &out, mesh.get(), one, 1, &o),
                 CSC_ERROR_INVALID_ARGUMENT, "method");
  }
  for (int bad = 0; bad < 4; ++bad) {
    o = CSC_MERGE_OPTIONS_INIT;
    o.use_frame = 1;
    if (bad == 0) o.frame_scale = 0.f;
    if (bad == 1) o.frame_scale = -1.f;
    if (bad == 2) o.frame_scale = kInf;
    if (bad == 3) o.frame_center[1] = kNaN;
    EXPECT_FAILS(csc_merger_merge(merger.get(), &out, mesh.get(), one, 1, &o),
                 CSC_ERROR_INVALID_ARGUMENT, "frame");
  }
  EXPECT_EQ(out, sentinel<csc_diff>());
}

TEST_F(Capi, MergeOfMismatchedDataIsInvalidInput) {
  csc_diff* out = sentinel<csc_diff>();
  // A base that is not the hierarchy's mesh.
  MeshPtr smaller = Grid(kN - 1).make();
  HostArrays small_edit(smaller.get());
  brush(small_edit, kN - 1, 0.5f, 0.5f, 0.4f, {0.05f, 0.f, 0.f});
  DiffPtr small_diff = capture(smaller.get(), small_edit);
  const csc_diff* small_one[1] = {small_diff.get()};
  EXPECT_FAILS(csc_merger_merge(merger.get(), &out, smaller.get(), small_one, 1, nullptr),
               CSC_ERROR_INVALID_INPUT, "hierarchy");
  // Same vertex count, other connectivity.
  Grid flipped(kN);
  for (std::size_t t = 0; t < flipped.triangles.size(); t += 3)
    std::swap(flipped.triangles[t + 1], flipped.triangles[t + 2]);
  MeshPtr other = flipped.make();
  const csc_diff* one[1] = {diff.get()};
  EXPECT_FAILS(csc_merger_merge(merger.get(), &out, other.get(), one, 1, nullptr),
               CSC_ERROR_INVALID_INPUT, "");
  // A diff of another mesh next to a good one.
  const csc_diff* mixed[2] = {diff.get(), small_diff.get()};
  EXPECT_FAILS(csc_merger_merge(merger.get(), &out, mesh.get(), mixed, 2, nullptr),
               CSC_ERROR_INVALID_INPUT, "diff 1");
  EXPECT_EQ(out, sentinel<csc_diff>());
  // The merger is still usable after failures.
  ASSERT_OK(csc_merger_merge(merger.get(), &out, mesh.get(), one, 1, nullptr));
  DiffPtr merged(out);
}

TEST_F(Capi, MergeOf64CopiesIsTheEdit) {
  std::vector<const csc_diff*> many(64, diff.get());
  csc_merge_options o = CSC_MERGE_OPTIONS_INIT;
  o.method = CSC_MERGE_AVERAGE;
  csc_diff* out = nullptr;
  ASSERT_OK(csc_merger_merge(merger.get(), &out, mesh.get(), many.data(), 64, &o));
  DiffPtr merged(out);
  const DiffContent a = content(diff.get()), m = content(out);
  EXPECT_EQ(a.indices, m.indices);
  ASSERT_EQ(a.values.size(), m.values.size());
  for (std::size_t i = 0; i < a.values.size(); ++i) EXPECT_NEAR(a.values[i], m.values[i], 1e-5f);
}

TEST_F(Capi, LastTimingsBadArgumentsAndValues) {
  csc_merge_timings t = CSC_MERGE_TIMINGS_INIT;
  t.blend_ms = -7;
  EXPECT_FAILS(csc_merger_last_timings(nullptr, &t), CSC_ERROR_INVALID_ARGUMENT, "merger");
  EXPECT_FAILS(csc_merger_last_timings(foreign<csc_merger>(diff.get()), &t),
               CSC_ERROR_INVALID_ARGUMENT, "kind");
  EXPECT_FAILS(csc_merger_last_timings(merger.get(), nullptr), CSC_ERROR_INVALID_ARGUMENT, "out");
  t.struct_size = sizeof(t) - 8;
  EXPECT_FAILS(csc_merger_last_timings(merger.get(), &t), CSC_ERROR_INVALID_ARGUMENT,
               "struct_size");
  EXPECT_EQ(t.blend_ms, -7);
  const csc_diff* one[1] = {diff.get()};
  csc_diff* out = nullptr;
  ASSERT_OK(csc_merger_merge(merger.get(), &out, mesh.get(), one, 1, nullptr));
  DiffPtr merged(out);
  t = CSC_MERGE_TIMINGS_INIT;
  ASSERT_OK(csc_merger_last_timings(merger.get(), &t));
  for (double ms : {t.isometry_ms, t.decompose_ms, t.blend_ms, t.apply_ms}) {
    EXPECT_GE(ms, 0.0);
    EXPECT_LT(ms, 60000.0);
  }
}

TEST(CapiMergeOrder, ThreeDiffsInAllSixOrdersGiveTheSameBits) {
  constexpr std::uint32_t n = 20;
  Grid g(n);
  MeshPtr base = g.make();
  ASSERT_TRUE(base);
  csc_hierarchy* h = nullptr;
  ASSERT_OK(csc_hierarchy_build(&h, base.get(), nullptr));
  HierarchyPtr hierarchy(h);
  csc_merger* m = nullptr;
  ASSERT_OK(csc_merger_create(&m, h));
  MergerPtr merger(m);
  const HostArrays host(base.get());
  // Three overlapping edits: the case where order could matter.
  HostArrays a(host), b(host), c(host);
  brush(a, n, 0.4f, 0.5f, 0.35f, {0.f, 0.f, 0.08f}, 1, 0.9f);
  brush(b, n, 0.55f, 0.5f, 0.3f, {0.03f, 0.f, -0.02f}, 0, 0.1f);
  brush(c, n, 0.5f, 0.4f, 0.3f, {0.f, 0.04f, 0.01f}, 1, 0.2f);
  std::array<DiffPtr, 3> diffs = {capture(base.get(), a), capture(base.get(), b),
                                  capture(base.get(), c)};
  for (int method = CSC_MERGE_FULL; method <= CSC_MERGE_PAPER_BLEND; ++method) {
    SCOPED_TRACE(csc_merge_method_name(static_cast<csc_merge_method>(method)));
    csc_merge_options o = CSC_MERGE_OPTIONS_INIT;
    o.method = static_cast<csc_merge_method>(method);
    std::array<int, 3> order = {0, 1, 2};
    std::unique_ptr<DiffContent> first;
    std::unique_ptr<HostArrays> first_applied;
    int orders = 0;
    do {
      const csc_diff* list[3] = {diffs[order[0]].get(), diffs[order[1]].get(),
                                 diffs[order[2]].get()};
      csc_diff* out = nullptr;
      ASSERT_OK(csc_merger_merge(merger.get(), &out, base.get(), list, 3, &o));
      DiffPtr merged(out);
      HostArrays applied(host);
      const csc_vertex_arrays arrays = applied.arrays();
      ASSERT_OK(csc_diff_apply_arrays(out, base.get(), &arrays));
      if (!first) {
        first = std::make_unique<DiffContent>(content(out));
        first_applied = std::make_unique<HostArrays>(applied);
        EXPECT_FALSE(first->indices.empty());
      } else {
        EXPECT_TRUE(content(out) == *first) << "order " << order[0] << order[1] << order[2];
        EXPECT_TRUE(applied == *first_applied) << "order " << order[0] << order[1] << order[2];
      }
      ++orders;
    } while (std::next_permutation(order.begin(), order.end()));
    EXPECT_EQ(orders, 6);
  }
}

// ==== destroy ==============================================================================

TEST_F(Capi, DestroyAcceptsNullAndIgnoresForeignHandles) {
  csc_mesh_destroy(nullptr);
  csc_hierarchy_destroy(nullptr);
  csc_diff_destroy(nullptr);
  csc_merger_destroy(nullptr);
  csc_bytes_destroy(nullptr);
  // Each destroy given a live handle of every other kind: refused, the handle stays usable.
  csc_mesh_destroy(foreign<csc_mesh>(diff.get()));
  csc_mesh_destroy(foreign<csc_mesh>(hierarchy.get()));
  csc_mesh_destroy(foreign<csc_mesh>(merger.get()));
  csc_mesh_destroy(foreign<csc_mesh>(bytes.get()));
  csc_hierarchy_destroy(foreign<csc_hierarchy>(mesh.get()));
  csc_hierarchy_destroy(foreign<csc_hierarchy>(diff.get()));
  csc_diff_destroy(foreign<csc_diff>(mesh.get()));
  csc_diff_destroy(foreign<csc_diff>(bytes.get()));
  csc_merger_destroy(foreign<csc_merger>(hierarchy.get()));
  csc_merger_destroy(foreign<csc_merger>(mesh.get()));
  csc_bytes_destroy(foreign<csc_bytes>(diff.get()));
  csc_bytes_destroy(foreign<csc_bytes>(merger.get()));
  EXPECT_EQ(csc_mesh_vertex_count(mesh.get()), kN * kN);
  EXPECT_NE(csc_hierarchy_digest(hierarchy.get()), 0u);
  csc_diff_info info = CSC_DIFF_INFO_INIT;
  EXPECT_EQ(csc_diff_get_info(diff.get(), &info), CSC_OK);
  EXPECT_GT(csc_bytes_size(bytes.get()), 0u);
  const csc_diff* one[1] = {diff.get()};
  csc_diff* out = nullptr;
  ASSERT_OK(csc_merger_merge(merger.get(), &out, mesh.get(), one, 1, nullptr));
  csc_diff_destroy(out);
}

// ==== threads ==============================================================================

TEST(CapiThreads, OneMeshReadConcurrentlyGivesEqualResults) {
  Grid g(48);
  MeshPtr base = g.make();
  ASSERT_TRUE(base);
  HostArrays edit(base.get());
  brush(edit, 48, 0.5f, 0.5f, 0.3f, {0.f, 0.f, 0.05f}, 1);
  DiffPtr d = capture(base.get(), edit);
  csc_hierarchy* h = nullptr;
  ASSERT_OK(csc_hierarchy_build(&h, base.get(), nullptr));
  HierarchyPtr reference(h);
  const std::uint64_t expected_digest = csc_hierarchy_digest(h);
  BytesPtr expected_bytes = encode(d.get(), base.get());
  const std::vector<std::uint8_t> expected_message = to_vector(expected_bytes.get());

  struct Result {
    std::uint64_t digest = 0;
    std::vector<std::uint8_t> message;
    bool ok = false;
  };
  std::array<Result, 2> results;
  std::array<std::thread, 2> threads;
  for (std::size_t t = 0; t < threads.size(); ++t)
    threads[t] = std::thread([&, t] {
      Result& r = results[t];
      for (int round = 0; round < 3; ++round) {
        csc_hierarchy* mine = nullptr;
        if (csc_hierarchy_build(&mine, base.get(), nullptr) != CSC_OK) return;
        r.digest = csc_hierarchy_digest(mine);
        csc_hierarchy_destroy(mine);
        csc_bytes* b = nullptr;
        if (csc_diff_encode(&b, d.get(), base.get(), nullptr) != CSC_OK) return;
        csc_bytes_destroy(b);
        csc_channel_view v = CSC_CHANNEL_VIEW_INIT;
        if (csc_mesh_channel(base.get(), 1, &v) != CSC_OK || v.desc.width != 3) return;
      }
      csc_encode_options o = CSC_ENCODE_OPTIONS_INIT;
      o.base_version = 3;
      o.sequence = 11;
      o.author = "ann";
      csc_bytes* b = nullptr;
      if (csc_diff_encode(&b, d.get(), base.get(), &o) != CSC_OK) return;
      r.message = to_vector(b);
      csc_bytes_destroy(b);
      r.ok = true;
    });
  for (auto& t : threads) t.join();
  for (const Result& r : results) {
    ASSERT_TRUE(r.ok);
    EXPECT_EQ(r.digest, expected_digest);
    EXPECT_EQ(r.message, expected_message);
  }
}

}  // namespace
