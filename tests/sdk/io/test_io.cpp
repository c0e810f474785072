// Mesh file reading and writing: the real and malformed files of assimp-testmodels, every PLY
// encoding and scalar type, OBJ/OFF/STL variants, error messages, and atomic writes.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "csculpt/error.h"
#include "csculpt/io.h"
#include "csculpt/mesh.h"
#include "test_meshes.h"
#include "test_support.h"

namespace csculpt {
using csculpt::test::invalid_input_message;

namespace {

namespace fs = std::filesystem;
using test::first_difference;

const fs::path kModels = CSCULPT_TEST_MODELS;

bool starts_with(const std::string& s, const std::string& prefix) {
  return s.rfind(prefix, 0) == 0;
}
bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

// Each test in a fresh directory of its own (test::TestDir), removed afterwards.
class IoFiles : public ::testing::Test {
 protected:
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::vector<std::string> listing() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir_))
      names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  }
  void write_text(const std::string& name, const std::string& bytes) const {
    std::ofstream(dir_ / name, std::ios::binary) << bytes;
  }

  test::TestDir scratch_{"csculpt_io"};
  const fs::path dir_ = scratch_.path();
};

// ------------------------------------------------------------------------------------------
// assimp-testmodels

std::map<std::string, Mesh> load_folder(const std::string& folder,
                                        std::vector<std::string>* rejected) {
  std::map<std::string, Mesh> loaded;
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(kModels / folder)) {
    if (e.is_regular_file()) files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  for (const fs::path& f : files) {
    const std::string name = folder + "/" + f.filename().string();
    try {
      loaded.emplace(name, read_mesh(f.string()));
    } catch (const InvalidInput& e) {
      EXPECT_TRUE(starts_with(e.what(), f.string())) << name << ": " << e.what();
      rejected->push_back(name + ": " + e.what());
    } catch (const std::exception& e) {
      ADD_FAILURE() << name << ": unexpected exception: " << e.what();
    }
  }
  return loaded;
}

TEST(IoModels, EveryTestModelLoadsOrIsRejectedWithItsName) {
  if (!fs::exists(kModels)) GTEST_SKIP() << "assimp-testmodels not installed";
  std::map<std::string, Mesh> all;
  std::vector<std::string> rejected;
  for (const char* folder : {"PLY", "OBJ", "OFF", "STL"}) all.merge(load_folder(folder, &rejected));
  for (const auto& [name, mesh] : all) {
    std::cout << "  loaded   " << name << ": " << mesh.vertex_count() << " vertices, "
              << mesh.face_count() << " triangles, " << mesh.channels.size() << " channels\n";
  }
  for (const std::string& r : rejected) std::cout << "  rejected " << r << "\n";

  auto expect_counts = [&](const std::string& name, std::size_t v, std::size_t t) {
    ASSERT_EQ(all.count(name), 1u) << name << " did not load";
    EXPECT_EQ(all[name].vertex_count(), v) << name;
    EXPECT_EQ(all[name].face_count(), t) << name;
  };
  expect_counts("PLY/cube.ply", 8, 12);
  expect_counts("PLY/cube_binary.ply", 8, 12);
  expect_counts("PLY/Wuson.ply", 11184, 3732);
  expect_counts("PLY/cube_uv.ply", 24, 12);
  expect_counts("OBJ/box.obj", 8, 12);
  expect_counts("OBJ/cube_usemtl.obj", 8, 12);
  expect_counts("OBJ/cube_with_vertexcolors.obj", 8, 12);
  expect_counts("OBJ/regr_3429812.obj", 4, 4);
  expect_counts("OBJ/testmixed.obj", 8, 12);
  expect_counts("OFF/Cube.off", 8, 12);
  expect_counts("STL/triangle.stl", 3, 1);
  expect_counts("STL/triangle_with_empty_solid.stl", 3, 1);

  // Same surfaces in different files.
  EXPECT_EQ(first_difference(all["OBJ/box.obj"], all["OBJ/box_without_lineending.obj"]), "");
  EXPECT_EQ(first_difference(all["OFF/Cube.off"], all["OFF/formatDetection"]), "");
  EXPECT_EQ(first_difference(all["STL/triangle.stl"], all["STL/formatDetection"]), "");
  ASSERT_EQ(all.count("STL/Spider_ascii.stl"), 1u);
  ASSERT_EQ(all.count("STL/Spider_binary.stl"), 1u);
  // The ascii file prints 6 decimals, so positions agree to that precision; the surface is
  // the same.
  const Mesh& spider_ascii = all["STL/Spider_ascii.stl"];
  const Mesh& spider_binary = all["STL/Spider_binary.stl"];
  ASSERT_EQ(spider_ascii.vertex_count(), spider_binary.vertex_count());
  EXPECT_EQ(spider_ascii.triangles, spider_binary.triangles);
  for (std::size_t v = 0; v < spider_ascii.vertex_count(); ++v) {
    EXPECT_NEAR(spider_ascii.positions[v].x, spider_binary.positions[v].x, 1e-6f);
    EXPECT_NEAR(spider_ascii.positions[v].y, spider_binary.positions[v].y, 1e-6f);
    EXPECT_NEAR(spider_ascii.positions[v].z, spider_binary.positions[v].z, 1e-6f);
  }
  EXPECT_GT(all["STL/Spider_binary.stl"].vertex_count(), 0u);
  // Welding: far fewer vertices than 3 per facet.
  EXPECT_LT(all["STL/Spider_binary.stl"].vertex_count(),
            all["STL/Spider_binary.stl"].face_count() * 3 / 2);

  // float-color.ply: float red/green/blue become albedo (alpha dropped).
  const Mesh& coloured = all["PLY/float-color.ply"];
  ASSERT_EQ(coloured.channels.size(), 1u);
  EXPECT_EQ(coloured.channels[0].desc, (ChannelDesc{"albedo", 3, Linearisation::srgb, 0.f, 1.f}));

  // Files that must be rejected, for the stated reason.
  auto expect_rejected = [&](const std::string& name, const std::string& reason) {
    const auto it = std::find_if(rejected.begin(), rejected.end(),
                                 [&](const std::string& r) { return starts_with(r, name + ": "); });
    ASSERT_NE(it, rejected.end()) << name << " was not rejected";
    EXPECT_TRUE(contains(*it, reason)) << *it;
  };
  expect_rejected("PLY/points.ply", "no faces");
  expect_rejected("PLY/pond.0.ply", "header claims 70051 vertex elements, but only 2171512 bytes");
  expect_rejected("OBJ/box_UTF16BE.obj", "UTF-16");
  expect_rejected("OBJ/point_cloud.obj", "no faces");
  expect_rejected("OBJ/testpoints.obj", "no faces");
  expect_rejected("OFF/invalid.off", "");
  expect_rejected("OBJ/spider.mtl", "unrecognised file format");
}

TEST(IoModels, EveryInvalidModelIsRejectedWithAMessage) {
  if (!fs::exists(kModels)) GTEST_SKIP() << "assimp-testmodels not installed";
  std::size_t count = 0;
  for (const auto& e : fs::directory_iterator(kModels / "invalid")) {
    const std::string p = e.path().string();
    const std::string msg = invalid_input_message([&] { read_mesh(p); });
    EXPECT_TRUE(starts_with(msg, p + ":")) << msg;
    EXPECT_GT(msg.size(), p.size() + 5) << msg;
    ++count;
  }
  EXPECT_GE(count, 10u);
  const std::string oom = (kModels / "invalid/OutOfMemory.off").string();
  EXPECT_TRUE(contains(invalid_input_message([&] { read_mesh(oom); }),
                       "header claims 353535235358 vertices"));
  const std::string empty = (kModels / "invalid/empty.ply").string();
  EXPECT_EQ(invalid_input_message([&] { read_mesh(empty); }), empty + ": file is empty");
  const std::string malformed = (kModels / "invalid/malformed.obj").string();
  EXPECT_EQ(invalid_input_message([&] { read_mesh(malformed); }),
            malformed + ":23: face index 12 out of range (8 vertices)");
}

// ------------------------------------------------------------------------------------------
// PLY: every encoding and scalar type

// A PLY file described once and encoded in any of the three encodings.
struct PlySpec {
  struct Prop {
    std::string type;
    std::string name;
    std::vector<double> values;  // one per element
  };
  struct List {
    std::string count_type;
    std::string type;
    std::string name;
    std::vector<std::vector<double>> values;  // one list per element
  };
  struct Element {
    std::string name;
    std::size_t count = 0;
    std::vector<Prop> props;  // scalars first, then lists (enough for these tests)
    std::vector<List> lists;
  };
  std::vector<Element> elements;
  std::vector<std::string> comments;
};

std::size_t type_size(const std::string& t) {
  if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
  if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
  if (t == "double" || t == "float64") return 8;
  return 4;
}

void put(std::string& out, const std::string& type, double v, bool big_endian) {
  unsigned char b[8];
  std::size_t n = type_size(type);
  if (type == "float" || type == "float32") {
    const float f = static_cast<float>(v);
    std::memcpy(b, &f, 4);
  } else if (type == "double" || type == "float64") {
    std::memcpy(b, &v, 8);
  } else {
    const auto i = static_cast<std::int64_t>(v);
    for (std::size_t k = 0; k < n; ++k) b[k] = static_cast<unsigned char>((i >> (8 * k)) & 0xff);
  }
  if (big_endian) std::reverse(b, b + n);
  out.append(reinterpret_cast<const char*>(b), n);
}

std::string text(const std::string& type, double v) {
  char buf[64];
  if (type == "float" || type == "float32") {
    std::snprintf(buf, sizeof(buf), "%.9g", static_cast<double>(static_cast<float>(v)));
  } else if (type == "double" || type == "float64") {
    std::snprintf(buf, sizeof(buf), "%.17g", v);
  } else {
    std::snprintf(buf, sizeof(buf), "%lld", static_cast<long long>(v));
  }
  return buf;
}

std::string encode(const PlySpec& spec, const std::string& format) {
  std::string out = "ply\nformat " + format + " 1.0\n";
  for (const std::string& c : spec.comments) out += "comment " + c + "\n";
  out += "obj_info generated by test_io\n";
  for (const auto& e : spec.elements) {
    out += "element " + e.name + " " + std::to_string(e.count) + "\n";
    for (const auto& p : e.props) out += "property " + p.type + " " + p.name + "\n";
    for (const auto& l : e.lists) {
      out += "property list " + l.count_type + " " + l.type + " " + l.name + "\n";
    }
  }
  out += "end_header\n";
  const bool ascii = format == "ascii";
  const bool big = format == "binary_big_endian";
  for (const auto& e : spec.elements) {
    for (std::size_t i = 0; i < e.count; ++i) {
      for (const auto& p : e.props) {
        if (ascii) {
          out += text(p.type, p.values[i]) + " ";
        } else {
          put(out, p.type, p.values[i], big);
        }
      }
      for (const auto& l : e.lists) {
        const auto& values = l.values[i];
        if (ascii) {
          out += std::to_string(values.size());
          for (double v : values) out.append(" ").append(text(l.type, v));
          out += " ";
        } else {
          put(out, l.count_type, static_cast<double>(values.size()), big);
          for (double v : values) put(out, l.type, v, big);
        }
      }
      if (ascii) out += "\n";
    }
  }
  return out;
}

// A quad pyramid: 5 vertices, a square base (fan-triangulated) and four sides, described with
// every PLY scalar type among its properties and surrounded by elements to skip.
PlySpec pyramid_spec() {
  PlySpec s;
  s.elements.push_back({"material",
                        2,
                        {{"uchar", "ambient_red", {10, 20}}, {"float", "shine", {0.5, 0.25}}},
                        {{"uchar", "float", "coeffs", {{1, 2, 3}, {}}}}});
  PlySpec::Element v{"vertex", 5, {}, {}};
  v.props = {
      {"double", "x", {0, 1, 1, 0, 0.5}},
      {"float32", "y", {0, 0, 1, 1, 0.5}},
      {"float", "z", {0, 0, 0, 0, 0.7071067811865476}},
      {"uchar", "red", {255, 0, 0, 128, 51}},
      {"uint8", "green", {0, 255, 0, 128, 102}},
      {"uchar", "blue", {0, 0, 255, 128, 153}},
      {"uchar", "alpha", {255, 255, 255, 255, 255}},
      {"char", "c8", {-128, 127, 0, -1, 5}},
      {"int8", "i8", {-5, 4, 3, 2, 1}},
      {"short", "s16", {-32768, 32767, 0, 1, -2}},
      {"int16", "i16", {1, 2, 3, 4, 5}},
      {"ushort", "u16", {65535, 0, 1, 2, 3}},
      {"uint16", "uu16", {5, 4, 3, 2, 1}},
      {"int", "i32", {-2147483648.0, 2147483647, 0, 7, -7}},
      {"int32", "ii32", {1, 2, 3, 4, 5}},
      {"uint", "u32", {4294967295.0, 0, 1, 2, 3}},
      {"uint32", "uu32", {16777217, 0, 1, 2, 3}},
      {"float", "rough_g", {0.1, 0.2, 0.3, 0.4, 0.5}},
      {"float64", "roughness", {0.25, 0.5, 0.75, 1, 0}},
      {"float", "rough_r", {0.6, 0.7, 0.8, 0.9, 1.0}},
  };
  v.lists = {{"uchar", "float", "normal_list", {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {}}}};
  s.elements.push_back(v);
  PlySpec::Element f{"face", 5, {{"uchar", "flags", {1, 2, 3, 4, 5}}}, {}};
  f.lists = {{"uint16",
              "uint32",
              "vertex_indices",
              {{0, 3, 2, 1}, {0, 1, 4}, {1, 2, 4}, {2, 3, 4}, {3, 0, 4}}},
             {"int", "float", "texcoord", {{0, 1}, {}, {2, 3}, {}, {1}}}};
  s.elements.push_back(f);
  s.elements.push_back({"edge", 1, {{"int", "vertex1", {0}}, {"int", "vertex2", {1}}}, {}});
  return s;
}

TEST(IoPly, AllEncodingsAndScalarTypesGiveTheSameMesh) {
  const PlySpec spec = pyramid_spec();
  const Mesh ascii = parse_ply(encode(spec, "ascii"), "a.ply");
  const Mesh little = parse_ply(encode(spec, "binary_little_endian"), "le.ply");
  const Mesh big = parse_ply(encode(spec, "binary_big_endian"), "be.ply");
  EXPECT_EQ(first_difference(ascii, little), "");
  EXPECT_EQ(first_difference(ascii, big), "");

  ASSERT_EQ(big.vertex_count(), 5u);
  ASSERT_EQ(big.face_count(), 6u);
  EXPECT_EQ(big.triangles[0], (Triangle{0, 3, 2}));
  EXPECT_EQ(big.triangles[1], (Triangle{0, 2, 1}));
  EXPECT_EQ(big.positions[4], (Vec3f{0.5f, 0.5f, static_cast<float>(0.7071067811865476)}));

  // Channels in order of first property; red/green/blue -> albedo scaled from uchar.
  std::vector<std::string> names;
  for (const Channel& c : big.channels) names.push_back(c.desc.name);
  EXPECT_EQ(names, (std::vector<std::string>{"albedo", "c8", "i8", "s16", "i16", "u16", "uu16",
                                             "i32", "ii32", "u32", "uu32", "rough", "roughness"}));
  const Channel& albedo = big.channels[0];
  EXPECT_EQ(albedo.desc, (ChannelDesc{"albedo", 3, Linearisation::srgb, 0.f, 1.f}));
  EXPECT_EQ(albedo.values[0], 1.f);
  EXPECT_EQ(albedo.values[4 * 3 + 1], static_cast<float>(102.0 / 255.0));
  EXPECT_EQ(big.channels[1].values[0], -128.f);
  EXPECT_EQ(big.channels[9].values[0], 4294967295.f);
  EXPECT_EQ(big.channels[10].values[0], 16777216.f);  // nearest float
  const Channel& rough = big.channels[11];
  EXPECT_EQ(rough.desc, (ChannelDesc{"rough", 2, Linearisation::identity}));
  EXPECT_EQ(rough.values[0], 0.6f);  // rough_r is component 0 although it comes later
  EXPECT_EQ(rough.values[1], 0.1f);
  EXPECT_EQ(big.channels[12].desc, (ChannelDesc{"roughness", 1, Linearisation::square, 0.f, 1.f}));
}

TEST(IoPly, ColourBecomesAlbedoOnlyWhenNoAlbedoChannelExists) {
  PlySpec spec;
  PlySpec::Element v{"vertex", 3, {}, {}};
  v.props = {{"float", "x", {0, 1, 0}},        {"float", "y", {0, 0, 1}},
             {"float", "z", {0, 0, 0}},        {"float", "albedo_r", {0.5, 0.5, 0.5}},
             {"float", "albedo_g", {0, 0, 0}}, {"float", "albedo_b", {1, 1, 1}},
             {"ushort", "red", {65535, 0, 0}}, {"ushort", "green", {0, 0, 0}},
             {"ushort", "blue", {0, 0, 0}},    {"float", "lone_r", {1, 2, 3}},
             {"float", "gap_r", {1, 2, 3}},    {"float", "gap_b", {1, 2, 3}}};
  spec.elements.push_back(v);
  spec.elements.push_back({"face", 1, {}, {{"uchar", "int", "vertex_index", {{0, 1, 2}}}}});
  const Mesh m = parse_ply(encode(spec, "ascii"), "c.ply");
  std::vector<std::string> names;
  for (const Channel& c : m.channels)
    names.push_back(c.desc.name + "/" + std::to_string(c.desc.width));
  EXPECT_EQ(names, (std::vector<std::string>{"albedo/3", "red/1", "green/1", "blue/1", "lone_r/1",
                                             "gap_r/1", "gap_b/1"}));
  EXPECT_EQ(m.channels[1].values[0], 65535.f);  // not scaled: it is not a colour here
}

TEST(IoPly, RejectsClashingChannelNames) {
  PlySpec spec;
  PlySpec::Element v{"vertex", 3, {}, {}};
  v.props = {{"float", "x", {0, 1, 0}},     {"float", "y", {0, 0, 1}},
             {"float", "z", {0, 0, 0}},     {"float", "foo", {0, 0, 0}},
             {"float", "foo_r", {0, 0, 0}}, {"float", "foo_g", {0, 0, 0}}};
  spec.elements.push_back(v);
  spec.elements.push_back({"face", 1, {}, {{"uchar", "int", "vertex_index", {{0, 1, 2}}}}});
  EXPECT_EQ(invalid_input_message([&] { parse_ply(encode(spec, "ascii"), "c.ply"); }),
            "c.ply: channel foo is defined twice (by property foo and by property foo_r)");
}

std::string ascii_triangle(const std::string& vertex_lines, const std::string& face_lines,
                           std::size_t faces = 1) {
  return "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
         "property float z\nelement face " +
         std::to_string(faces) + "\nproperty list uchar int vertex_indices\nend_header\n" +
         vertex_lines + face_lines;
}

TEST(IoPly, ErrorMessagesSayWhereAndWhat) {
  const std::string good_vertices = "0 0 0\n1 0 0\n0 1 0\n";
  EXPECT_NO_THROW(parse_ply(ascii_triangle(good_vertices, "3 0 1 2\n"), "t.ply"));
  EXPECT_EQ(invalid_input_message([&] {
              parse_ply(ascii_triangle("0 0 0\n1 nan 0\n0 1 0\n", "3 0 1 2\n"), "n.ply");
            }),
            "n.ply:11: vertex 1: property y is NaN");
  EXPECT_EQ(invalid_input_message(
                [&] { parse_ply(ascii_triangle(good_vertices, "3 0 1 9\n"), "i.ply"); }),
            "i.ply:13: face 0: vertex index 9 out of range (3 vertices)");
  EXPECT_EQ(invalid_input_message(
                [&] { parse_ply(ascii_triangle(good_vertices, "3 0 1 1\n"), "d.ply"); }),
            "d.ply:13: face 0 repeats vertex 1 (degenerate triangle)");
  EXPECT_EQ(
      invalid_input_message([&] { parse_ply(ascii_triangle(good_vertices, "2 0 1\n"), "s.ply"); }),
      "s.ply:13: face 0 has 2 vertices (need at least 3)");
  EXPECT_EQ(invalid_input_message(
                [&] { parse_ply(ascii_triangle(good_vertices, "3 0 1 x\n"), "b.ply"); }),
            "b.ply:13: face 0: property vertex_indices: expected int, got 'x'");
  EXPECT_EQ(invalid_input_message(
                [&] { parse_ply(ascii_triangle(good_vertices, "3 0 1 2\n3 0 1", 2), "u.ply"); }),
            "u.ply: unexpected end of file in element face (face 1 of 2), property vertex_indices");
  EXPECT_EQ(invalid_input_message(
                [&] { parse_ply(ascii_triangle(good_vertices, "3 0 1 2 7\n"), "x.ply"); }),
            "x.ply:13: unexpected data after the last element: '7'");
  EXPECT_EQ(invalid_input_message([&] {
              parse_ply("ply\nformat ascii 1.0\nelement vertex 0\nend_header\n", "empty.ply");
            }),
            "empty.ply: no vertices");
  EXPECT_EQ(invalid_input_message([&] { parse_ply("plx\n", "m.ply"); }),
            "m.ply: not a PLY file (does not start with 'ply')");
  EXPECT_EQ(invalid_input_message([&] {
              parse_ply("ply\nformat ascii 1.0\nelement vertex 1\nproperty float32 x\n", "h.ply");
            }),
            "h.ply: header has no end_header line");
  EXPECT_EQ(invalid_input_message([&] {
              parse_ply(
                  "ply\nformat ascii 1.0\nelement vertex 1\nproperty float128 x\nend_header\n",
                  "h.ply");
            }),
            "h.ply: header line 4: unknown type 'float128'");
  EXPECT_EQ(invalid_input_message([&] {
              parse_ply(
                  "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n1\n",
                  "h.ply");
            }),
            "h.ply: vertex element has no property y");
  const std::string big_uchar =
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
      "property float z\nproperty uchar red\nelement face 0\nend_header\n0 0 0 256\n";
  // (vertex count 3 with one line would be caught by the count check first)
  EXPECT_EQ(invalid_input_message([&] { parse_ply(big_uchar, "r.ply"); }),
            "r.ply:10: vertex 0: property red: value 256 out of range for uchar");
}

TEST(IoPly, HugeHeaderCountsAreRejectedBeforeAllocating) {
  std::string bytes =
      "ply\nformat binary_little_endian 1.0\nelement vertex 2147483648\nproperty float x\n"
      "end_header\n";
  bytes.resize(100, '\0');
  const auto start = std::chrono::steady_clock::now();
  EXPECT_EQ(
      invalid_input_message([&] { parse_ply(bytes, "huge.ply"); }),
      "huge.ply: header claims 2147483648 vertex elements, but only 10 bytes of data are left "
      "for them (truncated file?)");
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::milliseconds(100));

  // Counts that fit the bytes but not 32-bit indices, and elements without properties.
  EXPECT_TRUE(contains(invalid_input_message([] {
                         parse_ply(
                             "ply\nformat ascii 1.0\nelement edge 18446744073709551615\n"
                             "end_header\n",
                             "e.ply");
                       }),
                       "element edge has 18446744073709551615 entries but no properties"));
  // A list length beyond the end of the data.
  std::string list =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uint int vertex_indices\nend_header\n";
  list.append(36, '\0');
  list += std::string("\xff\xff\xff\x7f", 4);
  EXPECT_EQ(invalid_input_message([&] { parse_ply(list, "l.ply"); }),
            "l.ply: truncated binary data in element face (face 0 of 1)");
}

TEST(IoPly, BinaryNonFiniteValuesAreRejected) {
  PlySpec spec;
  PlySpec::Element v{"vertex", 3, {}, {}};
  v.props = {{"float", "x", {0, 1, 0}},
             {"float", "y", {0, std::numeric_limits<double>::quiet_NaN(), 1}},
             {"float", "z", {0, 0, 0}},
             {"double", "mask", {0, 0, 1e300}}};
  spec.elements.push_back(v);
  spec.elements.push_back({"face", 1, {}, {{"uchar", "int", "vertex_index", {{0, 1, 2}}}}});
  EXPECT_EQ(invalid_input_message([&] { parse_ply(encode(spec, "binary_big_endian"), "a.ply"); }),
            "a.ply: vertex 1: property y is NaN");
  spec.elements[0].props[1].values[1] = 0;
  EXPECT_EQ(
      invalid_input_message([&] { parse_ply(encode(spec, "binary_little_endian"), "a.ply"); }),
      "a.ply: vertex 2: property mask value 1e+300 is out of float range");
}

TEST(IoPly, WriterRefusesChannelNamesThatWouldNotReadBack) {
  Mesh m = test::make_grid(1);
  m.add_channel({"red", 1});
  m.add_channel({"green", 1});
  m.add_channel({"blue", 1});
  EXPECT_TRUE(contains(invalid_input_message([&] { write_mesh(m, "/nonexistent/never.ply"); }),
                       "would not read back as the same channels"));
  Mesh x = test::make_grid(1);
  x.add_channel({"x", 1});
  EXPECT_THROW(write_mesh(x, "/nonexistent/never.ply"), InvalidInput);
  Mesh spaced = test::make_grid(1);
  spaced.add_channel({"two words", 1});
  EXPECT_THROW(write_mesh(spaced, "/nonexistent/never.ply"), InvalidInput);
  Mesh invalid = test::make_grid(1);
  invalid.positions[0].x = std::numeric_limits<float>::infinity();
  EXPECT_THROW(write_mesh(invalid, "/nonexistent/never.ply"), InvalidInput);
}

// ------------------------------------------------------------------------------------------
// OBJ

TEST(IoObj, FaceFormsAndIgnoredStatements) {
  const std::string obj =
      "\xEF\xBB\xBF# comment\r\n"
      "mtllib x.mtl\r\n"
      "o thing\r\n"
      "v 0 0 0\r\n"
      "v 1 0 0 1.0\r\n"  // w ignored
      "v 1 1 0\r\n"
      "v 0 1 0\r\n"
      "vt 0 0\r\nvn 0 0 1\r\ng group\r\ns 1\r\nusemtl m\r\n"
      "f 1/1/1 2//1 3/2 4 # quad\r\n"
      "l 1 2\r\np 1\r\n"
      "v +1e0 -2.5E-1 3.\r\n"
      "f -4 -3 -1";  // relative, no newline at the end
  const Mesh m = parse_obj(obj, "q.obj");
  ASSERT_EQ(m.vertex_count(), 5u);
  EXPECT_EQ(m.positions[4], (Vec3f{1, -0.25f, 3}));
  ASSERT_EQ(m.face_count(), 3u);
  EXPECT_EQ(m.triangles[0], (Triangle{0, 1, 2}));
  EXPECT_EQ(m.triangles[1], (Triangle{0, 2, 3}));
  EXPECT_EQ(m.triangles[2], (Triangle{1, 2, 4}));
  EXPECT_TRUE(m.channels.empty());
}

TEST(IoObj, VertexColoursBecomeTheAlbedo) {
  // The "v x y z r g b" extension; a vertex without a colour gets the default albedo.
  const Mesh m = parse_obj(
      "v 0 0 0 1 0 0\nv 1 0 0 0 0.25 1\nv 0 1 0\nv 1 1 0 0.5 0.5 0.5 \nf 1 2 3\nf 2 4 3\n",
      "c.obj");
  ASSERT_EQ(m.channels.size(), 1u);
  EXPECT_EQ(m.channels[0].desc, default_channel("albedo", 3));
  const float d = default_albedo;
  EXPECT_EQ(m.channels[0].values,
            (std::vector<float>{1, 0, 0, 0, 0.25f, 1, d, d, d, 0.5f, 0.5f, 0.5f}));
  EXPECT_EQ(m.positions[3], (Vec3f{1, 1, 0}));
  // A file without colours has no channel (the material channels are the host's to add).
  EXPECT_TRUE(parse_obj("v 0 0 0 1\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "w.obj").channels.empty());
  const std::string rest = "v 1 0 0\nv 0 1 0\nf 1 2 3\n";
  EXPECT_EQ(invalid_input_message([&] { parse_obj("v 0 0 0 1 x 0\n" + rest, "x.obj"); }),
            "x.obj:1: bad vertex colour 'x'");
  EXPECT_EQ(invalid_input_message([&] { parse_obj("v 0 0 0 1 nan 0\n" + rest, "n.obj"); }),
            "n.obj:1: bad vertex colour 'nan'");
  EXPECT_EQ(invalid_input_message([&] { parse_obj(rest + "v 0 0 0 0 0 255\n", "b.obj"); }),
            "b.obj:4: vertex 2: colour b is 255, outside [0, 1]");
}

TEST(IoObj, ErrorsNameTheLine) {
  const std::string verts = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  EXPECT_EQ(invalid_input_message([&] { parse_obj(verts + "f 1 2 9\n", "box.obj"); }),
            "box.obj:4: face index 9 out of range (3 vertices)");
  EXPECT_EQ(invalid_input_message([&] { parse_obj(verts + "f 1 2 0\n", "z.obj"); }),
            "z.obj:4: face index 0 (OBJ indices start at 1)");
  EXPECT_EQ(invalid_input_message([&] { parse_obj(verts + "f -1 -2 -4\n", "r.obj"); }),
            "r.obj:4: relative face index -4 is before the first vertex (3 vertices so far)");
  EXPECT_EQ(invalid_input_message([&] { parse_obj(verts + "f 1 2 2\n", "d.obj"); }),
            "d.obj:4: face repeats vertex 1 (degenerate triangle)");
  EXPECT_EQ(invalid_input_message([&] { parse_obj(verts + "f\n", "f.obj"); }),
            "f.obj:4: face has 0 vertices (need at least 3)");
  EXPECT_EQ(invalid_input_message([&] { parse_obj(verts + "f 1 a 3\n", "a.obj"); }),
            "a.obj:4: bad face index 'a'");
  EXPECT_EQ(invalid_input_message([&] { parse_obj("v 1 2\n", "v.obj"); }),
            "v.obj:1: vertex has 2 coordinates, need 3");
  EXPECT_EQ(invalid_input_message([&] { parse_obj("v 1 2 3.1+e2\n", "n.obj"); }),
            "n.obj:1: bad vertex coordinate '3.1+e2'");
  EXPECT_EQ(invalid_input_message([&] { parse_obj("v 1 inf 3\n", "i.obj"); }),
            "i.obj:1: vertex 0: y is +Inf");
  EXPECT_EQ(invalid_input_message([&] { parse_obj("v 1e39 0 3\n", "o.obj"); }),
            "o.obj:1: bad vertex coordinate '1e39'");
  EXPECT_EQ(invalid_input_message([&] { parse_obj(verts, "p.obj"); }),
            "p.obj: no faces (point clouds cannot be merged)");
  EXPECT_EQ(invalid_input_message([&] { parse_obj("\xFF\xFEv\0 \0", "w.obj"); }),
            "w.obj: UTF-16 encoded OBJ is not supported (save it as UTF-8)");
  EXPECT_EQ(parse_obj("v 1e-50 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "u.obj").positions[0].x, 0.f);
}

// ------------------------------------------------------------------------------------------
// OFF

// ------------------------------------------------------------------------------------------
// Point sets: files without faces, read only where faces are optional

TEST(IoPoints, FilesWithoutFacesReadOnlyWhereFacesAreOptional) {
  const std::string ply_header =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\n";
  const std::string points = "0 0 0\n1 0 0\n0 1 2\n";
  const std::string no_face_element = ply_header + "end_header\n" + points;
  const std::string zero_faces =
      ply_header + "element face 0\nproperty list uchar int vertex_indices\nend_header\n" + points;
  for (const std::string& ply : {no_face_element, zero_faces}) {
    EXPECT_EQ(invalid_input_message([&] { parse_ply(ply, "p.ply"); }),
              "p.ply: no faces (point clouds cannot be merged)");
    const Mesh m = parse_ply(ply, "p.ply", Faces::optional);
    ASSERT_EQ(m.vertex_count(), 3u);
    EXPECT_EQ(m.face_count(), 0u);
    EXPECT_EQ(m.positions[2].z, 2.f);
  }
  EXPECT_EQ(parse_obj("v 0 0 0\nv 1 0 0\n", "p.obj", Faces::optional).vertex_count(), 2u);
  EXPECT_EQ(parse_off("OFF\n2 0 0\n0 0 0\n1 0 0\n", "p.off", Faces::optional).vertex_count(), 2u);

  // everything else is checked as before
  EXPECT_EQ(invalid_input_message([] { parse_obj("v 0 nan 0\n", "n.obj", Faces::optional); }),
            "n.obj:1: vertex 0: y is NaN");
  EXPECT_EQ(invalid_input_message([] { parse_obj("# nothing\n", "e.obj", Faces::optional); }),
            "e.obj: no vertices");
  EXPECT_EQ(invalid_input_message(
                [] { parse_off("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", "r.off",
                               Faces::optional); }),
            "r.off:6: face 0: vertex index 3 out of range (3 vertices)");
  // a mesh whose faces leave over a million of its vertices unused is still refused
  std::string sparse = "OFF\n1000005 1 0\n";
  sparse.reserve(sparse.size() + 1000005 * 6 + 16);
  for (std::size_t v = 0; v < 1000005; ++v) sparse += "0 0 0\n";
  sparse += "3 0 1 2\n";
  EXPECT_NE(invalid_input_message([&] { parse_off(sparse, "s.off", Faces::optional); })
                .find("used by no face"),
            std::string::npos);
}

TEST(IoOff, VariantsCommentsAndPolygons) {
  const Mesh plain = parse_off(
      "OFF\n# a comment\n\n4 2 0\n0 0 0\n1 0 0\n1 1 0 # trailing comment\n0 1 0\n4 0 1 2 3\n"
      "3 0 2 1 255 0 0\n",
      "p.off");
  ASSERT_EQ(plain.vertex_count(), 4u);
  ASSERT_EQ(plain.face_count(), 3u);
  EXPECT_EQ(plain.triangles[2], (Triangle{0, 2, 1}));

  const Mesh coloured = parse_off(
      "COFF 4 2 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n1 1 0 0 0 255 255\n0 1 0 1 1 1 1\n"
      "4 0 1 2 3\n3 0 2 1 255 0 0\n",
      "c.off");
  EXPECT_EQ(first_difference(plain, coloured), "");
  EXPECT_NO_THROW(
      parse_off("NOFF\n3 1\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n", "n.off"));
  EXPECT_NO_THROW(
      parse_off("STCNOFF\n3 1 0\n0 0 0 0 0 1 1 1 1 1 0 0\n1 0 0 0 0 1 1 1 1 1 0 0\n"
                "0 1 0 0 0 1 1 1 1 1 0 0\n3 0 1 2\n",
                "stcn.off"));
}

TEST(IoOff, Errors) {
  EXPECT_EQ(invalid_input_message([] { parse_off("4OFF\n1 1 0\n0 0 0 0\n3 0 0 0\n", "4.off"); }),
            "4.off:1: unsupported OFF variant '4OFF' (only 3-D [ST][C][N]OFF is supported)");
  EXPECT_EQ(invalid_input_message([] { parse_off("OFF BINARY\n", "b.off"); }),
            "b.off:1: binary OFF is not supported");
  EXPECT_EQ(invalid_input_message(
                [] { parse_off("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", "r.off"); }),
            "r.off:6: face 0: vertex index 3 out of range (3 vertices)");
  EXPECT_EQ(invalid_input_message(
                [] { parse_off("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n", "s.off"); }),
            "s.off:6: face 0 has 3 indices, its count says 4");
  EXPECT_EQ(invalid_input_message([] {
              parse_off("OFF\n3 1 0\n0.000 0.000 0.000\n1.000 0.000 0.000\n0.000 1.000 0.000\n",
                        "e.off");
            }),
            "e.off: unexpected end of file after 0 of 1 faces");
  EXPECT_EQ(invalid_input_message([] { parse_off("OFF\n3000000000 1 0\n0 0 0\n", "big.off"); }),
            "big.off:2: header claims 3000000000 vertices and 1 faces, but only 6 bytes follow");
  EXPECT_EQ(invalid_input_message([] { parse_off("PLY\n", "x.off"); }),
            "x.off:1: not an OFF file (expected 'OFF', got 'PLY')");
  EXPECT_EQ(invalid_input_message([] { parse_off("OFF\nthree 1 0\n", "c.off"); }),
            "c.off:2: expected '<vertices> <faces> [<edges>]', got 'three 1 0'");
}

// ------------------------------------------------------------------------------------------
// STL

std::string binary_stl(const std::string& header80,
                       const std::vector<std::array<float, 9>>& facets) {
  std::string out = header80;
  out.resize(80, ' ');
  const auto n = static_cast<std::uint32_t>(facets.size());
  for (int k = 0; k < 4; ++k) out.push_back(static_cast<char>((n >> (8 * k)) & 0xff));
  for (const auto& f : facets) {
    const float normal[3] = {0, 0, 1};
    out.append(reinterpret_cast<const char*>(normal), 12);
    out.append(reinterpret_cast<const char*>(f.data()), 36);
    out.append(2, '\0');
  }
  return out;
}

TEST(IoStl, BinaryStartingWithSolidAndWelding) {
  const std::vector<std::array<float, 9>> facets = {
      {0, 0, 0, 1, 0, 0, 0, 1, 0}, {1, 0, 0, 1, 1, 0, 0, 1, 0}, {-0.f, 0, 0, 0, 0, 1, 1, 0, 0}};
  std::vector<std::array<float, 9>> with_sliver = facets;
  // Zero-area facets (two bitwise-equal corners, -0 == 0) are dropped without a trace.
  with_sliver.insert(with_sliver.begin() + 1, {7, 7, 7, 7, 7, 7, 8, 8, 8});
  with_sliver.push_back({1, 0, 0, 0, 0, 1, 1, -0.f, 0});
  const Mesh m = parse_stl(binary_stl("solid but binary", with_sliver), "b.stl");
  ASSERT_EQ(m.vertex_count(), 5u);  // -0 welded with 0
  EXPECT_EQ(m.triangles[0], (Triangle{0, 1, 2}));
  EXPECT_EQ(m.triangles[1], (Triangle{1, 3, 2}));
  EXPECT_EQ(m.triangles[2], (Triangle{0, 4, 1}));

  const std::string ascii =
      "solid one\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n"
      "   vertex 0 1 0\n  endloop\n endfacet\nendsolid one\n"
      "SOLID two\n FACET NORMAL nan nan nan\n  OUTER LOOP\n   VERTEX 1 0 0\n   VERTEX 1 1 0\n"
      "   VERTEX 0 1 0\n  ENDLOOP\n ENDFACET\n"
      " facet normal 0 0 1\n  outer loop\n   vertex -0 0 0\n   vertex 0 0 1\n   vertex 1 0 0\n"
      "  endloop\n endfacet\nendsolid two";
  EXPECT_EQ(first_difference(parse_stl(ascii, "a.stl"), m), "");
}

TEST(IoStl, Errors) {
  EXPECT_EQ(invalid_input_message([] {
              parse_stl(
                  "solid x\n facet normal 0 0 1\n outer loop\n vertex 0 0 0\n vertex 0 0 0\n "
                  "vertex 1 0 0\n endloop\n endfacet\nendsolid\n",
                  "d.stl");
            }),
            "d.stl: no vertices");
  EXPECT_EQ(invalid_input_message([] {
              parse_stl(
                  "solid x\n facet normal 0 0 1\n outer loop\n vertex 0 0 0\n vertex 0 1 0\n "
                  "vertex 1 0 0\n vertex 1 1 0\n endloop\n endfacet\nendsolid\n",
                  "q.stl");
            }),
            "q.stl:7: facet 0 has more than 3 vertices (STL facets are triangles)");
  EXPECT_EQ(invalid_input_message([] {
              parse_stl("solid x\n facet normal 0 0 1\n outer loop\n vertex 0 0 0\n vertex 0 z 0\n",
                        "z.stl");
            }),
            "z.stl:5: expected a number, got 'z'");
  EXPECT_EQ(invalid_input_message([] {
              parse_stl("solid x\n facet normal 0 0 1\n outer loop\n vertex 0 0 0\n", "t.stl");
            }),
            "t.stl:5: expected 'vertex' or 'endloop', got end of file");
  std::string wrong_size = binary_stl("binary", {{0, 0, 0, 1, 0, 0, 0, 1, 0}});
  wrong_size.pop_back();
  EXPECT_EQ(invalid_input_message([&] { parse_stl(wrong_size, "w.stl"); }),
            "w.stl: binary STL header claims 1 facets (134 bytes) but the file has 133 bytes");
  const std::string nan_facet = binary_stl("x", {{0, 0, 0, 1, 0, 0, 0, std::nanf(""), 0}});
  EXPECT_EQ(invalid_input_message([&] { parse_stl(nan_facet, "n.stl"); }),
            "n.stl: facet 0: vertex 2: y is NaN");
  EXPECT_EQ(invalid_input_message([] { parse_stl("solid empty\nendsolid empty\n", "e.stl"); }),
            "e.stl: no vertices");
  EXPECT_EQ(invalid_input_message([] { parse_stl("hello", "h.stl"); }),
            "h.stl: not an STL file (too short for binary STL and does not start with 'solid')");
}

// ------------------------------------------------------------------------------------------
// Files: round trips, atomic writes, dispatch

TEST_F(IoFiles, PlyRoundTripIsBitExact) {
  Mesh m = test::make_icosphere_with_channels();
  m.channels[0].desc.linearisation = Linearisation::identity;  // kept through a header comment
  write_mesh(m, path("s.ply"));
  EXPECT_EQ(first_difference(read_mesh(path("s.ply")), m), "");
  EXPECT_EQ(listing(), (std::vector<std::string>{"s.ply"}));

  // Layout the external scorer relies on: little endian, only float scalars in the vertex
  // element, the face list in the face element.
  const std::string bytes = test::read_file(dir_ / "s.ply");
  const std::string header = bytes.substr(0, bytes.find("end_header\n"));
  EXPECT_TRUE(starts_with(header, "ply\nformat binary_little_endian 1.0\n"));
  const std::string vertex_part = header.substr(
      header.find("element vertex"), header.find("element face") - header.find("element vertex"));
  EXPECT_FALSE(contains(vertex_part, "list"));
  EXPECT_TRUE(contains(
      vertex_part, "property float albedo_r\nproperty float albedo_g\nproperty float albedo_b\n"));
  EXPECT_TRUE(contains(vertex_part, "property float tint_a\n"));
  EXPECT_TRUE(contains(header, "element face 320\nproperty list uchar int vertex_indices\n"));
  EXPECT_TRUE(contains(header, "comment csculpt linearisation albedo identity\n"));

  // Same bytes in, same mesh out.
  EXPECT_EQ(first_difference(parse_ply(bytes, "a"), parse_ply(bytes, "b")), "");
}

TEST_F(IoFiles, AsciiPlyWithChannelsRoundTrips) {
  const std::string ascii = encode(pyramid_spec(), "ascii");
  write_text("in.ply", ascii);
  const Mesh in = read_mesh(path("in.ply"));
  ASSERT_EQ(in.channels.size(), 13u);
  write_mesh(in, path("out.ply"));
  EXPECT_EQ(first_difference(read_mesh(path("out.ply")), in), "");
}

TEST_F(IoFiles, TruncatedBinaryPly) {
  write_mesh(test::make_icosphere(1), path("s.ply"));
  const std::string bytes = test::read_file(dir_ / "s.ply");
  EXPECT_EQ(invalid_input_message([&] { parse_ply(bytes.substr(0, bytes.size() - 5), "x.ply"); }),
            "x.ply: truncated binary data in element face (face 79 of 80)");
  const std::size_t body = bytes.find("end_header\n") + 11;
  EXPECT_EQ(invalid_input_message([&] { parse_ply(bytes.substr(0, body + 12 * 41 + 6), "v.ply"); }),
            "v.ply: header claims 42 vertex elements, but only 498 bytes of data are left for them "
            "(truncated file?)");
  std::string zero_count = bytes;
  zero_count[body + 12 * 42] = '\0';  // first face: 0 vertices, then its indices read as faces
  EXPECT_EQ(invalid_input_message([&] { parse_ply(zero_count, "z.ply"); }),
            "z.ply: face 0 has 0 vertices (need at least 3)");
  EXPECT_EQ(invalid_input_message([&] { parse_ply(bytes + "junk", "j.ply"); }),
            "j.ply: 4 bytes of unexpected data after the last element");
}

TEST_F(IoFiles, ObjRoundTripIsBitExactForPositionsAndAlbedo) {
  Mesh m = test::make_icosphere_with_channels();
  const int albedo = m.find_channel("albedo");
  ASSERT_GE(albedo, 0);
  for (float& v : m.channels[static_cast<std::size_t>(albedo)].values)
    v = std::fmod(v * 7.31f, 1.f);
  write_mesh(m, path("s.OBJ"));
  const Mesh back = read_mesh(path("s.OBJ"));
  // The albedo as vertex colours; the other channels have no place in an OBJ.
  EXPECT_EQ(
      first_difference(
          back, Mesh{m.positions, m.triangles, {m.channels[static_cast<std::size_t>(albedo)]}}),
      "");
  write_mesh(Mesh{m.positions, m.triangles, {}}, path("plain.obj"));
  EXPECT_TRUE(read_mesh(path("plain.obj")).channels.empty());
}

TEST_F(IoFiles, FailedWritesLeaveNothingBehind) {
  const Mesh m = test::make_icosphere(0);
  const std::string missing = path("no/such/dir/m.ply");
  EXPECT_THROW(write_mesh(m, missing), IoError);
  EXPECT_FALSE(fs::exists(missing));
  fs::create_directory(dir_ / "taken.ply");
  try {
    write_mesh(m, path("taken.ply"));
    ADD_FAILURE() << "expected IoError";
  } catch (const IoError& e) {
    EXPECT_TRUE(starts_with(e.what(), path("taken.ply") + ": cannot write")) << e.what();
  }
  EXPECT_EQ(listing(), (std::vector<std::string>{"taken.ply"}));
  EXPECT_THROW(write_mesh(m, path("m.stl")), InvalidInput);
  EXPECT_EQ(listing(), (std::vector<std::string>{"taken.ply"}));
}

TEST_F(IoFiles, OverwriteReplacesTheWholeFile) {
  write_mesh(test::make_icosphere(2), path("m.ply"));
  write_mesh(test::make_icosphere(0), path("m.ply"));
  EXPECT_EQ(read_mesh(path("m.ply")).vertex_count(), 12u);
  EXPECT_EQ(listing(), (std::vector<std::string>{"m.ply"}));
}

TEST_F(IoFiles, ReadErrors) {
  EXPECT_THROW(read_mesh(path("absent.ply")), IoError);
  fs::create_directory(dir_ / "d.ply");
  EXPECT_THROW(read_mesh(path("d.ply")), IoError);
  write_text("notes.txt", "hello\n");
  EXPECT_EQ(invalid_input_message([&] { read_mesh(path("notes.txt")); }),
            path("notes.txt") + ": unrecognised file format (supported: .ply .obj .off .stl)");
}

TEST_F(IoFiles, FormatIsSniffedWithoutAKnownExtension) {
  const Mesh m = test::make_icosphere(1);
  write_mesh(m, path("a.ply"));
  write_mesh(m, path("a.obj"));
  fs::rename(dir_ / "a.ply", dir_ / "ply_data");
  fs::rename(dir_ / "a.obj", dir_ / "obj_data.txt");
  EXPECT_EQ(first_difference(read_mesh(path("ply_data")), m), "");
  EXPECT_EQ(first_difference(read_mesh(path("obj_data.txt")), m), "");
  write_text("off_data", "OFF 3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(read_mesh(path("off_data")).face_count(), 1u);
  write_text("stl_data", binary_stl("", {{0, 0, 0, 1, 0, 0, 0, 1, 0}}));
  EXPECT_EQ(read_mesh(path("stl_data")).face_count(), 1u);
}

}  // namespace
}  // namespace csculpt
