// The C ABI of merging: the methods by name and the merger (csc_merger).
#include <cmath>
#include <string>

#include "capi_internal.h"

using namespace csculpt::capi;
using csculpt::InvalidInput;

static_assert(CSC_MAX_MERGE_DIFFS == csculpt::max_merge_diffs);

namespace {

struct MethodName {
  csc_merge_method method;
  csculpt::MergeMethod sdk;
};
constexpr MethodName kMethods[] = {
    {CSC_MERGE_FULL, csculpt::MergeMethod::full},
    {CSC_MERGE_SINGLE_PARENT, csculpt::MergeMethod::single_parent},
    {CSC_MERGE_SINGLE_LEVEL_ISOMETRY, csculpt::MergeMethod::single_level_isometry},
    {CSC_MERGE_MULTISCALE_TRANSLATION, csculpt::MergeMethod::multiscale_translation},
    {CSC_MERGE_WEIGHTED_TRANSLATION, csculpt::MergeMethod::weighted_translation},
    {CSC_MERGE_AVERAGE, csculpt::MergeMethod::average},
    {CSC_MERGE_SUM, csculpt::MergeMethod::sum},
    {CSC_MERGE_PAPER_BLEND, csculpt::MergeMethod::paper_blend},
    {CSC_MERGE_HIERARCHY_BLEND, csculpt::MergeMethod::hierarchy_blend},
    {CSC_MERGE_FRAME_TRANSPORT, csculpt::MergeMethod::frame_transport},
};
const MethodName* find_method(csc_merge_method m) {
  for (const MethodName& n : kMethods)
    if (n.method == m) return &n;
  return nullptr;
}

}  // namespace

extern "C" {

CSC_API const char* csc_merge_method_name(csc_merge_method method) {
  const MethodName* m = find_method(method);
  return m ? csculpt::to_string(m->sdk).data() : nullptr;
}

CSC_API csc_status csc_merge_method_from_name(csc_merge_method* out, const char* name) {
  return guarded("csc_merge_method_from_name", [&] {
    require_pointer(out, "out");
    require_pointer(name, "name");
    csculpt::MergeMethod sdk{};
    try {
      sdk = csculpt::merge_method_from_string(name);
    } catch (const InvalidInput& e) {
      bad_argument(e.what());  // an unknown name is a caller's mistake, like method 99
    }
    for (const MethodName& n : kMethods)
      if (n.sdk == sdk) *out = n.method;
  });
}

CSC_API csc_status csc_merger_create(csc_merger** out, const csc_hierarchy* hierarchy) {
  return guarded("csc_merger_create", [&] {
    require_pointer(out, "out");
    const csculpt::Hierarchy& h = handle(hierarchy, Tag::hierarchy, "hierarchy").hierarchy;
    *out = std::make_unique<csc_merger>(h).release();
  });
}

CSC_API void csc_merger_destroy(csc_merger* merger) {
  destroy(merger, Tag::merger);
}

CSC_API csc_status csc_merger_merge(csc_merger* merger, csc_diff** out, const csc_mesh* base,
                                    const csc_diff* const* diffs, uint32_t count,
                                    const csc_merge_options* options) {
  return guarded("csc_merger_merge", [&] {
    csculpt::Merger& m = handle(merger, Tag::merger, "merger").merger;
    require_pointer(out, "out");
    const csculpt::Mesh& b = handle(base, Tag::mesh, "base").mesh;
    if (count < 1 || count > csculpt::max_merge_diffs)
      bad_argument("count is " + std::to_string(count) + " (1 to " +
                   std::to_string(csculpt::max_merge_diffs) + " diffs are merged at once)");
    require_pointer(diffs, "diffs");
    const csculpt::Diff* pointers[csculpt::max_merge_diffs];
    for (std::uint32_t i = 0; i < count; ++i) {
      const std::string name = "diffs[" + std::to_string(i) + "]";
      pointers[i] = &handle(diffs[i], Tag::diff, name.c_str()).diff;
    }
    csc_merge_options o = CSC_MERGE_OPTIONS_INIT;
    if (options != nullptr) o = read_in(options, o, "options");
    const MethodName* method = find_method(o.method);
    if (method == nullptr)
      bad_argument("options->method " + std::to_string(static_cast<long long>(o.method)) +
                   " is not a merge method");
    csculpt::MergeFrame frame;
    if (o.use_frame) {
      if (!(o.frame_scale > 0) || !std::isfinite(o.frame_scale) ||
          !std::isfinite(o.frame_center[0]) || !std::isfinite(o.frame_center[1]) ||
          !std::isfinite(o.frame_center[2]))
        bad_argument("options: the frame's centre must be finite and its scale positive");
      frame.center = {o.frame_center[0], o.frame_center[1], o.frame_center[2]};
      frame.scale = o.frame_scale;
    } else {
      frame = csculpt::MergeFrame::fit(b.positions);
    }
    auto result = new_diff(
        m.merge(b, std::span<const csculpt::Diff* const>(pointers, count), method->sdk, frame));
    *out = result.release();
  });
}

CSC_API csc_status csc_merger_last_timings(const csc_merger* merger, csc_merge_timings* out) {
  return guarded("csc_merger_last_timings", [&] {
    const csculpt::MergeTimings& t = handle(merger, Tag::merger, "merger").merger.last_timings();
    csc_merge_timings v = CSC_MERGE_TIMINGS_INIT;
    v.isometry_ms = t.isometry_ms;
    v.decompose_ms = t.decompose_ms;
    v.blend_ms = t.blend_ms;
    v.apply_ms = t.apply_ms;
    write_out(out, v, "out");
  });
}

}  // extern "C"
