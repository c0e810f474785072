#include "handshake_monitor.h"

#include <zmq.h>

#include <cstring>

namespace csculpt::peer {
namespace {

// One per context, and every Transport has a context of its own.
constexpr const char* kMonitorEndpoint = "inproc://csculpt.router-monitor";

}  // namespace

void count_handshake_event(std::uint16_t event, HandshakeCounts& counts) {
  switch (event) {
    case ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL:
      ++counts.rejected;
      break;
    case ZMQ_EVENT_HANDSHAKE_FAILED_NO_DETAIL:
      ++counts.abandoned;
      break;
    default:
      break;
  }
}

HandshakeMonitor::HandshakeMonitor(zmq::context_t& context, zmq::socket_t& watched) {
  const int events = ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL | ZMQ_EVENT_HANDSHAKE_FAILED_NO_DETAIL;
  if (zmq_socket_monitor(watched.handle(), kMonitorEndpoint, events) != 0) throw zmq::error_t();
  pair_ = zmq::socket_t(context, zmq::socket_type::pair);
  pair_.set(zmq::sockopt::linger, 0);
  pair_.connect(kMonitorEndpoint);
}

void HandshakeMonitor::drain() {
  // Each event is two frames: 6 bytes (a uint16 event and a uint32 value, native byte order)
  // and the peer's address.
  while (true) {
    zmq::message_t head;
    if (!pair_.recv(head, zmq::recv_flags::dontwait)) return;
    std::uint16_t event = 0;
    if (head.size() >= sizeof event) std::memcpy(&event, head.data(), sizeof event);
    for (bool more = head.more(); more;) {
      zmq::message_t rest;
      if (!pair_.recv(rest, zmq::recv_flags::dontwait)) break;
      more = rest.more();
    }
    count_handshake_event(event, counts_);
  }
}

}  // namespace csculpt::peer
