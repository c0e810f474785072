// The public Session: the host thread's side (submit, update and the rebase, stats) over the
// network thread (PeerNode), and the mesh digest hosts compare for convergence.
#include "csculpt/peer/session.h"

#include <algorithm>
#include <cstring>
#include <map>
#include <optional>

#include "attribution.h"
#include "csculpt/diff.h"
#include "csculpt/error.h"
#include "csculpt/hash.h"
#include "csculpt/merge.h"
#include "host_values.h"
#include "invite.h"
#include "journal.h"
#include "merger_role.h"
#include "peer_node.h"
#include "presence.h"
#include "rebase.h"
#include "revert_log.h"
#include "undo_stack.h"

namespace csculpt::peer {

std::uint64_t mesh_digest(const Mesh& mesh) {
  std::uint64_t h = 0x6a09e667f3bcc908ull;
  h = hash_bytes(h, mesh.positions.data(), mesh.positions.size() * sizeof(Vec3f));
  for (const Channel& c : mesh.channels) {
    h = hash_bytes(h, c.desc.name.data(), c.desc.name.size());
    h = hash_bytes(h, c.values.data(), c.values.size() * sizeof(float));
  }
  return h;
}

namespace {

bool same_values(const AttributeDiff& a, const AttributeDiff& b) {
  return a.indices == b.indices && a.values.size() == b.values.size() &&
         (a.values.empty() ||
          std::memcmp(a.values.data(), b.values.data(), a.values.size() * sizeof(float)) == 0);
}

/// Whether `a` and `b` make the same change, bit for bit (a channel one lacks changes nothing).
bool same_change(const Diff& a, const Diff& b) {
  if (!same_values(a.positions, b.positions)) return false;
  static const AttributeDiff none;
  for (std::size_t c = 0; c < std::max(a.channels.size(), b.channels.size()); ++c)
    if (!same_values(c < a.channels.size() ? a.channels[c].change : none,
                     c < b.channels.size() ? b.channels[c].change : none))
      return false;
  return true;
}

}  // namespace

struct Session::Impl {
  std::unique_ptr<PeerNode> node;
  SessionOptions options;
  bool left = false;
  /// The host's view: the agreed version update() last applied, and its mesh.
  bool has_base = false;
  Mesh base;
  std::uint64_t version = 0;
  /// The merge state for rebasing (the node's hierarchy and frame, once it holds the mesh).
  std::shared_ptr<const Hierarchy> hierarchy;
  std::unique_ptr<Merger> merger;
  MergeFrame frame;
  /// What was sent for this base (decoded, as the peers see it), by sequence: a merged version
  /// names the one it includes.
  std::map<std::uint64_t, Diff> submitted;
  std::uint64_t next_sequence = 1;
  /// How the host's mesh differed from the base when the session last wrote it (a submit, an
  /// update, a resume): an update told the changed vertices compares those and `touched` with
  /// it, not the whole mesh. `host_state_sent`: it is what the latest submit left (an edit
  /// equal to it is not sent again).
  Diff host_state;
  bool host_state_sent = false;
  /// What the last update() wrote into the host's mesh, each vertex once (`wrote_all`: maybe
  /// every vertex), so the C ABI copies back only those; a mark per vertex while it is made.
  std::vector<std::uint32_t> wrote;
  std::vector<std::uint8_t> wrote_mark;
  bool wrote_all = true;
  /// The vertices where the host's mesh may differ from the base, increasing: what the last
  /// submit sent, what a rebase left, what undo and redo wrote. Submits with the host's changed
  /// vertices capture over these and the changed ones only.
  std::vector<std::uint32_t> touched;
  /// Reused by those submits: a mark per vertex (all clear between calls), the vertices to
  /// capture, and the capture.
  std::vector<std::uint8_t> marked;
  std::vector<std::uint32_t> candidates;
  Diff captured;
  /// Reused by update(): the diffs of the versions it applies at once.
  std::vector<const Diff*> merged;
  /// Strokes sent but not yet seen inside a merged version, and what each submit carried.
  std::uint32_t unacknowledged_strokes = 0;
  std::map<std::uint64_t, std::uint32_t> strokes_at;
  UndoStack undo;
  /// The values each applied version overwrote: how base steps back to a fork point.
  RevertLog reverts;
  /// Versions and snapshots taken from the network thread and not yet applied.
  std::vector<HostItem> pending;
  // the host side's statistics
  std::uint64_t versions_applied = 0, rebases = 0, strokes_submitted = 0, branch_rebases = 0,
                branch_versions_dropped = 0;
  /// Counted here, as the host applies a version holding them, never from what the network
  /// thread saw: a version of a branch that lost is never applied, and what it held is sent
  /// again and counted once, when the surviving chain has it.
  std::uint64_t strokes_acknowledged = 0;

  /// Refuses a host mesh of another layout (naming `call`), then makes the merge state.
  void ready_for(const Mesh& local, const char* call) {
    if (!same_layout(base, local))
      throw InvalidInput(std::string(call) +
                         ": the local mesh's vertices or channels differ from the session's");
    ensure_merge_state();
  }
  void ensure_merge_state() {
    if (merger) return;
    hierarchy = node->host().hierarchy();
    frame = node->host().frame();
    merger = std::make_unique<Merger>(*hierarchy);
    const EncodeOptions wire = session_wire_options(options.wire, frame);
    undo.set_tolerance(static_cast<float>(wire.position_tolerance * wire.position_scale),
                       static_cast<float>(wire.channel_tolerance));
  }
  /// Sends `d` (the host's edit from the base, captured from `local`) unless it is empty or was
  /// sent already; `local` then holds what the peers receive. False when nothing was sent.
  bool send(const Diff& d, Mesh& local, std::uint32_t strokes);
  /// send() found nothing to send; `at_base`: the host's mesh is the base. False.
  bool nothing_to_send(bool at_base, std::uint32_t strokes);
  /// Throws InvalidInput naming the first of `changed` out of the mesh's range.
  void require_in_range(std::span<const std::uint32_t> changed, const char* call) const;
  /// touched + `changed` (any order, repeats allowed) into `candidates`, increasing. Throws
  /// InvalidInput naming an index out of range before anything changes.
  void gather(std::span<const std::uint32_t> changed, const char* call);
  /// `touched` := where `local` differs from the base, among `among` (increasing).
  void retouch(const Mesh& local, std::span<const std::uint32_t> among);
  /// The same over every vertex (after a rebase, which is O(vertices) anyway).
  void retouch_all(const Mesh& local) {
    host_state = local.positions.empty() ? Diff{} : capture_diff(base, local);
    host_state_sent = false;
    touched = csculpt::peer::touched(host_state);
  }
  /// Whether `local` holds nothing but the base and the latest submit (no edit since),
  /// comparing the whole mesh or, given the host's `changed` vertices, those and `touched`.
  /// A value the host changed is checked (host_values.h) when it did edit.
  bool holds_only_submitted(const Mesh& local, const std::span<const std::uint32_t>* changed);
  /// update() with the host's changed vertices (null: compare the whole mesh).
  std::size_t update(Mesh& local, const std::span<const std::uint32_t>* changed);
  /// `vertices`, or `d`'s, were written into the host's mesh.
  void note_written(std::span<const std::uint32_t> vertices);
  void note_written(const Diff& d);
  /// Undo and redo write the host's mesh: what they `changed` joins the touched vertices.
  void written(std::span<const std::uint32_t> changed) {
    gather(changed, "undo");
    touched = candidates;
  }
  void apply_snapshot(const HostItem& item, Mesh& local);
  /// Resume: applies the journaled versions the node handed over, with `own` (this peer's
  /// unmerged edit) put into `local` at its base version. True when `local` holds edits to send.
  bool replay_journal(const std::optional<OwnEdit>& own, Mesh& local);
  void restore_own(const OwnEdit& own, Mesh& local);
  /// The mesh `item`'s snapshot branched from, and its version: our base stepped back to the
  /// fork point when we held another branch, so that branch's versions since are carried over,
  /// not dropped.
  std::pair<Mesh, std::uint64_t> fork_base(const HostItem& item);
  /// The submit of ours `item` includes (null: none; `sequence` is then left alone), its
  /// strokes counted acknowledged.
  const Diff* acknowledge(const HostItem& item, std::uint64_t& sequence);
  /// Applies consecutive merged versions, with one rebase of the host's edits; true if an edit
  /// we submitted was left out of them (resend). `unedited`: `local` is known to equal the base
  /// plus the latest submit.
  bool apply_versions(std::span<const HostItem> run, Mesh& local, bool unedited);
};

Session::Session(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

Session::~Session() {
  leave();
}

std::unique_ptr<Session> Session::create(const Mesh& mesh, const SessionOptions& options) {
  validate_options(options);
  validate(mesh, "session mesh");
  auto impl = std::make_unique<Impl>();
  impl->options = options;
  impl->node = std::make_unique<PeerNode>(new_invite(), true, options);
  impl->node->start_as_creator(mesh);
  impl->base = mesh;
  impl->has_base = true;
  impl->ensure_merge_state();
  impl->node->run();
  return std::unique_ptr<Session>(new Session(std::move(impl)));
}

std::unique_ptr<Session> Session::join(const std::string& invite_text,
                                       const SessionOptions& options, Millis timeout) {
  validate_options(options);
  const Invite invite = parse_invite(invite_text);
  auto impl = std::make_unique<Impl>();
  impl->options = options;
  impl->node = std::make_unique<PeerNode>(invite, false, options);
  impl->node->start_as_joiner();
  impl->node->run();
  if (!impl->node->host().wait_joined(timeout))
    throw IoError("no snapshot from " + invite.endpoint + " within " +
                  std::to_string(timeout.count()) + " ms (wrong invite, or no member reachable)");
  auto session = std::unique_ptr<Session>(new Session(std::move(impl)));
  Mesh scratch;
  session->update(scratch);  // takes the snapshot as the base
  return session;
}

namespace {

/// A resumed node: on the endpoint it had, if `options` lets the port be picked and it is free.
std::unique_ptr<PeerNode> resumed_node(const JournalMeta& meta, SessionOptions options) {
  if (options.bind.find('*') != std::string::npos && !meta.invite.endpoint.empty()) {
    SessionOptions again = options;
    again.bind = meta.invite.endpoint;
    try {
      return std::make_unique<PeerNode>(meta.invite, true, again);
    } catch (const IoError&) {  // taken: a new endpoint, as the options say
    }
  }
  return std::make_unique<PeerNode>(meta.invite, true, options);
}

}  // namespace

std::unique_ptr<Session> Session::resume(const std::string& journal_dir, Mesh& local,
                                         const SessionOptions& options) {
  validate_options(options);
  JournalState state = load_journal(journal_dir);
  Snapshot snap;
  try {
    snap = decode_snapshot(state.snapshot);
  } catch (const InvalidInput& e) {
    throw InvalidInput("journal: " + journal_dir + "/snapshot: " + e.what());
  }
  auto impl = std::make_unique<Impl>();
  impl->options = options;
  impl->options.journal = journal_dir;
  impl->options.id = state.meta.self;
  if (impl->options.name.empty()) impl->options.name = state.meta.name;
  impl->node = resumed_node(state.meta, impl->options);
  impl->node->start_resumed(snap, state);
  impl->base = std::move(snap.mesh);
  impl->has_base = true;
  impl->version = state.version;
  local = impl->base;
  const bool unmerged = impl->replay_journal(state.own, local);
  impl->node->run();
  auto session = std::unique_ptr<Session>(new Session(std::move(impl)));
  if (unmerged) session->submit(local, 0);
  return session;
}

void Session::Impl::restore_own(const OwnEdit& own, Mesh& local) {
  DiffHeader header;
  Diff d = decode_diff(own.diff, base, &header);
  apply_diff(d, local);
  submitted[header.sequence] = std::move(d);
  strokes_at[header.sequence] = own.strokes;
  unacknowledged_strokes = own.strokes;
  next_sequence = header.sequence + 1;
}

bool Session::Impl::replay_journal(const std::optional<OwnEdit>& own, Mesh& local) {
  ensure_merge_state();
  // An edit based on a version before the snapshot was merged or stale when it was taken.
  bool own_due = own && own->base_version >= version;
  auto restore_when_due = [&] {
    if (own_due && own->base_version == version) {
      restore_own(*own, local);
      own_due = false;
    }
  };
  restore_when_due();
  for (HostItem& item : node->host().take_items()) {
    apply_versions({&item, 1}, local, /*unedited=*/false);
    ++versions_applied;
    restore_when_due();
  }
  retouch_all(local);  // the restored edit differs from the base
  const bool unmerged = !equals_base_plus(base, nullptr, local);
  // Counted from the restart on: the strokes still unacknowledged are submitted again.
  if (!unmerged) unacknowledged_strokes = 0;
  strokes_submitted = unacknowledged_strokes;
  strokes_acknowledged = 0;
  return unmerged;
}

std::string Session::invite() const {
  return impl_->node->invite_text();
}
PeerId Session::id() const {
  return impl_->node->id();
}
std::string Session::endpoint() const {
  return impl_->node->endpoint();
}
std::uint64_t Session::version() const {
  return impl_->version;
}
const Mesh& Session::base() const {
  return impl_->base;
}

bool Session::submit(Mesh& local, std::uint32_t strokes) {
  Impl& s = *impl_;
  if (s.left) throw InvalidInput("submit: the session was left");
  s.ready_for(local, "submit");
  return s.send(capture_diff(s.base, local), local, strokes);
}

bool Session::submit(Mesh& local, std::uint32_t strokes, std::span<const std::uint32_t> changed) {
  Impl& s = *impl_;
  if (s.left) throw InvalidInput("submit: the session was left");
  s.ready_for(local, "submit");
  s.gather(changed, "submit");
  capture_diff_at(s.base, local, s.candidates, s.captured);
  return s.send(s.captured, local, strokes);
}

std::span<const std::uint32_t> Session::touched() const {
  return impl_->touched;
}

bool Session::Impl::send(const Diff& d, Mesh& local, std::uint32_t strokes) {
  check_diff_values(d, base, frame, "submit");  // the changed values: before anything is sent
  if (d.empty() || (host_state_sent && same_change(d, host_state)))
    return nothing_to_send(d.empty(), strokes);
  DiffHeader header;
  header.base_version = version;
  header.sequence = next_sequence;
  header.author = options.name;
  Diff sent;  // what the peers decode
  Bytes bytes = encode_diff(d, base, header, session_wire_options(options.wire, frame), &sent);
  // The host's values become what the peers receive: changed vertices the quantisation left
  // out go back to the base, the others to their decoded values.
  restore(base, d, local);
  apply_diff(sent, local);
  // Local now differs from the base at most where `sent` changes it.
  retouch(local, csculpt::peer::touched(sent));
  host_state = captured;  // assigned into its kept capacity: no allocation per submit
  // Every change within the wire's tolerance of the base (a rebase's float rounding): the host's
  // mesh is the base again, and an empty submit would only make an empty version.
  if (sent.empty()) {
    host_state_sent = false;
    return nothing_to_send(true, strokes);
  }
  ++next_sequence;
  unacknowledged_strokes += strokes;
  strokes_submitted += strokes;
  host_state_sent = true;
  strokes_at[header.sequence] = unacknowledged_strokes;
  submitted[header.sequence] = std::move(sent);
  Command c;
  c.kind = Command::Kind::submit;
  c.base_version = version;
  c.bytes = std::move(bytes);
  c.strokes = unacknowledged_strokes;
  node->command(std::move(c));
  return true;
}

bool Session::Impl::nothing_to_send(bool at_base, std::uint32_t strokes) {
  strokes_submitted += strokes;
  // These strokes changed nothing beyond a submit still waiting for its version: they are
  // there when it is, and acknowledged with it.
  if (!at_base && !submitted.empty()) {
    unacknowledged_strokes += strokes;
    strokes_at[submitted.rbegin()->first] = unacknowledged_strokes;
    return false;
  }
  // They changed nothing the session does not hold: acknowledged as they are, not left
  // unacknowledged for ever.
  strokes_acknowledged += strokes;
  // The host's mesh is the agreed base and nothing of ours is in flight: strokes sent before
  // are in the base (a snapshot carried them) or the host took them back. None waits for a
  // version any more.
  if (at_base && submitted.empty()) {
    strokes_acknowledged += unacknowledged_strokes;
    unacknowledged_strokes = 0;
  }
  return false;
}

std::pair<Mesh, std::uint64_t> Session::Impl::fork_base(const HostItem& item) {
  std::pair<Mesh, std::uint64_t> from{base, version};
  // No common version known: the whole kept history is carried (what both branches share
  // merges as one intent, SameChange::once).
  const std::uint64_t fork = item.fork.value_or(0);
  if (fork >= version) return from;  // our branch is the snapshot's: nothing of ours is lost
  from.second = reverts.revert(from.first, version, fork);
  ++branch_rebases;
  // Versions after the fork the log no longer reaches stay in the base: their changes are
  // not carried (a step over an earlier snapshot may reach before the fork: nothing dropped).
  if (item.fork && from.second > fork) branch_versions_dropped += from.second - fork;
  return from;
}

void Session::Impl::require_in_range(std::span<const std::uint32_t> changed,
                                     const char* call) const {
  const std::size_t n = base.vertex_count();
  for (const std::uint32_t v : changed)
    if (v >= n)
      throw InvalidInput(std::string(call) + ": changed vertex " + std::to_string(v) +
                         " is out of range (the session's mesh has " + std::to_string(n) +
                         " vertices)");
}

void Session::Impl::gather(std::span<const std::uint32_t> changed, const char* call) {
  require_in_range(changed, call);
  marked.resize(base.vertex_count(), 0);
  candidates.assign(touched.begin(), touched.end());
  for (const std::uint32_t v : touched) marked[v] = 1;
  for (const std::uint32_t v : changed)
    if (!marked[v]) {
      marked[v] = 1;
      candidates.push_back(v);
    }
  for (const std::uint32_t v : candidates) marked[v] = 0;
  std::sort(candidates.begin(), candidates.end());
}

void Session::Impl::retouch(const Mesh& local, std::span<const std::uint32_t> among) {
  capture_diff_at(base, local, among, captured);
  touched = csculpt::peer::touched(captured);
}

void Session::Impl::apply_snapshot(const HostItem& item, Mesh& local) {
  const Mesh& snap = item.snap->mesh;
  if (has_base) {
    // Carry the local edits, and our branch's versions since the fork, over to the snapshot.
    ensure_merge_state();
    auto [from, from_version] = fork_base(item);
    // A later fork may lie before this snapshot: the log steps back over it too.
    reverts.jumped(from_version, from, item.version, snap);
    if (rebase_onto_snapshot(from, snap, local, *merger, frame)) ++rebases;
    base = std::move(from);  // the snapshot now
  } else {
    local = snap;
    base = snap;
  }
  has_base = true;
  version = item.version;
  submitted.clear();
  strokes_at.clear();  // those submits are not in the snapshot: their strokes go out again
  ensure_merge_state();
  retouch_all(local);
}

const Diff* Session::Impl::acknowledge(const HostItem& item, std::uint64_t& sequence) {
  const Diff* ours = nullptr;
  for (const MergedSubmit& m : item.merged_by)
    if (m.peer == node->id())
      if (auto it = submitted.find(m.sequence); it != submitted.end()) {
        ours = &it->second;
        sequence = m.sequence;
        if (auto st = strokes_at.find(m.sequence); st != strokes_at.end()) {
          const std::uint32_t acknowledged = std::min(unacknowledged_strokes, st->second);
          unacknowledged_strokes -= acknowledged;
          strokes_acknowledged += acknowledged;
        }
      }
  return ours;
}

bool Session::Impl::apply_versions(std::span<const HostItem> run, Mesh& local, bool unedited) {
  ensure_merge_state();
  // Our submits were all based on the version before the run: the first version that merged
  // one holds it (a later one cannot).
  const Diff* ours = nullptr;
  std::uint64_t merged_sequence = 0;
  for (const HostItem& item : run)
    if (const Diff* d = acknowledge(item, merged_sequence)) ours = d;
  // Known equal when the run includes our latest submit (or none was sent) and the host
  // edited nothing since: the rebase need not compare the whole mesh again.
  const bool known =
      unedited && (submitted.empty() ? ours == nullptr : ours == &submitted.rbegin()->second);
  merged.clear();  // reused: update() runs every frame
  for (const HostItem& item : run) merged.push_back(&item.merged);
  const auto keep_reverts = [&](std::size_t i, const Mesh& before) {
    reverts.record(run[i].version, run[i].merged, before);
  };
  const bool empty = local.positions.empty();
  if (rebase_onto_versions(base, ours, merged, local, *merger, frame, known, keep_reverts)) {
    ++rebases;
    retouch_all(local);
    wrote_all = true;
  } else {
    touched.clear();  // local is the new base (or empty)
    host_state = Diff{};
    host_state_sent = false;
    wrote_all |= empty;
    // Written sparsely: our submit's vertices back to the base, then each version's.
    if (ours) note_written(*ours);
    for (const Diff* d : merged) note_written(*d);
  }
  version = run.back().version;
  const bool resend = !submitted.empty() && submitted.rbegin()->first != merged_sequence;
  submitted.clear();
  strokes_at.clear();
  return resend;
}

void Session::Impl::note_written(std::span<const std::uint32_t> vertices) {
  if (wrote_all) return;
  wrote_mark.resize(base.vertex_count(), 0);
  for (const std::uint32_t v : vertices)
    if (!wrote_mark[v]) {
      wrote_mark[v] = 1;
      wrote.push_back(v);
    }
}

void Session::Impl::note_written(const Diff& d) {
  note_written(d.positions.indices);
  for (const ChannelDiff& c : d.channels) note_written(c.change.indices);
}

bool Session::Impl::holds_only_submitted(const Mesh& local,
                                         const std::span<const std::uint32_t>* changed) {
  if (changed == nullptr) {
    if (equals_base_plus(base, submitted.empty() ? nullptr : &submitted.rbegin()->second, local))
      return true;
    check_host_values(local, base, frame, "update");
    return false;
  }
  // The host changed nothing but `changed` since the session last wrote its mesh, which then
  // differed from the base by host_state, over `touched`: the mesh is as the session left it,
  // and that was the base plus the latest submit.
  gather(*changed, "update");
  capture_diff_at(base, local, candidates, captured);
  const bool left_as_submitted =
      submitted.empty() ? same_change(host_state, Diff{}) : host_state_sent;
  if (left_as_submitted && same_change(captured, host_state)) return true;
  check_diff_values(captured, base, frame, "update");
  return false;
}

std::size_t Session::update(Mesh& local) {
  return impl_->update(local, nullptr);
}

std::size_t Session::update(Mesh& local, std::span<const std::uint32_t> changed) {
  return impl_->update(local, &changed);
}

std::optional<std::span<const std::uint32_t>> Session::written() const {
  if (impl_->wrote_all) return std::nullopt;
  return impl_->wrote;
}

std::size_t Session::Impl::update(Mesh& local, const std::span<const std::uint32_t>* changed) {
  std::size_t applied = 0;
  for (const std::uint32_t v : wrote) wrote_mark[v] = 0;  // also after a call that threw
  wrote.clear();
  wrote_all = false;
  // A submit that a version did not include (it reached the merger after the merge, based on
  // the older version) is sent again, rebased, once the versions are applied: the host does
  // not have to notice. Unless the host edited since: then the resend would carry strokes the
  // host has not counted yet, and its next submit, which counts them, carries both.
  bool resend = false;
  if (changed) require_in_range(*changed, "update");  // a host's mistake, even with no version
  for (HostItem& item : node->host().take_items()) pending.push_back(std::move(item));
  if (pending.empty()) return 0;  // hosts call this every frame: nothing to do is free
  // Refused before any version is applied: a bad value leaves them waiting for the next call.
  // A host that edited nothing since its submit holds only values the session checked.
  bool unedited = false;
  if (has_base && !local.positions.empty()) {
    ready_for(local, "update");
    unedited = holds_only_submitted(local, changed);
  }
  const bool host_edited = !unedited;
  std::size_t done = 0;  // pending[0, done) are applied: a failure keeps the rest for the next call
  try {
    while (done < pending.size()) {
      const HostItem& item = pending[done];
      std::size_t n = 1;
      if (item.snapshot) {
        // Edits submitted but not in the snapshot, or a lost branch's carried over: sent again.
        resend |= !submitted.empty() || (has_base && item.fork.value_or(0) < version);
        apply_snapshot(item, local);
        wrote_all = true;
        ++applied;
      } else if (item.version == version + 1) {  // always: the node hands them in order
        // With the versions that follow it, up to a snapshot: one rebase for them all.
        while (done + n < pending.size() && !pending[done + n].snapshot &&
               pending[done + n].version == item.version + n)
          ++n;
        resend |= apply_versions({pending.data() + done, n}, local, unedited);
        applied += n;
      }
      done += n;
      unedited = touched.empty();  // exact after a version or snapshot: local is the base
    }
  } catch (...) {
    versions_applied += applied;
    pending.erase(pending.begin(), pending.begin() + static_cast<std::ptrdiff_t>(done));
    wrote_all = true;  // a version may be half written: a mirror takes the whole mesh back
    throw;
  }
  pending.clear();
  versions_applied += applied;
  // The touched vertices are exact after a rebase: the resend need not capture the whole mesh.
  if (resend && !local.positions.empty() && !host_edited) {
    gather({}, "update");
    capture_diff_at(base, local, candidates, captured);
    send(captured, local, 0);
    note_written(candidates);  // the wire's rounding of what was sent
  }
  return applied;
}

void Session::record_stroke(const Mesh& local, std::span<const std::uint32_t> vertices,
                            std::span<const float> before) {
  Impl& s = *impl_;
  s.ready_for(local, "record_stroke");
  s.undo.record(local, s.hierarchy->topology(), vertices, before);
}

bool Session::undo(Mesh& local, std::vector<std::uint32_t>& changed) {
  Impl& s = *impl_;
  s.ready_for(local, "undo");
  const bool did = s.undo.undo(local, *s.merger, s.frame, changed);
  s.written(changed);
  return did;
}

bool Session::redo(Mesh& local, std::vector<std::uint32_t>& changed) {
  Impl& s = *impl_;
  s.ready_for(local, "redo");
  const bool did = s.undo.redo(local, *s.merger, s.frame, changed);
  s.written(changed);
  return did;
}

std::size_t Session::undo_depth() const {
  return impl_->undo.undo_depth();
}

std::size_t Session::redo_depth() const {
  return impl_->undo.redo_depth();
}

std::vector<Event> Session::poll_events() {
  return impl_->node->host().take_events();
}

SessionStats Session::stats() const {
  SessionStats st = impl_->node->host().stats();
  st.versions_applied = impl_->versions_applied;
  st.rebases = impl_->rebases;
  st.branch_rebases = impl_->branch_rebases;
  st.branch_versions_dropped = impl_->branch_versions_dropped;
  st.strokes_submitted = impl_->strokes_submitted;
  st.strokes_acknowledged = impl_->strokes_acknowledged;
  return st;
}

std::vector<std::pair<PeerId, std::vector<float>>> Session::attribution() const {
  return impl_->node->host().attribution();
}

void Session::set_presence(const Presence& presence) {
  if (impl_->left) throw InvalidInput("set_presence: the session was left");
  validate_presence(presence);
  impl_->node->presence(presence);
}

std::vector<PeerPresence> Session::presence() const {
  HostChannel& host = impl_->node->host();
  // Colours as the attribution view gives them: contributors first, then the other members.
  const std::vector<PeerId> contributors = host.attribution_peers();
  std::vector<PeerId> members{id()};
  for (const PeerInfo& p : host.peers())
    if (p.state != PeerState::left) members.push_back(p.id);
  std::sort(members.begin(), members.end());
  const Clock::time_point now = Clock::now();
  std::vector<PeerPresence> out;
  for (const auto& [peer, r] : host.presence()) {
    PeerPresence p;
    p.peer = peer;
    p.presence = r.presence;
    p.sequence = r.sequence;
    p.age = std::chrono::duration_cast<Millis>(now - r.at);
    p.colour = presence_colour(peer, r.presence.rgba, contributors, members);
    out.push_back(p);
  }
  return out;
}

std::vector<PeerInfo> Session::peers() const {
  return impl_->node->host().peers();
}

void Session::leave() {
  if (impl_->left) return;
  impl_->left = true;
  impl_->node->stop();
}

}  // namespace csculpt::peer
