/* A host of the installed libcsculpt: built only against the install tree (by CMake through
   find_package(csculpt) and by plain cc through pkg-config) to prove the package is usable on
   its own. Exits non-zero if any step fails. */
#include <csculpt.h>

#include <stdio.h>
#include <string.h>

#define N 4 /* an N x N grid of vertices */

static int check(csc_status status, const char* what) {
  if (status != CSC_OK) {
    fprintf(stderr, "%s: %s: %s\n", what, csc_status_str(status), csc_last_error());
    return 0;
  }
  return 1;
}

int main(void) {
  float positions[3 * N * N];
  uint32_t triangles[3 * 2 * (N - 1) * (N - 1)];
  float edited_a[3 * N * N];
  float edited_b[3 * N * N];
  uint32_t t = 0;
  int ok = 1;
  csc_mesh* base = NULL;
  csc_hierarchy* hierarchy = NULL;
  csc_merger* merger = NULL;
  csc_diff* diff_a = NULL;
  csc_diff* diff_b = NULL;
  csc_diff* merged = NULL;
  csc_mesh_desc desc = CSC_MESH_DESC_INIT;
  csc_vertex_arrays arrays_a = CSC_VERTEX_ARRAYS_INIT;
  csc_vertex_arrays arrays_b = CSC_VERTEX_ARRAYS_INIT;
  csc_vertex_arrays target = CSC_VERTEX_ARRAYS_INIT;
  const csc_diff* both[2];
  int x, y;

  /* A host built against MAJOR.MINOR runs with the same MAJOR and a MINOR at least as high. */
  if (csc_version() / 10000 != CSC_VERSION_MAJOR || csc_version() < CSC_VERSION_NUMBER) {
    fprintf(stderr, "loaded libcsculpt %s does not serve a host built for %s\n",
            csc_version_string(), CSC_VERSION_STRING);
    return 1;
  }

  for (y = 0; y < N; ++y)
    for (x = 0; x < N; ++x) {
      float* p = &positions[3 * (y * N + x)];
      p[0] = (float)x;
      p[1] = (float)y;
      p[2] = 0.f;
    }
  for (y = 0; y + 1 < N; ++y)
    for (x = 0; x + 1 < N; ++x) {
      uint32_t v = (uint32_t)(y * N + x);
      uint32_t quad[6] = {v, v + 1, v + N + 1, v, v + N + 1, v + N};
      memcpy(&triangles[t], quad, sizeof quad);
      t += 6;
    }
  desc.vertex_count = N * N;
  desc.positions = positions;
  desc.triangle_count = t / 3;
  desc.triangles = triangles;

  /* Two peers each lift one opposite corner of the grid in their own copy of the arrays. */
  memcpy(edited_a, positions, sizeof positions);
  memcpy(edited_b, positions, sizeof positions);
  edited_a[3 * 0 + 2] = 0.5f;
  edited_b[3 * (N * N - 1) + 2] = 0.25f;
  arrays_a.vertex_count = arrays_b.vertex_count = target.vertex_count = N * N;
  arrays_a.positions = edited_a;
  arrays_b.positions = edited_b;

  ok = check(csc_mesh_create(&base, &desc), "csc_mesh_create") &&
       check(csc_hierarchy_build(&hierarchy, base, NULL), "csc_hierarchy_build") &&
       check(csc_merger_create(&merger, hierarchy), "csc_merger_create") &&
       check(csc_diff_capture_arrays(&diff_a, base, &arrays_a), "capture a") &&
       check(csc_diff_capture_arrays(&diff_b, base, &arrays_b), "capture b");
  if (ok) {
    both[0] = diff_a;
    both[1] = diff_b;
    ok = check(csc_merger_merge(merger, &merged, base, both, 2, NULL), "csc_merger_merge");
  }
  if (ok) {
    /* The merge applied to the host's own copy of the base holds both edits (the blend moves
       each lifted corner most of the way, not exactly, on a grid this coarse). */
    target.positions = positions;
    ok = check(csc_diff_apply_arrays(merged, base, &target), "csc_diff_apply_arrays");
  }
  if (ok && !(positions[3 * 0 + 2] > 0.25f && positions[3 * (N * N - 1) + 2] > 0.125f)) {
    fprintf(stderr, "merged corners: %g %g\n", positions[2], positions[3 * (N * N - 1) + 2]);
    ok = 0;
  }

  csc_diff_destroy(merged);
  csc_diff_destroy(diff_b);
  csc_diff_destroy(diff_a);
  csc_merger_destroy(merger);
  csc_hierarchy_destroy(hierarchy);
  csc_mesh_destroy(base);
  if (!ok) return 1;
  printf("csculpt %s (header %s, wire protocol %u)\n", csc_version_string(), CSC_VERSION_STRING,
         (unsigned)csc_wire_protocol_version());
  return 0;
}
