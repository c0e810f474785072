// Snapshots (the ZeroMQ guide's Clone pattern): the whole agreed mesh, the session's merge
// frame and the attribution so far, as one MeshSnapshot FlatBuffer sent in chunks to a joiner
// or to a peer that diverged. Pure logic: no sockets.
#pragma once

#include <cstdint>
#include <map>
#include <span>
#include <vector>

#include "csculpt/merge.h"
#include "csculpt/mesh.h"
#include "csculpt/peer/membership.h"

namespace csculpt::peer {

/// The hash chains of consecutive versions: chains[i] is the chain of version first + i.
struct ChainHistory {
  std::uint64_t first = 0;
  std::vector<std::uint64_t> chains;
};

struct Snapshot {
  Mesh mesh;
  MergeFrame frame;
  std::map<PeerId, std::vector<float>> attribution;  ///< per peer, a value per vertex
  /// The sender's latest chains, ending at the snapshot's version: where a receiver that held
  /// another branch forked from it (Replication::fork_point).
  ChainHistory chains;
};

std::vector<std::uint8_t> encode_snapshot(const Mesh& mesh, const MergeFrame& frame,
                                          const std::map<PeerId, std::vector<float>>& attribution,
                                          const ChainHistory& chains = {});
std::vector<std::uint8_t> encode_snapshot(const Snapshot& snap);
/// Throws InvalidInput saying what is wrong: failed verification, a mesh that fails validate(),
/// a missing frame or attribution of the wrong size.
Snapshot decode_snapshot(std::span<const std::uint8_t> bytes);

/// Collects one snapshot's chunks, in any order. Chunks of another snapshot (version or size)
/// are ignored while one is under way; reset() gives up on it (its sender went quiet).
class SnapshotAssembly {
 public:
  /// Adds a chunk; true when every byte is in (then take()). A chunk already added counts
  /// once. Throws InvalidInput for a chunk outside its buffer.
  bool add(std::uint64_t version, std::uint64_t chain, std::uint64_t offset, std::uint64_t total,
           std::span<const std::uint8_t> data);
  /// The assembled bytes; the assembly is empty afterwards (its memory freed).
  std::vector<std::uint8_t> take();
  /// Drops a snapshot under way.
  void reset();
  std::uint64_t version() const { return version_; }
  std::uint64_t chain() const { return chain_; }

 private:
  static constexpr std::uint64_t kNone = ~std::uint64_t{0};
  std::uint64_t version_ = kNone;  // of the snapshot being assembled; none yet
  std::uint64_t chain_ = 0;
  std::uint64_t total_ = kNone;                  // bytes of the snapshot being assembled
  std::vector<std::uint8_t> buffer_;             // up to `total_` bytes, grown as chunks come
  std::map<std::uint64_t, std::size_t> chunks_;  // offset -> size of the chunks added
  std::size_t received_ = 0;                     // bytes of the chunks added
};

}  // namespace csculpt::peer
