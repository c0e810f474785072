// Wavefront OBJ: positions (v), their colours where a file has them (the common extension
// "v x y z r g b", read as the albedo channel) and faces (f); everything else (texture
// coordinates, normals, groups, materials, lines, points) is ignored because a merge only
// needs the surface and its material.
#include <algorithm>
#include <charconv>
#include <cmath>

#include "csculpt/io.h"
#include "io_detail.h"

namespace csculpt {
namespace {

using io_detail::cat;
using io_detail::quote;

// Calls fn(line_number, line) for every line, with the comment and the line ending removed.
template <class Fn>
void for_each_line(std::string_view text, Fn&& fn) {
  std::size_t pos = 0;
  std::size_t line_no = 0;
  while (pos < text.size()) {
    std::size_t nl = text.find('\n', pos);
    if (nl == std::string_view::npos) nl = text.size();
    std::string_view line = text.substr(pos, nl - pos);
    pos = nl + 1;
    ++line_no;
    if (const std::size_t hash = line.find('#'); hash != std::string_view::npos) {
      line = line.substr(0, hash);
    }
    fn(line_no, line);
  }
}

// A vertex colour's three components, each a finite number in [0, 1] (the extension's range;
// the albedo channel's).
void parse_colour(std::string_view rest, std::string_view what, std::size_t line_no,
                  std::size_t vertex, float rgb[3]) {
  for (int k = 0; k < 3; ++k) {
    const std::string_view token = io_detail::next_token(rest);
    if (!io_detail::parse_float(token, rgb[k]) || !std::isfinite(rgb[k])) {
      throw InvalidInput(cat(what, ":", line_no, ": bad vertex colour ", quote(token)));
    }
    if (rgb[k] < 0.f || rgb[k] > 1.f) {
      throw InvalidInput(cat(what, ":", line_no, ": vertex ", vertex, ": colour ", "rgb"[k], " is ",
                             rgb[k], ", outside [0, 1]"));
    }
  }
}

// How many more tokens `rest` holds.
std::size_t count_tokens(std::string_view rest) {
  std::size_t n = 0;
  while (!io_detail::next_token(rest).empty()) ++n;
  return n;
}

void append_float(std::string& out, float f) {
  // Shortest representation that reads back to the same float, independent of the locale
  // (printf's %g would print a decimal comma under some locales).
  char buf[32];
  const auto [ptr, ec] = std::to_chars(buf, buf + sizeof(buf), f);
  out.append(buf, ec == std::errc() ? static_cast<std::size_t>(ptr - buf) : 0);
}

void append_index(std::string& out, std::uint32_t zero_based) {
  char buf[24];
  const auto [ptr, ec] = std::to_chars(buf, buf + sizeof(buf), std::uint64_t{zero_based} + 1);
  out.append(buf, ec == std::errc() ? static_cast<std::size_t>(ptr - buf) : 0);
}

}  // namespace

Mesh parse_obj(std::string_view bytes, std::string_view what, Faces faces) {
  if (bytes.empty()) throw InvalidInput(cat(what, ": file is empty"));
  if (bytes.starts_with("\xFE\xFF") || bytes.starts_with("\xFF\xFE")) {
    throw InvalidInput(cat(what, ": UTF-16 encoded OBJ is not supported (save it as UTF-8)"));
  }
  if (bytes.starts_with("\xEF\xBB\xBF")) bytes.remove_prefix(3);
  if (const std::size_t nul = bytes.find('\0'); nul != std::string_view::npos) {
    const auto line =
        1 + std::count(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(nul), '\n');
    throw InvalidInput(cat(what, ":", line, ": NUL byte: not a text OBJ file (UTF-16 or binary?)"));
  }

  // First pass: count the vertices, so that a face may refer to a vertex defined later (as
  // several exporters do) while an index beyond the last vertex is still reported with its line.
  std::size_t total_vertices = 0;
  for_each_line(bytes, [&](std::size_t, std::string_view line) {
    std::string_view rest = line;
    if (io_detail::next_token(rest) == "v") ++total_vertices;
  });

  Mesh mesh;
  mesh.positions.reserve(total_vertices);
  // Vertex colours, when any vertex has one; a vertex without gets the default albedo.
  std::vector<float> colours;
  std::vector<std::uint32_t> poly;
  for_each_line(bytes, [&](std::size_t line_no, std::string_view line) {
    std::string_view rest = line;
    const std::string_view keyword = io_detail::next_token(rest);
    if (keyword == "v") {
      float xyz[3];
      for (int k = 0; k < 3; ++k) {
        const std::string_view token = io_detail::next_token(rest);
        if (token.empty()) {
          throw InvalidInput(cat(what, ":", line_no, ": vertex has ", k, " coordinates, need 3"));
        }
        if (!io_detail::parse_float(token, xyz[k])) {
          throw InvalidInput(cat(what, ":", line_no, ": bad vertex coordinate ", quote(token)));
        }
        if (!std::isfinite(xyz[k])) {
          throw InvalidInput(cat(what, ":", line_no, ": vertex ", mesh.positions.size(), ": ",
                                 "xyz"[k], " is ", io_detail::non_finite_name(xyz[k])));
        }
      }
      // Three more numbers are the vertex-colour extension's r g b; one (w) is ignored.
      if (count_tokens(rest) == 3) {
        if (colours.empty()) colours.assign(3 * total_vertices, default_albedo);
        parse_colour(rest, what, line_no, mesh.positions.size(),
                     &colours[3 * mesh.positions.size()]);
      }
      mesh.positions.push_back({xyz[0], xyz[1], xyz[2]});
    } else if (keyword == "f") {
      poly.clear();
      for (std::string_view token = io_detail::next_token(rest); !token.empty();
           token = io_detail::next_token(rest)) {
        // i, i/t, i//n or i/t/n: only the position index matters.
        const std::string_view index_text = token.substr(0, token.find('/'));
        std::int64_t index = 0;
        if (!io_detail::parse_int(index_text, index)) {
          throw InvalidInput(cat(what, ":", line_no, ": bad face index ", quote(token)));
        }
        std::int64_t resolved = 0;
        if (index > 0) {
          resolved = index - 1;
          if (static_cast<std::uint64_t>(resolved) >= total_vertices) {
            throw InvalidInput(cat(what, ":", line_no, ": face index ", index, " out of range (",
                                   total_vertices, " vertices)"));
          }
        } else if (index < 0) {
          // Relative to the vertices defined so far: -1 is the last one.
          resolved = static_cast<std::int64_t>(mesh.positions.size()) + index;
          if (resolved < 0) {
            throw InvalidInput(cat(what, ":", line_no, ": relative face index ", index,
                                   " is before the first vertex (", mesh.positions.size(),
                                   " vertices so far)"));
          }
        } else {
          throw InvalidInput(cat(what, ":", line_no, ": face index 0 (OBJ indices start at 1)"));
        }
        poly.push_back(static_cast<std::uint32_t>(resolved));
      }
      const std::string problem = io_detail::append_fan(poly, mesh.triangles);
      if (!problem.empty()) throw InvalidInput(cat(what, ":", line_no, ": face ", problem));
    }
  });
  if (!colours.empty()) mesh.channels.push_back({default_channel("albedo", 3), std::move(colours)});
  io_detail::check_parsed(mesh, what, faces);
  return mesh;
}

namespace io_detail {

std::string encode_obj(const Mesh& mesh, std::string_view what) {
  validate(mesh, what);
  std::string out = "# written by csculpt\n";
  out.reserve(out.size() + mesh.vertex_count() * 64 + mesh.face_count() * 24);
  // The albedo goes out as vertex colours (what readers of the extension show); the other
  // channels have no place in an OBJ: PLY keeps them.
  const int albedo = mesh.find_channel("albedo");
  const float* colours =
      albedo >= 0 && mesh.channels[static_cast<std::size_t>(albedo)].desc.width == 3
          ? mesh.channels[static_cast<std::size_t>(albedo)].values.data()
          : nullptr;
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
    const Vec3f& p = mesh.positions[v];
    out += "v ";
    append_float(out, p.x);
    out += ' ';
    append_float(out, p.y);
    out += ' ';
    append_float(out, p.z);
    for (int k = 0; colours && k < 3; ++k) {
      out += ' ';
      append_float(out, std::clamp(colours[3 * v + static_cast<std::size_t>(k)], 0.f, 1.f));
    }
    out += '\n';
  }
  for (const Triangle& t : mesh.triangles) {
    out += "f ";
    append_index(out, t[0]);
    out += ' ';
    append_index(out, t[1]);
    out += ' ';
    append_index(out, t[2]);
    out += '\n';
  }
  return out;
}

}  // namespace io_detail
}  // namespace csculpt
