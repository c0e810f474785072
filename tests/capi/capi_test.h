// Shared by the C-ABI tests (test_capi_*.cpp), which use libcsculpt.so only (no SDK header):
// owning handle wrappers, the error expectations (EXPECT_FAILS: the status, a message of the
// call's own naming the problem), meshes and edits made here, diff and message helpers, and
// the fixtures that set up a grid mesh, an edit of it, and a handle of every kind.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "csculpt.h"
#include "host_arrays.h"

namespace capi_test {

inline constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
inline constexpr float kInf = std::numeric_limits<float>::infinity();

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

inline constexpr const char* kMarker = "csculpt-error-marker";

/// Leaves a known message behind, so a later check sees the failing call's own message.
inline void mark_error() {
  csc_mesh* m = nullptr;
  const std::string path = std::string("/nonexistent/") + kMarker + ".ply";
  ASSERT_EQ(csc_mesh_read(&m, path.c_str()), CSC_ERROR_IO);
  ASSERT_NE(std::strstr(csc_last_error(), kMarker), nullptr);
}

inline ::testing::AssertionResult fails_with(const char* call, csc_status got, csc_status want,
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
inline void brush(HostArrays& h, std::uint32_t n, float cx, float cy, float radius,
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

inline DiffPtr capture(const csc_mesh* base, HostArrays& h) {
  csc_diff* d = nullptr;
  const csc_vertex_arrays a = h.arrays();
  const csc_status s = csc_diff_capture_arrays(&d, base, &a);
  EXPECT_EQ(s, CSC_OK) << csc_last_error();
  return DiffPtr(d);
}

inline BytesPtr encode(const csc_diff* diff, const csc_mesh* base, std::uint64_t version = 3,
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

inline std::vector<std::uint8_t> to_vector(const csc_bytes* b) {
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

inline DiffContent content(const csc_diff* d) {
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

// ---- fixtures ------------------------------------------------------------------------------

/// A 12 x 12 grid mesh with the channels "mask" and "tint" (`mesh`, made from `grid`) and the
/// host's copy of its arrays (`host`).
class CapiGrid : public ::testing::Test {
 protected:
  static constexpr std::uint32_t kN = 12;
  void SetUp() override {
    grid = std::make_unique<Grid>(kN);
    mesh = grid->make();
    ASSERT_TRUE(mesh);
    host = std::make_unique<HostArrays>(mesh.get());
  }

  std::unique_ptr<Grid> grid;
  MeshPtr mesh;
  std::unique_ptr<HostArrays> host;
};

/// CapiGrid and one edit of it, a patch moved up and painted in "tint" (`diff`), encoded as a
/// message (`bytes`: base version 3, sequence 11, author "ann").
class CapiGridEdit : public CapiGrid {
 protected:
  void SetUp() override {
    CapiGrid::SetUp();
    if (HasFatalFailure()) return;
    HostArrays edit(*host);
    brush(edit, kN, 0.3f, 0.4f, 0.3f, {0.f, 0.f, 0.1f}, 1);
    diff = capture(mesh.get(), edit);
    ASSERT_TRUE(diff);
    bytes = encode(diff.get(), mesh.get());
    ASSERT_TRUE(bytes);
  }

  DiffPtr diff;
  BytesPtr bytes;
};

/// CapiGridEdit and the grid's `hierarchy` and a `merger` on it: a live handle of every kind,
/// for the calls under test and as the foreign handles a confused host passes.
class CapiEveryHandle : public CapiGridEdit {
 protected:
  void SetUp() override {
    CapiGridEdit::SetUp();
    if (HasFatalFailure()) return;
    csc_hierarchy* h = nullptr;
    ASSERT_OK(csc_hierarchy_build(&h, mesh.get(), nullptr));
    hierarchy.reset(h);
    csc_merger* m = nullptr;
    ASSERT_OK(csc_merger_create(&m, hierarchy.get()));
    merger.reset(m);
  }

  HierarchyPtr hierarchy;
  MergerPtr merger;
};

}  // namespace capi_test
