// A set of small integers (vertices, triangles, tree nodes) marked while one pass collects
// them, then cleared from that pass's own list: one bit per item, so a million vertices'
// marks stay in the cache, where a stamp per vertex would not.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

class Marks {
 public:
  void resize(size_t items) { bits_.assign((items + 63) / 64, 0); }
  /** Marks `item`; false if it was marked already. */
  bool mark(uint32_t item) {
    uint64_t& word = bits_[item >> 6];
    const uint64_t bit = uint64_t{1} << (item & 63);
    if (word & bit) return false;
    word |= bit;
    return true;
  }
  bool marked(uint32_t item) const { return (bits_[item >> 6] >> (item & 63)) & 1u; }
  void unmark(uint32_t item) { bits_[item >> 6] &= ~(uint64_t{1} << (item & 63)); }
  /** Unmarks everything: `marked` must list every item marked since the last clear (whole
   *  words are cleared). */
  void clear(std::span<const uint32_t> marked) {
    for (uint32_t item : marked) bits_[item >> 6] = 0;
  }

 private:
  std::vector<uint64_t> bits_;
};
