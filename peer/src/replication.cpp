#include "replication.h"

#include <string>

#include "csculpt/error.h"
#include "csculpt/hash.h"
#include "csculpt/wire.h"

namespace csculpt::peer {

std::uint64_t next_chain(std::uint64_t parent, const Diff& merged) {
  return hash_mix(parent, digest(merged));
}

void Replication::reset(std::uint64_t version, std::uint64_t chain) {
  version_ = version;
  chain_ = chain;
  history_.clear();
}

Replication::Arrival Replication::classify(std::uint64_t version,
                                           std::uint64_t parent_chain) const {
  if (version <= version_) return Arrival::held;
  if (version > version_ + 1) return Arrival::gap;
  return parent_chain == chain_ ? Arrival::next : Arrival::other_branch;
}

void Replication::buffer(VersionRecord r) {
  if (buffered_.size() < kHistory) buffered_[r.version] = std::move(r);
}

std::optional<VersionRecord> Replication::take_next_buffered() {
  while (!buffered_.empty()) {
    auto it = buffered_.begin();
    if (it->first <= version_) {
      buffered_.erase(it);
      continue;
    }
    if (it->first != version_ + 1 || it->second.parent_chain != chain_) return std::nullopt;
    VersionRecord r = std::move(it->second);
    buffered_.erase(it);
    return r;
  }
  return std::nullopt;
}

Diff Replication::accept(VersionRecord r, Mesh& base) {
  DiffHeader header;
  Diff merged = decode_diff(r.diff_bytes, base, &header);
  if (header.base_version != version_)
    throw InvalidInput("version " + std::to_string(r.version) + " carries a diff based on " +
                       std::to_string(header.base_version));
  if (next_chain(chain_, merged) != r.chain)
    throw InvalidInput("version " + std::to_string(r.version) + " fails its hash chain");
  apply_diff(merged, base);
  version_ = r.version;
  chain_ = r.chain;
  history_.push_back(std::move(r));
  if (history_.size() > kHistory) history_.pop_front();
  return merged;
}

std::optional<std::uint64_t> Replication::chain_at(std::uint64_t version) const {
  if (version == version_) return chain_;
  for (const VersionRecord& r : history_)
    if (r.version == version) return r.chain;
  return std::nullopt;
}

bool Replication::diverges(std::uint64_t version, std::uint64_t chain) const {
  const std::optional<std::uint64_t> ours = chain_at(version);
  return ours && *ours != chain;
}

std::optional<std::vector<const VersionRecord*>> Replication::since(std::uint64_t after) const {
  if (history_.empty() || history_.front().version > after + 1) return std::nullopt;
  std::vector<const VersionRecord*> out;
  for (const VersionRecord& r : history_)
    if (r.version > after) out.push_back(&r);
  return out;
}

}  // namespace csculpt::peer
