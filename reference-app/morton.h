// Morton (Z-order) codes: points close in space get codes close in value, so sorting by them
// puts what a brush or a view touches together in memory.
#pragma once

#include <algorithm>
#include <cstdint>

/** Spreads the low 10 bits of v so that three of them interleave. */
inline uint32_t morton_spread_bits(uint32_t v) {
  v &= 0x3ffu;
  v = (v | (v << 16)) & 0x030000ffu;
  v = (v | (v << 8)) & 0x0300f00fu;
  v = (v | (v << 4)) & 0x030c30c3u;
  v = (v | (v << 2)) & 0x09249249u;
  return v;
}

/** The 30-bit code of the cell (x, y, z), each coordinate in [0, 1023]. */
inline uint32_t morton_code(uint32_t x, uint32_t y, uint32_t z) {
  return morton_spread_bits(x) | (morton_spread_bits(y) << 1) | (morton_spread_bits(z) << 2);
}

/** The cell in [0, 1023] of coordinate c on an axis whose box starts at lo, 1024 cells of
 *  1/scale each (clamped: a point outside the box gets the nearest cell). */
inline uint32_t morton_cell(float c, float lo, float scale) {
  return static_cast<uint32_t>(std::clamp((c - lo) * scale, 0.f, 1023.f));
}
