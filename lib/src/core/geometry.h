#pragma once
// Small geometric kernels shared by the library (not public API). Inline: the closest-point query
// runs tens of millions of times in hoppe's energy and the distance measurements.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>

namespace lodkit::detail {

/// A ball: the progressive mesh's error bounds follow balls of input vertices up the collapses.
struct Ball {
  Eigen::Vector3d centre;
  double radius;
};

/// The smallest ball holding both, padded by a relative epsilon so that rounding never leaves it a
/// hair small (the bounds built on it stay conservative).
inline Ball enclosing_ball(const Ball& a, const Ball& b) {
  const double d = (b.centre - a.centre).norm();
  if (d + b.radius <= a.radius) return a;
  if (d + a.radius <= b.radius) return b;
  const double r = 0.5 * (d + a.radius + b.radius);  // d > 0: equal centres put one ball inside the other
  const Eigen::Vector3d c = a.centre + (b.centre - a.centre) * ((r - a.radius) / d);
  return {c, r * (1 + 1e-12) + 1e-300};
}

/// The angle between two directions, accurate near 0 and pi, where acos of the cosine loses half the
/// digits (the AABB tree's acos form pads its angles by a slack instead).
inline double direction_angle(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

/// A cone of directions: those within `half_angle` (radians, up to pi) of the unit `axis`; none when
/// half_angle < 0.
struct NormalCone {
  Eigen::Vector3d axis;
  double half_angle;
};

/// The narrowest cone around both (Hoppe's normal cones for view-dependent refinement).
inline NormalCone enclosing_cone(const NormalCone& a, const NormalCone& b) {
  if (a.half_angle < 0) return b;
  if (b.half_angle < 0) return a;
  const double between = direction_angle(a.axis, b.axis);
  if (between + b.half_angle <= a.half_angle) return a;
  if (between + a.half_angle <= b.half_angle) return b;
  const double half = 0.5 * (between + a.half_angle + b.half_angle);
  if (half >= std::numbers::pi || !(between > 0)) return {a.axis, std::min(half, std::numbers::pi)};
  // Turn a's axis towards b's by half - a.half_angle, in their common plane.
  const Eigen::Vector3d across = (b.axis - a.axis.dot(b.axis) * a.axis).normalized();
  const double turn = half - a.half_angle;
  return {(std::cos(turn) * a.axis + std::sin(turn) * across).normalized(), half * (1 + 1e-12)};
}

/// Where the nearest point to x on segment a b lies, as t in [0, 1] along it (0 for a point-like segment).
inline double segment_parameter(const Eigen::Vector3d& x, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d d = b - a;
  const double len2 = d.squaredNorm();
  return len2 > 0 ? std::clamp((x - a).dot(d) / len2, 0.0, 1.0) : 0.0;
}

/// Closest point to `p` on triangle (a, b, c); robust for degenerate triangles (Ericson, RTCD 5.1.5).
inline Eigen::Vector3d closest_point_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                                 const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  // Voronoi-region walk: vertex regions, then edge regions, then the interior.
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  // (Each edge region needs its edge to have length: for a triangle with a repeated corner the
  // division was 0/0, a NaN point, and a mesh of one such face had no nearest face at all.)
  if (vc <= 0 && d1 >= 0 && d3 <= 0 && d1 - d3 > 0) return a + (d1 / (d1 - d3)) * ab;
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0 && d2 - d6 > 0) return a + (d2 / (d2 - d6)) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0 && (d4 - d3) + (d5 - d6) > 0)
    return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
  const double sum = va + vb + vc;
  if (!(sum > 0)) {  // degenerate (collinear) triangle: fall back to the closest of its edges
    auto on_segment = [&](const Eigen::Vector3d& s, const Eigen::Vector3d& e) {
      return Eigen::Vector3d(s + segment_parameter(p, s, e) * (e - s));
    };
    Eigen::Vector3d best = on_segment(a, b);
    for (const Eigen::Vector3d& q : {on_segment(b, c), on_segment(c, a)})
      if ((q - p).squaredNorm() < (best - p).squaredNorm()) best = q;
    return best;
  }
  const double v = vb / sum, w = vc / sum;
  return a + ab * v + ac * w;
}

/// The weights (v, w) of corners b and c at p's foot on the plane of triangle a b c, unclamped (negative
/// beyond an edge; the foot is a + v (b - a) + w (c - a)). Nothing for a triangle whose angle at a has
/// a squared sine of `min_sine2` or less (0: only a degenerate one), where the plane is uncertain.
inline std::optional<Eigen::Vector2d> plane_weights(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                                    const Eigen::Vector3d& c, const Eigen::Vector3d& p,
                                                    double min_sine2 = 0) {
  const Eigen::Vector3d e0 = b - a, e1 = c - a, ep = p - a;
  const double d00 = e0.dot(e0), d01 = e0.dot(e1), d11 = e1.dot(e1), dp0 = ep.dot(e0), dp1 = ep.dot(e1);
  const double det = d00 * d11 - d01 * d01;
  if (!(det > min_sine2 * d00 * d11)) return std::nullopt;
  return Eigen::Vector2d((d11 * dp0 - d01 * dp1) / det, (d00 * dp1 - d01 * dp0) / det);
}

/// Barycentric coordinates of p (on or near triangle a b c), clamped to the triangle; the centroid's
/// for a degenerate triangle.
inline Eigen::Vector3d barycentric(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                                   const Eigen::Vector3d& p) {
  const auto vw = plane_weights(a, b, c, p);
  if (!vw) return Eigen::Vector3d::Constant(1.0 / 3);
  const double v = vw->x(), w = vw->y();
  const Eigen::Vector3d bary = Eigen::Vector3d(1 - v - w, v, w).cwiseMax(0.0);
  return bary / bary.sum();
}

/// A triangle's plane and the three planes through its edges at right angles to it (outward unit
/// normals). Together they bound the distance to the triangle from below, cheaply; callers that skip
/// a triangle on the bound leave a margin of about 1e-9 of the coordinates for rounding.
struct TrianglePlanes {
  Eigen::Vector3d normal, edge_normal[3];
  double offset, edge_offset[3];
  double twice_area = 0;  ///< |(c1 - c0) x (c2 - c0)|
  /// False for a sliver (its angle at c0 under ~1e-4 rad): its normal is too uncertain for the margin,
  /// so the bound is 0 (here and in BoundRows, the same bound vectorised).
  bool bounds = true;

  /// Sets the planes of triangle c[0..2]; returns |(c1 - c0) x (c2 - c0)|^2 (four times the area squared).
  double set(const Eigen::Vector3d* c) {
    const Eigen::Vector3d e1 = c[1] - c[0], e2 = c[2] - c[0];
    const Eigen::Vector3d n = e1.cross(e2);
    const double area2 = n.squaredNorm();
    // n's rounding error, relative, is about 1e-16 / sin(angle at c0).
    bounds = area2 > 1e-8 * e1.squaredNorm() * e2.squaredNorm();
    const double len = std::sqrt(area2);
    twice_area = len;
    normal = len > 0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
    offset = normal.dot(c[0]);
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d outward = (c[(k + 1) % 3] - c[k]).cross(normal);
      const double l = outward.norm();
      edge_normal[k] = l > 0 ? Eigen::Vector3d(outward / l) : Eigen::Vector3d::Zero();
      edge_offset[k] = edge_normal[k].dot(c[k]);
    }
    return area2;
  }
  /// No more than the squared distance from x to the triangle: the squared distance to its plane plus
  /// the square of how far x lies outside the farthest edge plane (at right angles to each other).
  double lower_bound2(const Eigen::Vector3d& x) const {
    if (!bounds) return 0.0;
    const double plane = normal.dot(x) - offset;
    double outside = 0;
    for (int k = 0; k < 3; ++k) outside = std::max(outside, edge_normal[k].dot(x) - edge_offset[k]);
    return plane * plane + outside * outside;
  }
};

inline double triangle_area(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                            const Eigen::Vector3d& c) {
  return 0.5 * (b - a).cross(c - a).norm();
}

/// A triangle's quality, 4 sqrt(3) area / sum of squared edges: 1 when equilateral, 0 when degenerate.
/// `twice_area`: |(b - a) x (c - a)|, which callers checking a face's turn have at hand already.
inline double triangle_quality(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                               double twice_area) {
  constexpr double kTwoRootThree = 3.4641016151377544;  // 2 sqrt(3): half of 4 sqrt(3), for the doubled area
  const double sum = (b - a).squaredNorm() + (c - b).squaredNorm() + (a - c).squaredNorm();
  return sum > 0 ? kTwoRootThree * twice_area / sum : 0.0;
}

/// A point near `box` to measure positions from, such that p - origin is exact for every p in the box,
/// and so (p - origin) + origin == p. Per axis, Sterbenz's lemma: x - o is exact when o/2 <= x <= 2o, so
/// where the box lies within a factor of four of its distance from zero on one side, o is its centre
/// clamped to [max/2, 2 min] (mirrored below zero); elsewhere 0, which then lies closer to the box
/// than a third of its extent.
inline Eigen::Vector3d local_origin(const Eigen::AlignedBox3d& box) {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  if (box.isEmpty()) return origin;
  for (int i = 0; i < 3; ++i) {
    const double lo = box.min()[i], hi = box.max()[i];
    if (lo > 0 && hi <= 4 * lo) origin[i] = std::clamp(0.5 * (lo + hi), 0.5 * hi, 2 * lo);
    else if (hi < 0 && lo >= 4 * hi) origin[i] = std::clamp(0.5 * (lo + hi), 2 * hi, 0.5 * lo);
  }
  return origin;
}

}  // namespace lodkit::detail
