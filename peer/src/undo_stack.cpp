#include "undo_stack.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "csculpt/diff.h"
#include "csculpt/error.h"

namespace csculpt::peer {
namespace {

/// Floats per vertex over the position and every channel.
std::size_t stride_of(const Mesh& mesh) {
  std::size_t stride = 3;
  for (const Channel& c : mesh.channels) stride += c.desc.width;
  return stride;
}

void read_vertex(const Mesh& mesh, std::uint32_t v, float* out) {
  const Vec3f& p = mesh.positions[v];
  *out++ = p.x, *out++ = p.y, *out++ = p.z;
  for (const Channel& c : mesh.channels)
    out = std::copy_n(c.values.data() + std::size_t{c.desc.width} * v, c.desc.width, out);
}

void write_vertex(Mesh& mesh, std::uint32_t v, const float* in) {
  mesh.positions[v] = {in[0], in[1], in[2]};
  in += 3;
  for (Channel& c : mesh.channels) {
    std::copy_n(in, c.desc.width, c.values.data() + std::size_t{c.desc.width} * v);
    in += c.desc.width;
  }
}

/// The stroke's vertices and every vertex sharing a face with one, increasing.
std::vector<std::uint32_t> one_ring(const Topology& topology,
                                    std::span<const std::uint32_t> vertices) {
  std::vector<std::uint32_t> ring(vertices.begin(), vertices.end());
  for (std::uint32_t v : vertices)
    for (std::uint32_t f : topology.vertex_faces.row(v))
      for (std::uint32_t u : topology.triangles[f]) ring.push_back(u);
  std::sort(ring.begin(), ring.end());
  ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
  return ring;
}

void check_size(std::size_t values, std::size_t vertices, std::size_t stride) {
  if (values != vertices * stride)
    throw InvalidInput("record_stroke: `before` holds " + std::to_string(values) + " values; " +
                       std::to_string(vertices) + " vertices need " +
                       std::to_string(vertices * stride) + " (" + std::to_string(stride) +
                       " per vertex: the position, then every channel)");
}

void check_stroke(const Mesh& local, std::span<const std::uint32_t> sorted,
                  std::span<const float> before, std::size_t stride) {
  if (!sorted.empty() && sorted.back() >= local.vertex_count())
    throw InvalidInput("record_stroke: vertex " + std::to_string(sorted.back()) +
                       " is out of range (the mesh has " + std::to_string(local.vertex_count()) +
                       " vertices)");
  const auto repeated = std::adjacent_find(sorted.begin(), sorted.end());
  if (repeated != sorted.end())
    throw InvalidInput("record_stroke: vertex " + std::to_string(*repeated) + " is listed twice");
  for (std::size_t i = 0; i < before.size(); ++i)
    if (!std::isfinite(before[i]))
      throw InvalidInput("record_stroke: the value before the stroke of vertex " +
                         std::to_string(sorted[i / stride]) + " is not finite");
}

}  // namespace

std::size_t UndoStack::Record::bytes() const {
  return (vertices.size() + in_ring.size() + ring.size() + before.size() + after.size()) * 4;
}

void UndoStack::set_tolerance(float position_tolerance, float channel_tolerance) {
  position_tolerance_ = position_tolerance;
  channel_tolerance_ = channel_tolerance;
}

void UndoStack::clear() {
  records_.clear();
  done_ = 0;
  bytes_ = 0;
}

void UndoStack::record(const Mesh& local, const Topology& topology,
                       std::span<const std::uint32_t> vertices, std::span<const float> before) {
  const std::size_t stride = stride_of(local);
  check_size(before.size(), vertices.size(), stride);
  // Sorted with their before-values, so that the record is independent of the host's order.
  std::vector<std::uint32_t> order(vertices.size());
  for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(),
            [&](std::uint32_t a, std::uint32_t b) { return vertices[a] < vertices[b]; });
  Record r;
  r.vertices.reserve(order.size());
  r.before.reserve(before.size());
  for (std::uint32_t i : order) {
    r.vertices.push_back(vertices[i]);
    r.before.insert(r.before.end(), before.begin() + i * stride, before.begin() + (i + 1) * stride);
  }
  check_stroke(local, r.vertices, r.before, stride);
  if (r.vertices.empty()) return;
  r.ring = one_ring(topology, r.vertices);
  r.after.resize(r.ring.size() * stride);
  for (std::size_t k = 0; k < r.ring.size(); ++k)
    read_vertex(local, r.ring[k], &r.after[k * stride]);
  for (std::size_t i = 0; i < r.after.size(); ++i)
    if (!std::isfinite(r.after[i]))
      throw InvalidInput("record_stroke: the value of vertex " +
                         std::to_string(r.ring[i / stride]) + " is not finite");
  r.in_ring.reserve(r.vertices.size());
  for (std::uint32_t v : r.vertices)
    r.in_ring.push_back(static_cast<std::uint32_t>(
        std::lower_bound(r.ring.begin(), r.ring.end(), v) - r.ring.begin()));

  while (records_.size() > done_) {  // a new stroke drops what could have been redone
    bytes_ -= records_.back().bytes();
    records_.pop_back();
  }
  bytes_ += r.bytes();
  records_.push_back(std::move(r));
  done_ = records_.size();
  trim();
}

void UndoStack::trim() {
  while (records_.size() > 1 && (records_.size() > kMaxStrokes || bytes_ > kMaxBytes)) {
    bytes_ -= records_.front().bytes();
    records_.pop_front();
    --done_;
  }
}

std::vector<float> UndoStack::start_state(const Record& r, bool undoing, std::size_t stride) {
  std::vector<float> start = r.after;
  if (!undoing)
    for (std::size_t i = 0; i < r.vertices.size(); ++i)
      std::copy_n(&r.before[i * stride], stride, &start[r.in_ring[i] * stride]);
  return start;
}

bool UndoStack::unchanged_since(const Record& r, std::span<const float> start,
                                const Mesh& local) const {
  const std::size_t stride = stride_of(local);
  std::vector<float> now(stride);
  for (std::size_t k = 0; k < r.ring.size(); ++k) {
    read_vertex(local, r.ring[k], now.data());
    for (std::size_t i = 0; i < stride; ++i) {
      const float tolerance = i < 3 ? position_tolerance_ : channel_tolerance_;
      if (!(std::fabs(now[i] - start[k * stride + i]) <= tolerance)) return false;
    }
  }
  return true;
}

void UndoStack::step(const Record& r, bool undoing, Mesh& local, Merger& merger,
                     const MergeFrame& frame, std::vector<std::uint32_t>& changed) const {
  const std::size_t stride = stride_of(local);
  if (local.vertex_count() <= r.ring.back() || stride * r.ring.size() != r.after.size())
    throw InvalidInput("undo: the mesh's vertices or channels differ from the recorded stroke's");
  const std::vector<float> start = start_state(r, undoing, stride);
  auto target = [&](std::size_t i) {
    return undoing ? &r.before[i * stride] : &r.after[r.in_ring[i] * stride];
  };
  changed.clear();
  if (unchanged_since(r, start, local)) {  // nobody touched the surroundings: exact values
    for (std::size_t i = 0; i < r.vertices.size(); ++i)
      write_vertex(local, r.vertices[i], target(i));
    changed = r.vertices;
    return;
  }
  Mesh from = local;  // the surroundings as they stood, the rest as it is now
  for (std::size_t k = 0; k < r.ring.size(); ++k) write_vertex(from, r.ring[k], &start[k * stride]);
  Mesh mine = from;
  for (std::size_t i = 0; i < r.vertices.size(); ++i) write_vertex(mine, r.vertices[i], target(i));
  const Diff theirs = capture_diff(from, local);
  const Diff step = capture_diff(from, mine);
  const Diff* both[2] = {&theirs, &step};
  Mesh out = from;
  // The stroke's removal and everyone's later work are different intents even where they
  // happen to move a vertex alike (a colleague's inflate over my draw, redone): both add.
  apply_diff(merger.merge(from, both, MergeMethod::full, frame, SameChange::add), out);
  const Diff moved = capture_diff(local, out);
  for (std::uint32_t v : moved.positions.indices) changed.push_back(v);
  for (const ChannelDiff& c : moved.channels)
    changed.insert(changed.end(), c.change.indices.begin(), c.change.indices.end());
  std::sort(changed.begin(), changed.end());
  changed.erase(std::unique(changed.begin(), changed.end()), changed.end());
  std::vector<float> values(stride);
  for (std::uint32_t v : changed) {
    read_vertex(out, v, values.data());
    write_vertex(local, v, values.data());
  }
}

bool UndoStack::undo(Mesh& local, Merger& merger, const MergeFrame& frame,
                     std::vector<std::uint32_t>& changed) {
  if (done_ == 0) return false;
  step(records_[done_ - 1], true, local, merger, frame, changed);
  --done_;
  return true;
}

bool UndoStack::redo(Mesh& local, Merger& merger, const MergeFrame& frame,
                     std::vector<std::uint32_t>& changed) {
  if (done_ == records_.size()) return false;
  step(records_[done_], false, local, merger, frame, changed);
  ++done_;
  return true;
}

}  // namespace csculpt::peer
