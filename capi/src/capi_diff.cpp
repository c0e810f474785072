// The C ABI of diffs (csc_diff): captured from a host's arrays or meshes, applied, inspected.
#include <cstring>
#include <string>

#include "capi_internal.h"

using namespace csculpt::capi;
using csculpt::InvalidInput;

extern "C" {

CSC_API csc_status csc_diff_capture_arrays(csc_diff** out, const csc_mesh* base,
                                           const csc_vertex_arrays* current_in) {
  return guarded("csc_diff_capture_arrays", [&] {
    require_pointer(out, "out");
    const csculpt::Mesh& b = handle(base, Tag::mesh, "base").mesh;
    const csc_vertex_arrays current = host_arrays(current_in, b, "current");
    csculpt::Diff d;
    d.vertex_count = static_cast<std::uint32_t>(b.vertex_count());
    d.positions = csculpt::capture_attribute(floats(b.positions),
                                             {current.positions, b.vertex_count() * 3}, 3);
    for (std::size_t c = 0; c < b.channels.size(); ++c) {
      const csculpt::Channel& bc = b.channels[c];
      csculpt::ChannelDiff cd{bc.desc, {}};
      if (current.channels[c] != nullptr)
        cd.change = csculpt::capture_attribute(bc.values, {current.channels[c], bc.values.size()},
                                               bc.desc.width);
      d.channels.push_back(std::move(cd));
    }
    csculpt::validate(d, b, "current");
    *out = new_diff(std::move(d)).release();
  });
}

CSC_API csc_status csc_diff_capture(csc_diff** out, const csc_mesh* base, const csc_mesh* edited) {
  return guarded("csc_diff_capture", [&] {
    require_pointer(out, "out");
    const csculpt::Mesh& b = handle(base, Tag::mesh, "base").mesh;
    const csculpt::Mesh& e = handle(edited, Tag::mesh, "edited").mesh;
    *out = new_diff(csculpt::capture_diff(b, e)).release();
  });
}

CSC_API void csc_diff_destroy(csc_diff* diff) {
  destroy(diff, Tag::diff);
}

CSC_API csc_status csc_mesh_apply_diff(csc_mesh* mesh, const csc_diff* diff) {
  return guarded("csc_mesh_apply_diff", [&] {
    csculpt::Mesh& m = handle(mesh, Tag::mesh, "mesh").mesh;
    const csculpt::Diff& d = handle(diff, Tag::diff, "diff").diff;
    csculpt::apply_diff(d, m);  // validates before writing anything
  });
}

CSC_API csc_status csc_diff_apply_arrays(const csc_diff* diff, const csc_mesh* base,
                                         const csc_vertex_arrays* target_in) {
  return guarded("csc_diff_apply_arrays", [&] {
    const csculpt::Diff& d = handle(diff, Tag::diff, "diff").diff;
    const csculpt::Mesh& b = handle(base, Tag::mesh, "base").mesh;
    const csc_vertex_arrays target = host_arrays(target_in, b, "target");
    csculpt::validate(d, b, "diff");
    for (std::size_t i = 0; i < d.positions.indices.size(); ++i)
      std::memcpy(target.positions + std::size_t{3} * d.positions.indices[i],
                  d.positions.values.data() + 3 * i, 3 * sizeof(float));
    for (const csculpt::ChannelDiff& c : d.channels) {
      float* values = target.channels[static_cast<std::size_t>(b.find_channel(c.desc.name))];
      if (values == nullptr) continue;
      const std::uint32_t w = c.desc.width;
      for (std::size_t i = 0; i < c.change.indices.size(); ++i)
        std::memcpy(values + std::size_t{w} * c.change.indices[i], c.change.values.data() + w * i,
                    w * sizeof(float));
    }
  });
}

CSC_API csc_status csc_diff_get_info(const csc_diff* diff, csc_diff_info* out) {
  return guarded("csc_diff_get_info", [&] {
    const csculpt::Diff& d = handle(diff, Tag::diff, "diff").diff;
    csc_diff_info v = CSC_DIFF_INFO_INIT;
    v.vertex_count = d.vertex_count;
    v.touched_vertices = static_cast<std::uint32_t>(d.touched_vertices());
    v.position_changes = static_cast<std::uint32_t>(d.positions.size());
    v.channel_count = static_cast<std::uint32_t>(d.channels.size());
    v.digest = csculpt::digest(d);
    write_out(out, v, "out");
  });
}

CSC_API csc_status csc_diff_positions(const csc_diff* diff, const uint32_t** indices,
                                      const float** values, uint32_t* count) {
  return guarded("csc_diff_positions", [&] {
    const csculpt::Diff& d = handle(diff, Tag::diff, "diff").diff;
    require_pointer(indices, "indices");
    require_pointer(values, "values");
    require_pointer(count, "count");
    *indices = d.positions.indices.data();
    *values = d.positions.values.data();
    *count = static_cast<std::uint32_t>(d.positions.size());
  });
}

CSC_API csc_status csc_diff_channel(const csc_diff* diff, uint32_t index, const char** name,
                                    uint32_t* width, const uint32_t** indices, const float** values,
                                    uint32_t* count) {
  return guarded("csc_diff_channel", [&] {
    const csculpt::Diff& d = handle(diff, Tag::diff, "diff").diff;
    if (index >= d.channels.size())
      bad_argument("channel index " + std::to_string(index) + " out of range (" +
                   std::to_string(d.channels.size()) + " channels)");
    require_pointer(name, "name");
    require_pointer(width, "width");
    require_pointer(indices, "indices");
    require_pointer(values, "values");
    require_pointer(count, "count");
    const csculpt::ChannelDiff& c = d.channels[index];
    *name = c.desc.name.c_str();
    *width = c.desc.width;
    *indices = c.change.indices.data();
    *values = c.change.values.data();
    *count = static_cast<std::uint32_t>(c.change.size());
  });
}

}  // extern "C"
