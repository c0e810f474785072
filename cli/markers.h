// Marker edits: the loss check of the session tests. Each marker sets one vertex of a
// dedicated "marker" channel to 1, a vertex no other peer marks (peer p owns the vertices
// v ≡ p mod kMarkerSlots), so a marker's presence in the agreed mesh can be read off the values
// themselves: counters and digests alone cannot show a lost edit.
#pragma once

#include <cstdint>
#include <vector>

#include "csculpt/mesh.h"

namespace csculpt::cli {

/// Peers whose ids differ modulo this mark disjoint vertices.
constexpr std::uint32_t kMarkerSlots = 16;

/// Adds the (zeroed) marker channel to a session's first mesh.
void add_marker_channel(Mesh& mesh);

class MarkerPainter {
 public:
  /// Marks the vertices `slot` + kMarkerSlots * k for k = first, first + 1, ... (a restarted
  /// peer takes another `first` or `slot`, so that its markers are new ones). Throws
  /// InvalidInput when `mesh` has no marker channel (the session was not made with one).
  MarkerPainter(std::uint32_t slot, std::uint32_t first, std::uint32_t limit, const Mesh& mesh);

  /// Marks the next vertex of ours in `local`; the vertex, or -1 once `limit` are made or the
  /// mesh has no more.
  std::int64_t paint(Mesh& local);
  /// Markers made that `base` (an agreed version) now holds for the first time: acknowledged.
  std::vector<std::uint32_t> newly_acknowledged(const Mesh& base);
  /// Acknowledged markers `base` does not hold: lost.
  std::vector<std::uint32_t> lost(const Mesh& base) const;
  /// How many acknowledged markers `base` holds (the rest are lost, or carried until merged
  /// again); no allocation, for a check every frame.
  std::size_t held(const Mesh& base) const;
  /// Every vertex (anyone's) marked in `base`.
  static std::vector<std::uint32_t> present(const Mesh& base);

  std::size_t made() const { return made_.size(); }
  std::size_t acknowledged() const { return acknowledged_.size(); }

 private:
  static bool marked(const Mesh& mesh, std::uint32_t vertex);

  std::uint32_t slot_, first_, limit_;
  std::vector<std::uint32_t> made_;          // in order
  std::vector<std::uint32_t> acknowledged_;  // seen in an agreed version
  std::vector<std::uint32_t> waiting_;       // made, not yet seen
};

}  // namespace csculpt::cli
