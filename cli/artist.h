// A simulated artist in a peer session: scripted strokes at mixed scales (soft brushes as big as
// half the model, inflates, fine detail, twists, paint) applied at a steady rate to the local
// mesh, submitted every sync interval, with merged versions rebased in as they arrive. Used by
// `csculpt peer`, `csculpt demo` and `csculpt bench session`.
#pragma once

#include <chrono>
#include <cstdint>
#include <vector>

#include "csculpt/hierarchy.h"
#include "csculpt/peer/session.h"
#include "csculpt/testkit/generate.h"

namespace csculpt::cli {

struct ArtistOptions {
  std::uint64_t seed = 1;
  /// When not empty, the artist plays these artists' scripts instead of `seed`'s, all at once
  /// and in time order: stroke i of each (in this order), then stroke i + 1 of each, so
  /// `strokes_per_second` strokes of every script per second. One peer replaying the scripts
  /// of a session's artists is that session's single-peer baseline (`csculpt demo --replay`).
  std::vector<std::uint64_t> replayed_seeds;
  double strokes_per_second = 4;
  bool paint = true;
  /// How often the edit is submitted (the session's sync interval is a good choice).
  peer::Millis submit_every{250};
  /// Submit the whole mesh (the session compares every vertex) rather than the vertices the
  /// strokes changed: the safe default of hosts that do not track their changes.
  bool whole_mesh_submit = false;
};

class SimulatedArtist {
 public:
  /// `session` must outlive the artist; the local mesh starts as the session's base.
  SimulatedArtist(peer::Session& session, const ArtistOptions& options);

  /// One turn of the host loop at `now`: take merged versions in (rebasing local edits), make
  /// the strokes that are due if `editing`, and submit when the interval has passed. Returns
  /// the number of versions applied.
  std::size_t step(peer::Clock::time_point now, bool editing);

  /// Applies the next scripted stroke now (counted); false when it was skipped (paint on a
  /// mesh without the material channels).
  bool stroke();

  /// Takes the merged versions in (Session::update, told the changed vertices unless the
  /// artist submits the whole mesh); the number applied.
  std::size_t update();
  /// The host changed `vertex` of local() outside the artist's strokes (a marker): listed
  /// with the next submit and update like the strokes' vertices, or neither would find it.
  void changed(std::uint32_t vertex) {
    changed_.push_back(vertex);
    ++generation_;
  }

  /// Submits the edit (the changed vertices, or the whole mesh; see ArtistOptions) with
  /// `strokes`; what Session::submit returns.
  bool submit(std::uint32_t strokes);

  /// How many scripts the artist plays (1, or the number of replayed seeds).
  std::size_t scripts() const;

  Mesh& local() { return local_; }
  std::uint32_t strokes() const { return strokes_; }
  /// Grows whenever local() or the session's base may have changed through the artist (a
  /// stroke, a marker, versions taken in): what is derived from them is recomputed only then.
  std::uint64_t generation() const { return generation_; }
  /// Strokes made but not yet seen inside a merged version.
  std::uint64_t unacknowledged() const;

 private:
  peer::Session& session_;
  ArtistOptions options_;
  Mesh local_;
  Topology topology_;
  std::vector<Stroke> script_;
  std::vector<std::uint32_t> changed_;  ///< vertices the strokes wrote since the last submit
  std::uint32_t strokes_ = 0, unsent_strokes_ = 0;
  std::uint64_t generation_ = 0;
  std::size_t cursor_ = 0;  ///< next stroke of the script
  peer::Clock::time_point started_{}, next_submit_{};
  bool started_flag_ = false;
};

}  // namespace csculpt::cli
