// One mesh used from several threads at once through the C ABI: hierarchy builds, encodes
// and channel reads give the same results as on one thread.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <thread>
#include <vector>

#include "capi_test.h"
#include "csculpt.h"
#include "host_arrays.h"

namespace {

using namespace capi_test;

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
