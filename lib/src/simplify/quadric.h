#pragma once
// Garland-Heckbert quadric: Q(p) = p^T A p + 2 b^T p + c, the weighted sum of squared distances from p
// to a set of planes. `weight` is the total weight (area) so that Q / weight is a mean squared distance.
#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <optional>

namespace lodkit::detail {

struct Quadric {
  // Upper triangle of the symmetric A: xx xy xz yy yz zz.
  double a00 = 0, a01 = 0, a02 = 0, a11 = 0, a12 = 0, a22 = 0;
  double b0 = 0, b1 = 0, b2 = 0, c = 0;
  double weight = 0;

  /// The plane n . p + d = 0 (n unit) with weight w.
  static Quadric plane(const Eigen::Vector3d& n, double d, double w) {
    Quadric q;
    q.a00 = w * n.x() * n.x(), q.a01 = w * n.x() * n.y(), q.a02 = w * n.x() * n.z();
    q.a11 = w * n.y() * n.y(), q.a12 = w * n.y() * n.z(), q.a22 = w * n.z() * n.z();
    q.b0 = w * d * n.x(), q.b1 = w * d * n.y(), q.b2 = w * d * n.z();
    q.c = w * d * d;
    q.weight = w;
    return q;
  }

  Quadric& operator+=(const Quadric& o) {
    a00 += o.a00, a01 += o.a01, a02 += o.a02, a11 += o.a11, a12 += o.a12, a22 += o.a22;
    b0 += o.b0, b1 += o.b1, b2 += o.b2, c += o.c, weight += o.weight;
    return *this;
  }
  friend Quadric operator+(Quadric a, const Quadric& b) { return a += b; }

  double evaluate(const Eigen::Vector3d& p) const {
    const double x = p.x(), y = p.y(), z = p.z();
    const double v = x * (a00 * x + 2 * a01 * y + 2 * a02 * z) + y * (a11 * y + 2 * a12 * z) + a22 * z * z +
                     2 * (b0 * x + b1 * y + b2 * z) + c;
    return std::max(v, 0.0);  // rounding can dip below zero
  }

  Eigen::Matrix3d A() const {
    Eigen::Matrix3d m;
    m << a00, a01, a02, a01, a11, a12, a02, a12, a22;
    return m;
  }
  Eigen::Vector3d b() const { return {b0, b1, b2}; }

  /// The minimiser of Q nearest to `anchor`. Where A is near-singular (a flat or straight
  /// neighbourhood leaves p free along the plane or the line) the directions Q does not constrain stay
  /// at the anchor. Returns false when Q constrains nothing.
  bool minimiser_near(const Eigen::Vector3d& anchor, Eigen::Vector3d& out, double regularisation = 1e-8) const {
    const Eigen::Matrix3d a = A();
    if (const auto solved = well_conditioned_minimiser(a, out)) return *solved;
    // Minimise Q(p) + eps |p - anchor|^2. Along an eigenvector of A with eigenvalue lambda the step
    // from the anchor is scaled by lambda / (lambda + eps): all of it where Q constrains p, none where
    // it does not. The quadric cost used truncated_minimiser_near() before: the same idea with a hard
    // cut, but a trigonometric eigen-solve for 4 in 5 candidates on a scan. The errors were equal or
    // lower on five meshes at five targets each; eps = 1e-6 of the trace was worse on fandisk
    // (docs/benchmarks-log.md, "Engine speed-ups, session 9").
    Eigen::Matrix3d r = a;
    r.diagonal().array() += regularisation * a.trace();
    out = anchor - r.inverse() * (a * anchor + b());
    return out.allFinite();
  }

  /// As minimiser_near(), with a hard cut: directions whose eigenvalue is below `relative_floor` times
  /// the largest stay at the anchor's value. An eigen-solve; hoppe starts its local optimisation here
  /// (from the regularised point its RMS was higher on four of five meshes, and fandisk took 30 % longer).
  bool truncated_minimiser_near(const Eigen::Vector3d& anchor, Eigen::Vector3d& out, double relative_floor = 1e-6) const {
    const Eigen::Matrix3d a = A();
    if (const auto solved = well_conditioned_minimiser(a, out)) return *solved;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
    eig.computeDirect(a);
    const Eigen::Vector3d& lambda = eig.eigenvalues();
    const double top = lambda.cwiseAbs().maxCoeff();
    const Eigen::Vector3d gradient = a * anchor + b();
    out = anchor;
    for (int i = 0; i < 3; ++i) {
      if (lambda[i] <= relative_floor * top) continue;
      const Eigen::Vector3d e = eig.eigenvectors().col(i);
      out -= (e.dot(gradient) / lambda[i]) * e;
    }
    return out.allFinite();
  }

 private:
  /// The plain 3x3 solve where A is well conditioned (a corner-like neighbourhood): whether its result
  /// is finite. False where Q constrains nothing; nothing where A is too near singular for it.
  std::optional<bool> well_conditioned_minimiser(const Eigen::Matrix3d& a, Eigen::Vector3d& out) const {
    const double scale = a.trace();
    if (!(scale > 0)) return false;
    if (a.determinant() <= 1e-6 * scale * scale * scale) return std::nullopt;
    out = -a.inverse() * b();
    return out.allFinite();
  }
};

}  // namespace lodkit::detail
