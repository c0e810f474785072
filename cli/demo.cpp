// `csculpt demo`: N simulated artists in one serverless session on this machine. Every artist
// runs on its own host thread over its own peer::Session (which has its own network thread and
// sockets), exactly as separate programs would; only the summary is gathered in-process.
#include "demo.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <exception>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "artist.h"
#include "csculpt/folds.h"
#include "csculpt/io.h"
#include "csculpt/peer/session.h"
#include "csculpt/testkit/generate.h"

namespace csculpt::cli {
namespace {

using peer::Clock;
using peer::Millis;

double seconds_between(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

/// What an artist thread publishes after each turn, so the main thread never touches a
/// session it does not own (Session's host side is single-threaded).
struct Published {
  peer::SessionStats stats;
  std::uint64_t version = 0;
  std::uint32_t strokes = 0;
  std::uint64_t unacknowledged = 0;
  std::uint64_t local_digest = 0, base_digest = 0;
  bool digests = false;  ///< computed since editing stopped
  bool ready = false;
  std::string error;
};

struct Peer {
  std::unique_ptr<peer::Session> session;
  std::unique_ptr<SimulatedArtist> artist;
  std::thread thread;
  mutable std::mutex mutex;
  Published published;

  Published snapshot() const {
    std::lock_guard lock(mutex);
    return published;
  }
};

enum class Phase : int { setup, editing, syncing, stop };

std::string peer_name(std::uint32_t k) {
  return k < 26 ? std::string(1, static_cast<char>('A' + k)) : "P" + std::to_string(k + 1);
}

/// Artist k's stroke seed: a --replay run plays exactly the scripts a session would.
std::uint64_t artist_seed(const DemoOptions& o, std::uint32_t k) {
  return o.seed * 7919 + k;
}

/// Peer sessions the demo runs: one per artist, or one for all of them with --replay.
std::uint32_t session_count(const DemoOptions& o) {
  return o.replay ? 1 : o.peers;
}

ArtistOptions artist_options(const DemoOptions& o, std::uint32_t k) {
  ArtistOptions ao;
  ao.seed = artist_seed(o, k);
  if (o.replay)
    for (std::uint32_t j = 0; j < o.peers; ++j) ao.replayed_seeds.push_back(artist_seed(o, j));
  ao.strokes_per_second = o.strokes_per_second;
  ao.submit_every = Millis{o.sync_ms};
  return ao;
}

peer::SessionOptions session_options(const DemoOptions& o, std::uint32_t k) {
  peer::SessionOptions s;
  s.id = k + 1;  // the lowest id merges: A, whose attribution hue is green
  s.name = peer_name(k);
  s.sync = Millis{o.sync_ms};
  return s;
}

/// One artist's host loop: step (update, strokes, periodic submit), publish, and once editing
/// has stopped, the digests the main thread compares for convergence.
void artist_loop(Peer& p, const DemoOptions& o, std::uint32_t k, const std::atomic<int>& phase) {
  try {
    p.artist = std::make_unique<SimulatedArtist>(*p.session, artist_options(o, k));
    {
      std::lock_guard lock(p.mutex);
      p.published.ready = true;
    }
    while (phase.load() == static_cast<int>(Phase::setup)) std::this_thread::sleep_for(Millis{1});
    Clock::time_point next_digest{};
    while (true) {
      const int ph = phase.load();
      if (ph == static_cast<int>(Phase::stop)) break;
      const bool editing = ph == static_cast<int>(Phase::editing);
      const auto now = Clock::now();
      p.artist->step(now, editing);
      Published out;
      out.ready = true;
      out.stats = p.session->stats();
      out.version = p.session->version();
      out.strokes = p.artist->strokes();
      out.unacknowledged = p.artist->unacknowledged();
      if (!editing && now >= next_digest) {
        // Hashing a 320K-face mesh costs a few ms: often enough to notice convergence soon.
        next_digest = now + Millis{std::max<std::uint32_t>(10, o.sync_ms / 5)};
        out.local_digest = peer::mesh_digest(p.artist->local());
        out.base_digest = peer::mesh_digest(p.session->base());
        out.digests = true;
      } else {
        std::lock_guard lock(p.mutex);
        out.local_digest = p.published.local_digest;
        out.base_digest = p.published.base_digest;
        out.digests = p.published.digests && !editing;
      }
      {
        std::lock_guard lock(p.mutex);
        p.published = std::move(out);
      }
      std::this_thread::sleep_for(Millis{2});
    }
  } catch (const std::exception& e) {
    std::lock_guard lock(p.mutex);
    p.published.error = e.what();
    p.published.ready = true;
  }
}

bool all_converged(const std::vector<Published>& s) {
  for (const Published& p : s)
    if (!p.digests || p.version != s[0].version || p.local_digest != p.base_digest ||
        p.base_digest != s[0].base_digest || p.unacknowledged != 0)
      return false;
  return true;
}

/// The JSON summary's numbers, over every peer once the artist threads are done.
struct Summary {
  std::uint64_t strokes = 0, merges = 0, conflicting = 0, submit_bytes = 0, lost = 0,
                version_bytes = 0, rebases = 0, dropped = 0, version = 0;
  /// Summed over peers: each counts the merges it made, so this is every merge's (the
  /// merger's alone unless the election moved).
  std::uint64_t folds_introduced = 0;
  std::uint32_t opposed_face_pairs = 0;  ///< on the final mesh
  double merge_sum = 0, merge_max = 0;
  bool converged = false;
  double converge_s = 0, setup_s = 0, wall_s = 0;
};

Summary gather_summary(const std::vector<std::unique_ptr<Peer>>& peers) {
  Summary s;
  for (const auto& p : peers) {
    const peer::SessionStats st = p->session->stats();
    if (p->artist) {
      s.strokes += p->artist->strokes();
      s.lost += p->artist->unacknowledged();
    }
    s.merges += st.merges;
    s.conflicting += st.conflicting_strokes;
    s.submit_bytes += st.submit_bytes;
    s.version_bytes += st.version_bytes_sent;
    s.rebases += st.rebases;
    s.dropped += st.messages_dropped;
    s.folds_introduced += st.folds_introduced;
    s.merge_sum += st.merge_ms_sum;
    s.merge_max = std::max(s.merge_max, st.merge_ms_max);
  }
  return s;
}

double ratio(double a, std::uint64_t b) {
  return b ? a / static_cast<double>(b) : 0.0;
}

void print_summary(const DemoOptions& o, const Mesh& sphere, const Summary& s) {
  using ull = unsigned long long;
  std::printf(
      "{\"peers\":%u,\"artists\":%u,\"replay\":%s,\"faces\":%zu,\"vertices\":%zu,"
      "\"sync_ms\":%u,\"seconds\":%.1f,\"strokes\":%llu,\"merges\":%llu,\"version\":%llu,"
      "\"merge_ms_mean\":%.3f,\"merge_ms_max\":%.3f,\"bytes_per_stroke\":%.0f,"
      "\"submit_bytes\":%llu,\"version_bytes\":%llu,\"conflicting_edits\":%llu,"
      "\"conflicting_fraction\":%.3f,\"folds_introduced\":%llu,\"opposed_face_pairs\":%u,"
      "\"rebases\":%llu,\"messages_dropped\":%llu,\"converged\":%s,\"converge_s\":%.3f,"
      "\"lost_edits\":%llu,\"setup_s\":%.2f,\"wall_s\":%.2f,\"out\":\"%s\"}\n",
      session_count(o), o.peers, o.replay ? "true" : "false", sphere.face_count(),
      sphere.vertex_count(), o.sync_ms, o.seconds, ull(s.strokes), ull(s.merges), ull(s.version),
      ratio(s.merge_sum, s.merges), s.merge_max,
      ratio(static_cast<double>(s.submit_bytes), s.strokes), ull(s.submit_bytes),
      ull(s.version_bytes), ull(s.conflicting),
      ratio(static_cast<double>(s.conflicting), s.strokes), ull(s.folds_introduced),
      s.opposed_face_pairs, ull(s.rebases), ull(s.dropped), s.converged ? "true" : "false",
      s.converge_s, ull(s.lost), s.setup_s, s.wall_s, o.out.c_str());
  std::fflush(stdout);
}

/// Live merge lines: whichever peer merges (the election may move it), from its counters.
class MergeReporter {
 public:
  MergeReporter(std::uint32_t sessions, Clock::time_point t_edit)
      : last_(sessions), t_edit_(t_edit) {}

  void report(const std::vector<Published>& s) {
    const auto sessions = static_cast<std::uint32_t>(last_.size());
    std::uint64_t submits = 0, submit_bytes = 0, last_submits = 0, last_submit_bytes = 0;
    for (std::uint32_t k = 0; k < sessions; ++k) {
      submits += s[k].stats.submits;
      submit_bytes += s[k].stats.submit_bytes;
      last_submits += last_[k].submits;
      last_submit_bytes += last_[k].submit_bytes;
    }
    bool printed = false;
    for (std::uint32_t k = 0; k < sessions; ++k) {
      const peer::SessionStats& now = s[k].stats;
      const peer::SessionStats& before = last_[k];
      if (now.merges <= before.merges) continue;
      // The first line of a round carries the round's submits.
      print_line(k, now, before, printed ? 0 : submits - last_submits,
                 printed ? 0 : submit_bytes - last_submit_bytes);
      printed = true;
    }
    if (printed)
      for (std::uint32_t k = 0; k < sessions; ++k) last_[k] = s[k].stats;
  }

 private:
  void print_line(std::uint32_t k, const peer::SessionStats& now, const peer::SessionStats& before,
                  std::uint64_t submits, std::uint64_t submit_bytes) {
    const std::uint64_t merges = now.merges - before.merges;
    const std::uint32_t others = now.members > 0 ? now.members - 1 : 0;
    // Each merge makes the next version. The counters are published a moment before the
    // version number, so the number is counted here rather than read.
    const std::uint64_t to = std::max(now.version, printed_version_ + merges);
    printed_version_ = to;
    const std::string label =
        merges == 1 ? "version " + std::to_string(to)
                    : "versions " + std::to_string(to - merges + 1) + "-" + std::to_string(to);
    std::fprintf(
        stderr,
        "[%5.1f s] %s by %s: merge %.1f ms, %llu strokes (%llu conflicting), "
        "%llu submits in (%.1f KB), %.1f KB out to %u peers\n",
        seconds_between(t_edit_, Clock::now()), label.c_str(), peer_name(k).c_str(),
        (now.merge_ms_sum - before.merge_ms_sum) / static_cast<double>(merges),
        static_cast<unsigned long long>(now.merged_strokes - before.merged_strokes),
        static_cast<unsigned long long>(now.conflicting_strokes - before.conflicting_strokes),
        static_cast<unsigned long long>(submits), static_cast<double>(submit_bytes) / 1024.0,
        static_cast<double>(now.version_bytes_sent - before.version_bytes_sent) / 1024.0, others);
  }

  std::vector<peer::SessionStats> last_;
  std::uint64_t printed_version_ = 0;
  Clock::time_point t_edit_;
};

/// One demo run, step by step: the sessions, the artist threads, editing, syncing until
/// converged, then the final mesh and the summary.
class DemoRun {
 public:
  DemoRun(const DemoOptions& o, const Mesh& sphere) : o_(o), sphere_(sphere) {
    for (std::uint32_t k = 0; k < sessions_; ++k) peers_.push_back(std::make_unique<Peer>());
  }

  /// A creates the session; the others join with its invite (snapshot, then each builds the
  /// merge hierarchy for itself). Until the artist threads start, this thread is every
  /// session's host: it waits until everyone knows everyone (heartbeats spread membership),
  /// so the first submits reach the merger.
  void start_sessions(Clock::time_point t_start) {
    peers_[0]->session = peer::Session::create(sphere_, session_options(o_, 0));
    const std::string invite = peers_[0]->session->invite();
    for (std::uint32_t k = 1; k < sessions_; ++k)
      peers_[k]->session = peer::Session::join(invite, session_options(o_, k));
    const auto members_deadline = Clock::now() + Millis{10000};
    while (Clock::now() < members_deadline) {
      bool all = true;
      for (const auto& p : peers_) all &= p->session->stats().members == sessions_;
      if (all) break;
      std::this_thread::sleep_for(Millis{5});
    }
    setup_s_ = seconds_between(t_start, Clock::now());
    const std::string replaying =
        o_.replay ? " replaying " + std::to_string(o_.peers) + " artists' scripts" : "";
    std::fprintf(stderr,
                 "session: %u peers%s on a %zu-face sphere (%zu vertices), sync every %u ms, "
                 "joined in %.2f s; invite %s\n",
                 sessions_, replaying.c_str(), sphere_.face_count(), sphere_.vertex_count(),
                 o_.sync_ms, setup_s_, invite.substr(0, invite.find(':') + 9).c_str());
  }

  /// The artist threads, which build their topology and stroke scripts in parallel.
  void start_artists() {
    for (std::uint32_t k = 0; k < sessions_; ++k)
      peers_[k]->thread =
          std::thread(artist_loop, std::ref(*peers_[k]), std::cref(o_), k, std::cref(phase_));
    while (true) {
      const auto s = published();
      if (std::all_of(s.begin(), s.end(), [](const Published& p) { return p.ready; })) break;
      std::this_thread::sleep_for(Millis{5});
    }
  }

  /// The artists edit for o.seconds, then stop; syncing goes on until every peer holds the
  /// same version and mesh (or the timeout). Returns whether they converged.
  bool edit_and_sync() {
    const auto t_edit = Clock::now();
    reporter_.emplace(sessions_, t_edit);
    const auto edit_end = t_edit + std::chrono::duration_cast<Clock::duration>(
                                       std::chrono::duration<double>(o_.seconds));
    phase_ = static_cast<int>(Phase::editing);
    while (Clock::now() < edit_end) {
      const auto s = published();
      reporter_->report(s);
      if (!check_errors(s)) break;
      std::this_thread::sleep_for(Millis{10});
    }
    phase_ = static_cast<int>(Phase::syncing);
    const auto t_sync = Clock::now();
    const auto sync_deadline =
        t_sync + std::chrono::duration_cast<Clock::duration>(
                     std::chrono::duration<double>(o_.converge_timeout_seconds));
    bool converged = false;
    while (error_.empty() && Clock::now() < sync_deadline) {
      const auto s = published();
      reporter_->report(s);
      if (!check_errors(s)) break;
      if (all_converged(s)) {
        converged = true;
        break;
      }
      std::this_thread::sleep_for(Millis{10});
    }
    converge_s_ = seconds_between(t_sync, Clock::now());
    if (!converged && error_.empty()) explain_divergence(published());
    phase_ = static_cast<int>(Phase::stop);
    for (const auto& p : peers_) p->thread.join();
    reporter_->report(published());
    return converged;
  }

  /// With the artist threads done (this thread is every session's host again): the summary,
  /// and the final mesh with its attribution colours written; then every peer leaves.
  Summary finish(bool converged, Clock::time_point t_start) {
    Summary sum = gather_summary(peers_);
    const peer::Session& first = *peers_[0]->session;
    Mesh final_mesh = peers_[0]->artist ? peers_[0]->artist->local() : first.base();
    sum.opposed_face_pairs = count_opposed_face_pairs(final_mesh);
    const ChannelDesc attribution{"attribution", 3, Linearisation::identity, 0.f, 1.f};
    const int index = final_mesh.add_channel(attribution);
    final_mesh.channels[static_cast<std::size_t>(index)].values =
        peer::attribution_colours(first.attribution(), sphere_.vertex_count());
    write_mesh(final_mesh, o_.out);
    sum.version = first.version();
    for (auto& p : peers_) p->artist.reset();
    for (auto& p : peers_) p->session.reset();  // leave

    if (!error_.empty()) std::fprintf(stderr, "csculpt: error: %s\n", error_.c_str());
    std::fprintf(stderr, "%s after %.2f s of syncing; final mesh in %s\n",
                 converged ? "converged" : "NOT converged", converge_s_, o_.out.c_str());
    sum.converged = converged;
    sum.converge_s = converge_s_;
    sum.setup_s = setup_s_;
    sum.wall_s = seconds_between(t_start, Clock::now());
    return sum;
  }

  bool failed() const { return !error_.empty(); }

 private:
  std::vector<Published> published() const {
    std::vector<Published> s;
    for (const auto& p : peers_) s.push_back(p->snapshot());
    return s;
  }
  /// What each peer still lacked when syncing timed out, one line per peer: the version it
  /// holds, its strokes no merge has acknowledged, whether its mesh is the base plus nothing
  /// pending and whether its base is the first peer's.
  void explain_divergence(const std::vector<Published>& s) const {
    using ull = unsigned long long;
    for (std::uint32_t k = 0; k < sessions_; ++k) {
      const Published& p = s[k];
      std::fprintf(stderr,
                   "  %s: version %llu, %llu strokes unacknowledged, local %s base, base %s %s's\n",
                   peer_name(k).c_str(), ull(p.version), ull(p.unacknowledged),
                   !p.digests                        ? "not yet hashed against"
                   : p.local_digest == p.base_digest ? "="
                                                     : "!=",
                   p.base_digest == s[0].base_digest ? "=" : "!=", peer_name(0).c_str());
    }
  }

  /// Keeps the first artist's error; false once there is one.
  bool check_errors(const std::vector<Published>& s) {
    for (std::uint32_t k = 0; k < sessions_ && error_.empty(); ++k)
      if (!s[k].error.empty()) error_ = peer_name(k) + ": " + s[k].error;
    return error_.empty();
  }

  const DemoOptions& o_;
  const Mesh& sphere_;
  const std::uint32_t sessions_ = session_count(o_);
  std::vector<std::unique_ptr<Peer>> peers_;
  std::atomic<int> phase_{static_cast<int>(Phase::setup)};
  std::optional<MergeReporter> reporter_;
  std::string error_;
  double setup_s_ = 0, converge_s_ = 0;
};

}  // namespace

int run_demo(const DemoOptions& o) {
  const auto t_start = Clock::now();
  const Mesh sphere = make_sphere(o.faces, /*materials=*/true);
  DemoRun run(o, sphere);
  run.start_sessions(t_start);
  run.start_artists();
  const bool converged = run.edit_and_sync();
  const Summary sum = run.finish(converged, t_start);
  print_summary(o, sphere, sum);
  return converged && sum.lost == 0 && !run.failed() ? 0 : 1;
}

CLI::App* add_demo_command(CLI::App& app, DemoOptions& o) {
  CLI::App* demo = app.add_subcommand(
      "demo",
      "a serverless session on this machine: simulated artists sculpt and paint one mesh, "
      "their edits merge every sync interval");
  demo->add_option("--peers", o.peers,
                   "simulated artists, one peer session each (with --replay: one for all)")
      ->capture_default_str()
      ->check(CLI::Range(1u, 32u));
  demo->add_option("--seconds", o.seconds, "editing time (syncing continues until converged)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 86400.0));
  demo->add_option("--faces", o.faces, "faces of the built-in sphere")
      ->capture_default_str()
      ->check(CLI::Range(20u, 20000000u));
  demo->add_option("--sync-ms", o.sync_ms, "merge interval in milliseconds")
      ->capture_default_str()
      ->check(CLI::Range(10u, 600000u));
  demo->add_option("--strokes-per-second", o.strokes_per_second, "strokes per artist per second")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1000.0));
  demo->add_option("--converge-timeout", o.converge_timeout_seconds,
                   "seconds to wait for convergence after editing stops")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 3600.0));
  demo->add_option("-o,--out", o.out, "final mesh (PLY with materials and attribution colours)")
      ->capture_default_str();
  demo->add_option("--seed", o.seed, "stroke seed")->capture_default_str();
  demo->add_flag("--replay", o.replay,
                 "one peer plays all --peers artists' scripts (same seeds and rate) in time "
                 "order: the single-peer baseline of the same strokes, same JSON summary");
  return demo;
}

}  // namespace csculpt::cli
