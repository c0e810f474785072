// The C ABI's error reporting as a whole, through libcsculpt.so only (no SDK header): the
// version, every status's own text, the last-error message (thread-local, kept by successful
// calls), and the destroy functions with NULL and with live handles of the wrong kind. The
// bad arguments of each function are tested in the file of its area (test_capi_mesh.cpp,
// _io, _hierarchy, _diff, _wire, _merge).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "capi_test.h"
#include "csculpt.h"
#include "host_arrays.h"

namespace {

using namespace capi_test;

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

TEST_F(CapiEveryHandle, DestroyAcceptsNullAndIgnoresForeignHandles) {
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

}  // namespace
