// STL, binary and ascii. STL stores each facet's corners separately; corners with exactly
// equal coordinates are welded (in order of first occurrence, so the result is deterministic)
// to recover the shared vertices a merge needs.
#include <array>
#include <bit>
#include <cmath>
#include <unordered_map>

#include "csculpt/io.h"
#include "io_detail.h"

namespace csculpt {
namespace {

using io_detail::cat;
using io_detail::quote;

struct Key {
  std::uint32_t bits[3];
  friend bool operator==(const Key&, const Key&) = default;
};

struct KeyHash {
  std::size_t operator()(const Key& k) const {
    std::uint64_t h = 0x9E3779B97F4A7C15ull;
    for (std::uint32_t b : k.bits) {
      h ^= b;
      h *= 0xBF58476D1CE4E5B9ull;
      h ^= h >> 31;
    }
    return static_cast<std::size_t>(h);
  }
};

// Welds corners with bitwise-equal coordinates and adds facets as triangles.
class Welder {
 public:
  explicit Welder(Mesh& mesh, std::size_t expected_facets) : mesh_(mesh) {
    index_.reserve(expected_facets / 2);
    mesh_.triangles.reserve(expected_facets);
  }

  // A facet with two equal corners has zero area and no orientation; STL exporters emit such
  // slivers routinely (the Spider model has some), and as STL has no connectivity nothing
  // refers to them. They are dropped before welding so they leave no stray vertex behind.
  void add_facet(const std::array<Vec3f, 3>& corners) {
    std::array<Key, 3> keys;
    for (std::size_t c = 0; c < 3; ++c) keys[c] = key_of(corners[c]);
    if (keys[0] == keys[1] || keys[1] == keys[2] || keys[0] == keys[2]) {
      ++dropped_;
      return;
    }
    Triangle t;
    for (std::size_t c = 0; c < 3; ++c) {
      const auto [it, inserted] =
          index_.try_emplace(keys[c], static_cast<std::uint32_t>(mesh_.positions.size()));
      if (inserted) mesh_.positions.push_back(corners[c]);
      t[c] = it->second;
    }
    mesh_.triangles.push_back(t);
  }

  std::size_t dropped() const { return dropped_; }

 private:
  static Key key_of(const Vec3f& p) {
    // +0.0f turns -0 into +0 so that the two zeros, which compare equal, weld together.
    return Key{{std::bit_cast<std::uint32_t>(p.x + 0.0f), std::bit_cast<std::uint32_t>(p.y + 0.0f),
                std::bit_cast<std::uint32_t>(p.z + 0.0f)}};
  }

  Mesh& mesh_;
  std::unordered_map<Key, std::uint32_t, KeyHash> index_;
  std::size_t dropped_ = 0;
};

float load_f32_le(const unsigned char* p) {
  const std::uint32_t bits = std::uint32_t{p[0]} | std::uint32_t{p[1]} << 8 |
                             std::uint32_t{p[2]} << 16 | std::uint32_t{p[3]} << 24;
  return std::bit_cast<float>(bits);
}

void check_finite(const Vec3f& p, std::string_view where) {
  const float xyz[3] = {p.x, p.y, p.z};
  for (int k = 0; k < 3; ++k) {
    if (!std::isfinite(xyz[k])) {
      throw InvalidInput(cat(where, ": ", "xyz"[k], " is ", io_detail::non_finite_name(xyz[k])));
    }
  }
}

Mesh parse_binary(std::string_view bytes, std::uint64_t count, std::string_view what) {
  Mesh mesh;
  const auto n = static_cast<std::size_t>(count);
  Welder welder(mesh, n);
  const auto* data = reinterpret_cast<const unsigned char*>(bytes.data());
  for (std::size_t f = 0; f < n; ++f) {
    const unsigned char* facet = data + 84 + 50 * f + 12;  // skip the normal
    std::array<Vec3f, 3> corners;
    for (std::size_t c = 0; c < 3; ++c) {
      const unsigned char* v = facet + 12 * c;
      corners[c] = {load_f32_le(v), load_f32_le(v + 4), load_f32_le(v + 8)};
      check_finite(corners[c], cat(what, ": facet ", f, ": vertex ", c));
    }
    welder.add_facet(corners);
  }
  return mesh;
}

bool equals_ci(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    char c = a[i];
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
    if (c != b[i]) return false;
  }
  return true;
}

// Whitespace tokens with line numbers; solid names run to the end of their line.
class Lexer {
 public:
  Lexer(std::string_view text, std::string_view what) : rest_(text), what_(what) {}

  std::string_view next() {
    std::size_t i = 0;
    while (i < rest_.size() && io_detail::is_space(rest_[i])) {
      if (rest_[i] == '\n') ++line_;
      ++i;
    }
    std::size_t j = i;
    while (j < rest_.size() && !io_detail::is_space(rest_[j])) ++j;
    const std::string_view token = rest_.substr(i, j - i);
    rest_.remove_prefix(j);
    return token;
  }

  void skip_line() {
    const std::size_t nl = rest_.find('\n');
    rest_.remove_prefix(nl == std::string_view::npos ? rest_.size() : nl);
  }

  void expect(std::string_view keyword) {
    const std::string_view token = next();
    if (!equals_ci(token, keyword)) {
      throw InvalidInput(cat(where(), ": expected '", keyword, "', got ",
                             token.empty() ? std::string("end of file") : quote(token)));
    }
  }

  float number() {
    const std::string_view token = next();
    float f = 0;
    if (!io_detail::parse_float(token, f)) {
      throw InvalidInput(cat(where(), ": expected a number, got ",
                             token.empty() ? std::string("end of file") : quote(token)));
    }
    return f;
  }

  std::string where() const { return cat(what_, ":", line_); }

 private:
  std::string_view rest_;
  std::string_view what_;
  std::size_t line_ = 1;
};

Mesh parse_ascii(std::string_view bytes, std::string_view what) {
  Mesh mesh;
  // An ascii facet takes well over 100 bytes; this bounds the reservation by the file size.
  Welder welder(mesh, bytes.size() / 128);
  Lexer lex(bytes, what);
  std::size_t facet = 0;
  for (std::string_view token = lex.next(); !token.empty(); token = lex.next()) {
    if (token.size() < 5 || !equals_ci(token.substr(0, 5), "solid")) {
      throw InvalidInput(cat(lex.where(), ": expected 'solid', got ", quote(token)));
    }
    lex.skip_line();  // the solid's name
    for (;;) {
      token = lex.next();
      if (equals_ci(token, "endsolid")) {
        lex.skip_line();
        break;
      }
      if (!equals_ci(token, "facet")) {
        throw InvalidInput(cat(lex.where(), ": expected 'facet' or 'endsolid', got ",
                               token.empty() ? std::string("end of file") : quote(token)));
      }
      // The normal is recomputed by whoever needs it; some exporters even write NaN here.
      lex.expect("normal");
      for (int k = 0; k < 3; ++k) lex.next();
      lex.expect("outer");
      lex.expect("loop");
      std::array<Vec3f, 3> corners;
      std::size_t count = 0;
      for (token = lex.next(); equals_ci(token, "vertex"); token = lex.next()) {
        Vec3f p;
        p.x = lex.number();
        p.y = lex.number();
        p.z = lex.number();
        check_finite(p, cat(lex.where(), ": facet ", facet));
        if (count == 3) {
          throw InvalidInput(cat(lex.where(), ": facet ", facet,
                                 " has more than 3 vertices (STL facets are triangles)"));
        }
        corners[count++] = p;
      }
      if (!equals_ci(token, "endloop")) {
        throw InvalidInput(cat(lex.where(), ": expected 'vertex' or 'endloop', got ",
                               token.empty() ? std::string("end of file") : quote(token)));
      }
      if (count != 3) {
        throw InvalidInput(cat(lex.where(), ": facet ", facet, " has ", count,
                               " vertices (STL facets are triangles)"));
      }
      lex.expect("endfacet");
      welder.add_facet(corners);
      ++facet;
    }
  }
  return mesh;
}

}  // namespace

Mesh parse_stl(std::string_view bytes, std::string_view what, Faces faces) {
  if (bytes.empty()) throw InvalidInput(cat(what, ": file is empty"));
  std::uint64_t count = 0;
  if (bytes.size() >= 84) {
    for (std::size_t i = 84; i-- > 80;) count = count << 8 | static_cast<unsigned char>(bytes[i]);
  }
  std::string_view rest = bytes;
  const std::string_view first = io_detail::next_token(rest);
  const bool starts_with_solid = first.size() >= 5 && equals_ci(first.substr(0, 5), "solid");
  Mesh mesh;
  // Binary files may begin with "solid" too, so the size test comes first.
  if (bytes.size() >= 84 && 84 + 50 * count == bytes.size()) {
    mesh = parse_binary(bytes, count, what);
  } else if (starts_with_solid) {
    mesh = parse_ascii(bytes, what);
  } else if (bytes.size() >= 84) {
    throw InvalidInput(cat(what, ": binary STL header claims ", count, " facets (", 84 + 50 * count,
                           " bytes) but the file has ", bytes.size(), " bytes"));
  } else {
    throw InvalidInput(
        cat(what, ": not an STL file (too short for binary STL and does not start with 'solid')"));
  }
  validate(mesh, what, faces);
  return mesh;
}

}  // namespace csculpt
