// The C ABI of sessions (csc_session): create, join, submit, update, poll, statistics.
#include <cstring>
#include <new>
#include <string>

#include "capi_internal.h"
#include "csculpt/wire.h"

using namespace csculpt::capi;
using csculpt::InvalidInput;

namespace {

csculpt::peer::SessionOptions session_options(const csc_session_options* in) {
  const csc_session_options defaults = CSC_SESSION_OPTIONS_INIT;
  const csc_session_options o = in ? read_in(in, defaults, "options") : defaults;
  csculpt::peer::SessionOptions so;
  if (o.bind) so.bind = o.bind;
  if (o.name) {
    if (strnlen(o.name, csculpt::max_author_bytes + 1) > csculpt::max_author_bytes)
      bad_argument("options->name is longer than 256 bytes");
    so.name = o.name;
  }
  so.id = o.id;
  // The ranges of these values are the peer layer's to check (peer::validate_options, below):
  // one rule, one message, whichever API the host uses.
  so.sync = csculpt::peer::Millis{o.sync_ms};
  so.membership = {csculpt::peer::Millis{o.heartbeat_ms}, csculpt::peer::Millis{o.evasive_ms},
                   csculpt::peer::Millis{o.expired_ms}};
  so.wire.position_tolerance = o.position_tolerance;
  so.wire.channel_tolerance = o.channel_tolerance;
  if (o.journal_dir) so.journal = o.journal_dir;
  try {
    csculpt::peer::validate_options(so);
  } catch (const InvalidInput& e) {
    bad_argument(e.what());  // the host passed them: an argument error in the C ABI's terms
  }
  return so;
}

std::unique_ptr<csc_session> new_session(std::unique_ptr<csculpt::peer::Session> s) {
  auto h = std::make_unique<csc_session>();
  h->local = s->base();
  h->invite = s->invite();
  h->session = std::move(s);
  return h;
}

}  // namespace

namespace csculpt::capi {

csc_session& live_session(csc_session* s) {
  csc_session& h = handle(s, Tag::session, "session");
  if (h.left) bad_argument("the session was left");
  return h;
}

/// Host arrays -> the mirror (channels given as NULL keep the mirror's values).
void copy_in(const csc_vertex_arrays& a, csculpt::Mesh& m) {
  std::memcpy(static_cast<void*>(m.positions.data()), a.positions, m.positions.size() * 12);
  for (std::size_t c = 0; c < m.channels.size(); ++c)
    if (a.channels[c] != nullptr)
      std::memcpy(m.channels[c].values.data(), a.channels[c],
                  m.channels[c].values.size() * sizeof(float));
}

void copy_out(const csculpt::Mesh& m, const csc_vertex_arrays& a) {
  std::memcpy(a.positions, m.positions.data(), m.positions.size() * 12);
  for (std::size_t c = 0; c < m.channels.size(); ++c)
    if (a.channels[c] != nullptr)
      std::memcpy(a.channels[c], m.channels[c].values.data(),
                  m.channels[c].values.size() * sizeof(float));
}

void copy_in_at(const csc_vertex_arrays& a, std::span<const std::uint32_t> vertices,
                csculpt::Mesh& m) {
  const std::size_t n = m.positions.size();
  for (const std::uint32_t v : vertices) {
    if (v >= n) continue;
    std::memcpy(static_cast<void*>(&m.positions[v]), a.positions + std::size_t{v} * 3, 12);
    for (std::size_t c = 0; c < m.channels.size(); ++c)
      if (a.channels[c] != nullptr) {
        const std::size_t w = m.channels[c].desc.width;
        std::memcpy(m.channels[c].values.data() + v * w, a.channels[c] + v * w, w * 4);
      }
  }
}

void copy_out_at(const csculpt::Mesh& m, std::span<const std::uint32_t> vertices,
                 const csc_vertex_arrays& a) {
  const std::size_t n = m.positions.size();
  for (const std::uint32_t v : vertices) {
    if (v >= n) continue;
    std::memcpy(a.positions + std::size_t{v} * 3, &m.positions[v], 12);
    for (std::size_t c = 0; c < m.channels.size(); ++c)
      if (a.channels[c] != nullptr) {
        const std::size_t w = m.channels[c].desc.width;
        std::memcpy(a.channels[c] + v * w, m.channels[c].values.data() + v * w, w * 4);
      }
  }
}

}  // namespace csculpt::capi

extern "C" {

CSC_API csc_status csc_session_create(csc_session** out, const csc_mesh* mesh,
                                      const csc_session_options* options) {
  return guarded("csc_session_create", [&] {
    require_pointer(out, "out");
    const csculpt::Mesh& m = handle(mesh, Tag::mesh, "mesh").mesh;
    const csculpt::peer::SessionOptions so = session_options(options);
    *out = new_session(csculpt::peer::Session::create(m, so)).release();
  });
}

CSC_API csc_status csc_session_join(csc_session** out, const char* invite,
                                    const csc_session_options* options) {
  return guarded("csc_session_join", [&] {
    require_pointer(out, "out");
    require_pointer(invite, "invite");
    const csc_session_options defaults = CSC_SESSION_OPTIONS_INIT;
    const csc_session_options o = options ? read_in(options, defaults, "options") : defaults;
    const csculpt::peer::SessionOptions so = session_options(options);
    *out = new_session(
               csculpt::peer::Session::join(invite, so, csculpt::peer::Millis{o.join_timeout_ms}))
               .release();
  });
}

CSC_API csc_status csc_session_resume(csc_session** out, csc_mesh** local, const char* journal_dir,
                                      const csc_session_options* options) {
  return guarded("csc_session_resume", [&] {
    require_pointer(out, "out");
    require_pointer(local, "local");
    require_pointer(journal_dir, "journal_dir");
    const csculpt::peer::SessionOptions so = session_options(options);
    auto m = std::make_unique<csc_mesh>();
    std::unique_ptr<csc_session> h =
        new_session(csculpt::peer::Session::resume(journal_dir, m->mesh, so));
    h->local = m->mesh;  // the host's arrays will hold the unmerged edit too
    *out = h.release();
    *local = m.release();
  });
}

CSC_API csc_status csc_session_leave(csc_session* session) {
  return guarded("csc_session_leave", [&] {
    csc_session& h = live_session(session);
    h.session->leave();
    h.left = true;
  });
}

CSC_API void csc_session_destroy(csc_session* session) {
  if (!is(session, Tag::session)) return;
  try {
    session->session->leave();
  } catch (...) {
  }
  destroy(session, Tag::session);
}

CSC_API const char* csc_session_invite(const csc_session* session) {
  return is(session, Tag::session) ? session->invite.c_str() : nullptr;
}
CSC_API uint64_t csc_session_id(const csc_session* session) {
  return is(session, Tag::session) ? session->session->id() : 0;
}
CSC_API uint64_t csc_session_version(const csc_session* session) {
  return is(session, Tag::session) ? session->session->version() : 0;
}

CSC_API csc_status csc_session_copy_base(csc_mesh** out, const csc_session* session) {
  return guarded("csc_session_copy_base", [&] {
    require_pointer(out, "out");
    const csc_session& h = handle(session, Tag::session, "session");
    auto m = std::make_unique<csc_mesh>();
    m->mesh = h.session->base();
    *out = m.release();
  });
}

CSC_API csc_status csc_session_submit(csc_session* session, const csc_vertex_arrays* local,
                                      uint32_t strokes, int32_t* sent) {
  return guarded("csc_session_submit", [&] {
    csc_session& h = live_session(session);
    const csc_vertex_arrays a = host_arrays(local, h.local, "local");
    copy_in(a, h.local);
    // Bad host values (NaN/Inf) are refused before anything is sent or written back.
    const bool did = h.session->submit(h.local, strokes);
    copy_out(h.local, a);
    if (sent) *sent = did ? 1 : 0;
  });
}

namespace {

/// The host's listed vertices (`changed`, `count`), after copying the host's values of them
/// and of the vertices the session keeps as touched into the mirror: the mirror equals the
/// host's arrays but there (the host may have moved those since). They stay in h.synced.
std::span<const std::uint32_t> sync_listed(csc_session& h, const csc_vertex_arrays& a,
                                           const uint32_t* changed, uint32_t count) {
  if (count > 0) require_pointer(changed, "changed");
  const std::span<const std::uint32_t> listed(changed, count);
  const std::span<const std::uint32_t> touched = h.session->touched();
  h.synced.assign(touched.begin(), touched.end());
  h.synced.insert(h.synced.end(), listed.begin(), listed.end());
  copy_in_at(a, h.synced, h.local);
  return listed;
}

}  // namespace

CSC_API csc_status csc_session_submit_changed(csc_session* session, const csc_vertex_arrays* local,
                                              const uint32_t* changed, uint32_t count,
                                              uint32_t strokes, int32_t* sent) {
  return guarded("csc_session_submit_changed", [&] {
    csc_session& h = live_session(session);
    const csc_vertex_arrays a = host_arrays(local, h.local, "local");
    // The session may write the vertices it holds as touched and the listed ones: both are
    // copied in (the host's current values) and, once sent, out.
    const std::span<const std::uint32_t> listed = sync_listed(h, a, changed, count);
    // Bad host values (NaN/Inf) and indices out of range are refused before anything is sent.
    const bool did = h.session->submit(h.local, strokes, listed);
    if (did) copy_out_at(h.local, h.synced, a);
    if (sent) *sent = did ? 1 : 0;
  });
}

CSC_API csc_status csc_session_update(csc_session* session, const csc_vertex_arrays* local,
                                      uint32_t* applied) {
  return guarded("csc_session_update", [&] {
    csc_session& h = live_session(session);
    const csc_vertex_arrays a = host_arrays(local, h.local, "local");
    copy_in(a, h.local);
    const std::size_t n = h.session->update(h.local);
    copy_out(h.local, a);
    if (applied) *applied = static_cast<uint32_t>(n);
  });
}

CSC_API csc_status csc_session_update_changed(csc_session* session, const csc_vertex_arrays* local,
                                              const uint32_t* changed, uint32_t count,
                                              uint32_t* applied) {
  return guarded("csc_session_update_changed", [&] {
    csc_session& h = live_session(session);
    const csc_vertex_arrays a = host_arrays(local, h.local, "local");
    const std::span<const std::uint32_t> listed = sync_listed(h, a, changed, count);
    // Only what the session wrote goes back (all of it after a snapshot or a rebase), also
    // when it failed: the mirror and the host's arrays never part.
    const auto copy_back = [&] {
      if (const auto written = h.session->written())
        copy_out_at(h.local, *written, a);
      else
        copy_out(h.local, a);
    };
    std::size_t n = 0;
    try {
      n = h.session->update(h.local, listed);
    } catch (...) {
      copy_back();
      throw;
    }
    copy_back();
    if (applied) *applied = static_cast<uint32_t>(n);
  });
}

CSC_API csc_status csc_session_poll(csc_session* session, csc_session_event* event,
                                    int32_t* has_event) {
  return guarded("csc_session_poll", [&] {
    csc_session& h = handle(session, Tag::session, "session");
    require_pointer(event, "event");
    require_pointer(has_event, "has_event");
    require_struct_size(event->struct_size, first_published_size<csc_session_event>, "event");
    std::vector<csculpt::peer::Event>& queue = h.pending_events;
    if (queue.empty()) queue = h.session->poll_events();
    if (queue.empty()) {
      *has_event = 0;
      return;
    }
    const csculpt::peer::Event e = std::move(queue.front());
    queue.erase(queue.begin());
    h.event_message = e.message;
    csc_session_event v = CSC_SESSION_EVENT_INIT;
    v.kind = static_cast<csc_event_kind>(static_cast<std::uint32_t>(e.kind));
    v.peer = e.peer;
    v.version = e.version;
    v.epoch = e.epoch;
    v.message = h.event_message.c_str();
    write_out(event, v, "event");
    *has_event = 1;
  });
}

CSC_API csc_status csc_session_get_stats(const csc_session* session, csc_session_stats* out) {
  return guarded("csc_session_get_stats", [&] {
    const csculpt::peer::SessionStats s = handle(session, Tag::session, "session").session->stats();
    csc_session_stats v = CSC_SESSION_STATS_INIT;
    v.id = s.id;
    v.version = s.version;
    v.epoch = s.epoch;
    v.merger = s.merger;
    v.members = s.members;
    v.submits = s.submits;
    v.submit_bytes = s.submit_bytes;
    v.strokes_submitted = s.strokes_submitted;
    v.strokes_acknowledged = s.strokes_acknowledged;
    v.versions_applied = s.versions_applied;
    v.rebases = s.rebases;
    v.merges = s.merges;
    v.merged_strokes = s.merged_strokes;
    v.conflicting_strokes = s.conflicting_strokes;
    v.merge_ms_mean = s.merges ? s.merge_ms_sum / double(s.merges) : 0.0;
    v.merge_ms_max = s.merge_ms_max;
    v.messages_received = s.messages_received;
    v.messages_dropped = s.messages_dropped;
    v.stale_ignored = s.stale_ignored;
    v.auth_rejected = s.auth_rejected;
    v.folds_introduced = s.folds_introduced;
    write_out(out, v, "out");
  });
}

CSC_API csc_status csc_session_attribution_colors(const csc_session* session, float* rgb,
                                                  uint32_t vertex_count) {
  return guarded("csc_session_attribution_colors", [&] {
    const csc_session& h = handle(session, Tag::session, "session");
    require_pointer(rgb, "rgb");
    if (vertex_count != h.local.vertex_count())
      bad_argument("vertex_count is " + std::to_string(vertex_count) + ", the mesh has " +
                   std::to_string(h.local.vertex_count()));
    const std::vector<float> colours =
        csculpt::peer::attribution_colours(h.session->attribution(), vertex_count);
    std::memcpy(rgb, colours.data(), colours.size() * sizeof(float));
  });
}

}  // extern "C"
