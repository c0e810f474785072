// `csculpt merge ... --explain [--ideal IDEAL ...]`: why a merge is good or bad, as one JSON
// object. Per artist, what the edit was (support, size); per ideal, the scorer's rel_err
// (shared/eval/score_merge.py) over the smallest edit's support and over each artist's own;
// fold-overs nobody made; and where the error lives: in which connected parts of the mesh, at
// which level of the merge hierarchy (coarse: the big shapes are wrong; fine: details are
// lost or seams appear), and at which vertices.
#pragma once

#include <span>
#include <string>
#include <vector>

#include "csculpt/diff.h"
#include "csculpt/hierarchy.h"
#include "csculpt/merge.h"
#include "csculpt/mesh.h"

namespace csculpt::cli {

struct ExplainInput {
  const Mesh& base;
  std::span<const std::string> edit_names;  ///< one per diff, shown in the report
  std::span<const Diff> diffs;              ///< each artist's edit of `base`
  const Diff& merged;                       ///< the merge of `diffs`
  const Mesh& result;                       ///< `base` with `merged` applied
  const Hierarchy& hierarchy;               ///< the hierarchy the merge used
  MergeMethod method;
  std::vector<std::string> ideal_paths;  ///< meshes the result should match (may be empty)
};

/// The report as one line of JSON (no newline). Reads the ideals; throws InvalidInput (naming
/// the file) when one does not have the base's vertices and triangles.
std::string explain_merge(const ExplainInput& input);

}  // namespace csculpt::cli
