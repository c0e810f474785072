// libFuzzer target for the mesh readers. The first byte picks the parser (PLY, OBJ, OFF,
// STL), the rest is the file. Readers may only reject input with csculpt::InvalidInput; any
// other exception, crash, sanitizer report, leak or runaway allocation is a bug.
//
// Built and run for 20 s by the CTest test `fuzz` (tests/fuzz/run_fuzz.sh, fuzz.mk). A longer
// run, from the repository root after one `ctest -L fuzz` (which builds the binary):
//   cp -r tests/fuzz/corpus/mesh /tmp/mesh-corpus
//   build/tests/fuzz/work/fuzz_mesh_readers -max_total_time=300 -timeout=10 -max_len=4096 \
//     -rss_limit_mb=1024 -artifact_prefix=/tmp/ /tmp/mesh-corpus
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "csculpt/error.h"
#include "csculpt/io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string_view bytes(reinterpret_cast<const char*>(data + 1), size - 1);
  try {
    csculpt::Mesh mesh;
    switch (data[0] % 4) {
      case 0:
        mesh = csculpt::parse_ply(bytes, "fuzz.ply");
        break;
      case 1:
        mesh = csculpt::parse_obj(bytes, "fuzz.obj");
        break;
      case 2:
        mesh = csculpt::parse_off(bytes, "fuzz.off");
        break;
      default:
        mesh = csculpt::parse_stl(bytes, "fuzz.stl");
        break;
    }
    // Whatever a reader returns must be a mesh the merge accepts.
    csculpt::validate(mesh, "fuzz");
  } catch (const csculpt::InvalidInput&) {
  }
  return 0;
}
