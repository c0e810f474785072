// Helpers for the tests that run real sessions in this process over loopback sockets.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>
#include <thread>
#include <vector>

#include "csculpt/hierarchy.h"
#include "csculpt/mesh.h"
#include "csculpt/peer/session.h"
#include "csculpt/testkit/generate.h"

namespace csculpt::peer::testing {

/// Options with short intervals (merge every 30 ms; heartbeat 50, evasive 200, expired 400).
inline SessionOptions fast_options(PeerId id, std::string name = "") {
  SessionOptions o;
  o.id = id;
  o.name = std::move(name);
  o.sync = Millis{30};
  o.membership = {Millis{50}, Millis{200}, Millis{400}};
  return o;
}

/// Polls `done` every 5 ms until it holds or `timeout` passes; whether it held.
template <class Done>
bool wait_until(Done&& done, Millis timeout = Millis{5000}) {
  const auto deadline = Clock::now() + timeout;
  while (Clock::now() < deadline) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return done();
}

/// Two artists' runs of `strokes` scripted strokes each over `mesh` (seeds `seed` and
/// `seed` + 1), the mesh's hierarchy, and how long it took to build: what each joiner
/// builds, so the tests whose premise is a long merge or join can set their expiry from it.
struct TwoArtistsEdits {
  Hierarchy hierarchy;
  Millis build_time;
  std::vector<Mesh> edits;
};

inline TwoArtistsEdits two_artists_edits(const Mesh& mesh, std::uint64_t seed,
                                         std::uint32_t strokes) {
  const auto t0 = Clock::now();
  TwoArtistsEdits t{Hierarchy::build(mesh), {}, std::vector<Mesh>(2, mesh)};
  t.build_time = std::chrono::duration_cast<Millis>(Clock::now() - t0);
  for (std::size_t k = 0; k < t.edits.size(); ++k)
    for (const Stroke& s : scripted_strokes(mesh, seed + k, strokes, /*paint=*/false))
      apply_stroke(t.edits[k], s, &t.hierarchy.topology());
  return t;
}

}  // namespace csculpt::peer::testing
