// PLY reading (ascii, binary little and big endian) and writing (binary little endian).
//
// Vertex properties other than x, y, z become channels (see derive_channels); the face
// element's vertex_indices/vertex_index list gives polygons, fan-triangulated. Everything
// else (normals in lists, edges, materials, other face properties) is skipped, in all three
// encodings, by walking its declared layout.
//
// Index (section lines "// ----"): scalar types; channel layout (property names ->
// channels); header (parse_header and its lines); body cursors and reading (read_body);
// parse_ply; writing (encode_ply).
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <span>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include "csculpt/io.h"
#include "io_detail.h"

namespace csculpt {
namespace {

using io_detail::cat;
using io_detail::quote;

enum class Format { ascii, binary_le, binary_be };
enum class Scalar : std::uint8_t { i8, u8, i16, u16, i32, u32, f32, f64 };

std::optional<Scalar> scalar_from_name(std::string_view name) {
  static constexpr std::pair<std::string_view, Scalar> kNames[] = {
      {"char", Scalar::i8},     {"int8", Scalar::i8},     {"uchar", Scalar::u8},
      {"uint8", Scalar::u8},    {"short", Scalar::i16},   {"int16", Scalar::i16},
      {"ushort", Scalar::u16},  {"uint16", Scalar::u16},  {"int", Scalar::i32},
      {"int32", Scalar::i32},   {"uint", Scalar::u32},    {"uint32", Scalar::u32},
      {"float", Scalar::f32},   {"float32", Scalar::f32}, {"double", Scalar::f64},
      {"float64", Scalar::f64},
  };
  for (const auto& [n, s] : kNames) {
    if (n == name) return s;
  }
  return std::nullopt;
}

const char* name_of(Scalar s) {
  switch (s) {
    case Scalar::i8:
      return "char";
    case Scalar::u8:
      return "uchar";
    case Scalar::i16:
      return "short";
    case Scalar::u16:
      return "ushort";
    case Scalar::i32:
      return "int";
    case Scalar::u32:
      return "uint";
    case Scalar::f32:
      return "float";
    case Scalar::f64:
      return "double";
  }
  return "?";
}

std::size_t size_of(Scalar s) {
  switch (s) {
    case Scalar::i8:
    case Scalar::u8:
      return 1;
    case Scalar::i16:
    case Scalar::u16:
      return 2;
    case Scalar::i32:
    case Scalar::u32:
    case Scalar::f32:
      return 4;
    case Scalar::f64:
      return 8;
  }
  return 1;
}

bool is_integer(Scalar s) {
  return s != Scalar::f32 && s != Scalar::f64;
}

std::pair<std::int64_t, std::int64_t> integer_range(Scalar s) {
  switch (s) {
    case Scalar::i8:
      return {-128, 127};
    case Scalar::u8:
      return {0, 255};
    case Scalar::i16:
      return {-32768, 32767};
    case Scalar::u16:
      return {0, 65535};
    case Scalar::i32:
      return {-2147483648LL, 2147483647LL};
    case Scalar::u32:
      return {0, 4294967295LL};
    case Scalar::f32:
    case Scalar::f64:
      break;
  }
  return {0, 0};
}

// ---------------------------------------------------------------------------------------------
// Channel layout: how vertex property names map to channels. The writer runs the same
// derivation on the names it is about to write, so whatever it writes reads back unchanged.

struct Slot {
  int channel = -1;  // -1: the property is read but dropped (alpha of a red/green/blue colour)
  std::uint32_t component = 0;
  double scale = 1;  // integer colours map to [0,1]
};

struct ChannelLayout {
  std::vector<ChannelDesc> channels;
  std::vector<Slot> slots;  // one per input property
};

constexpr std::array<std::string_view, 4> kSuffixes = {"_r", "_g", "_b", "_a"};

int suffix_index(std::string_view name) {
  if (name.size() <= 2) return -1;
  for (std::size_t k = 0; k < kSuffixes.size(); ++k) {
    if (name.ends_with(kSuffixes[k])) return static_cast<int>(k);
  }
  return -1;
}

// `names`/`types`: the vertex element's scalar properties other than x, y, z, in file order.
ChannelLayout derive_channels(std::span<const std::string> names, std::span<const Scalar> types,
                              std::string_view what) {
  // name_r/_g[/_b[/_a]] groups: only a prefix of r,g,b,a is a vector; anything else (a lone
  // foo_r, or foo_r with foo_b) stays as separate scalar channels under the full names.
  // Hash maps rather than scans: a hostile header may declare a million properties.
  std::unordered_map<std::string_view, unsigned> masks;
  for (const std::string& n : names) {
    const int k = suffix_index(n);
    if (k >= 0) masks[std::string_view(n).substr(0, n.size() - 2)] |= 1u << k;
  }
  auto mask_of = [&](std::string_view base) -> unsigned {
    const auto it = masks.find(base);
    return it == masks.end() ? 0 : it->second;
  };
  auto group_width = [&](std::string_view base) -> std::uint32_t {
    switch (mask_of(base)) {
      case 0b0011:
        return 2;
      case 0b0111:
        return 3;
      case 0b1111:
        return 4;
      default:
        return 0;
    }
  };
  const std::unordered_set<std::string_view> present(names.begin(), names.end());
  auto has = [&](std::string_view n) { return present.count(n) != 0; };
  const bool albedo_taken = has("albedo") || group_width("albedo") != 0;
  const bool colour = has("red") && has("green") && has("blue") && !albedo_taken;

  ChannelLayout layout;
  std::vector<std::string> sources;  // what defined each channel, to report clashes
  std::unordered_map<std::string, int> channel_index;
  for (std::size_t i = 0; i < names.size(); ++i) {
    const std::string& n = names[i];
    std::string channel_name = n;
    std::string source = n;
    std::uint32_t width = 1;
    Slot slot;
    const int k = suffix_index(n);
    if (k >= 0 && group_width(std::string_view(n).substr(0, n.size() - 2)) != 0) {
      channel_name = n.substr(0, n.size() - 2);
      width = group_width(channel_name);
      source = cat(channel_name, "_r/...");
      slot.component = static_cast<std::uint32_t>(k);
    } else if (colour && (n == "red" || n == "green" || n == "blue" || n == "alpha")) {
      if (n == "alpha") {
        // Albedo is RGB (material_channels()); opacity is not a merged material parameter.
        layout.slots.push_back(Slot{});
        continue;
      }
      channel_name = "albedo";
      width = 3;
      source = "red/green/blue";
      slot.component = n == "red" ? 0 : n == "green" ? 1 : 2;
      if (types[i] == Scalar::u8) slot.scale = 1.0 / 255.0;
      if (types[i] == Scalar::u16) slot.scale = 1.0 / 65535.0;
    }
    const auto [it, inserted] =
        channel_index.try_emplace(channel_name, static_cast<int>(layout.channels.size()));
    slot.channel = it->second;
    if (inserted) {
      layout.channels.push_back(default_channel(channel_name, width));
      sources.push_back(source);
    } else {
      if (sources[static_cast<std::size_t>(slot.channel)] != source) {
        throw InvalidInput(cat(what, ": channel ", channel_name, " is defined twice (by property ",
                               sources[static_cast<std::size_t>(slot.channel)], " and by property ",
                               n, ")"));
      }
    }
    layout.slots.push_back(slot);
  }
  return layout;
}

// ---------------------------------------------------------------------------------------------
// Header

enum class Role : std::uint8_t { skip, x, y, z, channel, indices };

struct Property {
  std::string name;
  Scalar type = Scalar::f32;
  bool is_list = false;
  Scalar count_type = Scalar::u8;
  Role role = Role::skip;
  Slot slot;
};

struct Element {
  std::string name;
  std::uint64_t count = 0;
  std::vector<Property> props;
};

struct Header {
  Format format = Format::ascii;
  std::vector<Element> elements;
  std::vector<std::pair<std::string, Linearisation>> linearisations;    // from csculpt comments
  std::vector<std::pair<std::string, std::pair<float, float>>> ranges;  // from csculpt comments
  std::size_t body_offset = 0;
  std::size_t body_line = 1;  // line number of the first body line (ascii)
};

[[noreturn]] void header_error(std::string_view what, std::size_t line,
                               const std::string& problem) {
  throw InvalidInput(cat(what, ": header line ", line, ": ", problem));
}

/// A PLY header's lines, one at a time, with the current line's number for messages.
struct HeaderLines {
  std::string_view bytes;
  std::string_view what;
  std::size_t pos = 0;
  std::size_t line_no = 0;

  bool next(std::string_view& line) {
    if (pos >= bytes.size()) return false;
    std::size_t nl = bytes.find('\n', pos);
    if (nl == std::string_view::npos) nl = bytes.size();
    line = bytes.substr(pos, nl - pos);
    pos = nl + 1;
    ++line_no;
    return true;
  }
  [[noreturn]] void fail(const std::string& problem) const { header_error(what, line_no, problem); }
};

/// "comment csculpt linearisation <channel> <kind>" and "comment csculpt range <channel> <min>
/// <max>" record a channel's linearisation and value range when they differ from the
/// defaults for its name; other comments are skipped. `rest` follows "comment".
void parse_comment(std::string_view rest, const HeaderLines& lines, Header& h) {
  if (io_detail::next_token(rest) != "csculpt") return;
  const std::string_view what_kind = io_detail::next_token(rest);
  if (what_kind == "linearisation") {
    const std::string_view channel = io_detail::next_token(rest);
    const std::string_view kind = io_detail::next_token(rest);
    try {
      h.linearisations.emplace_back(std::string(channel), linearisation_from_string(kind));
    } catch (const InvalidInput& e) {
      lines.fail(e.what());
    }
  } else if (what_kind == "range") {
    const std::string channel(io_detail::next_token(rest));
    const std::string lo(io_detail::next_token(rest)), hi(io_detail::next_token(rest));
    char* end_lo = nullptr;
    char* end_hi = nullptr;
    const float min_value = std::strtof(lo.c_str(), &end_lo);
    const float max_value = std::strtof(hi.c_str(), &end_hi);
    if (channel.empty() || lo.empty() || hi.empty() || *end_lo != 0 || *end_hi != 0 ||
        std::isnan(min_value) || std::isnan(max_value) || min_value > max_value)
      lines.fail("malformed 'comment csculpt range <channel> <min> <max>' line");
    h.ranges.emplace_back(channel, std::make_pair(min_value, max_value));
  }
}

Format parse_format(std::span<const std::string_view> tokens, const HeaderLines& lines) {
  if (tokens.size() != 2) lines.fail("expected 'format <encoding> 1.0'");
  if (tokens[0] == "ascii") return Format::ascii;
  if (tokens[0] == "binary_little_endian") return Format::binary_le;
  if (tokens[0] == "binary_big_endian") return Format::binary_be;
  lines.fail(cat("unknown encoding ", quote(tokens[0]),
                 " (expected ascii, binary_little_endian or binary_big_endian)"));
}

Element parse_element(std::span<const std::string_view> tokens, const HeaderLines& lines) {
  if (tokens.size() != 2) lines.fail("expected 'element <name> <count>'");
  Element e;
  e.name = tokens[0];
  if (!io_detail::parse_uint(tokens[1], e.count)) {
    lines.fail(cat("bad element count ", quote(tokens[1])));
  }
  return e;
}

Property parse_property(std::span<const std::string_view> tokens, const HeaderLines& lines) {
  Property p;
  std::string_view type_name;
  if (!tokens.empty() && tokens[0] == "list") {
    if (tokens.size() != 4) lines.fail("expected 'property list <count type> <type> <name>'");
    const auto count_type = scalar_from_name(tokens[1]);
    if (!count_type) lines.fail(cat("unknown type ", quote(tokens[1])));
    if (!is_integer(*count_type)) {
      lines.fail(cat("list count type ", quote(tokens[1]), " is not an integer type"));
    }
    p.is_list = true;
    p.count_type = *count_type;
    type_name = tokens[2];
    p.name = tokens[3];
  } else {
    if (tokens.size() != 2) lines.fail("expected 'property <type> <name>'");
    type_name = tokens[0];
    p.name = tokens[1];
  }
  const auto type = scalar_from_name(type_name);
  if (!type) lines.fail(cat("unknown type ", quote(type_name)));
  p.type = *type;
  return p;
}

Header parse_header(std::string_view bytes, std::string_view what) {
  Header h;
  HeaderLines lines{bytes, what};
  std::string_view line;
  if (!lines.next(line) || io_detail::trim(line) != "ply") {
    throw InvalidInput(cat(what, ": not a PLY file (does not start with 'ply')"));
  }
  bool have_format = false;
  bool ended = false;
  // Sets rather than scans: a hostile header may declare a million properties.
  std::unordered_set<std::string> element_names;
  std::unordered_set<std::string> property_names;  // of the current element
  std::vector<std::string_view> tokens;
  while (!ended && lines.next(line)) {
    std::string_view rest = line;
    const std::string_view keyword = io_detail::next_token(rest);
    if (keyword.empty() || keyword == "obj_info") continue;
    if (keyword == "comment") {
      parse_comment(rest, lines, h);
      continue;
    }
    tokens.clear();
    for (std::string_view t = io_detail::next_token(rest); !t.empty();
         t = io_detail::next_token(rest)) {
      tokens.push_back(t);
    }
    if (keyword == "format") {
      if (have_format) lines.fail("second format line");
      h.format = parse_format(tokens, lines);
      have_format = true;
    } else if (keyword == "element") {
      Element e = parse_element(tokens, lines);
      if (!element_names.insert(e.name).second) {
        lines.fail(cat("element ", quote(e.name), " declared twice"));
      }
      property_names.clear();
      h.elements.push_back(std::move(e));
    } else if (keyword == "property") {
      if (h.elements.empty()) lines.fail("property before any element");
      Property p = parse_property(tokens, lines);
      Element& e = h.elements.back();
      if (!property_names.insert(p.name).second) {
        lines.fail(cat("property ", quote(p.name), " declared twice in element ", e.name));
      }
      e.props.push_back(std::move(p));
    } else if (keyword == "end_header") {
      ended = true;
    }
    // Any other line is ignored like a comment: old Blender exporters wrote a bare
    // "Created by Blender ..." line into the header.
  }
  if (!ended) throw InvalidInput(cat(what, ": header has no end_header line"));
  if (!have_format) throw InvalidInput(cat(what, ": header has no format line"));
  h.body_offset = std::min(lines.pos, bytes.size());
  h.body_line = lines.line_no + 1;
  return h;
}

// Checks the header's counts against the bytes that follow, before anything is allocated
// from them: a 100-byte file claiming 2^31 vertices is rejected here.
void check_counts(const Header& h, std::size_t body_bytes, std::string_view what) {
  std::uint64_t left = body_bytes;
  // ascii: every property needs a token and a separator, but the last token may end the file.
  const std::uint64_t slack = h.format == Format::ascii ? 1 : 0;
  for (const Element& e : h.elements) {
    if (e.count == 0) continue;
    if (e.props.empty()) {
      throw InvalidInput(
          cat(what, ": element ", e.name, " has ", e.count, " entries but no properties"));
    }
    std::uint64_t per = 0;
    for (const Property& p : e.props) {
      per += h.format == Format::ascii ? 2 : size_of(p.is_list ? p.count_type : p.type);
    }
    if (e.count > (left + slack) / per) {
      throw InvalidInput(cat(what, ": header claims ", e.count, " ", e.name, " elements, but only ",
                             left, " bytes of data are left for them (truncated file?)"));
    }
    left -= std::min(left, e.count * per);
  }
}

// Triangles to reserve for a face element: its count, but no more than the faces the body's
// bytes can hold as triangles (check_counts allows a face as short as its list's count, whose
// triangle would take 12 times its bytes). More faces than this still read, just reallocating.
std::size_t face_reservation(const Element& e, Format format, std::size_t body_bytes) {
  std::uint64_t per_triangle = 8;  // ascii "3 0 1 2\n"
  if (format != Format::ascii) {
    per_triangle = 0;
    for (const Property& p : e.props) {
      per_triangle += p.is_list ? size_of(p.count_type) + 3 * size_of(p.type) : size_of(p.type);
    }
  }
  return static_cast<std::size_t>(
      std::min<std::uint64_t>(e.count, body_bytes / std::max<std::uint64_t>(per_triangle, 1)));
}

// ---------------------------------------------------------------------------------------------
// Body cursors: one value at a time, with enough context to say where a problem is.

struct Where {
  const Element* element = nullptr;
  std::uint64_t index = 0;
  const Property* property = nullptr;
};

std::string element_position(const Where& w) {
  return cat(w.element->name, " ", w.index, " of ", w.element->count);
}

class AsciiCursor {
 public:
  AsciiCursor(std::string_view body, std::size_t first_line, std::string_view what)
      : rest_(body), line_(first_line), what_(what) {}

  std::string location() const { return cat(what_, ":", line_); }

  double read(Scalar type, const Where& w) {
    const std::string_view token = next(w);
    if (is_integer(type)) {
      std::int64_t v = 0;
      if (!io_detail::parse_int(token, v)) bad(token, type, w);
      const auto [lo, hi] = integer_range(type);
      if (v < lo || v > hi) {
        throw InvalidInput(cat(location(), ": ", w.element->name, " ", w.index, ": property ",
                               w.property->name, ": value ", v, " out of range for ",
                               name_of(type)));
      }
      return static_cast<double>(v);
    }
    if (type == Scalar::f32) {
      // Parsed as float directly: going through double could round twice.
      float f = 0;
      if (!io_detail::parse_float(token, f)) bad(token, type, w);
      return f;
    }
    double d = 0;
    if (!io_detail::parse_double(token, d)) bad(token, type, w);
    return d;
  }

  void skip(Scalar type, std::uint64_t n, const Where& w) {
    need_list(n, type, w);
    for (std::uint64_t i = 0; i < n; ++i) next(w);
  }

  // Each list entry needs at least two bytes of text.
  void need_list(std::uint64_t n, Scalar /*type*/, const Where& w) const {
    if (n > rest_.size() / 2 + 1) {
      throw InvalidInput(cat(location(), ": ", w.element->name, " ", w.index, ": list ",
                             w.property->name, " claims ", n,
                             " entries, more than the rest of the file holds"));
    }
  }

  void finish() {
    std::string_view rest = rest_;
    skip_space();
    if (const std::string_view token = io_detail::next_token(rest); !token.empty()) {
      throw InvalidInput(
          cat(location(), ": unexpected data after the last element: ", quote(token)));
    }
  }

 private:
  void skip_space() {
    std::size_t i = 0;
    while (i < rest_.size() && io_detail::is_space(rest_[i])) {
      if (rest_[i] == '\n') ++line_;
      ++i;
    }
    rest_.remove_prefix(i);
  }

  std::string_view next(const Where& w) {
    skip_space();
    std::size_t j = 0;
    while (j < rest_.size() && !io_detail::is_space(rest_[j])) ++j;
    if (j == 0) {
      throw InvalidInput(cat(what_, ": unexpected end of file in element ", w.element->name, " (",
                             element_position(w), "), property ", w.property->name));
    }
    const std::string_view token = rest_.substr(0, j);
    rest_.remove_prefix(j);
    return token;
  }

  [[noreturn]] void bad(std::string_view token, Scalar type, const Where& w) const {
    throw InvalidInput(cat(location(), ": ", w.element->name, " ", w.index, ": property ",
                           w.property->name, ": expected ", name_of(type), ", got ", quote(token)));
  }

  std::string_view rest_;
  std::size_t line_;
  std::string_view what_;
};

class BinaryCursor {
 public:
  BinaryCursor(std::string_view body, bool big_endian, std::string_view what)
      : rest_(body), big_endian_(big_endian), what_(what) {}

  std::string location() const { return std::string(what_); }

  double read(Scalar type, const Where& w) {
    const std::size_t n = size_of(type);
    if (rest_.size() < n) truncated(w);
    std::uint64_t raw = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const auto byte = static_cast<std::uint64_t>(static_cast<unsigned char>(rest_[i]));
      raw |= byte << (8 * (big_endian_ ? n - 1 - i : i));
    }
    rest_.remove_prefix(n);
    switch (type) {
      case Scalar::i8:
        return static_cast<std::int8_t>(static_cast<std::uint8_t>(raw));
      case Scalar::u8:
        return static_cast<std::uint8_t>(raw);
      case Scalar::i16:
        return static_cast<std::int16_t>(static_cast<std::uint16_t>(raw));
      case Scalar::u16:
        return static_cast<std::uint16_t>(raw);
      case Scalar::i32:
        return static_cast<std::int32_t>(static_cast<std::uint32_t>(raw));
      case Scalar::u32:
        return static_cast<std::uint32_t>(raw);
      case Scalar::f32:
        return std::bit_cast<float>(static_cast<std::uint32_t>(raw));
      case Scalar::f64:
        return std::bit_cast<double>(raw);
    }
    return 0;
  }

  void skip(Scalar type, std::uint64_t n, const Where& w) {
    need_list(n, type, w);
    rest_.remove_prefix(static_cast<std::size_t>(n) * size_of(type));
  }

  void need_list(std::uint64_t n, Scalar type, const Where& w) const {
    if (n > rest_.size() / size_of(type)) truncated(w);
  }

  void finish() {
    // Tolerate a trailing newline some writers add; anything else means the counts are wrong.
    if (!io_detail::trim(rest_).empty()) {
      throw InvalidInput(
          cat(what_, ": ", rest_.size(), " bytes of unexpected data after the last element"));
    }
  }

  [[noreturn]] void truncated(const Where& w) const {
    throw InvalidInput(cat(what_, ": truncated binary data in element ", w.element->name, " (",
                           element_position(w), ")"));
  }

 private:
  std::string_view rest_;
  bool big_endian_;
  std::string_view what_;
};

// Assigns each property its role and builds the mesh's channel list.
void assign_roles(Header& h, Mesh& mesh, std::string_view what) {
  for (Element& e : h.elements) {
    if (e.name == "vertex") {
      std::vector<std::string> names;
      std::vector<Scalar> types;
      std::vector<Property*> channel_props;
      bool have[3] = {false, false, false};
      for (Property& p : e.props) {
        const bool is_xyz = p.name == "x" || p.name == "y" || p.name == "z";
        if (is_xyz) {
          if (p.is_list) throw InvalidInput(cat(what, ": vertex property ", p.name, " is a list"));
          const int axis = p.name[0] - 'x';
          have[axis] = true;
          p.role = axis == 0 ? Role::x : axis == 1 ? Role::y : Role::z;
        } else if (!p.is_list) {
          names.push_back(p.name);
          types.push_back(p.type);
          channel_props.push_back(&p);
        }
      }
      for (int axis = 0; axis < 3; ++axis) {
        if (!have[axis] && e.count > 0) {
          throw InvalidInput(cat(what, ": vertex element has no property ", "xyz"[axis]));
        }
      }
      ChannelLayout layout = derive_channels(names, types, what);
      for (std::size_t i = 0; i < channel_props.size(); ++i) {
        channel_props[i]->role = layout.slots[i].channel >= 0 ? Role::channel : Role::skip;
        channel_props[i]->slot = layout.slots[i];
      }
      std::unordered_map<std::string_view, Linearisation> declared;
      for (const auto& [name, lin] : h.linearisations) declared[name] = lin;  // last one wins
      std::unordered_map<std::string_view, std::pair<float, float>> declared_ranges;
      for (const auto& [name, range] : h.ranges) declared_ranges[name] = range;
      for (ChannelDesc& d : layout.channels) {
        if (const auto it = declared.find(d.name); it != declared.end()) {
          d.linearisation = it->second;
        }
        if (const auto it = declared_ranges.find(d.name); it != declared_ranges.end()) {
          d.min_value = it->second.first;
          d.max_value = it->second.second;
        }
        Channel c;
        c.desc = d;
        mesh.channels.push_back(std::move(c));
      }
    } else if (e.name == "face") {
      bool found = false;
      for (Property& p : e.props) {
        if (found || !p.is_list || (p.name != "vertex_indices" && p.name != "vertex_index")) {
          continue;
        }
        if (!is_integer(p.type)) {
          throw InvalidInput(cat(what, ": face property ", p.name, " has non-integer index type ",
                                 name_of(p.type)));
        }
        p.role = Role::indices;
        found = true;
      }
      if (!found && e.count > 0) {
        throw InvalidInput(cat(what, ": face element has no vertex_indices list"));
      }
    }
  }
}

template <class Cursor>
void read_body(Cursor& cur, const Header& h, Mesh& mesh) {
  std::vector<std::uint32_t> poly;
  const std::uint64_t vertex_count = mesh.positions.size();
  for (const Element& e : h.elements) {
    Where w{&e, 0, nullptr};
    const bool is_vertex = e.name == "vertex";
    for (w.index = 0; w.index < e.count; ++w.index) {
      Vec3f* position = is_vertex ? &mesh.positions[static_cast<std::size_t>(w.index)] : nullptr;
      for (const Property& p : e.props) {
        w.property = &p;
        if (p.is_list) {
          const double count = cur.read(p.count_type, w);
          if (count < 0) {
            throw InvalidInput(cat(cur.location(), ": ", e.name, " ", w.index, ": property ",
                                   p.name, " has negative length ", count));
          }
          const auto n = static_cast<std::uint64_t>(count);
          if (p.role != Role::indices) {
            cur.skip(p.type, n, w);
            continue;
          }
          cur.need_list(n, p.type, w);
          poly.clear();
          for (std::uint64_t i = 0; i < n; ++i) {
            const double index = cur.read(p.type, w);
            if (index < 0 || index >= static_cast<double>(vertex_count)) {
              throw InvalidInput(cat(cur.location(), ": face ", w.index, ": vertex index ",
                                     static_cast<std::int64_t>(index), " out of range (",
                                     vertex_count, " vertices)"));
            }
            poly.push_back(static_cast<std::uint32_t>(index));
          }
          const std::string problem = io_detail::append_fan(poly, mesh.triangles);
          if (!problem.empty()) {
            throw InvalidInput(cat(cur.location(), ": face ", w.index, " ", problem));
          }
          continue;
        }
        const double value = cur.read(p.type, w);
        if (p.role == Role::skip) continue;
        const float f = io_detail::narrow(value * p.slot.scale);
        if (!std::isfinite(f)) {
          if (std::isfinite(value)) {
            throw InvalidInput(cat(cur.location(), ": vertex ", w.index, ": property ", p.name,
                                   " value ", value, " is out of float range"));
          }
          throw InvalidInput(cat(cur.location(), ": vertex ", w.index, ": property ", p.name,
                                 " is ", io_detail::non_finite_name(value)));
        }
        switch (p.role) {
          case Role::x:
            position->x = f;
            break;
          case Role::y:
            position->y = f;
            break;
          case Role::z:
            position->z = f;
            break;
          case Role::channel: {
            Channel& c = mesh.channels[static_cast<std::size_t>(p.slot.channel)];
            c.values[static_cast<std::size_t>(w.index) * c.desc.width + p.slot.component] = f;
            break;
          }
          case Role::skip:
          case Role::indices:
            break;
        }
      }
    }
  }
  cur.finish();
}

bool valid_property_name(std::string_view name) {
  if (name.empty()) return false;
  for (char c : name) {
    const auto u = static_cast<unsigned char>(c);
    if (u <= 0x20 || u == 0x7f) return false;
  }
  return true;
}

void put_u32_le(std::string& out, std::uint32_t v) {
  const char bytes[4] = {static_cast<char>(v & 0xff), static_cast<char>((v >> 8) & 0xff),
                         static_cast<char>((v >> 16) & 0xff), static_cast<char>((v >> 24) & 0xff)};
  out.append(bytes, 4);
}

void put_f32_le(std::string& out, float f) {
  put_u32_le(out, std::bit_cast<std::uint32_t>(f));
}

}  // namespace

Mesh parse_ply(std::string_view bytes, std::string_view what, Faces faces) {
  if (bytes.empty()) throw InvalidInput(cat(what, ": file is empty"));
  Header h = parse_header(bytes, what);
  const std::string_view body = bytes.substr(h.body_offset);
  check_counts(h, body.size(), what);

  Mesh mesh;
  assign_roles(h, mesh, what);
  for (const Element& e : h.elements) {
    if (e.name == "vertex") {
      if (e.count > std::numeric_limits<std::uint32_t>::max()) {
        throw InvalidInput(
            cat(what, ": ", e.count, " vertices is more than 32-bit indices can address"));
      }
      const auto n = static_cast<std::size_t>(e.count);
      mesh.positions.resize(n);
      for (Channel& c : mesh.channels) c.values.assign(n * c.desc.width, 0.f);
    } else if (e.name == "face") {
      mesh.triangles.reserve(face_reservation(e, h.format, body.size()));
    }
  }

  if (h.format == Format::ascii) {
    AsciiCursor cur(body, h.body_line, what);
    read_body(cur, h, mesh);
  } else {
    BinaryCursor cur(body, h.format == Format::binary_be, what);
    read_body(cur, h, mesh);
  }
  io_detail::check_parsed(mesh, what, faces);
  return mesh;
}

namespace io_detail {

std::string encode_ply(const Mesh& mesh, std::string_view what) {
  validate(mesh, what);
  if (mesh.vertex_count() > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max())) {
    throw InvalidInput(cat(what, ": ", mesh.vertex_count(),
                           " vertices do not fit the int indices of a PLY face list"));
  }
  // The property names, and a check that reading them back gives exactly these channels
  // (e.g. channels "red", "green", "blue" would come back as albedo).
  std::vector<std::string> names;
  for (const Channel& c : mesh.channels) {
    if (!valid_property_name(c.desc.name)) {
      throw InvalidInput(
          cat(what, ": channel name ", quote(c.desc.name),
              " cannot be a PLY property name (empty, spaces or control characters)"));
    }
    if (c.desc.width == 1) {
      names.push_back(c.desc.name);
    } else {
      for (std::uint32_t k = 0; k < c.desc.width; ++k)
        names.push_back(c.desc.name + std::string(kSuffixes[k]));
    }
  }
  for (const std::string& n : names) {
    if (n == "x" || n == "y" || n == "z") {
      throw InvalidInput(cat(what, ": channel ", n, " would clash with the position property ", n));
    }
  }
  const std::vector<Scalar> types(names.size(), Scalar::f32);
  const ChannelLayout layout = derive_channels(names, types, what);
  bool same = layout.channels.size() == mesh.channels.size();
  for (std::size_t c = 0; same && c < layout.channels.size(); ++c) {
    same = layout.channels[c].name == mesh.channels[c].desc.name &&
           layout.channels[c].width == mesh.channels[c].desc.width;
  }
  if (!same) {
    std::string read_back;
    for (const ChannelDesc& d : layout.channels) read_back += cat(" ", d.name, "(", d.width, ")");
    throw InvalidInput(cat(what,
                           ": these channel names would not read back as the same channels"
                           " from PLY; they would read as:",
                           read_back));
  }

  std::string header = "ply\nformat binary_little_endian 1.0\ncomment written by csculpt\n";
  for (const Channel& c : mesh.channels) {
    if (c.desc.linearisation != default_linearisation(c.desc.name)) {
      header += cat("comment csculpt linearisation ", c.desc.name, " ",
                    to_string(c.desc.linearisation), "\n");
    }
    const ChannelDesc defaults = default_channel(c.desc.name, c.desc.width);
    if (c.desc.min_value != defaults.min_value || c.desc.max_value != defaults.max_value) {
      // %.9g prints a float exactly (it reads back bit-identical); inf as "inf"
      char range[96];
      std::snprintf(range, sizeof range, "%.9g %.9g", double(c.desc.min_value),
                    double(c.desc.max_value));
      header += cat("comment csculpt range ", c.desc.name, " ", range, "\n");
    }
  }
  header += cat("element vertex ", mesh.vertex_count(), "\n");
  header += "property float x\nproperty float y\nproperty float z\n";
  for (const std::string& n : names) header += cat("property float ", n, "\n");
  header += cat("element face ", mesh.face_count(), "\n");
  header += "property list uchar int vertex_indices\nend_header\n";

  std::string out;
  out.reserve(header.size() + mesh.vertex_count() * (3 + names.size()) * 4 +
              mesh.face_count() * 13);
  out += header;
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
    const Vec3f& p = mesh.positions[v];
    put_f32_le(out, p.x);
    put_f32_le(out, p.y);
    put_f32_le(out, p.z);
    for (const Channel& c : mesh.channels) {
      for (std::uint32_t k = 0; k < c.desc.width; ++k)
        put_f32_le(out, c.values[v * c.desc.width + k]);
    }
  }
  for (const Triangle& t : mesh.triangles) {
    out.push_back(3);
    for (std::uint32_t i : t) put_u32_le(out, i);
  }
  return out;
}

}  // namespace io_detail
}  // namespace csculpt
