// Small deterministic meshes and comparison helpers shared by the tests.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "csculpt/mesh.h"

namespace csculpt::test {

/// A unit sphere: the regular icosahedron (12 vertices, 20 triangles) with every triangle
/// split into 4 `subdivisions` times, new vertices projected onto the sphere. Vertices are
/// shared (10 * 4^s + 2 of them, 20 * 4^s triangles), triangles wound counter-clockwise seen
/// from outside, so the mesh is a closed, consistently oriented 2-manifold.
inline Mesh make_icosphere(int subdivisions) {
  const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
  Mesh mesh;
  mesh.positions = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                    {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  mesh.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                    {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                    {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                    {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  auto normalise = [](Vec3f p) {
    const float len = std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z);
    return Vec3f{p.x / len, p.y / len, p.z / len};
  };
  for (Vec3f& p : mesh.positions) p = normalise(p);
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> midpoints;
    auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = a < b ? std::make_pair(a, b) : std::make_pair(b, a);
      const auto it = midpoints.find(key);
      if (it != midpoints.end()) return it->second;
      const Vec3f& pa = mesh.positions[a];
      const Vec3f& pb = mesh.positions[b];
      const auto index = static_cast<std::uint32_t>(mesh.positions.size());
      mesh.positions.push_back(
          normalise({(pa.x + pb.x) / 2, (pa.y + pb.y) / 2, (pa.z + pb.z) / 2}));
      midpoints.emplace(key, index);
      return index;
    };
    std::vector<Triangle> next;
    next.reserve(mesh.triangles.size() * 4);
    for (const Triangle& tri : mesh.triangles) {
      const std::uint32_t ab = midpoint(tri[0], tri[1]);
      const std::uint32_t bc = midpoint(tri[1], tri[2]);
      const std::uint32_t ca = midpoint(tri[2], tri[0]);
      next.push_back({tri[0], ab, ca});
      next.push_back({tri[1], bc, ab});
      next.push_back({tri[2], ca, bc});
      next.push_back({ab, bc, ca});
    }
    mesh.triangles = std::move(next);
  }
  return mesh;
}

/// An n x n grid of quads over [0,1]^2 in the z = 0 plane, each split into two triangles
/// wound counter-clockwise seen from +z: (n+1)^2 vertices (row-major, x fastest), 2 n^2
/// triangles. An open mesh with a boundary, unlike the icosphere.
inline Mesh make_grid(int n) {
  Mesh mesh;
  const auto m = static_cast<std::uint32_t>(n);
  for (std::uint32_t j = 0; j <= m; ++j) {
    for (std::uint32_t i = 0; i <= m; ++i) {
      mesh.positions.push_back({static_cast<float>(i) / static_cast<float>(m),
                                static_cast<float>(j) / static_cast<float>(m), 0.f});
    }
  }
  auto at = [m](std::uint32_t i, std::uint32_t j) { return j * (m + 1) + i; };
  for (std::uint32_t j = 0; j < m; ++j) {
    for (std::uint32_t i = 0; i < m; ++i) {
      mesh.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      mesh.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  }
  return mesh;
}

/// Adds the built-in material channels (albedo, metallic, roughness) with smooth, distinct
/// values in [0,1] derived from the positions, so that channels are not all constant.
inline void add_material_channels(Mesh& mesh) {
  for (const ChannelDesc& d : material_channels()) mesh.add_channel(d);
  Channel& albedo = mesh.channels[static_cast<std::size_t>(mesh.find_channel("albedo"))];
  Channel& metallic = mesh.channels[static_cast<std::size_t>(mesh.find_channel("metallic"))];
  Channel& roughness = mesh.channels[static_cast<std::size_t>(mesh.find_channel("roughness"))];
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
    const Vec3f& p = mesh.positions[v];
    albedo.values[3 * v + 0] = 0.5f + 0.5f * std::sin(3.1f * p.x + 0.2f);
    albedo.values[3 * v + 1] = 0.5f + 0.5f * std::sin(2.3f * p.y + 1.1f);
    albedo.values[3 * v + 2] = 0.5f + 0.5f * std::sin(1.7f * p.z + 2.0f);
    metallic.values[v] = p.x > 0 ? 1.f : 0.f;
    roughness.values[v] = 0.25f + 0.25f * (p.y + 1.f);
  }
}

/// "" when a and b are bit-identical (positions, triangles, channel layout and values),
/// otherwise a description of the first difference, for test failure messages.
inline std::string first_difference(const Mesh& a, const Mesh& b) {
  std::ostringstream out;
  auto same_bits = [](float x, float y) { return std::memcmp(&x, &y, sizeof(float)) == 0; };
  if (a.vertex_count() != b.vertex_count()) {
    out << "vertex count " << a.vertex_count() << " vs " << b.vertex_count();
    return out.str();
  }
  if (a.face_count() != b.face_count()) {
    out << "triangle count " << a.face_count() << " vs " << b.face_count();
    return out.str();
  }
  for (std::size_t v = 0; v < a.vertex_count(); ++v) {
    const Vec3f& p = a.positions[v];
    const Vec3f& q = b.positions[v];
    if (!same_bits(p.x, q.x) || !same_bits(p.y, q.y) || !same_bits(p.z, q.z)) {
      out.precision(9);
      out << "position " << v << ": (" << p.x << ", " << p.y << ", " << p.z << ") vs (" << q.x
          << ", " << q.y << ", " << q.z << ")";
      return out.str();
    }
  }
  for (std::size_t t = 0; t < a.face_count(); ++t) {
    if (a.triangles[t] != b.triangles[t]) {
      out << "triangle " << t << ": (" << a.triangles[t][0] << ", " << a.triangles[t][1] << ", "
          << a.triangles[t][2] << ") vs (" << b.triangles[t][0] << ", " << b.triangles[t][1] << ", "
          << b.triangles[t][2] << ")";
      return out.str();
    }
  }
  if (a.channels.size() != b.channels.size()) {
    out << "channel count " << a.channels.size() << " vs " << b.channels.size();
    return out.str();
  }
  for (std::size_t c = 0; c < a.channels.size(); ++c) {
    const Channel& x = a.channels[c];
    const Channel& y = b.channels[c];
    if (!(x.desc == y.desc)) {
      out << "channel " << c << ": " << x.desc.name << "/" << x.desc.width << "/"
          << to_string(x.desc.linearisation) << " vs " << y.desc.name << "/" << y.desc.width << "/"
          << to_string(y.desc.linearisation);
      return out.str();
    }
    if (x.values.size() != y.values.size()) {
      out << "channel " << x.desc.name << ": " << x.values.size() << " vs " << y.values.size()
          << " values";
      return out.str();
    }
    for (std::size_t i = 0; i < x.values.size(); ++i) {
      if (!same_bits(x.values[i], y.values[i])) {
        out.precision(9);
        out << "channel " << x.desc.name << " value " << i << ": " << x.values[i] << " vs "
            << y.values[i];
        return out.str();
      }
    }
  }
  return {};
}

/// An icosphere with the material channels plus a 2-wide and a 4-wide channel whose values
/// exercise float round trips (not simple fractions).
inline Mesh make_icosphere_with_channels() {
  Mesh m = make_icosphere(2);
  add_material_channels(m);
  const int uv = m.add_channel({"uv", 2});
  const int tint = m.add_channel({"tint", 4});
  for (std::size_t v = 0; v < m.vertex_count(); ++v) {
    for (std::size_t k = 0; k < 2; ++k) {
      m.channels[static_cast<std::size_t>(uv)].values[2 * v + k] = static_cast<float>(v + k) / 7.f;
    }
    for (std::size_t k = 0; k < 4; ++k) {
      m.channels[static_cast<std::size_t>(tint)].values[4 * v + k] =
          std::nextafter(static_cast<float>(v * k) / 3.f, 2.f);
    }
  }
  // Values that text formats get wrong unless they print enough digits.
  m.positions[0] = {0.1f, -0.f, 1.f / 3.f};
  m.positions[1] = {std::numeric_limits<float>::denorm_min(), 16777217.f, -1e-30f};
  return m;
}

}  // namespace csculpt::test
