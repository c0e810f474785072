// The host side's rebase: how a host's local mesh follows the agreed versions without losing,
// doubling or blocking a stroke. A merged version replaces what this peer submitted of it; edits
// made since the submit are merged (with the SDK merge) onto the new version. Pure logic.
#pragma once

#include <functional>
#include <span>

#include "csculpt/diff.h"
#include "csculpt/merge.h"
#include "csculpt/mesh.h"

namespace csculpt::peer {

/// Whether `local` has `base`'s vertex count and channel sizes.
bool same_layout(const Mesh& base, const Mesh& local);
/// Whether `local` equals `base` with `d` applied (bitwise; `d` null: `base` itself), without
/// making that state.
bool equals_base_plus(const Mesh& base, const Diff* d, const Mesh& local);
/// Puts the vertices `d` changes back to their values in `base`.
void restore(const Mesh& base, const Diff& d, Mesh& local);

/// Moves `base` (the agreed version) on by `merged` (the diffs of consecutive versions, in
/// order) and `local` with it. `ours` is what this peer submitted of them (null if none of its
/// submits is in): `local` edits beyond it are merged onto the last version, once however many
/// versions there are, and what it submitted is not applied twice. `local` empty becomes the
/// new base. `before_each(i, base)`, if given, sees the base each diff is about to be applied
/// to. Returns true when there were such edits (a rebase). Throws InvalidInput when `local`'s
/// layout is not `base`'s. `unedited`: the caller knows `local` equals `base` plus `ours` (the
/// whole-mesh comparison is skipped).
bool rebase_onto_versions(Mesh& base, const Diff* ours, std::span<const Diff* const> merged,
                          Mesh& local, Merger& merger, const MergeFrame& frame, bool unedited,
                          const std::function<void(std::size_t, const Mesh&)>& before_each = {});

/// One version's rebase_onto_versions.
inline bool rebase_onto_version(Mesh& base, const Diff* ours, const Diff& merged, Mesh& local,
                                Merger& merger, const MergeFrame& frame, bool unedited = false) {
  const Diff* one[1] = {&merged};
  return rebase_onto_versions(base, ours, one, local, merger, frame, unedited);
}

/// Carries `local`'s edits (from `base`) over to `snapshot`, which becomes the base. Returns true
/// when there were edits to carry (a rebase); `local` empty becomes the snapshot.
bool rebase_onto_snapshot(Mesh& base, const Mesh& snapshot, Mesh& local, Merger& merger,
                          const MergeFrame& frame);

}  // namespace csculpt::peer
