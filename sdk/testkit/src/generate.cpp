#include "csculpt/testkit/generate.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>

#include "csculpt/dual_quat.h"
#include "csculpt/error.h"
#include "csculpt/testkit/random.h"
#include "csculpt/vec3.h"

namespace csculpt {
namespace {

float falloff(float d, float r) {
  if (d >= r) return 0.f;
  const float t = 1.f - (d / r) * (d / r);
  return t * t;
}

/// Deterministic artist randomness: the same strokes on every platform.
struct Rng : SplitMix64 {
  float uniform() { return uniform_float(); }
  float range(float a, float b) { return range_float(a, b); }
  Vec3f direction() {
    for (;;) {
      const Vec3f v{range(-1, 1), range(-1, 1), range(-1, 1)};
      const float n2 = dot(v, v);
      if (n2 > 1e-4f && n2 <= 1.f) return scale(v, 1.f / std::sqrt(n2));
    }
  }
};

Quat axis_angle(Vec3f axis, float angle) {
  const float s = std::sin(0.5f * angle);
  return {std::cos(0.5f * angle), axis.x * s, axis.y * s, axis.z * s};
}

}  // namespace

Mesh make_sphere(std::uint32_t target_faces, bool materials) {
  // 20 k^2 faces: of the two k around sqrt(target / 20), the one whose count is closer
  // (the smaller on a tie).
  const auto below = static_cast<std::uint32_t>(
      std::max(1.0, std::floor(std::sqrt(static_cast<double>(target_faces) / 20.0))));
  auto distance = [&](std::uint64_t k) {
    const std::uint64_t faces = 20 * k * k;
    return faces > target_faces ? faces - target_faces : target_faces - faces;
  };
  const std::uint32_t k = distance(below + 1) < distance(below) ? below + 1 : below;
  const float t = (1.f + std::sqrt(5.f)) / 2.f;
  const std::array<Vec3f, 12> ico = {{{-1, t, 0},
                                      {1, t, 0},
                                      {-1, -t, 0},
                                      {1, -t, 0},
                                      {0, -1, t},
                                      {0, 1, t},
                                      {0, -1, -t},
                                      {0, 1, -t},
                                      {t, 0, -1},
                                      {t, 0, 1},
                                      {-t, 0, -1},
                                      {-t, 0, 1}}};
  const std::array<Triangle, 20> faces = {
      {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
       {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
       {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}}};
  Mesh mesh;
  for (const Vec3f& c : ico) mesh.positions.push_back(c);
  // Points on icosahedron edges are shared by the two faces of the edge: index them by the
  // edge's lower corner, upper corner and step from the lower corner.
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> edge_start;
  auto edge_point = [&](std::uint32_t a, std::uint32_t b, std::uint32_t step) -> std::uint32_t {
    if (step == 0) return a;
    if (step == k) return b;
    const bool flip = a > b;
    const std::uint32_t lo = flip ? b : a, hi = flip ? a : b;
    const std::uint32_t s = flip ? k - step : step;
    auto [it, inserted] = edge_start.try_emplace({lo, hi}, 0u);
    if (inserted) {
      it->second = static_cast<std::uint32_t>(mesh.positions.size());
      for (std::uint32_t i = 1; i < k; ++i) {
        const float w = static_cast<float>(i) / static_cast<float>(k);
        mesh.positions.push_back(add(scale(ico[lo], 1 - w), scale(ico[hi], w)));
      }
    }
    return it->second + s - 1;
  };
  for (const Triangle& f : faces) {
    // grid point (i, j): i steps from corner 0 towards corner 1, j towards corner 2
    std::vector<std::uint32_t> grid((k + 1) * (k + 1), 0);
    auto at = [&](std::uint32_t i, std::uint32_t j) -> std::uint32_t& {
      return grid[i * (k + 1) + j];
    };
    for (std::uint32_t i = 0; i <= k; ++i) {
      for (std::uint32_t j = 0; i + j <= k; ++j) {
        if (j == 0)
          at(i, j) = edge_point(f[0], f[1], i);
        else if (i == 0)
          at(i, j) = edge_point(f[0], f[2], j);
        else if (i + j == k)
          at(i, j) = edge_point(f[1], f[2], j);
        else {
          const float a = static_cast<float>(i) / static_cast<float>(k);
          const float b = static_cast<float>(j) / static_cast<float>(k);
          at(i, j) = static_cast<std::uint32_t>(mesh.positions.size());
          mesh.positions.push_back(
              add(add(scale(ico[f[0]], 1 - a - b), scale(ico[f[1]], a)), scale(ico[f[2]], b)));
        }
      }
    }
    for (std::uint32_t i = 0; i < k; ++i) {
      for (std::uint32_t j = 0; i + j < k; ++j) {
        mesh.triangles.push_back({at(i, j), at(i + 1, j), at(i, j + 1)});
        if (i + j + 1 < k) mesh.triangles.push_back({at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)});
      }
    }
  }
  for (Vec3f& p : mesh.positions) p = unit(p);
  if (materials) {
    for (const ChannelDesc& d : material_channels()) mesh.add_channel(d, default_material_fill(d));
  }
  return mesh;
}

std::vector<Vec3f> vertex_normals(const Mesh& mesh) {
  std::vector<Vec3f> n(mesh.vertex_count(), Vec3f{0, 0, 0});
  for (const Triangle& t : mesh.triangles) {
    const Vec3f& a = mesh.positions[t[0]];
    const Vec3f c = cross(sub(mesh.positions[t[1]], a), sub(mesh.positions[t[2]], a));
    for (std::uint32_t v : t) n[v] = add(n[v], c);
  }
  for (Vec3f& v : n) v = unit(v);
  return n;
}

void apply_stroke(Mesh& mesh, const Stroke& s, const Topology* topology,
                  std::vector<std::uint32_t>* changed) {
  if (!(s.radius > 0) || !std::isfinite(s.radius))
    throw InvalidInput("apply_stroke: the radius must be positive and finite, not " +
                       std::to_string(s.radius));
  const std::size_t n = mesh.vertex_count();
  const Vec3f axis = unit(s.axis);
  auto wrote = [changed](std::size_t v) {
    if (changed) changed->push_back(static_cast<std::uint32_t>(v));
  };
  switch (s.kind) {
    case Stroke::Kind::grab:
    case Stroke::Kind::inflate:
    case Stroke::Kind::detail: {
      const std::vector<Vec3f> normals =
          s.kind == Stroke::Kind::grab ? std::vector<Vec3f>{} : vertex_normals(mesh);
      for (std::size_t v = 0; v < n; ++v) {
        Vec3f& p = mesh.positions[v];
        const Vec3f d = sub(p, s.center);
        const float w = falloff(std::sqrt(dot(d, d)), s.radius);
        if (w == 0.f) continue;
        wrote(v);
        if (s.kind == Stroke::Kind::grab) {
          p = add(p, scale(axis, s.strength * s.radius * w));
        } else {
          float amount = s.strength * s.radius * w;
          if (s.kind == Stroke::Kind::detail) {
            const float f = s.frequency / s.radius;
            amount *=
                std::sin(f * d.x + 1.3f) * std::sin(f * d.y + 0.7f) * std::sin(f * d.z + 2.1f);
          }
          p = add(p, scale(normals[v], amount));
        }
      }
      break;
    }
    case Stroke::Kind::twist:
    case Stroke::Kind::bend: {
      const Vec3f dir = unit(s.direction);
      for (std::size_t v = 0; v < n; ++v) {
        Vec3f& p = mesh.positions[v];
        const Vec3f d = sub(p, s.center);
        float angle;
        if (s.kind == Stroke::Kind::twist) {
          angle = s.strength * falloff(std::sqrt(dot(d, d)), s.radius);
        } else {
          const float along = std::clamp(dot(d, dir) / s.radius, 0.f, 1.f);
          angle = s.strength * along * along * (3 - 2 * along);  // smoothstep
        }
        if (angle == 0.f) continue;
        wrote(v);
        p = add(s.center, rotate(axis_angle(axis, angle), d));
      }
      break;
    }
    case Stroke::Kind::smooth: {
      if (!topology) break;
      const std::vector<Vec3f> before = mesh.positions;
      for (std::size_t v = 0; v < n; ++v) {
        const Vec3f d = sub(before[v], s.center);
        const float w = falloff(std::sqrt(dot(d, d)), s.radius) * std::clamp(s.strength, 0.f, 1.f);
        const auto row = topology->vertex_vertices.row(v);
        if (w == 0.f || row.empty()) continue;
        wrote(v);
        Vec3f mean{0, 0, 0};
        for (std::uint32_t u : row) mean = add(mean, before[u]);
        mean = scale(mean, 1.f / static_cast<float>(row.size()));
        mesh.positions[v] = add(before[v], scale(sub(mean, before[v]), w));
      }
      break;
    }
    case Stroke::Kind::paint: {
      for (const ChannelDesc& d : material_channels())
        mesh.add_channel(d, default_material_fill(d));
      Channel& albedo = mesh.channels[static_cast<std::size_t>(mesh.find_channel("albedo"))];
      Channel& rough = mesh.channels[static_cast<std::size_t>(mesh.find_channel("roughness"))];
      Channel& metal = mesh.channels[static_cast<std::size_t>(mesh.find_channel("metallic"))];
      for (std::size_t v = 0; v < n; ++v) {
        const Vec3f d = sub(mesh.positions[v], s.center);
        const float w = falloff(std::sqrt(dot(d, d)), s.radius) * std::clamp(s.strength, 0.f, 1.f);
        if (w == 0.f) continue;
        wrote(v);
        for (int c = 0; c < 3; ++c) {
          float& a = albedo.values[3 * v + static_cast<std::size_t>(c)];
          a += (s.albedo[static_cast<std::size_t>(c)] - a) * w;
        }
        rough.values[v] += (s.roughness - rough.values[v]) * w;
        metal.values[v] += (s.metallic - metal.values[v]) * w;
      }
      break;
    }
  }
}

std::vector<Stroke> scripted_strokes(const Mesh& mesh, std::uint64_t seed, std::uint32_t count,
                                     bool paint) {
  if (count > 0 && mesh.vertex_count() == 0)
    throw InvalidInput("scripted_strokes: the mesh has no vertex to anchor a stroke to");
  Rng rng;
  rng.state = seed * 0x2545F4914F6CDD1Dull + 17;
  const float diag = bbox_diagonal(mesh.positions);
  std::vector<Stroke> strokes;
  for (std::uint32_t i = 0; i < count; ++i) {
    Stroke s;
    const Vec3f& anchor = mesh.positions[rng.next() % mesh.vertex_count()];
    s.center = anchor;
    s.axis = rng.direction();
    s.direction = rng.direction();
    const float pick = rng.uniform();
    if (pick < 0.25f) {  // large soft brush, up to half the model
      s.kind = Stroke::Kind::grab;
      s.radius = diag * rng.range(0.15f, 0.3f);
      s.strength = rng.range(0.05f, 0.2f);
    } else if (pick < 0.5f) {
      s.kind = Stroke::Kind::inflate;
      s.radius = diag * rng.range(0.05f, 0.15f);
      s.strength = rng.range(-0.15f, 0.15f);
    } else if (pick < 0.75f) {
      s.kind = Stroke::Kind::detail;
      s.radius = diag * rng.range(0.03f, 0.08f);
      s.strength = rng.range(0.03f, 0.08f);
      s.frequency = rng.range(6.f, 14.f);
    } else if (pick < 0.87f || !paint) {
      s.kind = Stroke::Kind::twist;
      s.radius = diag * rng.range(0.1f, 0.25f);
      s.strength = rng.range(-0.6f, 0.6f);
      s.axis = unit(anchor);
    } else {
      s.kind = Stroke::Kind::paint;
      s.radius = diag * rng.range(0.05f, 0.2f);
      s.strength = rng.range(0.3f, 1.f);
      s.albedo = {rng.uniform(), rng.uniform(), rng.uniform()};
      s.roughness = rng.uniform();
      s.metallic = rng.uniform() < 0.5f ? 0.f : 1.f;
    }
    strokes.push_back(s);
  }
  return strokes;
}

}  // namespace csculpt
