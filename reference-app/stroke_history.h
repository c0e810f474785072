// Local undo/redo of the artist's own strokes: each stroke keeps the values (position and
// every channel) of the vertices it touched, before and after, so undo and redo restore them
// bit for bit. Solo only: in a session the agreed mesh moves under the stroke, so there the
// app hands each ended stroke (last_vertices, last_before) to the session's own undo
// (csc_session_record_stroke), which merges the removal with everyone's later work.
#pragma once

#include <cstdint>
#include <deque>
#include <vector>

#include "mesh_document.h"

class StrokeHistory {
 public:
  void reset(const MeshDocument& document);
  /** Drops the kept strokes (nothing to undo or redo); a stroke being drawn stays open. */
  void forget_strokes() {
    strokes_.clear();
    undo_count_ = 0;
  }
  void begin_stroke();
  /** Records `vertex`'s values before the stroke first changes it (call before changing). */
  void touch(const MeshDocument& document, uint32_t vertex);
  void end_stroke(const MeshDocument& document);
  bool stroke_open() const { return open_; }

  bool can_undo() const { return undo_count_ > 0; }
  bool can_redo() const { return undo_count_ < strokes_.size(); }
  /** Writes the stroke's before (undo) or after (redo) values; `changed` gets its vertices. */
  bool undo(MeshDocument& document, std::vector<uint32_t>& changed);
  bool redo(MeshDocument& document, std::vector<uint32_t>& changed);
  size_t undo_depth() const { return undo_count_; }
  /** The stroke end_stroke() last kept: its vertices and their values before it. */
  const std::vector<uint32_t>& last_vertices() const { return strokes_.back().vertices; }
  const std::vector<float>& last_before() const { return strokes_.back().before; }
  const std::vector<float>& last_after() const { return strokes_.back().after; }
  bool has_last() const { return !strokes_.empty() && undo_count_ == strokes_.size(); }

 private:
  struct Stroke {
    std::vector<uint32_t> vertices;
    std::vector<float> before, after;  // stride_ floats per vertex
  };
  static constexpr size_t kMaxStrokes = 100;
  std::deque<Stroke> strokes_;
  size_t undo_count_ = 0;  // strokes_[0 .. undo_count_) are done; the rest can be redone
  Stroke current_;
  std::vector<uint32_t> stamp_;  // stroke number that last recorded each vertex
  uint32_t stroke_number_ = 0;
  uint32_t stride_ = 0;
  bool open_ = false;
};
