#include "artist.h"

namespace csculpt::cli {
namespace {

constexpr std::uint32_t kScriptLength = 4096;  ///< strokes per script; played in a loop

/// The artist's script: its own, or the replayed artists' scripts interleaved stroke by stroke
/// (their strokes are due at the same times, so this is their time order).
std::vector<Stroke> make_script(const Mesh& base, const ArtistOptions& o) {
  if (o.replayed_seeds.empty()) return scripted_strokes(base, o.seed, kScriptLength, o.paint);
  std::vector<std::vector<Stroke>> scripts;
  for (std::uint64_t seed : o.replayed_seeds)
    scripts.push_back(scripted_strokes(base, seed, kScriptLength, o.paint));
  std::vector<Stroke> interleaved;
  interleaved.reserve(std::size_t{kScriptLength} * scripts.size());
  for (std::uint32_t i = 0; i < kScriptLength; ++i)
    for (const std::vector<Stroke>& script : scripts) interleaved.push_back(script[i]);
  return interleaved;
}

}  // namespace

SimulatedArtist::SimulatedArtist(peer::Session& session, const ArtistOptions& options)
    : session_(session),
      options_(options),
      local_(session.base()),
      topology_(
          Topology::build(static_cast<std::uint32_t>(local_.vertex_count()), local_.triangles)),
      script_(make_script(session.base(), options)) {}

std::size_t SimulatedArtist::scripts() const {
  return options_.replayed_seeds.empty() ? 1 : options_.replayed_seeds.size();
}

bool SimulatedArtist::stroke() {
  const Stroke& s = script_[cursor_++ % script_.size()];
  // Paint adds the material channels a mesh lacks, which the session's mesh would refuse:
  // such a stroke is skipped rather than applied and undone.
  if (s.kind == Stroke::Kind::paint)
    for (const ChannelDesc& d : material_channels())
      if (local_.find_channel(d.name) < 0) return false;
  apply_stroke(local_, s, &topology_, &changed_);
  ++generation_;
  ++strokes_;
  ++unsent_strokes_;
  return true;
}

std::size_t SimulatedArtist::step(peer::Clock::time_point now, bool editing) {
  if (!started_flag_) {
    started_flag_ = true;
    started_ = now;
    next_submit_ = now + options_.submit_every;
  }
  const std::size_t applied = update();
  if (editing && options_.strokes_per_second > 0) {
    const double rate = options_.strokes_per_second * static_cast<double>(scripts());
    const double due = std::chrono::duration<double>(now - started_).count() * rate;
    // Strokes that changed nothing (paint on a mesh without material channels) are skipped;
    // the cap keeps a long stall from bursting.
    const std::size_t cap = 64 * scripts();
    for (std::size_t i = 0; i < cap && static_cast<double>(strokes_) < due; ++i) stroke();
  }
  if (now >= next_submit_) {
    next_submit_ = now + options_.submit_every;
    submit(unsent_strokes_);  // counted by the session whether or not anything was sent
    unsent_strokes_ = 0;
  }
  return applied;
}

std::size_t SimulatedArtist::update() {
  // changed_ holds what the strokes wrote since the last submit: just what update() asks for.
  const std::size_t applied =
      options_.whole_mesh_submit ? session_.update(local_) : session_.update(local_, changed_);
  if (applied > 0) ++generation_;
  return applied;
}

bool SimulatedArtist::submit(std::uint32_t strokes) {
  const bool sent = options_.whole_mesh_submit ? session_.submit(local_, strokes)
                                               : session_.submit(local_, strokes, changed_);
  if (sent) ++generation_;  // a submit sets the sent values to what the peers receive
  changed_.clear();         // listed once: the session keeps what differs from its base
  return sent;
}

std::uint64_t SimulatedArtist::unacknowledged() const {
  const peer::SessionStats s = session_.stats();
  return s.strokes_submitted + unsent_strokes_ - s.strokes_acknowledged;
}

}  // namespace csculpt::cli
