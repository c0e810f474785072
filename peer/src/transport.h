// The peer's sockets: one CURVE ROUTER it binds, one CURVE DEALER per peer it talks to, the ZAP
// handler that admits only holders of the session's client key, and a wake-up pipe so the
// network thread can sleep in zmq_poll until a message, a ZAP request or a host command comes.
// Every ZeroMQ failure leaves this file as csculpt::IoError saying what failed.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <vector>
#include <zmq.hpp>

#include "csculpt/peer/membership.h"
#include "csculpt/peer/session.h"
#include "handshake_monitor.h"

namespace csculpt::peer {

using CurveKey = std::array<std::uint8_t, 32>;
/// What a DEALER calls itself to a ROUTER: 'P' and the peer id's 8 bytes, little-endian (a
/// routing id may not start with a zero byte).
using RoutingId = std::array<std::uint8_t, 9>;

/// The CURVE public key of `secret`. Throws IoError when libzmq was built without CURVE.
CurveKey curve_public(const CurveKey& secret);

RoutingId routing_id(PeerId id);
/// Whether `routing` (the first frame a ROUTER hands over) is `sender`'s routing id: a member
/// cannot speak for another by accident. (A newer connection with an id in use takes it over,
/// ZMQ_ROUTER_HANDOVER: every member holds the session's keys and is trusted that far.)
bool is_routing_id_of(PeerId sender, std::span<const std::uint8_t> routing);

/// The answer to a ZAP request (RFC 27): accepted only for CURVE with the session's client key.
struct ZapDecision {
  bool accepted = false;
  std::array<std::string, 6> reply;  ///< version, request id, status code and text, user, meta
};
ZapDecision decide_zap(const std::vector<std::string>& request, const CurveKey& client_public);

/// The endpoint others reach a socket bound at `bound` (ZMQ_LAST_ENDPOINT) by: a wildcard
/// address ("tcp://0.0.0.0:port") becomes this machine's first non-loopback IPv4 address.
std::string advertised_endpoint(const std::string& bound);

/// Options of a DEALER made by curve_dealer.
struct DealerOptions {
  const RoutingId* routing_id = nullptr;  ///< none: libzmq picks one
  std::int64_t max_message_bytes = -1;    ///< ZMQ_MAXMSGSIZE; -1 = unlimited
  int send_hwm = 1000;                    ///< messages queued before sends are dropped
  /// A TCP connect not answered within this is given up and tried again (ZMQ_CONNECT_TIMEOUT,
  /// after the reconnect interval). Without it, a connect made while a partition drops its SYNs
  /// waits on the kernel's doubling retransmissions (1, 2, 4 s...) and a healed partition went
  /// unnoticed for seconds.
  int connect_timeout_ms = 1000;
};
/// A connected CURVE DEALER (the hostile test client makes them with wrong keys too). Throws
/// IoError.
zmq::socket_t curve_dealer(zmq::context_t& context, const std::string& endpoint,
                           const CurveKey& server_public, const CurveKey& client_secret,
                           const DealerOptions& options = {});

/// A message as a ROUTER received it.
struct Inbound {
  zmq::message_t routing;
  zmq::message_t payload;
};

class Transport {
 public:
  /// Binds the ROUTER to `bind` (port * picks a free one) with the invite's CURVE keys and
  /// starts answering ZAP requests; raises the process's open-file limit (raise_fd_limit).
  /// Throws IoError naming the endpoint that failed. (No ZMTP heartbeats: libzmq 4.3.4's
  /// heartbeat timer writes to a connection whose input stopped with an error and aborts the
  /// process on `!_io_error`, stream_engine_base.cpp:331, seen in a chaos run; membership has
  /// its own heartbeats, and PeerNode drops the connection to a member that expired.)
  Transport(const Invite& invite, PeerId self, const std::string& bind,
            std::size_t max_message_bytes);
  ~Transport();
  Transport(const Transport&) = delete;
  Transport& operator=(const Transport&) = delete;

  /// The endpoint bound (the port resolved).
  const std::string& endpoint() const { return endpoint_; }

  /// Connects a DEALER to `endpoint` once (later calls reuse it). Throws IoError for an
  /// endpoint ZeroMQ cannot connect to.
  void connect(const std::string& endpoint);
  /// Closes our DEALER to `endpoint` at once (the next send makes a new connection: after a
  /// partition the old one's TCP retransmissions back off for seconds; the ROUTER at the other
  /// end lets the new connection take over our routing id).
  void disconnect(const std::string& endpoint);
  /// Sends without ever blocking: past the high-water mark the message is dropped (the protocol
  /// recovers by fetches, resends and snapshots). False if it was dropped or `endpoint` could
  /// not be connected to.
  bool send(const std::string& endpoint, std::span<const std::uint8_t> bytes);

  /// Closes the DEALERs whose endpoint `keep` rejects, once it has rejected them for `linger`:
  /// a peer taken for dead that was only stalled comes back over the connection it still has.
  template <class Keep>
  void close_departed(Keep&& keep, Clock::time_point now, Clock::duration linger);

  /// Sleeps until a message arrives, a ZAP request (served here), a handshake event (counted
  /// here), wake() or `timeout`.
  void wait(Clock::duration timeout);
  /// The next received message, without waiting; false when there is none. A message of more
  /// than one frame keeps its first payload frame (a well-behaved peer sends one).
  bool receive(Inbound& out);
  /// Wakes wait() from any thread (one byte into a pipe: no lock, no ZeroMQ socket shared).
  void wake();

  /// Connections refused since the last call: by the ZAP handler (a wrong client key) or by
  /// the CURVE handshake itself (a wrong server key, another mechanism, garbage).
  std::uint64_t take_auth_rejected();
  /// Connections closed since the last call before they completed a handshake: clients that
  /// connected and said nothing for kHandshakeTimeout, or hung up midway.
  std::uint64_t take_handshakes_abandoned();

  /// ZMQ_HANDSHAKE_IVL of the ROUTER. A CURVE handshake is three round trips, milliseconds on
  /// a LAN and about 2.2 s at a 400 ms round trip with one lost packet (a 1 s retransmission);
  /// an unauthenticated connection holds a descriptor for no longer than this.
  static constexpr std::chrono::milliseconds kHandshakeTimeout{3000};

 private:
  void serve_zap();

  PeerId self_;
  Invite invite_;             // secrets for every DEALER we make
  CurveKey server_public_{};  // every member's ROUTER has this key
  CurveKey client_public_{};  // the only client key ZAP admits
  std::size_t max_message_bytes_;
  zmq::context_t context_{1};
  zmq::socket_t zap_;                        // inproc ZAP handler: bound before any CURVE socket
  zmq::socket_t router_;                     // where every peer's DEALER sends to us
  std::optional<HandshakeMonitor> monitor_;  // of router_'s handshakes
  std::map<std::string, zmq::socket_t> dealers_;       // endpoint -> our DEALER to it
  std::map<std::string, Clock::time_point> departed_;  // endpoint -> since when `keep` said no
  std::string endpoint_;
  int wake_pipe_[2] = {-1, -1};      // [0] polled by wait(), [1] written by wake()
  std::uint64_t auth_rejected_ = 0;  // by the ZAP handler
};

template <class Keep>
void Transport::close_departed(Keep&& keep, Clock::time_point now, Clock::duration linger) {
  for (auto it = dealers_.begin(); it != dealers_.end();) {
    if (keep(it->first)) {
      departed_.erase(it->first);
      ++it;
      continue;
    }
    const auto since = departed_.try_emplace(it->first, now).first;
    if (now - since->second < linger) {
      ++it;
      continue;
    }
    departed_.erase(since);
    it = dealers_.erase(it);
  }
}

}  // namespace csculpt::peer
