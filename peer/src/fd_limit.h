// The process's open-file limit: raised for a peer that accepts connections from anyone, and
// checked before a session opens its sockets.
#pragma once

#include <cstddef>

namespace csculpt::peer {

/// Raises the soft RLIMIT_NOFILE to the hard one, once per process (later calls do nothing):
/// libzmq has no cap on the connections a listener accepts, so unauthenticated clients that
/// connect and say nothing hold a descriptor each until the handshake times out, and the
/// usual soft limit of 1024 would let a thousand of them keep members out. Failure is not an
/// error: the peer then runs with the limit it was given.
void raise_fd_limit();

/// Descriptors a session needs free when it starts: libzmq's threads and mailboxes, the
/// session's sockets, and two connections per member for a session of a dozen.
inline constexpr std::size_t kSessionDescriptors = 64;

/// Throws IoError saying what to do when fewer than `needed` descriptors are free under the
/// soft open-file limit: libzmq aborts the process when it cannot open its own (at a limit of
/// 8), and a listener that cannot accept refuses every joiner without a word (at 16). Does
/// nothing where the open descriptors cannot be counted (no /proc).
void require_free_descriptors(std::size_t needed);

}  // namespace csculpt::peer
