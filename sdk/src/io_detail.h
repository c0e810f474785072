// Helpers shared by the mesh readers and writers (not part of the public API).
#pragma once

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <sstream>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "csculpt/error.h"
#include "csculpt/mesh.h"

namespace csculpt::io_detail {

template <class... Args>
std::string cat(const Args&... args) {
  std::ostringstream out;
  (out << ... << args);
  return out.str();
}

inline bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f';
}

inline std::string_view trim(std::string_view s) {
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

/// Splits off the next whitespace-separated token of `s` (empty when none is left).
inline std::string_view next_token(std::string_view& s) {
  std::size_t i = 0;
  while (i < s.size() && is_space(s[i])) ++i;
  std::size_t j = i;
  while (j < s.size() && !is_space(s[j])) ++j;
  std::string_view token = s.substr(i, j - i);
  s.remove_prefix(j);
  return token;
}

/// Shortens a token quoted in an error message so a garbage file cannot make it huge.
inline std::string quote(std::string_view token) {
  constexpr std::size_t kMax = 40;
  std::string out = "'";
  for (char c : token.substr(0, kMax)) {
    const auto u = static_cast<unsigned char>(c);
    out += u >= 0x20 && u < 0x7f ? c : '?';
  }
  if (token.size() > kMax) out += "...";
  return out + "'";
}

/// For a syntactically valid decimal number that from_chars found out of range: whether its
/// magnitude is below one (underflow, which means zero) rather than above (overflow).
inline bool below_one(std::string_view t) {
  if (!t.empty() && (t[0] == '+' || t[0] == '-')) t.remove_prefix(1);
  const std::size_t e = t.find_first_of("eE");
  std::int64_t exp10 = 0;
  if (e != std::string_view::npos) {
    std::string_view digits = t.substr(e + 1);
    const bool negative = !digits.empty() && digits[0] == '-';
    if (!digits.empty() && (digits[0] == '+' || digits[0] == '-')) digits.remove_prefix(1);
    for (char c : digits) {
      if (c < '0' || c > '9') break;
      exp10 = std::min<std::int64_t>(exp10 * 10 + (c - '0'), 1'000'000'000);
    }
    if (negative) exp10 = -exp10;
    t = t.substr(0, e);
  }
  std::size_t dot = t.find('.');
  if (dot == std::string_view::npos) dot = t.size();
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (t[i] >= '1' && t[i] <= '9') {
      // Power of ten of the leading significant digit.
      const auto lead =
          i < dot ? static_cast<std::int64_t>(dot - i - 1) : -static_cast<std::int64_t>(i - dot);
      return lead + exp10 < 0;
    }
  }
  return true;
}

/// Parses a whole token as a float with correct rounding (so text written with enough
/// digits reads back bit-exactly). Accepts a leading '+', which from_chars does not.
/// Values too small for a float become a signed zero; too large ones fail.
inline bool parse_float(std::string_view token, float& out) {
  if (token.size() > 1 && token[0] == '+' && token[1] != '-') token.remove_prefix(1);
  const char* end = token.data() + token.size();
  auto [ptr, ec] = std::from_chars(token.data(), end, out);
  if (ptr != end || token.empty()) return false;
  if (ec == std::errc::result_out_of_range && below_one(token)) {
    out = token[0] == '-' ? -0.f : 0.f;
    return true;
  }
  return ec == std::errc();
}

/// As parse_float, for double.
inline bool parse_double(std::string_view token, double& out) {
  if (token.size() > 1 && token[0] == '+' && token[1] != '-') token.remove_prefix(1);
  const char* end = token.data() + token.size();
  auto [ptr, ec] = std::from_chars(token.data(), end, out);
  if (ptr != end || token.empty()) return false;
  if (ec == std::errc::result_out_of_range && below_one(token)) {
    out = token[0] == '-' ? -0.0 : 0.0;
    return true;
  }
  return ec == std::errc();
}

inline bool parse_int(std::string_view token, std::int64_t& out) {
  if (token.size() > 1 && token[0] == '+' && token[1] != '-') token.remove_prefix(1);
  const char* end = token.data() + token.size();
  auto [ptr, ec] = std::from_chars(token.data(), end, out);
  return ec == std::errc() && ptr == end && !token.empty();
}

inline bool parse_uint(std::string_view token, std::uint64_t& out) {
  const char* end = token.data() + token.size();
  auto [ptr, ec] = std::from_chars(token.data(), end, out);
  return ec == std::errc() && ptr == end && !token.empty();
}

/// A double narrowed to float; finite values beyond the float range become +-Inf explicitly
/// (a plain cast would be undefined behaviour) so validation reports them.
inline float narrow(double d) {
  constexpr double kMax = std::numeric_limits<float>::max();
  if (d > kMax) return std::numeric_limits<float>::infinity();
  if (d < -kMax) return -std::numeric_limits<float>::infinity();
  return static_cast<float>(d);
}

inline const char* non_finite_name(double v) {
  if (std::isnan(v)) return "NaN";
  return v > 0 ? "+Inf" : "-Inf";
}

/// Fan-triangulates a polygon into `out`. Returns an empty string on success, otherwise what
/// is wrong with the polygon, for the caller to prefix with its location.
inline std::string append_fan(std::span<const std::uint32_t> poly, std::vector<Triangle>& out) {
  if (poly.size() < 3) {
    return cat("has ", poly.size(), " vertices (need at least 3)");
  }
  for (std::size_t i = 1; i + 1 < poly.size(); ++i) {
    const Triangle t{poly[0], poly[i], poly[i + 1]};
    if (t[0] == t[1] || t[0] == t[2] || t[1] == t[2]) {
      const std::uint32_t repeated = t[0] == t[1] || t[0] == t[2] ? t[0] : t[1];
      return cat("repeats vertex ", repeated, " (degenerate triangle)");
    }
    out.push_back(t);
  }
  return {};
}

/// Past this many unused vertices, and more than half of all, a file is rejected (read_mesh).
constexpr std::size_t kMaxUnreferencedVertices = 1'000'000;

/// Throws InvalidInput naming `what` and the counts when more than kMaxUnreferencedVertices
/// vertices, and more than half of them, are used by no triangle.
void check_unreferenced(const Mesh& mesh, std::string_view what);

/// What every parser checks of the mesh it read: validate(), and, when it has faces, that
/// they use enough of its vertices (check_unreferenced). A point set uses none.
void check_parsed(const Mesh& mesh, std::string_view what, Faces faces);

/// Serialises a validated mesh as binary little-endian PLY / as OBJ; `what` names the
/// destination in error messages.
std::string encode_ply(const Mesh& mesh, std::string_view what);
std::string encode_obj(const Mesh& mesh, std::string_view what);

}  // namespace csculpt::io_detail
