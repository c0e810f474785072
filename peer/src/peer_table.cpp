#include "peer_table.h"

#include <algorithm>
#include <chrono>

namespace csculpt::peer {
namespace {

// Round trips are smoothed like TCP's SRTT: one late heartbeat does not make the panel jump.
constexpr double kSmoothing = 0.25;
constexpr double kLongestRttMs = 60000;

}  // namespace

std::uint64_t micros(Clock::time_point t) {
  return static_cast<std::uint64_t>(
      std::chrono::duration_cast<std::chrono::microseconds>(t.time_since_epoch()).count());
}

void PeerTable::heartbeat_from(PeerId peer, std::uint64_t sent_us, Clock::time_point now) {
  Link& link = links_[peer];
  link.their_sent_us = sent_us;
  link.heard_at = now;
}

std::vector<fb::Echo> PeerTable::echoes(Clock::time_point now) const {
  std::vector<fb::Echo> out;
  for (const auto& [peer, link] : links_)
    if (link.their_sent_us != 0)
      out.emplace_back(peer, link.their_sent_us, micros(now) - micros(link.heard_at));
  return out;
}

void PeerTable::echoed(PeerId peer, const fb::Echo& echo, Clock::time_point now) {
  const double rtt_ms =
      (double(micros(now)) - double(echo.sent_us()) - double(echo.held_us())) / 1000.0;
  if (!(rtt_ms >= 0 && rtt_ms <= kLongestRttMs)) return;
  Link& link = links_[peer];
  link.rtt_ms = link.rtt_ms < 0 ? rtt_ms : link.rtt_ms + kSmoothing * (rtt_ms - link.rtt_ms);
}

void PeerTable::departed(PeerId peer) {
  returned(peer);
  departed_.push_back(peer);
  if (departed_.size() > kKeptDeparted) {
    links_.erase(departed_.front());
    departed_.pop_front();
  }
  Link& link = links_[peer];
  link.their_sent_us = 0;  // nothing to echo to a peer that is gone
  link.rtt_ms = -1;
}

void PeerTable::returned(PeerId peer) {
  departed_.erase(std::remove(departed_.begin(), departed_.end(), peer), departed_.end());
}

PeerInfo PeerTable::info(PeerId peer, PeerState state) const {
  PeerInfo p;
  p.id = peer;
  p.state = state;
  if (auto it = links_.find(peer); it != links_.end()) {
    p.name = it->second.name;
    p.latency_ms = it->second.rtt_ms;
  }
  return p;
}

std::vector<PeerInfo> PeerTable::list(
    const Membership& membership, std::optional<PeerId> merger,
    const std::map<PeerId, std::pair<std::uint64_t, std::uint64_t>>& reported) const {
  std::vector<PeerInfo> out;
  for (const Member* m : membership.others()) {
    PeerInfo p = info(m->id, m->evasive ? PeerState::evasive : PeerState::live);
    p.merger = merger == m->id;
    if (auto r = reported.find(m->id); r != reported.end()) p.version = r->second.first;
    out.push_back(std::move(p));
  }
  for (const PeerId peer : departed_)
    if (!membership.contains(peer)) out.push_back(info(peer, PeerState::left));
  return out;
}

}  // namespace csculpt::peer
