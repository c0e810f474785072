// `csculpt bench session`. Every peer's host runs its own loop (update as often as it can,
// 1 ms naps); one peer at a time makes a scripted stroke and submits it. A sample is the time
// from that submit until the last peer's update() has applied the version that merged it (the
// first version after the submit: nobody else edits meanwhile, and the submitter's
// acknowledgement is checked). Samples start at a random phase of the sync interval, so the
// wait for the merger's next tick is measured as an artist would meet it. Hosts submit the
// vertices their strokes changed; --full-submit makes them submit the whole mesh.
#include "bench_session.h"

#include "bench_stats.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <map>
#include <memory>
#include <mutex>
#include <random>
#include <thread>
#include <vector>

#include "artist.h"
#include "csculpt/peer/session.h"
#include "csculpt/testkit/generate.h"

namespace csculpt::cli {
namespace {

using peer::Clock;
using peer::Millis;

struct SubmitRecord {
  std::uint64_t request = 0;
  std::uint64_t base_version = 0;
  Clock::time_point at{};
  double submit_ms = 0;  ///< host side of submit(): capture, encode, decode (not the stroke)
  bool sent = false;
};

struct BenchPeer {
  std::unique_ptr<peer::Session> session;
  std::unique_ptr<SimulatedArtist> artist;  // its script and topology; stepped by hand here
  std::thread thread;
  std::atomic<std::uint64_t> request{0};  ///< stroke-and-submit requests (a counter)
  mutable std::mutex mutex;
  // published by the peer's thread
  std::uint64_t version = 0;
  std::map<std::uint64_t, Clock::time_point> applied_at;  ///< version -> when update() had it
  std::map<std::uint64_t, double> update_ms;  ///< version -> how long that update() took
  peer::SessionStats stats;
  SubmitRecord submit;
  std::string error;
};

void peer_loop(BenchPeer& p, const std::atomic<bool>& stop) {
  try {
    std::uint64_t done = 0;
    bool awaiting_ack = false;
    std::uint64_t acknowledged = p.session->stats().strokes_acknowledged;
    while (!stop.load()) {
      const std::uint64_t before = p.session->version();
      const auto t0 = Clock::now();
      const std::size_t applied = p.artist->update();
      const auto now = Clock::now();
      SubmitRecord record;
      const std::uint64_t request = p.request.load();
      if (request != done) {
        done = request;
        record.request = request;
        p.artist->stroke();
        record.base_version = p.session->version();
        record.at = Clock::now();
        record.sent = p.artist->submit(1);
        record.submit_ms = ms_between(record.at, Clock::now());
        awaiting_ack = record.sent;
      } else if (applied && awaiting_ack) {
        // A version that did not carry our edit (its base went stale): send it again.
        p.artist->submit(0);
      }
      const peer::SessionStats stats = p.session->stats();
      if (stats.strokes_acknowledged != acknowledged) {
        acknowledged = stats.strokes_acknowledged;
        awaiting_ack = false;
      }
      {
        std::lock_guard lock(p.mutex);
        for (std::uint64_t v = before + 1; v <= p.session->version(); ++v) {
          p.applied_at[v] = now;
          p.update_ms[v] = ms_between(t0, now);
        }
        p.version = p.session->version();
        p.stats = stats;
        if (record.request) p.submit = record;
      }
      std::this_thread::sleep_for(Millis{1});
    }
  } catch (const std::exception& e) {
    std::lock_guard lock(p.mutex);
    p.error = e.what();
  }
}

peer::SessionStats stats_of(const BenchPeer& p) {
  std::lock_guard lock(p.mutex);
  return p.stats;
}

using BenchPeers = std::vector<std::unique_ptr<BenchPeer>>;

/// Peer 1 creates the session, the others join; waits until everyone sees everyone. False
/// (after printing why) if they do not within 10 s.
bool start_peers(const BenchSessionOptions& o, const Mesh& sphere, std::uint32_t n_peers,
                 BenchPeers& peers) {
  for (std::uint32_t k = 0; k < n_peers; ++k) {
    auto p = std::make_unique<BenchPeer>();
    peer::SessionOptions so;
    so.id = k + 1;  // peer 1 merges
    so.name = "bench" + std::to_string(k + 1);
    so.sync = Millis{o.sync_ms};
    p->session = k == 0 ? peer::Session::create(sphere, so)
                        : peer::Session::join(peers[0]->session->invite(), so);
    ArtistOptions ao;
    ao.seed = o.seed * 1000 + k;
    ao.whole_mesh_submit = o.full_submit;
    p->artist = std::make_unique<SimulatedArtist>(*p->session, ao);
    peers.push_back(std::move(p));
  }
  const auto members_deadline = Clock::now() + Millis{10000};
  bool members = false;
  while (!members && Clock::now() < members_deadline) {
    members = true;
    for (const auto& p : peers) members &= p->session->stats().members == n_peers;
    if (!members) std::this_thread::sleep_for(Millis{5});
  }
  if (!members)
    std::fprintf(stderr, "bench session: %u peers did not all see each other in 10 s\n", n_peers);
  return members;
}

/// What the samples measured, and how many went wrong.
struct Samples {
  std::vector<double> e2e, merge_ms, bytes, submit_ms, version_bytes, update_ms;
  std::uint32_t unsent = 0, failed = 0, extra_merges = 0;
};

constexpr std::uint32_t kWarmup = 2;
const Millis kSampleTimeout{10000};

enum class Wait { complete, unsent, timed_out, error };

/// Waits for the author's submit of `request` (into `rec`), then for every peer to hold the
/// next version and the author to see its stroke acknowledged.
Wait wait_for_sample(const BenchPeers& peers, BenchPeer& author, std::uint64_t request,
                     const peer::SessionStats& author_before, SubmitRecord& rec,
                     std::string& error) {
  const auto deadline = Clock::now() + kSampleTimeout;
  bool complete = false;
  while (Clock::now() < deadline) {
    {
      std::lock_guard lock(author.mutex);
      rec = author.submit;
      if (!author.error.empty()) error = author.error;
    }
    if (!error.empty() || (rec.request == request && !rec.sent)) break;
    if (rec.request == request) {
      const std::uint64_t target = rec.base_version + 1;
      bool all = true;
      for (const auto& p : peers) {
        std::lock_guard lock(p->mutex);
        all &= p->version >= target;
      }
      std::lock_guard lock(author.mutex);
      if (all && author.stats.strokes_acknowledged > author_before.strokes_acknowledged) {
        complete = true;
        break;
      }
    }
    std::this_thread::sleep_for(Millis{1});
  }
  if (!error.empty()) return Wait::error;
  if (rec.request == request && !rec.sent) return Wait::unsent;
  return complete ? Wait::complete : Wait::timed_out;
}

/// Sample `s`'s figures (kept from the warm-up on only, but for its merge count).
void record_sample(const BenchPeers& peers, const BenchPeer& author, const BenchPeer& merger,
                   const SubmitRecord& rec, std::uint32_t s,
                   const peer::SessionStats& author_before, const peer::SessionStats& merger_before,
                   Samples& out) {
  const auto n_peers = static_cast<std::uint32_t>(peers.size());
  const std::uint64_t target = rec.base_version + 1;
  double worst = 0;
  for (const auto& p : peers) {
    std::lock_guard lock(p->mutex);
    worst = std::max(worst, ms_between(rec.at, p->applied_at.at(target)));
    if (s >= kWarmup) out.update_ms.push_back(p->update_ms.at(target));
  }
  const peer::SessionStats author_after = stats_of(author);
  const peer::SessionStats merger_after = stats_of(merger);
  // Nobody else edits, so exactly one merge should lie between submit and arrival.
  if (merger_after.merges != merger_before.merges + 1) ++out.extra_merges;
  if (s < kWarmup) return;
  out.e2e.push_back(worst);
  out.submit_ms.push_back(rec.submit_ms);
  out.bytes.push_back(static_cast<double>(author_after.submit_bytes - author_before.submit_bytes));
  const std::uint64_t merges = merger_after.merges - merger_before.merges;
  if (merges > 0) {
    out.merge_ms.push_back((merger_after.merge_ms_sum - merger_before.merge_ms_sum) /
                           static_cast<double>(merges));
    out.version_bytes.push_back(
        static_cast<double>(merger_after.version_bytes_sent - merger_before.version_bytes_sent) /
        static_cast<double>(merges * (n_peers - 1 ? n_peers - 1 : 1)));
  }
}

/// The samples, round robin over the submitting peer, each at a random phase of the sync
/// interval; stops at the first error (into `error`) or when too many fail.
Samples measure(const BenchSessionOptions& o, const BenchPeers& peers, std::string& error) {
  const auto n_peers = static_cast<std::uint32_t>(peers.size());
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> phase(0.0, static_cast<double>(o.sync_ms));
  Samples out;
  for (std::uint32_t s = 0; s < o.samples + kWarmup && error.empty();) {
    BenchPeer& author = *peers[s % n_peers];
    BenchPeer& merger = *peers[0];
    std::this_thread::sleep_for(
        std::chrono::duration<double, std::milli>(5.0 + phase(rng)));  // random tick phase
    const peer::SessionStats author_before = stats_of(author);
    const peer::SessionStats merger_before = stats_of(merger);
    const std::uint64_t request = author.request.fetch_add(1) + 1;
    SubmitRecord rec;
    const Wait wait = wait_for_sample(peers, author, request, author_before, rec, error);
    if (wait == Wait::error) break;
    if (wait == Wait::unsent) {
      ++out.unsent;  // the stroke changed nothing the wire carries: take the next one
      if (out.unsent > 10 * (o.samples + kWarmup)) break;
      continue;
    }
    if (wait == Wait::timed_out) {
      ++out.failed;
      std::fprintf(stderr, "bench session: sample %u did not complete within %lld ms\n", s,
                   static_cast<long long>(kSampleTimeout.count()));
      if (out.failed > 3) break;
      ++s;
      continue;
    }
    record_sample(peers, author, merger, rec, s, author_before, merger_before, out);
    ++s;
  }
  return out;
}

void print_result(const BenchSessionOptions& o, const Mesh& sphere, std::uint32_t n_peers,
                  const Samples& m, std::uint64_t dropped, double setup_ms) {
  double bytes_sum = 0;
  for (double b : m.bytes) bytes_sum += b;
  std::printf(
      "{\"bench\":\"session\",\"peers\":%u,\"faces\":%zu,\"vertices\":%zu,\"sync_ms\":%u,"
      "\"samples\":%zu,\"e2e_ms_p50\":%.2f,\"e2e_ms_p90\":%.2f,\"e2e_ms_p99\":%.2f,"
      "\"e2e_ms_max\":%.2f,"
      "\"merge_ms_p50\":%.2f,\"merge_ms_max\":%.2f,\"submit_ms_p50\":%.2f,\"update_ms_p50\":%.2f,"
      "\"bytes_per_stroke\":%.0f,\"bytes_per_stroke_mean\":%.0f,\"version_bytes_p50\":%.0f,"
      "\"failed\":%u,\"extra_merges\":%u,\"messages_dropped\":%llu,\"setup_ms\":%.0f,"
      "\"submit\":\"%s\",\"cores\":%u}\n",
      n_peers, sphere.face_count(), sphere.vertex_count(), o.sync_ms, m.e2e.size(),
      quantile(m.e2e, 0.5), quantile(m.e2e, 0.9), quantile(m.e2e, 0.99), quantile(m.e2e, 1.0),
      quantile(m.merge_ms, 0.5), quantile(m.merge_ms, 1.0), quantile(m.submit_ms, 0.5),
      quantile(m.update_ms, 0.5), quantile(m.bytes, 0.5),
      bytes_sum / static_cast<double>(m.bytes.size()), quantile(m.version_bytes, 0.5), m.failed,
      m.extra_merges, static_cast<unsigned long long>(dropped), setup_ms,
      o.full_submit ? "full" : "changed", std::thread::hardware_concurrency());
  std::fflush(stdout);
}

/// One configuration; returns false (after printing why on stderr) if it could not be measured.
bool run_configuration(const BenchSessionOptions& o, const Mesh& sphere, std::uint32_t n_peers) {
  const auto t_setup = Clock::now();
  BenchPeers peers;
  if (!start_peers(o, sphere, n_peers, peers)) return false;
  const double setup_ms = ms_between(t_setup, Clock::now());

  std::atomic<bool> stop{false};
  for (auto& p : peers) p->thread = std::thread(peer_loop, std::ref(*p), std::cref(stop));
  std::string error;
  const Samples samples = measure(o, peers, error);
  stop = true;
  for (auto& p : peers) p->thread.join();
  std::uint64_t dropped = 0;
  for (const auto& p : peers) dropped += p->stats.messages_dropped;
  if (!error.empty()) {
    std::fprintf(stderr, "bench session: %s\n", error.c_str());
    return false;
  }
  if (samples.e2e.empty()) {
    std::fprintf(stderr, "bench session: no sample completed with %u peers\n", n_peers);
    return false;
  }
  print_result(o, sphere, n_peers, samples, dropped, setup_ms);
  return true;
}

}  // namespace

CLI::App* add_bench_session_command(CLI::App& bench, BenchSessionOptions& o) {
  CLI::App* cmd = bench.add_subcommand(
      "session",
      "end-to-end latency of a loopback peer session: submit to every peer holding the merge");
  cmd->add_option("--faces", o.faces, "approximate face count")
      ->capture_default_str()
      ->check(CLI::Range(20u, 20000000u));
  cmd->add_option("--peers", o.peers, "peer counts, one JSON line each (e.g. 2,4,8)")
      ->delimiter(',')
      ->capture_default_str()
      ->check(CLI::Range(1u, 64u));
  cmd->add_option("--sync-ms", o.sync_ms, "merge interval in milliseconds")
      ->capture_default_str()
      ->check(CLI::Range(1u, 600000u));
  cmd->add_option("--samples", o.samples, "measured submits per configuration")
      ->capture_default_str()
      ->check(CLI::Range(1u, 100000u));
  cmd->add_option("--seed", o.seed, "stroke seed")->capture_default_str();
  cmd->add_flag(
      "--full-submit", o.full_submit,
      "hosts submit the whole mesh (compared vertex by vertex), not the changed vertices");
  return cmd;
}

int bench_session(const BenchSessionOptions& o) {
  const Mesh sphere = make_sphere(o.faces, /*materials=*/true);
  bool ok = true;
  for (std::uint32_t n : o.peers) ok &= run_configuration(o, sphere, n);
  return ok ? 0 : 1;
}

}  // namespace csculpt::cli
