// The process's open-file limit, raised for a peer that accepts connections from anyone.
#pragma once

namespace csculpt::peer {

/// Raises the soft RLIMIT_NOFILE to the hard one, once per process (later calls do nothing):
/// libzmq has no cap on the connections a listener accepts, so unauthenticated clients that
/// connect and say nothing hold a descriptor each until the handshake times out, and the
/// usual soft limit of 1024 would let a thousand of them keep members out. Failure is not an
/// error: the peer then runs with the limit it was given.
void raise_fd_limit();

}  // namespace csculpt::peer
