// libFuzzer target for the C entry points that take bytes: csc_diff_peek and csc_diff_decode,
// through the C ABI (capi/include/csculpt.h), against a fixed base (fuzz_base.h). Each call
// must return a status, never crash or throw; and the statuses must keep the header's
// promises:
// - only CSC_OK, CSC_ERROR_INVALID_INPUT or CSC_ERROR_UNKNOWN_BASE_VERSION (INTERNAL means an
//   exception other than InvalidInput escaped the SDK), with a csc_last_error() on failure;
// - peek's author points into the bytes and ends with a NUL inside them;
// - decode refuses what peek refuses, and a message for another base version with
//   UNKNOWN_BASE_VERSION; what it accepts, csc_diff_get_info, csc_diff_positions,
//   csc_mesh_apply_diff and csc_diff_encode all work on.
//
// Built and run for 20 s by the CTest test `fuzz` (tests/fuzz/run_fuzz.sh). A longer run,
// from the repository root after one `ctest -L fuzz` (which builds the binary):
//   cp -r tests/fuzz/corpus/wire /tmp/capi-corpus
//   build/tests/fuzz/work/fuzz_capi_bytes -max_total_time=300 -timeout=10 -rss_limit_mb=2048 \
//     -max_len=4096 -artifact_prefix=/tmp/ /tmp/capi-corpus
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "csculpt.h"
#include "fuzz_base.h"

namespace {

[[noreturn]] void fail(const char* what, csc_status status = CSC_OK) {
  std::fprintf(stderr, "fuzz_capi_bytes: %s (status %d: %s; last error: %s)\n", what,
               static_cast<int>(status), csc_status_str(status), csc_last_error());
  std::abort();
}

void require(csc_status s, const char* what) {
  if (s != CSC_OK) fail(what, s);
}

/// A failure status this input may give; anything else is a bug.
void check_refusal(csc_status s, const char* what) {
  if (s != CSC_ERROR_INVALID_INPUT && s != CSC_ERROR_UNKNOWN_BASE_VERSION) fail(what, s);
  if (csc_last_error()[0] == '\0') fail("a failure without csc_last_error()", s);
}

/// The fuzz base, built through the C ABI from the same arrays the SDK-side fuzzer uses.
csc_mesh* base() {
  static csc_mesh* mesh = [] {
    const csculpt::Mesh m = csculpt::fuzz::base_mesh();
    std::vector<csc_channel_desc> channels;
    std::vector<const float*> values;
    for (const csculpt::Channel& c : m.channels) {
      csc_channel_desc d{};
      d.name = c.desc.name.c_str();
      d.width = c.desc.width;
      d.linearisation = static_cast<csc_linearisation>(c.desc.linearisation);
      d.min_value = c.desc.min_value;
      d.max_value = c.desc.max_value;
      channels.push_back(d);
      values.push_back(c.values.data());
    }
    csc_mesh_desc desc = CSC_MESH_DESC_INIT;
    desc.vertex_count = static_cast<std::uint32_t>(m.vertex_count());
    desc.positions = reinterpret_cast<const float*>(m.positions.data());
    desc.triangle_count = static_cast<std::uint32_t>(m.face_count());
    desc.triangles = reinterpret_cast<const std::uint32_t*>(m.triangles.data());
    desc.channel_count = static_cast<std::uint32_t>(channels.size());
    desc.channels = channels.data();
    desc.channel_values = values.data();
    csc_mesh* out = nullptr;
    require(csc_mesh_create(&out, &desc), "csc_mesh_create of the fuzz base");
    return out;
  }();
  return mesh;
}

void check_decoded(const csc_diff* diff, const csc_message_info& info) {
  csc_diff_info di = CSC_DIFF_INFO_INIT;
  require(csc_diff_get_info(diff, &di), "csc_diff_get_info");
  if (di.vertex_count != csc_mesh_vertex_count(base()) || di.vertex_count != info.vertex_count)
    fail("decoded diff has another vertex count");
  if (di.channel_count != csc_mesh_channel_count(base())) fail("decoded diff's channel count");
  if (info.author == nullptr || std::strlen(info.author) > 256) fail("decode's author");
  const std::uint32_t* indices = nullptr;
  const float* values = nullptr;
  std::uint32_t count = 0;
  require(csc_diff_positions(diff, &indices, &values, &count), "csc_diff_positions");
  if (count != di.position_changes) fail("position count differs from csc_diff_get_info");
  for (std::uint32_t i = 0; i < count; ++i) {
    if (indices[i] >= di.vertex_count || (i > 0 && indices[i] <= indices[i - 1]))
      fail("decoded position indices not increasing and in range");
    for (int c = 0; c < 3; ++c)
      if (!std::isfinite(values[3 * i + c])) fail("decoded position not finite");
  }
  csc_mesh* copy = nullptr;
  require(csc_mesh_clone(&copy, base()), "csc_mesh_clone");
  require(csc_mesh_apply_diff(copy, diff), "csc_mesh_apply_diff of a decoded diff");
  csc_mesh_destroy(copy);
  csc_bytes* bytes = nullptr;
  csc_encode_options options = CSC_ENCODE_OPTIONS_INIT;
  options.base_version = info.base_version;
  options.sequence = info.sequence;
  options.author = info.author;
  require(csc_diff_encode(&bytes, diff, base(), &options), "csc_diff_encode of a decoded diff");
  csc_diff* again = nullptr;
  require(csc_diff_decode(&again, base(), info.base_version, csc_bytes_data(bytes),
                          csc_bytes_size(bytes), nullptr),
          "csc_diff_decode of a re-encoded diff");
  csc_diff_destroy(again);
  csc_bytes_destroy(bytes);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  csc_message_info peeked = CSC_MESSAGE_INFO_INIT;
  const csc_status peek = csc_diff_peek(data, size, &peeked);
  if (peek == CSC_OK) {
    const char* a = peeked.author;
    const auto* begin = reinterpret_cast<const char*>(data);
    if (a == nullptr) fail("peek gave a NULL author");
    // "" for a message without an author is static; otherwise it lies inside the bytes.
    if (a[0] != '\0' || (a >= begin && a < begin + size)) {
      if (a < begin || a >= begin + size) fail("peek's author is not inside the bytes");
      if (std::memchr(a, '\0', static_cast<std::size_t>(begin + size - a)) == nullptr)
        fail("peek's author has no NUL inside the bytes");
    }
  } else {
    check_refusal(peek, "csc_diff_peek");
  }

  // At the seeds' base version, and at the version the message names.
  const std::uint64_t versions[2] = {
      csculpt::fuzz::base_version,
      peek == CSC_OK ? peeked.base_version : csculpt::fuzz::base_version + 1};
  for (const std::uint64_t version : versions) {
    csc_diff* diff = nullptr;
    csc_message_info info = CSC_MESSAGE_INFO_INIT;
    const csc_status s = csc_diff_decode(&diff, base(), version, data, size, &info);
    if (s != CSC_OK) {
      check_refusal(s, "csc_diff_decode");
      if (diff != nullptr) fail("csc_diff_decode failed but wrote its out-parameter");
      if (peek != CSC_OK && s != CSC_ERROR_INVALID_INPUT)
        fail("peek refused the bytes but decode did not say INVALID_INPUT", s);
      if (peek == CSC_OK && peeked.base_version != version && s != CSC_ERROR_UNKNOWN_BASE_VERSION)
        fail("a message for another version was not refused as UNKNOWN_BASE_VERSION", s);
      continue;
    }
    if (peek != CSC_OK) fail("csc_diff_decode accepted bytes csc_diff_peek refused");
    if (info.base_version != version || info.sequence != peeked.sequence ||
        std::strcmp(info.author, peeked.author) != 0)
      fail("csc_diff_decode and csc_diff_peek read different headers");
    check_decoded(diff, info);
    csc_diff_destroy(diff);
  }
  return 0;
}
