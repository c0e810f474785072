#include "markers.h"

#include <algorithm>

#include "csculpt/error.h"

namespace csculpt::cli {
namespace {

constexpr const char* kChannel = "marker";

int marker_channel(const Mesh& mesh) {
  return mesh.find_channel(kChannel);
}

}  // namespace

void add_marker_channel(Mesh& mesh) {
  if (marker_channel(mesh) < 0) mesh.add_channel({kChannel, 1, Linearisation::identity, 0.f, 1.f});
}

MarkerPainter::MarkerPainter(std::uint32_t slot, std::uint32_t first, std::uint32_t limit,
                             const Mesh& mesh)
    : slot_(slot % kMarkerSlots), first_(first), limit_(limit) {
  if (marker_channel(mesh) < 0)
    throw InvalidInput(
        "--markers: the session's mesh has no marker channel (its creator must "
        "run with --markers too)");
}

bool MarkerPainter::marked(const Mesh& mesh, std::uint32_t vertex) {
  const int c = marker_channel(mesh);
  return c >= 0 && vertex < mesh.vertex_count() && mesh.channels[c].values[vertex] > 0.5f;
}

std::int64_t MarkerPainter::paint(Mesh& local) {
  const std::uint64_t v =
      std::uint64_t{slot_} + std::uint64_t{kMarkerSlots} * (first_ + made_.size());
  if (made_.size() >= limit_ || v >= local.vertex_count()) return -1;
  local.channels[marker_channel(local)].values[v] = 1.f;
  made_.push_back(static_cast<std::uint32_t>(v));
  waiting_.push_back(static_cast<std::uint32_t>(v));
  return static_cast<std::int64_t>(v);
}

std::vector<std::uint32_t> MarkerPainter::newly_acknowledged(const Mesh& base) {
  std::vector<std::uint32_t> now;
  std::erase_if(waiting_, [&](std::uint32_t v) {
    if (!marked(base, v)) return false;
    now.push_back(v);
    return true;
  });
  acknowledged_.insert(acknowledged_.end(), now.begin(), now.end());
  return now;
}

std::vector<std::uint32_t> MarkerPainter::lost(const Mesh& base) const {
  std::vector<std::uint32_t> out;
  for (std::uint32_t v : acknowledged_)
    if (!marked(base, v)) out.push_back(v);
  return out;
}

std::size_t MarkerPainter::held(const Mesh& base) const {
  return static_cast<std::size_t>(std::count_if(acknowledged_.begin(), acknowledged_.end(),
                                                [&](std::uint32_t v) { return marked(base, v); }));
}

std::vector<std::uint32_t> MarkerPainter::present(const Mesh& base) {
  std::vector<std::uint32_t> out;
  const int c = marker_channel(base);
  if (c < 0) return out;
  for (std::uint32_t v = 0; v < base.vertex_count(); ++v)
    if (base.channels[c].values[v] > 0.5f) out.push_back(v);
  return out;
}

}  // namespace csculpt::cli
