// Peers on different machines must merge to the same bits. Two things differ between
// machines: the blend kernel's width, SSE2 (4 nodes per register) or AVX2 (8 nodes), chosen at
// run time by the CPU, and the number of threads a Merger's pool runs. Both must give
// bit-identical merges: asserted here on real meshes (assimp's Spider STL, 18 components; the
// Blender cases' Suzanne) and the built-in sphere, 2 to 4 users, every method, with materials
// on the sphere (channels merge outside the kernel, and must stay identical too).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "csculpt/diff.h"
#include "csculpt/hierarchy.h"
#include "csculpt/io.h"
#include "csculpt/merge.h"
#include "csculpt/testkit/generate.h"
#include "csculpt/testkit/random.h"
#include "simd/blend_kernel.h"
#include "simd/face_rotation_lanes.h"

namespace csculpt {
namespace {

namespace fs = std::filesystem;

bool same_bits(const AttributeDiff& a, const AttributeDiff& b) {
  return a.indices == b.indices && a.values.size() == b.values.size() &&
         std::memcmp(a.values.data(), b.values.data(), a.values.size() * sizeof(float)) == 0;
}

/// Restores the automatic choice however the test ends.
struct BaselineOnly {
  BaselineOnly() { detail::set_simd_baseline_only(true); }
  ~BaselineOnly() { detail::set_simd_baseline_only(false); }
};

std::vector<std::pair<std::string, Mesh>> subjects() {
  std::vector<std::pair<std::string, Mesh>> out;
  out.emplace_back("sphere20k", make_sphere(20000, /*materials=*/true));
  const std::string spider = std::string(CSCULPT_TEST_MODELS) + "/STL/Spider_binary.stl";
  std::error_code ec;
  if (fs::is_regular_file(spider, ec)) out.emplace_back("Spider_binary.stl", read_mesh(spider));
  const fs::path suzanne = fs::path(CSCULPT_EVAL_CASES) / "grab_plus_detail_monkey" / "base.ply";
  if (fs::is_regular_file(suzanne, ec)) out.emplace_back("suzanne", read_mesh(suzanne.string()));
  return out;
}

/// Each of `users` artists' scripted strokes on `base`, as diffs.
std::vector<Diff> user_diffs(const Mesh& base, const Hierarchy& hierarchy, std::uint32_t users) {
  const bool paint = base.find_channel("albedo") >= 0;
  std::vector<Diff> diffs;
  for (std::uint32_t u = 0; u < users; ++u) {
    Mesh edit = base;
    for (const Stroke& s : scripted_strokes(base, 7000 + 31 * u + users, 6, paint))
      apply_stroke(edit, s, &hierarchy.topology());
    diffs.push_back(capture_diff(base, edit));
  }
  return diffs;
}

/// Asserts two merges are the same bits, positions and every channel.
void expect_same_bits(const Diff& a, const Diff& b, const std::string& what) {
  ASSERT_TRUE(same_bits(a.positions, b.positions)) << what;
  ASSERT_EQ(a.channels.size(), b.channels.size()) << what;
  for (std::size_t c = 0; c < a.channels.size(); ++c)
    ASSERT_TRUE(same_bits(a.channels[c].change, b.channels[c].change))
        << what << ", channel " << a.channels[c].desc.name;
}

/// Runs `compare(hierarchy, base, diffs, method, what)` for every subject, 2 to 4
/// users and every method; `compare` returns the reference merge it compared against. Asserts
/// the comparisons were made and moved vertices, so they are not vacuous.
template <class Compare>
void for_every_merge(Compare compare) {
  std::size_t compared = 0, moved = 0;
  for (const auto& [name, base] : subjects()) {
    const Hierarchy hierarchy = Hierarchy::build(base);
    for (std::uint32_t users = 2; users <= 4; ++users) {
      const std::vector<Diff> diffs = user_diffs(base, hierarchy, users);
      for (MergeMethod method : all_merge_methods()) {
        const std::string what =
            name + ", " + std::to_string(users) + " users, " + std::string(to_string(method));
        const Diff reference = compare(hierarchy, base, diffs, method, what);
        if (::testing::Test::HasFatalFailure()) return;
        ++compared;
        moved += reference.positions.size();
      }
    }
  }
  EXPECT_GE(compared, 3u * 8u);
  EXPECT_GT(moved, 0u);
}

TEST(SimdDispatch, Avx2AndSse2KernelsMergeToTheSameBits) {
  detail::set_simd_baseline_only(false);
  // compared only where the AVX2 kernel is what merges use
  if (detail::blend_chunk_avx2() == nullptr ||
      detail::blend_chunk_kernel() != detail::blend_chunk_avx2())
    GTEST_SKIP() << "the AVX2 kernel is not built or this CPU lacks AVX2 (or CSCULPT_SIMD=sse2)";
  for_every_merge([](const Hierarchy& hierarchy, const Mesh& base, const std::vector<Diff>& diffs,
                     MergeMethod method, const std::string& what) {
    Merger merger(hierarchy);
    const Diff wide = merger.merge(base, diffs, method);
    BaselineOnly baseline;
    EXPECT_NE(detail::blend_chunk_kernel(), detail::blend_chunk_avx2());
    expect_same_bits(wide, merger.merge(base, diffs, method), what);
    return wide;
  });
}

// The pool's chunks are fixed by the work, not by the threads, and each writes its own
// outputs: so one thread, two, three and eight (more threads than a small machine has cores)
// must give the same bits.
TEST(MergeThreads, OneTwoThreeAndEightThreadsMergeToTheSameBits) {
  for_every_merge([](const Hierarchy& hierarchy, const Mesh& base, const std::vector<Diff>& diffs,
                     MergeMethod method, const std::string& what) {
    Merger alone(hierarchy, 1);
    const Diff reference = alone.merge(base, diffs, method);
    for (unsigned threads : {2u, 3u, 8u}) {
      Merger merger(hierarchy, threads);
      expect_same_bits(merger.merge(base, diffs, method), reference,
                       what + ", " + std::to_string(threads) + " threads");
    }
    return reference;
  });
}

// The face-rotation kernel directly: every count from 1 to 40 (so every tail length of
// both widths), random faces with rotations small and large and some degenerate ones; the
// AVX2 build must compute the same faces to the same bits and decline the same ones.
TEST(SimdDispatch, FaceRotationsAgreeAtEveryCountAndTail) {
  if (detail::face_rotations_avx2() == nullptr)
    GTEST_SKIP() << "the AVX2 kernels are not built for this target";
  if (!__builtin_cpu_supports("avx2")) GTEST_SKIP() << "this CPU lacks AVX2";
  SplitMix64 rng;
  rng.state = 20261124;
  std::vector<Vec3f> base, edited;
  std::vector<std::uint32_t> triangles, faces;
  for (std::uint32_t f = 0; f < 40; ++f) {
    const float angle = static_cast<float>(f % 5 == 0 ? rng.range(1.0, 3.0) : rng.range(0, 0.3));
    const float c = std::cos(angle), s = std::sin(angle);
    for (int i = 0; i < 3; ++i) {
      const Vec3f p{static_cast<float>(rng.range(-1, 1)), static_cast<float>(rng.range(-1, 1)),
                    static_cast<float>(rng.range(-1, 1))};
      base.push_back(p);
      edited.push_back({c * p.x - s * p.y + 0.01f * static_cast<float>(rng.range(-1, 1)),
                        s * p.x + c * p.y, p.z + 0.5f});
      triangles.push_back(3 * f + static_cast<std::uint32_t>(i));
    }
    if (f % 7 == 3) base[3 * f + 2] = base[3 * f + 1];  // degenerate before
    faces.push_back(39 - f);                            // listed out of order
  }
  for (std::size_t count = 1; count <= faces.size(); ++count) {
    std::vector<Quat> narrow(count), wide(count);
    std::vector<std::uint32_t> redo_narrow(count), redo_wide(count);
    detail::FaceRotationArgs a;
    a.triangles = triangles.data();
    a.base = base.data();
    a.edited = edited.data();
    a.faces = faces.data();
    a.count = count;
    a.offsets = narrow.data();
    a.redo = redo_narrow.data();
    detail::set_simd_baseline_only(true);
    const std::size_t n_narrow = detail::face_rotations_kernel()(a);
    detail::set_simd_baseline_only(false);
    a.offsets = wide.data();
    a.redo = redo_wide.data();
    const std::size_t n_wide = detail::face_rotations_avx2()(a);
    ASSERT_EQ(n_narrow, n_wide) << count;
    ASSERT_LT(n_narrow, count) << "nothing computed in single precision: vacuous";
    redo_narrow.resize(n_narrow);
    redo_wide.resize(n_wide);
    ASSERT_EQ(redo_narrow, redo_wide) << count;
    for (std::size_t k = 0; k < count; ++k) {
      if (std::find(redo_narrow.begin(), redo_narrow.end(), k) != redo_narrow.end()) continue;
      ASSERT_EQ(std::memcmp(&narrow[k], &wide[k], sizeof(Quat)), 0) << count << " face " << k;
    }
  }
}

}  // namespace
}  // namespace csculpt
