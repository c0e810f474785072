#include "csculpt/diff.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>

#include "csculpt/error.h"
#include "csculpt/hash.h"

namespace csculpt {
namespace {

bool same_bits(const float* a, const float* b, std::uint32_t width) {
  return std::memcmp(a, b, sizeof(float) * width) == 0;
}

void validate_attribute(const AttributeDiff& a, std::uint32_t width, std::uint32_t vertex_count,
                        std::string_view what, std::string_view attribute) {
  auto fail = [&](const std::string& problem) {
    throw InvalidInput(std::string(what) + ": " + std::string(attribute) + ": " + problem);
  };
  if (a.values.size() != a.indices.size() * width)
    fail(std::to_string(a.indices.size()) + " indices but " + std::to_string(a.values.size()) +
         " values (width " + std::to_string(width) + ")");
  for (std::size_t i = 0; i < a.indices.size(); ++i) {
    if (a.indices[i] >= vertex_count)
      fail("vertex index " + std::to_string(a.indices[i]) + " out of range (" +
           std::to_string(vertex_count) + " vertices)");
    if (i > 0 && a.indices[i] <= a.indices[i - 1])
      fail("vertex indices not strictly increasing at entry " + std::to_string(i));
  }
  for (std::size_t i = 0; i < a.values.size(); ++i)
    if (!std::isfinite(a.values[i]))
      fail("value of vertex " + std::to_string(a.indices[i / width]) + " is not finite");
}

/// The listed vertices of one attribute (`width` floats each) whose bits differ, into `out`.
void capture_listed(const float* base, const float* edited, std::uint32_t width,
                    std::span<const std::uint32_t> vertices, AttributeDiff& out) {
  out.indices.clear();
  out.values.clear();
  for (const std::uint32_t v : vertices) {
    const float* e = edited + std::size_t{v} * width;
    if (same_bits(base + std::size_t{v} * width, e, width)) continue;
    out.indices.push_back(v);
    out.values.insert(out.values.end(), e, e + width);
  }
}

void check_listed(std::span<const std::uint32_t> vertices, std::size_t vertex_count) {
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    if (vertices[i] >= vertex_count)
      throw InvalidInput("capture_diff_at: vertex " + std::to_string(vertices[i]) +
                         " out of range (" + std::to_string(vertex_count) + " vertices)");
    if (i > 0 && vertices[i] <= vertices[i - 1])
      throw InvalidInput("capture_diff_at: vertices not strictly increasing at entry " +
                         std::to_string(i));
  }
}

}  // namespace

std::size_t Diff::touched_vertices() const {
  std::vector<std::uint32_t> all(positions.indices);
  for (const auto& c : channels)
    all.insert(all.end(), c.change.indices.begin(), c.change.indices.end());
  std::sort(all.begin(), all.end());
  return static_cast<std::size_t>(std::unique(all.begin(), all.end()) - all.begin());
}

AttributeDiff capture_attribute(std::span<const float> base, std::span<const float> edited,
                                std::uint32_t width) {
  if (width == 0) throw InvalidInput("capture_attribute: width 0");
  if (base.size() != edited.size() || base.size() % width != 0)
    throw InvalidInput("capture_attribute: " + std::to_string(base.size()) + " base and " +
                       std::to_string(edited.size()) +
                       " edited values are not the same whole vertices of width " +
                       std::to_string(width));
  AttributeDiff d;
  const std::size_t n = base.size() / width;
  for (std::size_t v = 0; v < n; ++v) {
    const float* b = base.data() + v * width;
    const float* e = edited.data() + v * width;
    if (!same_bits(b, e, width)) {
      d.indices.push_back(static_cast<std::uint32_t>(v));
      d.values.insert(d.values.end(), e, e + width);
    }
  }
  return d;
}

Diff capture_diff(const Mesh& base, const Mesh& edited) {
  check_same_connectivity(base, edited, "edited mesh");
  Diff d;
  d.vertex_count = static_cast<std::uint32_t>(base.vertex_count());
  static_assert(sizeof(Vec3f) == 3 * sizeof(float));
  d.positions = capture_attribute(
      {reinterpret_cast<const float*>(base.positions.data()), base.positions.size() * 3},
      {reinterpret_cast<const float*>(edited.positions.data()), edited.positions.size() * 3}, 3);
  for (std::size_t c = 0; c < base.channels.size(); ++c) {
    const Channel& b = base.channels[c];
    const Channel& e = edited.channels[c];
    d.channels.push_back({b.desc, capture_attribute(b.values, e.values, b.desc.width)});
  }
  return d;
}

void clear_to_layout(Diff& d, const Mesh& base) {
  d.vertex_count = static_cast<std::uint32_t>(base.vertex_count());
  d.positions.indices.clear();
  d.positions.values.clear();
  d.channels.resize(base.channels.size());
  for (std::size_t c = 0; c < base.channels.size(); ++c) {
    d.channels[c].desc = base.channels[c].desc;
    d.channels[c].change.indices.clear();
    d.channels[c].change.values.clear();
  }
}

void capture_diff_at(const Mesh& base, const Mesh& edited, std::span<const std::uint32_t> vertices,
                     Diff& out) {
  if (edited.vertex_count() != base.vertex_count() ||
      edited.channels.size() != base.channels.size())
    throw InvalidInput("capture_diff_at: the edited mesh's vertices or channels differ");
  for (std::size_t c = 0; c < base.channels.size(); ++c)
    if (edited.channels[c].desc.width != base.channels[c].desc.width ||
        edited.channels[c].values.size() != base.channels[c].values.size())
      throw InvalidInput("capture_diff_at: channel '" + base.channels[c].desc.name + "' differs");
  check_listed(vertices, base.vertex_count());
  clear_to_layout(out, base);
  capture_listed(reinterpret_cast<const float*>(base.positions.data()),
                 reinterpret_cast<const float*>(edited.positions.data()), 3, vertices,
                 out.positions);
  for (std::size_t c = 0; c < base.channels.size(); ++c) {
    const Channel& b = base.channels[c];
    capture_listed(b.values.data(), edited.channels[c].values.data(), b.desc.width, vertices,
                   out.channels[c].change);
  }
}

void validate(const Diff& diff, const Mesh& base, std::string_view what) {
  if (diff.vertex_count != base.vertex_count())
    throw InvalidInput(std::string(what) + ": diff is for " + std::to_string(diff.vertex_count) +
                       " vertices but the mesh has " + std::to_string(base.vertex_count()));
  validate_attribute(diff.positions, 3, diff.vertex_count, what, "positions");
  for (const ChannelDiff& c : diff.channels) {
    const int index = base.find_channel(c.desc.name);
    if (index < 0)
      throw InvalidInput(std::string(what) + ": channel '" + c.desc.name +
                         "' does not exist in the mesh");
    if (base.channels[static_cast<std::size_t>(index)].desc.width != c.desc.width)
      throw InvalidInput(std::string(what) + ": channel '" + c.desc.name + "' has width " +
                         std::to_string(c.desc.width) + " but the mesh's has " +
                         std::to_string(base.channels[static_cast<std::size_t>(index)].desc.width));
    validate_attribute(c.change, c.desc.width, diff.vertex_count, what, "channel " + c.desc.name);
  }
}

void apply_diff(const Diff& diff, Mesh& mesh) {
  validate(diff, mesh, "apply_diff");
  for (std::size_t i = 0; i < diff.positions.indices.size(); ++i) {
    const float* v = diff.positions.values.data() + 3 * i;
    mesh.positions[diff.positions.indices[i]] = {v[0], v[1], v[2]};
  }
  for (const ChannelDiff& c : diff.channels) {
    Channel& target = mesh.channels[static_cast<std::size_t>(mesh.find_channel(c.desc.name))];
    const std::uint32_t w = c.desc.width;
    for (std::size_t i = 0; i < c.change.indices.size(); ++i)
      std::copy_n(c.change.values.data() + w * i, w,
                  target.values.data() + std::size_t{w} * c.change.indices[i]);
  }
}

DiffStats diff_stats(const Diff& diff, const Mesh& base) {
  DiffStats s;
  s.vertices = diff.vertex_count;
  s.position_changes = static_cast<std::uint32_t>(diff.positions.size());
  s.edited_fraction =
      diff.vertex_count ? static_cast<double>(diff.touched_vertices()) / diff.vertex_count : 0.0;
  s.bbox_diagonal = bbox_diagonal(base.positions);
  double sum2 = 0;
  for (std::size_t i = 0; i < diff.positions.size(); ++i) {
    const Vec3f& b = base.positions[diff.positions.indices[i]];
    const float* e = diff.positions.values.data() + 3 * i;
    const double dx = double(e[0]) - b.x, dy = double(e[1]) - b.y, dz = double(e[2]) - b.z;
    const double d2 = dx * dx + dy * dy + dz * dz;
    sum2 += d2;
    s.max_displacement = std::max(s.max_displacement, std::sqrt(d2));
  }
  s.rms_displacement = diff.positions.size() ? std::sqrt(sum2 / double(diff.positions.size())) : 0;
  for (const ChannelDiff& c : diff.channels) {
    DiffStats::Channel cs{c.desc.name, static_cast<std::uint32_t>(c.change.size()), 0};
    const int index = base.find_channel(c.desc.name);
    if (index >= 0) {
      const auto& values = base.channels[static_cast<std::size_t>(index)].values;
      for (std::size_t i = 0; i < c.change.values.size(); ++i) {
        const std::size_t v = c.change.indices[i / c.desc.width];
        const double d =
            std::abs(double(c.change.values[i]) - values[v * c.desc.width + i % c.desc.width]);
        cs.max_change = std::max(cs.max_change, d);
      }
    }
    s.channels.push_back(cs);
  }
  return s;
}

namespace {

/// A JSON number, or null where the value overflowed (JSON has no inf or nan: a mesh with
/// coordinates near FLT_MAX has an infinite bounding-box diagonal).
struct JsonNumber {
  double value;
  friend std::ostream& operator<<(std::ostream& o, JsonNumber n) {
    return std::isfinite(n.value) ? o << n.value : o << "null";
  }
};

}  // namespace

std::string to_json(const DiffStats& s) {
  std::ostringstream o;
  o.precision(6);
  o << "{\"vertices\":" << s.vertices << ",\"position_changes\":" << s.position_changes
    << ",\"edited_fraction\":" << JsonNumber{s.edited_fraction}
    << ",\"max_displacement\":" << JsonNumber{s.max_displacement}
    << ",\"rms_displacement\":" << JsonNumber{s.rms_displacement}
    << ",\"bbox_diagonal\":" << JsonNumber{s.bbox_diagonal} << ",\"channels\":[";
  for (std::size_t i = 0; i < s.channels.size(); ++i)
    o << (i ? "," : "") << "{\"name\":\"" << s.channels[i].name
      << "\",\"changes\":" << s.channels[i].changes
      << ",\"max_change\":" << JsonNumber{s.channels[i].max_change} << "}";
  o << "]}";
  return o.str();
}

std::uint64_t digest(const Diff& diff) {
  std::uint64_t h = hash_seed;
  h = hash_bytes(h, &diff.vertex_count, sizeof diff.vertex_count);
  h = hash_bytes(h, diff.positions.indices.data(), diff.positions.indices.size() * 4);
  h = hash_bytes(h, diff.positions.values.data(), diff.positions.values.size() * 4);
  for (const auto& c : diff.channels) {
    h = hash_bytes(h, c.desc.name.data(), c.desc.name.size());
    h = hash_bytes(h, c.change.indices.data(), c.change.indices.size() * 4);
    h = hash_bytes(h, c.change.values.data(), c.change.values.size() * 4);
  }
  return h;
}

}  // namespace csculpt
