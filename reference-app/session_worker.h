// The thread that talks to the session. Every csc_session_* call of the app runs here, on its
// own mirror of the mesh's arrays, so a merge, a rebase, an undo merge, a late join's
// snapshot or a failover never holds up a frame: the artist never waits.
//
// The UI thread hands over what the artist did (ended strokes, undo and redo, the cursor)
// and takes back what changed in the mirror (the vertices whose values differ from what the
// UI last took, with their values), but only while no stroke is under way and only once the
// mirror holds every stroke handed so far, so the document and the mirror never disagree
// about the artist's own work. A stroke reaches the mirror as its change: where the mirror
// still holds the stroke's before-values it gets the after-values exactly; where a remote
// version moved the vertex meanwhile, the change is added to it.
#pragma once

#include <csculpt.h>

#include <array>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "bvh.h"
#include "mesh_document.h"
#include "version_normals.h"

/** The arrays of a mesh as the app keeps them: positions, then each channel's values. */
struct MeshArrays {
  std::vector<float> positions;
  std::vector<std::vector<float>> channels;
  std::vector<uint32_t> widths;
  std::vector<float> min_value, max_value;  // per channel: the range the session accepts
  uint32_t stride() const;                  // floats per vertex over all of them
  csc_vertex_arrays view();                 // valid until the next call
  uint32_t vertex_count() const { return static_cast<uint32_t>(positions.size() / 3); }
  void read(uint32_t v, float* out) const;
  void write(uint32_t v, const float* in);
  /** Appends the vertices whose values differ bitwise from `other`'s (same layout), increasing. */
  void differing_vertices(const MeshArrays& other, std::vector<uint32_t>& out) const;
  /** Whether any value of vertices [first, first + count) differs bitwise from `other`'s. */
  bool range_differs(const MeshArrays& other, uint32_t first, uint32_t count) const;
  /** The arrays of `mesh` (a csc_mesh), with its channels' ranges. */
  static MeshArrays of(const csc_mesh* mesh);

 private:
  std::vector<float*> pointers_;
};

/** What the panel and the scripts read: the session as the worker last saw it. */
struct SessionView {
  enum class PeerState { live, evasive, left };
  struct Peer {
    uint64_t id;
    PeerState state;
    std::string name;
    bool merger = false;
    uint64_t version = 0;
    double latency_ms = -1;  // negative until measured
  };
  struct Cursor {  // another artist's brush, recent and over the mesh
    uint64_t peer;
    std::array<float, 3> position;  // mesh coordinates
    float radius;                   // mesh units
    bool active;                    // a stroke under way
    std::array<float, 3> colour;    // RGB in [0,1]
  };
  std::string invite, status = "not in a session";
  uint64_t id = 0, version = 0;
  csc_session_stats stats = CSC_SESSION_STATS_INIT;
  std::vector<Peer> peers;
  std::vector<Cursor> cursors;
  std::vector<std::string> messages;  // the latest few, newest last
  size_t presence_seen = 0;           // peers whose cursor was seen over the mesh
  uint32_t undo_depth = 0, redo_depth = 0;
};

/** Changed vertices and their values (stride floats each), as the UI applies them. */
struct MeshChanges {
  std::vector<uint32_t> vertices;
  std::vector<float> values;
  uint64_t includes = 0;   // the UI's commands (strokes, undo, redo) the values include
  ChangedNormals normals;  // what the moved vertices change of the normals
  // The BVH's boxes around the moved vertices, from the worker's copy of the UI's tree
  // (empty until the worker has one: the UI then refits its own).
  std::vector<uint32_t> bvh_nodes;
  std::vector<BvhBox> bvh_boxes;
};

/** Who this peer is in a session and where the other peers reach it. */
struct PeerSettings {
  std::string name;  // shown in the others' peer lists
  // The ZeroMQ endpoint to listen on. Every peer is connected to by every other (a full mesh),
  // so a joiner on another machine needs it reachable too, not only the host.
  std::string bind;
};

class SessionWorker {
 public:
  /** Starts hosting a session on the document's arrays, `content`: the worker makes the mesh
   *  and the session of it (one hierarchy build: hundreds of milliseconds at 320K faces, which
   *  on the UI thread made a click on Host a frame that long). `bvh` is the UI's, tight over
   *  content.positions. */
  SessionWorker(MeshContent content, TriangleBvh bvh, PeerSettings settings);
  /** Starts joining `invite` on the worker; joined() and take_joined_mesh() tell the result. */
  SessionWorker(std::string invite, PeerSettings settings);
  ~SessionWorker();  // leaves the session and stops the thread
  SessionWorker(const SessionWorker&) = delete;
  SessionWorker& operator=(const SessionWorker&) = delete;

  // ---- UI thread ------------------------------------------------------------------------
  /** 0 while joining or creating, 1 once in the session, -1 when that failed (`error`). */
  int state(std::string& error) const;
  /** After a join: the session's mesh for the document (caller destroys), once. */
  csc_mesh* take_joined_mesh();
  /** An ended stroke: its vertices and their values before and after it (stride each). */
  void hand_stroke(std::vector<uint32_t> vertices, std::vector<float> before,
                   std::vector<float> after);
  void request_step(bool redo);
  void set_presence(const csc_presence& presence);
  /** A copy of the UI's BVH, tight over `positions` (the document's when it was copied), so
   *  the worker can hand over the boxes a version changes with the version. */
  void hand_bvh(TriangleBvh bvh, std::vector<float> positions);
  /** The changes the UI lacks, if the mirror includes every command handed and they were not
   *  taken yet; else null. */
  std::shared_ptr<const MeshChanges> take_changes();
  /** Waits (up to `timeout_ms`) until every command handed is in the mirror and sent. */
  void settle(int timeout_ms);
  SessionView view() const;
  /** The latest attribution colours, 3 per vertex (requests them from now on); null if none
   *  yet. Shared, never changed: the UI uploads from it without a copy. */
  std::shared_ptr<const std::vector<float>> attribution_colours();

 private:
  struct Command {  // what the UI did, in the order it did it
    enum class Kind { stroke, undo, redo, taken } kind;
    std::vector<uint32_t> vertices;  // a stroke's, with its values before and after
    std::vector<float> before, after;
    std::shared_ptr<const MeshChanges> changes;  // taken: what the UI applied
  };
  struct Inbox {
    std::vector<Command> commands;
    bool has_presence = false;
    csc_presence presence = CSC_PRESENCE_INIT;
    uint64_t handed = 0;  // strokes, undos and redos handed so far
  };

  void run(std::string invite);
  bool join(const std::string& invite);
  bool create();
  void loop();
  void drain_inbox();
  void apply_stroke(const Command& c);
  void apply_step(bool redo);
  bool poll_events();  // true when a merged version waits
  void sync();         // update and submit
  void refresh_view();
  void publish();
  /** Refits the worker's BVH to the mirror and lists the boxes around `box`'s moved vertices. */
  void add_bvh_boxes(MeshChanges& box);
  void note(std::string message);
  void finish();

  // the worker's own state
  csc_session* session_ = nullptr;
  MeshContent host_content_;  // hosting: what the session is created on, until it is
  PeerSettings settings_;
  MeshArrays mirror_, shown_;  // the session's side; what the UI's document holds
  VersionNormals normals_;
  TriangleBvh bvh_;                   // the UI's tree, refitted to the mirror at each publish
  std::vector<float> bvh_positions_;  // what bvh_ is tight over; empty until handed one
  std::vector<uint32_t> stale_;       // vertices bvh_ is not tight over (scratch)
  uint32_t strokes_unsent_ = 0;
  std::vector<uint32_t> unsent_vertices_;  // the strokes' since the last submit (may repeat)
  uint64_t done_ = 0;                      // strokes, undos and redos applied to the mirror
  uint64_t takes_drained_ = 0;
  bool dirty_ = true, attribution_stale_ = true;
  std::chrono::steady_clock::time_point last_submit_{}, last_view_{};
  std::set<uint64_t> presence_seen_;
  SessionView local_view_;

  // shared with the UI thread, under mutex_
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  Inbox inbox_;
  std::shared_ptr<const MeshChanges> outbox_;
  bool outbox_taken_ = false;
  std::unique_ptr<TriangleBvh> handed_bvh_;
  std::vector<float> handed_bvh_positions_;
  uint64_t takes_ = 0;  // outboxes the UI took; the worker has drained takes_drained_ of them
  SessionView view_;
  int state_ = 0;
  std::string error_;
  csc_mesh* joined_mesh_ = nullptr;
  bool want_attribution_ = false;
  std::shared_ptr<const std::vector<float>> attribution_;
  bool stop_ = false;

  std::thread thread_;
};
