// SessionOptions checked by the layer that owns them: every way into a session (C++, the C ABI,
// the CLI) gets the same clear errors.
#include <cmath>
#include <string>

#include "csculpt/error.h"
#include "csculpt/peer/session.h"
#include "csculpt/wire.h"

namespace csculpt::peer {
namespace {

constexpr Millis kLongest{60 * 60 * 1000};  // an hour: beyond it no session is interactive

[[noreturn]] void bad(const std::string& what) {
  throw InvalidInput("session options: " + what);
}

std::string ms(Millis m) {
  return std::to_string(m.count()) + " ms";
}

void check_interval(const char* name, Millis value) {
  if (value < Millis{1} || value > kLongest)
    bad(std::string(name) + " is " + ms(value) + "; it must be 1 ms to 1 hour");
}

void check_tolerance(const char* name, double value, double most) {
  if (!std::isfinite(value) || value < 0 || value > most)
    bad(std::string(name) + " is " + std::to_string(value) + "; it must be finite, 0 to " +
        std::to_string(most));
}

}  // namespace

void validate_options(const SessionOptions& o) {
  if (o.bind.empty()) bad("bind is empty; it must be a ZeroMQ endpoint such as tcp://127.0.0.1:*");
  if (o.name.size() > max_author_bytes)
    bad("name has " + std::to_string(o.name.size()) + " bytes; at most " +
        std::to_string(max_author_bytes));
  check_interval("sync", o.sync);
  const MembershipOptions& m = o.membership;
  check_interval("membership.heartbeat", m.heartbeat);
  check_interval("membership.expired", m.expired);
  if (!(m.heartbeat < m.evasive && m.evasive < m.expired))
    bad("membership needs heartbeat < evasive < expired (" + ms(m.heartbeat) + ", " +
        ms(m.evasive) + ", " + ms(m.expired) + ")");
  // A fraction of the session's frame: above 1 a change the size of the mesh could vanish.
  check_tolerance("wire.position_tolerance", o.wire.position_tolerance, 1.0);
  check_tolerance("wire.channel_tolerance", o.wire.channel_tolerance, 1e30);
  check_tolerance("wire.position_scale", o.wire.position_scale, 1e30);
  if (o.max_message_bytes < (std::size_t{64} << 10))
    bad("max_message_bytes is " + std::to_string(o.max_message_bytes) + "; at least 65536");
  // Every chunk travels in one message with its envelope (well under 4 KiB).
  if (o.snapshot_chunk_bytes < 1024 || o.snapshot_chunk_bytes > o.max_message_bytes - 4096)
    bad("snapshot_chunk_bytes is " + std::to_string(o.snapshot_chunk_bytes) +
        "; it must be 1024 to max_message_bytes - 4096");
  if (o.max_snapshot_bytes == 0) bad("max_snapshot_bytes is 0");
}

}  // namespace csculpt::peer
