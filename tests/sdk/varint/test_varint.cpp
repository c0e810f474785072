// The shared varint and index-gap coding (csculpt/varint.h).
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "csculpt/error.h"
#include "csculpt/varint.h"

namespace {

using namespace csculpt;

TEST(Varint, RoundTripsEdgeValues) {
  const std::uint64_t values[] = {0, 1, 127, 128, 16383, 16384, 0xffffffffull, ~std::uint64_t{0}};
  std::vector<std::uint8_t> bytes;
  for (std::uint64_t v : values) put_varint(bytes, v);
  EXPECT_EQ(bytes[0], 0u);
  EXPECT_EQ(bytes[2], 127u);
  VarintReader r(bytes.data(), bytes.size(), "test");
  for (std::uint64_t v : values) EXPECT_EQ(r.next(), v);
  EXPECT_TRUE(r.done());
  std::vector<std::uint8_t> longest;
  put_varint(longest, ~std::uint64_t{0});
  EXPECT_EQ(longest.size(), 10u);
}

TEST(Varint, RefusesTruncatedAndOverlongVarints) {
  const std::uint8_t truncated[] = {0x80, 0x80};
  VarintReader t(truncated, 2, "gaps");
  EXPECT_THROW(
      {
        try {
          t.next();
        } catch (const InvalidInput& e) {
          EXPECT_STREQ(e.what(), "gaps: truncated varint");
          throw;
        }
      },
      InvalidInput);
  // Ten bytes whose last carries more than the 64th bit: overflow, refused.
  std::vector<std::uint8_t> over(9, 0xff);
  over.push_back(0x02);
  VarintReader o(over.data(), over.size(), "gaps");
  EXPECT_THROW(o.next(), InvalidInput);
  std::vector<std::uint8_t> eleven(10, 0x80);
  eleven.push_back(0);
  VarintReader e(eleven.data(), eleven.size(), "gaps");
  EXPECT_THROW(e.next(), InvalidInput);
}

TEST(IndexGaps, RoundTripAndCodeGaps) {
  const std::vector<std::uint32_t> indices = {0, 1, 5, 200, 70000};
  std::vector<std::uint8_t> bytes;
  put_index_gaps(indices, bytes);
  EXPECT_EQ(bytes[0], 0u);  // the first gap counts from -1
  EXPECT_EQ(bytes[1], 0u);
  EXPECT_EQ(bytes[2], 3u);
  IndexGapReader r(bytes.data(), bytes.size(), "positions");
  for (std::uint32_t i : indices) EXPECT_EQ(r.next(70001), i);
  EXPECT_TRUE(r.done());
}

TEST(IndexGaps, RefusesIndicesOutOfRangeWithoutWrapping) {
  std::vector<std::uint8_t> bytes;
  put_varint(bytes, 3);
  put_varint(bytes, ~std::uint64_t{0} - 2);  // would wrap around to a small index
  IndexGapReader r(bytes.data(), bytes.size(), "positions");
  EXPECT_EQ(r.next(10), 3u);
  try {
    r.next(10);
    ADD_FAILURE() << "accepted a wrapping gap";
  } catch (const InvalidInput& e) {
    EXPECT_STREQ(e.what(), "positions: vertex index past 2^32 out of range (10 vertices)");
  }
  std::vector<std::uint8_t> at_end;
  put_varint(at_end, 10);
  IndexGapReader end(at_end.data(), at_end.size(), "mask");
  EXPECT_THROW(end.next(10), InvalidInput);
}

}  // namespace
