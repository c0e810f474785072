// Hierarchies through the C ABI: csc_hierarchy_build and its accessors with bad arguments
// and foreign handles, the statistics, and the digest (deterministic; K = 1 differs).
#include <gtest/gtest.h>

#include <cstdint>

#include "capi_test.h"
#include "csculpt.h"
#include "host_arrays.h"

namespace {

using namespace capi_test;

TEST_F(CapiEveryHandle, HierarchyBadArguments) {
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

TEST_F(CapiEveryHandle, HierarchyStatsAndOptions) {
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

}  // namespace
