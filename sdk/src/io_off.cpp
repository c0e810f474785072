// Object File Format: "[ST][C][N]OFF", a counts line, one vertex per line, one polygon per
// line. Per-vertex extras of the variants (texture coordinates, colours, normals) and face
// colours follow the fields we need on the same line and are ignored.
#include <cmath>

#include "csculpt/io.h"
#include "io_detail.h"

namespace csculpt {
namespace {

using io_detail::cat;
using io_detail::quote;

// Meaningful lines: comments ('#' to the end of the line) and blank lines skipped.
class Lines {
 public:
  explicit Lines(std::string_view text) : text_(text) {}

  bool next(std::string_view& line) {
    while (pos_ < text_.size()) {
      std::size_t nl = text_.find('\n', pos_);
      if (nl == std::string_view::npos) nl = text_.size();
      line = text_.substr(pos_, nl - pos_);
      pos_ = nl + 1;
      ++line_no_;
      if (const std::size_t hash = line.find('#'); hash != std::string_view::npos) {
        line = line.substr(0, hash);
      }
      if (!io_detail::trim(line).empty()) return true;
    }
    return false;
  }

  std::size_t line_no() const { return line_no_; }
  std::size_t remaining() const { return pos_ < text_.size() ? text_.size() - pos_ : 0; }

 private:
  std::string_view text_;
  std::size_t pos_ = 0;
  std::size_t line_no_ = 0;
};

}  // namespace

Mesh parse_off(std::string_view bytes, std::string_view what, Faces faces) {
  if (bytes.empty()) throw InvalidInput(cat(what, ": file is empty"));
  if (bytes.starts_with("\xEF\xBB\xBF")) bytes.remove_prefix(3);
  Lines lines(bytes);
  std::string_view line;
  if (!lines.next(line)) throw InvalidInput(cat(what, ": no OFF header"));
  std::string_view rest = line;
  const std::string_view keyword = io_detail::next_token(rest);
  if (!keyword.ends_with("OFF")) {
    throw InvalidInput(cat(what, ":", lines.line_no(), ": not an OFF file (expected 'OFF', got ",
                           quote(keyword), ")"));
  }
  const std::string_view prefix = keyword.substr(0, keyword.size() - 3);
  for (std::string_view p = prefix; !p.empty();) {
    if (p.starts_with("ST")) {
      p.remove_prefix(2);
    } else if (p[0] == 'C' || p[0] == 'N') {
      p.remove_prefix(1);
    } else {
      throw InvalidInput(cat(what, ":", lines.line_no(), ": unsupported OFF variant ",
                             quote(keyword), " (only 3-D [ST][C][N]OFF is supported)"));
    }
  }

  // The counts may follow the keyword on the same line.
  std::string_view counts = rest;
  if (io_detail::trim(counts).starts_with("BINARY")) {
    throw InvalidInput(cat(what, ":", lines.line_no(), ": binary OFF is not supported"));
  }
  if (io_detail::trim(counts).empty()) {
    if (!lines.next(counts)) throw InvalidInput(cat(what, ": no counts line after the header"));
  }
  const std::size_t counts_line = lines.line_no();
  const std::string_view counts_text = io_detail::trim(counts);
  std::uint64_t nv = 0;
  std::uint64_t nf = 0;
  const std::string_view nv_text = io_detail::next_token(counts);
  const std::string_view nf_text = io_detail::next_token(counts);
  if (!io_detail::parse_uint(nv_text, nv) || !io_detail::parse_uint(nf_text, nf)) {
    throw InvalidInput(cat(what, ":", counts_line,
                           ": expected '<vertices> <faces> [<edges>]', got ", quote(counts_text)));
  }
  // Each vertex needs at least "0 0 0" and a newline, each face "3 0 1 2" and a newline:
  // reject impossible counts before reserving anything.
  const std::uint64_t remaining = lines.remaining() + 1;
  if (nv > remaining / 6 || nf > remaining / 8 || nv * 6 + nf * 8 > remaining) {
    throw InvalidInput(cat(what, ":", counts_line, ": header claims ", nv, " vertices and ", nf,
                           " faces, but only ", lines.remaining(), " bytes follow"));
  }

  Mesh mesh;
  mesh.positions.reserve(static_cast<std::size_t>(nv));
  mesh.triangles.reserve(static_cast<std::size_t>(nf));
  for (std::uint64_t v = 0; v < nv; ++v) {
    if (!lines.next(line)) {
      throw InvalidInput(cat(what, ": unexpected end of file after ", v, " of ", nv, " vertices"));
    }
    float xyz[3];
    for (int k = 0; k < 3; ++k) {
      const std::string_view token = io_detail::next_token(line);
      if (token.empty()) {
        throw InvalidInput(
            cat(what, ":", lines.line_no(), ": vertex ", v, " has ", k, " coordinates, need 3"));
      }
      if (!io_detail::parse_float(token, xyz[k])) {
        throw InvalidInput(
            cat(what, ":", lines.line_no(), ": vertex ", v, ": bad coordinate ", quote(token)));
      }
      if (!std::isfinite(xyz[k])) {
        throw InvalidInput(cat(what, ":", lines.line_no(), ": vertex ", v, ": ", "xyz"[k], " is ",
                               io_detail::non_finite_name(xyz[k])));
      }
    }
    mesh.positions.push_back({xyz[0], xyz[1], xyz[2]});
  }
  std::vector<std::uint32_t> poly;
  for (std::uint64_t f = 0; f < nf; ++f) {
    if (!lines.next(line)) {
      throw InvalidInput(cat(what, ": unexpected end of file after ", f, " of ", nf, " faces"));
    }
    const std::string_view count_text = io_detail::next_token(line);
    std::uint64_t n = 0;
    if (!io_detail::parse_uint(count_text, n)) {
      throw InvalidInput(
          cat(what, ":", lines.line_no(), ": face ", f, ": bad vertex count ", quote(count_text)));
    }
    poly.clear();
    for (std::uint64_t i = 0; i < n; ++i) {
      const std::string_view token = io_detail::next_token(line);
      std::int64_t index = 0;
      if (token.empty()) {
        throw InvalidInput(cat(what, ":", lines.line_no(), ": face ", f, " has ", i,
                               " indices, its count says ", n));
      }
      if (!io_detail::parse_int(token, index)) {
        throw InvalidInput(
            cat(what, ":", lines.line_no(), ": face ", f, ": bad vertex index ", quote(token)));
      }
      if (index < 0 || static_cast<std::uint64_t>(index) >= nv) {
        throw InvalidInput(cat(what, ":", lines.line_no(), ": face ", f, ": vertex index ", index,
                               " out of range (", nv, " vertices)"));
      }
      poly.push_back(static_cast<std::uint32_t>(index));
    }
    const std::string problem = io_detail::append_fan(poly, mesh.triangles);
    if (!problem.empty()) {
      throw InvalidInput(cat(what, ":", lines.line_no(), ": face ", f, " ", problem));
    }
  }
  io_detail::check_parsed(mesh, what, faces);
  return mesh;
}

}  // namespace csculpt
