// The network thread of one peer: PeerNode owns the transport, membership and election, the
// replication state, the merger role and the snapshot assembly, and glues them together. It
// sleeps in zmq_poll until a message, a host command (HostChannel + Transport::wake), a
// background merge or snapshot load finished, or its next timer (heartbeat, merge). Its only link
// to the host thread is the HostChannel; merges and a joiner's snapshot load run on threads of
// their own (background_task.h).
#pragma once

#include <cstdint>
#include <deque>
#include <latch>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "background_task.h"
#include "csculpt/hierarchy.h"
#include "csculpt/merge.h"
#include "csculpt/mesh.h"
#include "csculpt/peer/membership.h"
#include "csculpt/peer/session.h"
#include "host_channel.h"
#include "journal.h"
#include "merger_role.h"
#include "messages.h"
#include "peer_table.h"
#include "presence.h"
#include "replication.h"
#include "snapshot.h"
#include "transport.h"

namespace csculpt::peer {

/// How long the endpoints of expired members are greeted (PeerNode::greet_lost): longer than
/// the partitions a session heals from.
constexpr Millis kGreetLostFor{10 * 60 * 1000};
/// How long a snapshot asked for (or a joiner's) may take before it is asked for again.
constexpr Millis kSnapshotRetry{2000};

/// A snapshot as sent: of `version` at `chain`.
struct EncodedSnapshot {
  std::uint64_t version = 0;
  std::uint64_t chain = 0;
  std::shared_ptr<const Bytes> bytes;
};

/// A snapshot on its way to `peer` at `endpoint`, sent up to `offset`.
struct OutgoingSnapshot {
  PeerId peer = 0;
  std::string endpoint;
  EncodedSnapshot snapshot;
  std::size_t offset = 0;
};

/// How long the loop sends snapshots' chunks, or handles messages, before the timers (our
/// heartbeats) get a turn: a snapshot of millions of faces is hundreds of chunks, and under
/// sanitizers each costs milliseconds.
constexpr Millis kTurn{10};

/// Runs `copy`, a task's copy of the network thread's mesh, and then counts `copied` down,
/// whether it returned or threw (PeerNode::release_base waits for it).
template <class Copy>
auto copy_then_count_down(std::latch& copied, Copy&& copy) {
  struct CountDown {
    std::latch& latch;
    ~CountDown() { latch.count_down(); }
  } done{copied};
  return copy();
}

class PeerNode {
 public:
  /// Binds this peer's socket (the creator's endpoint goes into its invite). Throws IoError.
  PeerNode(const Invite& invite, bool creator, const SessionOptions& options);
  ~PeerNode();  ///< stop()
  PeerNode(const PeerNode&) = delete;
  PeerNode& operator=(const PeerNode&) = delete;

  // ---- set-up, before run() ----------------------------------------------------------------
  /// This peer holds version 0 of `mesh` and merges.
  void start_as_creator(const Mesh& mesh);
  /// This peer asks the invite's endpoint for a snapshot.
  void start_as_joiner();
  /// This peer holds `snap` at the journal's snapshot version, applies the journaled versions
  /// after it (handed to the host as versions), appends to the journal from there on, greets
  /// the members it knew, and merges nothing until they had time to answer (the newest chain
  /// wins, not this peer's).
  void start_resumed(const Snapshot& snap, JournalState& state);
  void run();
  /// Tells the others this peer leaves and joins the thread (idempotent).
  void stop();

  // ---- any thread ------------------------------------------------------------------------
  /// The host's side of the link (commands in; versions, events, stats out).
  HostChannel& host() { return host_; }
  /// Posts a command and wakes the thread.
  void command(Command c);
  /// The host's brush cursor: kept, and the thread woken when it has a change to send.
  void presence(const Presence& p);
  PeerId id() const { return self_; }
  const std::string& endpoint() const { return transport_.endpoint(); }
  std::string invite_text() const;

 private:
  // the loop
  void loop();
  bool merge_waiting() const;
  Clock::time_point next_deadline() const;
  void receive_all();
  bool run_commands();
  void run_timers(Clock::time_point now);
  void publish_stats();

  // inbound
  void handle(const Inbound& message, Clock::time_point now);
  void dispatch(const fb::Envelope& env, Clock::time_point now);
  void heard(PeerId peer, Clock::time_point now);
  void on_hello(const fb::Envelope& env, const fb::Hello& hello, Clock::time_point now);
  void on_heartbeat(const fb::Envelope& env, const fb::Heartbeat& hb, Clock::time_point now);
  void learn_members(const fb::Heartbeat& hb, Clock::time_point now);
  void on_leave(PeerId peer);
  void on_elected(const fb::Envelope& env, PeerId merger);
  void on_submit(PeerId sender, const fb::Submit& submit);
  void on_version(const fb::Envelope& env, const fb::Version& v);
  bool is_current_merger_version(const fb::Envelope& env);
  void on_fetch(PeerId peer, std::uint64_t after);
  void on_snapshot_chunk(const fb::SnapshotChunk& c);
  void on_presence(PeerId sender, const fb::Presence& p, Clock::time_point now);
  void heard_timing(PeerId sender, const fb::Heartbeat& hb, Clock::time_point now);
  /// `hierarchy`: the snapshot mesh's, built by the loader (a joiner), or null (we have one).
  /// `journaled`: the loader wrote it to the journal as it came (journal.h, adopt_snapshot).
  void install_snapshot(std::shared_ptr<const Snapshot> snap,
                        std::shared_ptr<const Hierarchy> hierarchy = nullptr,
                        bool journaled = false);
  /// Installs the joiner's first snapshot once the loader decoded it and built its hierarchy.
  void finish_load();

  // membership and election glue
  void member_joined(PeerId peer, const std::string& endpoint);
  void merger_changed();
  void elect();
  void expire(Clock::time_point now);
  void departed(PeerId peer, const char* how);
  /// Hands the host the peers' list as it stands now.
  void publish_peers();
  void greet_lost(Clock::time_point now);
  void report_revived();

  // replication glue
  /// Accepts `r` (decoding and checking it), or appends it with `merged_here`, the diff this
  /// peer's merge decoded (moved from), and hands it to the host.
  void apply_version(VersionRecord r, Diff* merged_here = nullptr);
  void drain_buffered();
  void add_contributions(const VersionRecord& r);
  void check_divergence(PeerId merger, std::uint64_t version, std::uint64_t chain,
                        Clock::time_point now);
  void request_snapshot(PeerId from);
  bool snapshot_flowing(Clock::time_point now) const;

  // serving snapshots (peer_node_snapshot.cpp): encoded beside the network thread, once per
  // version however many ask
  /// Sends `peer` a snapshot of our version, or of one it can fetch onward from.
  void send_snapshot(PeerId peer);
  void begin_snapshot_encoding();
  /// Queues the encoded snapshot for those waiting for it.
  void finish_snapshot_encoding();
  /// Queues `e` for `peer`, unless one is already on its way to it.
  void queue_snapshot(PeerId peer, const EncodedSnapshot& e);
  /// Sends queued chunks for one turn (kTurn), in the order queued.
  void send_snapshot_chunks();
  void drop_outgoing_snapshot(PeerId peer);
  /// A latch a task counts down once it has its copy of base_ (copy_then_count_down).
  std::shared_ptr<std::latch> begin_base_copy();
  /// Before base_ changes: waits for the merge in flight (drop_merge) and for every task's
  /// copy of it.
  void release_base();

  // the journal (peer_node_journal.cpp): one call per event; a failure is reported and ends
  // journaling, never the session
  template <class Write>
  void journal(Write&& write);
  void snapshot_into(Journal& j);
  void create_journal();
  void journal_snapshot();
  /// The snapshot the loader wrote for the journal, put into place (Journal::adopt_snapshot).
  void adopt_journal_snapshot();
  void journal_version(const VersionRecord& r);
  /// Starts a compaction of the journal's log into a snapshot of our version, copied, encoded
  /// and written beside the network thread (Journal::begin_compaction).
  void begin_compaction(Journal& j);
  /// Puts a written compaction into place, or removes one the journal gave up.
  void finish_compaction();
  void journal_own();
  void journal_member(PeerId peer, const std::string& endpoint);
  bool hold_merges(Clock::time_point now) const { return now < resumed_merge_hold_; }

  // outbound
  EnvelopeHeader header() const;
  void send_to_peer(PeerId peer, const Bytes& bytes);
  void broadcast(const Bytes& bytes);
  void heartbeat(Clock::time_point now);
  void joining_heartbeat(Clock::time_point now);
  void send_heartbeat_to(const std::string& endpoint);
  Bytes hello(bool wants_snapshot) const;
  void send_own_submit();
  /// The merger's heartbeat says it holds `version` at `chain`: our submit goes again if it
  /// reached the merger while it was behind.
  void resend_own_submit_if_caught_up(std::uint64_t version, std::uint64_t chain);
  void send_presence(Clock::time_point now);
  /// Starts a merge of the held submits on the merge worker (one at a time).
  void merge_pending();
  /// Publishes the worker's finished merge, if this peer still merges.
  void finish_merge();
  /// Before base_ changes other than by our own merge: waits for the merge in flight, if
  /// any, and forgets it.
  void drop_merge();
  /// The merge state for the mesh of base_: `hierarchy` if given, else built here.
  void build_merge_state(std::shared_ptr<const Hierarchy> hierarchy = nullptr);

  // events and stats
  void event(EventKind kind, PeerId peer, std::string message = "");
  void dropped(const std::string& why);

  SessionOptions options_;
  Invite invite_;  // the session id and keys; its endpoint is the inviter's (joiner)
  PeerId self_;
  Transport transport_;
  Membership membership_;  // who is alive, self included
  Election election_;      // who merges, in which epoch
  HostChannel host_;       // everything the host thread sees

  /// Whether we hold the session's mesh (the creator at once, a joiner once its snapshot came);
  /// before that we serve nothing and only greet the inviter.
  bool joined_ = false;
  std::string joining_endpoint_;  // the inviter's: greeted until the snapshot comes, kept open
  Mesh base_;                     // the mesh of replication_.version()
  Replication replication_;       // agreed version, hash chain, history, early arrivals
  /// The version and chain each member last said it holds: a new merger first catches up with
  /// the most advanced (it never publishes a number someone already holds).
  std::map<PeerId, std::pair<std::uint64_t, std::uint64_t>> reported_;
  /// Our last submit, kept until a merged version covers it: a new merger gets it again.
  Command own_submit_;
  /// The version the merger last said it holds when our submit went to it (kUnknownVersion:
  /// it had not said). A merger behind our base ignores the submit as stale; it is sent again
  /// once the merger says it holds our base (it caught up with us: after a heal, a new merger
  /// that was behind), or the artist's work would wait for an edit that may never come.
  std::uint64_t own_submit_merger_version_ = kUnknownVersion;
  static constexpr std::uint64_t kUnknownVersion = ~std::uint64_t{0};
  std::optional<MergerRole> merger_;  // once the mesh (and so its hierarchy) is known
  std::shared_ptr<const Hierarchy> hierarchy_;
  MergeFrame frame_;           // the session's (first mesh's), for the merge and wire tolerances
  SnapshotAssembly snapshot_;  // the chunks of the snapshot on its way to us
  /// We asked for a snapshot (divergence): accept one older than our version.
  bool snapshot_requested_ = false;
  PresenceSender presence_;  // when our cursor goes out
  PeerTable peer_table_;     // names, round trips, who left lately
  /// Endpoints of members that expired (not of those that said they leave), greeted every few
  /// heartbeats for kGreetLostFor: after a partition each side took the other for dead and
  /// sends it nothing, so without this nobody would speak first when the network heals.
  std::map<std::string, Clock::time_point> lost_;  // endpoint -> when it expired
  Clock::time_point next_greeting_{};

  std::optional<Journal> journal_;  // SessionOptions::journal, once opened
  /// A resumed peer merges from then on (it waits for the others' newer versions first).
  Clock::time_point resumed_merge_hold_{};

  // rate limits
  Clock::time_point next_heartbeat_{};         // the membership timer (greetings while joining)
  Clock::time_point last_merge_{};             // the merger's last merge (or attempt)
  Clock::time_point next_fetch_{};             // one fetch per heartbeat interval
  Clock::time_point next_join_hello_{};        // one greeting per snapshot's expected time
  Clock::time_point next_divergence_check_{};  // one snapshot request per 4 heartbeats
  Clock::time_point next_snapshot_request_{};  // while one is awaited, not before this
  Clock::time_point last_snapshot_chunk_{};    // when the last chunk came

  /// Declared after what their tasks use (merger_, transport_'s wake-up), so they are joined
  /// before those go.
  BackgroundTask<MergeOutcome> merge_worker_{[this] { transport_.wake(); }};
  struct LoadedSnapshot {
    std::shared_ptr<const Snapshot> snap;
    std::shared_ptr<const Hierarchy> hierarchy;
    bool journaled = false;     ///< written for the journal's adopt_snapshot
    std::string journal_error;  ///< why that failed (journaling then stops)
  };
  BackgroundTask<LoadedSnapshot> snapshot_loader_{[this] { transport_.wake(); }};
  /// A journal compaction's snapshot, copied from base_, encoded and written synced; its
  /// result is its version.
  BackgroundTask<std::uint64_t> compaction_writer_{[this] { transport_.wake(); }};
  /// The snapshot asked for by snapshot_waiters_, copied from base_ and encoded.
  BackgroundTask<EncodedSnapshot> snapshot_encoder_{[this] { transport_.wake(); }};
  EncodedSnapshot served_;  // the last one encoded: sent again to whoever asks at its version
  std::vector<PeerId> snapshot_waiters_;
  std::deque<OutgoingSnapshot> outgoing_snapshots_;
  /// The tasks' copies of base_ in the making. A copy of a mesh of millions of faces takes
  /// long enough to matter to heartbeats, so a task makes its own on its thread and counts
  /// its latch down once made; base_ does not change before then (release_base). Shared:
  /// a task's count_down may still be returning when the network thread's wait does.
  std::vector<std::shared_ptr<std::latch>> base_copies_;

  std::vector<std::uint64_t> inbound_;  // aligned copy of a misaligned message
  std::thread thread_;
  bool stopped_ = false;  // stop() ran
};

}  // namespace csculpt::peer
