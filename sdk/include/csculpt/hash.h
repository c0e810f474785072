// The SDK's two content hashes, one copy each for every layer (SDK, peer, C ABI). Both are
// pinned by tests/sdk/hash/test_digest_pins.cpp: the word hash orders diffs before the merge's
// arithmetic (merges stay bit-identical only while it does not change) and FNV-1a gives
// csc_hierarchy_digest's values, which hosts see.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

namespace csculpt {

/// The SDK's digests start from this value (the diff digest with hash_bytes, the hierarchy
/// digest with fnv1a). It is FNV's 64-bit offset basis with its last decimal digit dropped, so
/// fnv1a from here is not the published FNV-1a; the digests' values depend on it, keep it.
constexpr std::uint64_t hash_seed = 1469598103934665603ull;

/// One multiply-xorshift step of the word hash: folds the 64-bit word `w` into `h`.
constexpr std::uint64_t hash_mix(std::uint64_t h, std::uint64_t w) {
  h ^= w + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
  h *= 0xff51afd7ed558ccdull;
  return h ^ (h >> 32);
}

/// Word-at-a-time 64-bit hash of `bytes` bytes: cheap enough to run over every changed value.
/// Little-endian words; the tail (under 8 bytes) is folded with the length as one last word.
inline std::uint64_t hash_bytes(std::uint64_t h, const void* data, std::size_t bytes) {
  const auto* p = static_cast<const unsigned char*>(data);
  std::size_t i = 0;
  for (; i + 8 <= bytes; i += 8) {
    std::uint64_t w;
    std::memcpy(&w, p + i, 8);
    h = hash_mix(h, w);
  }
  std::uint64_t tail = bytes;
  for (std::size_t k = 0; i < bytes; ++i, ++k) tail ^= std::uint64_t{p[i]} << (8 * (k + 1));
  return hash_mix(h, tail);
}

/// Byte-at-a-time 64-bit FNV-1a step over `bytes` bytes: slower, kept where its values are part
/// of an interface (the hierarchy digest, from hash_seed).
inline std::uint64_t fnv1a(std::uint64_t h, const void* data, std::size_t bytes) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < bytes; ++i) {
    h ^= p[i];
    h *= 1099511628211ull;
  }
  return h;
}

}  // namespace csculpt
