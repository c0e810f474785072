// Submits and updates that list the host's changed vertices (Session::submit and update with
// `changed`): the same edits, versions and meshes as whole-mesh calls, bit for bit, through
// rebases; what an update wrote back; the touched set after a rebase; refusals; a change the
// host did not list.
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <string>
#include <vector>

#include "csculpt/diff.h"
#include "csculpt/error.h"
#include "csculpt/peer/session.h"
#include "csculpt/testkit/generate.h"
#include "sessions.h"

namespace {

using namespace csculpt;
using namespace csculpt::peer;
using csculpt::peer::testing::fast_options;
using csculpt::peer::testing::wait_until;

/// The vertices where `local` differs from `base` (bitwise), increasing.
std::vector<std::uint32_t> differing(const Mesh& base, const Mesh& local) {
  const Diff d = capture_diff(base, local);
  std::vector<std::uint32_t> out(d.positions.indices);
  for (const ChannelDiff& c : d.channels)
    out.insert(out.end(), c.change.indices.begin(), c.change.indices.end());
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

std::vector<std::uint32_t> as_vector(std::span<const std::uint32_t> s) {
  return {s.begin(), s.end()};
}

/// Copies vertex `v` (position and every channel) from `from` to `to` (same layout).
void copy_vertex(const Mesh& from, Mesh& to, std::uint32_t v) {
  to.positions[v] = from.positions[v];
  for (std::size_t c = 0; c < from.channels.size(); ++c) {
    const std::size_t w = from.channels[c].desc.width;
    std::copy_n(from.channels[c].values.begin() + static_cast<std::ptrdiff_t>(v * w), w,
                to.channels[c].values.begin() + static_cast<std::ptrdiff_t>(v * w));
  }
}

/// A host that submits and updates either with the whole mesh or with the vertices its
/// strokes changed.
struct Host {
  std::unique_ptr<Session> session;
  Mesh local;
  bool listed = false;
  std::vector<std::uint32_t> changed;  // since the last submit
  std::size_t sparse_updates = 0;      // updates that wrote back a list of vertices

  void stroke(const Stroke& s) { apply_stroke(local, s, nullptr, &changed); }
  bool submit(std::uint32_t strokes) {
    // Listed backwards and twice: order and repeats must not matter.
    std::vector<std::uint32_t> list(changed.rbegin(), changed.rend());
    list.insert(list.end(), changed.begin(), changed.end());
    const bool sent =
        listed ? session->submit(local, strokes, list) : session->submit(local, strokes);
    changed.clear();
    return sent;
  }
  /// Applies the versions up to `v` once the network thread holds them.
  void update_to(std::uint64_t v) {
    ASSERT_TRUE(wait_until([&] { return session->stats().version >= v; }));
    // A host mirroring `local` (as the C ABI does) copies back only what update wrote.
    Mesh mirror = local;
    if (listed)
      session->update(local, changed);
    else
      session->update(local);
    ASSERT_EQ(session->version(), v);
    if (const auto written = session->written()) {
      ++sparse_updates;
      EXPECT_LT(written->size(), local.vertex_count());
      for (const std::uint32_t w : *written) copy_vertex(local, mirror, w);
      EXPECT_EQ(mesh_digest(mirror), mesh_digest(local)) << "update wrote more than it listed";
    }
    // The touched set is exact after a version: the vertices where local is not the base.
    EXPECT_EQ(as_vector(session->touched()), differing(session->base(), local));
  }
};

/// Two hosts play a script in which every version merges one submit while the other host has
/// edits of its own beyond it (so both rebase), then versions neither host edited beyond (so
/// the update writes sparsely); the digests of both hosts' meshes and bases after every
/// version, and how many updates wrote a list of vertices back.
std::vector<std::uint64_t> play_script(bool listed, std::size_t* sparse = nullptr) {
  const Mesh sphere = make_sphere(3000, /*materials=*/true);
  Host a{Session::create(sphere, fast_options(1)), sphere, listed, {}};
  Host b{Session::join(a.session->invite(), fast_options(2)), {}, listed, {}};
  b.local = b.session->base();
  const std::vector<Stroke> sa = scripted_strokes(sphere, 7, 12);
  const std::vector<Stroke> sb = scripted_strokes(sphere, 8, 16);
  std::vector<std::uint64_t> digests;
  auto record = [&] {
    for (const Host* h : {&a, &b}) {
      digests.push_back(mesh_digest(h->local));
      digests.push_back(mesh_digest(h->session->base()));
    }
  };
  std::uint64_t v = 0;
  for (std::size_t r = 0; r < 4; ++r) {
    b.stroke(sb[4 * r]);
    EXPECT_TRUE(b.submit(1));
    b.stroke(sb[4 * r + 1]);  // beyond the submit: b rebases it
    a.stroke(sa[3 * r]);      // not submitted: a rebases it
    a.update_to(++v);
    b.update_to(v);
    record();
    EXPECT_TRUE(a.submit(1));
    a.stroke(sa[3 * r + 1]);
    b.stroke(sb[4 * r + 2]);
    a.update_to(++v);
    b.update_to(v);
    record();
  }
  EXPECT_TRUE(b.submit(1));
  a.update_to(++v);
  b.update_to(v);
  EXPECT_TRUE(a.submit(1));
  a.update_to(++v);
  b.update_to(v);
  record();
  EXPECT_EQ(mesh_digest(a.local), mesh_digest(b.local));  // converged, nothing left unmerged
  EXPECT_EQ(mesh_digest(a.local), mesh_digest(a.session->base()));
  EXPECT_GE(b.session->stats().rebases, 8u);
  if (sparse) *sparse = a.sparse_updates + b.sparse_updates;
  return digests;
}

TEST(SessionChanged, ListedSubmitsMergeBitIdenticallyToWholeMeshSubmitsThroughRebases) {
  std::size_t sparse = 0;
  const std::vector<std::uint64_t> whole = play_script(false);
  const std::vector<std::uint64_t> listed = play_script(true, &sparse);
  EXPECT_GE(sparse, 3u);  // the last two versions, on both hosts: no edit beyond the submit
  ASSERT_EQ(whole.size(), listed.size());
  for (std::size_t i = 0; i < whole.size(); ++i) EXPECT_EQ(whole[i], listed[i]) << "digest " << i;
}

TEST(SessionChanged, AnIndexOutOfRangeIsRefusedByNameAndNothingIsSent) {
  const Mesh sphere = make_sphere(2000, true);
  Host a{Session::create(sphere, fast_options(1)), sphere, true, {}};
  a.stroke(scripted_strokes(sphere, 3, 1)[0]);
  const Mesh edited = a.local;
  const auto n = static_cast<std::uint32_t>(sphere.vertex_count());
  std::vector<std::uint32_t> bad = a.changed;
  bad.push_back(n + 5);
  try {
    a.session->submit(a.local, 1, bad);
    ADD_FAILURE() << "an index out of range was accepted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("changed vertex " + std::to_string(n + 5)),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("out of range"), std::string::npos) << e.what();
  }
  EXPECT_EQ(a.session->stats().strokes_submitted, 0u);
  EXPECT_TRUE(a.session->touched().empty());
  EXPECT_EQ(mesh_digest(a.local), mesh_digest(edited));  // not set to the wire's values
  // The next good call sends the edit.
  EXPECT_TRUE(a.submit(1));
  EXPECT_EQ(a.session->stats().strokes_submitted, 1u);
  EXPECT_FALSE(a.session->touched().empty());
  EXPECT_FALSE(a.session->submit(a.local, 0, {}));  // nothing new
}

TEST(SessionChanged, AListedUpdateRefusesABadIndexOrValueByNameAndAppliesNothing) {
  const Mesh sphere = make_sphere(2000, true);
  Host a{Session::create(sphere, fast_options(1)), sphere, true, {}};
  Host b{Session::join(a.session->invite(), fast_options(2)), {}, true, {}};
  b.local = b.session->base();
  a.stroke(scripted_strokes(sphere, 3, 1)[0]);
  EXPECT_TRUE(a.submit(1));
  ASSERT_TRUE(wait_until([&] { return b.session->stats().version >= 1; }));
  const auto n = static_cast<std::uint32_t>(sphere.vertex_count());
  const std::vector<std::uint32_t> out_of_range{n + 2};
  try {
    b.session->update(b.local, out_of_range);
    ADD_FAILURE() << "an index out of range was accepted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("changed vertex " + std::to_string(n + 2)),
              std::string::npos)
        << e.what();
  }
  b.local.positions[7].y = std::numeric_limits<float>::quiet_NaN();
  b.changed = {7};
  try {
    b.session->update(b.local, b.changed);
    ADD_FAILURE() << "a NaN the host listed was accepted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("vertex 7"), std::string::npos) << e.what();
  }
  EXPECT_EQ(b.session->version(), 0u);  // nothing applied
  b.local.positions[7] = sphere.positions[7];
  b.update_to(1);  // the next good call applies the version
  a.update_to(1);
  EXPECT_EQ(mesh_digest(a.local), mesh_digest(b.local));
}

TEST(SessionChanged, AVertexChangedButNotListedArrivesOnceListed) {
  const Mesh sphere = make_sphere(2000, true);
  // One merge after both submits: the second replaces the first in it.
  SessionOptions slow = fast_options(1);
  slow.sync = Millis{1500};
  Host a{Session::create(sphere, slow), sphere, true, {}};
  Host b{Session::join(a.session->invite(), fast_options(2)), {}, true, {}};
  b.local = b.session->base();
  const std::uint32_t u = 5;  // changed without telling the session, far from the stroke
  const Vec3f p = sphere.positions[u];
  Stroke grab;
  grab.center = {-p.x, -p.y, -p.z};
  grab.radius = 0.4f;
  b.stroke(grab);
  ASSERT_EQ(std::count(b.changed.begin(), b.changed.end(), u), 0);
  b.local.positions[u].z += 0.05f;
  const Vec3f hosts_value = b.local.positions[u];
  EXPECT_TRUE(b.submit(1));
  EXPECT_EQ(std::count(b.session->touched().begin(), b.session->touched().end(), u), 0);
  EXPECT_EQ(b.local.positions[u].z, hosts_value.z);  // left as the host made it, not sent
  EXPECT_TRUE(b.session->submit(b.local, 0, std::vector<std::uint32_t>{u}));
  EXPECT_EQ(std::count(b.session->touched().begin(), b.session->touched().end(), u), 1);
  a.update_to(1);
  EXPECT_NEAR(a.local.positions[u].z, hosts_value.z, 1e-4f);
  EXPECT_NE(a.local.positions[u].z, sphere.positions[u].z);
  b.update_to(1);
  EXPECT_EQ(mesh_digest(a.local), mesh_digest(b.local));
}

TEST(SessionChanged, WhatUndoWroteIsSentWithoutBeingListed) {
  const Mesh sphere = make_sphere(2000);
  Host a{Session::create(sphere, fast_options(1)), sphere, true, {}};
  Stroke grab;
  grab.center = sphere.positions[0];
  a.stroke(grab);
  std::vector<std::uint32_t> vertices = a.changed;
  std::vector<float> before;
  for (const std::uint32_t v : vertices)
    before.insert(before.end(),
                  {sphere.positions[v].x, sphere.positions[v].y, sphere.positions[v].z});
  a.session->record_stroke(a.local, vertices, before);
  EXPECT_TRUE(a.submit(1));
  a.update_to(1);
  std::vector<std::uint32_t> undone;
  ASSERT_TRUE(a.session->undo(a.local, undone));
  EXPECT_FALSE(undone.empty());
  EXPECT_TRUE(a.submit(1));  // nothing listed
  a.update_to(2);
  EXPECT_EQ(mesh_digest(a.local), mesh_digest(a.session->base()));
  EXPECT_NEAR(a.session->base().positions[0].z, sphere.positions[0].z, 1e-4f);
}

}  // namespace
