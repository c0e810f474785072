#include "journal.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <utility>

#include "csculpt/error.h"
#include "csculpt/hash.h"

namespace csculpt::peer {
namespace {

namespace fs = std::filesystem;

// Every file starts with its magic, then records: u32 payload length, u32 type, the payload,
// u64 checksum (hash_bytes of the length, type and payload). Little-endian.
constexpr std::size_t kMagicBytes = 8;
constexpr char kSessionMagic[] = "CSJ1SESS";
constexpr char kSnapshotMagic[] = "CSJ1SNAP";
constexpr char kLogMagic[] = "CSJ1LOG_";
constexpr std::size_t kFrameBytes = 4 + 4 + 8;

enum RecordType : std::uint32_t {
  kMetaRecord = 1,
  kSnapshotRecord = 2,
  kLogHeadRecord = 3,  // the snapshot (version, chain) the log follows
  kVersionRecord = 4,
  kOwnRecord = 5,
  kMemberRecord = 6,
};

std::string errno_text() {
  return std::strerror(errno);
}

std::uint64_t checksum(const std::uint8_t* frame_head, std::span<const std::uint8_t> payload) {
  return hash_bytes(hash_bytes(hash_seed, frame_head, 8), payload.data(), payload.size());
}

template <class T>
void put(Bytes& out, T v) {
  const auto* p = reinterpret_cast<const std::uint8_t*>(&v);
  out.insert(out.end(), p, p + sizeof v);
}
void put_bytes(Bytes& out, std::span<const std::uint8_t> b) {
  out.insert(out.end(), b.begin(), b.end());
}

Bytes frame(std::uint32_t type, std::span<const std::uint8_t> payload) {
  Bytes out;
  out.reserve(kFrameBytes + payload.size());
  put(out, static_cast<std::uint32_t>(payload.size()));
  put(out, type);
  put_bytes(out, payload);
  put(out, checksum(out.data(), payload));
  return out;
}

/// Reads fields off a record's payload; running past its end throws InvalidInput.
class Reader {
 public:
  explicit Reader(std::span<const std::uint8_t> b) : b_(b) {}
  template <class T>
  T get() {
    T v;
    std::memcpy(&v, take(sizeof v).data(), sizeof v);
    return v;
  }
  std::span<const std::uint8_t> take(std::size_t n) {
    if (n > b_.size() - at_) throw InvalidInput("record shorter than its fields");
    const auto s = b_.subspan(at_, n);
    at_ += n;
    return s;
  }
  std::span<const std::uint8_t> rest() { return take(b_.size() - at_); }

 private:
  std::span<const std::uint8_t> b_;
  std::size_t at_ = 0;
};

std::string as_string(std::span<const std::uint8_t> s) {
  return {reinterpret_cast<const char*>(s.data()), s.size()};
}

Bytes meta_payload(const JournalMeta& m) {
  Bytes out;
  put(out, m.invite.session);
  put_bytes(out, m.invite.server_secret);
  put_bytes(out, m.invite.client_secret);
  put(out, m.self);
  put(out, static_cast<std::uint32_t>(m.name.size()));
  put_bytes(out, {reinterpret_cast<const std::uint8_t*>(m.name.data()), m.name.size()});
  put_bytes(out, {reinterpret_cast<const std::uint8_t*>(m.invite.endpoint.data()),
                  m.invite.endpoint.size()});
  return out;
}

JournalMeta meta_of(std::span<const std::uint8_t> payload) {
  Reader r(payload);
  JournalMeta m;
  m.invite.session = r.get<std::uint64_t>();
  std::memcpy(m.invite.server_secret.data(), r.take(32).data(), 32);
  std::memcpy(m.invite.client_secret.data(), r.take(32).data(), 32);
  m.self = r.get<std::uint64_t>();
  m.name = as_string(r.take(r.get<std::uint32_t>()));
  m.invite.endpoint = as_string(r.rest());
  return m;
}

Bytes own_payload(const OwnEdit& own) {
  Bytes out;
  put(out, own.base_version);
  put(out, own.strokes);
  put_bytes(out, own.diff);
  return out;
}

Bytes member_payload(PeerId peer, const std::string& endpoint) {
  Bytes out;
  put(out, peer);
  put_bytes(out, {reinterpret_cast<const std::uint8_t*>(endpoint.data()), endpoint.size()});
  return out;
}

Bytes head_payload(std::uint64_t version, std::uint64_t chain) {
  Bytes out;
  put(out, version);
  put(out, chain);
  return out;
}

VersionRecord version_of(std::span<const std::uint8_t> payload) {
  // FlatBuffers reads scalars in place: an aligned copy.
  std::vector<std::uint64_t> aligned((payload.size() + 7) / 8);
  std::memcpy(aligned.data(), payload.data(), payload.size());
  const auto* data = reinterpret_cast<const std::uint8_t*>(aligned.data());
  flatbuffers::Verifier verifier(data, payload.size());
  if (!fb::VerifyEnvelopeBuffer(verifier) || !fb::GetEnvelope(data)->body_as_Version() ||
      !fb::GetEnvelope(data)->body_as_Version()->diff())
    throw InvalidInput("version record is not a verified Version");
  return record_of(*fb::GetEnvelope(data)->body_as_Version());
}

Bytes read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError("journal: cannot read " + path + ": " + errno_text());
  return Bytes(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

/// One framed record at `at` of `file`, or why there is none (a torn or corrupt one).
struct Parsed {
  std::uint32_t type = 0;
  std::span<const std::uint8_t> payload;
  std::size_t next = 0;
  std::string error;
};

Parsed parse_record(std::span<const std::uint8_t> file, std::size_t at) {
  Parsed p;
  if (file.size() - at < kFrameBytes) {
    p.error = "torn record header at byte " + std::to_string(at);
    return p;
  }
  std::uint32_t length;
  std::memcpy(&length, file.data() + at, 4);
  std::memcpy(&p.type, file.data() + at + 4, 4);
  if (length > file.size() - at - kFrameBytes) {
    p.error = "torn record of " + std::to_string(length) + " bytes at byte " + std::to_string(at);
    return p;
  }
  p.payload = file.subspan(at + 8, length);
  std::uint64_t stored;
  std::memcpy(&stored, file.data() + at + 8 + length, 8);
  if (stored != checksum(file.data() + at, p.payload)) {
    p.error = "record at byte " + std::to_string(at) + " fails its checksum";
    return p;
  }
  p.next = at + kFrameBytes + length;
  return p;
}

/// The single record of a `session` or `snapshot` file, checked; throws naming the file.
Bytes single_record(const std::string& path, const char* magic, std::uint32_t type) {
  if (!fs::exists(path)) throw IoError("journal: " + path + " is missing");
  const Bytes file = read_file(path);
  if (file.size() < kMagicBytes || std::memcmp(file.data(), magic, kMagicBytes) != 0)
    throw InvalidInput("journal: " + path + " is not a cSculpt journal file");
  const Parsed p = parse_record(file, kMagicBytes);
  if (!p.error.empty() || p.type != type)
    throw InvalidInput("journal: " + path + " is corrupt (" +
                       (p.error.empty() ? "unexpected record type" : p.error) + ")");
  return Bytes(p.payload.begin(), p.payload.end());
}

void write_all(int fd, std::span<const std::uint8_t> b, const std::string& path) {
  std::size_t done = 0;
  while (done < b.size()) {
    const ssize_t n = ::write(fd, b.data() + done, b.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw IoError("journal: cannot write " + path + ": " + errno_text());
    done += static_cast<std::size_t>(n);
  }
}

void sync_fd(int fd, const std::string& path) {
  if (::fdatasync(fd) != 0) throw IoError("journal: cannot sync " + path + ": " + errno_text());
}

/// Makes renames and new files in `dir` durable.
void sync_dir(const std::string& dir) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY);
  if (fd < 0) throw IoError("journal: cannot open " + dir + ": " + errno_text());
  const int rc = ::fsync(fd);
  ::close(fd);
  if (rc != 0) throw IoError("journal: cannot sync " + dir + ": " + errno_text());
}

/// Writes `path` whole, synced (not yet renamed into place).
void write_synced(const std::string& path, std::span<const std::uint8_t> bytes) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (fd < 0) throw IoError("journal: cannot create " + path + ": " + errno_text());
  try {
    write_all(fd, bytes, path);
    sync_fd(fd, path);
  } catch (...) {
    ::close(fd);
    throw;
  }
  ::close(fd);
}

void rename_file(const std::string& from, const std::string& to) {
  if (::rename(from.c_str(), to.c_str()) != 0)
    throw IoError("journal: cannot rename " + from + ": " + errno_text());
}

Bytes with_magic(const char* magic, std::initializer_list<Bytes> records) {
  std::size_t size = kMagicBytes;
  for (const Bytes& r : records) size += r.size();
  // Sized once and copied into: vector::insert here set off GCC 12's -O3 bounds warnings (a
  // false positive of the plain Release build).
  Bytes out(size);
  std::memcpy(out.data(), magic, kMagicBytes);
  std::size_t at = kMagicBytes;
  for (const Bytes& r : records) {
    if (!r.empty()) std::memcpy(out.data() + at, r.data(), r.size());
    at += r.size();
  }
  return out;
}

/// Writes a snapshot file at `path` (synced, not yet renamed into place).
void write_snapshot_file(const std::string& path, std::span<const std::uint8_t> snapshot,
                         std::uint64_t version, std::uint64_t chain) {
  Bytes payload = head_payload(version, chain);
  put_bytes(payload, snapshot);
  write_synced(path, with_magic(kSnapshotMagic, {frame(kSnapshotRecord, payload)}));
}

constexpr char kCompactionSnapshot[] = "snapshot.next";

/// Whether `file` is a log whose head names the snapshot at `version` with `chain`.
bool log_follows(const Bytes& file, std::uint64_t version, std::uint64_t chain) {
  if (file.size() < kMagicBytes || std::memcmp(file.data(), kLogMagic, kMagicBytes) != 0)
    return false;
  const Parsed p = parse_record(file, kMagicBytes);
  if (!p.error.empty() || p.type != kLogHeadRecord) return false;
  return p.payload.size() == 16 &&
         Bytes(p.payload.begin(), p.payload.end()) == head_payload(version, chain);
}

/// Takes one log record into `s`; throws InvalidInput for one that cannot be used.
void take_record(const Parsed& p, JournalState& s) {
  switch (p.type) {
    case kVersionRecord: {
      VersionRecord r = version_of(p.payload);
      const std::uint64_t held = s.versions.empty() ? s.version : s.versions.back().version;
      const std::uint64_t chain = s.versions.empty() ? s.chain : s.versions.back().chain;
      if (r.version != held + 1 || r.parent_chain != chain)
        throw InvalidInput("version " + std::to_string(r.version) + " does not follow " +
                           std::to_string(held));
      s.versions.push_back(std::move(r));
      return;
    }
    case kOwnRecord: {
      Reader r(p.payload);
      OwnEdit own;
      own.base_version = r.get<std::uint64_t>();
      own.strokes = r.get<std::uint32_t>();
      const auto diff = r.rest();
      own.diff.assign(diff.begin(), diff.end());
      s.own = std::move(own);
      return;
    }
    case kMemberRecord: {
      Reader r(p.payload);
      const PeerId peer = r.get<std::uint64_t>();
      s.members[peer] = as_string(r.rest());
      return;
    }
    default:
      throw InvalidInput("record of unknown type " + std::to_string(p.type));
  }
}

/// Reads the log's records after its head into `s`, stopping at the first bad one.
void read_log(const Bytes& file, const std::string& path, JournalState& s) {
  std::size_t at = parse_record(file, kMagicBytes).next;
  while (at < file.size()) {
    const Parsed p = parse_record(file, at);
    std::string error = p.error;
    if (error.empty()) try {
        take_record(p, s);
      } catch (const InvalidInput& e) {
        error = std::string("record at byte ") + std::to_string(at) + ": " + e.what();
      }
    if (!error.empty()) {
      s.dropped_bytes = file.size() - at;
      s.dropped_reason = path + ": " + error;
      break;
    }
    at = p.next;
  }
  s.log_bytes = at;
}

std::string file_in(const std::string& dir, const char* name) {
  return (fs::path(dir) / name).string();
}

}  // namespace

JournalState load_journal(const std::string& dir) {
  if (!fs::is_directory(dir)) throw IoError("journal: " + dir + " is not a directory");
  JournalState s;
  const std::string session_path = file_in(dir, "session");
  const std::string snapshot_path = file_in(dir, "snapshot");
  const Bytes meta = single_record(session_path, kSessionMagic, kMetaRecord);
  try {
    s.meta = meta_of(meta);
  } catch (const InvalidInput& e) {
    throw InvalidInput("journal: " + session_path + " is corrupt (" + e.what() + ")");
  }
  if (!fs::exists(snapshot_path))
    throw IoError("journal: " + snapshot_path +
                  " is missing (the peer never held the session's mesh)");
  const Bytes snap = single_record(snapshot_path, kSnapshotMagic, kSnapshotRecord);
  if (snap.size() < 16) throw InvalidInput("journal: " + snapshot_path + " is corrupt (short)");
  Reader r(snap);
  s.version = r.get<std::uint64_t>();
  s.chain = r.get<std::uint64_t>();
  const auto mesh = r.rest();
  s.snapshot.assign(mesh.begin(), mesh.end());
  // A compaction stopped between its two renames leaves the new log as log.tmp.
  for (const char* name : {"log", "log.tmp"}) {
    const std::string path = file_in(dir, name);
    if (!fs::exists(path)) continue;
    const Bytes file = read_file(path);
    if (!log_follows(file, s.version, s.chain)) continue;
    if (std::string(name) == "log.tmp") rename_file(path, file_in(dir, "log"));
    read_log(file, file_in(dir, "log"), s);
    return s;
  }
  throw InvalidInput("journal: " + file_in(dir, "log") + " is missing or does not follow " +
                     snapshot_path);
}

Journal::Journal(std::string dir, JournalLimits limits) : dir_(std::move(dir)), limits_(limits) {}

Journal::~Journal() {
  if (log_fd_ >= 0) ::close(log_fd_);
}

Journal::Journal(Journal&& o) noexcept
    : dir_(std::move(o.dir_)),
      limits_(o.limits_),
      log_fd_(std::exchange(o.log_fd_, -1)),
      has_snapshot_(o.has_snapshot_),
      log_bytes_(o.log_bytes_),
      log_versions_(o.log_versions_),
      own_(std::move(o.own_)),
      members_(std::move(o.members_)),
      compaction_(std::move(o.compaction_)) {}

Journal& Journal::operator=(Journal&& o) noexcept {
  if (this != &o) {
    if (log_fd_ >= 0) ::close(log_fd_);
    dir_ = std::move(o.dir_);
    limits_ = o.limits_;
    log_fd_ = std::exchange(o.log_fd_, -1);
    has_snapshot_ = o.has_snapshot_;
    log_bytes_ = o.log_bytes_;
    log_versions_ = o.log_versions_;
    own_ = std::move(o.own_);
    members_ = std::move(o.members_);
    compaction_ = std::move(o.compaction_);
  }
  return *this;
}

Journal Journal::create(const std::string& dir, const JournalMeta& meta, JournalLimits limits) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw IoError("journal: cannot create " + dir + ": " + ec.message());
  // A journal without a snapshot (a join that never got the mesh) holds nothing to resume.
  if (fs::exists(file_in(dir, "snapshot")))
    throw InvalidInput("journal: " + file_in(dir, "snapshot") +
                       " exists: this directory holds a journal already (resume it)");
  Journal j(dir, limits);
  const std::string path = file_in(dir, "session");
  write_synced(path + ".tmp", with_magic(kSessionMagic, {frame(kMetaRecord, meta_payload(meta))}));
  rename_file(path + ".tmp", path);
  sync_dir(dir);
  return j;
}

Journal Journal::reopen(const std::string& dir, const JournalState& state, const JournalMeta& meta,
                        JournalLimits limits) {
  Journal j(dir, limits);
  const std::string path = file_in(dir, "session");
  write_synced(path + ".tmp", with_magic(kSessionMagic, {frame(kMetaRecord, meta_payload(meta))}));
  rename_file(path + ".tmp", path);
  j.has_snapshot_ = true;
  j.own_ = state.own;
  j.members_ = state.members;
  j.log_versions_ = state.versions.size();
  j.open_log(state.log_bytes);
  sync_dir(dir);
  return j;
}

void Journal::open_log(std::uint64_t truncate_at) {
  if (log_fd_ >= 0) ::close(log_fd_);
  const std::string path = file_in(dir_, "log");
  log_fd_ = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
  if (log_fd_ < 0) throw IoError("journal: cannot open " + path + ": " + errno_text());
  // A torn tail goes: the next record starts right after the last valid one.
  if (::ftruncate(log_fd_, static_cast<off_t>(truncate_at)) != 0 ||
      ::lseek(log_fd_, static_cast<off_t>(truncate_at), SEEK_SET) < 0)
    throw IoError("journal: cannot cut " + path + ": " + errno_text());
  sync_fd(log_fd_, path);
  log_bytes_ = truncate_at;
}

void Journal::reset(std::span<const std::uint8_t> snapshot, std::uint64_t version,
                    std::uint64_t chain) {
  compaction_.reset();  // its snapshot would be older than this one, or of another branch
  const std::string path = file_in(dir_, "snapshot") + ".tmp";
  write_snapshot_file(path, snapshot, version, chain);
  install(path, version, chain, {}, version);
}

void write_compaction_snapshot(const std::string& dir, std::span<const std::uint8_t> snapshot,
                               std::uint64_t version, std::uint64_t chain) {
  write_snapshot_file(file_in(dir, kCompactionSnapshot), snapshot, version, chain);
}

void discard_compaction_snapshot(const std::string& dir) {
  std::error_code ec;
  fs::remove(file_in(dir, kCompactionSnapshot), ec);  // a leftover is ignored by load anyway
}

void Journal::adopt_snapshot(std::uint64_t version, std::uint64_t chain) {
  if (compaction_) throw std::logic_error("journal: adopt_snapshot during a compaction");
  install(file_in(dir_, kCompactionSnapshot), version, chain, {}, version);
}

void Journal::begin_compaction(std::uint64_t version, std::uint64_t chain) {
  compaction_ = Compaction{version, chain, {}, version};
}

std::optional<std::uint64_t> Journal::compacting() const {
  return compaction_ ? std::optional(compaction_->version) : std::nullopt;
}

void Journal::finish_compaction() {
  if (!compaction_) return;
  const Compaction c = std::move(*compaction_);
  compaction_.reset();
  install(file_in(dir_, kCompactionSnapshot), c.version, c.chain, c.versions, c.last_version);
}

/// Renames the synced snapshot at `snapshot_path` into place with a new log after it: its head,
/// `versions` (framed records after the snapshot, up to `last_version`), the own edit if based
/// on one of those versions (an older one is stale: the host rebases and submits it again;
/// another branch's is not ours to keep) and the members.
void Journal::install(const std::string& snapshot_path, std::uint64_t version, std::uint64_t chain,
                      std::span<const Bytes> versions, std::uint64_t last_version) {
  const std::string snap_path = file_in(dir_, "snapshot"), log_path = file_in(dir_, "log");
  Bytes log = with_magic(kLogMagic, {frame(kLogHeadRecord, head_payload(version, chain))});
  for (const Bytes& r : versions) put_bytes(log, r);
  if (own_ && (own_->base_version < version || own_->base_version > last_version)) own_.reset();
  if (own_) put_bytes(log, frame(kOwnRecord, own_payload(*own_)));
  for (const auto& [peer, endpoint] : members_)
    put_bytes(log, frame(kMemberRecord, member_payload(peer, endpoint)));
  write_synced(log_path + ".tmp", log);
  // The snapshot first, made durable before the log follows it: until the log is renamed
  // too, load_journal takes log.tmp. (Renamed together, a filesystem that kept the second
  // rename and lost the first would leave the old snapshot with a log that does not follow it.)
  rename_file(snapshot_path, snap_path);
  sync_dir(dir_);
  rename_file(log_path + ".tmp", log_path);
  sync_dir(dir_);
  has_snapshot_ = true;
  log_versions_ = versions.size();
  open_log(log.size());
}

void Journal::append(std::uint32_t type, std::span<const std::uint8_t> payload) {
  if (log_fd_ < 0) return;  // no snapshot yet: nothing to append to
  const Bytes record = frame(type, payload);
  const std::string path = file_in(dir_, "log");
  write_all(log_fd_, record, path);
  sync_fd(log_fd_, path);
  log_bytes_ += record.size();
  if (compaction_ && type == kVersionRecord) compaction_->versions.push_back(record);
}

void Journal::append_version(const VersionRecord& r) {
  append(kVersionRecord, version_message({}, r, false));
  ++log_versions_;
  if (compaction_) compaction_->last_version = r.version;
}

void Journal::append_own(const OwnEdit& own) {
  own_ = own;
  append(kOwnRecord, own_payload(own));
}

void Journal::append_member(PeerId peer, const std::string& endpoint) {
  auto [it, added] = members_.try_emplace(peer, endpoint);
  if (!added && it->second == endpoint) return;
  it->second = endpoint;
  append(kMemberRecord, member_payload(peer, endpoint));
}

bool Journal::wants_compaction() const {
  return !compaction_ &&
         (log_bytes_ > limits_.max_log_bytes || log_versions_ >= limits_.max_log_versions);
}

}  // namespace csculpt::peer
