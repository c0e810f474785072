#include "stroke_history.h"

#include <algorithm>

void StrokeHistory::reset(const MeshDocument& document) {
  strokes_.clear();
  undo_count_ = 0;
  current_ = {};
  stamp_.assign(document.vertex_count(), 0);
  stroke_number_ = 0;
  stride_ = document.values_per_vertex();
  open_ = false;
}

void StrokeHistory::begin_stroke() {
  current_.vertices.clear();
  current_.before.clear();
  current_.after.clear();
  if (++stroke_number_ == 0) {  // wrapped: forget the old stamps
    std::fill(stamp_.begin(), stamp_.end(), 0);
    stroke_number_ = 1;
  }
  open_ = true;
}

void StrokeHistory::touch(const MeshDocument& document, uint32_t vertex) {
  if (!open_ || stamp_[vertex] == stroke_number_) return;
  stamp_[vertex] = stroke_number_;
  current_.vertices.push_back(vertex);
  const size_t at = current_.before.size();
  current_.before.resize(at + stride_);
  document.copy_vertex_values(vertex, &current_.before[at]);
}

void StrokeHistory::end_stroke(const MeshDocument& document) {
  if (!open_) return;
  open_ = false;
  if (current_.vertices.empty()) return;
  current_.after.resize(current_.before.size());
  for (size_t i = 0; i < current_.vertices.size(); ++i)
    document.copy_vertex_values(current_.vertices[i], &current_.after[i * stride_]);
  strokes_.resize(undo_count_);  // a new stroke drops what could have been redone
  strokes_.push_back(std::move(current_));
  current_ = {};
  if (strokes_.size() > kMaxStrokes) strokes_.pop_front();
  undo_count_ = strokes_.size();
}

bool StrokeHistory::undo(MeshDocument& document, std::vector<uint32_t>& changed) {
  if (open_ || !can_undo()) return false;
  const Stroke& stroke = strokes_[--undo_count_];
  for (size_t i = 0; i < stroke.vertices.size(); ++i)
    document.set_vertex_values(stroke.vertices[i], &stroke.before[i * stride_]);
  changed = stroke.vertices;
  return true;
}

bool StrokeHistory::redo(MeshDocument& document, std::vector<uint32_t>& changed) {
  if (open_ || !can_redo()) return false;
  const Stroke& stroke = strokes_[undo_count_++];
  for (size_t i = 0; i < stroke.vertices.size(); ++i)
    document.set_vertex_values(stroke.vertices[i], &stroke.after[i * stride_]);
  changed = stroke.vertices;
  return true;
}
