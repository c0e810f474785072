#include "replication.h"

#include <string>

#include "csculpt/error.h"
#include "csculpt/hash.h"
#include "csculpt/wire.h"

namespace csculpt::peer {

std::uint64_t next_chain(std::uint64_t parent, const Diff& merged) {
  return hash_mix(parent, digest(merged));
}

void Replication::reset(std::uint64_t version, std::uint64_t chain, const ChainHistory& known) {
  version_ = version;
  chain_ = chain;
  history_.clear();
  history_bytes_ = 0;
  chains_.clear();
  const bool fits = !known.chains.empty() && known.chains.back() == chain &&
                    known.first + known.chains.size() - 1 == version;
  if (fits) {
    chains_.assign(known.chains.begin(), known.chains.end());
    chains_first_ = known.first;
  } else {
    chains_.push_back(chain);
    chains_first_ = version;
  }
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
  Diff merged = check(r, base);
  append(std::move(r), merged, base);
  return merged;
}

Diff Replication::check(const VersionRecord& r, const Mesh& base) const {
  DiffHeader header;
  Diff merged = decode_diff(r.diff_bytes, base, &header);
  if (header.base_version != version_)
    throw InvalidInput("version " + std::to_string(r.version) + " carries a diff based on " +
                       std::to_string(header.base_version));
  if (next_chain(chain_, merged) != r.chain)
    throw InvalidInput("version " + std::to_string(r.version) + " fails its hash chain");
  return merged;
}

void Replication::append(VersionRecord r, const Diff& merged, Mesh& base) {
  apply_diff(merged, base);
  version_ = r.version;
  chain_ = r.chain;
  if (chains_.empty()) chains_first_ = version_;  // a history that started with no reset()
  chains_.push_back(chain_);
  if (chains_.size() > kChainsKept) {
    chains_.pop_front();
    ++chains_first_;
  }
  history_bytes_ += r.diff_bytes.size();
  history_.push_back(std::move(r));
  while (history_.size() > 1 && history_bytes_ > kHistoryBytes) {
    history_bytes_ -= history_.front().diff_bytes.size();
    history_.pop_front();
  }
}

std::optional<std::uint64_t> Replication::chain_at(std::uint64_t version) const {
  if (version == version_) return chain_;
  if (version < chains_first_ || version - chains_first_ >= chains_.size()) return std::nullopt;
  return chains_[version - chains_first_];
}

ChainHistory Replication::recent_chains(std::size_t count) const {
  ChainHistory h;
  const std::size_t n = std::min(count, chains_.size());
  h.first = chains_first_ + (chains_.size() - n);
  h.chains.assign(chains_.end() - static_cast<std::ptrdiff_t>(n), chains_.end());
  return h;
}

std::optional<std::uint64_t> Replication::fork_point(const ChainHistory& theirs) const {
  if (theirs.chains.empty()) return std::nullopt;
  const std::uint64_t last = std::min(version_, theirs.first + theirs.chains.size() - 1);
  // Chains fold in every version before them: equal at v means equal up to v, so the search
  // could bisect; a linear scan from the end is as fast for the short forks partitions make.
  for (std::uint64_t v = last + 1; v-- > std::max(chains_first_, theirs.first);)
    if (chain_at(v) == theirs.chains[v - theirs.first]) return v;
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
