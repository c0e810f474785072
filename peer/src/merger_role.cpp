#include "merger_role.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "attribution.h"
#include "host_values.h"
#include "replication.h"

namespace csculpt::peer {
namespace {

/// Strokes that conflict as a conflict-rejecting system (MeshHisto) sees them: an edit
/// conflicts when another peer touched one of its vertices in the same window.
std::vector<bool> conflicts(const std::vector<std::vector<std::uint32_t>>& sets,
                            std::size_t vertex_count) {
  std::vector<std::uint8_t> hits(vertex_count, 0);
  for (const auto& s : sets)
    for (std::uint32_t v : s) hits[v] = static_cast<std::uint8_t>(std::min(2, hits[v] + 1));
  std::vector<bool> out;
  for (const auto& s : sets)
    out.push_back(std::any_of(s.begin(), s.end(), [&](std::uint32_t v) { return hits[v] > 1; }));
  return out;
}

}  // namespace

EncodeOptions session_wire_options(const EncodeOptions& wire, const MergeFrame& frame) {
  EncodeOptions o = wire;
  if (o.position_scale == 0) o.position_scale = frame.scale;
  return o;
}

MergerRole::MergerRole(std::shared_ptr<const Hierarchy> hierarchy)
    : hierarchy_(std::move(hierarchy)), merger_(*hierarchy_), folds_(hierarchy_->topology()) {}

bool MergerRole::accept(PeerId author, std::span<const std::uint8_t> diff_bytes,
                        std::uint32_t strokes, const Mesh& base, std::uint64_t version,
                        const MergeFrame& frame) {
  const DiffHeader header = peek_diff_header(diff_bytes);
  if (header.base_version != version) return false;
  PendingSubmit p;
  p.diff = decode_diff(diff_bytes, base);
  check_diff_values(p.diff, base, frame, "a submit");  // the same rule as the host's own
  p.sequence = header.sequence;
  p.strokes = strokes;
  auto [it, inserted] = pending_.try_emplace(author);
  if (inserted || it->second.sequence < p.sequence) it->second = std::move(p);
  return true;
}

MergeOutcome MergerRole::merge(Submits submits, const Mesh& base, std::uint64_t version,
                               std::uint64_t chain, const MergeFrame& frame,
                               const EncodeOptions& wire) {
  const auto t0 = Clock::now();
  std::vector<const Diff*> diffs;
  for (const auto& [peer, p] : submits) diffs.push_back(&p.diff);
  Diff merged = merger_.merge(base, diffs, MergeMethod::full, frame);
  // What everyone applies is the decoded message, the merger included.
  DiffHeader header;
  header.base_version = version;
  header.sequence = version + 1;
  header.author = "merge";
  MergeOutcome out;
  VersionRecord& r = out.record;
  r.diff_bytes = encode_diff(merged, base, header, session_wire_options(wire, frame), &out.decoded);
  r.merge_ms = std::chrono::duration<float, std::milli>(Clock::now() - t0).count();
  r.version = version + 1;
  r.parent_chain = chain;
  r.chain = next_chain(chain, out.decoded);
  std::vector<std::vector<std::uint32_t>> sets;
  for (const Diff* d : diffs) sets.push_back(touched(*d));
  const std::vector<bool> conflicting = conflicts(sets, base.vertex_count());
  std::size_t k = 0;
  for (const auto& [author, p] : submits) {
    r.merged.push_back({author, p.sequence, p.strokes});
    out.merged_strokes += p.strokes;
    if (conflicting[k]) r.conflicting += p.strokes;
    r.contributions.push_back(measure_contribution(author, p.diff, base, sets[k], frame.scale));
    ++k;
  }
  last_inputs_ = std::move(submits);
  last_merged_ = std::move(merged);
  return out;
}

std::uint32_t MergerRole::count_last_folds(const Mesh& base) {
  // One input merges to itself (Merger::merge): every fold of the result is one it made.
  if (last_inputs_.size() < 2) {
    last_inputs_.clear();
    return 0;
  }
  std::vector<const Diff*> diffs;
  for (const auto& [peer, p] : last_inputs_) diffs.push_back(&p.diff);
  const std::uint32_t folds = folds_.count_new_folds(base, diffs, last_merged_);
  last_inputs_.clear();
  return folds;
}

}  // namespace csculpt::peer
