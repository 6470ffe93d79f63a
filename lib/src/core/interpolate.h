#pragma once
// Vertex values (normals, UVs, colours) interpolated over a mesh's face (not public API).
#include <lodkit/mesh.h>

#include "core/geometry.h"

namespace lodkit::detail {

/// The barycentric weights of p (on or near face f of m) over the face's corners.
inline Eigen::Vector3d face_weights(const Mesh& m, Index f, const Eigen::Vector3d& p) {
  return barycentric(m.positions.row(m.triangles(f, 0)).transpose(), m.positions.row(m.triangles(f, 1)).transpose(),
                     m.positions.row(m.triangles(f, 2)).transpose(), p);
}

/// `rows`, one row per vertex of m (its normals or colours), at weights w over face f's corners.
template <typename Rows>
Eigen::Matrix<double, Rows::ColsAtCompileTime, 1> interpolate(const Mesh& m, Index f, const Eigen::Vector3d& w, const Rows& rows) {
  Eigen::Matrix<double, Rows::ColsAtCompileTime, 1> value = Eigen::Matrix<double, Rows::ColsAtCompileTime, 1>::Zero();
  for (int k = 0; k < 3; ++k) value += w[k] * rows.row(m.triangles(f, k)).transpose().template cast<double>();
  return value;
}

}  // namespace lodkit::detail
