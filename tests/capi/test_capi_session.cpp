// Sessions through the C ABI only (as a DCC host sees them): two peers on loopback, edits in
// host arrays, convergence, events, statistics, attribution, and bad arguments.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <filesystem>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "csculpt.h"
#include "host_arrays.h"

namespace {

csc_mesh* grid(int n) {
  std::vector<float> p;
  std::vector<std::uint32_t> t;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      p.push_back(float(i) / float(n - 1));
      p.push_back(float(j) / float(n - 1));
      p.push_back(0.05f * std::sin(float(i + 2 * j)));
    }
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      const auto v = static_cast<std::uint32_t>(j * n + i), w = static_cast<std::uint32_t>(n);
      t.insert(t.end(), {v, v + 1, v + w, v + 1, v + w + 1, v + w});
    }
  csc_mesh_desc d = CSC_MESH_DESC_INIT;
  d.vertex_count = static_cast<std::uint32_t>(p.size() / 3);
  d.positions = p.data();
  d.triangle_count = static_cast<std::uint32_t>(t.size() / 3);
  d.triangles = t.data();
  csc_mesh* m = nullptr;
  EXPECT_EQ(csc_mesh_create(&m, &d), CSC_OK) << csc_last_error();
  EXPECT_EQ(csc_mesh_add_material_channels(m), CSC_OK);
  return m;
}

csc_session_options fast(std::uint64_t id) {
  csc_session_options o = CSC_SESSION_OPTIONS_INIT;
  o.id = id;
  o.sync_ms = 30;
  o.heartbeat_ms = 50;
  o.evasive_ms = 200;
  o.expired_ms = 400;
  o.join_timeout_ms = 10000;
  return o;
}

TEST(CapiSession, TwoHostsEditTheirArraysAndConverge) {
  csc_mesh* mesh = grid(48);
  csc_session* a = nullptr;
  const csc_session_options oa = fast(1), ob = fast(2);
  ASSERT_EQ(csc_session_create(&a, mesh, &oa), CSC_OK) << csc_last_error();
  const std::string invite = csc_session_invite(a);
  EXPECT_EQ(invite.rfind("csculpt1:", 0), 0u);
  csc_session* b = nullptr;
  ASSERT_EQ(csc_session_join(&b, invite.c_str(), &ob), CSC_OK) << csc_last_error();
  EXPECT_EQ(csc_session_id(b), 2u);

  csc_mesh* b_base = nullptr;
  ASSERT_EQ(csc_session_copy_base(&b_base, b), CSC_OK);
  HostArrays ha(mesh), hb(b_base);
  // views of the hosts' arrays: edited in place below, never reallocated
  csc_vertex_arrays va = ha.arrays(), vb = hb.arrays();
  ASSERT_EQ(ha.positions, hb.positions);
  // a lifts the left half, b paints the right half red
  for (std::size_t v = 0; v < ha.positions.size() / 3; ++v) {
    if (ha.positions[3 * v] < 0.4f) ha.positions[3 * v + 2] += 0.1f * ha.positions[3 * v];
    if (hb.positions[3 * v] > 0.6f) hb.channels[0][3 * v] = 1.f;  // albedo red
  }
  int32_t sent = 0;
  ASSERT_EQ(csc_session_submit(a, &va, 1, &sent), CSC_OK) << csc_last_error();
  EXPECT_EQ(sent, 1);
  ASSERT_EQ(csc_session_submit(b, &vb, 1, &sent), CSC_OK);
  EXPECT_EQ(sent, 1);
  ASSERT_EQ(csc_session_submit(b, &vb, 0, &sent), CSC_OK);
  EXPECT_EQ(sent, 0);  // nothing new

  bool joined_event = false, version_event = false;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  for (;;) {
    if (std::chrono::steady_clock::now() >= deadline) {
      csc_session_stats sa = CSC_SESSION_STATS_INIT, sb = CSC_SESSION_STATS_INIT;
      csc_session_get_stats(a, &sa);
      csc_session_get_stats(b, &sb);
      ADD_FAILURE() << "no convergence: a v" << csc_session_version(a) << "/" << sa.version
                    << " ack " << sa.strokes_acknowledged << " epoch " << sa.epoch << " merger "
                    << sa.merger << " members " << sa.members << " merges " << sa.merges
                    << " dropped " << sa.messages_dropped << " stale " << sa.stale_ignored
                    << "; b v" << csc_session_version(b) << "/" << sb.version << " ack "
                    << sb.strokes_acknowledged << " epoch " << sb.epoch << " merger " << sb.merger
                    << " members " << sb.members << " merges " << sb.merges << " dropped "
                    << sb.messages_dropped << " stale " << sb.stale_ignored << " submits "
                    << sb.submits << "; positions equal " << (ha.positions == hb.positions)
                    << " channels equal " << (ha.channels == hb.channels);
      break;
    }
    std::uint32_t applied = 0;
    ASSERT_EQ(csc_session_update(a, &va, &applied), CSC_OK) << csc_last_error();
    ASSERT_EQ(csc_session_update(b, &vb, &applied), CSC_OK) << csc_last_error();
    csc_session_event e = CSC_SESSION_EVENT_INIT;
    int32_t has = 0;
    while (csc_session_poll(a, &e, &has) == CSC_OK && has) {
      joined_event |= e.kind == CSC_EVENT_JOINED;
      version_event |= e.kind == CSC_EVENT_VERSION;
      ASSERT_NE(e.message, nullptr);
    }
    csc_session_stats sa = CSC_SESSION_STATS_INIT, sb = CSC_SESSION_STATS_INIT;
    ASSERT_EQ(csc_session_get_stats(a, &sa), CSC_OK);
    ASSERT_EQ(csc_session_get_stats(b, &sb), CSC_OK);
    if (sa.strokes_acknowledged == 1 && sb.strokes_acknowledged == 1 &&
        csc_session_version(a) == csc_session_version(b) && ha.positions == hb.positions &&
        ha.channels == hb.channels)
      break;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  EXPECT_TRUE(joined_event);
  EXPECT_TRUE(version_event);
  csc_session_stats merged = CSC_SESSION_STATS_INIT;
  ASSERT_EQ(csc_session_get_stats(a, &merged), CSC_OK);
  EXPECT_EQ(merged.folds_introduced, 0u);  // a lift and a paint: nothing turned over
  // both edits arrived on both hosts
  float lift = 0, red = 0;
  for (std::size_t v = 0; v < ha.positions.size() / 3; ++v) {
    lift = std::max(lift, hb.positions[3 * v + 2] - csc_mesh_positions(mesh)[3 * v + 2]);
    red = std::max(red, ha.channels[0][3 * v]);
  }
  EXPECT_GT(lift, 0.02f);
  EXPECT_GT(red, 0.9f);
  std::vector<float> rgb(3 * va.vertex_count);
  EXPECT_EQ(csc_session_attribution_colors(a, rgb.data(), va.vertex_count), CSC_OK);
  EXPECT_NE(rgb.front(), rgb.back());  // left and right halves attributed to different peers
  EXPECT_EQ(csc_session_attribution_colors(a, rgb.data(), 3), CSC_ERROR_INVALID_ARGUMENT);

  EXPECT_EQ(csc_session_leave(b), CSC_OK);
  EXPECT_EQ(csc_session_submit(b, &vb, 0, nullptr), CSC_ERROR_INVALID_ARGUMENT);
  csc_session_destroy(b);
  csc_session_destroy(a);
  csc_mesh_destroy(b_base);
  csc_mesh_destroy(mesh);
}

// csc_session_stats grew folds_introduced in 0.5: a host built against 0.4 passes the older
// size and gets every field it knows, the new one left as it set it; a 0.5 host gets it written.
TEST(CapiSession, StatsGrewFoldsIntroducedAndOlderHostsStillReadTheirs) {
  csc_mesh* mesh = grid(8);
  const csc_session_options o = fast(1);
  csc_session* s = nullptr;
  ASSERT_EQ(csc_session_create(&s, mesh, &o), CSC_OK) << csc_last_error();
  constexpr std::uint64_t kUntouched = 0xC5C5C5C5C5C5C5C5ull;

  csc_session_stats now = CSC_SESSION_STATS_INIT;
  now.folds_introduced = kUntouched;
  ASSERT_EQ(csc_session_get_stats(s, &now), CSC_OK) << csc_last_error();
  EXPECT_EQ(now.folds_introduced, 0u);  // written: no merge yet
  EXPECT_EQ(now.struct_size, sizeof(csc_session_stats));

  csc_session_stats older = CSC_SESSION_STATS_INIT;
  older.struct_size = offsetof(csc_session_stats, folds_introduced);  // a 0.4 host's
  older.folds_introduced = kUntouched;
  ASSERT_EQ(csc_session_get_stats(s, &older), CSC_OK) << csc_last_error();
  EXPECT_EQ(older.folds_introduced, kUntouched);
  EXPECT_EQ(older.members, now.members);
  EXPECT_EQ(older.struct_size, offsetof(csc_session_stats, folds_introduced));

  csc_session_stats short_ = CSC_SESSION_STATS_INIT;
  short_.struct_size = offsetof(csc_session_stats, auth_rejected);  // no version had this
  EXPECT_EQ(csc_session_get_stats(s, &short_), CSC_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(csc_last_error()).find("struct_size"), std::string::npos)
      << csc_last_error();
  csc_session_destroy(s);
  csc_mesh_destroy(mesh);
}

TEST(CapiSession, BadArgumentsAndInvitesAreRefusedClearly) {
  csc_mesh* mesh = grid(8);
  csc_session* s = nullptr;
  EXPECT_EQ(csc_session_create(nullptr, mesh, nullptr), CSC_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(csc_session_create(&s, nullptr, nullptr), CSC_ERROR_INVALID_ARGUMENT);
  csc_session_options o = CSC_SESSION_OPTIONS_INIT;
  o.expired_ms = o.evasive_ms;
  EXPECT_EQ(csc_session_create(&s, mesh, &o), CSC_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(csc_last_error()).find("evasive"), std::string::npos);
  o = CSC_SESSION_OPTIONS_INIT;
  o.bind = "tcp://256.1.1.1:1";
  EXPECT_EQ(csc_session_create(&s, mesh, &o), CSC_ERROR_IO);
  EXPECT_NE(std::string(csc_last_error()).find("256.1.1.1"), std::string::npos);
  EXPECT_EQ(s, nullptr);
  EXPECT_EQ(csc_session_join(&s, "not an invite", nullptr), CSC_ERROR_INVALID_INPUT);
  EXPECT_NE(std::string(csc_last_error()).find("csculpt1:"), std::string::npos);
  // A well-formed invite to nobody: no snapshot within the timeout.
  const std::string nobody = "csculpt1:" + std::string(144, '0') + "@tcp://127.0.0.1:9";
  o = CSC_SESSION_OPTIONS_INIT;
  o.join_timeout_ms = 300;
  EXPECT_EQ(csc_session_join(&s, nobody.c_str(), &o), CSC_ERROR_IO);
  EXPECT_EQ(s, nullptr);
  // foreign handles and NULLs
  auto* foreign = reinterpret_cast<csc_session*>(mesh);
  int32_t has = 0;
  csc_session_event e = CSC_SESSION_EVENT_INIT;
  EXPECT_EQ(csc_session_poll(foreign, &e, &has), CSC_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(csc_session_leave(foreign), CSC_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(csc_session_invite(foreign), nullptr);
  EXPECT_EQ(csc_session_id(nullptr), 0u);
  csc_session_destroy(nullptr);
  csc_session_destroy(foreign);  // ignored
  ASSERT_EQ(csc_session_create(&s, mesh, nullptr), CSC_OK) << csc_last_error();
  EXPECT_EQ(csc_session_poll(s, nullptr, &has), CSC_ERROR_INVALID_ARGUMENT);
  e.struct_size = 4;
  EXPECT_EQ(csc_session_poll(s, &e, &has), CSC_ERROR_INVALID_ARGUMENT);
  HostArrays h(mesh);
  csc_vertex_arrays vh = h.arrays();
  vh.vertex_count -= 1;
  EXPECT_EQ(csc_session_submit(s, &vh, 1, nullptr), CSC_ERROR_INVALID_INPUT);
  vh.vertex_count += 1;
  h.positions[4] = std::nanf("");
  EXPECT_EQ(csc_session_submit(s, &vh, 1, nullptr), CSC_ERROR_INVALID_INPUT);
  EXPECT_TRUE(std::isnan(h.positions[4]));  // nothing written back on failure
  csc_session_destroy(s);
  csc_mesh_destroy(mesh);
}

bool wait_for(const std::function<bool()>& done) {
  for (int i = 0; i < 1000 && !done(); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  return done();
}

/// Two hosts of one session on a grid: peer 1 (`a`) created it, peer 2 (`b`) joined; each has
/// its arrays (`ha`, `hb`, viewed by `va`, `vb`).
class CapiSessionPair : public ::testing::Test {
 protected:
  void SetUp() override {
    const csc_session_options oa = fast(1), ob = fast(2);
    ASSERT_EQ(csc_session_create(&a, mesh, &oa), CSC_OK) << csc_last_error();
    ASSERT_EQ(csc_session_join(&b, csc_session_invite(a), &ob), CSC_OK) << csc_last_error();
  }
  void TearDown() override {
    csc_session_destroy(b);
    csc_session_destroy(a);
    csc_mesh_destroy(mesh);
  }
  csc_mesh* mesh = grid(24);
  csc_session *a = nullptr, *b = nullptr;
  HostArrays ha{mesh}, hb{mesh};
  csc_vertex_arrays va = ha.arrays(), vb = hb.arrays();
};

TEST_F(CapiSessionPair, ASubmitOfTheChangedVerticesReachesThePeerAndABadIndexIsRefused) {
  // b lifts three vertices and paints one; listed backwards, with a repeat
  const std::vector<std::uint32_t> changed = {300, 41, 7, 41};
  for (const std::uint32_t v : {7u, 41u, 300u}) hb.positions[3 * v + 2] += 0.2f;
  hb.channels[0][3 * 300] = 1.f;
  const HostArrays edited(hb);
  int32_t sent = -1;
  std::vector<std::uint32_t> bad = changed;
  bad.push_back(va.vertex_count + 2);
  EXPECT_EQ(csc_session_submit_changed(b, &vb, bad.data(), 5, 1, &sent), CSC_ERROR_INVALID_INPUT);
  EXPECT_NE(std::string(csc_last_error()).find(std::to_string(va.vertex_count + 2)),
            std::string::npos)
      << csc_last_error();
  EXPECT_EQ(sent, -1);
  EXPECT_TRUE(hb == edited);  // nothing written back
  EXPECT_EQ(csc_session_submit_changed(b, &vb, nullptr, 2, 1, &sent), CSC_ERROR_INVALID_ARGUMENT);
  ASSERT_EQ(csc_session_submit_changed(b, &vb, changed.data(), 4, 1, &sent), CSC_OK)
      << csc_last_error();
  EXPECT_EQ(sent, 1);
  EXPECT_FALSE(hb == edited);  // set to what the peers decode
  ASSERT_EQ(csc_session_submit_changed(b, &vb, nullptr, 0, 0, &sent), CSC_OK);
  EXPECT_EQ(sent, 0);  // nothing new
  ASSERT_TRUE(wait_for([&] {
    csc_session_update(a, &va, nullptr);
    csc_session_update(b, &vb, nullptr);
    return csc_session_version(a) >= 1 && csc_session_version(b) >= 1 && ha == hb;
  }));
  EXPECT_NEAR(ha.positions[3 * 41 + 2], edited.positions[3 * 41 + 2], 1e-4f);
  EXPECT_EQ(ha.channels[0][3 * 300], 1.f);
}

TEST_F(CapiSessionPair, AnUpdateOfTheChangedVerticesAppliesAndRebasesAsTheWholeUpdateDoes) {
  const std::vector<std::uint32_t> sent_b = {7, 41};
  for (const std::uint32_t v : sent_b) hb.positions[3 * v + 2] += 0.2f;
  ASSERT_EQ(csc_session_submit_changed(b, &vb, sent_b.data(), 2, 1, nullptr), CSC_OK);
  const std::vector<std::uint32_t> kept_a = {500};  // a's edit, not submitted: rebased
  ha.positions[3 * 500 + 1] += 0.1f;
  const float a_value = ha.positions[3 * 500 + 1];
  const std::vector<std::uint32_t> bad = {va.vertex_count};
  EXPECT_EQ(csc_session_update_changed(a, &va, bad.data(), 1, nullptr), CSC_ERROR_INVALID_INPUT);
  EXPECT_NE(std::string(csc_last_error()).find(std::to_string(va.vertex_count)), std::string::npos)
      << csc_last_error();
  EXPECT_EQ(csc_session_update_changed(a, &va, nullptr, 1, nullptr), CSC_ERROR_INVALID_ARGUMENT);
  uint32_t applied_a = 0, applied_b = 0;
  ASSERT_TRUE(wait_for([&] {
    uint32_t n = 0;
    EXPECT_EQ(csc_session_update_changed(a, &va, kept_a.data(), 1, &n), CSC_OK);
    applied_a += n;
    EXPECT_EQ(csc_session_update_changed(b, &vb, nullptr, 0, &n), CSC_OK);
    applied_b += n;
    return csc_session_version(a) >= 1 && csc_session_version(b) >= 1;
  }));
  EXPECT_EQ(applied_a, 1u);
  EXPECT_EQ(applied_b, 1u);
  // b edited nothing beyond its submit: its arrays are the agreed mesh, bit for bit.
  csc_mesh* base_b = nullptr;
  ASSERT_EQ(csc_session_copy_base(&base_b, b), CSC_OK);
  EXPECT_TRUE(hb == HostArrays(base_b));
  // a has b's edit and keeps its own.
  EXPECT_EQ(ha.positions[3 * 41 + 2], hb.positions[3 * 41 + 2]);
  EXPECT_EQ(ha.positions[3 * 500 + 1], a_value);
  // Sent, merged and applied on both: the same mesh.
  int32_t sent = 0;
  ASSERT_EQ(csc_session_submit_changed(a, &va, kept_a.data(), 1, 1, &sent), CSC_OK);
  EXPECT_EQ(sent, 1);
  ASSERT_TRUE(wait_for([&] {
    csc_session_update_changed(a, &va, nullptr, 0, nullptr);
    csc_session_update_changed(b, &vb, nullptr, 0, nullptr);
    return csc_session_version(a) >= 2 && csc_session_version(b) >= 2 && ha == hb;
  }));
  csc_mesh_destroy(base_b);
}

TEST(CapiSession, PresenceAndPeersCrossTheAbi) {
  csc_mesh* mesh = grid(16);
  csc_session_options oa = fast(1), ob = fast(2);
  oa.name = "ana";
  ob.name = "ben";
  csc_session *a = nullptr, *b = nullptr;
  ASSERT_EQ(csc_session_create(&a, mesh, &oa), CSC_OK) << csc_last_error();
  ASSERT_EQ(csc_session_join(&b, csc_session_invite(a), &ob), CSC_OK) << csc_last_error();
  csc_presence mine = CSC_PRESENCE_INIT;
  mine.position[0] = 0.25f;
  mine.position[1] = 0.5f;
  mine.radius = 0.125f;
  mine.active = 1;
  mine.visible = 1;
  ASSERT_EQ(csc_session_set_presence(a, &mine), CSC_OK) << csc_last_error();
  uint32_t count = 0;
  ASSERT_TRUE(wait_for([&] { return csc_session_presence_count(b, &count) == CSC_OK && count; }));
  csc_presence got = CSC_PRESENCE_INIT;
  ASSERT_EQ(csc_session_get_presence(b, 0, &got), CSC_OK) << csc_last_error();
  EXPECT_EQ(got.peer, 1u);
  EXPECT_EQ(got.position[0], 0.25f);
  EXPECT_EQ(got.position[1], 0.5f);
  EXPECT_EQ(got.radius, 0.125f);
  EXPECT_EQ(got.active, 1);
  EXPECT_EQ(got.visible, 1);
  EXPECT_LT(got.age_ms, 1000u);
  EXPECT_GT(got.colour[1], 0.5f);  // the first peer's green
  EXPECT_EQ(csc_session_get_presence(b, 1, &got), CSC_ERROR_INVALID_ARGUMENT);
  // Peers: names, merger, round trips.
  ASSERT_TRUE(wait_for([&] {
    csc_peer_info p = CSC_PEER_INFO_INIT;
    return csc_session_peer_count(b, &count) == CSC_OK && count == 1 &&
           csc_session_get_peer(b, 0, &p) == CSC_OK && p.latency_ms > 0;
  }));
  csc_peer_info info = CSC_PEER_INFO_INIT;
  ASSERT_EQ(csc_session_get_peer(b, 0, &info), CSC_OK);
  EXPECT_EQ(info.id, 1u);
  EXPECT_STREQ(info.name, "ana");
  EXPECT_EQ(info.state, CSC_PEER_LIVE);
  EXPECT_EQ(info.merger, 1);
  EXPECT_LT(info.latency_ms, 1000.0);
  // Bad host values name the field; nothing is sent.
  mine.position[2] = std::nanf("");
  EXPECT_EQ(csc_session_set_presence(a, &mine), CSC_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(csc_last_error()).find("position.z"), std::string::npos);
  mine.position[2] = 0.f;
  mine.radius = -1.f;
  EXPECT_EQ(csc_session_set_presence(a, &mine), CSC_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(csc_last_error()).find("radius"), std::string::npos);
  mine.radius = INFINITY;
  EXPECT_EQ(csc_session_set_presence(a, &mine), CSC_ERROR_INVALID_ARGUMENT);
  mine.radius = 0.1f;
  mine.struct_size = 4;
  EXPECT_EQ(csc_session_set_presence(a, &mine), CSC_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(csc_session_set_presence(a, nullptr), CSC_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(csc_session_presence_count(a, nullptr), CSC_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(csc_session_peer_count(nullptr, &count), CSC_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(csc_session_get_peer(b, 0, nullptr), CSC_ERROR_INVALID_ARGUMENT);
  // b leaves: a sees its cursor go and lists it as left.
  mine = CSC_PRESENCE_INIT;
  mine.visible = 1;
  ASSERT_EQ(csc_session_set_presence(b, &mine), CSC_OK);
  ASSERT_TRUE(wait_for([&] { return csc_session_presence_count(a, &count) == CSC_OK && count; }));
  ASSERT_EQ(csc_session_leave(b), CSC_OK);
  EXPECT_EQ(csc_session_set_presence(b, &mine), CSC_ERROR_INVALID_ARGUMENT);
  ASSERT_TRUE(wait_for([&] { return csc_session_presence_count(a, &count) == CSC_OK && !count; }));
  ASSERT_EQ(csc_session_peer_count(a, &count), CSC_OK);
  ASSERT_EQ(count, 1u);
  ASSERT_EQ(csc_session_get_peer(a, 0, &info), CSC_OK);
  EXPECT_EQ(info.state, CSC_PEER_LEFT);
  EXPECT_STREQ(info.name, "ben");
  csc_session_destroy(b);
  csc_session_destroy(a);
  csc_mesh_destroy(mesh);
}

// A host journals its session, the session ends, and csc_session_resume brings back the
// agreed mesh and the host's unmerged edit (the options of a 0.3 host are still accepted).
TEST(CapiSession, ResumeFromTheJournalBringsBackTheAgreedMeshAndTheUnmergedEdit) {
  const std::string dir =
      ::testing::TempDir() + "csculpt-capi-journal-" +
      std::to_string(std::chrono::steady_clock::now().time_since_epoch().count());
  csc_mesh* mesh = grid(24);
  csc_session_options o = fast(5);
  o.sync_ms = 3000;  // the first merge 3 s after the start: the edit stays unmerged
  o.journal_dir = dir.c_str();
  csc_session* a = nullptr;
  ASSERT_EQ(csc_session_create(&a, mesh, &o), CSC_OK) << csc_last_error();
  const std::string invite = csc_session_invite(a);
  HostArrays ha(mesh);
  csc_vertex_arrays va = ha.arrays();
  for (std::size_t v = 0; v < ha.positions.size() / 3; ++v) ha.positions[3 * v + 2] += 0.05f;
  int32_t sent = 0;
  ASSERT_EQ(csc_session_submit(a, &va, 1, &sent), CSC_OK) << csc_last_error();
  ASSERT_EQ(sent, 1);
  for (int i = 0; i < 400; ++i) {  // journaled before it is sent
    csc_session_stats st = CSC_SESSION_STATS_INIT;
    ASSERT_EQ(csc_session_get_stats(a, &st), CSC_OK);
    if (st.submits > 0) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  csc_session_destroy(a);

  csc_session_options old = fast(0);
  old.struct_size = offsetof(csc_session_options, journal_dir);  // a 0.3 host's
  csc_session* r = nullptr;
  csc_mesh* local = nullptr;
  EXPECT_EQ(csc_session_resume(&r, &local, nullptr, &old), CSC_ERROR_INVALID_ARGUMENT);
  const std::string empty = dir + "-none";
  EXPECT_EQ(csc_session_resume(&r, &local, empty.c_str(), &old), CSC_ERROR_IO);
  EXPECT_NE(std::string(csc_last_error()).find(empty), std::string::npos) << csc_last_error();
  ASSERT_EQ(csc_session_resume(&r, &local, dir.c_str(), &old), CSC_OK) << csc_last_error();
  EXPECT_EQ(csc_session_id(r), 5u);
  EXPECT_EQ(std::string(csc_session_invite(r)), invite);
  EXPECT_EQ(csc_session_version(r), 0u);
  HostArrays back(local);
  EXPECT_TRUE(back == ha);  // the unmerged edit is back in the host's arrays
  csc_mesh_destroy(local);
  csc_session_destroy(r);
  csc_mesh_destroy(mesh);
  std::filesystem::remove_all(dir);
}

}  // namespace
