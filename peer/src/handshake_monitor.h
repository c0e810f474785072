// Counts the ROUTER's connections that never completed a handshake, from libzmq's socket
// monitor: those the ZAP handler refused are counted where it answers, but a client with the
// wrong server key, another mechanism or garbage bytes fails before ZAP is asked, and a client
// that connects and says nothing is only dropped when ZMQ_HANDSHAKE_IVL runs out.
#pragma once

#include <cstdint>
#include <utility>
#include <zmq.hpp>

namespace csculpt::peer {

/// Connections that failed their handshake, by cause.
struct HandshakeCounts {
  std::uint64_t rejected = 0;   ///< a protocol failure: wrong CURVE keys, mechanism, garbage
  std::uint64_t abandoned = 0;  ///< closed or timed out before the handshake completed
};

/// Adds what a monitor event (ZMQ_EVENT_*) says to `counts`. ZMQ_EVENT_HANDSHAKE_FAILED_AUTH
/// adds nothing: it follows a ZAP denial, which the ZAP handler has counted already.
void count_handshake_event(std::uint16_t event, HandshakeCounts& counts);

class HandshakeMonitor {
 public:
  /// Starts monitoring `watched` (before it binds, so no connection is missed) into an inproc
  /// PAIR of `context`. Throws zmq::error_t.
  HandshakeMonitor(zmq::context_t& context, zmq::socket_t& watched);

  /// The PAIR socket, for zmq_poll.
  void* handle() { return pair_.handle(); }
  /// Reads the events waiting, without blocking, into the counts.
  void drain();
  /// Protocol failures since the last call.
  std::uint64_t take_rejected() { return std::exchange(counts_.rejected, 0); }
  /// Abandoned handshakes since the last call.
  std::uint64_t take_abandoned() { return std::exchange(counts_.abandoned, 0); }

 private:
  zmq::socket_t pair_;
  HandshakeCounts counts_;
};

}  // namespace csculpt::peer
