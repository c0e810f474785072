// The C ABI of hierarchies (csc_hierarchy): build, statistics, digest.
#include <string>

#include "capi_internal.h"

using namespace csculpt::capi;
using csculpt::InvalidInput;

extern "C" {

CSC_API csc_status csc_hierarchy_build(csc_hierarchy** out, const csc_mesh* mesh,
                                       const csc_hierarchy_options* options) {
  return guarded("csc_hierarchy_build", [&] {
    require_pointer(out, "out");
    const csculpt::Mesh& m = handle(mesh, Tag::mesh, "mesh").mesh;
    csculpt::HierarchyOptions o;
    if (options != nullptr) {
      const csc_hierarchy_options defaults = CSC_HIERARCHY_OPTIONS_INIT;
      const csc_hierarchy_options in = read_in(options, defaults, "options");
      if (in.max_parents < 1 || in.max_parents > 32)
        bad_argument("options->max_parents is " + std::to_string(in.max_parents) +
                     " (1 to 32 allowed)");
      o.max_parents = in.max_parents;
    }
    auto h = std::unique_ptr<csc_hierarchy>(new csc_hierarchy{
        Tag::hierarchy,
        csculpt::Hierarchy::build(static_cast<std::uint32_t>(m.vertex_count()), m.triangles, o)});
    *out = h.release();
  });
}

CSC_API void csc_hierarchy_destroy(csc_hierarchy* hierarchy) {
  destroy(hierarchy, Tag::hierarchy);
}

CSC_API csc_status csc_hierarchy_get_stats(const csc_hierarchy* hierarchy,
                                           csc_hierarchy_stats* out) {
  return guarded("csc_hierarchy_get_stats", [&] {
    const csculpt::HierarchyStats s =
        handle(hierarchy, Tag::hierarchy, "hierarchy").hierarchy.stats();
    csc_hierarchy_stats v = CSC_HIERARCHY_STATS_INIT;
    v.vertices = s.vertices;
    v.faces = s.faces;
    v.levels = s.levels;
    v.nodes = s.nodes;
    v.node_ratio = s.node_ratio;
    v.mean_level_ratio = s.mean_level_ratio;
    v.top_nodes = s.top_nodes;
    write_out(out, v, "out");
  });
}

CSC_API uint64_t csc_hierarchy_digest(const csc_hierarchy* hierarchy) {
  if (!is(hierarchy, Tag::hierarchy)) return 0;
  try {
    return hierarchy->hierarchy.digest();
  } catch (...) {
    return 0;
  }
}

}  // extern "C"
