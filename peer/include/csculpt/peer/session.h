// A serverless editing session over ZeroMQ (protocol: peer/schema/session.fbs).
//
// Every peer binds one ROUTER socket and connects one DEALER to each other peer; every socket
// is CURVE-encrypted and authenticated with keys carried by the invite, so a process without
// the invite can neither join nor read anything. Membership spreads by heartbeats; the live
// peer with the lowest id merges (epoch-numbered election, see membership.h). Peers send
// their edit since the last agreed version (cumulative, replacing what they sent before); the
// merger merges every sync interval and broadcasts version v+1 with a hash chain. A peer that
// sees a gap fetches what it missed; a late joiner gets a snapshot of the current version and
// what follows (the ZeroMQ guide's Clone pattern). Networking runs on its own thread: the
// host's calls never wait on the network.
//
// Host side (one thread): submit() sends the local edit; update() applies the merged versions
// received so far and rebases the local edits made since onto them with the SDK merge, so no
// stroke is lost, doubled or blocked.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "csculpt/mesh.h"
#include "csculpt/peer/membership.h"
#include "csculpt/wire.h"

namespace csculpt::peer {

struct SessionOptions {
  /// Where this peer listens: a ZeroMQ endpoint; port * picks a free one.
  std::string bind = "tcp://127.0.0.1:*";
  /// Shown to others (author of diffs).
  std::string name;
  /// This peer's id (the election picks the lowest live id); 0 = random.
  PeerId id = 0;
  /// The least time between two merges: the merger merges as soon as a submit is in, and a
  /// burst arriving within the interval is merged together (at least 1 ms, validate_options;
  /// the paper merged every 5 s and 20 s). 10 ms: an edit reaches every peer in about that
  /// (csculpt bench session), while a merge of a few strokes at 320K faces takes 1-2 ms.
  Millis sync{10};
  MembershipOptions membership;
  /// Wire tolerances of submitted and merged diffs (see wire.h); with position_scale 0 the
  /// position tolerance is relative to the session's frame (the first mesh's bounding-box
  /// diagonal). A change of a vertex smaller than the tolerance within one submit is not sent.
  EncodeOptions wire;
  /// Largest message a socket accepts (ZMQ_MAXMSGSIZE); snapshots go in chunks below it.
  std::size_t max_message_bytes = std::size_t{64} << 20;
  std::size_t snapshot_chunk_bytes = std::size_t{1} << 20;
  /// Largest snapshot a joiner accepts.
  std::size_t max_snapshot_bytes = std::size_t{2} << 30;
  /// A directory to journal the session to (docs/journal.md): the agreed versions and this
  /// peer's unmerged edit, synced to disk before the host sees them; Session::resume restarts
  /// from it. Empty: no journal. create and join refuse a directory that holds one already.
  std::string journal;
  /// The journal's log is compacted into a new snapshot past either bound.
  std::uint64_t journal_max_log_bytes = std::uint64_t{64} << 20;
  std::uint64_t journal_max_log_versions = 1024;
};

/// Throws InvalidInput naming the first option out of range: an interval (sync, heartbeat,
/// expired) outside 1 ms to 1 hour, membership thresholds not increasing, a negative, infinite
/// or NaN tolerance, a position tolerance above 1 (it is a fraction of the frame), a name longer
/// than max_author_bytes, message and chunk sizes that cannot carry a snapshot. Session::create
/// and Session::join call it.
void validate_options(const SessionOptions& options);

enum class EventKind : std::uint32_t {
  joined = 0,          ///< this peer holds the session's mesh (a joiner: the snapshot came)
  version = 1,         ///< a merged version is ready for update()
  peer_joined = 2,     ///< `peer` joined
  peer_evasive = 3,    ///< `peer` has been silent past the evasive threshold
  peer_left = 4,       ///< `peer` left or expired
  merger_changed = 5,  ///< `peer` merges from epoch `epoch` on
  dropped = 6,         ///< a message was malformed or hostile and dropped (`message` says why)
  error = 7,           ///< something failed on the network thread (`message`)
  peer_live = 8,       ///< `peer`, reported evasive, was heard again
};

struct Event {
  EventKind kind = EventKind::error;
  PeerId peer = 0;
  std::uint64_t version = 0;
  std::uint64_t epoch = 0;
  std::string message;
};

struct SessionStats {
  PeerId id = 0;
  std::uint64_t version = 0;  ///< the network thread's agreed version
  std::uint64_t epoch = 0;
  PeerId merger = 0;  ///< 0 while none is known
  std::uint32_t members = 0;
  // this peer as an author
  std::uint64_t submits = 0;
  std::uint64_t submit_bytes = 0;
  /// Submits sent again to a merger that was behind them when they came (it ignored them as
  /// stale) once it caught up: counted in `submits` too. Not in csc_session_stats.
  std::uint64_t submits_resent = 0;
  std::uint64_t strokes_submitted = 0;     ///< strokes the host reported
  std::uint64_t strokes_acknowledged = 0;  ///< of those, in a version update() applied
  std::uint64_t versions_applied = 0;      ///< by update()
  std::uint64_t rebases = 0;               ///< updates that had local edits to carry over
  /// Switches to another branch of the history (after a partition healed, the one this peer
  /// followed lost): its versions since the fork were carried over as local edits and sent
  /// again. Not in csc_session_stats.
  std::uint64_t branch_rebases = 0;
  /// Versions of a lost branch that could not be carried over (older than what the host keeps,
  /// revert_log.h): their edits are gone. 0 unless a partition outlasted that history. Not in
  /// csc_session_stats.
  std::uint64_t branch_versions_dropped = 0;
  // this peer as the merger
  std::uint64_t merges = 0;
  std::uint64_t merged_strokes = 0;
  std::uint64_t conflicting_strokes = 0;  ///< a conflict-rejecting system would refuse these
  /// New folds of this peer's merges, summed (csculpt/folds.h count_new_folds): faces a merge
  /// turned by more than 90 degrees from its base that none of the merged diffs turned, i.e.
  /// creases or spikes no artist made. 0 for a perfect merge.
  std::uint64_t folds_introduced = 0;
  double merge_ms_sum = 0;
  double merge_ms_max = 0;
  std::uint64_t version_bytes_sent = 0;
  // traffic and hostility
  std::uint64_t messages_received = 0;
  std::uint64_t bytes_received = 0;
  std::uint64_t messages_dropped = 0;  ///< malformed, hostile, another session's
  std::uint64_t stale_ignored = 0;     ///< of a stale epoch or from a non-merger
  std::uint64_t auth_rejected = 0;     ///< connections without the session key
  std::uint64_t snapshots_sent = 0;    ///< whole snapshots sent: every chunk handed to ZeroMQ
  std::uint64_t fetches = 0;
  /// Connections closed before completing a handshake: clients that connected and said nothing
  /// for the handshake timeout (3 s), or hung up midway. Not in csc_session_stats.
  std::uint64_t handshakes_abandoned = 0;
  // the journal (SessionOptions::journal): writes synced, and the time they took on the network
  // thread (an agreed version, a submit, a snapshot taken there). A compaction's snapshot is
  // encoded and written beside that thread: it counts in journal_snapshots and journal_writes,
  // its time only for the new log's writing and renames. Not in csc_session_stats.
  std::uint64_t journal_writes = 0;
  std::uint64_t journal_snapshots = 0;
  double journal_ms_sum = 0;
  double journal_ms_max = 0;
};

/// A brush cursor (presence): where an artist's brush is, shown live to the others.
struct Presence {
  Vec3f position{};        ///< in the session mesh's coordinates
  float radius = 0;        ///< the brush radius in mesh units
  bool active = false;     ///< a stroke is under way
  bool visible = false;    ///< the cursor is over the mesh
  std::uint32_t rgba = 0;  ///< 0xRRGGBBAA to be drawn in; 0: the receivers' choice
  friend bool operator==(const Presence&, const Presence&) = default;
};
/// Throws InvalidInput naming the field: a non-finite position or radius, a negative radius.
void validate_presence(const Presence& p);

/// Another peer's latest presence, as this peer holds it.
struct PeerPresence {
  PeerId peer = 0;
  Presence presence;
  std::uint64_t sequence = 0;  ///< the sender's numbering of it
  Millis age{0};               ///< since it arrived
  /// What to draw it in (RGB in [0,1]): its rgba if it gave one, else its attribution colour.
  std::array<float, 3> colour{};
};

enum class PeerState : std::uint32_t { live = 0, evasive = 1, left = 2 };

/// Another peer as this one sees it.
struct PeerInfo {
  PeerId id = 0;
  std::string name;  ///< from its hello ("" until that arrived)
  PeerState state = PeerState::live;
  bool merger = false;        ///< the merger this peer follows
  std::uint64_t version = 0;  ///< the agreed version its last heartbeat reported
  /// Round trip by heartbeat echoes (protocol.md), smoothed; negative until measured.
  double latency_ms = -1;
};
/// Peers that left are still listed by Session::peers(), the latest this many.
constexpr std::size_t kKeptDeparted = 16;

/// The decoded invite: endpoint of a member, session id and the CURVE secrets.
struct Invite {
  std::string endpoint;
  std::uint64_t session = 0;
  std::array<std::uint8_t, 32> server_secret{};
  std::array<std::uint8_t, 32> client_secret{};
};
/// "csculpt1:<144 hex digits>@<endpoint>"; parse throws InvalidInput saying what is wrong.
std::string format_invite(const Invite& invite);
Invite parse_invite(const std::string& text);

/// A 64-bit digest of a mesh's positions and channel values (convergence checks).
std::uint64_t mesh_digest(const Mesh& mesh);

class Session {
 public:
  /// Starts a session on `mesh` (this peer holds version 0 and merges). Throws on a mesh that
  /// fails validate() or an endpoint that cannot be bound.
  static std::unique_ptr<Session> create(const Mesh& mesh, const SessionOptions& options = {});
  /// Joins with an invite and waits up to `timeout` for the snapshot. Throws InvalidInput for
  /// a malformed invite, IoError if no snapshot came in time.
  static std::unique_ptr<Session> join(const std::string& invite,
                                       const SessionOptions& options = {},
                                       Millis timeout = Millis{30000});
  /// Restarts this peer's session from its journal (SessionOptions::journal) after the process
  /// ended, however it ended: the same session id, keys, peer id and name, the agreed mesh of
  /// the last journaled version, and `local` set to it plus this peer's unmerged edit (sent again
  /// at once). Binds the endpoint it had if `options.bind` picks a port (else `options.bind`),
  /// and greets the members it knew there; invite() has the endpoint. Other options come from
  /// `options` (its journal and id are ignored). Throws IoError or InvalidInput naming the
  /// journal file that is missing or corrupt.
  static std::unique_ptr<Session> resume(const std::string& journal_dir, Mesh& local,
                                         const SessionOptions& options = {});
  ~Session();  ///< leaves (tells the others) and stops the network thread
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  std::string invite() const;
  PeerId id() const;
  std::string endpoint() const;

  // ---- host thread --------------------------------------------------------------------
  /// The agreed version update() last applied, and its mesh.
  std::uint64_t version() const;
  const Mesh& base() const;
  /// Sends the edit from base() to `local` (same connectivity and channels) to the merger,
  /// replacing what was sent before for this base; `strokes` = strokes made since the last
  /// submit. The changed values of `local` are set to what the peers receive (within the wire
  /// tolerance). Returns false when there was nothing new to send: the strokes changed nothing
  /// the session does not hold, and are counted acknowledged at once, or nothing beyond the
  /// submit still waiting for its version, and are acknowledged with it.
  /// Never waits on the network.
  bool submit(Mesh& local, std::uint32_t strokes = 0);
  /// The same at the cost of the changed vertices instead of the whole mesh: `changed` lists the
  /// vertices the host changed since its last submit of either kind, updates in between
  /// included (any order, repeats allowed; a vertex listed too many costs a little, nothing
  /// else). What undo() and redo() write need not be listed.
  /// The session keeps the vertices where `local` differs from base() (touched()) and captures
  /// the edit over those and `changed` only; the edit sent is the same as submit(local, strokes)
  /// would send when every change is listed. A change of a vertex the host does not list is not
  /// sent until a later call lists it, a whole-mesh submit sends it, or an update that applies
  /// a version finds it (update(local) compares the whole mesh). Throws InvalidInput naming an
  /// index out of range (nothing is sent or changed).
  bool submit(Mesh& local, std::uint32_t strokes, std::span<const std::uint32_t> changed);
  /// The vertices where the host's mesh may differ from base() as far as the session knows,
  /// increasing: what the last submit sent, what a rebase left, what undo() and redo() wrote.
  /// Exact after a submit, an update that applied something and join; empty when the host's
  /// mesh is the base.
  std::span<const std::uint32_t> touched() const;
  /// Applies every merged version received so far to base() and rebases `local` onto it:
  /// local edits not yet inside a merged version are kept, edits already merged are not
  /// applied twice; the versions waiting together cost one rebase. A submitted edit that a
  /// version did not include (it reached the merger after the merge) is sent again, rebased,
  /// at once, unless the host edited since: its next submit then carries it with the new
  /// strokes (counted). Returns the number of versions applied.
  std::size_t update(Mesh& local);
  /// The same at the cost of what changed instead of the whole mesh: `changed` lists the
  /// vertices the host changed since its last submit of either kind, as for submit(local,
  /// strokes, changed) (what undo() and redo() wrote need not be listed). The session looks
  /// for edits since the submit at those and touched() only; an unlisted change is then
  /// neither found nor carried over by this update (it stays in `local`, unsent, until a call
  /// lists it or a whole-mesh submit sends it). Throws InvalidInput naming an index out of
  /// range or a bad value (nothing is applied).
  std::size_t update(Mesh& local, std::span<const std::uint32_t> changed);
  /// What the last update() wrote into `local`: the vertices, each once, or nullopt when it
  /// may have written any (a snapshot, a rebase of edits made since the submit, a first
  /// update on an empty mesh, a failure while applying). A host mirroring `local` copies back
  /// those only, also when update() threw (nothing, when it refused the host's values).
  std::optional<std::span<const std::uint32_t>> written() const;
  /// Records a stroke the host just ended on `local`, for undo(): the vertices it changed and
  /// their values before it (per vertex: the position, then every channel's values in the
  /// session mesh's channel order). Recording drops the strokes that could be redone; the
  /// oldest go past 100 strokes or 256 MiB. Throws InvalidInput naming a bad vertex or value.
  void record_stroke(const Mesh& local, std::span<const std::uint32_t> vertices,
                     std::span<const float> before);
  /// Undoes this artist's latest recorded stroke in `local`: the stroke's removal merged (the
  /// session's merge) with everything that happened on the mesh since, so other artists' work
  /// stays, also where they rotated the region over it. `changed` gets the vertices written;
  /// submit() then sends the undo like any edit. False when there is nothing to undo.
  bool undo(Mesh& local, std::vector<std::uint32_t>& changed);
  /// Redoes the latest undone stroke the same way.
  bool redo(Mesh& local, std::vector<std::uint32_t>& changed);
  /// Strokes undo() and redo() can take back / put back.
  std::size_t undo_depth() const;
  std::size_t redo_depth() const;
  /// Events since the last call (at most 10,000 are kept).
  std::vector<Event> poll_events();
  SessionStats stats() const;
  /// Per peer that contributed, a value per vertex: how much of the agreed mesh's change at
  /// that vertex came from it (the paper's Fig. 1/6 attribution).
  std::vector<std::pair<PeerId, std::vector<float>>> attribution() const;
  /// Sets this peer's brush cursor (every frame if the host likes): the network thread sends
  /// the latest to every member at most every 50 ms while it changes, and again every second.
  /// Throws InvalidInput naming the field (validate_presence).
  void set_presence(const Presence& presence);
  /// The other peers' presence (members only: a peer that left or expired has none).
  std::vector<PeerPresence> presence() const;
  /// The other peers: members, then the last few that left (at most kKeptDeparted).
  std::vector<PeerInfo> peers() const;
  /// Tells the others and stops the network thread; the session is unusable afterwards.
  void leave();

 private:
  struct Impl;
  explicit Session(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

/// The hue of the `rank`-th peer in increasing id order (green, blue, red, magenta, orange,
/// teal, yellow, violet, then again): attribution_colours and presence colours use it.
std::array<float, 3> peer_colour(std::size_t rank);

/// Attribution as vertex colours (RGB in [0,1], vertex-major): peer k gets a hue (green,
/// blue, red, ... in increasing id order), mixed by share; untouched vertices are light grey.
std::vector<float> attribution_colours(
    const std::vector<std::pair<PeerId, std::vector<float>>>& attribution,
    std::size_t vertex_count);

}  // namespace csculpt::peer
