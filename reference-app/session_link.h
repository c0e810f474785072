// The app's side of a collaborative session, through the C ABI only (csc_session_*): host or
// join (the join waits for a snapshot, so it runs on a worker thread and the artist keeps
// sculpting), the per-frame poll, submit and update, and what the panel shows.
#pragma once

#include <csculpt.h>

#include <array>
#include <chrono>
#include <cstdint>
#include <future>
#include <set>
#include <string>
#include <vector>

class SessionLink {
 public:
  enum class PeerState { live, evasive, left };
  struct Peer {
    uint64_t id;
    PeerState state;
    std::string name;
    bool merger = false;
    uint64_t version = 0;
    double latency_ms = -1;  // negative until measured
  };
  /** Another artist's brush cursor, recent and over the mesh. */
  struct Cursor {
    uint64_t peer;
    std::array<float, 3> position;  // mesh coordinates
    float radius;                   // mesh units
    bool active;                    // a stroke under way
    std::array<float, 3> colour;    // RGB in [0,1]
  };

  SessionLink() = default;
  SessionLink(const SessionLink&) = delete;
  SessionLink& operator=(const SessionLink&) = delete;
  ~SessionLink();

  /** Hosts a session on `mesh` (copied). On failure `error` says why. */
  bool host(const csc_mesh* mesh, std::string& error);
  /** Starts joining in the background; poll_join() tells when it is done. */
  void begin_join(const std::string& invite);
  /** While joining: 1 when the session is ready (copy its base into the document), -1 when
   *  the join failed (`error`), 0 while still waiting. */
  int poll_join(std::string& error);
  bool joining() const { return join_.valid(); }
  bool active() const { return session_ != nullptr; }

  /** Takes the session's events (peers, versions, errors), the peer list and the cursors. */
  void poll_events();
  /** This artist's brush cursor (every frame: the library sends at most 20 a second). */
  void set_presence(const csc_presence& presence);
  /** True once a merged version waits for update(). */
  bool version_pending() const { return version_pending_; }
  /** Applies merged versions into `local` (rebased in place); returns versions applied. */
  uint32_t update(csc_vertex_arrays& local);
  /** Sends the edit since the agreed version; `strokes` ended since the last submit. */
  bool submit(csc_vertex_arrays& local, uint32_t strokes);
  /** Hands an ended stroke to the session's undo (its vertices and their values before). */
  void record_stroke(csc_vertex_arrays& local, const std::vector<uint32_t>& vertices,
                     const std::vector<float>& before);
  /** Undoes (or redoes) this artist's latest stroke in `local`, merged with everyone's work
   *  since; false when there was none or it failed (noted). */
  bool undo(csc_vertex_arrays& local, bool redo);
  uint32_t undo_depth() const;
  uint32_t redo_depth() const;
  /** Re-sends while strokes are unacknowledged, once per sync interval (csculpt.h asks it). */
  bool resubmit_due() const;
  void leave();

  csc_mesh* copy_base(std::string& error) const;
  const char* invite() const { return session_ ? csc_session_invite(session_) : ""; }
  uint64_t id() const { return csc_session_id(session_); }
  uint64_t version() const { return csc_session_version(session_); }
  const csc_session_stats& stats() const { return stats_; }
  const std::vector<Peer>& peers() const { return peers_; }
  const std::vector<Cursor>& cursors() const { return cursors_; }
  /** How many peers' cursors were seen over the mesh during the session (the exit line). */
  size_t presence_seen() const { return presence_seen_.size(); }
  const std::vector<std::string>& messages() const { return messages_; }
  const std::string& status() const { return status_; }
  bool attribution_colours(std::vector<float>& rgb, uint32_t vertex_count) const;

 private:
  void note(std::string message);
  void set_peer(uint64_t id, PeerState state);
  void refresh_peers();
  void refresh_cursors();

  csc_session* session_ = nullptr;
  csc_session_options options_ = CSC_SESSION_OPTIONS_INIT;
  struct JoinResult {
    csc_session* session = nullptr;
    std::string error;
  };
  std::future<JoinResult> join_;
  std::vector<Peer> peers_;
  std::vector<Cursor> cursors_;
  std::set<uint64_t> presence_seen_;
  std::vector<std::string> messages_;  // the latest few, newest last
  std::string status_ = "not in a session";
  csc_session_stats stats_ = CSC_SESSION_STATS_INIT;
  bool version_pending_ = false;
  std::chrono::steady_clock::time_point last_submit_{};
};
