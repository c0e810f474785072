#include "presence.h"

#include <algorithm>
#include <cmath>

#include "csculpt/error.h"

namespace csculpt::peer {

void validate_presence(const Presence& p) {
  const char* axes[3] = {"position.x", "position.y", "position.z"};
  const float values[3] = {p.position.x, p.position.y, p.position.z};
  for (int i = 0; i < 3; ++i)
    if (!std::isfinite(values[i]))
      throw InvalidInput(std::string("presence: ") + axes[i] + " is not finite");
  if (!std::isfinite(p.radius)) throw InvalidInput("presence: radius is not finite");
  if (p.radius < 0) throw InvalidInput("presence: radius is negative");
}

Clock::time_point PresenceSender::next_send(bool changed, bool any) const {
  if (!any) return Clock::time_point::max();
  return last_ + (changed ? min_interval_ : refresh_);
}

std::uint64_t PresenceSender::sent(Clock::time_point now) {
  last_ = now;
  return ++sequence_;
}

bool PresenceTable::accept(PeerId peer, std::uint64_t sequence, const Presence& p,
                           Clock::time_point now) {
  auto [it, inserted] = latest_.try_emplace(peer, ReceivedPresence{p, sequence, now});
  if (inserted) return true;
  if (sequence <= it->second.sequence) return false;
  it->second = {p, sequence, now};
  return true;
}

std::array<float, 3> presence_colour(PeerId peer, std::uint32_t rgba,
                                     std::span<const PeerId> contributors,
                                     std::span<const PeerId> members) {
  if ((rgba & 0xffu) != 0)
    return {float(rgba >> 24) / 255.f, float((rgba >> 16) & 0xffu) / 255.f,
            float((rgba >> 8) & 0xffu) / 255.f};
  const auto at = std::lower_bound(contributors.begin(), contributors.end(), peer);
  if (at != contributors.end() && *at == peer)
    return peer_colour(static_cast<std::size_t>(at - contributors.begin()));
  // After the contributors: its rank among the members that have not contributed.
  std::size_t rank = contributors.size();
  for (const PeerId m : members)
    if (m < peer && !std::binary_search(contributors.begin(), contributors.end(), m)) ++rank;
  return peer_colour(rank);
}

}  // namespace csculpt::peer
