/*
 * host_sample.c: a complete cSculpt host in C99, the template to copy into a DCC plug-in.
 *
 * It owns its scene the way Maya, Houdini or an in-house tool does: its own vertex positions
 * and one buffer per colour/material channel, edited in place by its "brush". It hosts a
 * session (prints "INVITE <invite>") or joins one, runs the host loop at ~60 Hz, makes N
 * deterministic strokes (a grab plus an albedo paint), optionally undoes its last one, waits
 * until the others have its work, prints "FINAL version=V digest=D" and leaves.
 *
 *   host-sample [--host | --join INVITE] [--mesh FILE] [--seconds S] [--linger S]
 *               [--strokes N] [--seed N] [--undo-last] [--out FILE.ply]
 *
 * Everything goes through csculpt.h and libcsculpt.so: no C++ SDK header. The body of the
 * loop in run() is what a DCC puts in its idle or timer callback; docs/c-api.md, "The host
 * loop in a real DCC", walks through it.
 */
#define _POSIX_C_SOURCE 200112L /* clock_gettime, nanosleep */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "csculpt.h"

enum { MAX_CHANNELS = 16, STROKE_FRAMES = 6 };

/* Every csc_status is checked: on failure say which call and why (csc_last_error), and fail. */
#define CHECK(call)                                                                              \
  do {                                                                                           \
    csc_status s_ = (call);                                                                      \
    if (s_ != CSC_OK) {                                                                          \
      fprintf(stderr, "host-sample: %s: %s: %s\n", #call, csc_status_str(s_), csc_last_error()); \
      return 1;                                                                                  \
    }                                                                                            \
  } while (0)

/* The host's scene. In a DCC these are its own buffers (a Maya MFnMesh's points and colour
 * set, a Houdini detail's P and Cd); the layout (channel order and widths) is the session
 * mesh's, which every peer shares. */
typedef struct scene {
  csc_mesh* layout; /* the mesh the arrays were made from: triangles, channel names, widths */
  uint32_t vertex_count, channel_count, stride; /* stride: 3 + the sum of channel widths */
  float* positions;
  float* channels[MAX_CHANNELS];
  uint32_t widths[MAX_CHANNELS];
  int albedo;               /* index of the "albedo" channel the brush paints */
  csc_vertex_arrays arrays; /* what every session call reads and writes, in place */
} scene;

/* A stroke under way: its vertices, their values before it (record_stroke's layout) and
 * the brush's weight on each. */
typedef struct stroke {
  uint32_t count, frame, centre, centre_index; /* centre: vertex id; index: in vertices */
  uint32_t* vertices;
  float *before, *weight;
  float offset[3], colour[3];
} stroke;

typedef struct options {
  const char *join, *mesh, *out;
  double seconds, linger;
  unsigned strokes, seed;
  int undo_last;
} options;

static double now_s(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* A deterministic pseudo-random number in [0, 1): the strokes depend on --seed only. */
static float rnd(uint64_t* state) {
  *state = *state * 6364136223846793005ULL + 1442695040888963407ULL;
  return (float)((*state >> 40) & 0xFFFFFF) / 16777216.f;
}

/* The digest `csculpt peer` prints (mesh_digest in peer/src/session.cpp): a word hash over the
 * positions, then each channel's name and values. Equal digests: bit-identical scenes. */
static uint64_t mix(uint64_t h, uint64_t w) {
  h ^= w + 0x9e3779b97f4a7c15ULL + (h << 6) + (h >> 2);
  h *= 0xff51afd7ed558ccdULL;
  return h ^ (h >> 32);
}
static uint64_t hash_bytes(uint64_t h, const void* data, size_t bytes) {
  const unsigned char* p = (const unsigned char*)data;
  uint64_t w, tail = bytes;
  size_t i = 0, k;
  for (; i + 8 <= bytes; i += 8) memcpy(&w, p + i, 8), h = mix(h, w); /* little-endian hosts */
  for (k = 1; i < bytes; ++i, ++k) tail ^= (uint64_t)p[i] << (8 * k);
  return mix(h, tail);
}
static uint64_t scene_digest(const scene* sc) {
  uint64_t h = hash_bytes(0x6a09e667f3bcc908ULL, sc->positions, 12u * sc->vertex_count);
  uint32_t c;
  for (c = 0; c < sc->channel_count; ++c) {
    csc_channel_view v = CSC_CHANNEL_VIEW_INIT;
    csc_mesh_channel(sc->layout, c, &v); /* cannot fail: c is in range */
    h = hash_bytes(h, v.desc.name, strlen(v.desc.name));
    h = hash_bytes(h, sc->channels[c], 4u * sc->widths[c] * sc->vertex_count);
  }
  return h;
}

/* A small UV sphere, for when no --mesh is given (a DCC has its own geometry). */
static int make_sphere(csc_mesh** out) {
  enum { RINGS = 24, SEGS = 48, V = 2 + (RINGS - 1) * SEGS, T = 2 * SEGS * (RINGS - 1) };
  static float p[3 * V];
  static uint32_t t[3 * T];
  csc_mesh_desc d = CSC_MESH_DESC_INIT;
  uint32_t r, s, n = 0, v = 2;
  p[2] = 1.f, p[5] = -1.f; /* the poles: vertices 0 and 1 */
  for (r = 1; r < RINGS; ++r)
    for (s = 0; s < SEGS; ++s, ++v) {
      double th = 3.14159265358979 * r / RINGS, ph = 2 * 3.14159265358979 * s / SEGS;
      p[3 * v] = (float)(sin(th) * cos(ph)), p[3 * v + 1] = (float)(sin(th) * sin(ph));
      p[3 * v + 2] = (float)cos(th);
    }
  for (r = 0; r + 1 < RINGS; ++r)
    for (s = 0; s < SEGS; ++s) {
      uint32_t a = 2 + r * SEGS + s, b = 2 + r * SEGS + (s + 1) % SEGS;
      if (r == 0) t[n++] = 0, t[n++] = a, t[n++] = b;
      if (r + 2 == RINGS)
        t[n++] = 1, t[n++] = b, t[n++] = a;
      else
        t[n++] = a, t[n++] = a + SEGS, t[n++] = b, t[n++] = b, t[n++] = a + SEGS, t[n++] = b + SEGS;
    }
  d.vertex_count = V, d.positions = p, d.triangle_count = n / 3, d.triangles = t;
  CHECK(csc_mesh_create(out, &d));
  return 0;
}

/* Fills the host's arrays from a mesh (the file or sphere it hosts, or the session's base
 * when it joins). A DCC would instead build its mesh from these values. */
static int scene_adopt(scene* sc, csc_mesh* mesh) {
  uint32_t c;
  sc->layout = mesh;
  sc->vertex_count = csc_mesh_vertex_count(mesh);
  sc->channel_count = csc_mesh_channel_count(mesh);
  sc->albedo = csc_mesh_find_channel(mesh, "albedo");
  if (sc->channel_count > MAX_CHANNELS || sc->albedo < 0) {
    fprintf(stderr, "host-sample: the mesh needs an albedo channel and at most %d channels\n",
            MAX_CHANNELS);
    return 1;
  }
  sc->positions = malloc(12u * sc->vertex_count);
  if (!sc->positions) return fprintf(stderr, "host-sample: out of memory\n"), 1;
  memcpy(sc->positions, csc_mesh_positions(mesh), 12u * sc->vertex_count);
  sc->stride = 3;
  for (c = 0; c < sc->channel_count; ++c) {
    csc_channel_view v = CSC_CHANNEL_VIEW_INIT;
    CHECK(csc_mesh_channel(mesh, c, &v));
    sc->widths[c] = v.desc.width, sc->stride += v.desc.width;
    sc->channels[c] = malloc(4u * v.desc.width * sc->vertex_count);
    if (!sc->channels[c]) return fprintf(stderr, "host-sample: out of memory\n"), 1;
    if ((int)c == sc->albedo && v.desc.width != 3) return fprintf(stderr, "albedo not RGB\n"), 1;
    memcpy(sc->channels[c], v.values, 4u * v.desc.width * sc->vertex_count);
  }
  sc->arrays.struct_size = sizeof sc->arrays;
  sc->arrays.vertex_count = sc->vertex_count, sc->arrays.positions = sc->positions;
  sc->arrays.channel_count = sc->channel_count, sc->arrays.channels = sc->channels;
  return 0;
}

/* The start of a stroke: the vertices within the brush radius of a random centre, and their
 * values now (all channels, the session mesh's order): what record_stroke needs at the end. */
static void stroke_begin(stroke* st, const scene* sc, uint64_t* rng) {
  const float diag = csc_mesh_bbox_diagonal(sc->layout), radius = 0.2f * diag;
  const float* cp;
  uint32_t v, c, k;
  st->centre = (uint32_t)(rnd(rng) * (float)sc->vertex_count) % sc->vertex_count;
  cp = &sc->positions[3 * st->centre];
  for (k = 0; k < 3; ++k)
    st->offset[k] = 0.05f * diag * (2 * rnd(rng) - 1), st->colour[k] = rnd(rng);
  st->count = st->frame = 0;
  for (v = 0; v < sc->vertex_count; ++v) {
    const float* p = &sc->positions[3 * v];
    float d2 = 0, w, *b;
    for (k = 0; k < 3; ++k) d2 += (p[k] - cp[k]) * (p[k] - cp[k]);
    if (d2 >= radius * radius) continue;
    w = 1 - d2 / (radius * radius);
    if (v == st->centre) st->centre_index = st->count;
    st->vertices[st->count] = v, st->weight[st->count] = w * w;
    b = &st->before[(size_t)st->count++ * sc->stride];
    memcpy(b, p, 12), b += 3;
    for (c = 0; c < sc->channel_count; ++c)
      memcpy(b, &sc->channels[c][v * sc->widths[c]], 4u * sc->widths[c]), b += sc->widths[c];
  }
}

/* One dab (one frame) of the stroke: grab the vertices along `offset` and paint albedo
 * towards `colour`, a fraction more each frame, written straight into the host's arrays. */
static void stroke_dab(stroke* st, scene* sc) {
  const float f = (float)++st->frame / STROKE_FRAMES;
  uint32_t i, k, a = (uint32_t)sc->albedo, before_albedo = 3;
  for (k = 0; k < a; ++k) before_albedo += sc->widths[k];
  for (i = 0; i < st->count; ++i) {
    const float w = f * st->weight[i], *b = &st->before[(size_t)i * sc->stride];
    const uint32_t v = st->vertices[i];
    for (k = 0; k < 3; ++k) {
      sc->positions[3 * v + k] = b[k] + w * st->offset[k];
      sc->channels[a][3 * v + k] =
          b[before_albedo + k] + w * (st->colour[k] - b[before_albedo + k]);
    }
  }
}

static const char* const kEventNames[] = {"joined",       "version",   "peer_joined",
                                          "peer_evasive", "peer_left", "merger_changed",
                                          "dropped",      "error",     "peer_live"};

/* Prints what the session reports (a DCC shows it in its status bar or peer list) and notes
 * a merged version waiting for csc_session_update. Returns 1 if polling failed. */
static int poll_events(csc_session* s, int* version_pending) {
  csc_session_event e = CSC_SESSION_EVENT_INIT;
  int32_t has = 0;
  for (;;) {
    CHECK(csc_session_poll(s, &e, &has));
    if (!has) return 0;
    if (e.kind == CSC_EVENT_VERSION) *version_pending = 1;
    printf(
        "EVENT %s peer=%llu version=%llu%s%s\n",
        (size_t)e.kind < sizeof kEventNames / sizeof *kEventNames ? kEventNames[e.kind] : "unknown",
        (unsigned long long)e.peer, (unsigned long long)e.version,
        e.message && *e.message ? " message=" : "", e.message ? e.message : "");
  }
}

static int parse_args(int argc, char** argv, options* o) {
  int i, host = 0;
  o->join = o->mesh = o->out = NULL, o->seconds = 2, o->linger = 1, o->strokes = 3, o->seed = 1;
  o->undo_last = 0;
  for (i = 1; i < argc; ++i) {
#define VALUE_OF(name) (i + 1 < argc && !strcmp(argv[i], name) && ++i)
    /* clang-format off */
    if (!strcmp(argv[i], "--host")) host = 1;
    else if (!strcmp(argv[i], "--undo-last")) o->undo_last = 1;
    else if (VALUE_OF("--join")) o->join = argv[i];
    else if (VALUE_OF("--mesh")) o->mesh = argv[i];
    else if (VALUE_OF("--out")) o->out = argv[i];
    else if (VALUE_OF("--seconds")) o->seconds = atof(argv[i]);
    else if (VALUE_OF("--linger")) o->linger = atof(argv[i]);
    else if (VALUE_OF("--strokes")) o->strokes = (unsigned)atoi(argv[i]);
    else if (VALUE_OF("--seed")) o->seed = (unsigned)atoi(argv[i]);
    else {
      fprintf(stderr, "host-sample: bad argument '%s'\nusage: host-sample [--host | --join "
              "INVITE] [--mesh FILE] [--seconds S] [--linger S] [--strokes N] [--seed N] "
              "[--undo-last] [--out FILE.ply]\n", argv[i]);
      return 1;
    }
    /* clang-format on */
  }
  if (host == (o->join != NULL) || (o->join && o->mesh)) {
    fprintf(stderr, "host-sample: give --host (optionally with --mesh) or --join INVITE\n");
    return 1;
  }
  return 0;
}

/* Writes the host's arrays as a mesh file (the session mesh's triangles and channels). */
static int save_scene(const scene* sc, const char* path) {
  csc_channel_desc descs[MAX_CHANNELS];
  const float* values[MAX_CHANNELS];
  csc_mesh_desc d = CSC_MESH_DESC_INIT;
  csc_mesh* out;
  uint32_t c;
  for (c = 0; c < sc->channel_count; ++c) {
    csc_channel_view v = CSC_CHANNEL_VIEW_INIT;
    CHECK(csc_mesh_channel(sc->layout, c, &v));
    descs[c] = v.desc, values[c] = sc->channels[c];
  }
  d.vertex_count = sc->vertex_count, d.positions = sc->positions;
  d.triangle_count = csc_mesh_triangle_count(sc->layout);
  d.triangles = csc_mesh_triangles(sc->layout);
  d.channel_count = sc->channel_count, d.channels = descs, d.channel_values = values;
  CHECK(csc_mesh_create(&out, &d));
  if (csc_mesh_write(out, path) != CSC_OK) {
    fprintf(stderr, "host-sample: cannot save %s: %s\n", path, csc_last_error());
    csc_mesh_destroy(out);
    return 1;
  }
  csc_mesh_destroy(out);
  return 0;
}

/* The undo line: the undone stroke's centre vertex before the stroke and as the stroke left
 * it (`after`, taken before the undo), so a test can check where it lands on the others. */
static void report_undo(const stroke* st, const scene* sc, const float* after, uint32_t n) {
  const float* b = &st->before[(size_t)st->centre_index * sc->stride];
  printf("UNDO vertices=%u centre=%u before=%.9g,%.9g,%.9g after=%.9g,%.9g,%.9g\n", n, st->centre,
         b[0], b[1], b[2], after[0], after[1], after[2]);
}

/* The session's life: host or join, the loop, the final line. Handles are left in `sc` and
 * `*s` for main to release whatever happens. */
static int run(const options* o, scene* sc, stroke* st, csc_session** s) {
  csc_mesh* mesh = NULL;
  csc_session_options so = CSC_SESSION_OPTIONS_INIT;
  csc_session_stats stats = CSC_SESSION_STATS_INIT;
  uint64_t rng = 0x9E3779B97F4A7C15ULL ^ o->seed;
  unsigned made = 0, undone = 0;
  uint32_t strokes_unsent = 0, applied, k;
  int in_stroke = 0, version_pending = 0;
  double start, last_submit = 0, idle_since = -1;
  const struct timespec frame = {0, 16000000L}; /* ~60 Hz */
  so.name = "host-sample";

  /* Host: the artist's current mesh becomes version 0. Join: the session's mesh replaces
   * the scene (a DCC asks first, or opens it as a new object). */
  if (!o->join) {
    if (o->mesh)
      CHECK(csc_mesh_read(&mesh, o->mesh));
    else if (make_sphere(&mesh))
      return 1;
    sc->layout = mesh;                           /* main destroys it from here on */
    CHECK(csc_mesh_add_material_channels(mesh)); /* albedo, metallic, roughness if missing */
    CHECK(csc_session_create(s, mesh, &so));
    printf("INVITE %s\n", csc_session_invite(*s));
  } else {
    csc_status status = csc_session_join(s, o->join, &so); /* waits for the snapshot */
    if (status != CSC_OK) {
      fprintf(stderr, "host-sample: cannot join the session: %s\n", csc_last_error());
      return 1;
    }
    CHECK(csc_session_copy_base(&mesh, *s));
    sc->layout = mesh;
  }
  if (scene_adopt(sc, mesh)) return 1;
  st->vertices = malloc(sizeof(uint32_t) * sc->vertex_count);
  st->weight = malloc(sizeof(float) * sc->vertex_count);
  st->before = malloc(sizeof(float) * sc->stride * sc->vertex_count);
  if (!st->vertices || !st->weight || !st->before) return fprintf(stderr, "out of memory\n"), 1;
  printf("READY id=%llu version=%llu vertices=%u\n", (unsigned long long)csc_session_id(*s),
         (unsigned long long)csc_session_version(*s), sc->vertex_count);

  /* The host loop: one turn per frame (~60 Hz). In a DCC this is the body of the idle or
   * timer callback; the rest of the application runs between turns. Nothing here waits on
   * the network: the session has its own thread. */
  for (start = now_s();;) {
    const double now = now_s() - start;
    csc_presence me = CSC_PRESENCE_INIT;
    if (poll_events(*s, &version_pending)) return 1;
    CHECK(csc_session_get_stats(*s, &stats));
    /* 1. Merged versions in, between strokes only: a remote write under the brush would
     *    fight the artist and make the stroke's before-values stale. */
    if (!in_stroke && (version_pending || stats.version != csc_session_version(*s))) {
      CHECK(csc_session_update(*s, &sc->arrays, &applied));
      version_pending = 0; /* a DCC refreshes normals and GPU buffers when applied > 0 */
    }
    /* 2. The artist: strokes spread over --seconds, each STROKE_FRAMES frames long. */
    if (!in_stroke && made < o->strokes && now >= o->seconds * made / o->strokes)
      stroke_begin(st, sc, &rng), in_stroke = 1;
    if (in_stroke) {
      stroke_dab(st, sc);
      for (k = 0; k < 3; ++k) me.position[k] = sc->positions[3 * st->centre + k];
      me.radius = 0.2f * csc_mesh_bbox_diagonal(mesh), me.active = me.visible = 1;
      if (st->frame == STROKE_FRAMES) { /* the stroke ends: record it so undo can take it back */
        CHECK(csc_session_record_stroke(*s, &sc->arrays, st->vertices, st->count, st->before));
        in_stroke = 0, ++made, ++strokes_unsent;
        printf("STROKE %u vertices=%u centre=%u\n", made, st->count, st->centre);
      }
    }
    CHECK(csc_session_set_presence(*s, &me)); /* the brush cursor the others draw */
    /* 3. Ctrl+Z on the last stroke, once the others have it: the undo travels as an edit. */
    if (o->undo_last && !undone && made == o->strokes && !in_stroke && !strokes_unsent &&
        stats.strokes_acknowledged == stats.strokes_submitted) {
      uint32_t n;
      float after[3];
      memcpy(after, &sc->positions[3 * st->centre], sizeof after);
      CHECK(csc_session_undo(*s, &sc->arrays, NULL, &n)); /* a DCC redraws the n vertices */
      report_undo(st, sc, after, n);
      undone = 1, strokes_unsent += n > 0; /* sent like a stroke */
    }
    /* 4. Submit between strokes, at least once per sync interval while edits are unmerged. */
    if (!in_stroke && now - last_submit >= so.sync_ms / 1000.0 &&
        (strokes_unsent || stats.strokes_acknowledged < stats.strokes_submitted)) {
      int32_t sent;
      CHECK(csc_session_submit(*s, &sc->arrays, strokes_unsent, &sent));
      strokes_unsent = 0; /* counted whether or not anything was new to send */
      last_submit = now;
    }
    fflush(stdout);
    /* 5. Idle: strokes (and the undo) made, merged and applied. Stay --linger seconds more
     *    (the others' late edits keep arriving), then leave. */
    if (made == o->strokes && undone == (unsigned)o->undo_last && !in_stroke && !strokes_unsent &&
        stats.strokes_acknowledged == stats.strokes_submitted && !version_pending &&
        stats.version == csc_session_version(*s)) {
      if (idle_since < 0) idle_since = now;
      if (now - idle_since >= o->linger) break;
    } else {
      idle_since = -1;
    }
    if (now > o->seconds + o->linger + 60) {
      fprintf(stderr, "host-sample: the session did not take this host's edits in 60 s\n");
      return 1;
    }
    nanosleep(&frame, NULL); /* a DCC returns from its callback here instead */
  }
  printf("FINAL version=%llu digest=%016llx strokes=%u submitted=%llu acknowledged=%llu\n",
         (unsigned long long)csc_session_version(*s), (unsigned long long)scene_digest(sc), made,
         (unsigned long long)stats.strokes_submitted,
         (unsigned long long)stats.strokes_acknowledged);
  if (o->out && save_scene(sc, o->out)) return 1;
  CHECK(csc_session_leave(*s)); /* the others are told at once rather than by expiry */
  return 0;
}

int main(int argc, char** argv) {
  options o;
  scene sc;
  stroke st;
  csc_session* s = NULL;
  int rc;
  uint32_t c;
  memset(&sc, 0, sizeof sc), memset(&st, 0, sizeof st);
  /* A host built against this header needs a library of the same major, at least as new. */
  if (csc_version() / 10000 != CSC_VERSION_MAJOR || csc_version() < CSC_VERSION_NUMBER) {
    fprintf(stderr, "host-sample: built for cSculpt %s, loaded %s\n", CSC_VERSION_STRING,
            csc_version_string());
    return 1;
  }
  if (parse_args(argc, argv, &o)) return 1;
  rc = run(&o, &sc, &st, &s);
  fflush(stdout);
  csc_session_destroy(s); /* leaves if run() did not; accepts NULL */
  csc_mesh_destroy(sc.layout);
  free(sc.positions), free(st.vertices), free(st.weight), free(st.before);
  for (c = 0; c < MAX_CHANNELS; ++c) free(sc.channels[c]);
  return rc;
}
