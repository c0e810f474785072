#include "revert_log.h"

namespace csculpt::peer {
namespace {

/// `d` with `mesh`'s values in place of its own: applied after `d`, it undoes `d`.
Diff overwritten_by(const Diff& d, const Mesh& mesh) {
  Diff old = d;
  for (std::size_t i = 0; i < old.positions.indices.size(); ++i) {
    const Vec3f& p = mesh.positions[old.positions.indices[i]];
    old.positions.values[3 * i] = p.x;
    old.positions.values[3 * i + 1] = p.y;
    old.positions.values[3 * i + 2] = p.z;
  }
  for (std::size_t c = 0; c < old.channels.size(); ++c) {
    AttributeDiff& change = old.channels[c].change;
    const Channel& values = mesh.channels[c];  // a diff has the base's channels, in order
    const std::uint32_t w = values.desc.width;
    for (std::size_t i = 0; i < change.indices.size(); ++i)
      for (std::uint32_t k = 0; k < w; ++k)
        change.values[i * w + k] = values.values[std::size_t{change.indices[i]} * w + k];
  }
  return old;
}

std::size_t bytes_of(const Diff& d) {
  std::size_t n = d.positions.indices.size() * 4 + d.positions.values.size() * 4;
  for (const ChannelDiff& c : d.channels)
    n += c.change.indices.size() * 4 + c.change.values.size() * 4;
  return n + sizeof(Diff);
}

}  // namespace

void RevertLog::push(Entry e) {
  bytes_ += bytes_of(e.old);
  entries_.push_back(std::move(e));
  while (entries_.size() > 1 && bytes_ > max_bytes_) {
    bytes_ -= bytes_of(entries_.front().old);
    entries_.pop_front();
  }
}

void RevertLog::record(std::uint64_t version, const Diff& merged, const Mesh& base) {
  if (!entries_.empty() && entries_.back().version + 1 != version) clear();
  push({version, version - 1, overwritten_by(merged, base)});
}

void RevertLog::jumped(std::uint64_t from_version, const Mesh& from, std::uint64_t version,
                       const Mesh& to) {
  while (!entries_.empty() && entries_.back().version > from_version) {
    bytes_ -= bytes_of(entries_.back().old);
    entries_.pop_back();
  }
  // Entries that do not end at `from` (the log was cleared since) describe another state.
  if (!entries_.empty() && entries_.back().version != from_version) clear();
  push({version, from_version, overwritten_by(capture_diff(from, to), from)});
}

std::uint64_t RevertLog::revert(Mesh& mesh, std::uint64_t version, std::uint64_t target) const {
  if (entries_.empty() || entries_.back().version != version) return version;
  std::uint64_t reached = version;
  for (auto it = entries_.rbegin(); it != entries_.rend() && reached > target; ++it) {
    apply_diff(it->old, mesh);
    reached = it->previous;
  }
  return reached;
}

void RevertLog::clear() {
  entries_.clear();
  bytes_ = 0;
}

}  // namespace csculpt::peer
