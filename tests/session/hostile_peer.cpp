// A hostile participant for the multi-process session tests (test_hostile.py).
//
//   hostile_peer nokey INVITE [SECONDS]   connect without the session's keys (raw TCP, plain
//                                         ZeroMQ, CURVE with a wrong client key, CURVE with a
//                                         wrong server key) and send garbage
//   hostile_peer keyed INVITE [SECONDS]   connect with the keys, say hello (to learn each
//                                         member's version, chain and epoch from heartbeats)
//                                         and send garbage and valid-but-wrong messages
//   hostile_peer overflow INVITE [SECONDS]  connect with the keys, say hello, then only claim
//                                         epoch 2^64-1 (for the merger and for itself)
//
// Prints one JSON object per line: what it sent, what it learnt, and a final "done" line.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>
#include <zmq.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <map>
#include <random>
#include <string>
#include <thread>
#include <vector>
#include <zmq.hpp>

#include "csculpt/error.h"
#include "csculpt/peer/session.h"
#include "csculpt/varint.h"
#include "csculpt/wire.h"
#include "diff_generated.h"
#include "messages.h"
#include "snapshot.h"
#include "transport.h"

namespace {

namespace fb = csculpt::session;
namespace wfb = csculpt::wire;
using namespace csculpt::peer;
using Clock = std::chrono::steady_clock;

std::mt19937_64 rng(12345);

Bytes random_bytes(std::size_t n) {
  Bytes b(n);
  for (auto& x : b) x = static_cast<std::uint8_t>(rng());
  return b;
}

void say(const std::string& json) {
  std::printf("%s\n", json.c_str());
  std::fflush(stdout);
}

void send_all(zmq::socket_t& s, const std::vector<Bytes>& messages) {
  for (const Bytes& m : messages) (void)s.send(zmq::buffer(m), zmq::send_flags::dontwait);
}

std::vector<Bytes> garbage_set() {
  std::vector<Bytes> out = {Bytes{}, random_bytes(1), random_bytes(7), random_bytes(100),
                            random_bytes(5000)};
  // The right file identifier ("CSS1" at offset 4) in front of garbage: passes the cheap check,
  // must fail verification.
  Bytes ident = random_bytes(64);
  std::memcpy(ident.data() + 4, "CSS1", 4);
  out.push_back(ident);
  return out;
}

// ---- nokey -------------------------------------------------------------------------------

int run_nokey(const Invite& inv, double seconds) {
  const auto deadline = Clock::now() + std::chrono::duration<double>(seconds);
  int attempts = 0;
  // Raw TCP garbage: the ZMTP greeting fails before any security mechanism is reached.
  if (inv.endpoint.rfind("tcp://", 0) == 0) {
    const std::string hp = inv.endpoint.substr(6);
    const std::size_t colon = hp.rfind(':');
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(static_cast<std::uint16_t>(std::stoi(hp.substr(colon + 1))));
    inet_pton(AF_INET, hp.substr(0, colon).c_str(), &addr.sin_addr);
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    if (fd >= 0 && ::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0) {
      const Bytes g = random_bytes(4096);
      (void)!::write(fd, g.data(), g.size());
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      ++attempts;
      say(R"({"event":"sent","what":"raw tcp garbage"})");
    }
    if (fd >= 0) ::close(fd);
  }
  zmq::context_t ctx;
  const CurveKey server_public = curve_public(inv.server_secret);
  CurveKey wrong_secret{}, wrong_server{};
  for (auto& b : wrong_secret) b = static_cast<std::uint8_t>(rng());
  for (auto& b : wrong_server) b = static_cast<std::uint8_t>(rng());
  {
    zmq::socket_t plain(ctx, zmq::socket_type::dealer);
    plain.set(zmq::sockopt::linger, 0);
    plain.connect(inv.endpoint);
    send_all(plain, garbage_set());
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    ++attempts;
    say(R"({"event":"sent","what":"plain zeromq garbage"})");
  }
  {
    zmq::socket_t wrong_server_key =
        curve_dealer(ctx, inv.endpoint, curve_public(wrong_server), wrong_secret);
    send_all(wrong_server_key, garbage_set());
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    ++attempts;
    say(R"({"event":"sent","what":"curve with a wrong server key"})");
  }
  {
    // The right server key but a client key the session does not know: the handshake reaches
    // the ZAP check, which must refuse it (auth_rejected counts it). Kept open until the
    // deadline: libzmq reconnects and is refused again.
    zmq::socket_t wrong_client = curve_dealer(ctx, inv.endpoint, server_public, wrong_secret);
    send_all(wrong_client, garbage_set());
    ++attempts;
    say(R"({"event":"sent","what":"curve with a wrong client key"})");
    while (Clock::now() < deadline) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  say("{\"event\":\"done\",\"attempts\":" + std::to_string(attempts) + "}");
  return 0;
}

// ---- keyed -------------------------------------------------------------------------------

struct Known {
  std::string endpoint;
  std::uint64_t version = 0, chain = 0, epoch = 0;
  PeerId merger = 0;
  bool heard = false;
};

class Keyed {
 public:
  // The peers' own transport: a CURVE ROUTER with the session's keys (its ZAP handler admits
  // the members) and DEALERs whose routing id is 'P' + our id, as every peer checks.
  Keyed(const Invite& inv, PeerId self, bool overflow_epoch)
      : inv_(inv),
        self_(self),
        overflow_epoch_(overflow_epoch),
        transport_(inv, self, "tcp://127.0.0.1:*", std::size_t{64} << 20),
        endpoint_(transport_.endpoint()) {}

  int run(double seconds) {
    const auto deadline = Clock::now() + std::chrono::duration<double>(seconds);
    // 1. Garbage and malformed envelopes to the inviter, before anyone knows us.
    for (const Bytes& g : garbage_set()) send(inv_.endpoint, g, "garbage");
    Bytes hb = heartbeat(inv_.session, self_, 0);
    send(inv_.endpoint, Bytes(hb.begin(), hb.begin() + static_cast<long>(hb.size() / 2)),
         "truncated envelope");
    send(inv_.endpoint, heartbeat(inv_.session ^ 0x5a5a5a5aull, self_, 0), "another session");
    send(inv_.endpoint, heartbeat(inv_.session, 0, 0), "sender id 0");
    send(inv_.endpoint, hello(99, false), "hello of protocol 99");
    // 2. Join as a member (with the keys we are one) to learn versions, chains and epochs.
    send(inv_.endpoint, hello(1, true), "hello");
    pump(std::chrono::milliseconds(100));
    const auto learn_until = Clock::now() + std::chrono::seconds(10);
    while ((!merger_known() || vertex_count_ == 0) && Clock::now() < learn_until)
      pump(std::chrono::milliseconds(20));
    if (!merger_known() || vertex_count_ == 0) {
      std::fprintf(stderr, "hostile_peer: learnt no merger or no snapshot within 10 s\n");
      return 1;
    }
    say("{\"event\":\"learnt\",\"vertices\":" + std::to_string(vertex_count_) + ",\"merger\":" +
        std::to_string(merger_id()) + ",\"members\":" + std::to_string(known_.size()) + "}");
    // 3. Valid-but-wrong messages, repeated with what we last heard, until the deadline.
    int rounds = 0;
    while (Clock::now() < deadline) {
      if (overflow_epoch_)
        overflow_round();
      else
        round();
      ++rounds;
      pump(std::chrono::milliseconds(60));
    }
    for (const auto& [id, k] : known_) send(k.endpoint, leave(), "leave");
    pump(std::chrono::milliseconds(50));
    std::string counts;
    for (const auto& [what, n] : sent_)
      counts.append(counts.empty() ? "\"" : ",\"")
          .append(what)
          .append("\":")
          .append(std::to_string(n));
    say("{\"event\":\"done\",\"rounds\":" + std::to_string(rounds) + ",\"sent\":{" + counts + "}}");
    return 0;
  }

 private:
  void round() {
    const PeerId merger = merger_id();
    const Known& m = known_.at(merger);
    // To the merger: submits on an unknown base, with out-of-range indices, with a garbage diff.
    send(m.endpoint, submit(diff_message(m.version + 1000, vertex_count_, false)),
         "submit on an unknown base version");
    for (std::uint64_t v = m.version; v <= m.version + 1; ++v)
      send(m.endpoint, submit(diff_message(v, vertex_count_, true)),
           "submit with out-of-range indices");
    send(m.endpoint, submit(random_bytes(40)), "submit with a garbage diff");
    // To every member, in its own state: forged versions.
    for (const auto& [id, k] : known_) {
      if (!k.heard) continue;
      const Bytes empty = diff_message(k.version, vertex_count_, false);
      const Bytes bad_indices = diff_message(k.version, vertex_count_, true);
      // Speaking for the merger over our own connection: the sender does not match it.
      send(k.endpoint, version(merger, k.epoch, k.version + 1, k.chain, k.chain ^ 1, empty, false),
           "version in the merger's name");
      // Our own version in a stale epoch: ignored as stale.
      send(k.endpoint, version(self_, 0, k.version + 1, k.chain, k.chain ^ 1, empty, false),
           "version of a stale epoch");
      // A far-future epoch: we are not the lowest live id, so nobody follows (the merger
      // re-asserts itself past it).
      send(k.endpoint,
           version(self_, k.epoch + 1000000, k.version + 1, k.chain, k.chain ^ 1, empty, false),
           "version of a far-future epoch");
      // A replay (answers to fetches skip the epoch checks) with the right parent and a wrong
      // chain: fails the hash chain.
      send(k.endpoint, version(self_, k.epoch, k.version + 1, k.chain, k.chain ^ 1, empty, true),
           "replayed version with a wrong hash chain");
      // ... and one whose diff has indices out of range.
      send(k.endpoint,
           version(self_, k.epoch, k.version + 1, k.chain, k.chain ^ 1, bad_indices, true),
           "replayed version with out-of-range indices");
    }
  }

  /// Only this: a heartbeat naming the real merger in epoch 2^64-1 (a claim for the merger a
  /// peer already follows raises its epoch to the claim's), and a claim of our own in that
  /// epoch (the merger re-asserts itself one past it).
  void overflow_round() {
    const PeerId merger = merger_id();
    for (const auto& [id, k] : known_) {
      send(k.endpoint, heartbeat(inv_.session, self_, 0, merger, ~std::uint64_t{0}),
           "heartbeat naming the merger in epoch 2^64-1");
      send(k.endpoint, elected(~std::uint64_t{0}), "claim to merge epoch 2^64-1");
    }
  }

  bool merger_known() const {
    const PeerId m = merger_id();
    auto it = known_.find(m);
    return m != 0 && it != known_.end() && it->second.heard;
  }
  PeerId merger_id() const {
    // The merger's own word counts most; else what most recently heard peers say.
    for (const auto& [id, k] : known_)
      if (k.heard && k.merger == id) return id;
    return 0;
  }

  void pump(std::chrono::milliseconds budget) {
    const auto until = Clock::now() + budget;
    while (Clock::now() < until) {
      if (Clock::now() >= next_heartbeat_) {
        // Stay a member: a silent one expires and is sent nothing more to learn from.
        next_heartbeat_ = Clock::now() + std::chrono::milliseconds(40);
        for (const auto& [id, k] : known_)
          send(k.endpoint, heartbeat(inv_.session, self_, 0), "heartbeat");
      }
      transport_.wait(std::min<Clock::duration>(
          std::chrono::milliseconds(5), std::max(Clock::duration::zero(), until - Clock::now())));
      Inbound message;
      while (transport_.receive(message)) learn_from(message);
    }
  }

  /// What a member's heartbeat says (versions, chains, epochs, members) and the snapshot's
  /// vertex count, read with the peers' own checks (open_envelope, SnapshotAssembly).
  void learn_from(const Inbound& message) {
    const Opened opened = open_envelope(
        {static_cast<const std::uint8_t*>(message.payload.data()), message.payload.size()},
        {static_cast<const std::uint8_t*>(message.routing.data()), message.routing.size()},
        inv_.session, self_, storage_);
    if (!opened.envelope) return;
    const fb::Envelope* env = opened.envelope;
    if (env->body_type() == fb::Body::Heartbeat) {
      const fb::Heartbeat* hb = env->body_as_Heartbeat();
      Known& k = known_[env->sender()];
      k.version = hb->version();
      k.chain = hb->chain();
      k.merger = hb->merger();
      k.epoch = env->epoch();
      k.heard = true;
      if (hb->members())
        for (const fb::Member* m : *hb->members())
          if (m->endpoint() && m->peer() != self_)
            known_[m->peer()].endpoint = m->endpoint()->str();
    } else if (env->body_type() == fb::Body::SnapshotChunk && vertex_count_ == 0) {
      const fb::SnapshotChunk* c = env->body_as_SnapshotChunk();
      if (!c->data() || c->total() > (std::size_t{1} << 30)) return;
      try {
        if (snapshot_.add(c->version(), c->chain(), c->offset(), c->total(),
                          {c->data()->data(), c->data()->size()}))
          vertex_count_ =
              static_cast<std::uint32_t>(decode_snapshot(snapshot_.take()).mesh.vertex_count());
      } catch (const csculpt::InvalidInput&) {
        // a chunk outside its buffer or a snapshot that does not decode: learn nothing
      }
    }
  }

  // ---- message builders ----------------------------------------------------------------------
  EnvelopeHeader as(PeerId sender, std::uint64_t epoch = 0) const {
    return {inv_.session, sender, epoch};
  }
  Bytes heartbeat(std::uint64_t session, PeerId sender, std::uint64_t version, PeerId merger = 0,
                  std::uint64_t epoch = 0) {
    return heartbeat_message({session, sender, epoch}, version, 0, merger);
  }
  Bytes hello(std::uint32_t protocol, bool wants_snapshot) {
    return hello_message(as(self_), endpoint_, "hostile", wants_snapshot, protocol);
  }
  Bytes elected(std::uint64_t epoch) { return elected_message(as(self_, epoch), self_); }
  Bytes leave() { return leave_message(as(self_)); }
  Bytes submit(const Bytes& diff) { return submit_message(as(self_), diff, 7); }
  Bytes version(PeerId sender, std::uint64_t epoch, std::uint64_t v, std::uint64_t parent,
                std::uint64_t chain, const Bytes& diff, bool replay) {
    VersionRecord r;
    r.version = v;
    r.parent_chain = parent;
    r.chain = chain;
    r.diff_bytes = diff;
    return version_message(as(sender, epoch), r, replay);
  }
  /// A DiffMessage built by hand (the codec refuses to write a bad one): empty, or moving
  /// vertex `vertex_count + 5` (out of range).
  static Bytes diff_message(std::uint64_t base_version, std::uint32_t vertex_count,
                            bool out_of_range) {
    flatbuffers::FlatBufferBuilder b(256);
    flatbuffers::Offset<wfb::AttributeChanges> positions = 0;
    if (out_of_range) {
      std::vector<std::uint8_t> gaps;
      csculpt::put_varint(gaps, std::uint64_t{vertex_count} + 5);
      const float value[3] = {0.5f, 0.5f, 0.5f};
      std::vector<std::uint8_t> values(12);
      std::memcpy(values.data(), value, 12);
      positions = wfb::CreateAttributeChanges(b, 1, b.CreateVector(gaps), wfb::ValueCoding::Float32,
                                              0.0, b.CreateVector(values));
    }
    b.Finish(wfb::CreateDiffMessage(b, csculpt::wire_protocol_version, base_version,
                                    b.CreateString("hostile"), 1, vertex_count, positions),
             wfb::DiffMessageIdentifier());
    return {b.GetBufferPointer(), b.GetBufferPointer() + b.GetSize()};
  }

  void send(const std::string& endpoint, const Bytes& bytes, const std::string& what) {
    if (endpoint.empty()) return;
    transport_.send(endpoint, bytes);
    ++sent_[what];
  }

  Invite inv_;
  PeerId self_;
  bool overflow_epoch_;  // overflow mode: only the epoch 2^64-1 claims
  Transport transport_;
  std::string endpoint_;                // ours, announced in hellos
  std::map<PeerId, Known> known_;       // what each member last told us
  std::map<std::string, int> sent_;     // what we sent, by kind, for the final report
  SnapshotAssembly snapshot_;           // the inviter's snapshot, for the vertex count
  std::vector<std::uint64_t> storage_;  // open_envelope's aligned copies
  std::uint32_t vertex_count_ = 0;
  Clock::time_point next_heartbeat_{};
};

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: hostile_peer nokey|keyed|overflow INVITE [SECONDS]\n");
    return 2;
  }
  try {
    const std::string mode = argv[1];
    const Invite inv = parse_invite(argv[2]);
    const double seconds = argc > 3 ? std::stod(argv[3]) : 2.0;
    if (mode == "nokey") return run_nokey(inv, seconds);
    if (mode == "keyed") return Keyed(inv, 900001, false).run(seconds);
    if (mode == "overflow") return Keyed(inv, 900001, true).run(seconds);
    std::fprintf(stderr, "hostile_peer: unknown mode '%s'\n", mode.c_str());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "hostile_peer: error: %s\n", e.what());
    return 1;
  }
}
