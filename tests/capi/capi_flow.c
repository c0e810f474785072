/*
 * The whole flow of a host, in plain C99, through libcsculpt.so only: build the agreed base
 * from the host's arrays, two artists edit copies of the host arrays, each edit is captured
 * (zero-copy), encoded, peeked and decoded on a receiver, the two are merged (in both orders)
 * and applied both into host arrays and into a csc_mesh. Every property checked here is one a
 * host relies on; any failure prints what went wrong and exits 1.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "csculpt.h"

static void fail_at(int line, const char* format, ...) {
  va_list args;
  fprintf(stderr, "capi_flow.c:%d: FAILED: ", line);
  va_start(args, format);
  vfprintf(stderr, format, args);
  va_end(args);
  fputc('\n', stderr);
  exit(1);
}

#define CHECK(cond, ...)                         \
  do {                                           \
    if (!(cond)) fail_at(__LINE__, __VA_ARGS__); \
  } while (0)

#define CSC(call)                                                                          \
  do {                                                                                     \
    csc_status status_ = (call);                                                           \
    if (status_ != CSC_OK)                                                                 \
      fail_at(__LINE__, "%s -> %s: %s", #call, csc_status_str(status_), csc_last_error()); \
  } while (0)

/* The grid: N x N vertices over [0,1]^2 with a gentle wave in z, so the surface is curved. */
enum { N = 64, V = N * N, T = 2 * (N - 1) * (N - 1) };
static const float kPi = 3.14159265358979f;

/* The channels the base mesh ends with: the host's own "mask" and the built-in material ones. */
enum { kChannels = 4 };

typedef struct Host {
  float positions[3 * V];
  float* channels[kChannels]; /* base channel order */
  uint32_t widths[kChannels];
} Host;

static void host_init(Host* h, const csc_mesh* mesh) {
  uint32_t c;
  memcpy(h->positions, csc_mesh_positions(mesh), sizeof h->positions);
  for (c = 0; c < kChannels; ++c) {
    csc_channel_view view = CSC_CHANNEL_VIEW_INIT;
    CSC(csc_mesh_channel(mesh, c, &view));
    h->widths[c] = view.desc.width;
    h->channels[c] = (float*)malloc(sizeof(float) * V * view.desc.width);
    CHECK(h->channels[c] != NULL, "out of memory");
    memcpy(h->channels[c], view.values, sizeof(float) * V * view.desc.width);
  }
}

static void host_free(Host* h) {
  uint32_t c;
  for (c = 0; c < kChannels; ++c) free(h->channels[c]);
}

static csc_vertex_arrays host_arrays(Host* h) {
  csc_vertex_arrays a = CSC_VERTEX_ARRAYS_INIT;
  a.vertex_count = V;
  a.positions = h->positions;
  a.channel_count = kChannels;
  a.channels = h->channels;
  return a;
}

/* Does vertex v of `a` differ bitwise from `b` in positions or any channel? */
static int vertex_differs(const Host* a, const Host* b, uint32_t v) {
  uint32_t c;
  if (memcmp(a->positions + 3 * v, b->positions + 3 * v, 3 * sizeof(float)) != 0) return 1;
  for (c = 0; c < kChannels; ++c) {
    const uint32_t w = a->widths[c];
    if (memcmp(a->channels[c] + w * v, b->channels[c] + w * v, w * sizeof(float)) != 0) return 1;
  }
  return 0;
}

static int hosts_equal(const Host* a, const Host* b) {
  uint32_t c;
  if (memcmp(a->positions, b->positions, sizeof a->positions) != 0) return 0;
  for (c = 0; c < kChannels; ++c)
    if (memcmp(a->channels[c], b->channels[c], sizeof(float) * V * a->widths[c]) != 0) return 0;
  return 1;
}

/* A brush falloff: 1 at `centre`, 0 from `radius` on (so the edits below have known supports). */
static float falloff(const float* p, float cx, float cy, float radius) {
  const float dx = p[0] - cx, dy = p[1] - cy;
  const float t = 1.f - (dx * dx + dy * dy) / (radius * radius);
  return t > 0.f ? t * t : 0.f;
}

static double max_abs_diff(const float* a, const float* b, uint32_t n) {
  double m = 0;
  uint32_t i;
  for (i = 0; i < n; ++i) {
    const double d = fabs((double)a[i] - (double)b[i]);
    if (d > m) m = d;
  }
  return m;
}

static csc_diff* merge2(csc_merger* merger, const csc_mesh* base, const csc_diff* first,
                        const csc_diff* second, csc_merge_method method) {
  const csc_diff* diffs[2];
  csc_merge_options options = CSC_MERGE_OPTIONS_INIT;
  csc_diff* out = NULL;
  diffs[0] = first;
  diffs[1] = second;
  options.method = method;
  CSC(csc_merger_merge(merger, &out, base, diffs, 2, &options));
  CHECK(out != NULL, "merge gave no diff");
  return out;
}

static csc_bytes* encode(const csc_diff* diff, const csc_mesh* base, uint64_t sequence,
                         const char* author) {
  csc_encode_options options = CSC_ENCODE_OPTIONS_INIT;
  csc_bytes* bytes = NULL;
  options.base_version = 7;
  options.sequence = sequence;
  options.author = author;
  CSC(csc_diff_encode(&bytes, diff, base, &options));
  CHECK(csc_bytes_data(bytes) != NULL && csc_bytes_size(bytes) > 0, "empty message");
  return bytes;
}

/* What a receiver does with bytes: peek the header, then decode against the named base. */
static csc_diff* receive(const csc_bytes* bytes, const csc_mesh* base, uint64_t sequence,
                         const char* author) {
  csc_message_info peeked = CSC_MESSAGE_INFO_INIT, info = CSC_MESSAGE_INFO_INIT;
  csc_diff* diff = NULL;
  CSC(csc_diff_peek(csc_bytes_data(bytes), csc_bytes_size(bytes), &peeked));
  CHECK(peeked.protocol == csc_wire_protocol_version(), "peek: protocol %u", peeked.protocol);
  CHECK(peeked.base_version == 7, "peek: base_version %llu",
        (unsigned long long)peeked.base_version);
  CHECK(peeked.sequence == sequence, "peek: sequence %llu", (unsigned long long)peeked.sequence);
  CHECK(peeked.vertex_count == V, "peek: vertex_count %u", peeked.vertex_count);
  CHECK(peeked.author != NULL && strcmp(peeked.author, author) == 0, "peek: author '%s'",
        peeked.author ? peeked.author : "(null)");
  CSC(csc_diff_decode(&diff, base, peeked.base_version, csc_bytes_data(bytes),
                      csc_bytes_size(bytes), &info));
  CHECK(diff != NULL, "decode gave no diff");
  CHECK(info.sequence == sequence && info.base_version == 7 && info.vertex_count == V,
        "decode: header differs from peek");
  CHECK(info.author != NULL && strcmp(info.author, author) == 0, "decode: author '%s'",
        info.author ? info.author : "(null)");
  return diff;
}

int main(void) {
  static float positions[3 * V];
  static uint32_t triangles[3 * T];
  static float mask[V];
  static Host base_host, alice, bob, merged_ab, merged_ba, summed, decoded_alice;
  static unsigned char in_a[V], in_b[V];
  csc_channel_desc mask_desc;
  const float* mask_values[1];
  csc_mesh_desc desc = CSC_MESH_DESC_INIT;
  csc_mesh *base = NULL, *applied = NULL;
  csc_hierarchy* hierarchy = NULL;
  csc_hierarchy_stats stats = CSC_HIERARCHY_STATS_INIT;
  csc_merger* merger = NULL;
  csc_diff *diff_a = NULL, *diff_b = NULL, *recv_a = NULL, *recv_b = NULL;
  csc_diff *m_ab = NULL, *m_ba = NULL, *m_sum = NULL, *lossless = NULL, *wrong = NULL;
  csc_bytes *bytes_a = NULL, *bytes_b = NULL, *bytes_lossless = NULL;
  csc_diff_info info_a = CSC_DIFF_INFO_INIT, info_b = CSC_DIFF_INFO_INIT;
  csc_diff_info info_ab = CSC_DIFF_INFO_INIT, info_ba = CSC_DIFF_INFO_INIT;
  csc_encode_options lossless_options = CSC_ENCODE_OPTIONS_INIT;
  csc_vertex_arrays arrays;
  uint32_t i, j, v, c, touched_a = 0, touched_b = 0;
  int32_t albedo;
  float diag;
  double pos_tol, err, max_move_a = 0;
  const uint32_t *idx_ab, *idx_ba;
  const float *val_ab, *val_ba;
  uint32_t count_ab, count_ba;

  /* ---- versions ---- */
  CHECK(csc_version() == CSC_VERSION_NUMBER, "csc_version() %u, header %u", csc_version(),
        (unsigned)CSC_VERSION_NUMBER);
  CHECK(strcmp(csc_version_string(), CSC_VERSION_STRING) == 0, "version string %s",
        csc_version_string());
  CHECK(csc_wire_protocol_version() >= 1, "wire protocol %u", csc_wire_protocol_version());

  /* ---- the base mesh, from the host's own arrays ---- */
  for (j = 0; j < N; ++j)
    for (i = 0; i < N; ++i) {
      const float x = (float)i / (N - 1), y = (float)j / (N - 1);
      float* p = positions + 3 * (j * N + i);
      p[0] = x;
      p[1] = y;
      p[2] = 0.05f * sinf(2.f * kPi * x) * cosf(2.f * kPi * y);
      mask[j * N + i] = x;
    }
  for (j = 0, c = 0; j + 1 < N; ++j)
    for (i = 0; i + 1 < N; ++i) {
      const uint32_t a = j * N + i, b = a + 1, d = a + N, e = d + 1;
      uint32_t* t = triangles + 6 * c++;
      t[0] = a, t[1] = b, t[2] = e;
      t[3] = a, t[4] = e, t[5] = d;
    }
  mask_desc.name = "mask";
  mask_desc.width = 1;
  mask_desc.linearisation = CSC_LINEARISATION_IDENTITY;
  mask_desc.min_value = 0.f;
  mask_desc.max_value = 1.f;
  mask_values[0] = mask;
  desc.vertex_count = V;
  desc.positions = positions;
  desc.triangle_count = T;
  desc.triangles = triangles;
  desc.channel_count = 1;
  desc.channels = &mask_desc;
  desc.channel_values = mask_values;
  CSC(csc_mesh_create(&base, &desc));
  CSC(csc_mesh_add_material_channels(base));
  CHECK(csc_mesh_vertex_count(base) == V && csc_mesh_triangle_count(base) == T, "mesh counts %u %u",
        csc_mesh_vertex_count(base), csc_mesh_triangle_count(base));
  CHECK(csc_mesh_channel_count(base) == kChannels, "%u channels", csc_mesh_channel_count(base));
  CHECK(memcmp(csc_mesh_positions(base), positions, sizeof positions) == 0,
        "positions not copied bit for bit");
  CHECK(memcmp(csc_mesh_triangles(base), triangles, sizeof triangles) == 0, "triangles not copied");
  CHECK(csc_mesh_find_channel(base, "mask") == 0, "mask is not channel 0");
  albedo = csc_mesh_find_channel(base, "albedo");
  CHECK(albedo > 0, "no albedo channel after csc_mesh_add_material_channels");
  {
    csc_channel_view view = CSC_CHANNEL_VIEW_INIT;
    CSC(csc_mesh_channel(base, (uint32_t)albedo, &view));
    CHECK(view.desc.width == 3 && view.desc.linearisation == CSC_LINEARISATION_SRGB &&
              view.desc.min_value == 0.f && view.desc.max_value == 1.f,
          "albedo: width %u linearisation %d range [%g, %g]", view.desc.width,
          (int)view.desc.linearisation, view.desc.min_value, view.desc.max_value);
    CSC(csc_mesh_channel(base, 0, &view));
    CHECK(memcmp(view.values, mask, sizeof mask) == 0, "mask values not copied");
  }
  diag = csc_mesh_bbox_diagonal(base);
  CHECK(diag > 1.4f && diag < 1.5f, "bbox diagonal %g", diag);

  CSC(csc_hierarchy_build(&hierarchy, base, NULL));
  CSC(csc_hierarchy_get_stats(hierarchy, &stats));
  CHECK(stats.vertices == V && stats.faces == T && stats.top_nodes == 1 && stats.levels > 1,
        "hierarchy stats: %u vertices %u faces %u levels %u top nodes", stats.vertices, stats.faces,
        stats.levels, stats.top_nodes);
  CSC(csc_merger_create(&merger, hierarchy));

  /* ---- two artists edit copies of the host arrays ---- */
  host_init(&base_host, base);
  host_init(&alice, base);
  host_init(&bob, base);
  for (v = 0; v < V; ++v) {
    /* Alice grabs the left region up. */
    float* p = alice.positions + 3 * v;
    const float wa = falloff(p, 0.2f, 0.5f, 0.15f);
    float* q = bob.positions + 3 * v;
    const float wb = falloff(q, 0.78f, 0.5f, 0.15f);
    p[2] += 0.12f * wa;
    /* Bob paints the right region red and nudges it sideways. */
    if (wb > 0.f) {
      float* rgb = bob.channels[albedo] + 3 * v;
      q[1] += 0.02f * wb;
      rgb[0] = rgb[0] + (0.95f - rgb[0]) * wb;
      rgb[1] = rgb[1] * (1.f - wb);
      rgb[2] = rgb[2] * (1.f - wb);
    }
  }
  for (v = 0; v < V; ++v) {
    in_a[v] = (unsigned char)vertex_differs(&alice, &base_host, v);
    in_b[v] = (unsigned char)vertex_differs(&bob, &base_host, v);
    touched_a += in_a[v];
    touched_b += in_b[v];
    CHECK(!(in_a[v] && in_b[v]), "the test's edits overlap at vertex %u", v);
    if (in_a[v]) {
      const double d = fabs((double)alice.positions[3 * v + 2] - base_host.positions[3 * v + 2]);
      if (d > max_move_a) max_move_a = d;
    }
  }
  CHECK(touched_a > 100 && touched_b > 100, "edits too small: %u and %u vertices", touched_a,
        touched_b);

  /* ---- capture (zero-copy from the host arrays) ---- */
  arrays = host_arrays(&alice);
  CSC(csc_diff_capture_arrays(&diff_a, base, &arrays));
  arrays = host_arrays(&bob);
  CSC(csc_diff_capture_arrays(&diff_b, base, &arrays));
  CSC(csc_diff_get_info(diff_a, &info_a));
  CSC(csc_diff_get_info(diff_b, &info_b));
  CHECK(info_a.touched_vertices == touched_a && info_a.position_changes == touched_a,
        "alice's diff: %u touched, %u moved; the host changed %u", info_a.touched_vertices,
        info_a.position_changes, touched_a);
  CHECK(info_b.touched_vertices == touched_b, "bob's diff: %u touched; the host changed %u",
        info_b.touched_vertices, touched_b);
  CHECK(info_a.vertex_count == V && info_a.channel_count == kChannels, "alice's diff layout");
  CHECK(info_a.digest != info_b.digest, "different diffs with one digest");

  /* ---- encode, send, peek, decode ---- */
  bytes_a = encode(diff_a, base, 1, "alice");
  bytes_b = encode(diff_b, base, 1, "bob");
  printf("message sizes: alice %u vertices -> %zu bytes, bob %u vertices -> %zu bytes\n", touched_a,
         csc_bytes_size(bytes_a), touched_b, csc_bytes_size(bytes_b));
  recv_a = receive(bytes_a, base, 1, "alice");
  recv_b = receive(bytes_b, base, 1, "bob");

  /* The decoded edit is the artist's within the wire tolerance (0.8 x 1e-5 x diagonal plus
   * half an ulp), and vertices it does not list keep the base's bits. */
  pos_tol = 1e-5 * diag;
  host_init(&decoded_alice, base);
  arrays = host_arrays(&decoded_alice);
  CSC(csc_diff_apply_arrays(recv_a, base, &arrays));
  err = max_abs_diff(decoded_alice.positions, alice.positions, 3 * V);
  CHECK(err <= pos_tol, "decoded alice: position error %g > %g", err, pos_tol);
  for (v = 0; v < V; ++v)
    if (!in_a[v])
      CHECK(!vertex_differs(&decoded_alice, &base_host, v),
            "decoded alice changed vertex %u she did not touch", v);

  /* A message for another base version is refused as such, and *out is left alone. */
  wrong = (csc_diff*)&wrong; /* a sentinel the call must not overwrite */
  {
    const csc_status s =
        csc_diff_decode(&wrong, base, 8, csc_bytes_data(bytes_a), csc_bytes_size(bytes_a), NULL);
    CHECK(s == CSC_ERROR_UNKNOWN_BASE_VERSION, "decode against version 8: %s (%s)",
          csc_status_str(s), csc_last_error());
    CHECK(wrong == (csc_diff*)&wrong, "a failed decode wrote *out");
    CHECK(csc_last_error()[0] != '\0', "no message for the failed decode");
  }

  /* Lossless options: the receiver gets the captured diff bit for bit. */
  lossless_options.base_version = 7;
  lossless_options.position_tolerance = 0;
  lossless_options.channel_tolerance = 0;
  CSC(csc_diff_encode(&bytes_lossless, diff_b, base, &lossless_options));
  CSC(csc_diff_decode(&lossless, base, 7, csc_bytes_data(bytes_lossless),
                      csc_bytes_size(bytes_lossless), NULL));
  {
    csc_diff_info li = CSC_DIFF_INFO_INIT;
    CSC(csc_diff_get_info(lossless, &li));
    CHECK(li.digest == info_b.digest && li.touched_vertices == info_b.touched_vertices,
          "lossless round trip changed the diff (digest %llx vs %llx)",
          (unsigned long long)li.digest, (unsigned long long)info_b.digest);
  }

  /* ---- merge, in both orders ---- */
  m_ab = merge2(merger, base, recv_a, recv_b, CSC_MERGE_FULL);
  m_ba = merge2(merger, base, recv_b, recv_a, CSC_MERGE_FULL);
  CSC(csc_diff_get_info(m_ab, &info_ab));
  CSC(csc_diff_get_info(m_ba, &info_ba));
  CHECK(info_ab.digest == info_ba.digest, "merge digest depends on the order");
  CSC(csc_diff_positions(m_ab, &idx_ab, &val_ab, &count_ab));
  CSC(csc_diff_positions(m_ba, &idx_ba, &val_ba, &count_ba));
  CHECK(count_ab == count_ba && memcmp(idx_ab, idx_ba, count_ab * sizeof(uint32_t)) == 0 &&
            memcmp(val_ab, val_ba, 3 * count_ab * sizeof(float)) == 0,
        "merged positions depend on the order");

  host_init(&merged_ab, base);
  host_init(&merged_ba, base);
  arrays = host_arrays(&merged_ab);
  CSC(csc_diff_apply_arrays(m_ab, base, &arrays));
  arrays = host_arrays(&merged_ba);
  CSC(csc_diff_apply_arrays(m_ba, base, &arrays));
  CHECK(hosts_equal(&merged_ab, &merged_ba), "merge in reversed order is not bit-identical");

  /* Untouched vertices keep the base's bits; each region carries its artist's edit. */
  for (v = 0; v < V; ++v)
    if (!in_a[v] && !in_b[v])
      CHECK(!vertex_differs(&merged_ab, &base_host, v), "merge changed untouched vertex %u", v);
  err = 0;
  for (v = 0; v < V; ++v)
    if (in_a[v]) {
      const double e = max_abs_diff(merged_ab.positions + 3 * v, alice.positions + 3 * v, 3);
      if (e > err) err = e;
    }
  printf("full merge: alice's region within %.3g of her edit (largest move %.3g)\n", err,
         max_move_a);
  /* The paper's merge blends multiscale isometries: a disjoint sculpt is kept to a few % of
   * its size (the SDK's unit tests measure the same bound), not exactly. */
  CHECK(err <= 0.05 * max_move_a + pos_tol, "full merge: alice's region off by %g", err);
  err = 0;
  for (v = 0; v < V; ++v)
    if (in_b[v]) {
      const double e =
          max_abs_diff(merged_ab.channels[albedo] + 3 * v, bob.channels[albedo] + 3 * v, 3);
      if (e > err) err = e;
    }
  /* A disjoint paint stays exact in the full merge, up to the wire's channel tolerance. */
  CHECK(err <= 1e-4 + 1e-6, "full merge: bob's paint off by %g", err);

  /* A per-vertex method (sum) keeps both disjoint sculpts to within the wire tolerance. */
  m_sum = merge2(merger, base, recv_b, recv_a, CSC_MERGE_SUM);
  host_init(&summed, base);
  arrays = host_arrays(&summed);
  CSC(csc_diff_apply_arrays(m_sum, base, &arrays));
  for (v = 0; v < V; ++v) {
    if (in_a[v]) {
      err = max_abs_diff(summed.positions + 3 * v, alice.positions + 3 * v, 3);
      CHECK(err <= pos_tol, "sum merge: vertex %u off alice's edit by %g", v, err);
    } else if (in_b[v]) {
      err = max_abs_diff(summed.positions + 3 * v, bob.positions + 3 * v, 3);
      CHECK(err <= pos_tol, "sum merge: vertex %u off bob's edit by %g", v, err);
      err = max_abs_diff(summed.channels[albedo] + 3 * v, bob.channels[albedo] + 3 * v, 3);
      CHECK(err <= 1e-4 + 1e-6, "sum merge: vertex %u off bob's paint by %g", v, err);
    } else {
      CHECK(!vertex_differs(&summed, &base_host, v), "sum merge changed untouched vertex %u", v);
    }
  }

  /* ---- the same merged diff applied to a csc_mesh gives the host's bits ---- */
  CSC(csc_mesh_clone(&applied, base));
  CSC(csc_mesh_apply_diff(applied, m_ab));
  CHECK(memcmp(csc_mesh_positions(applied), merged_ab.positions, sizeof merged_ab.positions) == 0,
        "csc_mesh_apply_diff and csc_diff_apply_arrays disagree on positions");
  for (c = 0; c < kChannels; ++c) {
    csc_channel_view view = CSC_CHANNEL_VIEW_INIT;
    CSC(csc_mesh_channel(applied, c, &view));
    CHECK(memcmp(view.values, merged_ab.channels[c], sizeof(float) * V * view.desc.width) == 0,
          "csc_mesh_apply_diff and csc_diff_apply_arrays disagree on channel %u", c);
  }
  /* The base itself is untouched by all of the above. */
  CHECK(memcmp(csc_mesh_positions(base), positions, sizeof positions) == 0, "the base changed");

  csc_mesh_destroy(applied);
  csc_diff_destroy(m_sum);
  csc_diff_destroy(m_ab);
  csc_diff_destroy(m_ba);
  csc_diff_destroy(lossless);
  csc_diff_destroy(recv_a);
  csc_diff_destroy(recv_b);
  csc_diff_destroy(diff_a);
  csc_diff_destroy(diff_b);
  csc_bytes_destroy(bytes_a);
  csc_bytes_destroy(bytes_b);
  csc_bytes_destroy(bytes_lossless);
  csc_merger_destroy(merger);
  csc_hierarchy_destroy(hierarchy);
  csc_mesh_destroy(base);
  host_free(&base_host);
  host_free(&alice);
  host_free(&bob);
  host_free(&merged_ab);
  host_free(&merged_ba);
  host_free(&summed);
  host_free(&decoded_alice);
  printf("capi_flow: all checks passed\n");
  return 0;
}
