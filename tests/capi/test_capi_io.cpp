// Mesh files through the C ABI: csc_mesh_read of bad arguments, missing files and the
// malformed assimp-testmodels (invalid input naming the file), real models, csc_mesh_write's
// errors (no temporary file left behind), and PLY round trips bit for bit, ranges included.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "capi_test.h"
#include "csculpt.h"
#include "host_arrays.h"

namespace {

using namespace capi_test;

namespace fs = std::filesystem;
const fs::path kModels = CSCULPT_TEST_MODELS;

TEST(CapiMeshRead, BadArgumentsAndMissingFiles) {
  csc_mesh* out = sentinel<csc_mesh>();
  EXPECT_FAILS(csc_mesh_read(nullptr, "x.ply"), CSC_ERROR_INVALID_ARGUMENT, "out");
  EXPECT_FAILS(csc_mesh_read(&out, nullptr), CSC_ERROR_INVALID_ARGUMENT, "path");
  EXPECT_FAILS(csc_mesh_read(&out, "/nonexistent/missing.ply"), CSC_ERROR_IO, "missing.ply");
  EXPECT_FAILS(csc_mesh_read(&out, ""), CSC_ERROR_IO, "cannot");
  const std::string dir = fs::temp_directory_path().string();
  EXPECT_FAILS(csc_mesh_read(&out, dir.c_str()), CSC_ERROR_IO, "directory");
  EXPECT_EQ(out, sentinel<csc_mesh>());
}

TEST(CapiMeshRead, MalformedModelsAreInvalidInputNamingTheFile) {
  if (!fs::exists(kModels)) GTEST_SKIP() << "assimp-testmodels not installed";
  csc_mesh* out = sentinel<csc_mesh>();
  std::size_t count = 0;
  for (const auto& e : fs::directory_iterator(kModels / "invalid")) {
    const std::string p = e.path().string();
    EXPECT_FAILS(csc_mesh_read(&out, p.c_str()), CSC_ERROR_INVALID_INPUT, p.c_str());
    ++count;
  }
  EXPECT_GE(count, 10u);
  const std::vector<std::pair<std::string, const char*>> specific = {
      {"invalid/OutOfMemory.off", "353535235358 vertices"},
      {"invalid/empty.ply", "file is empty"},
      {"invalid/malformed.obj", "out of range"},
      {"PLY/points.ply", "no faces"},
      {"OBJ/point_cloud.obj", "no faces"},
      {"OBJ/box_UTF16BE.obj", "UTF-16"},
      {"PLY/pond.0.ply", "header claims 70051 vertex elements"},
      {"OBJ/spider.mtl", "unrecognised file format"}};
  for (const auto& [name, keyword] : specific) {
    const std::string p = (kModels / name).string();
    EXPECT_FAILS(csc_mesh_read(&out, p.c_str()), CSC_ERROR_INVALID_INPUT, keyword);
  }
  EXPECT_EQ(out, sentinel<csc_mesh>());
}

TEST(CapiMeshRead, RealModelsRead) {
  if (!fs::exists(kModels)) GTEST_SKIP() << "assimp-testmodels not installed";
  for (const char* name : {"PLY/cube.ply", "PLY/cube_binary.ply", "OFF/Cube.off", "OBJ/box.obj",
                           "STL/Spider_binary.stl"}) {
    csc_mesh* out = nullptr;
    ASSERT_OK(csc_mesh_read(&out, (kModels / name).string().c_str()));
    MeshPtr m(out);
    EXPECT_GT(csc_mesh_vertex_count(out), 0u) << name;
    EXPECT_GT(csc_mesh_triangle_count(out), 0u) << name;
  }
}

/// CapiGridEdit and a fresh temporary directory (`dir`), removed afterwards.
class CapiGridEditTempDir : public CapiGridEdit {
 protected:
  void SetUp() override {
    CapiGridEdit::SetUp();
    dir = fs::temp_directory_path() /
          ("csculpt-capi-" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
           "-" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  void TearDown() override { fs::remove_all(dir); }
  fs::path dir;
};

TEST_F(CapiGridEditTempDir, WriteBadArgumentsAndUnwritablePaths) {
  const std::string ok_path = (dir / "m.ply").string();
  EXPECT_FAILS(csc_mesh_write(nullptr, ok_path.c_str()), CSC_ERROR_INVALID_ARGUMENT, "mesh");
  EXPECT_FAILS(csc_mesh_write(foreign<csc_mesh>(bytes.get()), ok_path.c_str()),
               CSC_ERROR_INVALID_ARGUMENT, "kind");
  EXPECT_FAILS(csc_mesh_write(mesh.get(), nullptr), CSC_ERROR_INVALID_ARGUMENT, "path");
  EXPECT_FAILS(csc_mesh_write(mesh.get(), "/nonexistent/dir/never.ply"), CSC_ERROR_IO, "never.ply");
  EXPECT_FAILS(csc_mesh_write(mesh.get(), "/proc/csculpt-never.ply"), CSC_ERROR_IO,
               "csculpt-never.ply");
  const std::string unsupported = (dir / "m.xyz").string();
  EXPECT_FAILS(csc_mesh_write(mesh.get(), unsupported.c_str()), CSC_ERROR_INVALID_INPUT, ".xyz");
  // The target is a directory: the rename fails, and no temporary file is left behind.
  fs::create_directory(dir / "taken.ply");
  const std::string taken = (dir / "taken.ply").string();
  EXPECT_FAILS(csc_mesh_write(mesh.get(), taken.c_str()), CSC_ERROR_IO, "taken.ply");
  std::vector<std::string> left;
  for (const auto& e : fs::directory_iterator(dir)) left.push_back(e.path().filename().string());
  EXPECT_EQ(left, std::vector<std::string>{"taken.ply"});
  EXPECT_FALSE(fs::exists(ok_path));
}

/// Writes `m` to `path` and reads it back.
MeshPtr write_and_read(const csc_mesh* m, const std::string& path) {
  EXPECT_EQ(csc_mesh_write(m, path.c_str()), CSC_OK) << csc_last_error();
  csc_mesh* r = nullptr;
  EXPECT_EQ(csc_mesh_read(&r, path.c_str()), CSC_OK) << csc_last_error();
  return MeshPtr(r);
}

/// Positions, triangles, channel names, widths, linearisations and values bit for bit; the
/// ranges too when `ranges` is set.
void expect_same_mesh(const csc_mesh* a, const csc_mesh* b, bool ranges) {
  ASSERT_EQ(csc_mesh_vertex_count(b), csc_mesh_vertex_count(a));
  ASSERT_EQ(csc_mesh_triangle_count(b), csc_mesh_triangle_count(a));
  ASSERT_EQ(csc_mesh_channel_count(b), csc_mesh_channel_count(a));
  const std::size_t n = csc_mesh_vertex_count(a);
  EXPECT_EQ(std::memcmp(csc_mesh_positions(a), csc_mesh_positions(b), 12 * n), 0);
  EXPECT_EQ(std::memcmp(csc_mesh_triangles(a), csc_mesh_triangles(b),
                        std::size_t{12} * csc_mesh_triangle_count(a)),
            0);
  for (std::uint32_t k = 0; k < csc_mesh_channel_count(a); ++k) {
    csc_channel_view x = CSC_CHANNEL_VIEW_INIT, y = CSC_CHANNEL_VIEW_INIT;
    ASSERT_OK(csc_mesh_channel(a, k, &x));
    ASSERT_OK(csc_mesh_channel(b, k, &y));
    SCOPED_TRACE(x.desc.name);
    EXPECT_STREQ(x.desc.name, y.desc.name);
    EXPECT_EQ(x.desc.width, y.desc.width);
    EXPECT_EQ(x.desc.linearisation, y.desc.linearisation);
    if (ranges) {
      EXPECT_EQ(x.desc.min_value, y.desc.min_value);
      EXPECT_EQ(x.desc.max_value, y.desc.max_value);
    }
    EXPECT_EQ(std::memcmp(x.values, y.values, 4 * n * x.desc.width), 0);
  }
}

TEST_F(CapiGridEditTempDir, PlyWithChannelsRoundTripsBitForBit) {
  // Channels whose description a PLY property can carry: the material channels, and custom
  // channels of every linearisation with the default (unbounded) range.
  Grid g(kN);
  g.channels = {{"mask", 1, CSC_LINEARISATION_IDENTITY, -kInf, kInf},
                {"tint", 3, CSC_LINEARISATION_SRGB, -kInf, kInf},
                {"gloss", 2, CSC_LINEARISATION_SQUARE, -kInf, kInf}};
  std::vector<float> gloss(2 * kN * kN);
  for (std::size_t i = 0; i < gloss.size(); ++i) gloss[i] = std::sqrt(static_cast<float>(i) / 7.f);
  g.values.push_back(gloss.data());
  MeshPtr original = g.make();
  ASSERT_TRUE(original);
  ASSERT_OK(csc_mesh_add_material_channels(original.get()));
  HostArrays edit(original.get());
  brush(edit, kN, 0.6f, 0.3f, 0.4f, {0.013f, -0.007f, 0.1f}, 4, 0.3f);  // values that are not round
  DiffPtr d = capture(original.get(), edit);
  ASSERT_OK(csc_mesh_apply_diff(original.get(), d.get()));

  MeshPtr back = write_and_read(original.get(), (dir / "round.ply").string());
  ASSERT_TRUE(back);
  expect_same_mesh(original.get(), back.get(), true);
  // The mesh read back is the same base: capturing against it finds nothing changed.
  csc_diff* none = nullptr;
  ASSERT_OK(csc_diff_capture(&none, original.get(), back.get()));
  DiffPtr kept(none);
  csc_diff_info info = CSC_DIFF_INFO_INIT;
  ASSERT_OK(csc_diff_get_info(none, &info));
  EXPECT_EQ(info.touched_vertices, 0u);

  // OBJ keeps positions (as text) and faces.
  MeshPtr obj = write_and_read(original.get(), (dir / "round.obj").string());
  ASSERT_TRUE(obj);
  EXPECT_EQ(csc_mesh_vertex_count(obj.get()), kN * kN);
  EXPECT_EQ(std::memcmp(csc_mesh_triangles(obj.get()), csc_mesh_triangles(original.get()),
                        std::size_t{12} * csc_mesh_triangle_count(obj.get())),
            0);
}

// csculpt.h, csc_mesh_write: ".ply (binary, channels as vertex properties; reads back
// bit-identical)". A custom channel's range is part of the mesh (merged values are clamped
// into it), so a peer that loads the base from the file must get it back.
TEST_F(CapiGridEditTempDir, PlyKeepsTheRangeOfCustomChannels) {
  MeshPtr back = write_and_read(mesh.get(), (dir / "ranges.ply").string());
  ASSERT_TRUE(back);
  expect_same_mesh(mesh.get(), back.get(), true);
  csc_diff* none = nullptr;
  EXPECT_EQ(csc_diff_capture(&none, mesh.get(), back.get()), CSC_OK) << csc_last_error();
  csc_diff_destroy(none);
}

}  // namespace
