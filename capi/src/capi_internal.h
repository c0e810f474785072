// What the C ABI's source files share (not installed): the handles behind the header's opaque
// types, the mapping of exceptions to csc_status, and the checks of a caller's arguments.
// Every entry point catches everything and maps it to a csc_status with a thread-local message;
// no exception or C++ type crosses.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "csculpt.h"
#include "csculpt/diff.h"
#include "csculpt/error.h"
#include "csculpt/hierarchy.h"
#include "csculpt/merge.h"
#include "csculpt/mesh.h"
#include "csculpt/peer/session.h"

namespace csculpt::capi {

// Each handle starts with a tag, so a handle of another kind is refused instead of misread.
// Destroy clears it, which helps catch some double destroys; a destroyed handle is still
// undefined behaviour to pass (the header says so).
enum class Tag : std::uint32_t {
  dead = 0,
  mesh = 0x4d455348,       // "MESH"
  hierarchy = 0x48494552,  // "HIER"
  diff = 0x44494646,       // "DIFF"
  merger = 0x4d524752,     // "MRGR"
  bytes = 0x42595445,      // "BYTE"
  session = 0x53455353,    // "SESS"
};

}  // namespace csculpt::capi

struct csc_mesh {
  csculpt::capi::Tag tag = csculpt::capi::Tag::mesh;
  csculpt::Mesh mesh;
};
struct csc_hierarchy {
  csculpt::capi::Tag tag = csculpt::capi::Tag::hierarchy;
  csculpt::Hierarchy hierarchy;
};
struct csc_diff {
  csculpt::capi::Tag tag = csculpt::capi::Tag::diff;
  csculpt::Diff diff;
  std::string author;  // of a decoded message (csc_message_info::author points here)
};
struct csc_merger {
  csculpt::capi::Tag tag = csculpt::capi::Tag::merger;
  explicit csc_merger(const csculpt::Hierarchy& h) : merger(h) {}
  csculpt::Merger merger;
};
struct csc_bytes {
  csculpt::capi::Tag tag = csculpt::capi::Tag::bytes;
  std::vector<std::uint8_t> data;
};
struct csc_session {
  csculpt::capi::Tag tag = csculpt::capi::Tag::session;
  std::unique_ptr<csculpt::peer::Session> session;
  csculpt::Mesh local;  // mirror of the host's arrays between calls
  std::string invite;
  std::string event_message;  // of the last polled event
  std::vector<csculpt::peer::Event> pending_events;
  std::vector<std::uint32_t> changed;  // of the last undo or redo
  std::vector<std::uint32_t> synced;   // scratch: the vertices a changed-only submit copies
  // the snapshots csc_session_presence_count and csc_session_peer_count took
  std::vector<csculpt::peer::PeerPresence> presence;
  std::vector<csculpt::peer::PeerInfo> peers;
  bool left = false;
};

namespace csculpt::capi {

// ---- Errors (capi_errors.cpp) -------------------------------------------------------------

/// A bad argument (NULL, wrong struct_size, foreign handle): CSC_ERROR_INVALID_ARGUMENT.
struct ArgumentError {
  std::string message;
};
/// A diff message for another base version: CSC_ERROR_UNKNOWN_BASE_VERSION.
struct BaseVersionError {
  std::string message;
};

/// Keeps `message` as this thread's csc_last_error() and returns `status`.
csc_status fail(csc_status status, std::string message);

/// Runs `body` (which returns nothing and throws on failure) and maps what it throws.
template <class Body>
csc_status guarded(const char* function, Body&& body) noexcept {
  try {
    body();
    return CSC_OK;
  } catch (const ArgumentError& e) {
    return fail(CSC_ERROR_INVALID_ARGUMENT, std::string(function) + ": " + e.message);
  } catch (const BaseVersionError& e) {
    return fail(CSC_ERROR_UNKNOWN_BASE_VERSION, std::string(function) + ": " + e.message);
  } catch (const InvalidInput& e) {
    return fail(CSC_ERROR_INVALID_INPUT, std::string(function) + ": " + e.what());
  } catch (const IoError& e) {
    return fail(CSC_ERROR_IO, std::string(function) + ": " + e.what());
  } catch (const OutOfMemory& e) {
    return fail(CSC_ERROR_OUT_OF_MEMORY, std::string(function) + ": " + e.what());
  } catch (const std::bad_alloc&) {
    return fail(CSC_ERROR_OUT_OF_MEMORY, std::string(function) + ": out of memory");
  } catch (const std::exception& e) {
    return fail(CSC_ERROR_INTERNAL, std::string(function) + ": internal error: " + e.what());
  } catch (...) {
    return fail(CSC_ERROR_INTERNAL, std::string(function) + ": internal error");
  }
}

[[noreturn]] void bad_argument(std::string message);

// ---- Arguments and handles (capi_arguments.cpp) -------------------------------------------

template <class T>
void require_pointer(const T* p, const char* name) {
  if (p == nullptr) bad_argument(std::string(name) + " is NULL");
}

template <class Handle>
bool is(const Handle* h, Tag tag) {
  return h != nullptr && h->tag == tag;
}

template <class Handle>
Handle& handle(Handle* h, Tag tag, const char* name) {
  if (h == nullptr) bad_argument(std::string(name) + " is NULL");
  if (h->tag != tag) bad_argument(std::string(name) + " is not a handle of the right kind");
  return *h;
}

template <class Handle>
void destroy(Handle* h, Tag tag) noexcept {
  if (h == nullptr || h->tag != tag) return;
  h->tag = Tag::dead;
  delete h;
}

/// The size of a struct's first published layout (ABI 0.2): the least a caller's struct_size
/// may say. When a struct grows, specialise this with its old size so older hosts keep working.
template <class T>
inline constexpr std::size_t first_published_size = sizeof(T);
/// csc_session_options grew journal_dir in 0.4. (`inline`: an explicit specialisation is not
/// implicitly so, and every file including this one would define it.)
template <>
inline constexpr std::size_t first_published_size<csc_session_options> =
    offsetof(csc_session_options, journal_dir);
/// csc_session_stats grew folds_introduced in 0.5.
template <>
inline constexpr std::size_t first_published_size<csc_session_stats> = offsetof(csc_session_stats,
                                                                                folds_introduced);

void require_struct_size(std::uint32_t declared, std::size_t minimum, const char* name);

/// Reads an input struct: fields past the caller's struct_size (a host built against an older
/// header) keep `defaults`; fields past ours (a newer host) are not read.
template <class T>
T read_in(const T* in, const T& defaults, const char* name) {
  require_pointer(in, name);
  require_struct_size(in->struct_size, first_published_size<T>, name);
  T value = defaults;
  std::memcpy(static_cast<void*>(&value), in, std::min<std::size_t>(in->struct_size, sizeof(T)));
  value.struct_size = sizeof(T);
  return value;
}

/// Writes an output struct: at most the caller's declared size (which must cover the first
/// published layout); the caller's struct_size is kept.
template <class T>
void write_out(T* out, const T& value, const char* name) {
  require_pointer(out, name);
  require_struct_size(out->struct_size, first_published_size<T>, name);
  const std::uint32_t size = out->struct_size;
  std::memcpy(static_cast<void*>(out), &value, std::min<std::size_t>(size, sizeof(T)));
  out->struct_size = size;
}

Linearisation to_linearisation(csc_linearisation lin);
csc_linearisation from_linearisation(Linearisation lin);

/// A mesh's positions as the flat float array the header shows.
std::span<const float> floats(const std::vector<Vec3f>& v);

/// The host's arrays, checked against the base mesh's layout.
csc_vertex_arrays host_arrays(const csc_vertex_arrays* in, const Mesh& base, const char* name);

std::unique_ptr<csc_diff> new_diff(Diff d);

// ---- Sessions (capi_session.cpp) ----------------------------------------------------------

/// The session behind `s`, refused (argument error) once left.
csc_session& live_session(csc_session* s);
/// Host arrays -> the mirror (channels given as NULL keep the mirror's values).
void copy_in(const csc_vertex_arrays& a, Mesh& m);
/// The mirror -> host arrays (channels given as NULL are not written).
void copy_out(const Mesh& m, const csc_vertex_arrays& a);
/// The same for the listed vertices only; indices out of range are skipped (the session
/// refuses them with its own message).
void copy_in_at(const csc_vertex_arrays& a, std::span<const std::uint32_t> vertices, Mesh& m);
void copy_out_at(const Mesh& m, std::span<const std::uint32_t> vertices,
                 const csc_vertex_arrays& a);

}  // namespace csculpt::capi
