#include "transport.h"

#include <arpa/inet.h>
#include <ifaddrs.h>
#include <net/if.h>
#include <netinet/in.h>

#include <fcntl.h>
#include <unistd.h>
#include <zmq.h>

#include <cstring>

#include "csculpt/error.h"
#include "fd_limit.h"

namespace csculpt::peer {
namespace {

/// The first IPv4 address of an interface that is up and not the loopback, or 127.0.0.1.
std::string primary_ipv4() {
  ifaddrs* list = nullptr;
  std::string found = "127.0.0.1";
  if (::getifaddrs(&list) != 0) return found;
  for (const ifaddrs* a = list; a; a = a->ifa_next) {
    if (!a->ifa_addr || a->ifa_addr->sa_family != AF_INET || !(a->ifa_flags & IFF_UP) ||
        (a->ifa_flags & IFF_LOOPBACK))
      continue;
    char text[INET_ADDRSTRLEN] = {};
    const auto* in = reinterpret_cast<const sockaddr_in*>(a->ifa_addr);
    if (::inet_ntop(AF_INET, &in->sin_addr, text, sizeof text)) {
      found = text;
      break;
    }
  }
  ::freeifaddrs(list);
  return found;
}

}  // namespace

/// A socket bound to every interface ("tcp://0.0.0.0:port", what "tcp://*:port" reports) is
/// reached through one of them: the invite and the membership gossip carry that address, not
/// 0.0.0.0, which a joiner on another machine cannot connect to.
std::string advertised_endpoint(const std::string& bound) {
  const std::string wildcard = "tcp://0.0.0.0:";
  if (bound.rfind(wildcard, 0) != 0) return bound;
  return "tcp://" + primary_ipv4() + ":" + bound.substr(wildcard.size());
}

namespace {

constexpr const char* kZapEndpoint = "inproc://zeromq.zap.01";

std::string z85(const CurveKey& key) {
  char out[41];
  zmq_z85_encode(out, key.data(), key.size());
  return out;
}

[[noreturn]] void fail(const std::string& what, const zmq::error_t& e) {
  throw IoError(what + ": " + e.what());
}

}  // namespace

CurveKey curve_public(const CurveKey& secret) {
  char pub[41];
  if (zmq_curve_public(pub, z85(secret).c_str()) != 0)
    throw IoError("CURVE is not available in this libzmq");
  CurveKey out{};
  zmq_z85_decode(out.data(), pub);
  return out;
}

RoutingId routing_id(PeerId id) {
  RoutingId r{'P'};
  for (int i = 0; i < 8; ++i) r[1 + i] = static_cast<std::uint8_t>(id >> (8 * i));
  return r;
}

bool is_routing_id_of(PeerId sender, std::span<const std::uint8_t> routing) {
  const RoutingId rid = routing_id(sender);
  return routing.size() == rid.size() && std::memcmp(routing.data(), rid.data(), rid.size()) == 0;
}

ZapDecision decide_zap(const std::vector<std::string>& request, const CurveKey& client_public) {
  // Frames: version, request id, domain, address, identity, mechanism, credentials...
  ZapDecision d;
  d.accepted = request.size() >= 7 && request[5] == "CURVE" && request[6].size() == 32 &&
               std::memcmp(request[6].data(), client_public.data(), 32) == 0;
  d.reply = {"1.0",
             request.size() > 1 ? request[1] : "",
             d.accepted ? "200" : "400",
             d.accepted ? "OK" : "not a member of this session",
             "",
             ""};
  return d;
}

zmq::socket_t curve_dealer(zmq::context_t& context, const std::string& endpoint,
                           const CurveKey& server_public, const CurveKey& client_secret,
                           const DealerOptions& options) {
  try {
    zmq::socket_t s(context, zmq::socket_type::dealer);
    const CurveKey client_public = curve_public(client_secret);
    s.set(zmq::sockopt::curve_serverkey, zmq::const_buffer(server_public.data(), 32));
    s.set(zmq::sockopt::curve_publickey, zmq::const_buffer(client_public.data(), 32));
    s.set(zmq::sockopt::curve_secretkey, zmq::const_buffer(client_secret.data(), 32));
    s.set(zmq::sockopt::linger, 0);
    s.set(zmq::sockopt::sndhwm, options.send_hwm);
    if (options.routing_id)
      s.set(zmq::sockopt::routing_id,
            zmq::const_buffer(options.routing_id->data(), options.routing_id->size()));
    s.set(zmq::sockopt::maxmsgsize, options.max_message_bytes);
    s.set(zmq::sockopt::connect_timeout, options.connect_timeout_ms);
    s.connect(endpoint);
    return s;
  } catch (const zmq::error_t& e) {
    fail("connecting to '" + endpoint + "'", e);
  }
}

Transport::Transport(const Invite& invite, PeerId self, const std::string& bind,
                     std::size_t max_message_bytes)
    : self_(self), invite_(invite), max_message_bytes_(max_message_bytes) {
  raise_fd_limit();
  require_free_descriptors(kSessionDescriptors);
  server_public_ = curve_public(invite.server_secret);
  client_public_ = curve_public(invite.client_secret);
  if (::pipe(wake_pipe_) != 0) throw IoError("creating the network thread's wake-up pipe failed");
  for (int fd : wake_pipe_) ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) | O_NONBLOCK);
  try {
    // ZAP handler first: CURVE sockets ask it about every connecting client.
    zap_ = zmq::socket_t(context_, zmq::socket_type::rep);
    zap_.bind(kZapEndpoint);
    router_ = zmq::socket_t(context_, zmq::socket_type::router);
    router_.set(zmq::sockopt::curve_server, 1);
    router_.set(zmq::sockopt::curve_secretkey, zmq::const_buffer(invite.server_secret.data(), 32));
    router_.set(zmq::sockopt::zap_domain, "csculpt");
    router_.set(zmq::sockopt::maxmsgsize, static_cast<std::int64_t>(max_message_bytes));
    router_.set(zmq::sockopt::linger, 0);
    router_.set(zmq::sockopt::rcvhwm, 100000);
    router_.set(zmq::sockopt::handshake_ivl, static_cast<int>(kHandshakeTimeout.count()));
    // A member reconnecting (its old connection dead but not yet closed here, as after a
    // partition) is heard at once instead of refused until the old one times out.
    router_.set(zmq::sockopt::router_handover, 1);
    monitor_.emplace(context_, router_);
    router_.bind(bind);
    endpoint_ = advertised_endpoint(router_.get(zmq::sockopt::last_endpoint));
  } catch (const zmq::error_t& e) {
    for (int fd : wake_pipe_) ::close(fd);
    fail("binding the session's socket to '" + bind + "'", e);
  }
}

Transport::~Transport() {
  for (int fd : wake_pipe_)
    if (fd >= 0) ::close(fd);
}

void Transport::connect(const std::string& endpoint) {
  if (dealers_.count(endpoint)) return;
  const RoutingId rid = routing_id(self_);
  DealerOptions o;
  o.routing_id = &rid;
  o.max_message_bytes = static_cast<std::int64_t>(max_message_bytes_);
  o.send_hwm = 10000;
  dealers_.emplace(endpoint,
                   curve_dealer(context_, endpoint, server_public_, invite_.client_secret, o));
}

void Transport::disconnect(const std::string& endpoint) {
  dealers_.erase(endpoint);
  departed_.erase(endpoint);
}

bool Transport::send(const std::string& endpoint, std::span<const std::uint8_t> bytes) {
  try {
    connect(endpoint);
    return dealers_.at(endpoint)
        .send(zmq::const_buffer(bytes.data(), bytes.size()), zmq::send_flags::dontwait)
        .has_value();
  } catch (const IoError&) {
    return false;  // an endpoint a peer gave us that ZeroMQ refuses: as if unreachable
  } catch (const zmq::error_t&) {
    return false;
  }
}

void Transport::wait(Clock::duration timeout) {
  zmq::pollitem_t items[] = {{router_.handle(), 0, ZMQ_POLLIN, 0},
                             {zap_.handle(), 0, ZMQ_POLLIN, 0},
                             {nullptr, wake_pipe_[0], ZMQ_POLLIN, 0},
                             {monitor_->handle(), 0, ZMQ_POLLIN, 0}};
  const auto ms =
      std::chrono::ceil<std::chrono::milliseconds>(std::max(Clock::duration::zero(), timeout));
  try {
    zmq::poll(items, 4, ms);
  } catch (const zmq::error_t& e) {
    if (e.num() == EINTR) return;
    fail("waiting for messages", e);
  }
  if (items[1].revents & ZMQ_POLLIN) serve_zap();
  if (items[3].revents & ZMQ_POLLIN) monitor_->drain();
  if (items[2].revents & ZMQ_POLLIN) {
    char drain[64];
    while (::read(wake_pipe_[0], drain, sizeof drain) > 0) {
    }
  }
}

bool Transport::receive(Inbound& out) {
  try {
    while (true) {
      if (!router_.recv(out.routing, zmq::recv_flags::dontwait)) return false;
      if (!out.routing.more()) continue;
      if (!router_.recv(out.payload, zmq::recv_flags::dontwait)) return false;
      while (out.payload.more()) {
        zmq::message_t extra;
        if (!router_.recv(extra, zmq::recv_flags::dontwait)) break;
      }
      return true;
    }
  } catch (const zmq::error_t& e) {
    fail("receiving a message", e);
  }
}

void Transport::wake() {
  const char byte = 1;
  (void)!::write(wake_pipe_[1], &byte, 1);  // a full pipe already wakes the thread
}

std::uint64_t Transport::take_auth_rejected() {
  const std::uint64_t n = auth_rejected_ + monitor_->take_rejected();
  auth_rejected_ = 0;
  return n;
}

std::uint64_t Transport::take_handshakes_abandoned() {
  return monitor_->take_abandoned();
}

void Transport::serve_zap() {
  try {
    std::vector<std::string> request;
    while (true) {
      zmq::message_t f;
      if (!zap_.recv(f, zmq::recv_flags::dontwait)) break;
      request.push_back(f.to_string());
      if (!f.more()) break;
    }
    if (request.size() < 6) return;
    const ZapDecision d = decide_zap(request, client_public_);
    if (!d.accepted) ++auth_rejected_;
    for (std::size_t i = 0; i < d.reply.size(); ++i)
      zap_.send(zmq::buffer(d.reply[i]),
                i + 1 < d.reply.size() ? zmq::send_flags::sndmore : zmq::send_flags::none);
  } catch (const zmq::error_t& e) {
    fail("answering a ZAP request", e);
  }
}

}  // namespace csculpt::peer
