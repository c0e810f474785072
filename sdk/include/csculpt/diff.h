// Sparse per-vertex differences between a base mesh and an edited state of the same
// connectivity (paper §3: ΔM = {Δv^i}, i in E).
#pragma once

#include <algorithm>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "csculpt/mesh.h"

namespace csculpt {

/// The changed vertices of one attribute. `values` holds the edited values themselves
/// (width per vertex), not deltas, so that applying a diff reproduces the edit bit for bit;
/// the delta is value - base.
struct AttributeDiff {
  std::vector<std::uint32_t> indices;  ///< strictly increasing
  std::vector<float> values;           ///< indices.size() * width
  std::size_t size() const { return indices.size(); }
  bool empty() const { return indices.empty(); }
  friend bool operator==(const AttributeDiff&, const AttributeDiff&) = default;
};

struct ChannelDiff {
  ChannelDesc desc;
  AttributeDiff change;
  friend bool operator==(const ChannelDiff&, const ChannelDiff&) = default;
};

struct Diff {
  std::uint32_t vertex_count = 0;
  AttributeDiff positions;            ///< width 3
  std::vector<ChannelDiff> channels;  ///< one per channel of the base, in the base's order
  /// Vertices changed in any attribute.
  std::size_t touched_vertices() const;
  /// No vertex changed in any attribute.
  bool empty() const {
    return positions.empty() && std::all_of(channels.begin(), channels.end(),
                                            [](const ChannelDiff& c) { return c.change.empty(); });
  }
  friend bool operator==(const Diff&, const Diff&) = default;
};

/// Makes `d` the diff of no change on `base`: its vertex count, no positions, and one empty entry
/// per channel of `base` in its order (the layout captures, decodes and merges give), reusing
/// `d`'s buffers.
void clear_to_layout(Diff& d, const Mesh& base);

/// Every vertex whose position or channel value differs (bitwise) from the base.
/// Throws InvalidInput if the connectivity or channel layout differs.
Diff capture_diff(const Mesh& base, const Mesh& edited);

/// capture_diff over `vertices` only (strictly increasing): the same diff when every vertex that
/// differs is listed, at the cost of the listed vertices (connectivity is not compared). Writes
/// into `out`, reusing its buffers. Throws InvalidInput if the vertex counts or channels differ,
/// or an index is out of range or not increasing.
void capture_diff_at(const Mesh& base, const Mesh& edited, std::span<const std::uint32_t> vertices,
                     Diff& out);

/// Capture from raw arrays (what a host holds): positions as xyz floats. Throws InvalidInput
/// unless both arrays hold the same number of whole vertices of `width` (> 0) values.
AttributeDiff capture_attribute(std::span<const float> base, std::span<const float> edited,
                                std::uint32_t width);

/// Writes the diff's values into `mesh` (which must have the diff's vertex count and the
/// channels it names). Throws InvalidInput on a mismatch or an out-of-range index.
void apply_diff(const Diff& diff, Mesh& mesh);

/// Checks indices are increasing and in range, value counts match, values are finite.
/// Throws InvalidInput with `what` as prefix.
void validate(const Diff& diff, const Mesh& base, std::string_view what);

struct DiffStats {
  std::uint32_t vertices = 0;
  std::uint32_t position_changes = 0;
  double edited_fraction = 0;
  double max_displacement = 0;
  double rms_displacement = 0;
  double bbox_diagonal = 0;
  struct Channel {
    std::string name;
    std::uint32_t changes = 0;
    double max_change = 0;
  };
  std::vector<Channel> channels;
};
DiffStats diff_stats(const Diff& diff, const Mesh& base);
std::string to_json(const DiffStats& stats);

/// A stable 64-bit digest of the diff's content (indices and value bits).
std::uint64_t digest(const Diff& diff);

}  // namespace csculpt
