// Built-in meshes and scripted sculpting strokes: the default mesh of the demo and the
// benchmark, and the edits the tests and benchmarks merge.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "csculpt/hierarchy.h"
#include "csculpt/mesh.h"

namespace csculpt {

/// A unit sphere: an icosahedron whose edges are split into k segments (20 k^2 triangles,
/// 10 k^2 + 2 shared vertices), k chosen so the face count is closest to `target_faces`.
/// With `materials`, adds the built-in material channels filled with default_material_fill()
/// (a grey rough dielectric, csculpt/mesh.h).
Mesh make_sphere(std::uint32_t target_faces, bool materials = false);

/// Area-weighted vertex normals (unit; zero for a vertex on no non-degenerate face).
std::vector<Vec3f> vertex_normals(const Mesh& mesh);

/// A sculpting or painting stroke, applied with a smooth falloff (1 - (d/r)^2)^2 around
/// `center` out to `radius`.
struct Stroke {
  enum class Kind : std::uint32_t {
    grab,     ///< move along `axis` by strength * radius
    inflate,  ///< move along the normal by strength * radius
    detail,   ///< high-frequency relief along the normal (noise of `frequency` per radius)
    twist,    ///< rotate about `axis` through center by up to `strength` radians
    bend,     ///< rotate about `axis` by strength * (how far past center along `direction`)
    smooth,   ///< Laplacian smoothing towards the neighbours' mean
    paint,    ///< blend the material channels towards `albedo`, `roughness`, `metallic`
  };
  Kind kind = Kind::grab;
  Vec3f center{0, 0, 0};
  float radius = 0.5f;
  float strength = 0.1f;
  Vec3f axis{0, 0, 1};
  Vec3f direction{1, 0, 0};
  float frequency = 8.f;
  std::array<float, 3> albedo{0.8f, 0.2f, 0.1f};
  float roughness = 0.3f;
  float metallic = 1.f;
};

/// Applies the stroke to `mesh` in place (positions, or the material channels for paint,
/// which are added if missing). `topology` is needed for smooth only. Throws InvalidInput on
/// a radius that is not positive and finite. `changed` (if given) gets the vertices the stroke
/// wrote appended, each once per call.
void apply_stroke(Mesh& mesh, const Stroke& stroke, const Topology* topology = nullptr,
                  std::vector<std::uint32_t>* changed = nullptr);

/// A deterministic artist: `count` strokes at mixed scales (soft brushes as big as half the
/// model, medium inflates, fine detail, occasional twists and paint) around the surface of
/// `mesh`, from `seed`. Throws InvalidInput when strokes are asked of a mesh without vertices.
std::vector<Stroke> scripted_strokes(const Mesh& mesh, std::uint64_t seed, std::uint32_t count,
                                     bool paint = true);

}  // namespace csculpt
