// Merges through the C ABI: the method names, csc_merger_create and csc_merger_merge with
// bad arguments and mismatched data (the merger stays usable), 64 copies of one edit, the
// timings, and the same bits for three diffs in all six orders with every method.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "capi_test.h"
#include "csculpt.h"
#include "host_arrays.h"

namespace {

using namespace capi_test;

TEST(CapiMergeMethods, NamesRoundTripAndUnknownValuesAreRefused) {
  std::vector<std::string> names;
  for (int m = CSC_MERGE_FULL; m <= CSC_MERGE_FRAME_TRANSPORT; ++m) {
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
  for (std::int64_t m : {10LL, 99LL, 0x7FFFFFFFLL})
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

TEST_F(CapiEveryHandle, MergerCreateBadArguments) {
  csc_merger* out = sentinel<csc_merger>();
  EXPECT_FAILS(csc_merger_create(nullptr, hierarchy.get()), CSC_ERROR_INVALID_ARGUMENT, "out");
  EXPECT_FAILS(csc_merger_create(&out, nullptr), CSC_ERROR_INVALID_ARGUMENT, "hierarchy");
  EXPECT_FAILS(csc_merger_create(&out, foreign<csc_hierarchy>(mesh.get())),
               CSC_ERROR_INVALID_ARGUMENT, "kind");
  EXPECT_EQ(out, sentinel<csc_merger>());
}

TEST_F(CapiEveryHandle, MergeBadArguments) {
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
  for (std::int64_t m : {10LL, 99LL, 0x7FFFFFFFLL}) {
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

TEST_F(CapiEveryHandle, MergeOfMismatchedDataIsInvalidInput) {
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

TEST_F(CapiEveryHandle, MergeOf64CopiesIsTheEdit) {
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

TEST_F(CapiEveryHandle, LastTimingsBadArgumentsAndValues) {
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

}  // namespace
