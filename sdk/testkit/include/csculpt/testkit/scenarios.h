// Merge scenarios with a known expected result (paper §3.1 properties and Fig. 3/5
// comparisons), on the built-in sphere: used by the tests and by `csculpt scenarios`,
// which prints the table of errors per scenario and method quoted in the README.
#pragma once

#include <string>
#include <vector>

#include "csculpt/merge.h"
#include "csculpt/mesh.h"

namespace csculpt {

struct Scenario {
  std::string name;
  std::string description;
  Mesh base;
  std::vector<Mesh> edits;
  /// Where an expected result exists: the edits applied one after the other, finest first
  /// (the detail carried along by the large edit), or the shared edit when they are equal.
  bool has_expected = true;
  Mesh expected;
  /// The methods the paper says `full` must beat here (Fig. 3, Fig. 5).
  std::vector<MergeMethod> full_beats;
};

/// disjoint, identical, translation+detail, twist+detail, bend+detail, overlapping-coarse,
/// paint-overlap, four-users. `faces` sets the sphere's resolution.
std::vector<Scenario> make_scenarios(std::uint32_t faces = 40000);

struct ScenarioScore {
  double rel_err = 0;      ///< RMS distance to expected over the finest edit's support,
                           ///< relative to that edit's RMS size (0 = intent kept whole)
  double roughness = 0;    ///< merged displacement roughness / the roughest input's (~1 = smooth)
  double channel_err = 0;  ///< RMS error of material channels (linear) against expected
};

/// Scores `merged` against the scenario (rel_err only when it has an expected result).
ScenarioScore score(const Scenario& scenario, const Mesh& merged, const Topology& topology);

}  // namespace csculpt
