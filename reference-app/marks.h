// A set of small integers (vertices, triangles, tree nodes) marked while one pass collects
// them, then cleared from that pass's own list: one bit per item, so a million vertices'
// marks stay in the cache, where a stamp per vertex would not.
#pragma once

#include <bit>
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
  /** Calls visit(item) for every marked item in increasing order and unmarks them all: a
   *  scan of every word (16K at a million items), far cheaper than sorting a list of them. */
  template <typename Visit>
  void take_in_order(Visit&& visit) {
    for (size_t w = 0; w < bits_.size(); ++w) {
      for (uint64_t word = bits_[w]; word != 0; word &= word - 1)
        visit(static_cast<uint32_t>(w * 64 + static_cast<size_t>(std::countr_zero(word))));
      bits_[w] = 0;
    }
  }
  /** Unmarks everything: `marked` must list every item marked since the last clear (whole
   *  words are cleared). */
  void clear(std::span<const uint32_t> marked) {
    for (uint32_t item : marked) bits_[item >> 6] = 0;
  }

 private:
  std::vector<uint64_t> bits_;
};
