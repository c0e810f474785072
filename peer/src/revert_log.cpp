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

void RevertLog::record(std::uint64_t version, const Diff& merged, const Mesh& base) {
  if (!entries_.empty() && entries_.back().first + 1 != version) clear();
  Diff old = overwritten_by(merged, base);
  bytes_ += bytes_of(old);
  entries_.emplace_back(version, std::move(old));
  while (entries_.size() > 1 && bytes_ > max_bytes_) {
    bytes_ -= bytes_of(entries_.front().second);
    entries_.pop_front();
  }
}

std::uint64_t RevertLog::revert(Mesh& mesh, std::uint64_t version, std::uint64_t target) const {
  if (entries_.empty() || entries_.back().first != version) return version;
  std::uint64_t reached = version;
  for (auto it = entries_.rbegin(); it != entries_.rend() && reached > target; ++it) {
    apply_diff(it->second, mesh);
    reached = it->first - 1;
  }
  return reached;
}

void RevertLog::clear() {
  entries_.clear();
  bytes_ = 0;
}

}  // namespace csculpt::peer
