// The shared hashes (csculpt/hash.h): the word hash and FNV-1a themselves; their values in the
// digests are pinned by test_digest_pins.cpp.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>

#include "csculpt/hash.h"

namespace {

using namespace csculpt;

TEST(Hash, WordHashFoldsTheTailWithTheLength) {
  const char a[] = "abcdefghijk";
  // Each prefix length gives another value, and the same bytes the same value.
  std::uint64_t previous = 0;
  for (std::size_t n = 0; n <= 11; ++n) {
    const std::uint64_t h = hash_bytes(hash_seed, a, n);
    EXPECT_NE(h, previous) << n;
    EXPECT_EQ(h, hash_bytes(hash_seed, a, n));
    previous = h;
  }
  EXPECT_EQ(hash_bytes(hash_seed, "", 0), hash_mix(hash_seed, 0));
  std::uint64_t w;
  std::memcpy(&w, a, 8);
  EXPECT_EQ(hash_bytes(hash_seed, a, 8), hash_mix(hash_mix(hash_seed, w), 8));
}

TEST(Hash, Fnv1aHasItsPublishedValues) {
  // FNV-1a 64 test vectors (the reference's "", "a", "foobar") from FNV's offset basis ...
  constexpr std::uint64_t offset_basis = 0xcbf29ce484222325ull;
  EXPECT_EQ(fnv1a(offset_basis, "", 0), offset_basis);
  EXPECT_EQ(fnv1a(offset_basis, "a", 1), 0xaf63dc4c8601ec8cull);
  EXPECT_EQ(fnv1a(offset_basis, "foobar", 6), 0x85944171f73967e8ull);
  // ... and the SDK's seed is not it (the hierarchy digest's values depend on the seed).
  EXPECT_NE(hash_seed, offset_basis);
  EXPECT_EQ(fnv1a(hash_seed, "", 0), hash_seed);
}

}  // namespace
