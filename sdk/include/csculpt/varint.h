// LEB128 varints and the index-gap coding built on them, shared by the wire codec
// (csculpt/wire.h) and the peer protocol's attribution lists. An increasing index list is sent
// as the gaps between successive indices (index[i] - index[i-1] - 1, the first from -1), each a
// varint: a dense stroke costs about a byte per vertex.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "csculpt/error.h"

namespace csculpt {

/// Appends `v` as an unsigned LEB128 varint (7 bits a byte, low first; 1 to 10 bytes).
inline void put_varint(std::vector<std::uint8_t>& out, std::uint64_t v) {
  while (v >= 0x80) {
    out.push_back(static_cast<std::uint8_t>(v | 0x80));
    v >>= 7;
  }
  out.push_back(static_cast<std::uint8_t>(v));
}

/// Reads varints from a byte range; every failure throws InvalidInput naming what was read.
class VarintReader {
 public:
  VarintReader(const std::uint8_t* data, std::size_t size, std::string what)
      : p_(data), end_(data + size), what_(std::move(what)) {}
  /// The next varint; throws on a truncated one or one longer than 64 bits.
  std::uint64_t next() {
    std::uint64_t v = 0;
    for (int shift = 0; shift < 64; shift += 7) {
      if (p_ == end_) throw InvalidInput(what_ + ": truncated varint");
      const std::uint8_t b = *p_++;
      if (shift == 63 && b > 1) break;
      v |= std::uint64_t{b & 0x7fu} << shift;
      if (!(b & 0x80)) return v;
    }
    throw InvalidInput(what_ + ": varint longer than 64 bits");
  }
  bool done() const { return p_ == end_; }

 private:
  const std::uint8_t* p_;
  const std::uint8_t* end_;
  std::string what_;  // owned: callers pass temporaries
};

/// Appends the gap coding of `indices` (strictly increasing).
inline void put_index_gaps(std::span<const std::uint32_t> indices, std::vector<std::uint8_t>& out) {
  std::uint64_t next = 0;  // index[-1] + 1
  for (const std::uint32_t i : indices) {
    put_varint(out, i - next);
    next = std::uint64_t{i} + 1;
  }
}

/// Reads a gap-coded index list back, each index checked against the vertex count.
class IndexGapReader {
 public:
  /// `what` names the list in errors ("positions": "positions indices: truncated varint").
  IndexGapReader(const std::uint8_t* data, std::size_t size, std::string what)
      : varints_(data, size, what + " indices"), what_(std::move(what)) {}
  /// The next index; throws InvalidInput if it is not below `vertex_count`.
  std::uint32_t next(std::uint64_t vertex_count) {
    // Checked before adding: a hostile gap near 2^64 would wrap around to a small index.
    const std::uint64_t gap = varints_.next();
    if (gap >= vertex_count - next_)
      throw InvalidInput(
          what_ + ": vertex index " +
          (gap > std::uint64_t{1} << 32 ? std::string("past 2^32") : std::to_string(next_ + gap)) +
          " out of range (" + std::to_string(vertex_count) + " vertices)");
    const std::uint64_t index = next_ + gap;
    next_ = index + 1;
    return static_cast<std::uint32_t>(index);
  }
  bool done() const { return varints_.done(); }

 private:
  VarintReader varints_;
  std::string what_;
  std::uint64_t next_ = 0;  // the previous index + 1
};

}  // namespace csculpt
