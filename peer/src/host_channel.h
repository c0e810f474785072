// What the network thread (PeerNode) and the host thread (Session) share, behind one mutex:
// the host's commands one way; merged versions, snapshots, events, statistics, attribution and
// the merge state the other way. Neither side ever waits on the other for long: every call
// takes the lock for a copy or a move.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <utility>
#include <vector>

#include "csculpt/diff.h"
#include "csculpt/hierarchy.h"
#include "csculpt/merge.h"
#include "csculpt/peer/session.h"
#include "messages.h"
#include "presence.h"
#include "snapshot.h"

namespace csculpt::peer {

/// The host's last submit, or its wish to leave.
struct Command {
  enum class Kind { none, submit, leave } kind = Kind::none;
  std::uint64_t base_version = 0;  ///< the agreed version the diff is from
  Bytes bytes;                     ///< a DiffMessage; cleared once a version made it stale
  std::uint32_t strokes = 0;       ///< strokes not yet acknowledged, this one's included
};

/// What the network thread hands to the host: a merged version, or a whole snapshot.
struct HostItem {
  bool snapshot = false;
  std::uint64_t version = 0;
  Diff merged;                           ///< version: the diff from version - 1
  std::vector<MergedSubmit> merged_by;   ///< version: the submits it includes
  std::shared_ptr<const Snapshot> snap;  ///< snapshot
  /// snapshot: the latest version its branch and the one we held share (nullopt: none known).
  /// Below our version, we held another branch: what it had since is merged, not dropped.
  std::optional<std::uint64_t> fork;
};

/// At most this many events wait for poll_events (the oldest go first).
constexpr std::size_t kMaxEvents = 10000;

class HostChannel {
 public:
  // ---- host -> network ----------------------------------------------------------------------
  void post(Command c);
  std::deque<Command> take_commands();
  /// The host's brush cursor (only the latest is kept: the network thread rate-limits it).
  /// True when the network thread should be woken: a change it has not seen, none before.
  bool set_presence(const Presence& p);
  /// Whether the host changed its presence since the last take, and whether it ever set one.
  std::pair<bool, bool> presence_state() const;
  Presence take_presence();

  // ---- network -> host ----------------------------------------------------------------------
  /// A version or snapshot for update(), with the statistics it changes (`change`) under the
  /// same lock: a reader never sees one without the other.
  template <class Change>
  void push_item(HostItem item, Change&& change) {
    std::lock_guard lock(mutex_);
    items_.push_back(std::move(item));
    change(stats_);
  }
  std::vector<HostItem> take_items();
  void push_event(Event e);
  std::vector<Event> take_events();

  /// Changes the statistics under the lock (`change(SessionStats&)`).
  template <class Change>
  void update_stats(Change&& change) {
    std::lock_guard lock(mutex_);
    change(stats_);
  }
  SessionStats stats() const;

  /// Attribution: the network thread changes it (`change(map&)`), the host copies it.
  template <class Change>
  void update_attribution(Change&& change) {
    std::lock_guard lock(mutex_);
    change(attribution_);
  }
  std::vector<std::pair<PeerId, std::vector<float>>> attribution() const;
  /// The peers attribution holds (increasing id), without their values.
  std::vector<PeerId> attribution_peers() const;

  /// The others' presence: the network thread changes it (`change(PresenceTable&)`).
  template <class Change>
  void update_presence(Change&& change) {
    std::lock_guard lock(mutex_);
    change(presence_);
  }
  std::map<PeerId, ReceivedPresence> presence() const;
  /// The others as the network thread last listed them.
  void set_peers(std::vector<PeerInfo> peers);
  std::vector<PeerInfo> peers() const;
  /// A snapshot's merge frame and attribution, replacing ours.
  void set_frame_and_attribution(const MergeFrame& frame,
                                 std::map<PeerId, std::vector<float>> attribution);
  /// The bytes of a snapshot of `mesh` with our frame and attribution (copied, so that the
  /// encoding does not hold the host's lock), and `chains`.
  Bytes encode_snapshot_of(const Mesh& mesh, const ChainHistory& chains) const;
  /// The same, unencoded and with a copy of `mesh`: to be encoded beside the network thread.
  Snapshot snapshot_of(const Mesh& mesh, const ChainHistory& chains) const;

  void set_hierarchy(std::shared_ptr<const Hierarchy> hierarchy);
  std::shared_ptr<const Hierarchy> hierarchy() const;
  void set_frame(const MergeFrame& frame);
  MergeFrame frame() const;

  /// The network thread holds the session's mesh (a joiner: its snapshot came).
  void set_joined();
  bool wait_joined(Millis timeout);

 private:
  /// A snapshot without a mesh: our frame and attribution, copied under the lock.
  Snapshot frame_and_attribution() const;
  mutable std::mutex mutex_;
  std::condition_variable joined_cv_;  // wait_joined() sleeps on it
  bool joined_ = false;
  std::deque<Command> commands_;  // the host's, in order, for the next loop turn
  std::deque<HostItem> items_;    // versions and snapshots, in order, for update()
  std::deque<Event> events_;      // bounded by kMaxEvents
  SessionStats stats_;
  std::map<PeerId, std::vector<float>> attribution_;  // per peer, a value per vertex
  std::shared_ptr<const Hierarchy> hierarchy_;        // built once the mesh is known
  MergeFrame frame_;                                  // the session's, from its first mesh
  Presence own_presence_;                             // the host's latest
  bool presence_set_ = false, presence_changed_ = false;
  PresenceTable presence_;       // the others' latest cursors
  std::vector<PeerInfo> peers_;  // the others, as last listed
};

}  // namespace csculpt::peer
