#include "artist.h"

#include "csculpt/diff.h"

namespace csculpt::cli {

SimulatedArtist::SimulatedArtist(peer::Session& session, const ArtistOptions& options)
    : session_(session),
      options_(options),
      local_(session.base()),
      topology_(
          Topology::build(static_cast<std::uint32_t>(local_.vertex_count()), local_.triangles)),
      script_(scripted_strokes(session.base(), options.seed, 4096, options.paint)) {}

std::size_t SimulatedArtist::stroke() {
  const Mesh before_channels_only = local_;  // paint adds channels the base may lack: refused
  const Stroke& s = script_[cursor_++ % script_.size()];
  apply_stroke(local_, s, &topology_);
  if (local_.channels.size() != session_.base().channels.size()) {
    local_ = before_channels_only;  // the session's mesh has no material channels to paint
    return 0;
  }
  ++strokes_;
  ++unsent_strokes_;
  return capture_diff(before_channels_only, local_).touched_vertices();
}

std::size_t SimulatedArtist::step(peer::Clock::time_point now, bool editing) {
  if (!started_flag_) {
    started_flag_ = true;
    started_ = now;
    next_submit_ = now + options_.submit_every;
  }
  const std::size_t applied = session_.update(local_);
  if (editing && options_.strokes_per_second > 0) {
    const double due =
        std::chrono::duration<double>(now - started_).count() * options_.strokes_per_second;
    // Strokes that changed nothing (paint on a mesh without material channels) are skipped;
    // the cap keeps a long stall from bursting.
    for (int i = 0; i < 64 && static_cast<double>(strokes_) < due; ++i) stroke();
  }
  if (now >= next_submit_) {
    next_submit_ = now + options_.submit_every;
    if (session_.submit(local_, unsent_strokes_)) unsent_strokes_ = 0;
  }
  return applied;
}

std::uint64_t SimulatedArtist::unacknowledged() const {
  const peer::SessionStats s = session_.stats();
  return s.strokes_submitted + unsent_strokes_ - s.strokes_acknowledged;
}

}  // namespace csculpt::cli
