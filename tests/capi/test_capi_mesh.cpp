// Meshes through the C ABI: csc_mesh_create with bad arguments and invalid meshes (the
// specific status, a message naming the problem, *out untouched), newer struct sizes, the
// accessors (host arrays round trip; NULL and foreign handles give empty values), channels,
// material channels and clone.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "capi_test.h"
#include "csculpt.h"
#include "host_arrays.h"

namespace {

using namespace capi_test;

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

TEST_F(CapiEveryHandle, AccessorsOfNullAndForeignHandlesGiveEmptyValues) {
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

TEST_F(CapiGridEdit, MeshChannelBadArguments) {
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

TEST_F(CapiEveryHandle, AddMaterialChannels) {
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

TEST_F(CapiGridEdit, CloneBadArgumentsAndDeepCopy) {
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

}  // namespace
