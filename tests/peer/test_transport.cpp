// The transport's socket-free parts: routing ids, the ZAP decision, CURVE key derivation, the
// handshake monitor's counting.
#include <gtest/gtest.h>

#include <zmq.h>

#include "handshake_monitor.h"
#include "transport.h"

namespace {

using namespace csculpt;
using namespace csculpt::peer;

TEST(Transport, RoutingIdIsPAndTheIdLittleEndian) {
  const RoutingId r = routing_id(0x0102030405060708ull);
  const RoutingId expected = {'P', 8, 7, 6, 5, 4, 3, 2, 1};
  EXPECT_EQ(r, expected);
  EXPECT_TRUE(is_routing_id_of(0x0102030405060708ull, r));
  EXPECT_FALSE(is_routing_id_of(0x0102030405060709ull, r));
  EXPECT_FALSE(is_routing_id_of(0x0102030405060708ull, std::span(r).first(8)));
  EXPECT_EQ(routing_id(0)[0], 'P');  // never a leading zero byte
}

TEST(Transport, CurvePublicKeyIsDerivedDeterministically) {
  CurveKey secret{};
  for (std::size_t i = 0; i < secret.size(); ++i) secret[i] = static_cast<std::uint8_t>(7 * i + 1);
  const CurveKey a = curve_public(secret), b = curve_public(secret);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, secret);
  secret[5] ^= 1;  // (not a bit X25519 clamps away)
  EXPECT_NE(curve_public(secret), a);
}

std::vector<std::string> zap_request(const std::string& mechanism, const std::string& key) {
  return {"1.0", "req-7", "csculpt", "127.0.0.1", "", mechanism, key};
}

TEST(Transport, ZapAdmitsOnlyTheSessionsClientKey) {
  CurveKey client{};
  client.fill(3);
  const std::string key(client.begin(), client.end());
  const ZapDecision ok = decide_zap(zap_request("CURVE", key), client);
  EXPECT_TRUE(ok.accepted);
  EXPECT_EQ(ok.reply[0], "1.0");
  EXPECT_EQ(ok.reply[1], "req-7");
  EXPECT_EQ(ok.reply[2], "200");
  std::string other = key;
  other[5] ^= 1;
  for (const auto& request :
       {zap_request("CURVE", other), zap_request("PLAIN", key), zap_request("NULL", ""),
        zap_request("CURVE", key.substr(0, 31)),
        std::vector<std::string>{"1.0", "req-7", "csculpt", "127.0.0.1", "", "CURVE"}}) {
    const ZapDecision no = decide_zap(request, client);
    EXPECT_FALSE(no.accepted);
    EXPECT_EQ(no.reply[1], "req-7");
    EXPECT_EQ(no.reply[2], "400");
  }
}

TEST(Transport, HandshakeEventsCountedByCause) {
  HandshakeCounts c;
  count_handshake_event(ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL, c);   // wrong server key, NULL
  count_handshake_event(ZMQ_EVENT_HANDSHAKE_FAILED_NO_DETAIL, c);  // silent until the timeout
  count_handshake_event(ZMQ_EVENT_HANDSHAKE_FAILED_NO_DETAIL, c);
  count_handshake_event(ZMQ_EVENT_HANDSHAKE_FAILED_AUTH, c);  // ZAP counted it already
  count_handshake_event(ZMQ_EVENT_HANDSHAKE_SUCCEEDED, c);
  EXPECT_EQ(c.rejected, 1u);
  EXPECT_EQ(c.abandoned, 2u);
}

}  // namespace
