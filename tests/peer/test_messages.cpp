// Envelopes and message bodies: encode, open_envelope's checks, the version record's round trip.
#include <gtest/gtest.h>

#include <cstring>

#include "messages.h"
#include "transport.h"

namespace {

using namespace csculpt;
using namespace csculpt::peer;

constexpr std::uint64_t kSession = 0x5e55105e55105eull;
const EnvelopeHeader kFrom{kSession, 42, 7};

std::vector<std::uint8_t> rid(PeerId id) {
  const RoutingId r = routing_id(id);
  return {r.begin(), r.end()};
}

Opened open(const Bytes& message, PeerId routed_as = 42, std::uint64_t session = kSession,
            PeerId self = 1) {
  static std::vector<std::uint64_t> storage;
  static std::vector<std::uint8_t> routing;
  routing = rid(routed_as);
  return open_envelope(message, routing, session, self, storage);
}

TEST(Envelope, CarriesTheHeaderAndBody) {
  const Bytes bytes = hello_message(kFrom, "tcp://127.0.0.1:9", "ann", true);
  const Opened o = open(bytes);
  ASSERT_NE(o.envelope, nullptr) << o.error;
  EXPECT_EQ(o.envelope->session(), kSession);
  EXPECT_EQ(o.envelope->sender(), 42u);
  EXPECT_EQ(o.envelope->epoch(), 7u);
  ASSERT_EQ(o.envelope->body_type(), fb::Body::Hello);
  const fb::Hello* h = o.envelope->body_as_Hello();
  EXPECT_EQ(h->protocol(), kProtocol);
  EXPECT_EQ(h->endpoint()->str(), "tcp://127.0.0.1:9");
  EXPECT_EQ(h->name()->str(), "ann");
  EXPECT_TRUE(h->wants_snapshot());
}

TEST(Envelope, EveryBodyOpens) {
  const std::uint8_t data[3] = {1, 2, 3};
  const std::vector<std::pair<Bytes, fb::Body>> messages = {
      {heartbeat_message(kFrom, 3, 4, 5, {{42, "tcp://a:1"}, {43, "tcp://b:2"}}),
       fb::Body::Heartbeat},
      {leave_message(kFrom), fb::Body::Leave},
      {elected_message(kFrom, 42), fb::Body::Elected},
      {submit_message(kFrom, data, 9), fb::Body::Submit},
      {fetch_message(kFrom, 11), fb::Body::Fetch},
      {snapshot_request_message(kFrom), fb::Body::SnapshotRequest},
      {snapshot_chunk_message(kFrom, 2, 3, 0, 3, data), fb::Body::SnapshotChunk}};
  for (const auto& [bytes, body] : messages) {
    const Opened o = open(bytes);
    ASSERT_NE(o.envelope, nullptr) << o.error;
    EXPECT_EQ(o.envelope->body_type(), body);
  }
  const fb::Heartbeat* hb = open(messages[0].first).envelope->body_as_Heartbeat();
  EXPECT_EQ(hb->version(), 3u);
  EXPECT_EQ(hb->chain(), 4u);
  EXPECT_EQ(hb->merger(), 5u);
  ASSERT_EQ(hb->members()->size(), 2u);
  EXPECT_EQ(hb->members()->Get(1)->endpoint()->str(), "tcp://b:2");
  const fb::Submit* s = open(messages[3].first).envelope->body_as_Submit();
  EXPECT_EQ(s->strokes(), 9u);
  EXPECT_EQ(std::vector<std::uint8_t>(s->diff()->begin(), s->diff()->end()),
            std::vector<std::uint8_t>(data, data + 3));
  EXPECT_EQ(open(messages[4].first).envelope->body_as_Fetch()->after(), 11u);
}

TEST(Envelope, VersionRecordRoundTrips) {
  VersionRecord r;
  r.version = 12;
  r.parent_chain = 0x1111;
  r.chain = 0x2222;
  r.diff_bytes = {9, 8, 7, 6};
  r.merged = {{42, 3, 5}, {43, 1, 0}};
  r.contributions = {{42, {0, 2}, {255, 17}, 0.5f}, {43, {}, {}, 0.f}};
  r.merge_ms = 1.5f;
  r.conflicting = 5;
  const Bytes bytes = version_message(kFrom, r, true);
  const Opened o = open(bytes);
  ASSERT_NE(o.envelope, nullptr) << o.error;
  const fb::Version* v = o.envelope->body_as_Version();
  EXPECT_TRUE(v->replay());
  const VersionRecord back = record_of(*v);
  EXPECT_EQ(back.version, r.version);
  EXPECT_EQ(back.parent_chain, r.parent_chain);
  EXPECT_EQ(back.chain, r.chain);
  EXPECT_EQ(back.diff_bytes, r.diff_bytes);
  ASSERT_EQ(back.merged.size(), 2u);
  EXPECT_EQ(back.merged[0].peer, 42u);
  EXPECT_EQ(back.merged[0].sequence, 3u);
  EXPECT_EQ(back.merged[0].strokes, 5u);
  ASSERT_EQ(back.contributions.size(), 2u);
  EXPECT_EQ(back.contributions[0].index_gaps, r.contributions[0].index_gaps);
  EXPECT_EQ(back.contributions[0].amounts, r.contributions[0].amounts);
  EXPECT_EQ(back.contributions[0].scale, 0.5f);
  EXPECT_EQ(back.merge_ms, 1.5f);
  EXPECT_EQ(back.conflicting, 5u);
}

TEST(Envelope, RefusesWhatIsNotOursOrNotWellFormed) {
  const Bytes good = heartbeat_message(kFrom, 1, 2, 0);
  EXPECT_EQ(open(Bytes{}).error, "message is not a cSculpt session envelope");
  EXPECT_EQ(open(Bytes(good.begin(), good.begin() + 7)).error,
            "message is not a cSculpt session envelope");
  Bytes truncated(good.begin(), good.begin() + static_cast<long>(good.size() / 2));
  EXPECT_EQ(open(truncated).error, "message failed FlatBuffers verification");
  Bytes ident(64, 0xee);
  std::memcpy(ident.data() + 4, "CSS1", 4);
  EXPECT_EQ(open(ident).error, "message failed FlatBuffers verification");
  EXPECT_EQ(open(good, 42, kSession ^ 1).error, "message of another session");
  const std::string spoof = "message whose sender id does not match its connection";
  EXPECT_EQ(open(good, 43).error, spoof);                // speaks for another
  EXPECT_EQ(open(good, 42, kSession, 42).error, spoof);  // claims to be us
  EXPECT_EQ(open(heartbeat_message({kSession, 0, 0}, 1, 2, 0), 0).error, spoof);  // id 0
  EXPECT_NE(open(good).envelope, nullptr);
}

TEST(Envelope, OpensAMisalignedPayload) {
  const Bytes good = elected_message(kFrom, 42);
  std::vector<std::uint64_t> backing(good.size() / 8 + 2);
  auto* shifted = reinterpret_cast<std::uint8_t*>(backing.data()) + 1;
  std::memcpy(shifted, good.data(), good.size());
  std::vector<std::uint64_t> storage;
  const std::vector<std::uint8_t> routing = rid(42);
  const Opened o = open_envelope({shifted, good.size()}, routing, kSession, 1, storage);
  ASSERT_NE(o.envelope, nullptr) << o.error;
  EXPECT_EQ(o.envelope->body_as_Elected()->merger(), 42u);
  EXPECT_FALSE(storage.empty());  // read from the aligned copy
}

}  // namespace
