// The base mesh the wire fuzzers decode against, shared with the test that writes and checks
// their seed corpus (tests/sdk/wire/test_wire.cpp): the seeds are real messages only for this mesh.
#pragma once

#include <cstdint>
#include <limits>
#include <vector>

#include "csculpt/mesh.h"
#include "csculpt/testkit/generate.h"

namespace csculpt::fuzz {

/// The version every seed names, so that csc_diff_decode reaches the decoder with them.
inline constexpr std::uint64_t base_version = 7;

/// 42 vertices with the material channels (widths 3, 1, 1) and an unbounded width-4 one, so
/// every channel width a message can carry has a counterpart.
inline Mesh base_mesh() {
  Mesh mesh = make_sphere(80, /*materials=*/true);
  ChannelDesc tint;
  tint.name = "tint";
  tint.width = 4;
  const std::vector<float> fill{0.25f, -1.5f, 3.f, 0.f};
  mesh.add_channel(tint, fill);
  return mesh;
}

}  // namespace csculpt::fuzz
