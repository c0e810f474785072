// The invite text: "csculpt1:" + session id, server secret and client secret in hex + "@" +
// a member's endpoint. Whoever holds it is a member (it carries the CURVE secrets).
#include "invite.h"

#include <random>
#include <string_view>

#include "csculpt/error.h"

namespace csculpt::peer {
namespace {

constexpr std::string_view kPrefix = "csculpt1:";
constexpr std::size_t kKeyDigits = 2 * (8 + 32 + 32);

std::string hex(const std::uint8_t* p, std::size_t n) {
  static const char* digits = "0123456789abcdef";
  std::string s;
  for (std::size_t i = 0; i < n; ++i) {
    s += digits[p[i] >> 4];
    s += digits[p[i] & 15];
  }
  return s;
}

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

bool unhex(std::string_view s, std::uint8_t* out, std::size_t n) {
  if (s.size() != 2 * n) return false;
  for (std::size_t i = 0; i < n; ++i) {
    const int hi = hex_value(s[2 * i]), lo = hex_value(s[2 * i + 1]);
    if (hi < 0 || lo < 0) return false;
    out[i] = static_cast<std::uint8_t>(hi * 16 + lo);
  }
  return true;
}

bool has_prefix(const std::string& s, std::string_view prefix) {
  return s.rfind(prefix, 0) == 0;
}

}  // namespace

std::uint64_t random_u64() {
  std::random_device rd;
  return (std::uint64_t{rd()} << 32) ^ rd();
}

Invite new_invite() {
  Invite invite;
  invite.session = random_u64();
  for (auto& b : invite.server_secret) b = static_cast<std::uint8_t>(random_u64());
  for (auto& b : invite.client_secret) b = static_cast<std::uint8_t>(random_u64());
  return invite;
}

std::string format_invite(const Invite& invite) {
  std::uint8_t session[8];
  for (int i = 0; i < 8; ++i)
    session[i] = static_cast<std::uint8_t>(invite.session >> (56 - 8 * i));
  return std::string(kPrefix) + hex(session, 8) + hex(invite.server_secret.data(), 32) +
         hex(invite.client_secret.data(), 32) + "@" + invite.endpoint;
}

Invite parse_invite(const std::string& text) {
  if (!has_prefix(text, kPrefix))
    throw InvalidInput("invite does not start with '" + std::string(kPrefix) + "'");
  const std::size_t at = text.find('@');
  if (at == std::string::npos) throw InvalidInput("invite has no '@<endpoint>'");
  const std::string_view keys(text.data() + kPrefix.size(), at - kPrefix.size());
  if (keys.size() != kKeyDigits)
    throw InvalidInput("invite key part has " + std::to_string(keys.size()) +
                       " hex digits, 144 expected");
  Invite inv;
  std::uint8_t session[8];
  if (!unhex(keys.substr(0, 16), session, 8) ||
      !unhex(keys.substr(16, 64), inv.server_secret.data(), 32) ||
      !unhex(keys.substr(80, 64), inv.client_secret.data(), 32))
    throw InvalidInput("invite key part is not hexadecimal");
  for (int i = 0; i < 8; ++i) inv.session = (inv.session << 8) | session[i];
  inv.endpoint = text.substr(at + 1);
  if (!has_prefix(inv.endpoint, "tcp://") && !has_prefix(inv.endpoint, "ipc://") &&
      !has_prefix(inv.endpoint, "inproc://"))
    throw InvalidInput("invite endpoint '" + inv.endpoint + "' is not tcp://, ipc:// or inproc://");
  return inv;
}

}  // namespace csculpt::peer
