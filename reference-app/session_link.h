// The app's side of a collaborative session, through the C ABI only: host or join, hand the
// artist's strokes, undo and cursor over, take back what the session changed, and what the
// panel shows. Every csc_session_* call runs on the SessionWorker's thread (session_worker.h),
// so nothing here waits on a merge, a rebase or the network.
#pragma once

#include <csculpt.h>

#include <memory>
#include <string>
#include <vector>

#include "session_worker.h"

class SessionLink {
 public:
  using PeerState = SessionView::PeerState;
  using Peer = SessionView::Peer;
  using Cursor = SessionView::Cursor;

  SessionLink() = default;
  SessionLink(const SessionLink&) = delete;
  SessionLink& operator=(const SessionLink&) = delete;

  /** Starts hosting a session on a copy of the document's arrays in the background: the
   *  session is active at once (strokes are handed, and merged once it exists); poll_host()
   *  tells when it exists or failed. */
  void host(MeshContent content, TriangleBvh bvh, PeerSettings settings);
  /** While a hosted session is being created: 1, once, when it exists (invite() holds its
   *  invite), -1 when it could not be (`error`; the link is out of the session), 0 otherwise. */
  int poll_host(std::string& error);
  bool starting_host() const { return worker_ && starting_host_; }
  /** Starts joining in the background; poll_join() tells when it is done. */
  void begin_join(const std::string& invite, PeerSettings settings);
  /** While joining: 1, once, when the session's mesh has come (take_joined_mesh() for the
   *  document; the session is active once adopted() says the document holds it), -1 when the
   *  join failed (`error`), 0 otherwise. */
  int poll_join(std::string& error);
  /** The session's mesh after a join (caller destroys). */
  csc_mesh* take_joined_mesh() { return worker_ ? worker_->take_joined_mesh() : nullptr; }
  /** The app's document holds the joined mesh: from now on the session is active. */
  void adopted();
  bool joining() const { return worker_ && !joined_; }
  bool active() const { return worker_ && joined_; }

  /** Reads what the worker published (peers, cursors, statistics, messages). */
  void poll_events();
  /** A digest of what the panel and the scene show of the session, but for its running
   *  figures (bytes, latency, merge time): when it changes, a frame is due. */
  uint64_t look() const;
  /** This artist's brush cursor (every frame: the library sends at most 20 a second). */
  void set_presence(const csc_presence& presence);
  /** Gives the worker a copy of the document's BVH, tight over `positions`. */
  void hand_bvh(TriangleBvh bvh, std::vector<float> positions);
  /** An ended stroke: its vertices and their values before and after it. */
  void hand_stroke(const std::vector<uint32_t>& vertices, const std::vector<float>& before,
                   const std::vector<float>& after);
  /** Undoes (or redoes) this artist's latest stroke, merged with everyone's work since; the
   *  result comes back through take_changes(). */
  void request_step(bool redo);
  /** What the session changed since the last call, once it includes everything handed. */
  std::shared_ptr<const MeshChanges> take_changes();
  /** Waits up to `timeout_ms` for everything handed to be merged into the mirror and sent. */
  void settle(int timeout_ms);
  void leave();

  uint32_t undo_depth() const { return view_.undo_depth; }
  uint32_t redo_depth() const { return view_.redo_depth; }
  const char* invite() const { return view_.invite.c_str(); }
  uint64_t id() const { return view_.id; }
  uint64_t version() const { return view_.version; }
  const csc_session_stats& stats() const { return view_.stats; }
  const std::vector<Peer>& peers() const { return view_.peers; }
  const std::vector<Cursor>& cursors() const { return view_.cursors; }
  size_t presence_seen() const { return view_.presence_seen; }
  const std::vector<std::string>& messages() const { return messages_; }
  const std::string& status() const { return status_; }
  /** The latest attribution colours (3 per vertex); null while none came yet. */
  std::shared_ptr<const std::vector<float>> attribution_colours();

 private:
  void note(std::string message);

  std::unique_ptr<SessionWorker> worker_;
  bool joined_ = false;
  bool adopting_ = false;       // the mesh has come; the app is preparing its document
  bool starting_host_ = false;  // hosting: the worker is creating the session
  SessionView view_;
  std::vector<std::string> notes_, messages_;  // the app's own; with the worker's
  std::string status_ = "not in a session";
};
