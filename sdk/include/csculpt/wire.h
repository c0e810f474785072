// The wire codec: a Diff to and from the bytes of a FlatBuffers `DiffMessage`
// (schema: sdk/schema/diff.fbs, the source of truth).
//
// Compact: indices delta-coded as varints; values sent as quantised changes from the base with
// a stated bound (or lossless floats). Every inbound buffer is verified (FlatBuffers Verifier
// with explicit limits) and checked (indices in range and increasing, counts consistent,
// values finite, the base's vertex count and channels) before anything is built from it.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "csculpt/diff.h"
#include "csculpt/mesh.h"

namespace csculpt {

/// The wire protocol version this build writes and the highest it reads.
inline constexpr std::uint32_t wire_protocol_version = 1;

/// What a message says about itself, readable before decoding (peek_diff_header).
struct DiffHeader {
  std::uint32_t protocol = wire_protocol_version;
  std::uint64_t base_version = 0;
  std::uint64_t sequence = 0;
  /// At most max_author_bytes. Read from a message, it points into the message's bytes.
  std::string_view author;
  std::uint32_t vertex_count = 0;
};

inline constexpr std::size_t max_author_bytes = 256;

struct EncodeOptions {
  /// Largest position error of the decoded diff, as a fraction of `position_scale`; 0 sends
  /// positions losslessly (float bits).
  double position_tolerance = 1e-5;
  /// The length the tolerance is relative to; 0 = the base's bounding-box diagonal (computed
  /// per call: pass it when encoding often on a large mesh, e.g. MergeFrame::scale).
  double position_scale = 0;
  /// Largest channel error, absolute in the channel's stored units; 0 = lossless.
  double channel_tolerance = 1e-4;
};

/// Encodes `diff` (taken against `base`) as a DiffMessage. Quantised changes that round to
/// zero in every component are left out, so the message can list fewer vertices than `diff`.
/// The decoded diff (decode_diff of these bytes) is what every receiver sees: a sender that
/// needs bit-identical state with its peers uses it in place of `diff`.
///
/// Bound: each decoded component is within 0.8 x tolerance (x scale) of the original plus half
/// a float ulp of the value (negligible within ~30 bounding-box diagonals of the origin).
/// `decoded` (may be null) receives that decoded diff, bit for bit what decode_diff of the
/// bytes gives, without decoding them (it must not be `diff` itself). Throws InvalidInput if the
/// diff does not fit the base or the author is too long.
std::vector<std::uint8_t> encode_diff(const Diff& diff, const Mesh& base, const DiffHeader& header,
                                      const EncodeOptions& options = {}, Diff* decoded = nullptr);

/// Limits applied to inbound bytes before and while decoding.
struct DecodeLimits {
  std::size_t max_bytes = std::size_t{1} << 30;  ///< larger buffers are refused unread
  std::uint32_t max_channels = 64;
};

/// Verifies the buffer and returns its header. Throws InvalidInput saying what is wrong.
DiffHeader peek_diff_header(std::span<const std::uint8_t> bytes, const DecodeLimits& limits = {});

/// Verifies and decodes a DiffMessage against `base` (the mesh of the message's base
/// version). Throws InvalidInput, saying what is wrong, for bytes that are not a valid
/// DiffMessage, a newer protocol, another vertex count, an unknown channel or one of another
/// width, indices out of range, inconsistent counts or values that are not finite.
/// The result passes validate(diff, base); channels come in the base's order.
Diff decode_diff(std::span<const std::uint8_t> bytes, const Mesh& base,
                 DiffHeader* header = nullptr, const DecodeLimits& limits = {});

}  // namespace csculpt
