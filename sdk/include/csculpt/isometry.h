// Per-vertex isometries of an edit (paper §3.1 "Per-Vertex Isometries").
#pragma once

#include <span>
#include <vector>

#include "csculpt/dual_quat.h"
#include "csculpt/hierarchy.h"

namespace csculpt {

/// Closest rotation (Frobenius norm) to the row-major 3x3 matrix `a`, as a quaternion with
/// w >= 0. Uses a scaled Newton iteration for the polar decomposition (Higham 1986), which is
/// exact at convergence and about ten times faster than an SVD; falls back to the SVD for
/// reflections (det < 0) and near-singular matrices. Returns false if `a` has rank < 2.
bool closest_rotation(const double a[9], Quat& out);

/// Reference: the same through Eigen's JacobiSVD, R = U diag(1, 1, det(U V^T)) V^T.
bool closest_rotation_svd(const double a[9], Quat& out);

/// Quaternion (w >= 0) of a proper rotation matrix (row-major), Shepperd's method.
Quat quat_from_rotation_matrix(const double m[9]);

/// The rotation of one triangle: SVD-closest rotation to A = (e0b, e1b, nb)(e0a, e1a, na)^-1,
/// computed in closed form (see the kernel): equal to closest_rotation_svd(A) to rounding.
/// Returns false for a triangle degenerate before or after the edit (it then contributes
/// nothing, so it cannot poison its vertices).
bool face_rotation(const Vec3f& a0, const Vec3f& a1, const Vec3f& a2, const Vec3f& b0,
                   const Vec3f& b1, const Vec3f& b2, Quat& out);

/// Dense per-vertex isometries of `edited` against `base` (same topology), as used by the
/// merge: rotation = normalised sum of incident face rotations (degenerate faces count as
/// the identity), translation such that each vertex lands exactly on its edited position.
/// Identity where the vertex and all its neighbours are unchanged.
std::vector<DualQuat> vertex_isometries(const Topology& topology, std::span<const Vec3f> base,
                                        std::span<const Vec3f> edited);

}  // namespace csculpt
