// Replication without sockets: gap detection, the hash chain, buffering, fetch answers and
// divergence.
#include <gtest/gtest.h>

#include "csculpt/error.h"
#include "csculpt/peer/session.h"
#include "csculpt/wire.h"
#include "pieces.h"
#include "replication.h"

namespace {

using namespace csculpt;
using namespace csculpt::peer;
using namespace csculpt::peer::testing;

/// The versions a merger would publish: each a stroke from the one before, chained. With
/// `prefix`, they follow its versions (another branch from its end, pushed by `push`).
std::vector<VersionRecord> history(std::size_t n, std::vector<VersionRecord> prefix = {},
                                   float push = 0.01f) {
  std::vector<VersionRecord> out = prefix;
  Mesh base = sphere();
  for (const VersionRecord& r : prefix) apply_diff(decode_diff(r.diff_bytes, base), base);
  std::uint64_t chain = prefix.empty() ? kGenesisChain : prefix.back().chain;
  for (std::size_t v = prefix.size() + 1; v <= prefix.size() + n; ++v) {
    const Diff d = stroke_diff(base, {0.f, 0.f, 1.f}, {float(v) * push, 0.f, 0.f});
    DiffHeader h;
    h.base_version = v - 1;
    h.sequence = v;
    VersionRecord r;
    r.version = v;
    r.parent_chain = chain;
    r.diff_bytes = encode_diff(d, base, h);
    const Diff decoded = decode_diff(r.diff_bytes, base);
    r.chain = next_chain(chain, decoded);
    chain = r.chain;
    apply_diff(decoded, base);
    out.push_back(std::move(r));
  }
  return out;
}

Replication at_start() {
  Replication r;
  r.reset(0, kGenesisChain);
  return r;
}

TEST(Replication, ClassifiesArrivals) {
  const Replication r = at_start();
  EXPECT_EQ(r.classify(0, 0), Replication::Arrival::held);
  EXPECT_EQ(r.classify(1, kGenesisChain), Replication::Arrival::next);
  EXPECT_EQ(r.classify(1, kGenesisChain ^ 1), Replication::Arrival::other_branch);
  EXPECT_EQ(r.classify(2, 0), Replication::Arrival::gap);
  EXPECT_EQ(r.classify(1000, 0), Replication::Arrival::gap);
}

TEST(Replication, AcceptsAChainAndConvergesOnTheMergersMesh) {
  const auto h = history(3);
  Replication r = at_start();
  Mesh base = sphere();
  for (const VersionRecord& v : h) {
    ASSERT_EQ(r.classify(v.version, v.parent_chain), Replication::Arrival::next);
    r.accept(v, base);
  }
  EXPECT_EQ(r.version(), 3u);
  EXPECT_EQ(r.chain(), h.back().chain);
  EXPECT_EQ(r.latest().version, 3u);
  EXPECT_EQ(r.chain_at(1).value_or(0), h[0].chain);
  EXPECT_EQ(r.chain_at(0).value_or(0), kGenesisChain);  // where the session started
  EXPECT_NE(mesh_digest(base), mesh_digest(sphere()));
}

// After a partition each side merged its own versions from a common one: a snapshot's chains
// tell the receiver where (the versions its own branch had since are carried over from there).
TEST(Replication, FindsWhereTwoBranchesForked) {
  const auto shared = history(2);
  const auto a = history(4, shared, 0.01f), b = history(3, shared, -0.02f);
  Replication ra = at_start(), rb = at_start();
  Mesh base_a = sphere(), base_b = sphere();
  for (const VersionRecord& v : a) ra.accept(v, base_a);
  for (const VersionRecord& v : b) rb.accept(v, base_b);
  ASSERT_NE(a[2].chain, b[2].chain);
  EXPECT_EQ(ra.fork_point(rb.recent_chains(kChainsSent)), 2u);
  EXPECT_EQ(rb.fork_point(ra.recent_chains(kChainsSent)), 2u);
  // The same branch, one peer behind: the fork point is the version it holds.
  Replication behind = at_start();
  Mesh base = sphere();
  for (std::size_t i = 0; i < 4; ++i) behind.accept(a[i], base);
  EXPECT_EQ(behind.fork_point(ra.recent_chains(kChainsSent)), 4u);
  // Chains that do not reach back to the fork: no common version known.
  EXPECT_FALSE(ra.fork_point(rb.recent_chains(2)).has_value());
  // A snapshot's chains become ours: the receiver can tell the next one where it forked.
  Replication joined;
  joined.reset(b.size(), b.back().chain, rb.recent_chains(kChainsSent));
  EXPECT_EQ(joined.chain_at(1).value_or(0), b[0].chain);
  EXPECT_EQ(joined.fork_point(ra.recent_chains(kChainsSent)), 2u);
  // Chains that do not end at the snapshot's version are not believed.
  Replication wrong;
  wrong.reset(b.size(), b.back().chain ^ 1, rb.recent_chains(kChainsSent));
  EXPECT_FALSE(wrong.chain_at(1).has_value());
}

TEST(Replication, RefusesABrokenChainOrAForeignBaseAndChangesNothing) {
  auto h = history(2);
  Replication r = at_start();
  Mesh base = sphere();
  VersionRecord forged = h[0];
  forged.chain ^= 1;
  EXPECT_THROW(r.accept(forged, base), InvalidInput);
  EXPECT_EQ(r.version(), 0u);
  EXPECT_EQ(r.chain(), kGenesisChain);
  EXPECT_EQ(mesh_digest(base), mesh_digest(sphere()));
  // Version 2's diff is based on version 1: offered as version 1 it is refused.
  VersionRecord misplaced = h[1];
  misplaced.version = 1;
  misplaced.parent_chain = kGenesisChain;
  try {
    r.accept(misplaced, base);
    ADD_FAILURE() << "accepted a diff based on another version";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("based on 1"), std::string::npos) << e.what();
  }
  r.accept(h[0], base);
  EXPECT_EQ(r.version(), 1u);
}

TEST(Replication, BuffersAheadOfAGapAndDrainsInOrder) {
  const auto h = history(4);
  Replication r = at_start();
  Mesh base = sphere();
  r.buffer(h[3]);
  r.buffer(h[2]);
  EXPECT_FALSE(r.take_next_buffered().has_value());  // version 1 is missing
  r.buffer(h[1]);
  r.accept(h[0], base);
  std::vector<std::uint64_t> drained;
  while (auto next = r.take_next_buffered()) {
    drained.push_back(next->version);
    r.accept(std::move(*next), base);
  }
  EXPECT_EQ(drained, (std::vector<std::uint64_t>{2, 3, 4}));
  EXPECT_EQ(r.chain(), h[3].chain);
}

TEST(Replication, DropsBufferedVersionsItPassedOrOfAnotherBranch) {
  const auto h = history(3);
  Replication r = at_start();
  Mesh base = sphere();
  r.buffer(h[0]);
  VersionRecord other = h[1];
  other.parent_chain ^= 1;
  r.buffer(other);
  r.accept(h[0], base);
  EXPECT_FALSE(r.take_next_buffered().has_value());  // 1 passed, 2 follows another chain
}

TEST(Replication, AnswersFetchesFromItsHistoryOrAsksForASnapshot) {
  const auto h = history(3);
  Replication r = at_start();
  Mesh base = sphere();
  EXPECT_FALSE(r.since(0).has_value());  // nothing kept
  for (const VersionRecord& v : h) r.accept(v, base);
  const auto all = r.since(0);
  ASSERT_TRUE(all);
  ASSERT_EQ(all->size(), 3u);
  EXPECT_EQ((*all)[0]->version, 1u);
  EXPECT_EQ(r.since(2)->size(), 1u);
  EXPECT_TRUE(r.since(3)->empty());
  r.reset(3, h[2].chain);  // e.g. after a snapshot: the old history is not ours to serve
  EXPECT_FALSE(r.since(1).has_value());
}

TEST(Replication, DetectsDivergenceOnlyAtVersionsItHolds) {
  const auto h = history(2);
  Replication r = at_start();
  Mesh base = sphere();
  for (const VersionRecord& v : h) r.accept(v, base);
  EXPECT_FALSE(r.diverges(1, h[0].chain));
  EXPECT_TRUE(r.diverges(1, h[0].chain ^ 1));
  EXPECT_TRUE(r.diverges(2, 0));
  EXPECT_FALSE(r.diverges(9, 0));  // unknown: no verdict
}

}  // namespace
