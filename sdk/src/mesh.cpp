#include "csculpt/mesh.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <string>
#include <unordered_set>

#include "csculpt/error.h"

namespace csculpt {
namespace {

template <class... Args>
std::string cat(const Args&... args) {
  std::ostringstream out;
  (out << ... << args);
  return out.str();
}

// Names a non-finite value the way a person reading the message expects.
const char* non_finite_name(float v) {
  if (std::isnan(v)) return "NaN";
  return v > 0 ? "+Inf" : "-Inf";
}

constexpr char kComponentNames[] = {'r', 'g', 'b', 'a'};

std::string describe(const ChannelDesc& d) {
  char range[64];
  std::snprintf(range, sizeof range, "[%g, %g]", double(d.min_value), double(d.max_value));
  return cat(d.name, " (width ", d.width, ", ", to_string(d.linearisation), ", range ", range, ")");
}

// sRGB transfer functions on [0, inf), evaluated in double so that a float survives the
// round trip stored -> linear -> stored (the merge relies on unchanged values staying
// bit-identical).
double srgb_eotf(double v) {
  return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
}
double srgb_oetf(double l) {
  return l <= 0.0031308 ? l * 12.92 : 1.055 * std::pow(l, 1.0 / 2.4) - 0.055;
}

// Odd extension: merged deltas can push a value slightly below 0, and a plain square root
// or power of a negative number would turn it into NaN.
template <class F>
float odd(F f, float v) {
  const double a = std::fabs(static_cast<double>(v));
  const double r = f(a);
  return static_cast<float>(v < 0 ? -r : r);
}

}  // namespace

std::string_view to_string(Linearisation lin) {
  switch (lin) {
    case Linearisation::identity:
      return "identity";
    case Linearisation::square:
      return "square";
    case Linearisation::srgb:
      return "srgb";
  }
  return "unknown";
}

Linearisation linearisation_from_string(std::string_view name) {
  if (name == "identity" || name == "linear") return Linearisation::identity;
  if (name == "square") return Linearisation::square;
  if (name == "srgb") return Linearisation::srgb;
  throw InvalidInput(
      cat("unknown linearisation '", name, "' (expected identity, linear, square or srgb)"));
}

Linearisation default_linearisation(std::string_view channel_name) {
  if (channel_name == "albedo") return Linearisation::srgb;
  if (channel_name == "roughness") return Linearisation::square;
  return Linearisation::identity;
}

float to_linear(Linearisation lin, float stored) {
  switch (lin) {
    case Linearisation::identity:
      return stored;
    case Linearisation::square:
      return odd([](double v) { return v * v; }, stored);
    case Linearisation::srgb:
      return odd(srgb_eotf, stored);
  }
  return stored;
}

float from_linear(Linearisation lin, float linear) {
  switch (lin) {
    case Linearisation::identity:
      return linear;
    case Linearisation::square:
      return odd([](double l) { return std::sqrt(l); }, linear);
    case Linearisation::srgb:
      return odd(srgb_oetf, linear);
  }
  return linear;
}

ChannelDesc default_channel(std::string_view name, std::uint32_t width) {
  ChannelDesc d{std::string(name), width, default_linearisation(name)};
  if (name == "albedo" || name == "metallic" || name == "roughness") {
    d.min_value = 0.f;
    d.max_value = 1.f;
  }
  return d;
}

std::vector<ChannelDesc> material_channels() {
  return {default_channel("albedo", 3), default_channel("metallic", 1),
          default_channel("roughness", 1)};
}

std::vector<float> default_material_fill(const ChannelDesc& desc) {
  const float value = desc.name == "albedo"      ? default_albedo
                      : desc.name == "metallic"  ? default_metallic
                      : desc.name == "roughness" ? default_roughness
                                                 : 0.f;
  return std::vector<float>(desc.width, value);
}

int Mesh::find_channel(std::string_view name) const {
  for (std::size_t i = 0; i < channels.size(); ++i) {
    if (channels[i].desc.name == name) return static_cast<int>(i);
  }
  return -1;
}

int Mesh::add_channel(const ChannelDesc& desc, std::span<const float> fill) {
  if (desc.name.empty()) throw InvalidInput("add_channel: empty channel name");
  if (desc.width < 1 || desc.width > 4) {
    throw InvalidInput(
        cat("add_channel: channel ", desc.name, " has width ", desc.width, " (must be 1..4)"));
  }
  if (!fill.empty() && fill.size() != desc.width) {
    throw InvalidInput(cat("add_channel: channel ", desc.name, ": fill has ", fill.size(),
                           " values, expected ", desc.width));
  }
  if (const int existing = find_channel(desc.name); existing >= 0) {
    // An existing channel of another width would silently change the meaning of the
    // caller's data; a different linearisation is the file's choice and is kept.
    const ChannelDesc& have = channels[static_cast<std::size_t>(existing)].desc;
    if (have.width != desc.width) {
      throw InvalidInput(cat("add_channel: channel ", desc.name, " already exists with width ",
                             have.width, ", not ", desc.width));
    }
    return existing;
  }
  Channel c;
  c.desc = desc;
  c.values.resize(vertex_count() * desc.width, 0.f);
  if (!fill.empty()) {
    for (std::size_t v = 0; v < vertex_count(); ++v) {
      std::copy(fill.begin(), fill.end(),
                c.values.begin() + static_cast<std::ptrdiff_t>(v * desc.width));
    }
  }
  channels.push_back(std::move(c));
  return static_cast<int>(channels.size() - 1);
}

void validate(const Mesh& mesh, std::string_view what, Faces faces) {
  const std::size_t n = mesh.vertex_count();
  if (n == 0) throw InvalidInput(cat(what, ": no vertices"));
  if (mesh.triangles.empty() && faces == Faces::required) {
    throw InvalidInput(cat(what, ": no faces (point clouds cannot be merged)"));
  }
  if (n > std::numeric_limits<std::uint32_t>::max()) {
    throw InvalidInput(cat(what, ": ", n, " vertices is more than 32-bit indices can address"));
  }
  for (std::size_t v = 0; v < n; ++v) {
    const Vec3f& p = mesh.positions[v];
    const float xyz[3] = {p.x, p.y, p.z};
    for (int k = 0; k < 3; ++k) {
      if (!std::isfinite(xyz[k])) {
        throw InvalidInput(
            cat(what, ": vertex ", v, ": position ", "xyz"[k], " is ", non_finite_name(xyz[k])));
      }
    }
  }
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Triangle& tri = mesh.triangles[t];
    for (std::uint32_t i : tri) {
      if (i >= n) {
        throw InvalidInput(
            cat(what, ": triangle ", t, ": vertex index ", i, " out of range (", n, " vertices)"));
      }
    }
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) {
      const std::uint32_t repeated = tri[0] == tri[1] || tri[0] == tri[2] ? tri[0] : tri[1];
      throw InvalidInput(cat(what, ": triangle ", t, " (", tri[0], ", ", tri[1], ", ", tri[2],
                             ") repeats vertex ", repeated));
    }
  }
  std::unordered_set<std::string_view> names;
  for (std::size_t c = 0; c < mesh.channels.size(); ++c) {
    const Channel& ch = mesh.channels[c];
    const ChannelDesc& d = ch.desc;
    if (d.name.empty()) throw InvalidInput(cat(what, ": channel ", c, " has an empty name"));
    if (!names.insert(d.name).second) {
      throw InvalidInput(cat(what, ": channel ", d.name, " appears twice"));
    }
    if (d.width < 1 || d.width > 4) {
      throw InvalidInput(
          cat(what, ": channel ", d.name, " has width ", d.width, " (must be 1..4)"));
    }
    if (ch.values.size() != n * d.width) {
      throw InvalidInput(cat(what, ": channel ", d.name, " has ", ch.values.size(),
                             " values, expected ", n * d.width, " (", n, " vertices x width ",
                             d.width, ")"));
    }
    for (std::size_t i = 0; i < ch.values.size(); ++i) {
      if (!std::isfinite(ch.values[i])) {
        const std::size_t v = i / d.width;
        const std::size_t k = i % d.width;
        std::string component = d.width == 1 ? std::string() : cat("_", kComponentNames[k]);
        throw InvalidInput(cat(what, ": vertex ", v, ": channel ", d.name, component, " is ",
                               non_finite_name(ch.values[i])));
      }
    }
  }
}

void check_same_connectivity(const Mesh& base, const Mesh& edited, std::string_view what) {
  if (edited.vertex_count() != base.vertex_count()) {
    throw InvalidInput(cat(what, ": ", edited.vertex_count(), " vertices, but the base has ",
                           base.vertex_count()));
  }
  if (edited.face_count() != base.face_count()) {
    throw InvalidInput(
        cat(what, ": ", edited.face_count(), " triangles, but the base has ", base.face_count()));
  }
  for (std::size_t t = 0; t < base.triangles.size(); ++t) {
    const Triangle& a = edited.triangles[t];
    const Triangle& b = base.triangles[t];
    if (a != b) {
      throw InvalidInput(cat(what, ": triangle ", t, " is (", a[0], ", ", a[1], ", ", a[2],
                             ") but in the base it is (", b[0], ", ", b[1], ", ", b[2], ")"));
    }
  }
  if (edited.channels.size() != base.channels.size()) {
    throw InvalidInput(cat(what, ": ", edited.channels.size(), " channels, but the base has ",
                           base.channels.size()));
  }
  for (std::size_t c = 0; c < base.channels.size(); ++c) {
    const ChannelDesc& a = edited.channels[c].desc;
    const ChannelDesc& b = base.channels[c].desc;
    if (!(a == b)) {
      throw InvalidInput(
          cat(what, ": channel ", c, " is ", describe(a), " but in the base it is ", describe(b)));
    }
  }
}

float bbox_diagonal(std::span<const Vec3f> positions) {
  if (positions.empty()) return 0.f;
  Vec3f lo = positions[0];
  Vec3f hi = positions[0];
  for (const Vec3f& p : positions) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  const double dx = static_cast<double>(hi.x) - lo.x;
  const double dy = static_cast<double>(hi.y) - lo.y;
  const double dz = static_cast<double>(hi.z) - lo.z;
  return static_cast<float>(std::sqrt(dx * dx + dy * dy + dz * dz));
}

}  // namespace csculpt
