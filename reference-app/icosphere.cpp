#include "icosphere.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <unordered_map>

#include "morton.h"

namespace {

using Vec = std::array<double, 3>;

Vec lerp(const Vec& a, const Vec& b, double t) {
  return {a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t, a[2] + (b[2] - a[2]) * t};
}

Vec normalised(const Vec& v) {
  const double n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  return {v[0] / n, v[1] / n, v[2] / n};
}

uint32_t sphere_morton_code(const float* p) {  // the unit sphere's box is [-1, 1]^3
  auto cell = [](float c) { return morton_cell(c, -1.f, 511.5f); };
  return morton_code(cell(p[0]), cell(p[1]), cell(p[2]));
}

// Renumbers the vertices along the Morton curve (triangles keep their order and winding).
void reorder_by_morton(TriangleMesh& mesh) {
  const size_t count = mesh.positions.size() / 3;
  std::vector<uint32_t> codes(count), order(count), new_index(count);
  for (size_t v = 0; v < count; ++v) codes[v] = sphere_morton_code(&mesh.positions[3 * v]);
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(),
                   [&](uint32_t a, uint32_t b) { return codes[a] < codes[b]; });
  std::vector<float> positions(mesh.positions.size());
  for (size_t i = 0; i < count; ++i) {
    new_index[order[i]] = static_cast<uint32_t>(i);
    std::copy_n(&mesh.positions[3 * order[i]], 3, &positions[3 * i]);
  }
  mesh.positions.swap(positions);
  for (uint32_t& index : mesh.triangles) index = new_index[index];
}

}  // namespace

TriangleMesh make_geodesic_sphere(uint32_t target_faces) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  const std::array<Vec, 12> corners = {{{-1, t, 0},
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
  const std::array<std::array<uint32_t, 3>, 20> faces = {
      {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
       {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
       {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}}};
  const uint32_t n =
      std::max<uint32_t>(1, static_cast<uint32_t>(std::lround(std::sqrt(target_faces / 20.0))));

  TriangleMesh mesh;
  std::unordered_map<uint64_t, uint32_t> index_of;  // build time only
  index_of.reserve(10 * size_t{n} * n + 2);
  // A shared vertex must get one index and one position whichever face reaches it first, so
  // corners and edge points are keyed and placed from their canonical (lower corner first) form.
  auto vertex = [&](uint64_t key, const Vec& where) {
    auto [it, inserted] =
        index_of.try_emplace(key, static_cast<uint32_t>(mesh.positions.size() / 3));
    if (inserted) {
      const Vec p = normalised(where);
      for (double c : p) mesh.positions.push_back(static_cast<float>(c));
    }
    return it->second;
  };
  auto edge_point = [&](uint32_t a, uint32_t b, uint32_t step) {  // step/n of the way from a to b
    if (a > b) std::swap(a, b), step = n - step;
    const uint64_t key = (uint64_t{1} << 62) | (uint64_t{a} << 40) | (uint64_t{b} << 20) | step;
    return vertex(key, lerp(corners[a], corners[b], double(step) / n));
  };
  for (uint32_t f = 0; f < faces.size(); ++f) {
    const auto [a, b, c] = faces[f];
    auto point = [&](uint32_t i, uint32_t j) -> uint32_t {  // a + (b-a) i/n + (c-a) j/n
      if (i == 0 && j == 0) return vertex(a, corners[a]);
      if (i == n) return vertex(b, corners[b]);
      if (j == n) return vertex(c, corners[c]);
      if (j == 0) return edge_point(a, b, i);
      if (i == 0) return edge_point(a, c, j);
      if (i + j == n) return edge_point(b, c, j);
      const uint64_t key = (uint64_t{2} << 62) | (uint64_t{f} << 40) | (uint64_t{i} << 20) | j;
      const Vec ab = lerp(corners[a], corners[b], double(i) / n);
      const Vec ac = lerp(corners[a], corners[c], double(j) / n);
      return vertex(key, {ab[0] + ac[0] - corners[a][0], ab[1] + ac[1] - corners[a][1],
                          ab[2] + ac[2] - corners[a][2]});
    };
    for (uint32_t i = 0; i < n; ++i)
      for (uint32_t j = 0; i + j < n; ++j) {
        mesh.triangles.insert(mesh.triangles.end(),
                              {point(i, j), point(i + 1, j), point(i, j + 1)});
        if (i + j + 1 < n)
          mesh.triangles.insert(mesh.triangles.end(),
                                {point(i + 1, j), point(i + 1, j + 1), point(i, j + 1)});
      }
  }
  reorder_by_morton(mesh);
  return mesh;
}
