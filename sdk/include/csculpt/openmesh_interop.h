// Conversion between csculpt::Mesh and OpenMesh triangle meshes, for hosts and tools built on
// OpenMesh. Channels travel as named persistent vertex properties.
#pragma once

#include <span>

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

#include "csculpt/mesh.h"

namespace csculpt {

using OpenMeshTriMesh = OpenMesh::TriMesh_ArrayKernelT<>;

/// Positions, triangles (vertex i -> vertex handle i, triangle t -> face handle t, corner order
/// kept) and every channel as a persistent vertex property named like the channel, of type
/// float (width 1) or OpenMesh::Vec2f / Vec3f / Vec4f.
/// Throws InvalidInput if the mesh fails validate(), or if OpenMesh cannot represent a
/// triangle (a non-manifold edge or vertex, or flipped orientation next to a neighbour): the
/// message names the first such triangle, rather than dropping it as add_face would.
OpenMeshTriMesh to_openmesh(const Mesh& mesh);

/// Positions, triangles and the given channels, each read from the vertex property of that
/// name and the type matching its width. Throws InvalidInput if one is missing or has another
/// type, if the mesh has deleted elements (call garbage_collection() first), or if the result
/// fails validate().
Mesh from_openmesh(const OpenMeshTriMesh& om, std::span<const ChannelDesc> channels);

/// As above, with every persistent vertex property of type float / Vec2f / Vec3f / Vec4f
/// (OpenMesh's own "v:" properties excluded), in property order, as a channel with
/// default_linearisation() of its name.
Mesh from_openmesh(const OpenMeshTriMesh& om);

}  // namespace csculpt
