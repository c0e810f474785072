/*
 * csculpt.h — the stable C ABI of the cSculpt SDK.
 *
 * cSculpt merges concurrent sculpting and painting edits of one mesh (paper: "cSculpt: A
 * System for Collaborative Sculpting", §3). This header is the whole public contract: what is
 * not declared here is not API. It is valid C99 and C++.
 *
 * Conventions (every function follows them unless its comment says otherwise):
 *
 * - Results. Functions that can fail return a csc_status; CSC_OK (0) is success. On failure
 *   nothing is written to out-parameters, no handle passed in is changed, and
 *   csc_last_error() describes the problem in words a person can read.
 * - Out-parameter first. A function that creates something takes `T** out` as its first
 *   argument; on success *out owns a new handle that the caller releases with the matching
 *   csc_*_destroy(). Every destroy function accepts NULL.
 * - Memory. Memory the library allocates is released by the library (destroy functions);
 *   the host never frees it with its own allocator. Pointers the library returns into a handle
 *   ("borrowed") stay valid until that handle is destroyed or changed by a call documented to
 *   change it.
 * - Threads. Any function may be called from any thread. Handles are not locked: a handle
 *   that a call changes (a csc_mesh being applied to, a csc_merger merging) must not be used
 *   by another thread during that call. Calls that only read a handle (marked "reads") may run
 *   concurrently on it. csc_hierarchy is immutable once built and may be shared freely.
 * - Errors. Bad arguments (NULL where a pointer is needed, a wrong struct_size, a handle of
 *   another kind) give CSC_ERROR_INVALID_ARGUMENT. A destroyed handle must not be passed again
 *   (its memory is gone: undefined behaviour, as for free()).
 *   Bad data (a malformed file or message, a diff for another mesh, NaN/Inf) gives
 *   CSC_ERROR_INVALID_INPUT. No C++ exception, type or STL object crosses this boundary.
 * - Growth. Option and description structs start with `struct_size` (set it with the
 *   matching CSC_*_INIT macro or sizeof); fields are only appended, so a host built against
 *   an older header keeps working. Enums are 32-bit. New behaviour arrives as new functions;
 *   existing signatures never change (see docs/api-stability.md).
 */
#ifndef CSCULPT_H
#define CSCULPT_H

#include <stddef.h>
#include <stdint.h>

#if defined(_WIN32)
#if defined(CSC_BUILDING_LIBRARY)
#define CSC_API __declspec(dllexport)
#else
#define CSC_API __declspec(dllimport)
#endif
#elif defined(__GNUC__)
#define CSC_API __attribute__((visibility("default")))
#else
#define CSC_API
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* ---- Version ------------------------------------------------------------------------------ */

#define CSC_VERSION_MAJOR 0
#define CSC_VERSION_MINOR 5
#define CSC_VERSION_PATCH 0
/** MAJOR * 10000 + MINOR * 100 + PATCH, as csc_version() returns it. */
#define CSC_VERSION_NUMBER (CSC_VERSION_MAJOR * 10000 + CSC_VERSION_MINOR * 100 + CSC_VERSION_PATCH)
#define CSC_VERSION_STRING "0.5.0"

/** The version of the library actually loaded (compare with CSC_VERSION_NUMBER: a host built
 *  against MAJOR.MINOR runs with any library of the same MAJOR and a MINOR at least as high).
 *  Never fails; thread-safe. */
CSC_API uint32_t csc_version(void);
/** "MAJOR.MINOR.PATCH" of the loaded library; static storage. */
CSC_API const char* csc_version_string(void);
/** The wire protocol version the library writes (diff messages); it reads 1 to this. */
CSC_API uint32_t csc_wire_protocol_version(void);

/* ---- Status and errors -------------------------------------------------------------------- */

typedef enum csc_status {
  CSC_OK = 0,
  /** A NULL or out-of-range argument, a wrong struct_size, a handle of another kind. */
  CSC_ERROR_INVALID_ARGUMENT = 1,
  /** Data that cannot be used: malformed file or message, mismatched mesh, NaN/Inf. */
  CSC_ERROR_INVALID_INPUT = 2,
  /** A file could not be opened, read or written. */
  CSC_ERROR_IO = 3,
  /** A diff message names a base version other than the one given to decode it against. */
  CSC_ERROR_UNKNOWN_BASE_VERSION = 4,
  /** Memory could not be allocated. */
  CSC_ERROR_OUT_OF_MEMORY = 5,
  /** A bug in the library (please report it with csc_last_error()). */
  CSC_ERROR_INTERNAL = 6,
  CSC_STATUS_MAX_ENUM = 0x7FFFFFFF
} csc_status;

/** A short constant description of a status ("invalid argument"); static storage; never NULL
 *  (unknown values give "unknown status"). */
CSC_API const char* csc_status_str(csc_status status);

/** The message of the most recent failed call on this thread ("" if none has failed). Owned
 *  by the library, valid until the next failing call on the same thread. Thread-local. */
CSC_API const char* csc_last_error(void);

/* ---- Handles ------------------------------------------------------------------------------ */

/** A triangle mesh: positions, triangles and named per-vertex float channels. */
typedef struct csc_mesh csc_mesh;
/** The multiresolution vertex hierarchy of a mesh's connectivity (paper §3.1). Immutable. */
typedef struct csc_hierarchy csc_hierarchy;
/** A sparse edit of a mesh: the changed vertices of positions and of each channel. */
typedef struct csc_diff csc_diff;
/** Merges diffs on one hierarchy; reuses its workspace between merges. */
typedef struct csc_merger csc_merger;
/** Bytes the library made (an encoded diff message). */
typedef struct csc_bytes csc_bytes;

/* ---- Channels ----------------------------------------------------------------------------- */

/** How a channel's stored values map to the linear space its edits merge in. */
typedef enum csc_linearisation {
  CSC_LINEARISATION_IDENTITY = 0, /**< already linear (metallic, masks) */
  CSC_LINEARISATION_SQUARE = 1,   /**< linear = v^2 (roughness -> alpha) */
  CSC_LINEARISATION_SRGB = 2,     /**< sRGB-encoded colour in [0,1] */
  CSC_LINEARISATION_MAX_ENUM = 0x7FFFFFFF
} csc_linearisation;

/** A per-vertex channel: `width` floats per vertex (1 to 4), vertex-major. */
typedef struct csc_channel_desc {
  const char* name; /**< unique within the mesh, 1 to 255 bytes, no NUL */
  uint32_t width;
  csc_linearisation linearisation;
  /** Valid range of stored values (min_value <= max_value); merged values are clamped into
   *  it. -INFINITY and INFINITY (from <math.h>) leave a channel unbounded. */
  float min_value;
  float max_value;
} csc_channel_desc;

/* ---- Meshes ------------------------------------------------------------------------------- */

/** A mesh described by the host's own arrays. The library copies them (a csc_mesh is the
 *  agreed base a session merges against, kept once per version); per-edit calls
 *  (csc_diff_capture_arrays, csc_diff_apply_arrays) work on the host's arrays in place. */
typedef struct csc_mesh_desc {
  uint32_t struct_size;
  uint32_t vertex_count;
  const float* positions; /**< 3 * vertex_count: x, y, z per vertex */
  uint32_t triangle_count;
  const uint32_t* triangles; /**< 3 * triangle_count vertex indices, counter-clockwise */
  uint32_t channel_count;
  const csc_channel_desc* channels; /**< channel_count descriptions (may be NULL if 0) */
  /** channel_count arrays of vertex_count * width floats; NULL entries are filled with 0. */
  const float* const* channel_values;
} csc_mesh_desc;
#define CSC_MESH_DESC_INIT \
  { sizeof(csc_mesh_desc), 0, NULL, 0, NULL, 0, NULL, NULL }

/** Builds a mesh from host arrays (copied). Fails with CSC_ERROR_INVALID_INPUT for no
 *  vertices or triangles, an index out of range or repeated within a triangle, NaN/Inf, a
 *  channel of width outside 1..4, a duplicate or empty channel name, min_value > max_value. */
CSC_API csc_status csc_mesh_create(csc_mesh** out, const csc_mesh_desc* desc);

/** Adds the built-in material channels (albedo RGB sRGB [0,1], metallic [0,1], roughness
 *  squared [0,1]) that the mesh lacks, filled with a grey rough dielectric. Changes `mesh`. */
CSC_API csc_status csc_mesh_add_material_channels(csc_mesh* mesh);

/** Reads a .ply, .obj, .off or .stl file (PLY vertex properties become channels; an OBJ's
 *  vertex colours, "v x y z r g b" in [0,1], the albedo channel, the default grey where a
 *  vertex has none). Fails with CSC_ERROR_IO if it cannot be read, CSC_ERROR_INVALID_INPUT
 *  (naming the file, the place and the problem) if it is malformed. */
CSC_API csc_status csc_mesh_read(csc_mesh** out, const char* path);

/** Writes .ply (binary, channels as vertex properties; reads back bit-identical) or .obj
 *  (positions, the albedo as vertex colours, faces; reads back bit-identical in those).
 *  Writes a temporary file and renames it: a failure leaves no partial file. Reads `mesh`. */
CSC_API csc_status csc_mesh_write(const csc_mesh* mesh, const char* path);

/** A deep copy. Reads `mesh`. */
CSC_API csc_status csc_mesh_clone(csc_mesh** out, const csc_mesh* mesh);

CSC_API void csc_mesh_destroy(csc_mesh* mesh);

/** Counts; 0 for NULL or a foreign handle. Read. */
CSC_API uint32_t csc_mesh_vertex_count(const csc_mesh* mesh);
CSC_API uint32_t csc_mesh_triangle_count(const csc_mesh* mesh);
CSC_API uint32_t csc_mesh_channel_count(const csc_mesh* mesh);

/** Borrowed read-only views of the mesh's arrays (3 floats per vertex; 3 indices per
 *  triangle); NULL for NULL or a foreign handle. Valid until the mesh is destroyed or changed
 *  (csc_mesh_apply_diff, csc_mesh_add_material_channels). */
CSC_API const float* csc_mesh_positions(const csc_mesh* mesh);
CSC_API const uint32_t* csc_mesh_triangles(const csc_mesh* mesh);

/** A channel as the mesh holds it; `desc.name` and `values` are borrowed like the arrays. */
typedef struct csc_channel_view {
  uint32_t struct_size;
  csc_channel_desc desc;
  const float* values; /**< vertex_count * desc.width */
} csc_channel_view;
#define CSC_CHANNEL_VIEW_INIT \
  { sizeof(csc_channel_view), {NULL, 0, CSC_LINEARISATION_IDENTITY, 0.f, 0.f}, NULL }

/** Channel `index` (0 .. channel_count-1). Reads `mesh`. */
CSC_API csc_status csc_mesh_channel(const csc_mesh* mesh, uint32_t index, csc_channel_view* out);

/** The index of the channel called `name`, or -1 (also for NULL arguments). Reads `mesh`. */
CSC_API int32_t csc_mesh_find_channel(const csc_mesh* mesh, const char* name);

/** Axis-aligned bounding-box diagonal of the positions. Reads `mesh`. */
CSC_API float csc_mesh_bbox_diagonal(const csc_mesh* mesh);

/* ---- Hierarchy ---------------------------------------------------------------------------- */

typedef struct csc_hierarchy_options {
  uint32_t struct_size;
  /** K, the blended parents per node (paper: 7; 1 gives a tree). 1 to 32. */
  uint32_t max_parents;
} csc_hierarchy_options;
#define CSC_HIERARCHY_OPTIONS_INIT \
  { sizeof(csc_hierarchy_options), 7 }

/** Builds the hierarchy of the mesh's connectivity (paper §3.1). A pure function of the
 *  triangles: every peer builds the same hierarchy bit for bit (compare csc_hierarchy_digest).
 *  `options` may be NULL for the defaults. Reads `mesh`; the hierarchy does not refer to it
 *  afterwards. */
CSC_API csc_status csc_hierarchy_build(csc_hierarchy** out, const csc_mesh* mesh,
                                       const csc_hierarchy_options* options);
CSC_API void csc_hierarchy_destroy(csc_hierarchy* hierarchy);

typedef struct csc_hierarchy_stats {
  uint32_t struct_size;
  uint32_t vertices;
  uint32_t faces;
  uint32_t levels;
  uint64_t nodes;          /**< over all levels */
  double node_ratio;       /**< nodes / vertices (paper: about 1.33) */
  double mean_level_ratio; /**< mean |L(i+1)| / |L(i)| */
  uint32_t top_nodes;      /**< nodes of the coarsest level: one per connected component */
} csc_hierarchy_stats;
#define CSC_HIERARCHY_STATS_INIT \
  { sizeof(csc_hierarchy_stats), 0, 0, 0, 0, 0.0, 0.0, 0 }

CSC_API csc_status csc_hierarchy_get_stats(const csc_hierarchy* hierarchy,
                                           csc_hierarchy_stats* out);
/** A 64-bit digest of every array of the hierarchy (0 for NULL). */
CSC_API uint64_t csc_hierarchy_digest(const csc_hierarchy* hierarchy);

/* ---- Diffs -------------------------------------------------------------------------------- */

/** The host's current vertex arrays, for capturing a diff from them or applying one into
 *  them without copying. Same vertex count and channel order as the base mesh. */
typedef struct csc_vertex_arrays {
  uint32_t struct_size;
  uint32_t vertex_count;
  float* positions; /**< 3 * vertex_count */
  uint32_t channel_count;
  /** channel_count arrays, in the base mesh's channel order, of vertex_count * width floats.
   *  A NULL entry is skipped (capture: unchanged; apply: not written). */
  float* const* channels;
} csc_vertex_arrays;
#define CSC_VERTEX_ARRAYS_INIT \
  { sizeof(csc_vertex_arrays), 0, NULL, 0, NULL }

/** The diff from `base` to `current`: every vertex whose position or channel value differs
 *  bitwise. Reads the host arrays in place (nothing is copied but the changes). Fails with
 *  CSC_ERROR_INVALID_INPUT if the counts differ from the base or a changed value is NaN/Inf.
 *  Reads `base` and `current`. */
CSC_API csc_status csc_diff_capture_arrays(csc_diff** out, const csc_mesh* base,
                                           const csc_vertex_arrays* current);

/** The diff from `base` to `edited` (same vertex count, triangles and channels). */
CSC_API csc_status csc_diff_capture(csc_diff** out, const csc_mesh* base, const csc_mesh* edited);

CSC_API void csc_diff_destroy(csc_diff* diff);

/** Writes the diff's values into `mesh` (its base, or a mesh of the same layout). Changes
 *  `mesh`; on failure `mesh` is unchanged. */
CSC_API csc_status csc_mesh_apply_diff(csc_mesh* mesh, const csc_diff* diff);

/** Writes the diff's values into the host's arrays in place (`target` has the base mesh's
 *  vertex count and channel order, given through `base`). Only changed vertices are written.
 *  On failure nothing is written. */
CSC_API csc_status csc_diff_apply_arrays(const csc_diff* diff, const csc_mesh* base,
                                         const csc_vertex_arrays* target);

typedef struct csc_diff_info {
  uint32_t struct_size;
  uint32_t vertex_count;     /**< of the mesh the diff is for */
  uint32_t touched_vertices; /**< changed in any attribute */
  uint32_t position_changes;
  uint32_t channel_count; /**< channels the diff carries (the base's channels) */
  uint64_t digest;        /**< content digest (what orders diffs canonically in a merge) */
} csc_diff_info;
#define CSC_DIFF_INFO_INIT \
  { sizeof(csc_diff_info), 0, 0, 0, 0, 0 }

CSC_API csc_status csc_diff_get_info(const csc_diff* diff, csc_diff_info* out);

/** The changed positions: `*count` vertex indices (strictly increasing) and 3 * `*count`
 *  edited values (x, y, z), borrowed until the diff is destroyed. */
CSC_API csc_status csc_diff_positions(const csc_diff* diff, const uint32_t** indices,
                                      const float** values, uint32_t* count);

/** The changes of channel `index` of the diff (the base's channel order): its name (borrowed),
 *  width, and `*count` indices with `*count * width` edited values. */
CSC_API csc_status csc_diff_channel(const csc_diff* diff, uint32_t index, const char** name,
                                    uint32_t* width, const uint32_t** indices, const float** values,
                                    uint32_t* count);

/* ---- Wire format (FlatBuffers DiffMessage, schema sdk/schema/diff.fbs) --------------------- */

/** What a diff message says about itself. `author` is borrowed from the bytes it was read
 *  from (csc_diff_peek) or from the diff handle (csc_diff_decode), NUL-terminated. */
typedef struct csc_message_info {
  uint32_t struct_size;
  uint32_t protocol;
  uint64_t base_version;
  uint64_t sequence;
  uint32_t vertex_count;
  const char* author;
} csc_message_info;
#define CSC_MESSAGE_INFO_INIT \
  { sizeof(csc_message_info), 0, 0, 0, 0, NULL }

typedef struct csc_encode_options {
  uint32_t struct_size;
  uint64_t base_version; /**< the agreed version the diff is taken against */
  uint64_t sequence;     /**< the author's counter */
  const char* author;    /**< NULL or at most 256 bytes */
  /** Largest position error, as a fraction of position_scale; 0 = lossless. */
  double position_tolerance;
  /** Length the tolerance is relative to; 0 = the base's bounding-box diagonal. */
  double position_scale;
  /** Largest channel error in stored units; 0 = lossless. */
  double channel_tolerance;
} csc_encode_options;
#define CSC_ENCODE_OPTIONS_INIT \
  { sizeof(csc_encode_options), 0, 0, NULL, 1e-5, 0.0, 1e-4 }

/** Encodes `diff` (taken against `base`) as a diff message: indices delta-coded, changes
 *  quantised within the stated tolerances (each decoded component within 0.8 x tolerance plus
 *  half a float ulp), or lossless with zero tolerances. A 10,000-vertex stroke is about 40 KB.
 *  `options` may be NULL (defaults above). Reads `diff` and `base`. The receivers' diff is
 *  csc_diff_decode of these bytes: a sender that must hold the same state as its peers uses
 *  that in place of `diff`. */
CSC_API csc_status csc_diff_encode(csc_bytes** out, const csc_diff* diff, const csc_mesh* base,
                                   const csc_encode_options* options);

/** Borrowed view of the bytes; valid until csc_bytes_destroy. */
CSC_API const uint8_t* csc_bytes_data(const csc_bytes* bytes);
CSC_API size_t csc_bytes_size(const csc_bytes* bytes);
CSC_API void csc_bytes_destroy(csc_bytes* bytes);

/** Verifies a message (FlatBuffers verifier with limits, identifier, protocol) and reads its
 *  header without decoding, e.g. to choose the base to decode it against. `info->author`
 *  points into `data`. Fails with CSC_ERROR_INVALID_INPUT saying what is wrong. */
CSC_API csc_status csc_diff_peek(const void* data, size_t size, csc_message_info* info);

/** Verifies and decodes a message against `base`, the mesh of version `base_version`. Fails
 *  with CSC_ERROR_UNKNOWN_BASE_VERSION if the message names another base version, and with
 *  CSC_ERROR_INVALID_INPUT (saying what is wrong) for corrupt bytes, a newer protocol, another
 *  vertex count, an unknown channel or width, indices out of range, inconsistent counts or
 *  non-finite values. `info` may be NULL; its `author` is borrowed from the new diff. */
CSC_API csc_status csc_diff_decode(csc_diff** out, const csc_mesh* base, uint64_t base_version,
                                   const void* data, size_t size, csc_message_info* info);

/* ---- Merge -------------------------------------------------------------------------------- */

/** The paper's method and the variants it is compared with (Fig. 3, Fig. 5). */
typedef enum csc_merge_method {
  CSC_MERGE_FULL = 0,                   /**< frame-transport merge (default) */
  CSC_MERGE_SINGLE_PARENT = 1,          /**< isometries, multiscale, a tree (K = 1) */
  CSC_MERGE_SINGLE_LEVEL_ISOMETRY = 2,  /**< isometries blended per vertex, no hierarchy */
  CSC_MERGE_MULTISCALE_TRANSLATION = 3, /**< translations on the hierarchy */
  CSC_MERGE_WEIGHTED_TRANSLATION = 4,   /**< translations blended per vertex by magnitude */
  CSC_MERGE_AVERAGE = 5,                /**< mean of the translations */
  CSC_MERGE_SUM = 6,                    /**< sum of the translations */
  CSC_MERGE_PAPER_BLEND = 7,            /**< the hierarchy merge with the paper's node blend */
  CSC_MERGE_HIERARCHY_BLEND = 8,        /**< the hierarchy merge, intent-counting node blend */
  CSC_MERGE_FRAME_TRANSPORT = 9,        /**< frame transport without the stacked hedge (0.5) */
  CSC_MERGE_METHOD_MAX_ENUM = 0x7FFFFFFF
} csc_merge_method;

/** "full", "single-parent", ...; NULL for an unknown value. Static storage. */
CSC_API const char* csc_merge_method_name(csc_merge_method method);
/** Parses a name csc_merge_method_name gives; CSC_ERROR_INVALID_ARGUMENT (listing the valid
 *  names) for any other. */
CSC_API csc_status csc_merge_method_from_name(csc_merge_method* out, const char* name);

typedef struct csc_merge_options {
  uint32_t struct_size;
  csc_merge_method method;
  /** The working frame (positions are merged centred on frame_center and divided by
   *  frame_scale, so the blend's magnitudes do not depend on units or placement). With
   *  use_frame = 0 it is fitted to the base's bounding box on each call; a session fits it
   *  once and passes it, so every peer merges in the same frame. */
  uint32_t use_frame;
  float frame_center[3];
  float frame_scale;
} csc_merge_options;
#define CSC_MERGE_OPTIONS_INIT \
  { sizeof(csc_merge_options), CSC_MERGE_FULL, 0, {0.f, 0.f, 0.f}, 1.f }

/** A merger for meshes of `hierarchy`'s connectivity. It keeps a reference to `hierarchy`,
 *  which must outlive it, and owns a small worker pool. */
CSC_API csc_status csc_merger_create(csc_merger** out, const csc_hierarchy* hierarchy);
CSC_API void csc_merger_destroy(csc_merger* merger);

/** The most diffs one csc_merger_merge call merges. */
#define CSC_MAX_MERGE_DIFFS 64

/** Merges `count` diffs (1 to CSC_MAX_MERGE_DIFFS), each taken against `base`, into one diff
 *  from `base` (paper §3.1). The result depends only on `base` and the set of diffs:
 *  bit-identical for any order of `diffs`, on every run and every peer of the same build.
 *  Vertices no diff touches keep their exact base values and are not listed. `options` may be
 *  NULL (full, fitted frame). Changes `merger`'s workspace: one merge at a time per merger.
 *  Fails with CSC_ERROR_INVALID_INPUT if a diff does not fit `base` or `base` is not the
 *  hierarchy's mesh. */
CSC_API csc_status csc_merger_merge(csc_merger* merger, csc_diff** out, const csc_mesh* base,
                                    const csc_diff* const* diffs, uint32_t count,
                                    const csc_merge_options* options);

/** Timings of the merger's last merge, in milliseconds. */
typedef struct csc_merge_timings {
  uint32_t struct_size;
  double isometry_ms;
  double decompose_ms;
  double blend_ms;
  double apply_ms;
} csc_merge_timings;
#define CSC_MERGE_TIMINGS_INIT \
  { sizeof(csc_merge_timings), 0.0, 0.0, 0.0, 0.0 }

CSC_API csc_status csc_merger_last_timings(const csc_merger* merger, csc_merge_timings* out);

/* ---- Sessions: serverless collaboration over ZeroMQ ------------------------------------------
 *
 * Several peers edit one mesh; each holds the agreed version and its host's local state. A
 * session is created on a mesh (that peer holds version 0) or joined with an invite string
 * (the joiner receives a snapshot of the current version). Every socket is CURVE-encrypted and
 * authenticated with keys the invite carries: a process without it can neither join nor read.
 * The live peer with the lowest id merges every sync interval; if it goes, another is elected.
 * Networking runs on the session's own thread: no call below waits on the network.
 *
 * The host loop: csc_session_update() takes merged versions in (the host's arrays are rebased:
 * local edits not yet merged are kept, merged ones are not applied twice), the artist edits,
 * csc_session_submit() sends the edit since the agreed version (at least once per sync
 * interval while there are unmerged edits), csc_session_poll() reports what happened.
 * A session handle is used from one host thread at a time. */

typedef struct csc_session csc_session;

typedef struct csc_session_options {
  uint32_t struct_size;
  const char* bind; /**< ZeroMQ endpoint to listen on; NULL: "tcp://127.0.0.1:*" (free port) */
  const char* name; /**< shown to others; NULL: "" */
  uint64_t id;      /**< this peer's id (the lowest live id merges); 0: random */
  /** The least time between two merges in ms, at least 1: the merger merges as soon as a
   *  submit is in and merges a burst within the interval together (the paper: 5 s, 20 s). */
  uint32_t sync_ms;
  uint32_t heartbeat_ms;
  uint32_t evasive_ms;       /**< silent this long: reported evasive */
  uint32_t expired_ms;       /**< silent this long: gone (a new merger is elected) */
  double position_tolerance; /**< wire tolerance, fraction of the bounding-box diagonal */
  double channel_tolerance;  /**< wire tolerance of channels, stored units */
  uint32_t join_timeout_ms;  /**< csc_session_join waits this long for the snapshot */
  /** Since 0.4. A directory to journal the session to (docs/journal.md): the agreed versions
   *  and this peer's unmerged edit, synced before the host sees them; csc_session_resume
   *  restarts from it. NULL: no journal. Create and join refuse a directory holding one. */
  const char* journal_dir;
} csc_session_options;
#define CSC_SESSION_OPTIONS_INIT \
  { sizeof(csc_session_options), NULL, NULL, 0, 10, 200, 600, 1200, 1e-5, 1e-4, 30000, NULL }

/** Starts a session on `mesh` (copied; it becomes version 0). `options` may be NULL. Fails with
 *  CSC_ERROR_IO if the endpoint cannot be bound, or when fewer than 64 file descriptors are
 *  free under the process's open-file limit (csc_last_error says how to raise it); joining
 *  and resuming check the same. */
CSC_API csc_status csc_session_create(csc_session** out, const csc_mesh* mesh,
                                      const csc_session_options* options);

/** Joins the session of `invite` and waits for the snapshot (options->join_timeout_ms). Fails
 *  with CSC_ERROR_INVALID_INPUT for a malformed invite, CSC_ERROR_IO when no snapshot came. */
CSC_API csc_status csc_session_join(csc_session** out, const char* invite,
                                    const csc_session_options* options);

/** Since 0.4. Restarts this peer's session from its journal directory after the process ended,
 *  however it ended: same session id, keys, peer id and name, the agreed mesh of the last
 *  journaled version (csc_session_copy_base), and `*local` a new mesh holding it plus this
 *  peer's unmerged edit (sent again at once): the host copies it into its arrays before its
 *  next csc_session_update or csc_session_submit, and destroys it. Binds the endpoint the peer
 *  had when options->bind picks the port (else options->bind); csc_session_invite has the
 *  endpoint. options->id and options->journal_dir are ignored; `options` may be NULL. Fails
 *  with CSC_ERROR_IO or CSC_ERROR_INVALID_INPUT naming the journal file that is missing or
 *  corrupt. */
CSC_API csc_status csc_session_resume(csc_session** out, csc_mesh** local, const char* journal_dir,
                                      const csc_session_options* options);

/** Tells the others this peer leaves and stops its network thread. Later calls other than
 *  reads and destroy fail with CSC_ERROR_INVALID_ARGUMENT. */
CSC_API csc_status csc_session_leave(csc_session* session);

/** Leaves (if not yet) and releases the session. Accepts NULL. */
CSC_API void csc_session_destroy(csc_session* session);

/** The invite others join with (NUL-terminated, borrowed until destroy); NULL for NULL. */
CSC_API const char* csc_session_invite(const csc_session* session);
/** This peer's id; 0 for NULL. */
CSC_API uint64_t csc_session_id(const csc_session* session);
/** The agreed version csc_session_update last applied; 0 for NULL. */
CSC_API uint64_t csc_session_version(const csc_session* session);

/** A copy of the agreed version's mesh (e.g. to fill the host's arrays after joining). */
CSC_API csc_status csc_session_copy_base(csc_mesh** out, const csc_session* session);

/** Sends the edit from the agreed version to the host's `local` arrays (same layout as the
 *  session mesh) to the merger, replacing what was sent before for this version; `strokes`
 *  counts the strokes made since the last submit. Changed values in `local` are set to what
 *  the peers receive (within the wire tolerance). `*sent` (may be NULL) is 1 if something was
 *  sent, 0 if there was nothing new (the strokes changed nothing the session does not hold:
 *  they count as acknowledged at once; or nothing beyond the submit still waiting for its
 *  version: they are acknowledged with it). Copies the arrays once each way
 *  (O(vertices)). */
CSC_API csc_status csc_session_submit(csc_session* session, const csc_vertex_arrays* local,
                                      uint32_t strokes, int32_t* sent);

/** csc_session_submit at the cost of the changed vertices instead of the whole mesh (since
 *  0.4): `changed` lists the `count` vertices the host changed since its last submit of either
 *  kind, updates in between included (any order, repeats allowed, listing a vertex too many
 *  costs a little and nothing else; may be NULL when count is 0). What csc_session_undo and
 *  csc_session_redo write need not be listed. The session keeps the vertices
 *  where the host's arrays differ from the agreed version and captures, copies and sends over
 *  those and the listed ones only; the edit sent is the one csc_session_submit would send when
 *  every change is listed. A change of a vertex that is not listed is not sent until a later
 *  call lists it, a csc_session_submit sends it, or a csc_session_update that applies a
 *  version finds it (it compares the whole arrays; csc_session_update_changed does not).
 *  Fails with CSC_ERROR_INVALID_INPUT naming an index out of range (nothing is sent or
 *  written). */
CSC_API csc_status csc_session_submit_changed(csc_session* session, const csc_vertex_arrays* local,
                                              const uint32_t* changed, uint32_t count,
                                              uint32_t strokes, int32_t* sent);

/** Applies the merged versions received so far and rebases `local` onto them (written in
 *  place). A submitted edit that a version did not include (it reached the merger after the
 *  merge) is sent again at once, unless the host changed `local` since its submit: the next
 *  submit then carries it with the new strokes, counted. `*applied` (may be NULL) is the
 *  number of versions applied. */
CSC_API csc_status csc_session_update(csc_session* session, const csc_vertex_arrays* local,
                                      uint32_t* applied);

/** csc_session_update at the cost of what changed instead of the whole arrays (since 0.4):
 *  `changed` lists the `count` vertices the host changed since its last submit of either kind,
 *  as for csc_session_submit_changed (what csc_session_undo and csc_session_redo write need
 *  not be listed; may be NULL when count is 0). The session copies in and compares those and
 *  the vertices it keeps as differing from the agreed version, and writes back only what it
 *  changed: a frame that applies a small version costs that version, not the mesh (the whole
 *  arrays are still written after a snapshot or when edits made since the submit are
 *  rebased). An unlisted change is neither found nor carried over by this call: it stays in
 *  the arrays, unsent, until a call lists it or a csc_session_submit sends it. Fails with
 *  CSC_ERROR_INVALID_INPUT naming an index out of range or a bad value (nothing is applied
 *  or written). */
CSC_API csc_status csc_session_update_changed(csc_session* session, const csc_vertex_arrays* local,
                                              const uint32_t* changed, uint32_t count,
                                              uint32_t* applied);

/* ---- Undo inside a session ------------------------------------------------------------------
 * Each artist undoes and redoes their own strokes; everyone else's merged work stays. Undoing
 * a stroke merges its removal (the session's merge) with everything that happened on the mesh
 * since, so where another artist bent or twisted the region over the stroke, the stroke goes
 * away along the moved surface (subtracting its translation would leave a dent elsewhere).
 * The host records each stroke when it ends; undo and redo write into the host's arrays, and
 * the next csc_session_submit() sends the result like any edit (count it as a stroke). */

/** Records a stroke the host just ended: the `count` vertices it changed (`vertices`, each
 *  once) and their values before it in `before`: count * stride floats, per vertex the
 *  position (3) and then every channel's `width` values in the session mesh's channel order
 *  (stride = 3 + the sum of the widths). `local` holds the values after it. Recording drops
 *  the strokes that could be redone; past 100 strokes or 256 MiB the oldest go. Fails with
 *  CSC_ERROR_INVALID_INPUT naming a vertex out of range or repeated, a size mismatch or a
 *  non-finite value (nothing is recorded). */
CSC_API csc_status csc_session_record_stroke(csc_session* session, const csc_vertex_arrays* local,
                                             const uint32_t* vertices, uint32_t count,
                                             const float* before);

/** Undoes this artist's latest recorded stroke in `local` (written in place). `*changed` (may
 *  be NULL; borrowed until the next undo or redo on this session) lists the `*changed_count`
 *  vertices whose values changed, increasing; 0 when there was nothing to undo. */
CSC_API csc_status csc_session_undo(csc_session* session, const csc_vertex_arrays* local,
                                    const uint32_t** changed, uint32_t* changed_count);

/** Redoes the latest undone stroke the same way. */
CSC_API csc_status csc_session_redo(csc_session* session, const csc_vertex_arrays* local,
                                    const uint32_t** changed, uint32_t* changed_count);

/** How many strokes csc_session_undo and csc_session_redo can take back / put back (either
 *  pointer may be NULL). */
CSC_API csc_status csc_session_undo_depth(const csc_session* session, uint32_t* undo,
                                          uint32_t* redo);

typedef enum csc_event_kind {
  CSC_EVENT_JOINED = 0,         /**< this peer holds the session's mesh */
  CSC_EVENT_VERSION = 1,        /**< a merged version is ready for csc_session_update */
  CSC_EVENT_PEER_JOINED = 2,    /**< `peer` joined */
  CSC_EVENT_PEER_EVASIVE = 3,   /**< `peer` has been silent past the evasive threshold */
  CSC_EVENT_PEER_LEFT = 4,      /**< `peer` left or expired */
  CSC_EVENT_MERGER_CHANGED = 5, /**< `peer` merges from `epoch` on */
  CSC_EVENT_DROPPED = 6,        /**< a malformed or hostile message was dropped (`message`) */
  CSC_EVENT_ERROR = 7,          /**< the network thread met an error (`message`) */
  CSC_EVENT_PEER_LIVE = 8,      /**< `peer`, reported evasive, was heard again */
  CSC_EVENT_KIND_MAX_ENUM = 0x7FFFFFFF
} csc_event_kind;

typedef struct csc_session_event {
  uint32_t struct_size;
  csc_event_kind kind;
  uint64_t peer;
  uint64_t version;
  uint64_t epoch;
  const char* message; /**< borrowed until the next csc_session_poll on this session */
} csc_session_event;
#define CSC_SESSION_EVENT_INIT \
  { sizeof(csc_session_event), CSC_EVENT_ERROR, 0, 0, 0, NULL }

/** Takes the next event, if any: `*has_event` is 1 and `event` filled, or 0. Never blocks. */
CSC_API csc_status csc_session_poll(csc_session* session, csc_session_event* event,
                                    int32_t* has_event);

typedef struct csc_session_stats {
  uint32_t struct_size;
  uint64_t id;
  uint64_t version; /**< the network thread's agreed version */
  uint64_t epoch;
  uint64_t merger; /**< 0 while none is known */
  uint32_t members;
  uint64_t submits;
  uint64_t submit_bytes;
  uint64_t strokes_submitted;
  uint64_t strokes_acknowledged; /**< in a version csc_session_update applied */
  uint64_t versions_applied;
  uint64_t rebases;
  uint64_t merges; /**< as the merger */
  uint64_t merged_strokes;
  uint64_t conflicting_strokes; /**< a conflict-rejecting system would have refused these */
  double merge_ms_mean;
  double merge_ms_max;
  uint64_t messages_received;
  uint64_t messages_dropped; /**< malformed, hostile, another session's */
  uint64_t stale_ignored;    /**< of a stale epoch or not from the merger */
  uint64_t auth_rejected;    /**< connections without the session key */
  /** As the merger: faces its merges turned over (normal past 90 degrees from the merge's base)
   *  that none of the merged submits turned: creases no artist made. Since 0.5. */
  uint64_t folds_introduced;
} csc_session_stats;
#define CSC_SESSION_STATS_INIT \
  { sizeof(csc_session_stats), 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0.0, 0.0, 0, 0, 0, 0, 0 }

CSC_API csc_status csc_session_get_stats(const csc_session* session, csc_session_stats* out);

/** Attribution as vertex colours: 3 floats per vertex into `rgb` (vertex_count must be the
 *  mesh's): peers get green, blue, red, ... by increasing id, mixed where several edited,
 *  light grey where nobody did (the paper's Fig. 1/6). */
CSC_API csc_status csc_session_attribution_colors(const csc_session* session, float* rgb,
                                                  uint32_t vertex_count);

/* ---- Sessions: presence and peers --------------------------------------------------------
 *
 * Presence: every artist sees the others' brush cursors live. The host sets its cursor as often
 * as it likes (every frame); the network thread sends the latest to every member at most 20
 * times a second while it changes, and again every second. Presence is not merged or versioned.
 * The others' cursors and the peer list are read as snapshots: a *_count call takes one, the
 * matching get reads entry `index` (0 to count - 1) of it. */

/** A brush cursor. csc_session_set_presence reads position, radius, active, visible and rgba;
 *  csc_session_get_presence fills every field. */
typedef struct csc_presence {
  uint32_t struct_size;
  uint64_t peer;     /**< whose (get only) */
  float position[3]; /**< in the session mesh's coordinates; finite */
  float radius;      /**< brush radius in mesh units; finite, at least 0 */
  int32_t active;    /**< 1 while a stroke is under way */
  int32_t visible;   /**< 1 while the cursor is over the mesh */
  /** 0xRRGGBBAA the sender asks to be drawn in; 0 (alpha 0): the receivers choose. */
  uint32_t rgba;
  uint32_t age_ms; /**< since it arrived (get only); hide a cursor not heard of for a while */
  /** What to draw it in, RGB in [0,1] (get only): its rgba if it gave one, else the colour the
   *  attribution view gives that peer (csc_session_attribution_colors). */
  float colour[3];
} csc_presence;
#define CSC_PRESENCE_INIT                                        \
  {                                                              \
    sizeof(csc_presence), 0, {0.f, 0.f, 0.f}, 0.f, 0, 0, 0, 0, { \
      0.f, 0.f, 0.f                                              \
    }                                                            \
  }

/** Sets this peer's brush cursor. Fails with CSC_ERROR_INVALID_ARGUMENT naming the field for a
 *  non-finite position or radius or a negative radius. Never waits on the network. */
CSC_API csc_status csc_session_set_presence(csc_session* session, const csc_presence* presence);
/** Takes a snapshot of the other peers' cursors (members only: a peer that left or expired has
 *  none) and gives their number. */
CSC_API csc_status csc_session_presence_count(csc_session* session, uint32_t* count);
/** Entry `index` of the last csc_session_presence_count snapshot. */
CSC_API csc_status csc_session_get_presence(const csc_session* session, uint32_t index,
                                            csc_presence* out);

typedef enum csc_peer_state {
  CSC_PEER_LIVE = 0,
  CSC_PEER_EVASIVE = 1, /**< silent past the evasive threshold (CSC_EVENT_PEER_EVASIVE) */
  CSC_PEER_LEFT = 2,    /**< left or expired (the latest 16 are listed) */
  CSC_PEER_STATE_MAX_ENUM = 0x7FFFFFFF
} csc_peer_state;

/** Another peer of the session, as this one sees it. */
typedef struct csc_peer_info {
  uint32_t struct_size;
  uint64_t id;
  const char* name; /**< its `name` option; borrowed until the next csc_session_peer_count */
  csc_peer_state state;
  int32_t merger;   /**< 1 if it is the merger this peer follows */
  uint64_t version; /**< the agreed version its last heartbeat reported */
  /** Round trip in ms (heartbeat echoes, smoothed); negative until measured. */
  double latency_ms;
} csc_peer_info;
#define CSC_PEER_INFO_INIT \
  { sizeof(csc_peer_info), 0, NULL, CSC_PEER_LIVE, 0, 0, -1.0 }

/** Takes a snapshot of the other peers (members, then the latest that left) and gives their
 *  number. */
CSC_API csc_status csc_session_peer_count(csc_session* session, uint32_t* count);
/** Entry `index` of the last csc_session_peer_count snapshot. */
CSC_API csc_status csc_session_get_peer(const csc_session* session, uint32_t index,
                                        csc_peer_info* out);

#ifdef __cplusplus
} /* extern "C" */
#endif

#endif /* CSCULPT_H */
