// Invites: round trip, and each way a text can be malformed rejected with InvalidInput.
#include <gtest/gtest.h>

#include <set>

#include "csculpt/error.h"
#include "invite.h"

namespace {

using namespace csculpt;
using namespace csculpt::peer;

Invite sample() {
  Invite inv;
  inv.endpoint = "tcp://127.0.0.1:5555";
  inv.session = 0x0123456789abcdefull;
  for (std::size_t i = 0; i < 32; ++i) {
    inv.server_secret[i] = static_cast<std::uint8_t>(i);
    inv.client_secret[i] = static_cast<std::uint8_t>(255 - i);
  }
  return inv;
}

TEST(InviteText, HasTheDocumentedShape) {
  const std::string text = format_invite(sample());
  EXPECT_EQ(text.rfind("csculpt1:0123456789abcdef000102", 0), 0u);
  EXPECT_EQ(text.size(), 9 + 144 + 1 + std::string("tcp://127.0.0.1:5555").size());
  EXPECT_EQ(text.substr(text.find('@')), "@tcp://127.0.0.1:5555");
}

TEST(InviteText, RoundTripsEveryEndpointKind) {
  for (const char* endpoint : {"tcp://10.0.0.1:1", "ipc:///tmp/s", "inproc://x"}) {
    Invite inv = sample();
    inv.endpoint = endpoint;
    const Invite back = parse_invite(format_invite(inv));
    EXPECT_EQ(back.endpoint, inv.endpoint);
    EXPECT_EQ(back.session, inv.session);
    EXPECT_EQ(back.server_secret, inv.server_secret);
    EXPECT_EQ(back.client_secret, inv.client_secret);
  }
}

TEST(InviteText, AcceptsUpperCaseHex) {
  std::string text = format_invite(sample());
  for (std::size_t i = 9; i < text.find('@'); ++i)
    text[i] = static_cast<char>(std::toupper(static_cast<unsigned char>(text[i])));
  EXPECT_EQ(parse_invite(text).session, sample().session);
}

TEST(InviteText, RejectsMalformedText) {
  const std::string text = format_invite(sample());
  const std::string keys = text.substr(0, text.find('@'));
  auto message = [](const std::string& t) {
    try {
      parse_invite(t);
    } catch (const InvalidInput& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(message("csculpt2:" + text.substr(9)).find("does not start with"), std::string::npos);
  EXPECT_NE(message(keys).find("no '@"), std::string::npos);
  EXPECT_NE(message(keys.substr(0, keys.size() - 1) + "@tcp://x:1").find("143 hex digits"),
            std::string::npos);
  EXPECT_NE(message(keys + "0@tcp://x:1").find("145 hex digits"), std::string::npos);
  std::string bad = text;
  bad[20] = 'z';
  EXPECT_NE(message(bad).find("not hexadecimal"), std::string::npos);
  EXPECT_NE(message(keys + "@udp://x").find("is not tcp://"), std::string::npos);
  EXPECT_NE(message(keys + "@").find("is not tcp://"), std::string::npos);
  EXPECT_EQ(message(""), "invite does not start with 'csculpt1:'");
}

TEST(InviteText, NewInvitesAreRandom) {
  std::set<std::uint64_t> sessions;
  for (int i = 0; i < 8; ++i) {
    const Invite a = new_invite();
    sessions.insert(a.session);
    EXPECT_NE(a.server_secret, a.client_secret);
    EXPECT_TRUE(a.endpoint.empty());
  }
  EXPECT_EQ(sessions.size(), 8u);
}

}  // namespace
