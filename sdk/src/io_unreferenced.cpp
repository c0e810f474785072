// The readers' limit on unused vertices. A face-less vertex costs as much as a used one in
// every later step (hierarchy, merges, snapshots: 10-30x its bytes in the file) while adding
// nothing a sculptor can touch, so a file that is mostly such vertices (a sparse file, a
// point cloud with a token face) is refused at the reader, before those steps run. Stray
// vertices that exporters leave are few; a small mesh is cheap whatever it holds.
#include "io_detail.h"

namespace csculpt::io_detail {

void check_unreferenced(const Mesh& mesh, std::string_view what) {
  const std::size_t n = mesh.positions.size();
  if (n <= kMaxUnreferencedVertices) return;
  std::vector<bool> used(n);
  std::size_t referenced = 0;
  for (const Triangle& t : mesh.triangles) {
    for (const std::uint32_t i : t) {
      if (i < n && !used[i]) {
        used[i] = true;
        ++referenced;
      }
    }
  }
  const std::size_t unreferenced = n - referenced;
  if (unreferenced > kMaxUnreferencedVertices && unreferenced > n / 2) {
    throw InvalidInput(cat(what, ": ", unreferenced, " of ", n,
                           " vertices are used by no face (at most half, or ",
                           kMaxUnreferencedVertices, ", may be unused)"));
  }
}

}  // namespace csculpt::io_detail
