// The C ABI of a session's presence (brush cursors) and its peer list: set, snapshot, read.
#include <algorithm>
#include <cstdint>
#include <string>

#include "capi_internal.h"

using namespace csculpt::capi;
using csculpt::InvalidInput;
namespace peer = csculpt::peer;

namespace {

peer::Presence presence_in(const csc_presence* in) {
  const csc_presence defaults = CSC_PRESENCE_INIT;
  const csc_presence p = read_in(in, defaults, "presence");
  peer::Presence out;
  out.position = {p.position[0], p.position[1], p.position[2]};
  out.radius = p.radius;
  out.active = p.active != 0;
  out.visible = p.visible != 0;
  out.rgba = p.rgba;
  try {
    peer::validate_presence(out);
  } catch (const InvalidInput& e) {
    bad_argument(e.what());  // the host's own values: an argument error in the C ABI's terms
  }
  return out;
}

csc_presence presence_out(const peer::PeerPresence& p) {
  csc_presence v = CSC_PRESENCE_INIT;
  v.peer = p.peer;
  v.position[0] = p.presence.position.x;
  v.position[1] = p.presence.position.y;
  v.position[2] = p.presence.position.z;
  v.radius = p.presence.radius;
  v.active = p.presence.active ? 1 : 0;
  v.visible = p.presence.visible ? 1 : 0;
  v.rgba = p.presence.rgba;
  v.age_ms = static_cast<uint32_t>(std::clamp<long long>(p.age.count(), 0, UINT32_MAX));
  std::copy(p.colour.begin(), p.colour.end(), v.colour);
  return v;
}

template <class T>
const T& entry(const std::vector<T>& snapshot, uint32_t index, const char* count_function) {
  if (index >= snapshot.size())
    bad_argument("index " + std::to_string(index) + " is past the " +
                 std::to_string(snapshot.size()) + " entries " + count_function + " gave");
  return snapshot[index];
}

/// A *_count call: `take(handle)` refreshes one of the handle's snapshots and gives its size.
template <class Take>
csc_status take_snapshot(const char* function, csc_session* session, uint32_t* count, Take&& take) {
  return guarded(function, [&] {
    csc_session& h = handle(session, Tag::session, "session");
    require_pointer(count, "count");
    *count = static_cast<uint32_t>(take(h));
  });
}

}  // namespace

extern "C" {

CSC_API csc_status csc_session_set_presence(csc_session* session, const csc_presence* presence) {
  return guarded("csc_session_set_presence", [&] {
    csc_session& h = handle(session, Tag::session, "session");
    if (h.left) bad_argument("the session was left");
    h.session->set_presence(presence_in(presence));
  });
}

CSC_API csc_status csc_session_presence_count(csc_session* session, uint32_t* count) {
  return take_snapshot("csc_session_presence_count", session, count, [](csc_session& h) {
    h.presence = h.session->presence();
    return h.presence.size();
  });
}

CSC_API csc_status csc_session_get_presence(const csc_session* session, uint32_t index,
                                            csc_presence* out) {
  return guarded("csc_session_get_presence", [&] {
    const csc_session& h = handle(session, Tag::session, "session");
    const csc_presence v = presence_out(entry(h.presence, index, "csc_session_presence_count"));
    write_out(out, v, "out");
  });
}

CSC_API csc_status csc_session_peer_count(csc_session* session, uint32_t* count) {
  return take_snapshot("csc_session_peer_count", session, count, [](csc_session& h) {
    h.peers = h.session->peers();
    return h.peers.size();
  });
}

CSC_API csc_status csc_session_get_peer(const csc_session* session, uint32_t index,
                                        csc_peer_info* out) {
  return guarded("csc_session_get_peer", [&] {
    const csc_session& h = handle(session, Tag::session, "session");
    const peer::PeerInfo& p = entry(h.peers, index, "csc_session_peer_count");
    csc_peer_info v = CSC_PEER_INFO_INIT;
    v.id = p.id;
    v.name = p.name.c_str();
    v.state = static_cast<csc_peer_state>(static_cast<std::uint32_t>(p.state));
    v.merger = p.merger ? 1 : 0;
    v.version = p.version;
    v.latency_ms = p.latency_ms;
    write_out(out, v, "out");
  });
}

}  // extern "C"
