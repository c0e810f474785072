// The blend kernel runs as SSE2 (4 nodes per register) or AVX2 (8 nodes), chosen at run
// time by the CPU. Peers on different CPUs must merge to the same bits, so both widths must
// give bit-identical merges: asserted here on real meshes (assimp's Spider STL, 18
// components; the Blender cases' Suzanne) and the built-in sphere, 2 to 4 users, every
// method, with materials on the sphere (channels merge outside the kernel, and must
// stay identical too).
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "blend_kernel.h"
#include "csculpt/diff.h"
#include "csculpt/generate.h"
#include "csculpt/hierarchy.h"
#include "csculpt/io.h"
#include "csculpt/merge.h"

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

TEST(SimdDispatch, Avx2AndSse2KernelsMergeToTheSameBits) {
  detail::set_simd_baseline_only(false);
  if (detail::blend_chunk_kernel() == detail::blend_chunk_avx2() &&
      detail::blend_chunk_avx2() != nullptr) {
    // the AVX2 kernel is what merges use here: compare it against the baseline
  } else {
    GTEST_SKIP() << "the AVX2 kernel is not built or this CPU lacks AVX2 (or CSCULPT_SIMD=sse2)";
  }
  std::size_t compared = 0, moved = 0;
  for (const auto& [name, base] : subjects()) {
    const Hierarchy hierarchy = Hierarchy::build(base);
    const bool paint = base.find_channel("albedo") >= 0;
    for (std::uint32_t users = 2; users <= 4; ++users) {
      std::vector<Diff> diffs;
      for (std::uint32_t u = 0; u < users; ++u) {
        Mesh edit = base;
        const Topology& topology = hierarchy.topology();
        for (const Stroke& s : scripted_strokes(base, 7000 + 31 * u + users, 6, paint))
          apply_stroke(edit, s, &topology);
        diffs.push_back(capture_diff(base, edit));
      }
      for (MergeMethod method : all_merge_methods()) {
        Merger merger(hierarchy);
        const Diff wide = merger.merge(base, diffs, method);
        Diff narrow;
        {
          BaselineOnly baseline;
          ASSERT_NE(detail::blend_chunk_kernel(), detail::blend_chunk_avx2());
          narrow = merger.merge(base, diffs, method);
        }
        const std::string what =
            name + ", " + std::to_string(users) + " users, " + std::string(to_string(method));
        ASSERT_TRUE(same_bits(wide.positions, narrow.positions)) << what;
        ASSERT_EQ(wide.channels.size(), narrow.channels.size()) << what;
        for (std::size_t c = 0; c < wide.channels.size(); ++c)
          ASSERT_TRUE(same_bits(wide.channels[c].change, narrow.channels[c].change))
              << what << ", channel " << wide.channels[c].desc.name;
        ++compared;
        moved += wide.positions.size();
      }
    }
  }
  EXPECT_GE(compared, 3u * 8u);
  EXPECT_GT(moved, 0u);  // the merges did move vertices: the comparison is not vacuous
}

}  // namespace
}  // namespace csculpt
