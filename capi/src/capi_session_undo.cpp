// The C ABI of undo inside a session: record a stroke, undo, redo (csculpt::peer::Session's
// per-artist undo; peer/src/undo_stack.h says how it merges).
#include <span>

#include "capi_internal.h"

using namespace csculpt::capi;

namespace {

using Step = bool (csculpt::peer::Session::*)(csculpt::Mesh&, std::vector<std::uint32_t>&);

void run_step(csc_session* session, const csc_vertex_arrays* local, const uint32_t** changed,
              uint32_t* changed_count, Step step) {
  csc_session& h = live_session(session);
  require_pointer(changed_count, "changed_count");
  const csc_vertex_arrays a = host_arrays(local, h.local, "local");
  copy_in(a, h.local);
  if (!((*h.session).*step)(h.local, h.changed)) h.changed.clear();
  copy_out(h.local, a);
  *changed_count = static_cast<uint32_t>(h.changed.size());
  if (changed) *changed = h.changed.data();
}

}  // namespace

extern "C" {

CSC_API csc_status csc_session_record_stroke(csc_session* session, const csc_vertex_arrays* local,
                                             const uint32_t* vertices, uint32_t count,
                                             const float* before) {
  return guarded("csc_session_record_stroke", [&] {
    csc_session& h = live_session(session);
    const csc_vertex_arrays a = host_arrays(local, h.local, "local");
    if (count > 0) {
      require_pointer(vertices, "vertices");
      require_pointer(before, "before");
    }
    std::size_t stride = 3;
    for (const csculpt::Channel& c : h.local.channels) stride += c.desc.width;
    copy_in(a, h.local);
    h.session->record_stroke(h.local, std::span<const uint32_t>(vertices, count),
                             std::span<const float>(before, std::size_t{count} * stride));
  });
}

CSC_API csc_status csc_session_undo(csc_session* session, const csc_vertex_arrays* local,
                                    const uint32_t** changed, uint32_t* changed_count) {
  return guarded("csc_session_undo", [&] {
    run_step(session, local, changed, changed_count, &csculpt::peer::Session::undo);
  });
}

CSC_API csc_status csc_session_redo(csc_session* session, const csc_vertex_arrays* local,
                                    const uint32_t** changed, uint32_t* changed_count) {
  return guarded("csc_session_redo", [&] {
    run_step(session, local, changed, changed_count, &csculpt::peer::Session::redo);
  });
}

CSC_API csc_status csc_session_undo_depth(const csc_session* session, uint32_t* undo,
                                          uint32_t* redo) {
  return guarded("csc_session_undo_depth", [&] {
    const csc_session& h = handle(session, Tag::session, "session");
    if (undo) *undo = static_cast<uint32_t>(h.session->undo_depth());
    if (redo) *redo = static_cast<uint32_t>(h.session->redo_depth());
  });
}

}  // extern "C"
