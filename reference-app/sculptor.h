// The brushes: one dab changes the vertices within the brush's world radius of the hit point,
// weighted by the falloff, mirrored across the enabled symmetry planes. After each change the
// normals of the touched region are recomputed and the BVH refitted, and the vertices whose
// drawn values changed are queued for the renderer's partial upload.
#pragma once

#include <glm/vec3.hpp>

#include <cstdint>
#include <span>
#include <vector>

#include "brush.h"
#include "bvh.h"
#include "mesh_document.h"
#include "side_task.h"
#include "stroke_history.h"
#include "version_normals.h"

struct DabInput {
  glm::vec3 center;          // the hit point
  glm::vec3 view_direction;  // from the eye towards the hit point
  float radius;              // world units
  float strength;            // 0..1, pressure applied
  bool invert;
  BrushKind kind;  // the brush in effect (Shift selects smooth)
};

class Sculptor {
 public:
  Sculptor(MeshDocument& document, TriangleBvh& bvh, StrokeHistory& history)
      : document_(document), bvh_(bvh), history_(history) {}
  /** Sizes the per-vertex scratch after the document's layout changed. */
  void reset();

  void dab(const DabInput& input, const BrushSettings& settings);
  /** Grab: the region under the press follows the cursor's world offset `delta`. */
  void grab_begin(const DabInput& input, const BrushSettings& settings);
  void grab_move(glm::vec3 delta);
  void grab_end() { grab_entries_.clear(); }
  /** A grab's moves left the BVH's boxes loose (cheap per move): tightened once. */
  void stroke_ended() { bvh_.tighten(document_.positions, document_.triangles); }

  /** After positions (or only channels) of `vertices` changed outside a stroke (undo, a
   *  merged version): normals around them, BVH boxes, and the renderer's queue. */
  void refresh_after_change(std::span<const uint32_t> vertices, bool positions_changed);
  /** The same for a session version whose values the document holds now: its normals and
   *  the BVH's boxes around what moved were computed by the session worker (no boxes: they
   *  are refitted here). */
  void adopt_version(std::span<const uint32_t> vertices, const ChangedNormals& normals,
                     std::span<const uint32_t> bvh_nodes, std::span<const BvhBox> bvh_boxes);
  /** Vertices to re-upload (unique, unsorted); the renderer clears it. */
  std::vector<uint32_t>& dirty_vertices() { return dirty_; }
  void clear_dirty();
  uint32_t last_dab_vertices() const { return last_dab_vertices_; }

 private:
  struct RegionVertex {
    uint32_t vertex;
    float weight;
  };
  struct GrabEntry {
    uint32_t vertex;
    float weight;
    glm::vec3 mirror;  // the symmetry's sign per axis
    glm::vec3 original;
  };
  void gather_region(glm::vec3 center, float radius, glm::vec3 view_direction, bool front_only,
                     Falloff falloff);
  void apply(const DabInput& input, const BrushSettings& settings, glm::vec3 center, float parity);
  std::span<const glm::vec3> mirrors(const BrushSettings& settings);
  uint32_t next_stamp(std::vector<uint32_t>& stamps, uint32_t& epoch);
  void mark_dirty(uint32_t v);  // queued for the renderer once
  /** refresh_after_change for a grab's move: the BVH's boxes only grow. */
  void refresh(std::span<const uint32_t> vertices, bool positions_changed);
  /** The normals around `vertices` and the renderer's queue (not the BVH). */
  void refresh_normals(std::span<const uint32_t> vertices, bool positions_changed);
  /** Recomputes the normals normals_change_ lists and queues their vertices. */
  void update_changed_normals();
  /** The vertex normals part of it (the face normals already current). */
  void update_vertex_normals();
  /** After a dab moved vertices: the normals around them and the boxes its queries met. */
  void refresh_region();
  /** Empties region_leaves_ and its marks, as the next region query expects them. */
  void forget_region_leaves();
  glm::vec3 position(uint32_t v) const;
  void set_position(uint32_t v, glm::vec3 p);

  MeshDocument& document_;
  TriangleBvh& bvh_;
  StrokeHistory& history_;
  // Scratch reused by every dab (no allocation once warmed up).
  std::vector<RegionVertex> region_;
  // The BVH leaves the region queries of one dab or grab met, each once over the mirrors
  // (marked in leaf_marks_); both empty between calls.
  std::vector<uint32_t> region_leaves_;
  Marks leaf_marks_;
  SideTask side_;
  std::vector<glm::vec3> targets_;
  std::vector<glm::vec3> mirrors_;
  NormalsChange normals_change_;
  std::vector<uint32_t> dirty_stamp_;
  uint32_t dirty_epoch_ = 1;
  std::vector<uint32_t> changed_, dirty_;
  std::vector<GrabEntry> grab_entries_;
  uint32_t last_dab_vertices_ = 0;
};
