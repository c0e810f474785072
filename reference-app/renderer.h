// OpenGL 3.3 core drawing of the mesh: one buffer per attribute (position, normal, albedo,
// roughness, metallic) so a brush re-uploads only the changed vertices of what it changed.
#pragma once

#include <epoxy/gl.h>
#include <glm/mat4x4.hpp>

#include <iterator>
#include <span>
#include <string>
#include <vector>

#include "draw_clusters.h"
#include "marks.h"
#include "mesh_buffers.h"
#include "mesh_document.h"

struct ViewSettings {
  bool flat_shading = false;
  bool wireframe = false;
  bool backface_culling = true;
};

class Renderer {
 public:
  Renderer() = default;
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;
  ~Renderer() { release(); }
  /** Deletes the GL objects (the context must be current). */
  void release();

  bool init(std::string& error);
  /** Takes a new mesh (after the layout changed): `clusters` built for its positions and
   *  triangles (DrawClusters::build, which a caller may run on another thread: it is tens of
   *  milliseconds at 320K faces), then every vertex value uploaded. */
  void upload_mesh(const MeshDocument& document, DrawClusters clusters);
  /** Makes and fills a mesh's buffers in the current context, which may be another thread's
   *  sharing this one's objects: llvmpipe copies the data into new memory in the call, and at
   *  1M vertices that is hundreds of milliseconds, mostly pages faulted in. Ends with
   *  glFinish, so the buffers are complete for every context. */
  static MeshBuffers fill_buffers(const MeshDocument& document, const DrawClusters& clusters);
  /** upload_mesh() with buffers fill_buffers() made: they replace the drawn ones. */
  void adopt_mesh(const MeshDocument& document, DrawClusters clusters, MeshBuffers buffers);
  /** Uploads every vertex value again (the same triangles). */
  void upload_values(const MeshDocument& document);
  /** Uploads `vertices` (unique, any order) as a few contiguous glBufferSubData runs. Called
   *  every frame, empty or not: the draw's clusters catch up with earlier changes. */
  void upload_vertices(const MeshDocument& document, std::span<const uint32_t> vertices);
  /** Replaces the drawn colours (e.g. the attribution view) without touching the document;
   *  until upload_values() or upload_mesh(), vertices uploaded as changed keep these colours. */
  void upload_colour_override(std::span<const float> rgb);
  void draw(const glm::mat4& view, const glm::mat4& projection, const ViewSettings& settings);
  uint32_t uploaded_vertices_last() const { return uploaded_last_; }
  /** Triangles the last draw() sent to GL (the clusters in view and not facing away). */
  uint32_t drawn_triangles_last() const { return drawn_last_; }

 private:
  enum Attribute { kPosition, kNormal, kAlbedo, kRoughness, kMetallic, kAttributeCount };
  static_assert(std::size(MeshBuffers{}.attributes) == kAttributeCount);
  static_assert(sizeof(GLuint) == sizeof(unsigned));
  void upload_range(const MeshDocument& document, uint32_t first, uint32_t count);
  /** Points the vertex array's attributes at buffers_ and its indices at index_buffer_. */
  void attach_buffers();
  /** The visible clusters' index ranges for this draw (drawn once, or twice for wireframe). */
  void find_visible(const glm::mat4& view, const glm::mat4& projection, bool cull_back_faces);
  void draw_visible() const;

  GLuint program_ = 0, vao_ = 0, index_buffer_ = 0;
  GLuint buffers_[kAttributeCount] = {};
  GLint u_view_ = -1, u_projection_ = -1, u_flat_ = -1, u_wire_ = -1;
  GLsizei index_count_ = 0;
  uint32_t vertex_count_ = 0, uploaded_last_ = 0, drawn_last_ = 0;
  bool colour_overridden_ = false;
  DrawClusters clusters_;
  Marks upload_marks_;                               // the vertices of one upload, taken in order
  std::vector<uint32_t> range_first_, range_count_;  // visible index ranges, per draw
  std::vector<GLsizei> draw_counts_;
  std::vector<const void*> draw_offsets_;
  std::vector<float> constant_;  // fill for a material channel the mesh lacks
};
