#include "sculptor.h"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>

namespace {

// Per-dab displacement as a fraction of the brush radius at full strength and weight: small
// enough that a stroke of overlapping dabs builds up smoothly.
constexpr float kDrawDepth = 0.1f;
constexpr float kPinchRate = 0.3f;
constexpr float kTwistRadians = 0.3f;

glm::vec3 rotate_about(glm::vec3 v, glm::vec3 axis, float angle) {  // Rodrigues' formula
  const float c = std::cos(angle), s = std::sin(angle);
  return v * c + glm::cross(axis, v) * s + axis * glm::dot(axis, v) * (1.f - c);
}

}  // namespace

void Sculptor::reset() {
  const size_t vertices = document_.vertex_count();
  dirty_stamp_.assign(vertices, 0);
  normals_change_.resize(static_cast<uint32_t>(vertices), document_.triangle_count());
  leaf_marks_.resize(bvh_.node_count());
  dirty_epoch_ = 1;
  dirty_.clear();
  grab_entries_.clear();
}

uint32_t Sculptor::next_stamp(std::vector<uint32_t>& stamps, uint32_t& epoch) {
  if (++epoch == 0) {
    std::fill(stamps.begin(), stamps.end(), 0);
    epoch = 1;
  }
  return epoch;
}

glm::vec3 Sculptor::position(uint32_t v) const {
  const float* p = &document_.positions[3 * size_t{v}];
  return {p[0], p[1], p[2]};
}

void Sculptor::set_position(uint32_t v, glm::vec3 p) {
  float* out = &document_.positions[3 * size_t{v}];
  out[0] = p.x, out[1] = p.y, out[2] = p.z;
}

std::span<const glm::vec3> Sculptor::mirrors(const BrushSettings& settings) {
  mirrors_.assign(1, glm::vec3(1.f));
  for (int axis = 0; axis < 3; ++axis) {
    if (!settings.symmetry[axis]) continue;
    const size_t count = mirrors_.size();
    for (size_t i = 0; i < count; ++i) {
      glm::vec3 m = mirrors_[i];
      m[axis] = -1.f;
      mirrors_.push_back(m);
    }
  }
  return mirrors_;
}

void Sculptor::gather_region(glm::vec3 center, float radius, glm::vec3 view_direction,
                             bool front_only, Falloff falloff) {
  region_.clear();
  // The leaves are met with a hair more than the radius: a vertex accepted at exactly the
  // radius (its distance rounded differently from the box's) still has all its leaves listed.
  bvh_.for_each_leaf_near(center, radius * 1.0001f, [&](uint32_t leaf) {
    if (leaf_marks_.mark(leaf)) region_leaves_.push_back(leaf);
    for (uint32_t v : bvh_.owned_vertices(leaf)) {
      const float distance = glm::length(position(v) - center);
      if (distance > radius) continue;
      const float* n = &document_.normals[3 * size_t{v}];
      if (front_only && glm::dot(glm::vec3(n[0], n[1], n[2]), view_direction) > 0.f) continue;
      const float weight = falloff_weight(falloff, distance / radius);
      if (weight > 0.f) region_.push_back({v, weight});
    }
  });
  // The order is the tree's (leaves left to right, each one's vertices as built), whichever
  // leaves the refitted boxes let the query visit: every sum and undo record is the same
  // for the same mesh, without sorting.
}

void Sculptor::dab(const DabInput& input, const BrushSettings& settings) {
  changed_.clear();
  last_dab_vertices_ = 0;
  for (const glm::vec3& m : mirrors(settings)) {
    const float parity = m.x * m.y * m.z;  // a reflection turns a twist the other way
    DabInput mirrored = input;
    mirrored.view_direction = input.view_direction * m;
    gather_region(input.center * m, input.radius, mirrored.view_direction,
                  settings.front_faces_only, settings.falloff);
    apply(mirrored, settings, input.center * m, parity);
    last_dab_vertices_ += static_cast<uint32_t>(region_.size());
  }
  if (input.kind == BrushKind::paint)
    refresh_normals(changed_, false);
  else
    refresh_region();
  forget_region_leaves();
}

void Sculptor::refresh_region() {
  // Every triangle around a moved vertex is held by a leaf the region's query visited, each
  // by one: their list needs no search around the moved vertices and no repeats removed.
  normals_change_.triangles.clear();
  for (uint32_t leaf : region_leaves_)
    for (uint32_t t : bvh_.leaf_triangles(leaf)) normals_change_.triangles.push_back(t);
  // The helper lists the triangles' corners while this thread recomputes their face normals
  // and refits the leaves (the positions are in this core's cache): disjoint data.
  side_.start([this] { normals_change_.collect_corners(document_.triangles); });
  document_.recompute_face_normals(normals_change_.triangles);
  bvh_.refit_leaves(document_.positions, document_.triangles, region_leaves_);
  side_.wait();
  update_vertex_normals();
}

void Sculptor::forget_region_leaves() {
  leaf_marks_.clear(region_leaves_);
  region_leaves_.clear();
}

void Sculptor::apply(const DabInput& input, const BrushSettings& settings, glm::vec3 center,
                     float parity) {
  if (region_.empty()) return;
  for (const RegionVertex& r : region_) {
    history_.touch(document_, r.vertex);
    changed_.push_back(r.vertex);
  }
  const float sign = input.invert ? -1.f : 1.f;
  const float s = input.strength;
  if (input.kind == BrushKind::paint) {
    auto paint = [&](int channel_index, const float* target, uint32_t width) {
      if (channel_index < 0) return;
      MeshChannel& channel = document_.channels[channel_index];
      for (const RegionVertex& r : region_) {
        const float t = std::min(1.f, s * r.weight);
        float* value = &channel.values[size_t{r.vertex} * width];
        for (uint32_t c = 0; c < width; ++c)
          value[c] = std::clamp(value[c] + (target[c] - value[c]) * t, channel.min_value,
                                channel.max_value);
      }
    };
    // Invert paints the complement (1 - colour, 1 - value): a quick way back to light/rough.
    auto pick = [&](float v) { return input.invert ? 1.f - v : v; };
    switch (settings.paint_channel) {
      case PaintChannel::albedo: {
        const float colour[3] = {pick(settings.colour.r), pick(settings.colour.g),
                                 pick(settings.colour.b)};
        paint(document_.albedo, colour, 3);
        break;
      }
      case PaintChannel::roughness: {
        const float value = pick(settings.roughness);
        paint(document_.roughness, &value, 1);
        break;
      }
      case PaintChannel::metallic: {
        const float value = pick(settings.metallic);
        paint(document_.metallic, &value, 1);
        break;
      }
    }
    return;
  }
  // The region's weighted normal and centre: the plane that draw, flatten and crease work to.
  glm::vec3 area_normal(0.f), area_center(0.f);
  float total = 0.f;
  for (const RegionVertex& r : region_) {
    const float* n = &document_.normals[3 * size_t{r.vertex}];
    area_normal += glm::vec3(n[0], n[1], n[2]) * r.weight;
    area_center += position(r.vertex) * r.weight;
    total += r.weight;
  }
  if (glm::length(area_normal) > 0.f) area_normal = glm::normalize(area_normal);
  area_center /= total;
  const float depth = kDrawDepth * input.radius * s;

  if (input.kind == BrushKind::smooth) {  // Laplacian step towards the mean of the neighbours
    targets_.resize(region_.size());
    for (size_t i = 0; i < region_.size(); ++i) {
      const uint32_t v = region_[i].vertex;
      glm::vec3 mean(0.f);
      const uint32_t begin = document_.neighbour_offsets[v],
                     end = document_.neighbour_offsets[v + 1];
      for (uint32_t k = begin; k < end; ++k) mean += position(document_.neighbours[k]);
      targets_[i] = end > begin ? mean / float(end - begin) : position(v);
    }
    for (size_t i = 0; i < region_.size(); ++i) {
      const glm::vec3 p = position(region_[i].vertex);
      set_position(region_[i].vertex, p + (targets_[i] - p) * std::min(1.f, s * region_[i].weight));
    }
    return;
  }
  for (const RegionVertex& r : region_) {
    glm::vec3 p = position(r.vertex);
    const float w = r.weight;
    auto toward_centre = [&](float rate) {  // along the surface, towards the dab's centre
      glm::vec3 t = center - p;
      t -= area_normal * glm::dot(t, area_normal);
      return t * std::min(1.f, rate * s * w);
    };
    switch (input.kind) {
      case BrushKind::draw:
        p += area_normal * (sign * depth * w);
        break;
      case BrushKind::inflate: {
        const float* n = &document_.normals[3 * size_t{r.vertex}];
        p += glm::vec3(n[0], n[1], n[2]) * (sign * depth * w);
        break;
      }
      case BrushKind::flatten:  // invert pushes away from the plane (contrast)
        p -= area_normal * (glm::dot(p - area_center, area_normal) * sign * std::min(1.f, s * w));
        break;
      case BrushKind::crease:  // a sharp groove (or ridge when inverted) that pinches its walls in
        p += -area_normal * (sign * depth * w * w) + toward_centre(0.5f * kPinchRate);
        break;
      case BrushKind::pinch:
        p += toward_centre(kPinchRate) * sign;
        break;
      case BrushKind::twist:
        p = center + rotate_about(p - center, area_normal, sign * parity * kTwistRadians * s * w);
        break;
      default:
        break;
    }
    set_position(r.vertex, p);
  }
}

void Sculptor::grab_begin(const DabInput& input, const BrushSettings& settings) {
  grab_entries_.clear();
  for (const glm::vec3& m : mirrors(settings)) {
    gather_region(input.center * m, input.radius, input.view_direction * m,
                  settings.front_faces_only, settings.falloff);
    for (const RegionVertex& r : region_) {
      history_.touch(document_, r.vertex);
      grab_entries_.push_back(
          {r.vertex, r.weight * std::min(1.f, 2.f * input.strength), m, position(r.vertex)});
    }
  }
  forget_region_leaves();  // a grab's moves grow boxes by vertex (they have no query)
}

void Sculptor::grab_move(glm::vec3 delta) {
  changed_.clear();
  // Reset, then add every mirror's share: where two mirrored regions overlap they add up.
  for (const GrabEntry& e : grab_entries_) set_position(e.vertex, e.original);
  for (const GrabEntry& e : grab_entries_) {
    set_position(e.vertex, position(e.vertex) + delta * e.mirror * e.weight);
    changed_.push_back(e.vertex);
  }
  last_dab_vertices_ = static_cast<uint32_t>(grab_entries_.size());
  refresh(changed_, true);
}

// Outside a stroke the boxes around what moved are refitted exactly at once: growing them
// first, as a grab's move does, would be a pass tighten() then redoes.
void Sculptor::refresh_after_change(std::span<const uint32_t> vertices, bool positions_changed) {
  if (!positions_changed) {
    refresh_normals(vertices, false);
    bvh_.tighten(document_.positions, document_.triangles);
    return;
  }
  // A merged version moves tens of thousands of vertices: the boxes are refitted on the
  // helper while this thread recomputes the normals (disjoint data).
  side_.start(
      [this, vertices] { bvh_.refit_exactly(document_.positions, document_.triangles, vertices); });
  refresh_normals(vertices, true);
  side_.wait();
}

void Sculptor::adopt_version(std::span<const uint32_t> vertices, const ChangedNormals& normals,
                             std::span<const uint32_t> bvh_nodes,
                             std::span<const BvhBox> bvh_boxes) {
  if (normals.moved.empty()) {
    refresh_after_change(vertices, false);
    return;
  }
  if (bvh_nodes.empty())
    bvh_.refit_exactly(document_.positions, document_.triangles, normals.moved);
  else
    bvh_.set_boxes(bvh_nodes, bvh_boxes);
  document_.set_normals(normals.triangles, normals.face_normals, normals.vertices, normals.normals);
  for (uint32_t v : normals.vertices) mark_dirty(v);
  for (uint32_t v : vertices) mark_dirty(v);  // channels may have changed where none moved
}

void Sculptor::refresh(std::span<const uint32_t> vertices, bool positions_changed) {
  refresh_normals(vertices, positions_changed);
  if (positions_changed) bvh_.refit(document_.positions, vertices);
}

void Sculptor::mark_dirty(uint32_t v) {
  if (dirty_stamp_[v] == dirty_epoch_) return;
  dirty_stamp_[v] = dirty_epoch_;
  dirty_.push_back(v);
}

void Sculptor::refresh_normals(std::span<const uint32_t> vertices, bool positions_changed) {
  if (!positions_changed) {
    for (uint32_t v : vertices) mark_dirty(v);
    return;
  }
  // A moved vertex changes the normals of every corner of its triangles.
  normals_change_.collect(document_.triangles, document_.around, vertices);
  update_changed_normals();
}

void Sculptor::update_changed_normals() {
  document_.recompute_face_normals(normals_change_.triangles);
  update_vertex_normals();
}

void Sculptor::update_vertex_normals() {
  document_.recompute_normals(normals_change_.vertices);
  for (uint32_t v : normals_change_.vertices) mark_dirty(v);
}

void Sculptor::clear_dirty() {
  dirty_.clear();
  next_stamp(dirty_stamp_, dirty_epoch_);
}
