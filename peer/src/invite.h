// Invites (csculpt/peer/session.h: format_invite, parse_invite) and the randomness a new
// session and a new peer id come from.
#pragma once

#include <cstdint>

#include "csculpt/peer/session.h"

namespace csculpt::peer {

/// 64 bits from std::random_device (session ids, peer ids, CURVE secrets).
std::uint64_t random_u64();

/// A new session's invite: a random session id and random CURVE secrets; no endpoint yet (the
/// creator's is known once its socket is bound).
Invite new_invite();

}  // namespace csculpt::peer
