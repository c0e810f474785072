#include "peer_command.h"

#include <poll.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <optional>
#include <string>
#include <string_view>
#include <thread>

#include "artist.h"
#include "csculpt/error.h"
#include "csculpt/io.h"
#include "csculpt/peer/session.h"
#include "csculpt/testkit/generate.h"
#include "markers.h"

namespace csculpt::cli {
namespace {

// Set by SIGINT/SIGTERM: the peer leaves cleanly and prints its summary.
volatile std::sig_atomic_t g_signalled = 0;
void on_signal(int) {
  g_signalled = 1;
}

std::string json_string(std::string_view s) {
  std::string out = "\"";
  for (const char c : s) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", static_cast<unsigned>(c));
          out += buf;
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
}

std::string json_list(const std::vector<std::uint32_t>& values) {
  std::string out = "[";
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (i) out += ",";
    out += std::to_string(values[i]);
  }
  return out + "]";
}

std::string hex64(std::uint64_t v) {
  char buf[24];
  std::snprintf(buf, sizeof buf, "\"%016llx\"", static_cast<unsigned long long>(v));
  return buf;
}

/// Wall-clock milliseconds: a driving script compares them with its own clock (time.time()),
/// e.g. to measure how long after a SIGKILL a survivor saw the new merger.
std::string now_ms() {
  const auto t = std::chrono::system_clock::now().time_since_epoch();
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3f", std::chrono::duration<double, std::milli>(t).count());
  return buf;
}

/// One JSON object per line, flushed at once (the reader is usually a pipe).
class Line {
 public:
  explicit Line(std::string_view event) : text_("{\"event\":" + json_string(event)) {}
  Line& num(std::string_view key, std::uint64_t v) { return raw(key, std::to_string(v)); }
  Line& real(std::string_view key, double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.3f", v);
    return raw(key, buf);
  }
  Line& str(std::string_view key, std::string_view v) { return raw(key, json_string(v)); }
  Line& raw(std::string_view key, std::string_view v) {
    text_ += ",";
    text_ += json_string(key);
    text_ += ":";
    text_ += v;
    return *this;
  }
  void emit() {
    text_ += "}\n";
    std::fputs(text_.c_str(), stdout);
    std::fflush(stdout);
  }

 private:
  std::string text_;
};

/// Reads stdin without blocking: a line `quit` or end of file asks the peer to finish, a line
/// `stop-editing` to stop making strokes and keep syncing.
class StdinWatch {
 public:
  bool editing_stopped() const { return stop_editing_; }
  bool quit_requested() {
    if (eof_) return true;
    pollfd p{0, POLLIN, 0};
    while (::poll(&p, 1, 0) > 0 && (p.revents & (POLLIN | POLLHUP | POLLERR))) {
      char buf[512];
      const ssize_t n = ::read(0, buf, sizeof buf);
      if (n <= 0) {
        eof_ = true;
        return true;
      }
      pending_.append(buf, static_cast<std::size_t>(n));
      for (std::size_t nl; (nl = pending_.find('\n')) != std::string::npos;) {
        std::string line = pending_.substr(0, nl);
        pending_.erase(0, nl + 1);
        while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
        if (line == "quit") quit_ = true;
        if (line == "stop-editing") stop_editing_ = true;
      }
      if (quit_) return true;
    }
    return quit_;
  }

 private:
  std::string pending_;
  bool eof_ = false, quit_ = false, stop_editing_ = false;
};

std::string_view kind_name(peer::EventKind k) {
  switch (k) {
    case peer::EventKind::joined:
      return "joined";
    case peer::EventKind::version:
      return "version";
    case peer::EventKind::peer_joined:
      return "peer_joined";
    case peer::EventKind::peer_evasive:
      return "peer_evasive";
    case peer::EventKind::peer_left:
      return "peer_left";
    case peer::EventKind::merger_changed:
      return "merger_changed";
    case peer::EventKind::dropped:
      return "dropped";
    case peer::EventKind::error:
      return "error";
    case peer::EventKind::peer_live:
      return "peer_live";
  }
  return "unknown";
}

/// What a state line reports; a line is printed whenever any of it changes.
struct State {
  std::uint64_t version = 0, digest = 0, base_digest = 0, strokes = 0, unacknowledged = 0,
                acknowledged = 0, dropped = 0, stale = 0, auth_rejected = 0, abandoned = 0,
                merger = 0, epoch = 0, members = 0;
  /// With markers: those seen acknowledged, and how many of them the base holds now (fewer
  /// while a lost branch's are carried, until merged again).
  std::uint64_t markers_acknowledged = 0, markers_held = 0;
  bool editing = false;
  friend bool operator==(const State&, const State&) = default;
};

peer::SessionOptions session_options(const PeerCommandOptions& o) {
  peer::SessionOptions so;
  so.id = o.id;
  so.bind = o.bind;
  so.sync = peer::Millis{o.sync_ms};
  so.membership = {peer::Millis{o.heartbeat_ms}, peer::Millis{o.evasive_ms},
                   peer::Millis{o.expired_ms}};
  so.name = o.name.empty() ? (o.id ? "peer-" + std::to_string(o.id) : "peer") : o.name;
  if (!o.resume.empty() && o.name.empty()) so.name.clear();  // the journal's
  so.journal = o.journal;
  so.journal_max_log_versions = o.journal_max_log_versions;
  return so;
}

/// Creates the session (on a built-in sphere), joins the one of the invite or resumes the one
/// of the journal (`resumed` gets the local mesh with the unmerged edits), and prints the invite
/// line.
std::unique_ptr<peer::Session> open_session(const PeerCommandOptions& o,
                                            const peer::SessionOptions& so, Mesh& resumed) {
  std::unique_ptr<peer::Session> session;
  if (!o.resume.empty()) {
    session = peer::Session::resume(o.resume, resumed, so);
  } else if (o.join.empty()) {
    Mesh sphere = make_sphere(o.faces, true);
    if (o.markers) add_marker_channel(sphere);
    session = peer::Session::create(sphere, so);
  } else {
    session = peer::Session::join(o.join, so, peer::Millis{o.join_timeout_ms});
  }
  Line("invite")
      .str("invite", session->invite())
      .num("id", session->id())
      .str("endpoint", session->endpoint())
      .num("version", session->version())
      .num("vertices", session->base().vertex_count())
      .raw("base_digest", hex64(peer::mesh_digest(session->base())))
      .raw("resumed", o.resume.empty() ? "false" : "true")
      .raw("t", now_ms())
      .emit();
  return session;
}

/// The digests of the artist's mesh and the session's base, each hashed again only when what
/// it covers moved (the artist's generation, the version), and at least every kRefresh in case
/// something changed them otherwise: hashing both meshes on every 3 ms turn took a quarter of
/// the peer processes' CPU, and hashing both on every dab half of it, on the cores the hosts
/// they test share.
class Digests {
 public:
  void refresh(const peer::Session& session, SimulatedArtist& artist) {
    const auto now = peer::Clock::now();
    const bool stale = now - at_ >= kRefresh;
    if (stale) at_ = now;
    if (stale || artist.generation() != generation_) {
      generation_ = artist.generation();
      local_ = peer::mesh_digest(artist.local());
    }
    if (stale || session.version() != version_) {
      version_ = session.version();
      base_ = peer::mesh_digest(session.base());
    }
  }
  std::uint64_t local() const { return local_; }
  std::uint64_t base() const { return base_; }

 private:
  static constexpr std::chrono::milliseconds kRefresh{250};
  std::uint64_t generation_ = ~std::uint64_t{0}, version_ = ~std::uint64_t{0};
  peer::Clock::time_point at_{};
  std::uint64_t local_ = 0, base_ = 0;
};

void print_event(const peer::Event& e, peer::PeerId self, std::uint64_t local_digest) {
  Line line(kind_name(e.kind));
  line.num("id", self).raw("t", now_ms());
  switch (e.kind) {
    case peer::EventKind::version:
      line.num("version", e.version)
          .num("merger", e.peer)
          .num("epoch", e.epoch)
          .raw("digest", hex64(local_digest));
      break;
    case peer::EventKind::merger_changed:
      line.num("merger", e.peer).num("epoch", e.epoch).num("version", e.version);
      break;
    case peer::EventKind::dropped:
    case peer::EventKind::error:
      line.str("reason", e.message).num("version", e.version);
      break;
    default:
      line.num("peer", e.peer).num("version", e.version).str("detail", e.message);
  }
  line.emit();
}

State read_state(const peer::Session& session, SimulatedArtist& artist, bool editing,
                 const MarkerPainter* markers, Digests& digests) {
  const peer::SessionStats st = session.stats();
  State s;
  s.version = session.version();
  digests.refresh(session, artist);
  s.digest = digests.local();
  s.base_digest = digests.base();
  s.strokes = artist.strokes();
  s.unacknowledged = artist.unacknowledged();
  s.acknowledged = st.strokes_acknowledged;
  s.dropped = st.messages_dropped;
  s.stale = st.stale_ignored;
  s.auth_rejected = st.auth_rejected;
  s.abandoned = st.handshakes_abandoned;
  s.merger = st.merger;
  s.epoch = st.epoch;
  s.members = st.members;
  s.editing = editing;
  if (markers) {
    s.markers_acknowledged = markers->acknowledged();
    s.markers_held = markers->held(session.base());
  }
  return s;
}

void print_state(const State& s, peer::PeerId self, bool markers) {
  Line line("state");
  if (markers)
    line.num("markers_acknowledged", s.markers_acknowledged).num("markers_held", s.markers_held);
  line.num("id", self)
      .raw("t", now_ms())
      .num("version", s.version)
      .raw("digest", hex64(s.digest))
      .raw("base_digest", hex64(s.base_digest))
      .num("strokes", s.strokes)
      .num("unacknowledged", s.unacknowledged)
      .num("acknowledged", s.acknowledged)
      .num("messages_dropped", s.dropped)
      .num("stale_ignored", s.stale)
      .num("auth_rejected", s.auth_rejected)
      .num("handshakes_abandoned", s.abandoned)
      .num("merger", s.merger)
      .num("epoch", s.epoch)
      .num("members", s.members)
      .raw("editing", s.editing ? "true" : "false")
      .emit();
}

/// The artist edits until --seconds, syncing goes on until --linger more (or a signal, or
/// `quit` on stdin); every event and every change of state is printed.
/// A marker with each new stroke; the markers an agreed version shows for the first time.
void mark(peer::Session& session, SimulatedArtist& artist, MarkerPainter& markers) {
  while (markers.made() < artist.strokes()) {
    const std::int64_t v = markers.paint(artist.local());
    if (v < 0) break;
    artist.changed(static_cast<std::uint32_t>(v));
    Line("marker").num("id", session.id()).num("vertex", static_cast<std::uint64_t>(v)).emit();
  }
  const std::vector<std::uint32_t> seen = markers.newly_acknowledged(session.base());
  if (!seen.empty())
    Line("marker_acked").num("id", session.id()).raw("vertices", json_list(seen)).emit();
}

void edit_and_sync(const PeerCommandOptions& o, peer::Session& session, SimulatedArtist& artist,
                   MarkerPainter* markers, peer::Clock::time_point start) {
  StdinWatch input;
  const auto edit_end = start + std::chrono::duration_cast<peer::Clock::duration>(
                                    std::chrono::duration<double>(o.seconds));
  const auto linger_end = edit_end + std::chrono::duration_cast<peer::Clock::duration>(
                                         std::chrono::duration<double>(o.linger));
  const peer::PeerId self = session.id();
  State last;
  Digests digests;
  bool first_state = true;
  while (true) {
    const auto now = peer::Clock::now();
    const bool quit = g_signalled || (!o.ignore_stdin && input.quit_requested());
    const bool editing = !quit && !input.editing_stopped() && now < edit_end;
    artist.step(now, editing);
    if (markers) mark(session, artist, *markers);
    for (const peer::Event& e : session.poll_events()) {
      digests.refresh(session, artist);
      print_event(e, self, digests.local());
    }
    const State s = read_state(session, artist, editing, markers, digests);
    if (first_state || !(s == last)) {
      first_state = false;
      last = s;
      print_state(s, self, markers != nullptr);
    }
    if (quit || now >= linger_end) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(3));
  }
}

/// The final mesh with an attribution channel.
void write_final_mesh(const peer::Session& session, const Mesh& local, const std::string& path) {
  Mesh out = local;
  Channel colours;
  colours.desc = ChannelDesc{"attribution", 3, Linearisation::identity, 0.f, 1.f};
  colours.values = peer::attribution_colours(session.attribution(), local.vertex_count());
  out.channels.push_back(std::move(colours));
  write_mesh(out, path);
}

/// `lost`: the artist's strokes not seen inside a merged version. With markers, also what the
/// agreed mesh holds: our acknowledged markers it lacks, and everyone's it has.
void print_summary(const peer::Session& session, const Mesh& local, std::uint32_t strokes,
                   std::uint64_t lost, const peer::SessionStats& st, double seconds,
                   const MarkerPainter* markers) {
  Line line("summary");
  if (markers)
    line.num("markers_made", markers->made())
        .num("markers_acknowledged", markers->acknowledged())
        .num("markers_lost", markers->lost(session.base()).size())
        .raw("marked", json_list(MarkerPainter::present(session.base())));
  line.num("id", session.id())
      .raw("t", now_ms())
      .num("version", session.version())
      .raw("digest", hex64(peer::mesh_digest(local)))
      .raw("base_digest", hex64(peer::mesh_digest(session.base())))
      .num("strokes", strokes)
      .num("strokes_submitted", st.strokes_submitted)
      .num("acknowledged", st.strokes_acknowledged)
      .num("lost_edits", lost)
      .num("submits", st.submits)
      .num("submit_bytes", st.submit_bytes)
      .num("submits_resent", st.submits_resent)
      .num("versions_applied", st.versions_applied)
      .num("rebases", st.rebases)
      .num("branch_rebases", st.branch_rebases)
      .num("branch_versions_dropped", st.branch_versions_dropped)
      .num("merges", st.merges)
      .num("merged_strokes", st.merged_strokes)
      .num("conflicting_strokes", st.conflicting_strokes)
      .num("folds_introduced", st.folds_introduced)
      .real("merge_ms_max", st.merge_ms_max)
      .real("merge_ms_mean", st.merges ? st.merge_ms_sum / double(st.merges) : 0.0)
      .num("version_bytes_sent", st.version_bytes_sent)
      .num("messages_received", st.messages_received)
      .num("bytes_received", st.bytes_received)
      .num("messages_dropped", st.messages_dropped)
      .num("stale_ignored", st.stale_ignored)
      .num("auth_rejected", st.auth_rejected)
      .num("handshakes_abandoned", st.handshakes_abandoned)
      .num("snapshots_sent", st.snapshots_sent)
      .num("fetches", st.fetches)
      .num("journal_writes", st.journal_writes)
      .num("journal_snapshots", st.journal_snapshots)
      .real("journal_ms_mean",
            st.journal_writes ? st.journal_ms_sum / double(st.journal_writes) : 0.0)
      .real("journal_ms_max", st.journal_ms_max)
      .num("epoch", st.epoch)
      .num("merger", st.merger)
      .num("members", st.members)
      .real("seconds", seconds)
      .emit();
}

}  // namespace

CLI::App* add_peer_command(CLI::App& app, PeerCommandOptions& o) {
  CLI::App* p = app.add_subcommand(
      "peer",
      "one simulated artist in a serverless session, as its own process (JSON lines on stdout: "
      "invite, events, state changes, summary)");
  p->add_option("--join", o.join, "invite of the session to join (else create one)")
      ->check([](const std::string& invite) {
        // An empty invite (an unset shell variable) used to create a new session silently.
        return invite.empty() ? std::string("--join needs an invite (csculpt1:...@tcp://...)")
                              : std::string();
      });
  p->add_option("--faces", o.faces, "faces of the built-in sphere of a new session")
      ->capture_default_str()
      ->check(CLI::Range(20u, 50000000u));
  p->add_option("--id", o.id, "peer id, > 0 (the live peer with the lowest id merges); 0: random")
      ->capture_default_str();
  p->add_option("--name", o.name, "name shown to the others (default peer-<id>)");
  p->add_option("--bind", o.bind, "ZeroMQ endpoint to listen on (port * picks a free one)")
      ->capture_default_str();
  p->add_option("--sync-ms", o.sync_ms, "merge and submit interval")
      ->capture_default_str()
      ->check(CLI::Range(1u, 3600000u));
  p->add_option("--heartbeat-ms", o.heartbeat_ms, "heartbeat interval")
      ->capture_default_str()
      ->check(CLI::Range(1u, 3600000u));
  p->add_option("--evasive-ms", o.evasive_ms, "silence after which a peer is reported evasive")
      ->capture_default_str()
      ->check(CLI::Range(1u, 3600000u));
  p->add_option("--expired-ms", o.expired_ms,
                "silence after which a peer is gone (and a new merger elected)")
      ->capture_default_str()
      ->check(CLI::Range(1u, 3600000u));
  p->add_option("--join-timeout-ms", o.join_timeout_ms, "how long to wait for the snapshot")
      ->capture_default_str()
      ->check(CLI::Range(1u, 3600000u));
  p->add_option("--seconds", o.seconds, "how long to make strokes")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1e6));
  p->add_option("--strokes-per-second", o.strokes_per_second, "stroke rate while editing")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1000.0));
  p->add_option("--seed", o.seed, "stroke script seed")->capture_default_str();
  p->add_option("--linger", o.linger,
                "seconds to keep syncing after editing stops; a line 'quit' or end of file on "
                "stdin ends the run earlier, a line 'stop-editing' stops the strokes")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1e6));
  p->add_flag("--ignore-stdin", o.ignore_stdin,
              "do not read stdin (run for --seconds + --linger regardless)");
  p->add_flag("--markers", o.markers,
              "with each stroke, a marker (one vertex of a 'marker' channel set to 1) whose "
              "presence the summary checks in the agreed mesh; the creator adds the channel");
  p->add_option("--marker-slot", o.marker_slot,
                "which markable vertices are this peer's (0-15; default: its id mod 16)")
      ->check(CLI::Range(0, 15));
  p->add_option("--marker-first", o.marker_first,
                "index of the first marker (a restarted peer makes new markers from here)");
  p->add_option("--marker-limit", o.marker_limit, "markers to make at most");
  p->add_option("--out", o.out, "final mesh to write (PLY/OBJ; PLY keeps an attribution channel)");
  CLI::Option* journal = p->add_option(
      "--journal", o.journal,
      "directory to journal the session to (agreed versions and unmerged edits, synced; "
      "docs/journal.md)");
  p->add_option("--resume", o.resume,
                "restart this peer's session from its journal directory (same session, keys "
                "and id; a new invite line), after a crash or kill")
      ->excludes(journal)
      ->excludes("--join");
  p->add_option("--journal-max-versions", o.journal_max_log_versions,
                "versions in the journal's log before it is compacted into a snapshot")
      ->capture_default_str()
      ->check(CLI::Range(std::uint64_t{1}, std::uint64_t{1} << 40));
  return p;
}

int run_peer(const PeerCommandOptions& o) {
  try {
    if (o.evasive_ms >= o.expired_ms) throw InvalidInput("--evasive-ms must be below --expired-ms");
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    std::signal(SIGPIPE, SIG_IGN);  // the driver may stop reading: keep going, leave cleanly

    const peer::SessionOptions so = session_options(o);
    Mesh resumed;
    std::unique_ptr<peer::Session> session = open_session(o, so, resumed);
    ArtistOptions ao;
    ao.seed = o.seed;
    ao.strokes_per_second = o.strokes_per_second;
    ao.submit_every = so.sync;
    SimulatedArtist artist(*session, ao);
    if (!o.resume.empty()) artist.local() = std::move(resumed);  // the unmerged edits are back
    std::optional<MarkerPainter> markers;
    if (o.markers)
      markers.emplace(static_cast<std::uint32_t>(o.marker_slot >= 0 ? std::uint64_t(o.marker_slot)
                                                                    : session->id() % kMarkerSlots),
                      o.marker_first, o.marker_limit, session->base());
    const auto start = peer::Clock::now();
    edit_and_sync(o, *session, artist, markers ? &*markers : nullptr, start);

    // The summary describes the state at the end of editing and syncing; leaving then tells
    // the others at once rather than letting them wait for the expiry threshold.
    const peer::SessionStats st = session->stats();
    const Mesh& local = artist.local();
    const std::uint64_t lost = artist.unacknowledged();
    if (!o.out.empty()) write_final_mesh(*session, local, o.out);
    const double seconds = std::chrono::duration<double>(peer::Clock::now() - start).count();
    print_summary(*session, local, artist.strokes(), lost, st, seconds,
                  markers ? &*markers : nullptr);
    session->leave();
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "csculpt peer: error: %s\n", e.what());
    return 1;
  }
}

}  // namespace csculpt::cli
