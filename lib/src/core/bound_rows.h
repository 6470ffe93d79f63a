#pragma once
// Lower bounds of a point's distance to many triangles at once (not public API).
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/geometry.h"

namespace lodkit::detail {

/// The planes of m triangles in blocks of four (per block, 16 rows of four: normal x, y, z, offset,
/// then each edge plane's x, y, z, offset), so that one point's bounds against all of them take one
/// AVX2 instruction per row and block where the CPU has it (chosen at run time), with no scalar tail.
class BoundRows {
 public:
  /// Room for m triangles; set each with set().
  void resize(std::size_t m) {
    m_ = m;
    blocks_ = (m + 3) / 4;
    rows_.resize(64 * blocks_);
    bounds_.resize(4 * blocks_);
    planes_.resize(4 * blocks_);
    prism_.resize(m);
  }
  /// Triangle i's planes (a sliver's bound is 0, as TrianglePlanes::lower_bound2 has it).
  void set(std::size_t i, const TrianglePlanes& t) {
    double* r = rows_.data() + 64 * (i / 4) + i % 4;
    auto at = [&](int row) -> double& { return r[4 * row]; };
    prism_[i] = t.bounds;
    if (!t.bounds) {
      for (int row = 0; row < 16; ++row) at(row) = 0.0;
      return;
    }
    for (int c = 0; c < 3; ++c) {
      at(c) = t.normal[c];
      for (int e = 0; e < 3; ++e) at(4 + 4 * e + c) = t.edge_normal[e][c];
    }
    at(3) = t.offset;
    for (int e = 0; e < 3; ++e) at(7 + 4 * e) = t.edge_offset[e];
  }
  /// For each triangle i, no more than the squared distance from x to it (see
  /// TrianglePlanes::lower_bound2); valid until the next call.
  const double* lower_bounds2(const Eigen::Vector3d& x);
  /// The triangles whose bound from the last lower_bounds2(x) is below `limit`, as bits (triangle i:
  /// bit i). For at most 64 triangles.
  std::uint64_t below(double limit) const;
  /// The first triangle with the least bound from the last lower_bounds2(x) (at least one triangle).
  std::size_t lowest() const;
  /// For each triangle i, x's signed distance to its plane, from the last lower_bounds2(x). Where the
  /// bound equals its square, x lies inside the triangle's prism (no edge plane has it outside), and
  /// for a triangle that bounds (not a sliver), that is then x's squared distance to it.
  const double* plane_distances() const { return planes_.data(); }
  /// Whether the point of the last lower_bounds2(x) lies inside triangle i's prism, so that its squared
  /// plane distance is its squared distance to the triangle (never for a sliver, whose bound is 0).
  bool inside_prism(std::size_t i) const { return prism_[i] && bounds_[i] == planes_[i] * planes_[i]; }
  /// Whether the AVX2 kernel is used where the CPU has it (default); off, the plain one, which must
  /// give the same bits (tests switch it to check that).
  static void use_vector_kernel(bool on);

 private:
  std::size_t m_ = 0, blocks_ = 0;
  std::vector<double> rows_;
  std::vector<double> bounds_;  ///< the last point's bounds (padded to whole blocks)
  std::vector<double> planes_;  ///< the last point's signed distances to the planes
  std::vector<char> prism_;     ///< per triangle: whether its rows bound (not a sliver)
};

}  // namespace lodkit::detail
