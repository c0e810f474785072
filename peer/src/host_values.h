// What a session accepts from a host (or from a peer's submit) as a mesh's values: finite
// numbers, positions within reach of the session's mesh, channel values inside their range.
// A value outside is refused before anything is applied, sent or merged, with an error that
// names the vertex and the bound, so one bad value can neither cut a host off nor move other
// artists' vertices (a far-off vertex turns the merge's rotations into noise around it).
#pragma once

#include <string_view>

#include "csculpt/diff.h"
#include "csculpt/merge.h"
#include "csculpt/mesh.h"

namespace csculpt::peer {

/// How far from the session's centre a position may be, in initial bounding-box diagonals:
/// far beyond any legitimate grab, close enough that the merge's arithmetic stays sound.
inline constexpr float kMaxReach = 1000.f;
/// How far outside its range a channel value is still accepted, as a share of the range.
inline constexpr double kRangeSlack = 1e-3;

/// Throws InvalidInput ("`what`: ...") at the first value of `local` that differs from
/// `base` (same layout) and is not finite, is a position farther than kMaxReach x frame.scale
/// from frame.center, or is a channel value outside the channel's range (by more than kRangeSlack
/// of it). Values equal to the
/// base's came from the session and are not the host's to answer for.
void check_host_values(const Mesh& local, const Mesh& base, const MergeFrame& frame,
                       std::string_view what);

/// The same for the values a diff sets (a peer's submit, decoded on `base`).
void check_diff_values(const Diff& diff, const Mesh& base, const MergeFrame& frame,
                       std::string_view what);

}  // namespace csculpt::peer
