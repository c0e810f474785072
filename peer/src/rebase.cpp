#include "rebase.h"

#include <algorithm>
#include <cstring>

#include "csculpt/error.h"

namespace csculpt::peer {
namespace {

/// Whether `width`-wide `local` equals `base` with `change` applied (bitwise), without making
/// that state: memcmp of the runs between changed vertices.
bool equals_with(const float* base, const float* local, std::size_t vertices, std::uint32_t width,
                 const AttributeDiff* change) {
  std::size_t v = 0;
  const std::size_t row = std::size_t{width} * sizeof(float);
  if (change) {
    for (std::size_t i = 0; i < change->indices.size(); ++i) {
      const std::size_t at = change->indices[i];
      if (std::memcmp(base + v * width, local + v * width, (at - v) * row) != 0) return false;
      if (std::memcmp(change->values.data() + i * width, local + at * width, row) != 0)
        return false;
      v = at + 1;
    }
  }
  return std::memcmp(base + v * width, local + v * width, (vertices - v) * row) == 0;
}

/// `base` + `theirs` + `mine` (both from `base`) merged, into `local`.
void merge_into(const Mesh& base, const Diff& theirs, const Diff& mine, Mesh& local, Merger& merger,
                const MergeFrame& frame) {
  const Diff* both[2] = {&theirs, &mine};
  Mesh out = base;
  apply_diff(merger.merge(base, both, MergeMethod::full, frame), out);
  local = std::move(out);
}

}  // namespace

bool same_layout(const Mesh& base, const Mesh& local) {
  if (local.vertex_count() != base.vertex_count() || local.channels.size() != base.channels.size())
    return false;
  for (std::size_t c = 0; c < base.channels.size(); ++c)
    if (local.channels[c].values.size() != base.channels[c].values.size()) return false;
  return true;
}

bool equals_base_plus(const Mesh& base, const Diff* d, const Mesh& local) {
  const std::size_t n = base.vertex_count();
  if (!equals_with(reinterpret_cast<const float*>(base.positions.data()),
                   reinterpret_cast<const float*>(local.positions.data()), n, 3,
                   d ? &d->positions : nullptr))
    return false;
  for (std::size_t c = 0; c < base.channels.size(); ++c)
    if (!equals_with(base.channels[c].values.data(), local.channels[c].values.data(), n,
                     base.channels[c].desc.width, d ? &d->channels[c].change : nullptr))
      return false;
  return true;
}

void restore(const Mesh& base, const Diff& d, Mesh& local) {
  for (std::uint32_t v : d.positions.indices) local.positions[v] = base.positions[v];
  for (std::size_t c = 0; c < d.channels.size(); ++c) {
    const std::uint32_t w = d.channels[c].desc.width;
    for (std::uint32_t v : d.channels[c].change.indices)
      std::copy_n(base.channels[c].values.data() + std::size_t{w} * v, w,
                  local.channels[c].values.data() + std::size_t{w} * v);
  }
}

bool rebase_onto_versions(Mesh& base, const Diff* ours, std::span<const Diff* const> merged,
                          Mesh& local, Merger& merger, const MergeFrame& frame, bool unedited,
                          const std::function<void(std::size_t, const Mesh&)>& before_each) {
  const bool empty = local.positions.empty();
  if (!empty && !same_layout(base, local))
    throw InvalidInput("update: the local mesh's vertices or channels differ from the session's");
  const bool edited = !empty && !unedited && !equals_base_plus(base, ours, local);
  // With edits since the submit: the state the submit described (the base if none of ours is
  // in), which both they and the versions are measured from.
  Mesh sent_state;
  if (edited) {
    sent_state = base;
    if (ours) apply_diff(*ours, sent_state);
  } else if (!empty && ours) {
    restore(base, *ours, local);  // local = base + ours follows the versions sparsely
  }
  for (std::size_t i = 0; i < merged.size(); ++i) {
    if (before_each) before_each(i, base);
    apply_diff(*merged[i], base);
    if (!edited && !empty) apply_diff(*merged[i], local);
  }
  if (empty) local = base;
  if (!edited) return false;
  // One merge for the whole run: a host catching up on hundreds of versions while it edits
  // does not merge hundreds of times.
  const Diff theirs = capture_diff(sent_state, base);
  const Diff mine = capture_diff(sent_state, local);
  merge_into(sent_state, theirs, mine, local, merger, frame);
  return true;
}

bool rebase_onto_snapshot(Mesh& base, const Mesh& snapshot, Mesh& local, Merger& merger,
                          const MergeFrame& frame) {
  bool rebased = false;
  if (!local.positions.empty()) {
    const Diff mine = capture_diff(base, local);
    const Diff theirs = capture_diff(base, snapshot);
    merge_into(base, theirs, mine, local, merger, frame);
    rebased = true;
  } else {
    local = snapshot;
  }
  base = snapshot;
  return rebased;
}

}  // namespace csculpt::peer
