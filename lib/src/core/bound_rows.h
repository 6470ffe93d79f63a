#pragma once
// Lower bounds of a point's distance to many triangles at once (not public API).
#include <cstddef>
#include <vector>

#include "core/geometry.h"

namespace lodkit::detail {

/// The planes of m triangles side by side (rows of m: normal x, y, z, offset, then each edge plane's
/// x, y, z, offset), so that one point's bounds against all of them vectorise: four triangles per
/// instruction where the CPU has AVX2, chosen at load time.
class BoundRows {
 public:
  /// Room for m triangles; set each with set().
  void resize(std::size_t m) {
    m_ = m;
    rows_.resize(16 * m);
    bounds_.resize(m);
    planes_.resize(m);
  }
  /// Triangle i's planes (a sliver's bound is 0, as TrianglePlanes::lower_bound2 has it).
  void set(std::size_t i, const TrianglePlanes& t) {
    if (!t.bounds) {
      for (int r = 0; r < 16; ++r) rows_[r * m_ + i] = 0.0;
      return;
    }
    for (int c = 0; c < 3; ++c) {
      rows_[c * m_ + i] = t.normal[c];
      for (int e = 0; e < 3; ++e) rows_[(4 + 4 * e + c) * m_ + i] = t.edge_normal[e][c];
    }
    rows_[3 * m_ + i] = t.offset;
    for (int e = 0; e < 3; ++e) rows_[(7 + 4 * e) * m_ + i] = t.edge_offset[e];
  }
  /// For each triangle i, no more than the squared distance from x to it (see
  /// TrianglePlanes::lower_bound2); valid until the next call.
  const double* lower_bounds2(const Eigen::Vector3d& x);
  /// For each triangle i, x's signed distance to its plane, from the last lower_bounds2(x). Where the
  /// bound equals its square, x lies inside the triangle's prism (no edge plane has it outside), and
  /// for a triangle that bounds (not a sliver), that is then x's squared distance to it.
  const double* plane_distances() const { return planes_.data(); }

 private:
  std::size_t m_ = 0;
  std::vector<double> rows_;
  std::vector<double> bounds_;  ///< the last point's bounds
  std::vector<double> planes_;  ///< the last point's signed distances to the planes
};

}  // namespace lodkit::detail
