// Wire codec (schema sdk/schema/diff.fbs).
#include "csculpt/wire.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <string>

#include "csculpt/error.h"
#include "csculpt/varint.h"
#include "diff_generated.h"

namespace csculpt {
namespace {

namespace fb = csculpt::wire;

// Quantisation step as a fraction of the tolerance: rounding costs at most step/2 = 0.8 x
// tolerance, leaving 0.2 x tolerance for the float rounding of the decoded value.
constexpr double step_per_tolerance = 1.6;
// Past this many steps a change is not worth quantising (and q * step would lose integers).
constexpr double max_quantum = 9.0e15;

// ---- varints -------------------------------------------------------------------------------

std::uint64_t zigzag(std::int64_t v) {
  return (static_cast<std::uint64_t>(v) << 1) ^ static_cast<std::uint64_t>(v >> 63);
}
std::int64_t unzigzag(std::uint64_t v) {
  return static_cast<std::int64_t>(v >> 1) ^ -static_cast<std::int64_t>(v & 1);
}

// ---- encoding ------------------------------------------------------------------------------

struct EncodedAttribute {
  std::vector<std::uint8_t> index_gaps;
  std::vector<std::uint8_t> values;
  std::uint32_t count = 0;
  fb::ValueCoding coding = fb::ValueCoding::Float32;
  double step = 0;
};

/// What decode_attribute makes of quantised values: the kept vertices and base + q x step,
/// computed as the decoder computes them (bit for bit), without reading the bytes back.
void decoded_attribute(const float* base, std::uint32_t width,
                       const std::vector<std::uint32_t>& kept, const std::vector<std::int64_t>& q,
                       double step, AttributeDiff& out) {
  out.indices = kept;
  out.values.resize(q.size());
  for (std::size_t i = 0; i < kept.size(); ++i)
    for (std::uint32_t c = 0; c < width; ++c)
      out.values[i * width + c] = static_cast<float>(
          double(base[std::size_t{kept[i]} * width + c]) + double(q[i * width + c]) * step);
}

/// `base` holds `width` floats per vertex of the base mesh. `decoded` (may be null) gets what
/// a receiver decodes.
EncodedAttribute encode_attribute(const AttributeDiff& change, const float* base,
                                  std::uint32_t width, double tolerance, AttributeDiff* decoded) {
  EncodedAttribute e;
  const std::size_t n = change.indices.size();
  const double step = step_per_tolerance * tolerance;
  bool quantise = tolerance > 0 && std::isfinite(step) && step > 0;
  std::vector<std::int64_t> q;
  std::vector<std::uint32_t> kept;
  if (quantise) {
    q.reserve(n * width);
    kept.reserve(n);
    std::vector<std::int64_t> row(width);
    for (std::size_t i = 0; i < n && quantise; ++i) {
      const std::size_t v = change.indices[i];
      bool nonzero = false;
      for (std::uint32_t c = 0; c < width; ++c) {
        const double d =
            (double(change.values[i * width + c]) - double(base[v * width + c])) / step;
        if (!(std::abs(d) < max_quantum)) {
          quantise = false;
          break;
        }
        row[c] = std::llround(d);
        nonzero |= row[c] != 0;
      }
      if (nonzero) {
        kept.push_back(change.indices[i]);
        q.insert(q.end(), row.begin(), row.end());
      }
    }
  }
  if (!quantise) {
    if (decoded) *decoded = change;  // sent as float bits
    e.count = static_cast<std::uint32_t>(n);
    put_index_gaps(change.indices, e.index_gaps);
    e.values.resize(change.values.size() * sizeof(float));
    static_assert(std::endian::native == std::endian::little, "wire floats are little-endian");
    if (!e.values.empty()) std::memcpy(e.values.data(), change.values.data(), e.values.size());
    return e;
  }
  e.count = static_cast<std::uint32_t>(kept.size());
  e.step = step;
  if (decoded) decoded_attribute(base, width, kept, q, step, *decoded);
  put_index_gaps(kept, e.index_gaps);
  // Planar, plain and predicted; keep the smaller.
  std::vector<std::uint8_t> plain, predicted;
  plain.reserve(q.size() * 2);
  predicted.reserve(q.size() * 2);
  for (std::uint32_t c = 0; c < width; ++c) {
    std::int64_t previous = 0;
    for (std::size_t i = 0; i < kept.size(); ++i) {
      const std::int64_t value = q[i * width + c];
      put_varint(plain, zigzag(value));
      put_varint(predicted, zigzag(value - previous));
      previous = value;
    }
  }
  if (predicted.size() < plain.size()) {
    e.coding = fb::ValueCoding::QuantisedDeltaPredicted;
    e.values = std::move(predicted);
  } else {
    e.coding = fb::ValueCoding::QuantisedDelta;
    e.values = std::move(plain);
  }
  return e;
}

flatbuffers::Offset<fb::AttributeChanges> build_attribute(flatbuffers::FlatBufferBuilder& b,
                                                          const EncodedAttribute& e) {
  const auto gaps = b.CreateVector(e.index_gaps);
  const auto values = b.CreateVector(e.values);
  return fb::CreateAttributeChanges(b, e.count, gaps, e.coding, e.step, values);
}

// ---- decoding ------------------------------------------------------------------------------

/// FlatBuffers reads scalars in place, so a buffer must sit at an address aligned for its
/// largest scalar (8: the ulong fields); bytes from a socket, a nested vector or a host need
/// not. Misaligned input is copied once into aligned storage.
class AlignedBytes {
 public:
  explicit AlignedBytes(std::span<const std::uint8_t> bytes) : original_(bytes), view_(bytes) {
    if (reinterpret_cast<std::uintptr_t>(bytes.data()) % alignof(std::uint64_t) == 0) return;
    storage_.resize((bytes.size() + 7) / 8);
    std::memcpy(storage_.data(), bytes.data(), bytes.size());
    view_ = {reinterpret_cast<const std::uint8_t*>(storage_.data()), bytes.size()};
  }
  std::span<const std::uint8_t> bytes() const { return view_; }
  /// A view into the aligned bytes, as the same bytes of the caller's buffer.
  std::string_view in_original(std::string_view v) const {
    if (v.empty() || view_.data() == original_.data()) return v;
    const auto offset = reinterpret_cast<const std::uint8_t*>(v.data()) - view_.data();
    return {reinterpret_cast<const char*>(original_.data()) + offset, v.size()};
  }

 private:
  std::span<const std::uint8_t> original_, view_;
  std::vector<std::uint64_t> storage_;
};

const fb::DiffMessage* verified_message(std::span<const std::uint8_t> bytes,
                                        const DecodeLimits& limits) {
  if (bytes.size() > limits.max_bytes)
    throw InvalidInput("diff message of " + std::to_string(bytes.size()) +
                       " bytes exceeds the limit of " + std::to_string(limits.max_bytes));
  if (bytes.size() < 8)
    throw InvalidInput("diff message too short (" + std::to_string(bytes.size()) + " bytes)");
  if (!fb::DiffMessageBufferHasIdentifier(bytes.data()))
    throw InvalidInput("not a cSculpt diff message (file identifier is not \"" +
                       std::string(fb::DiffMessageIdentifier()) + "\")");
  // Explicit limits: depth 8 is more than the schema nests; the size bound is the buffer
  // itself; the table count is bounded by what the channel limit could need (checked with
  // its own message once verified) with room to spare.
  flatbuffers::Verifier verifier(
      bytes.data(), bytes.size(), /*max_depth=*/8,
      /*max_tables=*/std::max<flatbuffers::uoffset_t>(1024, limits.max_channels * 4 + 16));
  if (!fb::VerifyDiffMessageBuffer(verifier))
    throw InvalidInput("diff message failed FlatBuffers verification (corrupt or truncated)");
  return fb::GetDiffMessage(bytes.data());
}

DiffHeader header_of(const fb::DiffMessage& m) {
  DiffHeader h;
  h.protocol = m.protocol();
  h.base_version = m.base_version();
  h.sequence = m.sequence();
  if (m.author()) {
    if (m.author()->size() > max_author_bytes)
      throw InvalidInput("diff message author is " + std::to_string(m.author()->size()) +
                         " bytes (at most " + std::to_string(max_author_bytes) + ")");
    h.author = std::string_view(m.author()->data(), m.author()->size());
    if (h.author.find('\0') != std::string_view::npos)
      throw InvalidInput("diff message author contains a NUL byte");
  }
  h.vertex_count = m.vertex_count();
  if (h.protocol == 0 || h.protocol > wire_protocol_version)
    throw InvalidInput("diff message has protocol " + std::to_string(h.protocol) +
                       "; this build reads 1 to " + std::to_string(wire_protocol_version));
  return h;
}

void decode_attribute(const fb::AttributeChanges* a, const float* base, std::uint32_t width,
                      std::uint32_t vertex_count, const std::string& what, AttributeDiff& out) {
  if (a == nullptr) return;
  const std::uint32_t count = a->count();
  if (count > vertex_count)
    throw InvalidInput(what + ": " + std::to_string(count) + " changed vertices but the mesh has " +
                       std::to_string(vertex_count));
  const auto* gaps = a->index_gaps();
  if (count > 0 && gaps == nullptr) throw InvalidInput(what + ": indices missing");
  // Each varint is at least one byte: a cheap bound before allocating.
  if (gaps && gaps->size() < count)
    throw InvalidInput(what + ": " + std::to_string(count) + " indices in " +
                       std::to_string(gaps->size()) + " bytes");
  out.indices.resize(count);
  if (count > 0) {
    IndexGapReader r(gaps->data(), gaps->size(), what);
    for (std::uint32_t i = 0; i < count; ++i) out.indices[i] = r.next(vertex_count);
    if (!r.done())
      throw InvalidInput(what + ": bytes left over after " + std::to_string(count) + " indices");
  } else if (gaps && gaps->size() != 0) {
    throw InvalidInput(what + ": index bytes but no changed vertices");
  }

  const auto* values = a->values();
  const std::size_t n = std::size_t{count} * width;
  const std::size_t bytes = values ? values->size() : 0;
  out.values.resize(n);
  switch (a->coding()) {
    case fb::ValueCoding::Float32: {
      if (bytes != n * sizeof(float))
        throw InvalidInput(what + ": " + std::to_string(bytes) + " value bytes for " +
                           std::to_string(count) + " vertices of width " + std::to_string(width) +
                           " (expected " + std::to_string(n * sizeof(float)) + ")");
      if (n) std::memcpy(out.values.data(), values->data(), n * sizeof(float));
      break;
    }
    case fb::ValueCoding::QuantisedDelta:
    case fb::ValueCoding::QuantisedDeltaPredicted: {
      const double step = a->step();
      if (!(std::isfinite(step) && step > 0))
        throw InvalidInput(what + ": quantisation step " + std::to_string(step) +
                           " is not a finite positive number");
      if (bytes < n)
        throw InvalidInput(what + ": " + std::to_string(n) + " values in " + std::to_string(bytes) +
                           " bytes");
      const bool predicted = a->coding() == fb::ValueCoding::QuantisedDeltaPredicted;
      VarintReader r(values ? values->data() : nullptr, bytes, what + " values");
      for (std::uint32_t c = 0; c < width; ++c) {
        std::int64_t q = 0;
        for (std::uint32_t i = 0; i < count; ++i) {
          const std::int64_t stored = unzigzag(r.next());
          // Wrapping add: a hostile stream may overflow; the value is checked below anyway.
          q = predicted ? static_cast<std::int64_t>(static_cast<std::uint64_t>(q) +
                                                    static_cast<std::uint64_t>(stored))
                        : stored;
          const std::size_t v = out.indices[i];
          const double value = double(base[v * width + c]) + double(q) * step;
          const float f = static_cast<float>(value);
          if (!std::isfinite(value) || !std::isfinite(f))
            throw InvalidInput(what + ": value of vertex " + std::to_string(v) + " is not finite");
          out.values[std::size_t{i} * width + c] = f;
        }
      }
      if (!r.done())
        throw InvalidInput(what + ": bytes left over after " + std::to_string(n) + " values");
      return;  // finite by construction
    }
    default:
      throw InvalidInput(what + ": unknown value coding " +
                         std::to_string(static_cast<unsigned>(a->coding())));
  }
  for (std::size_t i = 0; i < n; ++i)
    if (!std::isfinite(out.values[i]))
      throw InvalidInput(what + ": value of vertex " + std::to_string(out.indices[i / width]) +
                         " is not finite");
}

}  // namespace

std::vector<std::uint8_t> encode_diff(const Diff& diff, const Mesh& base, const DiffHeader& header,
                                      const EncodeOptions& options, Diff* decoded) {
  validate(diff, base, "encode_diff");
  if (header.author.size() > max_author_bytes)
    throw InvalidInput("encode_diff: author is " + std::to_string(header.author.size()) +
                       " bytes (at most " + std::to_string(max_author_bytes) + ")");
  if (!(options.position_tolerance >= 0) || !(options.channel_tolerance >= 0) ||
      !(options.position_scale >= 0))
    throw InvalidInput("encode_diff: tolerances and scale must be >= 0");
  double scale = options.position_scale;
  if (scale == 0 && options.position_tolerance > 0) scale = bbox_diagonal(base.positions);
  if (scale == 0) scale = 1;  // a point-like mesh: the tolerance is absolute

  if (decoded) clear_to_layout(*decoded, base);  // as decode_diff lays it out
  flatbuffers::FlatBufferBuilder b(1024 + diff.positions.size() * 8);
  static_assert(sizeof(Vec3f) == 3 * sizeof(float));
  const auto positions = build_attribute(
      b, encode_attribute(diff.positions, reinterpret_cast<const float*>(base.positions.data()), 3,
                          options.position_tolerance * scale,
                          decoded ? &decoded->positions : nullptr));
  std::vector<flatbuffers::Offset<fb::ChannelChanges>> channels;
  for (const ChannelDiff& c : diff.channels) {
    if (c.change.empty()) continue;
    const auto k = static_cast<std::size_t>(base.find_channel(c.desc.name));
    const Channel& bc = base.channels[k];
    const auto changes = build_attribute(
        b, encode_attribute(c.change, bc.values.data(), c.desc.width, options.channel_tolerance,
                            decoded ? &decoded->channels[k].change : nullptr));
    channels.push_back(
        fb::CreateChannelChanges(b, b.CreateString(c.desc.name), c.desc.width, changes));
  }
  const auto author = b.CreateString(header.author.data(), header.author.size());
  const auto channel_vector = b.CreateVector(channels);
  const auto message =
      fb::CreateDiffMessage(b, wire_protocol_version, header.base_version, author, header.sequence,
                            diff.vertex_count, positions, channel_vector);
  fb::FinishDiffMessageBuffer(b, message);
  return {b.GetBufferPointer(), b.GetBufferPointer() + b.GetSize()};
}

DiffHeader peek_diff_header(std::span<const std::uint8_t> bytes, const DecodeLimits& limits) {
  const AlignedBytes aligned(bytes);
  DiffHeader h = header_of(*verified_message(aligned.bytes(), limits));
  h.author = aligned.in_original(h.author);
  return h;
}

Diff decode_diff(std::span<const std::uint8_t> bytes, const Mesh& base, DiffHeader* header,
                 const DecodeLimits& limits) {
  const AlignedBytes aligned(bytes);
  const fb::DiffMessage& m = *verified_message(aligned.bytes(), limits);
  DiffHeader h = header_of(m);
  h.author = aligned.in_original(h.author);
  if (h.vertex_count != base.vertex_count())
    throw InvalidInput("diff message is for " + std::to_string(h.vertex_count) +
                       " vertices but the base mesh has " + std::to_string(base.vertex_count()));
  Diff d;
  clear_to_layout(d, base);  // h.vertex_count, checked above
  decode_attribute(m.positions(), reinterpret_cast<const float*>(base.positions.data()), 3,
                   d.vertex_count, "diff message positions", d.positions);
  if (const auto* channels = m.channels()) {
    if (channels->size() > limits.max_channels)
      throw InvalidInput("diff message has " + std::to_string(channels->size()) +
                         " channels, more than the limit of " +
                         std::to_string(limits.max_channels));
    if (channels->size() > base.channels.size())
      throw InvalidInput("diff message has " + std::to_string(channels->size()) +
                         " channels; the base mesh has " + std::to_string(base.channels.size()));
    std::vector<bool> seen(base.channels.size(), false);
    for (const fb::ChannelChanges* c : *channels) {
      const std::string name(c->name()->data(), c->name()->size());
      const int index = base.find_channel(name);
      const std::string what = "diff message channel '" + name + "'";
      if (index < 0) throw InvalidInput(what + " does not exist in the base mesh");
      const auto k = static_cast<std::size_t>(index);
      if (seen[k]) throw InvalidInput(what + " appears twice");
      seen[k] = true;
      const Channel& bc = base.channels[k];
      if (c->width() != bc.desc.width)
        throw InvalidInput(what + " has width " + std::to_string(c->width()) +
                           " but the base's has " + std::to_string(bc.desc.width));
      decode_attribute(c->changes(), bc.values.data(), bc.desc.width, d.vertex_count, what,
                       d.channels[k].change);
    }
  }
  if (header) *header = h;
  return d;
}

}  // namespace csculpt
