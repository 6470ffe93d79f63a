#pragma once
// Small geometric kernels shared by the library (not public API).
#include <Eigen/Core>

namespace lodkit::detail {

/// Closest point to `p` on triangle (a, b, c); robust for degenerate triangles (Ericson, RTCD 5.1.5).
Eigen::Vector3d closest_point_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                          const Eigen::Vector3d& b, const Eigen::Vector3d& c);

inline double triangle_area(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                            const Eigen::Vector3d& c) {
  return 0.5 * (b - a).cross(c - a).norm();
}

}  // namespace lodkit::detail
