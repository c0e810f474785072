// The mesh the artist edits: the host's own arrays (positions, triangles, every channel of
// the file, in the csc_mesh's channel order), its topology and normals. The C ABI copies in
// and out of these arrays (csc_mesh_create, csc_vertex_arrays); the brushes edit them in place.
#pragma once

#include <csculpt.h>

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "surface_normals.h"

struct MeshChannel {
  std::string name;
  uint32_t width = 1;
  csc_linearisation linearisation = CSC_LINEARISATION_IDENTITY;
  float min_value = 0.f, max_value = 1.f;
  std::vector<float> values;  // vertex_count * width
};

/** The arrays a csc_mesh is made of, copied out of a document: hosting hands them to the
 *  session worker, which makes the mesh (csc_mesh_create copies and checks them again) off the
 *  UI thread. */
struct MeshContent {
  std::vector<float> positions;
  std::vector<uint32_t> triangles;
  std::vector<MeshChannel> channels;

  /** A new csc_mesh of these arrays (caller destroys), or NULL with `error`. */
  csc_mesh* to_csc_mesh(std::string& error) const;
};

class MeshDocument {
 public:
  /** Reads a file through csc_mesh_read and adds the material channels it lacks. On failure
   *  the document is unchanged and `error` says why. */
  bool load(const std::string& path, std::string& error);
  /** Replaces the document with the built-in geodesic sphere (with material channels). */
  void make_sphere(uint32_t target_faces);
  /** Copies a mesh's arrays in as they are (no channel added: a session's layout is fixed). */
  bool adopt(const csc_mesh* mesh, const std::string& label, std::string& error);
  /** A new csc_mesh of the current arrays (caller destroys), or NULL with `error`. */
  csc_mesh* to_csc_mesh(std::string& error) const;
  /** PLY with every channel, or OBJ with positions (csc_mesh_write). */
  bool save(const std::string& path, std::string& error) const;

  /** Views of the arrays for csc_diff_capture_arrays / csc_session_*; valid until the
   *  document's layout changes (load, make_sphere, adopt). */
  csc_vertex_arrays vertex_arrays();

  uint32_t vertex_count() const { return static_cast<uint32_t>(positions.size() / 3); }
  uint32_t triangle_count() const { return static_cast<uint32_t>(triangles.size() / 3); }
  /** Floats per vertex over positions and every channel (the undo record's stride). */
  uint32_t values_per_vertex() const;
  void copy_vertex_values(uint32_t vertex, float* out) const;
  void set_vertex_values(uint32_t vertex, const float* in);

  /** Recomputes the face normals of `triangles` from their positions (each once per change,
   *  not once per corner). */
  void recompute_face_normals(std::span<const uint32_t> triangles);
  /** Recomputes the normals of `vertices` from the face normals around them (area-weighted,
   *  summed in a fixed order so equal positions give bit-identical normals: an undone stroke
   *  redraws the same). Their triangles' face normals must be current. */
  void recompute_normals(std::span<const uint32_t> vertices);
  void recompute_all_normals();
  /** Takes face normals of `faces` and vertex normals of `vertices` computed elsewhere from
   *  the positions this document holds (3 floats each, in the lists' order). */
  void set_normals(std::span<const uint32_t> faces, std::span<const float> face_values,
                   std::span<const uint32_t> vertices, std::span<const float> vertex_values);
  /** Vertex and face normals that differ bitwise from what recomputing them all from the
   *  positions gives (0 when every path that moves vertices kept them current). */
  uint32_t stale_normals() const;

  std::vector<float> positions;
  std::vector<uint32_t> triangles;
  std::vector<MeshChannel> channels;
  std::vector<float> normals;
  std::vector<float> face_normals;                 // per triangle, unnormalised (twice its area)
  int albedo = -1, metallic = -1, roughness = -1;  // channel indices
  std::string label;                               // file name or "built-in sphere"

  // Topology (compressed rows): the triangles around each vertex and its neighbours.
  VertexTriangles around;
  std::vector<uint32_t> neighbour_offsets, neighbours;

 private:
  void build_topology();
  void find_material_channels();
  void finish_layout();
  std::vector<float*> channel_pointers_;
};
