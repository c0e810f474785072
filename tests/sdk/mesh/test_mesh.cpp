// Mesh basics: validation, connectivity checks, linearisation, channels, OpenMesh interop, and
// the shared test meshes themselves.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "csculpt/error.h"
#include "csculpt/mesh.h"
#include "csculpt/openmesh_interop.h"
#include "test_meshes.h"
#include "test_support.h"

namespace csculpt {
using csculpt::test::invalid_input_message;

namespace {

using test::first_difference;
using test::make_grid;
using test::make_icosphere;

// The message of the InvalidInput `fn` throws ("" and a test failure if it throws nothing).

Mesh single_triangle() {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.triangles = {{0, 1, 2}};
  return m;
}

// ------------------------------------------------------------------------------------------
// Test meshes

TEST(MeshTestMeshes, IcosphereIsAClosedOrientedUnitSphere) {
  for (int s = 0; s <= 3; ++s) {
    const Mesh m = make_icosphere(s);
    const std::size_t four_s = std::size_t{1} << (2 * s);
    EXPECT_EQ(m.vertex_count(), 10 * four_s + 2);
    EXPECT_EQ(m.face_count(), 20 * four_s);
    EXPECT_NO_THROW(validate(m, "icosphere"));
    for (const Vec3f& p : m.positions) {
      EXPECT_NEAR(std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z), 1.0f, 1e-6f);
    }
    // Closed and consistently oriented: every directed edge once, its reverse once.
    std::map<std::pair<std::uint32_t, std::uint32_t>, int> directed;
    double volume = 0;
    for (const Triangle& t : m.triangles) {
      for (int k = 0; k < 3; ++k) ++directed[{t[k], t[(k + 1) % 3]}];
      const Vec3f& a = m.positions[t[0]];
      const Vec3f& b = m.positions[t[1]];
      const Vec3f& c = m.positions[t[2]];
      volume += (a.x * (b.y * c.z - b.z * c.y) - a.y * (b.x * c.z - b.z * c.x) +
                 a.z * (b.x * c.y - b.y * c.x)) /
                6.0;
    }
    for (const auto& [edge, count] : directed) {
      EXPECT_EQ(count, 1);
      EXPECT_EQ(directed.count({edge.second, edge.first}), 1u);
    }
    EXPECT_GT(volume, 0.0) << "triangles must face outwards";
    EXPECT_LT(volume, 4.0 / 3.0 * M_PI);
  }
}

TEST(MeshTestMeshes, GridLayout) {
  const Mesh m = make_grid(4);
  EXPECT_EQ(m.vertex_count(), 25u);
  EXPECT_EQ(m.face_count(), 32u);
  EXPECT_NO_THROW(validate(m, "grid"));
  EXPECT_EQ(m.positions[24], (Vec3f{1, 1, 0}));
  EXPECT_FLOAT_EQ(bbox_diagonal(m.positions), std::sqrt(2.0f));
}

// ------------------------------------------------------------------------------------------
// validate

TEST(MeshValidate, AcceptsWellFormedMeshes) {
  Mesh m = make_icosphere(1);
  test::add_material_channels(m);
  EXPECT_NO_THROW(validate(m, "sphere"));
}

TEST(MeshValidate, RejectsEmptyMeshesAndPointClouds) {
  EXPECT_EQ(invalid_input_message([] { validate(Mesh{}, "a.ply"); }), "a.ply: no vertices");
  Mesh cloud;
  cloud.positions = {{0, 0, 0}, {1, 0, 0}};
  const std::string msg = invalid_input_message([&] { validate(cloud, "b.ply"); });
  EXPECT_EQ(msg.rfind("b.ply: no faces", 0), 0u) << msg;
  EXPECT_NE(msg.find("point clouds cannot be merged"), std::string::npos) << msg;
}

TEST(MeshValidate, RejectsBadIndices) {
  Mesh m = single_triangle();
  m.triangles.push_back({0, 2, 3});
  EXPECT_EQ(invalid_input_message([&] { validate(m, "x"); }),
            "x: triangle 1: vertex index 3 out of range (3 vertices)");
  m = single_triangle();
  m.triangles = {{0, 1, 2}, {2, 1, 2}};
  EXPECT_EQ(invalid_input_message([&] { validate(m, "x"); }),
            "x: triangle 1 (2, 1, 2) repeats vertex 2");
}

TEST(MeshValidate, RejectsNonFiniteValuesNamingVertexAndComponent) {
  Mesh m = single_triangle();
  m.positions[1].y = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(invalid_input_message([&] { validate(m, "m"); }), "m: vertex 1: position y is NaN");
  m = single_triangle();
  m.positions[2].z = -std::numeric_limits<float>::infinity();
  EXPECT_EQ(invalid_input_message([&] { validate(m, "m"); }), "m: vertex 2: position z is -Inf");

  m = single_triangle();
  m.add_channel({"albedo", 3, Linearisation::srgb});
  m.channels[0].values[2 * 3 + 1] = std::numeric_limits<float>::infinity();
  EXPECT_EQ(invalid_input_message([&] { validate(m, "m"); }),
            "m: vertex 2: channel albedo_g is +Inf");
  m.channels[0].values[2 * 3 + 1] = 0;
  m.add_channel({"mask", 1});
  m.channels[1].values[0] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(invalid_input_message([&] { validate(m, "m"); }), "m: vertex 0: channel mask is NaN");
}

/// A channel built member by member: GCC 12 at -O3 warns that a braced ChannelDesc temporary's
/// name "may be used uninitialized" (a false positive of the plain Release build).
Channel channel(const char* name, std::uint32_t width, std::vector<float> values) {
  Channel c;
  c.desc.name = name;
  c.desc.width = width;
  c.values = std::move(values);
  return c;
}

TEST(MeshValidate, RejectsBadChannelLayouts) {
  Mesh m = single_triangle();
  m.channels.push_back(channel("rough", 1, {0.5f, 0.5f}));
  EXPECT_EQ(invalid_input_message([&] { validate(m, "m"); }),
            "m: channel rough has 2 values, expected 3 (3 vertices x width 1)");
  m.channels.back() = channel("wide", 5, std::vector<float>(15, 0.f));
  EXPECT_EQ(invalid_input_message([&] { validate(m, "m"); }),
            "m: channel wide has width 5 (must be 1..4)");
  m.channels.back() = channel("", 1, std::vector<float>(3, 0.f));
  EXPECT_EQ(invalid_input_message([&] { validate(m, "m"); }), "m: channel 0 has an empty name");
  m.channels.back() = channel("a", 1, std::vector<float>(3, 0.f));
  m.channels.push_back(channel("a", 1, std::vector<float>(3, 0.f)));
  EXPECT_EQ(invalid_input_message([&] { validate(m, "m"); }), "m: channel a appears twice");
}

// ------------------------------------------------------------------------------------------
// check_same_connectivity

TEST(MeshConnectivity, AcceptsSameLayoutWithDifferentValues) {
  Mesh base = make_icosphere(1);
  test::add_material_channels(base);
  Mesh edited = base;
  edited.positions[3].x += 0.25f;
  edited.channels[0].values[0] = 0.125f;
  EXPECT_NO_THROW(check_same_connectivity(base, edited, "edit"));
}

TEST(MeshConnectivity, ReportsTheFirstDifference) {
  Mesh base = make_icosphere(1);
  test::add_material_channels(base);

  Mesh edited = base;
  edited.positions.pop_back();
  EXPECT_EQ(invalid_input_message([&] { check_same_connectivity(base, edited, "e1"); }),
            "e1: 41 vertices, but the base has 42");

  edited = base;
  edited.triangles.pop_back();
  EXPECT_EQ(invalid_input_message([&] { check_same_connectivity(base, edited, "e2"); }),
            "e2: 79 triangles, but the base has 80");

  edited = base;
  std::swap(edited.triangles[5][0], edited.triangles[5][1]);
  const std::string flipped =
      invalid_input_message([&] { check_same_connectivity(base, edited, "e3"); });
  EXPECT_EQ(flipped.rfind("e3: triangle 5 is (", 0), 0u) << flipped;

  edited = base;
  edited.channels.pop_back();
  EXPECT_EQ(invalid_input_message([&] { check_same_connectivity(base, edited, "e4"); }),
            "e4: 2 channels, but the base has 3");

  edited = base;
  edited.channels[2].desc.linearisation = Linearisation::identity;
  EXPECT_EQ(invalid_input_message([&] { check_same_connectivity(base, edited, "e5"); }),
            "e5: channel 2 is roughness (width 1, identity, range [0, 1]) but in the base it is "
            "roughness (width 1, square, range [0, 1])");
}

// ------------------------------------------------------------------------------------------
// Linearisation

TEST(MeshLinearisation, RoundTripsOverTheUnitInterval) {
  for (Linearisation lin : {Linearisation::identity, Linearisation::square, Linearisation::srgb}) {
    for (int i = 0; i <= 10000; ++i) {
      const float x = static_cast<float>(i) / 10000.f;
      EXPECT_NEAR(to_linear(lin, from_linear(lin, x)), x, 1e-6f) << to_string(lin) << " " << x;
      EXPECT_NEAR(from_linear(lin, to_linear(lin, x)), x, 1e-6f) << to_string(lin) << " " << x;
    }
  }
}

TEST(MeshLinearisation, KnownValues) {
  EXPECT_EQ(to_linear(Linearisation::identity, 0.3f), 0.3f);
  EXPECT_FLOAT_EQ(to_linear(Linearisation::square, 0.5f), 0.25f);
  EXPECT_FLOAT_EQ(from_linear(Linearisation::square, 0.25f), 0.5f);
  EXPECT_NEAR(to_linear(Linearisation::srgb, 0.5f), 0.2140411f, 1e-6f);
  EXPECT_NEAR(to_linear(Linearisation::srgb, 0.04f), 0.04f / 12.92f, 1e-8f);
  EXPECT_EQ(to_linear(Linearisation::srgb, 0.f), 0.f);
  EXPECT_FLOAT_EQ(to_linear(Linearisation::srgb, 1.f), 1.f);
  // Monotonic.
  float previous = -1;
  for (int i = 0; i <= 1000; ++i) {
    const float v = to_linear(Linearisation::srgb, static_cast<float>(i) / 1000.f);
    EXPECT_GT(v, previous);
    previous = v;
  }
}

TEST(MeshLinearisation, OddExtensionKeepsValuesOutsideTheRangeFinite) {
  for (Linearisation lin : {Linearisation::square, Linearisation::srgb}) {
    for (float x : {-0.5f, -0.01f, 1.5f}) {
      const float l = to_linear(lin, x);
      ASSERT_TRUE(std::isfinite(l));
      EXPECT_EQ(l, x < 0 ? -to_linear(lin, -x) : l);
      EXPECT_NEAR(from_linear(lin, l), x, 1e-6f);
    }
    EXPECT_EQ(from_linear(lin, -0.25f), -from_linear(lin, 0.25f));
  }
}

TEST(MeshLinearisation, Names) {
  for (Linearisation lin : {Linearisation::identity, Linearisation::square, Linearisation::srgb}) {
    EXPECT_EQ(linearisation_from_string(to_string(lin)), lin);
  }
  EXPECT_EQ(linearisation_from_string("linear"), Linearisation::identity);
  const std::string msg = invalid_input_message([] { linearisation_from_string("gamma"); });
  EXPECT_NE(msg.find("'gamma'"), std::string::npos) << msg;
}

// ------------------------------------------------------------------------------------------
// Channels

TEST(MeshChannels, MaterialChannels) {
  // The material channels are stored in [0, 1]: merged values are clamped there.
  const std::vector<ChannelDesc> expected = {{"albedo", 3, Linearisation::srgb, 0.f, 1.f},
                                             {"metallic", 1, Linearisation::identity, 0.f, 1.f},
                                             {"roughness", 1, Linearisation::square, 0.f, 1.f}};
  EXPECT_EQ(material_channels(), expected);
  for (const ChannelDesc& d : material_channels()) {
    EXPECT_EQ(default_linearisation(d.name), d.linearisation) << d.name;
  }
  EXPECT_EQ(default_linearisation("mask"), Linearisation::identity);
}

TEST(MeshChannels, AddAndFind) {
  Mesh m = single_triangle();
  EXPECT_EQ(m.find_channel("albedo"), -1);
  const float grey[3] = {0.5f, 0.25f, 0.125f};
  EXPECT_EQ(m.add_channel({"albedo", 3, Linearisation::srgb}, grey), 0);
  EXPECT_EQ(m.add_channel({"mask", 1}), 1);
  EXPECT_EQ(m.find_channel("albedo"), 0);
  EXPECT_EQ(m.find_channel("mask"), 1);
  EXPECT_EQ(m.channels[0].values,
            (std::vector<float>{0.5f, 0.25f, 0.125f, 0.5f, 0.25f, 0.125f, 0.5f, 0.25f, 0.125f}));
  EXPECT_EQ(m.channels[1].values, (std::vector<float>{0, 0, 0}));
  // Existing channel: index returned, values untouched.
  const float other[3] = {1, 1, 1};
  EXPECT_EQ(m.add_channel({"albedo", 3, Linearisation::srgb}, other), 0);
  EXPECT_EQ(m.channels[0].values[0], 0.5f);
  EXPECT_EQ(m.channels.size(), 2u);
  EXPECT_NO_THROW(validate(m, "m"));
}

TEST(MeshChannels, AddRejectsInconsistentRequests) {
  Mesh m = single_triangle();
  m.add_channel({"albedo", 3, Linearisation::srgb});
  EXPECT_THROW(m.add_channel({"albedo", 1}), InvalidInput);
  const float two[2] = {1, 2};
  EXPECT_THROW(m.add_channel({"uv", 3}, two), InvalidInput);
  EXPECT_THROW(m.add_channel({"bad", 0}), InvalidInput);
  EXPECT_THROW(m.add_channel({"bad", 5}), InvalidInput);
  EXPECT_THROW(m.add_channel({"", 1}), InvalidInput);
  EXPECT_EQ(m.channels.size(), 1u);
}

TEST(MeshBbox, Diagonal) {
  EXPECT_EQ(bbox_diagonal({}), 0.f);
  const std::vector<Vec3f> pts = {{-1, 0, 0}, {1, 2, 0}, {0, 0, 2}};
  EXPECT_FLOAT_EQ(bbox_diagonal(pts), std::sqrt(12.f));
}

// ------------------------------------------------------------------------------------------
// OpenMesh interop

TEST(OpenMeshInterop, RoundTripKeepsEverything) {
  const Mesh m = test::make_icosphere_with_channels();
  const OpenMeshTriMesh om = to_openmesh(m);
  EXPECT_EQ(om.n_vertices(), m.vertex_count());
  EXPECT_EQ(om.n_faces(), m.face_count());

  OpenMesh::VPropHandleT<OpenMesh::Vec3f> albedo;
  ASSERT_TRUE(om.get_property_handle(albedo, "albedo"));
  EXPECT_TRUE(om.property(albedo).persistent());
  EXPECT_EQ(om.property(albedo, OpenMesh::VertexHandle(5))[1], m.channels[0].values[5 * 3 + 1]);
  OpenMesh::VPropHandleT<float> roughness;
  ASSERT_TRUE(om.get_property_handle(roughness, "roughness"));
  OpenMesh::VPropHandleT<OpenMesh::Vec2f> uv;
  EXPECT_TRUE(om.get_property_handle(uv, "uv"));
  OpenMesh::VPropHandleT<OpenMesh::Vec4f> tint;
  EXPECT_TRUE(om.get_property_handle(tint, "tint"));

  // Discovery gives the default linearisation by name, which these channels use.
  EXPECT_EQ(first_difference(from_openmesh(om), m), "");
  EXPECT_EQ(first_difference(from_openmesh(om, std::vector<ChannelDesc>{}),
                             Mesh{m.positions, m.triangles, {}}),
            "");
}

TEST(OpenMeshInterop, ExplicitChannelsKeepTheirLinearisation) {
  Mesh m = make_grid(3);
  m.add_channel({"albedo", 3, Linearisation::identity});
  const OpenMeshTriMesh om = to_openmesh(m);
  const std::vector<ChannelDesc> descs = {{"albedo", 3, Linearisation::identity}};
  EXPECT_EQ(first_difference(from_openmesh(om, descs), m), "");
  const std::vector<ChannelDesc> wrong_width = {{"albedo", 1, Linearisation::identity}};
  const std::string msg = invalid_input_message([&] { from_openmesh(om, wrong_width); });
  EXPECT_NE(msg.find("no vertex property 'albedo' of type float"), std::string::npos) << msg;
}

TEST(OpenMeshInterop, IgnoresOpenMeshsOwnAndNonPersistentProperties) {
  OpenMeshTriMesh om = to_openmesh(make_grid(2));
  om.request_vertex_normals();
  OpenMesh::VPropHandleT<float> scratch;
  om.add_property(scratch, "scratch");
  EXPECT_TRUE(from_openmesh(om).channels.empty());
}

TEST(OpenMeshInterop, RejectsNonManifoldTrianglesByName) {
  // Three triangles on the edge 0-1: the third cannot be represented by a halfedge mesh.
  Mesh fin;
  fin.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  fin.triangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  const std::string msg = invalid_input_message([&] { to_openmesh(fin); });
  EXPECT_EQ(msg.rfind("to_openmesh: triangle 2 (0, 1, 4)", 0), 0u) << msg;

  // Inconsistent orientation between neighbours is rejected the same way.
  Mesh flipped = make_grid(1);
  std::swap(flipped.triangles[1][1], flipped.triangles[1][2]);
  const std::string msg2 = invalid_input_message([&] { to_openmesh(flipped); });
  EXPECT_EQ(msg2.rfind("to_openmesh: triangle 1 ", 0), 0u) << msg2;
}

TEST(OpenMeshInterop, RejectsInvalidMeshesAndDeletedElements) {
  EXPECT_THROW(to_openmesh(Mesh{}), InvalidInput);
  OpenMeshTriMesh om = to_openmesh(make_grid(2));
  om.request_vertex_status();
  om.request_edge_status();
  om.request_face_status();
  om.delete_face(OpenMesh::FaceHandle(0), false);
  EXPECT_THROW(from_openmesh(om), InvalidInput);
}

}  // namespace
}  // namespace csculpt
