// The C ABI (capi/include/csculpt.h) over the C++ SDK. Every entry point catches everything and
// maps it to a csc_status with a thread-local message; no exception or C++ type crosses.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <new>
#include <string>
#include <vector>

#include <zmq.hpp>
#include "csculpt.h"
#include "csculpt/diff.h"
#include "csculpt/error.h"
#include "csculpt/hierarchy.h"
#include "csculpt/io.h"
#include "csculpt/merge.h"
#include "csculpt/mesh.h"
#include "csculpt/peer/session.h"
#include "csculpt/wire.h"

namespace {

// Each handle starts with a tag, so a handle of another kind is refused instead of misread.
// Destroy clears it, which helps catch some double destroys; a destroyed handle is still
// undefined behaviour to pass (the header says so).
enum class Tag : std::uint32_t {
  dead = 0,
  mesh = 0x4d455348,       // "MESH"
  hierarchy = 0x48494552,  // "HIER"
  diff = 0x44494646,       // "DIFF"
  merger = 0x4d524752,     // "MRGR"
  bytes = 0x42595445,      // "BYTE"
  session = 0x53455353,    // "SESS"
};

}  // namespace

struct csc_mesh {
  Tag tag = Tag::mesh;
  csculpt::Mesh mesh;
};
struct csc_hierarchy {
  Tag tag = Tag::hierarchy;
  csculpt::Hierarchy hierarchy;
};
struct csc_diff {
  Tag tag = Tag::diff;
  csculpt::Diff diff;
  std::string author;  // of a decoded message (csc_message_info::author points here)
};
struct csc_merger {
  Tag tag = Tag::merger;
  explicit csc_merger(const csculpt::Hierarchy& h) : merger(h) {}
  csculpt::Merger merger;
};
struct csc_bytes {
  Tag tag = Tag::bytes;
  std::vector<std::uint8_t> data;
};
struct csc_session {
  Tag tag = Tag::session;
  std::unique_ptr<csculpt::peer::Session> session;
  csculpt::Mesh local;  // mirror of the host's arrays between calls
  std::string invite;
  std::string event_message;  // of the last polled event
  std::vector<csculpt::peer::Event> pending_events;
  bool left = false;
};

namespace {

using csculpt::InvalidInput;

thread_local std::string t_last_error;

/// A bad argument (NULL, wrong struct_size, foreign handle): CSC_ERROR_INVALID_ARGUMENT.
struct ArgumentError {
  std::string message;
};
/// A diff message for another base version: CSC_ERROR_UNKNOWN_BASE_VERSION.
struct BaseVersionError {
  std::string message;
};

csc_status fail(csc_status status, std::string message) {
  try {
    t_last_error = std::move(message);
  } catch (...) {
    t_last_error.clear();
  }
  return status;
}

/// Runs `body` (which returns nothing and throws on failure) and maps what it throws.
template <class Body>
csc_status guarded(const char* function, Body&& body) noexcept {
  try {
    body();
    return CSC_OK;
  } catch (const ArgumentError& e) {
    return fail(CSC_ERROR_INVALID_ARGUMENT, std::string(function) + ": " + e.message);
  } catch (const BaseVersionError& e) {
    return fail(CSC_ERROR_UNKNOWN_BASE_VERSION, std::string(function) + ": " + e.message);
  } catch (const csculpt::InvalidInput& e) {
    return fail(CSC_ERROR_INVALID_INPUT, std::string(function) + ": " + e.what());
  } catch (const csculpt::IoError& e) {
    return fail(CSC_ERROR_IO, std::string(function) + ": " + e.what());
  } catch (const std::bad_alloc&) {
    return fail(CSC_ERROR_OUT_OF_MEMORY, std::string(function) + ": out of memory");
  } catch (const std::exception& e) {
    return fail(CSC_ERROR_INTERNAL, std::string(function) + ": internal error: " + e.what());
  } catch (...) {
    return fail(CSC_ERROR_INTERNAL, std::string(function) + ": internal error");
  }
}

[[noreturn]] void bad_argument(std::string message) {
  throw ArgumentError{std::move(message)};
}

template <class T>
void require_pointer(const T* p, const char* name) {
  if (p == nullptr) bad_argument(std::string(name) + " is NULL");
}

template <class Handle>
bool is(const Handle* h, Tag tag) {
  return h != nullptr && h->tag == tag;
}

template <class Handle>
Handle& handle(Handle* h, Tag tag, const char* name) {
  if (h == nullptr) bad_argument(std::string(name) + " is NULL");
  if (h->tag != tag) bad_argument(std::string(name) + " is not a handle of the right kind");
  return *h;
}

/// The size of a struct's first published layout (ABI 0.2): the least a caller's struct_size
/// may say. When a struct grows, specialise this with its old size so older hosts keep working.
template <class T>
constexpr std::size_t first_published_size = sizeof(T);

void require_struct_size(std::uint32_t declared, std::size_t minimum, const char* name) {
  if (declared < minimum)
    bad_argument(std::string(name) + "->struct_size is " + std::to_string(declared) +
                 ", at least " + std::to_string(minimum) +
                 " expected (initialise it with the _INIT macro)");
}

/// Reads an input struct: fields past the caller's struct_size (a host built against an older
/// header) keep `defaults`; fields past ours (a newer host) are not read.
template <class T>
T read_in(const T* in, const T& defaults, const char* name) {
  require_pointer(in, name);
  require_struct_size(in->struct_size, first_published_size<T>, name);
  T value = defaults;
  std::memcpy(static_cast<void*>(&value), in, std::min<std::size_t>(in->struct_size, sizeof(T)));
  value.struct_size = sizeof(T);
  return value;
}

/// Writes an output struct: at most the caller's declared size (which must cover the first
/// published layout); the caller's struct_size is kept.
template <class T>
void write_out(T* out, const T& value, const char* name) {
  require_pointer(out, name);
  require_struct_size(out->struct_size, first_published_size<T>, name);
  const std::uint32_t size = out->struct_size;
  std::memcpy(static_cast<void*>(out), &value, std::min<std::size_t>(size, sizeof(T)));
  out->struct_size = size;
}

csculpt::Linearisation to_linearisation(csc_linearisation lin) {
  switch (lin) {
    case CSC_LINEARISATION_IDENTITY:
      return csculpt::Linearisation::identity;
    case CSC_LINEARISATION_SQUARE:
      return csculpt::Linearisation::square;
    case CSC_LINEARISATION_SRGB:
      return csculpt::Linearisation::srgb;
    default:
      bad_argument("unknown linearisation " + std::to_string(static_cast<long long>(lin)));
  }
}

csc_linearisation from_linearisation(csculpt::Linearisation lin) {
  return static_cast<csc_linearisation>(static_cast<std::uint32_t>(lin));
}

std::span<const float> floats(const std::vector<csculpt::Vec3f>& v) {
  static_assert(sizeof(csculpt::Vec3f) == 3 * sizeof(float));
  return {reinterpret_cast<const float*>(v.data()), v.size() * 3};
}

/// The host's arrays, checked against the base mesh's layout.
csc_vertex_arrays host_arrays(const csc_vertex_arrays* in, const csculpt::Mesh& base,
                              const char* name) {
  const csc_vertex_arrays defaults = CSC_VERTEX_ARRAYS_INIT;
  const csc_vertex_arrays arrays = read_in(in, defaults, name);
  const csc_vertex_arrays* a = &arrays;
  // Counts that do not match the base are bad data (the header's contract), not a bad call.
  if (a->vertex_count != base.vertex_count())
    throw InvalidInput(std::string(name) + " has " + std::to_string(a->vertex_count) +
                       " vertices but the base mesh has " + std::to_string(base.vertex_count()));
  if (a->positions == nullptr) bad_argument(std::string(name) + "->positions is NULL");
  if (a->channel_count != base.channels.size())
    throw InvalidInput(std::string(name) + " has " + std::to_string(a->channel_count) +
                       " channels but the base mesh has " + std::to_string(base.channels.size()));
  if (a->channel_count > 0 && a->channels == nullptr)
    bad_argument(std::string(name) + "->channels is NULL");
  return arrays;
}

std::unique_ptr<csc_diff> new_diff(csculpt::Diff d) {
  auto h = std::make_unique<csc_diff>();
  h->diff = std::move(d);
  return h;
}

template <class Handle>
void destroy(Handle* h, Tag tag) noexcept {
  if (h == nullptr || h->tag != tag) return;
  h->tag = Tag::dead;
  delete h;
}

}  // namespace

extern "C" {

// ---- Version, status ---------------------------------------------------------------------

CSC_API uint32_t csc_version(void) {
  return CSC_VERSION_NUMBER;
}
CSC_API const char* csc_version_string(void) {
  return CSC_VERSION_STRING;
}
CSC_API uint32_t csc_wire_protocol_version(void) {
  return csculpt::wire_protocol_version;
}

CSC_API const char* csc_status_str(csc_status status) {
  switch (status) {
    case CSC_OK:
      return "ok";
    case CSC_ERROR_INVALID_ARGUMENT:
      return "invalid argument";
    case CSC_ERROR_INVALID_INPUT:
      return "invalid input";
    case CSC_ERROR_IO:
      return "input/output error";
    case CSC_ERROR_UNKNOWN_BASE_VERSION:
      return "unknown base version";
    case CSC_ERROR_OUT_OF_MEMORY:
      return "out of memory";
    case CSC_ERROR_INTERNAL:
      return "internal error";
    default:
      return "unknown status";
  }
}

CSC_API const char* csc_last_error(void) {
  return t_last_error.c_str();
}

// ---- Meshes ------------------------------------------------------------------------------

CSC_API csc_status csc_mesh_create(csc_mesh** out, const csc_mesh_desc* desc_in) {
  return guarded("csc_mesh_create", [&] {
    require_pointer(out, "out");
    const csc_mesh_desc defaults = CSC_MESH_DESC_INIT;
    const csc_mesh_desc description = read_in(desc_in, defaults, "desc");
    const csc_mesh_desc* desc = &description;
    if (desc->vertex_count > 0 && desc->positions == nullptr)
      bad_argument("desc->positions is NULL");
    if (desc->triangle_count > 0 && desc->triangles == nullptr)
      bad_argument("desc->triangles is NULL");
    if (desc->channel_count > 0 && desc->channels == nullptr)
      bad_argument("desc->channels is NULL");
    if (desc->channel_count > 256)
      bad_argument("desc->channel_count is " + std::to_string(desc->channel_count) +
                   " (at most 256)");
    auto h = std::make_unique<csc_mesh>();
    csculpt::Mesh& m = h->mesh;
    m.positions.resize(desc->vertex_count);
    if (desc->vertex_count)
      std::memcpy(static_cast<void*>(m.positions.data()), desc->positions,
                  std::size_t{desc->vertex_count} * 12);
    m.triangles.resize(desc->triangle_count);
    if (desc->triangle_count)
      std::memcpy(static_cast<void*>(m.triangles.data()), desc->triangles,
                  std::size_t{desc->triangle_count} * 12);
    for (std::uint32_t c = 0; c < desc->channel_count; ++c) {
      const csc_channel_desc& cd = desc->channels[c];
      const std::string what = "channel " + std::to_string(c);
      if (cd.name == nullptr)
        bad_argument("desc->channels[" + std::to_string(c) + "].name is NULL");
      const std::size_t len = strnlen(cd.name, 256);
      if (len == 0 || len > 255) throw InvalidInput(what + ": name must be 1 to 255 bytes");
      if (cd.width < 1 || cd.width > 4)
        throw InvalidInput(what + " '" + cd.name + "': width " + std::to_string(cd.width) +
                           " (1 to 4 allowed)");
      if (std::isnan(cd.min_value) || std::isnan(cd.max_value) || cd.min_value > cd.max_value)
        throw InvalidInput(what + " '" + cd.name + "': min_value must be <= max_value");
      csculpt::ChannelDesc d{std::string(cd.name, len), cd.width,
                             to_linearisation(cd.linearisation), cd.min_value, cd.max_value};
      if (m.find_channel(d.name) >= 0)
        throw InvalidInput(what + ": the name '" + d.name + "' is used twice");
      csculpt::Channel channel{std::move(d), {}};
      const std::size_t n = std::size_t{desc->vertex_count} * cd.width;
      channel.values.assign(n, 0.f);
      if (desc->channel_values != nullptr && desc->channel_values[c] != nullptr && n)
        std::memcpy(channel.values.data(), desc->channel_values[c], n * sizeof(float));
      m.channels.push_back(std::move(channel));
    }
    csculpt::validate(m, "mesh");
    *out = h.release();
  });
}

CSC_API csc_status csc_mesh_add_material_channels(csc_mesh* mesh) {
  return guarded("csc_mesh_add_material_channels", [&] {
    csculpt::Mesh& m = handle(mesh, Tag::mesh, "mesh").mesh;
    // Check every existing channel first, so a conflict changes nothing.
    for (const csculpt::ChannelDesc& d : csculpt::material_channels()) {
      const int i = m.find_channel(d.name);
      if (i >= 0 && m.channels[static_cast<std::size_t>(i)].desc.width != d.width)
        throw InvalidInput("the mesh has a channel '" + d.name + "' of width " +
                           std::to_string(m.channels[static_cast<std::size_t>(i)].desc.width) +
                           " (the material channel has width " + std::to_string(d.width) + ")");
    }
    csculpt::Mesh copy = m;
    for (const csculpt::ChannelDesc& d : csculpt::material_channels()) {
      const float grey[3] = {0.5f, 0.5f, 0.5f};
      const float zero = 0.f, rough = 0.7f;
      std::span<const float> fill = d.name == "albedo"     ? std::span<const float>(grey, 3)
                                    : d.name == "metallic" ? std::span<const float>(&zero, 1)
                                                           : std::span<const float>(&rough, 1);
      copy.add_channel(d, fill);
    }
    m = std::move(copy);
  });
}

CSC_API csc_status csc_mesh_read(csc_mesh** out, const char* path) {
  return guarded("csc_mesh_read", [&] {
    require_pointer(out, "out");
    require_pointer(path, "path");
    auto h = std::make_unique<csc_mesh>();
    h->mesh = csculpt::read_mesh(path);
    *out = h.release();
  });
}

CSC_API csc_status csc_mesh_write(const csc_mesh* mesh, const char* path) {
  return guarded("csc_mesh_write", [&] {
    const csculpt::Mesh& m = handle(mesh, Tag::mesh, "mesh").mesh;
    require_pointer(path, "path");
    csculpt::write_mesh(m, path);
  });
}

CSC_API csc_status csc_mesh_clone(csc_mesh** out, const csc_mesh* mesh) {
  return guarded("csc_mesh_clone", [&] {
    require_pointer(out, "out");
    const csculpt::Mesh& m = handle(mesh, Tag::mesh, "mesh").mesh;
    auto h = std::make_unique<csc_mesh>();
    h->mesh = m;
    *out = h.release();
  });
}

CSC_API void csc_mesh_destroy(csc_mesh* mesh) {
  destroy(mesh, Tag::mesh);
}

CSC_API uint32_t csc_mesh_vertex_count(const csc_mesh* mesh) {
  return is(mesh, Tag::mesh) ? static_cast<uint32_t>(mesh->mesh.vertex_count()) : 0;
}
CSC_API uint32_t csc_mesh_triangle_count(const csc_mesh* mesh) {
  return is(mesh, Tag::mesh) ? static_cast<uint32_t>(mesh->mesh.face_count()) : 0;
}
CSC_API uint32_t csc_mesh_channel_count(const csc_mesh* mesh) {
  return is(mesh, Tag::mesh) ? static_cast<uint32_t>(mesh->mesh.channels.size()) : 0;
}
CSC_API const float* csc_mesh_positions(const csc_mesh* mesh) {
  return is(mesh, Tag::mesh) ? floats(mesh->mesh.positions).data() : nullptr;
}
CSC_API const uint32_t* csc_mesh_triangles(const csc_mesh* mesh) {
  return is(mesh, Tag::mesh) ? mesh->mesh.triangles.data()->data() : nullptr;
}

CSC_API csc_status csc_mesh_channel(const csc_mesh* mesh, uint32_t index, csc_channel_view* out) {
  return guarded("csc_mesh_channel", [&] {
    const csculpt::Mesh& m = handle(mesh, Tag::mesh, "mesh").mesh;
    if (index >= m.channels.size())
      bad_argument("channel index " + std::to_string(index) + " out of range (" +
                   std::to_string(m.channels.size()) + " channels)");
    const csculpt::Channel& c = m.channels[index];
    csc_channel_view v = CSC_CHANNEL_VIEW_INIT;
    v.desc = {c.desc.name.c_str(), c.desc.width, from_linearisation(c.desc.linearisation),
              c.desc.min_value, c.desc.max_value};
    v.values = c.values.data();
    write_out(out, v, "out");
  });
}

CSC_API int32_t csc_mesh_find_channel(const csc_mesh* mesh, const char* name) {
  if (!is(mesh, Tag::mesh) || name == nullptr) return -1;
  return mesh->mesh.find_channel(name);
}

CSC_API float csc_mesh_bbox_diagonal(const csc_mesh* mesh) {
  return is(mesh, Tag::mesh) ? csculpt::bbox_diagonal(mesh->mesh.positions) : 0.f;
}

// ---- Hierarchy ---------------------------------------------------------------------------

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

// ---- Diffs -------------------------------------------------------------------------------

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

// ---- Wire --------------------------------------------------------------------------------

CSC_API csc_status csc_diff_encode(csc_bytes** out, const csc_diff* diff, const csc_mesh* base,
                                   const csc_encode_options* options) {
  return guarded("csc_diff_encode", [&] {
    require_pointer(out, "out");
    const csculpt::Diff& d = handle(diff, Tag::diff, "diff").diff;
    const csculpt::Mesh& b = handle(base, Tag::mesh, "base").mesh;
    csc_encode_options o = CSC_ENCODE_OPTIONS_INIT;
    if (options != nullptr) o = read_in(options, o, "options");
    if (!(o.position_tolerance >= 0) || !(o.channel_tolerance >= 0) || !(o.position_scale >= 0) ||
        !std::isfinite(o.position_tolerance) || !std::isfinite(o.channel_tolerance) ||
        !std::isfinite(o.position_scale))
      bad_argument("options: tolerances and scale must be finite and >= 0");
    csculpt::DiffHeader header;
    header.base_version = o.base_version;
    header.sequence = o.sequence;
    if (o.author != nullptr) {
      const std::size_t len = strnlen(o.author, csculpt::max_author_bytes + 1);
      if (len > csculpt::max_author_bytes)
        bad_argument("options->author is longer than " + std::to_string(csculpt::max_author_bytes) +
                     " bytes");
      header.author = std::string_view(o.author, len);
    }
    csculpt::EncodeOptions eo;
    eo.position_tolerance = o.position_tolerance;
    eo.position_scale = o.position_scale;
    eo.channel_tolerance = o.channel_tolerance;
    auto h = std::make_unique<csc_bytes>();
    h->data = csculpt::encode_diff(d, b, header, eo);
    *out = h.release();
  });
}

CSC_API const uint8_t* csc_bytes_data(const csc_bytes* bytes) {
  return is(bytes, Tag::bytes) ? bytes->data.data() : nullptr;
}
CSC_API size_t csc_bytes_size(const csc_bytes* bytes) {
  return is(bytes, Tag::bytes) ? bytes->data.size() : 0;
}
CSC_API void csc_bytes_destroy(csc_bytes* bytes) {
  destroy(bytes, Tag::bytes);
}

}  // extern "C"

namespace {
std::span<const std::uint8_t> byte_span(const void* data, std::size_t size) {
  if (data == nullptr && size > 0) bad_argument("data is NULL");
  return {static_cast<const std::uint8_t*>(data), size};
}

csc_message_info message_info(const csculpt::DiffHeader& h, const char* author) {
  csc_message_info v = CSC_MESSAGE_INFO_INIT;
  v.protocol = h.protocol;
  v.base_version = h.base_version;
  v.sequence = h.sequence;
  v.vertex_count = h.vertex_count;
  v.author = author;
  return v;
}
}  // namespace

extern "C" {

CSC_API csc_status csc_diff_peek(const void* data, size_t size, csc_message_info* info) {
  return guarded("csc_diff_peek", [&] {
    require_pointer(info, "info");
    require_struct_size(info->struct_size, first_published_size<csc_message_info>, "info");
    const csculpt::DiffHeader h = csculpt::peek_diff_header(byte_span(data, size));
    // FlatBuffers strings are NUL-terminated in the buffer (checked by the verifier), and an
    // author with an inner NUL is refused, so the view is a C string; "" when absent.
    write_out(info, message_info(h, h.author.data() ? h.author.data() : ""), "info");
  });
}

CSC_API csc_status csc_diff_decode(csc_diff** out, const csc_mesh* base, uint64_t base_version,
                                   const void* data, size_t size, csc_message_info* info) {
  return guarded("csc_diff_decode", [&] {
    require_pointer(out, "out");
    const csculpt::Mesh& b = handle(base, Tag::mesh, "base").mesh;
    if (info != nullptr)
      require_struct_size(info->struct_size, first_published_size<csc_message_info>, "info");
    const auto bytes = byte_span(data, size);
    const csculpt::DiffHeader peeked = csculpt::peek_diff_header(bytes);
    if (peeked.base_version != base_version)
      throw BaseVersionError{"the message is based on version " +
                             std::to_string(peeked.base_version) + ", not " +
                             std::to_string(base_version)};
    csculpt::DiffHeader h;
    auto d = new_diff(csculpt::decode_diff(bytes, b, &h));
    d->author.assign(h.author);
    if (info != nullptr) write_out(info, message_info(h, d->author.c_str()), "info");
    *out = d.release();
  });
}

// ---- Merge -------------------------------------------------------------------------------

}  // extern "C"

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
    if (count < 1 || count > 64)
      bad_argument("count is " + std::to_string(count) + " (1 to 64 diffs are merged at once)");
    require_pointer(diffs, "diffs");
    const csculpt::Diff* pointers[64];
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

// ---- Sessions ------------------------------------------------------------------------------

}  // extern "C"

namespace {

csculpt::peer::SessionOptions session_options(const csc_session_options* in) {
  const csc_session_options defaults = CSC_SESSION_OPTIONS_INIT;
  const csc_session_options o = in ? read_in(in, defaults, "options") : defaults;
  csculpt::peer::SessionOptions so;
  if (o.bind) so.bind = o.bind;
  if (o.name) {
    if (strnlen(o.name, csculpt::max_author_bytes + 1) > csculpt::max_author_bytes)
      bad_argument("options->name is longer than 256 bytes");
    so.name = o.name;
  }
  so.id = o.id;
  if (o.sync_ms < 1 || o.heartbeat_ms < 1 || o.evasive_ms <= o.heartbeat_ms ||
      o.expired_ms <= o.evasive_ms)
    bad_argument("options: need sync_ms >= 1 and heartbeat_ms < evasive_ms < expired_ms");
  so.sync = csculpt::peer::Millis{o.sync_ms};
  so.membership = {csculpt::peer::Millis{o.heartbeat_ms}, csculpt::peer::Millis{o.evasive_ms},
                   csculpt::peer::Millis{o.expired_ms}};
  if (!(o.position_tolerance >= 0) || !(o.channel_tolerance >= 0) ||
      !std::isfinite(o.position_tolerance) || !std::isfinite(o.channel_tolerance))
    bad_argument("options: tolerances must be finite and >= 0");
  so.wire.position_tolerance = o.position_tolerance;
  so.wire.channel_tolerance = o.channel_tolerance;
  return so;
}

std::unique_ptr<csc_session> new_session(std::unique_ptr<csculpt::peer::Session> s) {
  auto h = std::make_unique<csc_session>();
  h->local = s->base();
  h->invite = s->invite();
  h->session = std::move(s);
  return h;
}

csc_session& live_session(csc_session* s) {
  csc_session& h = handle(s, Tag::session, "session");
  if (h.left) bad_argument("the session was left");
  return h;
}

/// Host arrays -> the mirror (channels given as NULL keep the mirror's values).
void copy_in(const csc_vertex_arrays& a, csculpt::Mesh& m) {
  std::memcpy(static_cast<void*>(m.positions.data()), a.positions, m.positions.size() * 12);
  for (std::size_t c = 0; c < m.channels.size(); ++c)
    if (a.channels[c] != nullptr)
      std::memcpy(m.channels[c].values.data(), a.channels[c],
                  m.channels[c].values.size() * sizeof(float));
}

void copy_out(const csculpt::Mesh& m, const csc_vertex_arrays& a) {
  std::memcpy(a.positions, m.positions.data(), m.positions.size() * 12);
  for (std::size_t c = 0; c < m.channels.size(); ++c)
    if (a.channels[c] != nullptr)
      std::memcpy(a.channels[c], m.channels[c].values.data(),
                  m.channels[c].values.size() * sizeof(float));
}

}  // namespace

extern "C" {

CSC_API csc_status csc_session_create(csc_session** out, const csc_mesh* mesh,
                                      const csc_session_options* options) {
  return guarded("csc_session_create", [&] {
    require_pointer(out, "out");
    const csculpt::Mesh& m = handle(mesh, Tag::mesh, "mesh").mesh;
    const csculpt::peer::SessionOptions so = session_options(options);
    try {
      *out = new_session(csculpt::peer::Session::create(m, so)).release();
    } catch (const zmq::error_t& e) {
      throw csculpt::IoError(std::string("cannot listen on '") + so.bind + "': " + e.what());
    }
  });
}

CSC_API csc_status csc_session_join(csc_session** out, const char* invite,
                                    const csc_session_options* options) {
  return guarded("csc_session_join", [&] {
    require_pointer(out, "out");
    require_pointer(invite, "invite");
    const csc_session_options defaults = CSC_SESSION_OPTIONS_INIT;
    const csc_session_options o = options ? read_in(options, defaults, "options") : defaults;
    const csculpt::peer::SessionOptions so = session_options(options);
    try {
      *out = new_session(
                 csculpt::peer::Session::join(invite, so, csculpt::peer::Millis{o.join_timeout_ms}))
                 .release();
    } catch (const zmq::error_t& e) {
      throw csculpt::IoError(std::string("cannot join: ") + e.what());
    }
  });
}

CSC_API csc_status csc_session_leave(csc_session* session) {
  return guarded("csc_session_leave", [&] {
    csc_session& h = live_session(session);
    h.session->leave();
    h.left = true;
  });
}

CSC_API void csc_session_destroy(csc_session* session) {
  if (!is(session, Tag::session)) return;
  try {
    session->session->leave();
  } catch (...) {
  }
  destroy(session, Tag::session);
}

CSC_API const char* csc_session_invite(const csc_session* session) {
  return is(session, Tag::session) ? session->invite.c_str() : nullptr;
}
CSC_API uint64_t csc_session_id(const csc_session* session) {
  return is(session, Tag::session) ? session->session->id() : 0;
}
CSC_API uint64_t csc_session_version(const csc_session* session) {
  return is(session, Tag::session) ? session->session->version() : 0;
}

CSC_API csc_status csc_session_copy_base(csc_mesh** out, const csc_session* session) {
  return guarded("csc_session_copy_base", [&] {
    require_pointer(out, "out");
    const csc_session& h = handle(session, Tag::session, "session");
    auto m = std::make_unique<csc_mesh>();
    m->mesh = h.session->base();
    *out = m.release();
  });
}

CSC_API csc_status csc_session_submit(csc_session* session, const csc_vertex_arrays* local,
                                      uint32_t strokes, int32_t* sent) {
  return guarded("csc_session_submit", [&] {
    csc_session& h = live_session(session);
    const csc_vertex_arrays a = host_arrays(local, h.local, "local");
    copy_in(a, h.local);
    // Bad host values (NaN/Inf) are refused before anything is sent or written back.
    const bool did = h.session->submit(h.local, strokes);
    copy_out(h.local, a);
    if (sent) *sent = did ? 1 : 0;
  });
}

CSC_API csc_status csc_session_update(csc_session* session, const csc_vertex_arrays* local,
                                      uint32_t* applied) {
  return guarded("csc_session_update", [&] {
    csc_session& h = live_session(session);
    const csc_vertex_arrays a = host_arrays(local, h.local, "local");
    copy_in(a, h.local);
    const std::size_t n = h.session->update(h.local);
    copy_out(h.local, a);
    if (applied) *applied = static_cast<uint32_t>(n);
  });
}

CSC_API csc_status csc_session_poll(csc_session* session, csc_session_event* event,
                                    int32_t* has_event) {
  return guarded("csc_session_poll", [&] {
    csc_session& h = handle(session, Tag::session, "session");
    require_pointer(event, "event");
    require_pointer(has_event, "has_event");
    require_struct_size(event->struct_size, first_published_size<csc_session_event>, "event");
    std::vector<csculpt::peer::Event>& queue = h.pending_events;
    if (queue.empty()) queue = h.session->poll_events();
    if (queue.empty()) {
      *has_event = 0;
      return;
    }
    const csculpt::peer::Event e = std::move(queue.front());
    queue.erase(queue.begin());
    h.event_message = e.message;
    csc_session_event v = CSC_SESSION_EVENT_INIT;
    v.kind = static_cast<csc_event_kind>(static_cast<std::uint32_t>(e.kind));
    v.peer = e.peer;
    v.version = e.version;
    v.epoch = e.epoch;
    v.message = h.event_message.c_str();
    write_out(event, v, "event");
    *has_event = 1;
  });
}

CSC_API csc_status csc_session_get_stats(const csc_session* session, csc_session_stats* out) {
  return guarded("csc_session_get_stats", [&] {
    const csculpt::peer::SessionStats s = handle(session, Tag::session, "session").session->stats();
    csc_session_stats v = CSC_SESSION_STATS_INIT;
    v.id = s.id;
    v.version = s.version;
    v.epoch = s.epoch;
    v.merger = s.merger;
    v.members = s.members;
    v.submits = s.submits;
    v.submit_bytes = s.submit_bytes;
    v.strokes_submitted = s.strokes_submitted;
    v.strokes_acknowledged = s.strokes_acknowledged;
    v.versions_applied = s.versions_applied;
    v.rebases = s.rebases;
    v.merges = s.merges;
    v.merged_strokes = s.merged_strokes;
    v.conflicting_strokes = s.conflicting_strokes;
    v.merge_ms_mean = s.merges ? s.merge_ms_sum / double(s.merges) : 0.0;
    v.merge_ms_max = s.merge_ms_max;
    v.messages_received = s.messages_received;
    v.messages_dropped = s.messages_dropped;
    v.stale_ignored = s.stale_ignored;
    v.auth_rejected = s.auth_rejected;
    write_out(out, v, "out");
  });
}

CSC_API csc_status csc_session_attribution_colors(const csc_session* session, float* rgb,
                                                  uint32_t vertex_count) {
  return guarded("csc_session_attribution_colors", [&] {
    const csc_session& h = handle(session, Tag::session, "session");
    require_pointer(rgb, "rgb");
    if (vertex_count != h.local.vertex_count())
      bad_argument("vertex_count is " + std::to_string(vertex_count) + ", the mesh has " +
                   std::to_string(h.local.vertex_count()));
    const std::vector<float> colours =
        csculpt::peer::attribution_colours(h.session->attribution(), vertex_count);
    std::memcpy(rgb, colours.data(), colours.size() * sizeof(float));
  });
}

}  // extern "C"
