// The journal (peer/src/journal.h): round trip, a torn tail cut at every byte dropped and never
// misread, a corrupt checksum, compaction bounding the log, clear errors for a missing or
// garbage directory, compactions written beside the network thread; and Session::resume
// bringing back the agreed mesh and the unmerged edit.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <stdexcept>
#include <thread>

#include "csculpt/error.h"
#include "csculpt/peer/session.h"
#include "csculpt/testkit/generate.h"
#include "csculpt/vec3.h"
#include "invite.h"
#include "journal.h"
#include "pieces.h"
#include "replication.h"
#include "sessions.h"
#include "snapshot.h"

namespace {

using namespace csculpt;
using namespace csculpt::peer;
using namespace csculpt::peer::testing;
namespace fs = std::filesystem;

/// A fresh directory under the test temp dir, removed at the end.
class TempDir {
 public:
  explicit TempDir(const std::string& name)
      : path_((fs::temp_directory_path() /
               ("csculpt-journal-" + name + "-" + std::to_string(random_u64())))
                  .string()) {}
  ~TempDir() { fs::remove_all(path_); }
  const std::string& path() const { return path_; }
  std::string file(const char* name) const { return (fs::path(path_) / name).string(); }

 private:
  std::string path_;
};

Bytes read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void write_bytes(const std::string& path, const Bytes& b) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
}

JournalMeta sample_meta() {
  JournalMeta m;
  m.invite = new_invite();
  m.invite.endpoint = "tcp://127.0.0.1:5555";
  m.self = 42;
  m.name = "ada";
  return m;
}

/// Version `v` after `parent` (chains are arbitrary here: load checks only that they link).
VersionRecord sample_version(std::uint64_t v, std::uint64_t parent) {
  VersionRecord r;
  r.version = v;
  r.parent_chain = parent;
  r.chain = parent * 31 + v;
  r.diff_bytes = Bytes(40 + v, static_cast<std::uint8_t>(v));
  r.merged = {{7, v, 2}, {42, v + 1, 1}};
  r.contributions = {{7, Bytes{1, 2, 3}, Bytes{9, 8, 7}, 0.5f}};
  r.merge_ms = 1.5f;
  r.conflicting = 1;
  return r;
}

Bytes sample_snapshot() {
  return encode_snapshot(sphere(), MergeFrame::fit(sphere().positions), {});
}

/// A journal at version 0 with `versions` versions, an own edit after the second, two members.
std::vector<VersionRecord> fill(const std::string& dir, int versions) {
  Journal j = Journal::create(dir, sample_meta(), {});
  j.reset(sample_snapshot(), 0, kGenesisChain);
  j.append_member(7, "tcp://127.0.0.1:7007");
  std::vector<VersionRecord> out;
  std::uint64_t parent = kGenesisChain;
  for (int v = 1; v <= versions; ++v) {
    out.push_back(sample_version(static_cast<std::uint64_t>(v), parent));
    parent = out.back().chain;
    j.append_version(out.back());
    if (v == 2) j.append_own({2, 3, Bytes{5, 6, 7, 8}});
  }
  j.append_member(9, "tcp://127.0.0.1:9009");
  return out;
}

void expect_same(const VersionRecord& a, const VersionRecord& b) {
  EXPECT_EQ(a.version, b.version);
  EXPECT_EQ(a.parent_chain, b.parent_chain);
  EXPECT_EQ(a.chain, b.chain);
  EXPECT_EQ(a.diff_bytes, b.diff_bytes);
  ASSERT_EQ(a.merged.size(), b.merged.size());
  for (std::size_t i = 0; i < a.merged.size(); ++i) {
    EXPECT_EQ(a.merged[i].peer, b.merged[i].peer);
    EXPECT_EQ(a.merged[i].sequence, b.merged[i].sequence);
    EXPECT_EQ(a.merged[i].strokes, b.merged[i].strokes);
  }
  ASSERT_EQ(a.contributions.size(), b.contributions.size());
  EXPECT_EQ(a.contributions[0].index_gaps, b.contributions[0].index_gaps);
  EXPECT_EQ(a.contributions[0].amounts, b.contributions[0].amounts);
  EXPECT_EQ(a.merge_ms, b.merge_ms);
  EXPECT_EQ(a.conflicting, b.conflicting);
}

TEST(Journal, RoundTripsMetaSnapshotVersionsOwnEditAndMembers) {
  TempDir dir("roundtrip");
  const std::vector<VersionRecord> written = fill(dir.path(), 5);
  const JournalState s = load_journal(dir.path());
  EXPECT_EQ(s.meta.self, 42u);
  EXPECT_EQ(s.meta.name, "ada");
  EXPECT_EQ(s.meta.invite.endpoint, "tcp://127.0.0.1:5555");
  EXPECT_NE(s.meta.invite.session, 0u);
  EXPECT_EQ(s.version, 0u);
  EXPECT_EQ(s.chain, kGenesisChain);
  EXPECT_EQ(s.snapshot, sample_snapshot());
  ASSERT_EQ(s.versions.size(), 5u);
  for (std::size_t i = 0; i < 5; ++i) expect_same(s.versions[i], written[i]);
  ASSERT_TRUE(s.own);
  EXPECT_EQ(s.own->base_version, 2u);
  EXPECT_EQ(s.own->strokes, 3u);
  EXPECT_EQ(s.own->diff, (Bytes{5, 6, 7, 8}));
  EXPECT_EQ(s.members.at(7), "tcp://127.0.0.1:7007");
  EXPECT_EQ(s.members.at(9), "tcp://127.0.0.1:9009");
  EXPECT_EQ(s.dropped_bytes, 0u);
  EXPECT_EQ(s.log_bytes, read_bytes(dir.file("log")).size());
}

// The log cut at every byte (a write torn by a crash): what loads is exactly the records
// entirely before the cut, the rest is reported dropped, and reopening cuts the file there so
// the next record follows the last valid one.
TEST(Journal, ATornTailAtEveryByteIsDroppedNeverMisread) {
  TempDir dir("torn");
  const std::vector<VersionRecord> written = fill(dir.path(), 4);
  const Bytes log = read_bytes(dir.file("log"));
  const JournalState whole = load_journal(dir.path());
  std::size_t previous_versions = 0;
  for (std::size_t cut = 0; cut < log.size(); ++cut) {
    write_bytes(dir.file("log"), Bytes(log.begin(), log.begin() + cut));
    JournalState s;
    try {
      s = load_journal(dir.path());
    } catch (const InvalidInput& e) {
      // Before the log's head is whole the log is not one of this snapshot: refused, named.
      EXPECT_NE(std::string(e.what()).find("log"), std::string::npos) << e.what();
      continue;
    }
    ASSERT_LE(s.log_bytes, cut);
    EXPECT_EQ(s.log_bytes + s.dropped_bytes, cut);
    EXPECT_GE(s.versions.size(), previous_versions) << "at cut " << cut;
    previous_versions = s.versions.size();
    for (std::size_t i = 0; i < s.versions.size(); ++i) expect_same(s.versions[i], written[i]);
    if (s.dropped_bytes) {
      EXPECT_NE(s.dropped_reason.find("torn"), std::string::npos);
    }
  }
  EXPECT_EQ(previous_versions, whole.versions.size());
  // Reopened after a cut inside the last version (the member record after it is 44 bytes):
  // appending goes on from the version before.
  const std::size_t cut = log.size() - 60;
  write_bytes(dir.file("log"), Bytes(log.begin(), log.begin() + cut));
  JournalState s = load_journal(dir.path());
  const std::size_t kept = s.versions.size();
  ASSERT_EQ(kept, written.size() - 1);
  {
    Journal j = Journal::reopen(dir.path(), s, s.meta, {});
    EXPECT_EQ(read_bytes(dir.file("log")).size(), s.log_bytes);
    VersionRecord next = sample_version(kept + 1, s.versions.back().chain);
    j.append_version(next);
  }
  const JournalState after = load_journal(dir.path());
  EXPECT_EQ(after.dropped_bytes, 0u);
  ASSERT_EQ(after.versions.size(), kept + 1);
  EXPECT_EQ(after.versions.back().version, kept + 1);
}

TEST(Journal, ACorruptRecordEndsTheLogThere) {
  TempDir dir("corrupt");
  fill(dir.path(), 4);
  Bytes log = read_bytes(dir.file("log"));
  const JournalState whole = load_journal(dir.path());
  // A byte in the middle of the log flipped: the records from the one it hits on are dropped.
  const std::size_t at = log.size() / 2;
  log[at] ^= 0x40;
  write_bytes(dir.file("log"), log);
  const JournalState s = load_journal(dir.path());
  EXPECT_LT(s.versions.size(), whole.versions.size());
  EXPECT_LE(s.log_bytes, at);
  EXPECT_NE(s.dropped_reason.find("checksum"), std::string::npos) << s.dropped_reason;
  EXPECT_NE(s.dropped_reason.find(dir.file("log")), std::string::npos) << s.dropped_reason;
}

TEST(Journal, CompactionBoundsTheLogAndKeepsTheState) {
  TempDir dir("compaction");
  JournalLimits limits;
  limits.max_log_versions = 8;
  Journal j = Journal::create(dir.path(), sample_meta(), limits);
  j.reset(sample_snapshot(), 0, kGenesisChain);
  j.append_member(7, "tcp://127.0.0.1:7007");
  std::uint64_t parent = kGenesisChain, held = 0;
  std::size_t largest = 0;
  for (std::uint64_t v = 1; v <= 50; ++v) {
    const VersionRecord r = sample_version(v, parent);
    parent = r.chain;
    j.append_version(r);
    j.append_own({v, 1, Bytes{static_cast<std::uint8_t>(v)}});
    largest = std::max<std::size_t>(largest, read_bytes(dir.file("log")).size());
    if (j.wants_compaction()) {
      j.reset(sample_snapshot(), v, r.chain);
      held = v;
    }
  }
  EXPECT_EQ(held, 48u);
  EXPECT_LT(largest, 8 * 1024u);  // 8 versions of ~200 bytes and the own edits
  const JournalState s = load_journal(dir.path());
  EXPECT_EQ(s.version, 48u);
  ASSERT_EQ(s.versions.size(), 2u);
  EXPECT_EQ(s.versions.back().version, 50u);
  EXPECT_EQ(s.versions.back().chain, parent);
  ASSERT_TRUE(s.own);
  EXPECT_EQ(s.own->base_version, 50u);
  EXPECT_EQ(s.members.at(7), "tcp://127.0.0.1:7007");  // carried over
  EXPECT_FALSE(fs::exists(dir.file("log.tmp")));
}

// A compaction stopped between renaming the snapshot and the log: the new log is taken.
TEST(Journal, ACompactionStoppedBetweenItsRenamesLoadsTheNewLog) {
  TempDir dir("half");
  fill(dir.path(), 3);
  const JournalState before = load_journal(dir.path());
  Journal j = Journal::reopen(dir.path(), before, before.meta, {});
  j.reset(sample_snapshot(), 3, before.versions.back().chain);
  // Undo the second rename by hand: log.tmp is the new log, log an old one.
  fs::rename(dir.file("log"), dir.file("log.tmp"));
  const Bytes old_log = {'C', 'S', 'J', '1', 'L', 'O', 'G', '_'};
  write_bytes(dir.file("log"), old_log);
  const JournalState s = load_journal(dir.path());
  EXPECT_EQ(s.version, 3u);
  EXPECT_TRUE(s.versions.empty());
  EXPECT_TRUE(fs::exists(dir.file("log")));
  EXPECT_FALSE(fs::exists(dir.file("log.tmp")));
}

/// The journal in `dir`, reopened to append to.
Journal reopened(const std::string& dir, JournalLimits limits = {}) {
  const JournalState s = load_journal(dir);
  return Journal::reopen(dir, s, s.meta, limits);
}

// A compaction whose snapshot is written beside the network thread: until it is put into
// place the journal is the old snapshot and the whole log (a crash then loses nothing and
// ignores the half-made snapshot); once it is, the new snapshot and the versions appended
// meanwhile, the own edit based on one of them and the members.
TEST(Journal, ACompactionBesideTheNetworkThreadKeepsWhatCameMeanwhile) {
  TempDir dir("beside");
  const std::vector<VersionRecord> written = fill(dir.path(), 5);
  JournalLimits limits;
  limits.max_log_versions = 2;  // past it from the start: only the compaction under way holds
  Journal j = reopened(dir.path(), limits);
  EXPECT_TRUE(j.wants_compaction());
  j.begin_compaction(5, written.back().chain);
  EXPECT_EQ(j.compacting(), std::optional<std::uint64_t>(5));
  std::thread writer(
      [&] { write_compaction_snapshot(dir.path(), sample_snapshot(), 5, written.back().chain); });
  std::vector<VersionRecord> after = written;
  for (std::uint64_t v = 6; v <= 8; ++v) {
    after.push_back(sample_version(v, after.back().chain));
    j.append_version(after.back());
    EXPECT_FALSE(j.wants_compaction());  // one at a time
  }
  j.append_own({7, 4, Bytes{1, 1, 2, 3}});
  j.append_member(11, "tcp://127.0.0.1:1111");
  writer.join();
  const JournalState crashed = load_journal(dir.path());  // as if it stopped here
  EXPECT_EQ(crashed.version, 0u);
  ASSERT_EQ(crashed.versions.size(), 8u);
  for (std::size_t i = 0; i < 8; ++i) expect_same(crashed.versions[i], after[i]);
  j.finish_compaction();
  EXPECT_FALSE(j.compacting());
  const JournalState s = load_journal(dir.path());
  EXPECT_EQ(s.version, 5u);
  EXPECT_EQ(s.chain, written.back().chain);
  EXPECT_EQ(s.snapshot, sample_snapshot());
  ASSERT_EQ(s.versions.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) expect_same(s.versions[i], after[5 + i]);
  ASSERT_TRUE(s.own);
  EXPECT_EQ(s.own->base_version, 7u);
  EXPECT_EQ(s.own->diff, (Bytes{1, 1, 2, 3}));
  EXPECT_EQ(s.members.size(), 3u);
  EXPECT_EQ(s.members.at(11), "tcp://127.0.0.1:1111");
  EXPECT_FALSE(fs::exists(dir.file("snapshot.next")));
  EXPECT_FALSE(fs::exists(dir.file("log.tmp")));
  // The log goes on from there.
  after.push_back(sample_version(9, after.back().chain));
  j.append_version(after.back());
  EXPECT_EQ(load_journal(dir.path()).versions.size(), 4u);
}

// A snapshot taken at once (a divergence, a branch's state) while a compaction is written
// gives the compaction up: the journal is the reset's, and the compaction's file goes.
TEST(Journal, AResetDuringACompactionGivesItUp) {
  TempDir dir("given-up");
  const std::vector<VersionRecord> written = fill(dir.path(), 3);
  Journal j = reopened(dir.path());
  j.begin_compaction(3, written.back().chain);
  write_compaction_snapshot(dir.path(), sample_snapshot(), 3, written.back().chain);
  // A joiner's snapshot is never adopted then: its writer would share the compaction's file.
  EXPECT_THROW(j.adopt_snapshot(3, written.back().chain), std::logic_error);
  j.reset(sample_snapshot(), 9, 99);
  EXPECT_FALSE(j.compacting());
  discard_compaction_snapshot(dir.path());  // what PeerNode does once the writer is done
  j.finish_compaction();                    // nothing under way: a no-op
  const JournalState s = load_journal(dir.path());
  EXPECT_EQ(s.version, 9u);
  EXPECT_EQ(s.chain, 99u);
  EXPECT_TRUE(s.versions.empty());
  EXPECT_FALSE(fs::exists(dir.file("snapshot.next")));
}

std::string load_error(const std::string& dir) {
  try {
    load_journal(dir);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(Journal, AMissingEmptyOrGarbageDirectoryIsRefusedNamingTheFile) {
  TempDir dir("errors");
  EXPECT_NE(load_error(dir.path()).find(dir.path()), std::string::npos);
  fs::create_directories(dir.path());
  EXPECT_NE(load_error(dir.path()).find(dir.file("session")), std::string::npos);
  write_bytes(dir.file("session"), Bytes(100, 0x5a));
  const std::string garbage = load_error(dir.path());
  EXPECT_NE(garbage.find(dir.file("session")), std::string::npos) << garbage;
  EXPECT_NE(garbage.find("not a cSculpt journal"), std::string::npos) << garbage;
  fs::remove(dir.file("session"));
  {
    Journal j = Journal::create(dir.path(), sample_meta(), {});  // no snapshot yet
  }
  EXPECT_NE(load_error(dir.path()).find(dir.file("snapshot")), std::string::npos);
  // Nothing to resume without a snapshot: a new journal may start there; with one, not.
  Journal::create(dir.path(), sample_meta(), {}).reset(sample_snapshot(), 0, kGenesisChain);
  EXPECT_THROW(Journal::create(dir.path(), sample_meta(), {}), InvalidInput);  // resume it
  fill((fs::path(dir.path()) / "second").string(), 1);
  const std::string second = (fs::path(dir.path()) / "second").string();
  Bytes snap = read_bytes((fs::path(second) / "snapshot").string());
  snap[snap.size() / 2] ^= 1;
  write_bytes((fs::path(second) / "snapshot").string(), snap);
  EXPECT_NE(load_error(second).find("snapshot is corrupt"), std::string::npos)
      << load_error(second);
}

// ---- Session::resume, in one process -----------------------------------------------------

TEST(SessionResume, BringsBackTheAgreedMeshWithTheSameIdentity) {
  TempDir dir("agreed");
  SessionOptions o = fast_options(3, "ada");
  o.journal = dir.path();
  std::uint64_t version = 0, base_digest = 0;
  std::string endpoint, invite;
  {
    auto s = Session::create(sphere(), o);
    endpoint = s->endpoint();
    invite = s->invite();
    Mesh local = stroked(sphere(), {0, 0, 1}, {0, 0.2f, 0});
    ASSERT_TRUE(s->submit(local, 1));
    ASSERT_TRUE(wait_until([&] { return s->update(local) > 0; }));
    version = s->version();
    base_digest = mesh_digest(s->base());
  }
  Mesh local;
  auto r = Session::resume(dir.path(), local, o);
  EXPECT_EQ(r->id(), 3u);
  EXPECT_EQ(r->endpoint(), endpoint);  // the port was free again
  EXPECT_EQ(r->invite(), invite);      // same session, keys and endpoint
  EXPECT_EQ(r->version(), version);
  EXPECT_EQ(mesh_digest(r->base()), base_digest);
  EXPECT_EQ(mesh_digest(local), base_digest);  // nothing was left unmerged
}

TEST(SessionResume, BringsBackTheUnmergedEditAndMergesIt) {
  TempDir dir("unmerged");
  SessionOptions o = fast_options(3, "ada");
  o.journal = dir.path();
  o.sync = Millis{2000};  // the first merge two seconds after the start: the edit stays unmerged
  std::uint64_t local_digest = 0;
  {
    auto s = Session::create(sphere(), o);
    Mesh local = stroked(sphere(), {0, 0, 1}, {0, 0.2f, 0});
    ASSERT_TRUE(s->submit(local, 2));
    ASSERT_TRUE(wait_until([&] { return s->stats().submits > 0; }));  // journaled before sent
    local_digest = mesh_digest(local);
  }
  Mesh local;
  auto r = Session::resume(dir.path(), local, o);
  EXPECT_EQ(r->version(), 0u);
  EXPECT_EQ(mesh_digest(r->base()), mesh_digest(sphere()));
  EXPECT_EQ(mesh_digest(local), local_digest);
  EXPECT_EQ(r->stats().strokes_submitted, 2u);
  // Sent again at once: merged by the resumed peer once its hold is over.
  ASSERT_TRUE(wait_until([&] { return r->update(local) > 0; }, Millis{8000}));
  EXPECT_EQ(mesh_digest(r->base()), local_digest);
  EXPECT_EQ(r->stats().strokes_acknowledged, 2u);
}

/// The time one compaction of `mesh` takes: its snapshot encoded and written synced.
Millis compaction_time(const Mesh& mesh, const std::string& dir) {
  const auto t0 = Clock::now();
  write_compaction_snapshot(dir, encode_snapshot(mesh, MergeFrame::fit(mesh.positions), {}), 1, 1);
  return std::chrono::duration_cast<Millis>(Clock::now() - t0);
}

// A compaction encodes the whole mesh and writes it synced: at millions of faces, seconds on
// a shared disk. On the network thread that silenced the journaling peer past the others'
// expiry, every bound's worth of versions (a merger journaling its session was replaced and
// the session went on without it). The expiry here is half of what one compaction of this
// mesh takes, timed here (sanitizers slow both alike, and under them a smaller mesh is
// enough): the compactions are written beside the network thread, nobody expires the
// merger, and its journal resumes the last version.
TEST(SessionJournal, CompactionsLongerThanTheExpiryLeaveThePeerAMember) {
  TempDir timing("timing"), dir("compacting");
  fs::create_directories(timing.path());
  // The smallest sphere whose compaction takes 400 ms (sanitizers slow it: a smaller one).
  Mesh mesh;
  Millis compaction{0};
  for (std::uint32_t faces = 250000; compaction < Millis{400} && faces <= 4000000; faces *= 2) {
    mesh = make_sphere(faces);
    compaction = compaction_time(mesh, timing.path());
  }
  std::printf("%zu faces, compaction %lld ms\n", mesh.triangles.size(),
              static_cast<long long>(compaction.count()));
  const Millis expired = std::max(Millis{150}, compaction / 2);
  auto options = [&](PeerId id) {
    SessionOptions o = fast_options(id);
    o.membership = {expired / 8, expired / 2, expired};
    return o;
  };
  SessionOptions journaled = options(1);
  journaled.journal = dir.path();
  journaled.journal_max_log_versions = 2;
  auto a = Session::create(mesh, journaled);
  auto b = Session::join(a->invite(), options(2), Millis{120000});
  ASSERT_TRUE(
      wait_until([&] { return a->peers().size() == 1 && b->peers().size() == 1; }, Millis{60000}));
  b->poll_events();
  Mesh local = mesh;
  // Versions until the first snapshot and three compactions are in place (each compaction
  // starts with the first version past the bound once the one before is done).
  for (int k = 0; a->stats().journal_snapshots < 4; ++k) {
    ASSERT_LT(k, 400) << a->stats().journal_snapshots << " snapshots";
    local = stroked(local, unit(Vec3f{0.01f * float(k), 1, 0.5f}), {0, 0, 0.05f});
    ASSERT_TRUE(a->submit(local, 1));
    ASSERT_TRUE(wait_until([&] { return a->update(local) > 0; }, Millis{60000}));
  }
  std::this_thread::sleep_for(2 * expired);
  ASSERT_GT(compaction, expired) << "a compaction was not longer than the expiry";
  for (const Event& e : b->poll_events())
    EXPECT_NE(e.kind, EventKind::peer_left) << "peer " << e.peer << " expired";
  EXPECT_EQ(b->stats().merger, 1u);
  const std::uint64_t version = a->version(), digest = mesh_digest(a->base());
  b.reset();
  a.reset();
  EXPECT_GE(load_journal(dir.path()).version, 4u);  // a compaction's snapshot, not the first
  Mesh resumed;
  auto r = Session::resume(dir.path(), resumed, options(1));
  EXPECT_EQ(r->version(), version);
  EXPECT_EQ(mesh_digest(r->base()), digest);
}

TEST(SessionResume, ADirectoryWithoutAJournalIsRefusedNamingTheFile) {
  TempDir dir("none");
  fs::create_directories(dir.path());
  Mesh local;
  try {
    Session::resume(dir.path(), local);
    FAIL() << "resumed from an empty directory";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find(dir.file("session")), std::string::npos) << e.what();
  }
}

}  // namespace
