// libFuzzer target for the wire decoder: peek_diff_header and decode_diff on arbitrary bytes
// against a fixed base mesh with channels of widths 1, 3 and 4 (fuzz_base.h). They may only
// refuse input with csculpt::InvalidInput; any other exception, crash, sanitizer report, leak
// or runaway allocation is a bug. Beyond not crashing, it checks what the header promises:
// - peek and decode agree (decode succeeds only if peek does, with the same header);
// - a decoded diff passes validate() against the base;
// - it re-encodes: lossless bit for bit, and quantised within the stated bound.
//
// Built and run for 20 s by the CTest test `fuzz` (tests/fuzz/run_fuzz.sh). A longer run,
// from the repository root after one `ctest -L fuzz` (which builds the binary):
//   cp -r tests/fuzz/corpus/wire /tmp/wire-corpus
//   build/tests/fuzz/work/fuzz_wire_decode -max_total_time=300 -timeout=10 -rss_limit_mb=2048 \
//     -max_len=4096 -artifact_prefix=/tmp/ /tmp/wire-corpus
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <span>

#include "csculpt/diff.h"
#include "csculpt/error.h"
#include "csculpt/wire.h"
#include "fuzz_base.h"

namespace {

[[noreturn]] void fail(const char* what, const char* detail = "") {
  std::fprintf(stderr, "fuzz_wire_decode: %s %s\n", what, detail);
  std::abort();
}

const csculpt::Mesh& base() {
  static const csculpt::Mesh mesh = csculpt::fuzz::base_mesh();
  return mesh;
}

bool same_bits(const csculpt::AttributeDiff& a, const csculpt::AttributeDiff& b) {
  return a.indices == b.indices && a.values.size() == b.values.size() &&
         (a.values.empty() ||
          std::memcmp(a.values.data(), b.values.data(), a.values.size() * sizeof(float)) == 0);
}

/// Every component of `got` within the header's bound of `want` (both applied to the base,
/// so a dropped vertex is judged by the base value it keeps).
void check_bound(const float* want, const float* got, std::size_t n, double tol, const char* what) {
  for (std::size_t i = 0; i < n; ++i) {
    const double err = std::abs(double(want[i]) - double(got[i]));
    const float m = std::max(std::abs(want[i]), std::abs(got[i]));
    const double half_ulp = 0.5 * (double(std::nextafter(m, INFINITY)) - double(m));
    if (!(err <= 0.8 * tol + half_ulp + 1e-12 * (std::abs(double(want[i])) + tol)))
      fail("re-encoded value outside the stated bound:", what);
  }
}

void check_reencode(const csculpt::Diff& d) {
  const csculpt::Mesh& b = base();
  // Lossless: bit for bit (channels come back in the base's order, as decode gave them).
  const csculpt::Diff exact =
      csculpt::decode_diff(csculpt::encode_diff(d, b, {}, csculpt::EncodeOptions{0, 0, 0}), b);
  if (!same_bits(exact.positions, d.positions)) fail("lossless re-encode changed positions");
  for (std::size_t c = 0; c < d.channels.size(); ++c)
    if (!same_bits(exact.channels[c].change, d.channels[c].change))
      fail("lossless re-encode changed a channel");
  // Quantised: within the bound.
  const csculpt::EncodeOptions o{1e-4, 0, 1e-3};
  const csculpt::Diff q = csculpt::decode_diff(csculpt::encode_diff(d, b, {}, o), b);
  csculpt::validate(q, b, "re-encoded");
  csculpt::Mesh want = b, got = b;
  csculpt::apply_diff(d, want);
  csculpt::apply_diff(q, got);
  check_bound(reinterpret_cast<const float*>(want.positions.data()),
              reinterpret_cast<const float*>(got.positions.data()), 3 * b.vertex_count(),
              o.position_tolerance * csculpt::bbox_diagonal(b.positions), "positions");
  for (std::size_t c = 0; c < b.channels.size(); ++c)
    check_bound(want.channels[c].values.data(), got.channels[c].values.data(),
                want.channels[c].values.size(), o.channel_tolerance, "channel");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::uint8_t> bytes(data, size);
  bool peeked = false;
  csculpt::DiffHeader header;
  try {
    header = csculpt::peek_diff_header(bytes);
    peeked = true;
  } catch (const csculpt::InvalidInput&) {
  }
  // A tight limit must only ever refuse more, never crash.
  try {
    csculpt::DecodeLimits tight;
    tight.max_channels = 1;
    tight.max_bytes = 512;
    (void)csculpt::decode_diff(bytes, base(), nullptr, tight);
  } catch (const csculpt::InvalidInput&) {
  }

  csculpt::Diff d;
  csculpt::DiffHeader decoded_header;
  try {
    d = csculpt::decode_diff(bytes, base(), &decoded_header);
  } catch (const csculpt::InvalidInput&) {
    return 0;
  }
  if (!peeked) fail("decode_diff accepted a message peek_diff_header refused");
  if (decoded_header.base_version != header.base_version ||
      decoded_header.sequence != header.sequence || decoded_header.author != header.author ||
      decoded_header.vertex_count != header.vertex_count ||
      decoded_header.protocol != header.protocol)
    fail("peek_diff_header and decode_diff read different headers");
  try {
    csculpt::validate(d, base(), "decoded");
  } catch (const csculpt::InvalidInput& e) {
    fail("decoded diff fails validate():", e.what());
  }
  try {
    check_reencode(d);
  } catch (const std::exception& e) {
    fail("a decoded diff could not be re-encoded:", e.what());
  }
  return 0;
}
