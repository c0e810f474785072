// Attribution (the paper's Fig. 1/6): how much of each vertex's change came from which peer.
// The merger measures every merged diff's change per vertex and sends it quantised with the
// version (messages.h Contribution); every peer sums what it receives. Pure logic.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "csculpt/diff.h"
#include "csculpt/mesh.h"
#include "messages.h"

namespace csculpt::peer {

/// Every vertex a diff touches (positions or any channel), increasing.
std::vector<std::uint32_t> touched(const Diff& d);

/// How much `d` changes each of `vertices` (touched(d)): position displacement in units of
/// `scale` plus the absolute channel changes.
std::vector<float> change_amounts(const Diff& d, const Mesh& base,
                                  std::span<const std::uint32_t> vertices, float scale);

/// `peer`'s contribution of `d` (from `base`), over `vertices` = touched(d).
Contribution measure_contribution(PeerId peer, const Diff& d, const Mesh& base,
                                  std::span<const std::uint32_t> vertices, float scale);

/// Adds a received contribution to `into` (one value per vertex). Attribution is advisory: a
/// malformed list (bad varint, index out of range) is cut where it goes wrong, never trusted.
void add_contribution(const Contribution& c, std::vector<float>& into);

}  // namespace csculpt::peer
