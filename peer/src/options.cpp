// SessionOptions checked by the layer that owns them: every way into a session (C++, the C ABI,
// the CLI) gets the same clear errors.
#include <cmath>
#include <sstream>
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

void check_tolerance(const char* name, double value, double most, const char* unit) {
  if (std::isfinite(value) && value >= 0 && value <= most) return;
  std::ostringstream m;
  m << name << " is " << value << "; it must be 0 (lossless) to " << most << " (" << unit << ")";
  bad(m.str());
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
  // Coarser steps would erase strokes while the session counts them acknowledged: a stroke
  // smaller than the step rounds to nothing on the wire.
  check_tolerance("wire.position_tolerance", o.wire.position_tolerance, 0.01,
                  "a fraction of the session's bounding-box diagonal");
  check_tolerance("wire.channel_tolerance", o.wire.channel_tolerance, 0.05,
                  "in the channel's stored units; an 8-bit colour step is 0.004");
  check_tolerance("wire.position_scale", o.wire.position_scale, 1e30,
                  "the length the position tolerance is a fraction of; 0: the diagonal");
  if (o.max_message_bytes < (std::size_t{64} << 10))
    bad("max_message_bytes is " + std::to_string(o.max_message_bytes) + "; at least 65536");
  // Every chunk travels in one message with its envelope (well under 4 KiB).
  if (o.snapshot_chunk_bytes < 1024 || o.snapshot_chunk_bytes > o.max_message_bytes - 4096)
    bad("snapshot_chunk_bytes is " + std::to_string(o.snapshot_chunk_bytes) +
        "; it must be 1024 to max_message_bytes - 4096");
  if (o.max_snapshot_bytes == 0) bad("max_snapshot_bytes is 0");
  if (o.journal_max_log_versions == 0) bad("journal_max_log_versions is 0");
}

}  // namespace csculpt::peer
