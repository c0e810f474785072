// Diff messages through the C ABI: csc_diff_encode's bad arguments and limits, the bytes
// accessors, csc_diff_peek and csc_diff_decode with bad arguments, the wrong base version or
// mesh, and hostile bytes (random buffers, every truncation, every bit flip, mutations): a
// clean status and a readable message, or a diff that fits the base.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "capi_test.h"
#include "csculpt.h"
#include "host_arrays.h"

namespace {

using namespace capi_test;

TEST_F(CapiGridEdit, EncodeBadArguments) {
  csc_bytes* out = sentinel<csc_bytes>();
  EXPECT_FAILS(csc_diff_encode(nullptr, diff.get(), mesh.get(), nullptr),
               CSC_ERROR_INVALID_ARGUMENT, "out");
  EXPECT_FAILS(csc_diff_encode(&out, nullptr, mesh.get(), nullptr), CSC_ERROR_INVALID_ARGUMENT,
               "diff");
  EXPECT_FAILS(csc_diff_encode(&out, diff.get(), nullptr, nullptr), CSC_ERROR_INVALID_ARGUMENT,
               "base");
  EXPECT_FAILS(csc_diff_encode(&out, foreign<csc_diff>(mesh.get()), mesh.get(), nullptr),
               CSC_ERROR_INVALID_ARGUMENT, "kind");
  EXPECT_FAILS(csc_diff_encode(&out, diff.get(), foreign<csc_mesh>(diff.get()), nullptr),
               CSC_ERROR_INVALID_ARGUMENT, "kind");
  csc_encode_options o = CSC_ENCODE_OPTIONS_INIT;
  o.struct_size = sizeof(o) - 8;
  EXPECT_FAILS(csc_diff_encode(&out, diff.get(), mesh.get(), &o), CSC_ERROR_INVALID_ARGUMENT,
               "struct_size");
  for (double bad : {-1e-5, static_cast<double>(kNaN), static_cast<double>(kInf)}) {
    for (int field = 0; field < 3; ++field) {
      o = CSC_ENCODE_OPTIONS_INIT;
      (field == 0   ? o.position_tolerance
       : field == 1 ? o.position_scale
                    : o.channel_tolerance) = bad;
      EXPECT_FAILS(csc_diff_encode(&out, diff.get(), mesh.get(), &o), CSC_ERROR_INVALID_ARGUMENT,
                   "tolerance");
    }
  }
  const std::string long_author(257, 'a');
  o = CSC_ENCODE_OPTIONS_INIT;
  o.author = long_author.c_str();
  EXPECT_FAILS(csc_diff_encode(&out, diff.get(), mesh.get(), &o), CSC_ERROR_INVALID_ARGUMENT,
               "author");
  MeshPtr smaller = Grid(kN - 1).make();
  EXPECT_FAILS(csc_diff_encode(&out, diff.get(), smaller.get(), nullptr), CSC_ERROR_INVALID_INPUT,
               "vertices");
  EXPECT_EQ(out, sentinel<csc_bytes>());

  // 256 bytes is the limit, not past it.
  const std::string max_author(256, 'b');
  o.author = max_author.c_str();
  csc_bytes* b = nullptr;
  ASSERT_OK(csc_diff_encode(&b, diff.get(), mesh.get(), &o));
  BytesPtr kept(b);
  csc_message_info info = CSC_MESSAGE_INFO_INIT;
  ASSERT_OK(csc_diff_peek(csc_bytes_data(b), csc_bytes_size(b), &info));
  EXPECT_EQ(std::string(info.author), max_author);
}

TEST_F(CapiEveryHandle, BytesAccessorsOfNullAndForeignHandles) {
  for (const csc_bytes* bad :
       {static_cast<const csc_bytes*>(nullptr), foreign<const csc_bytes>(mesh.get()),
        foreign<const csc_bytes>(diff.get()), foreign<const csc_bytes>(merger.get())}) {
    EXPECT_EQ(csc_bytes_data(bad), nullptr);
    EXPECT_EQ(csc_bytes_size(bad), 0u);
  }
  EXPECT_NE(csc_bytes_data(bytes.get()), nullptr);
  EXPECT_GT(csc_bytes_size(bytes.get()), 0u);
}

/// A message that says something: "function: " then at least a few words of printable text.
::testing::AssertionResult readable_message(const char* function) {
  const std::string m = csc_last_error();
  const std::string prefix = std::string(function) + ": ";
  if (m.rfind(prefix, 0) != 0)
    return ::testing::AssertionFailure() << "message does not start with '" << prefix << "': " << m;
  const std::string rest = m.substr(prefix.size());
  const auto printable = std::count_if(rest.begin(), rest.end(), [](char ch) {
    return ch == ' ' || std::isalnum(static_cast<unsigned char>(ch));
  });
  if (rest.size() < 10 || rest.find(' ') == std::string::npos ||
      static_cast<std::size_t>(printable) * 10 < rest.size() * 8)
    return ::testing::AssertionFailure() << "message is not words: '" << m << "'";
  return ::testing::AssertionSuccess();
}

/// The receiver's two calls on `data`; every outcome must be a clean status.
void expect_clean_rejection_or_valid(const csc_mesh* base, const std::uint8_t* data,
                                     std::size_t size, bool must_fail, const std::string& what) {
  csc_message_info info = CSC_MESSAGE_INFO_INIT;
  info.sequence = 4242;
  mark_error();
  const csc_status peek = csc_diff_peek(data, size, &info);
  if (must_fail) {
    EXPECT_EQ(peek, CSC_ERROR_INVALID_INPUT) << what;
  }
  if (peek != CSC_OK) {
    EXPECT_TRUE(fails_with("csc_diff_peek", peek, CSC_ERROR_INVALID_INPUT, "")) << what;
    EXPECT_TRUE(readable_message("csc_diff_peek")) << what;
    EXPECT_EQ(info.sequence, 4242u) << what << ": peek wrote info on failure";
  }
  csc_diff* out = sentinel<csc_diff>();
  mark_error();
  const csc_status dec = csc_diff_decode(&out, base, 3, data, size, nullptr);
  if (must_fail) {
    EXPECT_NE(dec, CSC_OK) << what;
  }
  if (dec == CSC_OK) {
    EXPECT_EQ(peek, CSC_OK) << what << ": decoded what peek refused";
    DiffPtr d(out);
    // Whatever decodes is a diff that fits the base.
    csc_mesh* c = nullptr;
    ASSERT_OK(csc_mesh_clone(&c, base));
    MeshPtr copy(c);
    EXPECT_EQ(csc_mesh_apply_diff(copy.get(), d.get()), CSC_OK) << what << csc_last_error();
  } else {
    EXPECT_TRUE(dec == CSC_ERROR_INVALID_INPUT || dec == CSC_ERROR_UNKNOWN_BASE_VERSION)
        << what << ": " << csc_status_str(dec);
    EXPECT_TRUE(fails_with("csc_diff_decode", dec, dec, "")) << what;
    EXPECT_TRUE(readable_message("csc_diff_decode")) << what;
    EXPECT_EQ(out, sentinel<csc_diff>()) << what << ": decode wrote *out on failure";
  }
}

TEST_F(CapiEveryHandle, PeekAndDecodeBadArguments) {
  const auto* data = csc_bytes_data(bytes.get());
  const std::size_t size = csc_bytes_size(bytes.get());
  csc_message_info info = CSC_MESSAGE_INFO_INIT;
  info.sequence = 99;
  EXPECT_FAILS(csc_diff_peek(data, size, nullptr), CSC_ERROR_INVALID_ARGUMENT, "info");
  EXPECT_FAILS(csc_diff_peek(nullptr, size, &info), CSC_ERROR_INVALID_ARGUMENT, "data");
  info.struct_size = sizeof(info) - 1;
  EXPECT_FAILS(csc_diff_peek(data, size, &info), CSC_ERROR_INVALID_ARGUMENT, "struct_size");
  info.struct_size = 0;
  EXPECT_FAILS(csc_diff_peek(data, size, &info), CSC_ERROR_INVALID_ARGUMENT, "struct_size");
  EXPECT_EQ(info.sequence, 99u);
  info.struct_size = sizeof(info);
  EXPECT_FAILS(csc_diff_peek(nullptr, 0, &info), CSC_ERROR_INVALID_INPUT, "");
  EXPECT_EQ(info.sequence, 99u);

  csc_diff* out = sentinel<csc_diff>();
  EXPECT_FAILS(csc_diff_decode(nullptr, mesh.get(), 3, data, size, nullptr),
               CSC_ERROR_INVALID_ARGUMENT, "out");
  EXPECT_FAILS(csc_diff_decode(&out, nullptr, 3, data, size, nullptr), CSC_ERROR_INVALID_ARGUMENT,
               "base");
  EXPECT_FAILS(csc_diff_decode(&out, foreign<csc_mesh>(hierarchy.get()), 3, data, size, nullptr),
               CSC_ERROR_INVALID_ARGUMENT, "kind");
  EXPECT_FAILS(csc_diff_decode(&out, mesh.get(), 3, nullptr, size, nullptr),
               CSC_ERROR_INVALID_ARGUMENT, "data");
  info.struct_size = 4;
  EXPECT_FAILS(csc_diff_decode(&out, mesh.get(), 3, data, size, &info), CSC_ERROR_INVALID_ARGUMENT,
               "struct_size");
  EXPECT_EQ(out, sentinel<csc_diff>());
  EXPECT_EQ(info.sequence, 99u);
}

TEST_F(CapiGridEdit, DecodeAgainstTheWrongBaseOrMesh) {
  const auto* data = csc_bytes_data(bytes.get());
  const std::size_t size = csc_bytes_size(bytes.get());
  csc_diff* out = sentinel<csc_diff>();
  csc_message_info info = CSC_MESSAGE_INFO_INIT;
  info.sequence = 99;
  for (std::uint64_t version : {0ull, 2ull, 4ull, ~0ull})
    EXPECT_FAILS(csc_diff_decode(&out, mesh.get(), version, data, size, &info),
                 CSC_ERROR_UNKNOWN_BASE_VERSION, "version");
  MeshPtr smaller = Grid(kN - 1).make();
  EXPECT_FAILS(csc_diff_decode(&out, smaller.get(), 3, data, size, &info), CSC_ERROR_INVALID_INPUT,
               "vertices");
  MeshPtr bare = Grid(kN, false).make();  // lacks the channels the message carries
  EXPECT_FAILS(csc_diff_decode(&out, bare.get(), 3, data, size, &info), CSC_ERROR_INVALID_INPUT,
               "channel");
  Grid wide(kN);
  wide.channels[1].width = 2;  // "tint" of another width
  MeshPtr other_width = wide.make();
  EXPECT_FAILS(csc_diff_decode(&out, other_width.get(), 3, data, size, &info),
               CSC_ERROR_INVALID_INPUT, "width");
  EXPECT_EQ(out, sentinel<csc_diff>());
  EXPECT_EQ(info.sequence, 99u);

  ASSERT_OK(csc_diff_decode(&out, mesh.get(), 3, data, size, &info));
  DiffPtr d(out);
  EXPECT_EQ(info.sequence, 11u);
  EXPECT_EQ(info.base_version, 3u);
  EXPECT_STREQ(info.author, "ann");
}

TEST_F(CapiGridEdit, PeekBorrowsTheAuthorFromTheBytesAndAnAbsentAuthorIsEmpty) {
  const std::uint8_t* data = csc_bytes_data(bytes.get());
  const std::size_t size = csc_bytes_size(bytes.get());
  csc_message_info info = CSC_MESSAGE_INFO_INIT;
  ASSERT_OK(csc_diff_peek(data, size, &info));
  EXPECT_STREQ(info.author, "ann");
  const auto* author = reinterpret_cast<const std::uint8_t*>(info.author);
  EXPECT_TRUE(author >= data && author + 4 <= data + size) << "author not borrowed from data";
  EXPECT_EQ(info.protocol, csc_wire_protocol_version());
  EXPECT_EQ(info.vertex_count, kN * kN);

  csc_encode_options o = CSC_ENCODE_OPTIONS_INIT;
  o.author = nullptr;
  csc_bytes* b = nullptr;
  ASSERT_OK(csc_diff_encode(&b, diff.get(), mesh.get(), &o));
  BytesPtr anonymous(b);
  info = CSC_MESSAGE_INFO_INIT;
  ASSERT_OK(csc_diff_peek(csc_bytes_data(b), csc_bytes_size(b), &info));
  ASSERT_NE(info.author, nullptr);
  EXPECT_STREQ(info.author, "");
  csc_diff* d = nullptr;
  info = CSC_MESSAGE_INFO_INIT;
  ASSERT_OK(csc_diff_decode(&d, mesh.get(), 0, csc_bytes_data(b), csc_bytes_size(b), &info));
  DiffPtr decoded(d);
  ASSERT_NE(info.author, nullptr);
  EXPECT_STREQ(info.author, "");
}

TEST_F(CapiGrid, RandomBytesAreRejectedCleanly) {
  std::mt19937 rng(20240611);
  std::uniform_int_distribution<int> byte(0, 255);
  std::uniform_int_distribution<std::size_t> length(0, 600);
  for (int round = 0; round < 1500; ++round) {
    const std::size_t n = length(rng);
    // Exactly sized heap blocks: a read past the end is an ASan error.
    std::unique_ptr<std::uint8_t[]> buf(new std::uint8_t[n]);
    for (std::size_t i = 0; i < n; ++i) buf[i] = static_cast<std::uint8_t>(byte(rng));
    // Half of them carry the file identifier, so the verifier has to look further.
    if (round % 2 == 1 && n >= 8) std::memcpy(buf.get() + 4, "CSD1", 4);
    expect_clean_rejection_or_valid(mesh.get(), buf.get(), n, true,
                                    "random buffer " + std::to_string(round));
  }
}

TEST_F(CapiGridEdit, EveryTruncationOfAMessageIsRejected) {
  const std::vector<std::uint8_t> msg = to_vector(bytes.get());
  for (std::size_t len = 0; len < msg.size(); ++len) {
    std::unique_ptr<std::uint8_t[]> buf(new std::uint8_t[len]);
    std::copy(msg.begin(), msg.begin() + static_cast<std::ptrdiff_t>(len), buf.get());
    expect_clean_rejection_or_valid(mesh.get(), buf.get(), len, true,
                                    "cut at " + std::to_string(len));
  }
}

TEST_F(CapiGrid, EveryBitFlipOfASmallMessageIsHandledCleanly) {
  // A 3-vertex move and paint: a message small enough to flip every bit of.
  HostArrays edit(*host);
  for (std::uint32_t v : {5u, 40u, 41u}) {
    edit.positions[3 * v + 2] += 0.01f * static_cast<float>(v);
    edit.channels[0][v] = 0.25f;
  }
  DiffPtr small = capture(mesh.get(), edit);
  BytesPtr small_bytes = encode(small.get(), mesh.get());
  const std::vector<std::uint8_t> msg = to_vector(small_bytes.get());
  RecordProperty("small_message_bytes", static_cast<int>(msg.size()));
  ASSERT_LT(msg.size(), 400u);
  std::size_t decoded = 0, rejected = 0;
  for (std::size_t i = 0; i < msg.size(); ++i)
    for (int bit = 0; bit < 8; ++bit) {
      std::unique_ptr<std::uint8_t[]> buf(new std::uint8_t[msg.size()]);
      std::copy(msg.begin(), msg.end(), buf.get());
      buf[i] ^= static_cast<std::uint8_t>(1u << bit);
      csc_diff* out = nullptr;
      const csc_status s = csc_diff_decode(&out, mesh.get(), 3, buf.get(), msg.size(), nullptr);
      csc_diff_destroy(out);
      (s == CSC_OK ? decoded : rejected) += 1;
      expect_clean_rejection_or_valid(mesh.get(), buf.get(), msg.size(), false,
                                      "byte " + std::to_string(i) + " bit " + std::to_string(bit));
    }
  EXPECT_GT(rejected, 0u);
  RecordProperty("bit_flips_decoded", static_cast<int>(decoded));
  RecordProperty("bit_flips_rejected", static_cast<int>(rejected));
}

TEST_F(CapiGridEdit, RandomMutationsOfAMessageAreHandledCleanly) {
  const std::vector<std::uint8_t> msg = to_vector(bytes.get());
  std::mt19937 rng(77);
  std::uniform_int_distribution<std::size_t> pos(0, msg.size() - 1);
  std::uniform_int_distribution<int> byte(0, 255), edits(1, 8);
  for (int round = 0; round < 1500; ++round) {
    std::unique_ptr<std::uint8_t[]> buf(new std::uint8_t[msg.size()]);
    std::copy(msg.begin(), msg.end(), buf.get());
    for (int k = edits(rng); k > 0; --k) buf[pos(rng)] = static_cast<std::uint8_t>(byte(rng));
    expect_clean_rejection_or_valid(mesh.get(), buf.get(), msg.size(), false,
                                    "mutation " + std::to_string(round));
  }
}

}  // namespace
