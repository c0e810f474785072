// Diffs through the C ABI: capture from host arrays and from meshes (bad arguments, other
// counts, non-finite values, mismatched meshes), apply to a mesh and to host arrays (failures
// write nothing; only the listed vertices are written), inspection, newer output structs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "capi_test.h"
#include "csculpt.h"
#include "host_arrays.h"

namespace {

using namespace capi_test;

TEST_F(CapiGridEdit, CaptureArraysBadArguments) {
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
TEST_F(CapiGrid, CaptureArraysOfOtherCountsIsInvalidInput) {
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

TEST_F(CapiGrid, CaptureArraysWithNonFiniteChangesIsInvalidInput) {
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

TEST_F(CapiEveryHandle, CaptureOfMeshesBadArgumentsAndMismatches) {
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

TEST_F(CapiGridEdit, ApplyToMeshBadArgumentsLeaveTheMeshUnchanged) {
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

TEST_F(CapiEveryHandle, ApplyToArraysBadArgumentsWriteNothing) {
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

TEST_F(CapiGridEdit, ApplyToArraysTouchesOnlyListedVertices) {
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

TEST_F(CapiEveryHandle, DiffInspectionBadArgumentsLeaveOutputsAlone) {
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

TEST_F(CapiGridEdit, OutputStructsOfANewerHeaderKeepTheirTail) {
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

}  // namespace
