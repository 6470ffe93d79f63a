#include "simplify/attribute_quadric.h"

namespace lodkit::detail {

void AttributeQuadrics::add_face(std::size_t w, const Eigen::Vector3d p[3], const double* const s[3], double area) {
  Eigen::VectorXd P[3];
  for (int i = 0; i < 3; ++i) {
    P[i].resize(n_);
    P[i].head<3>() = p[i];
    for (int j = 0; j < k_; ++j) P[i][3 + j] = s[i][j];
  }
  Eigen::VectorXd e1 = P[1] - P[0];
  if (!(e1.norm() > 0)) return;
  e1.normalize();
  Eigen::VectorXd e2 = P[2] - P[0];
  e2 -= e1.dot(e2) * e1;
  if (!(e2.norm() > 0)) return;
  e2.normalize();
  // Distance to the plane through P0 spanned by e1, e2: A = I - e1 e1' - e2 e2', b = (P0.e1) e1 + (P0.e2) e2 - P0.
  const double d1 = P[0].dot(e1), d2 = P[0].dot(e2);
  double* q = &data_[w * stride_];
  std::size_t at = 0;
  for (int r = 0; r < n_; ++r)
    for (int c = r; c < n_; ++c) q[at++] += area * ((r == c ? 1.0 : 0.0) - e1[r] * e1[c] - e2[r] * e2[c]);
  for (int r = 0; r < n_; ++r) q[at++] += area * (d1 * e1[r] + d2 * e2[r] - P[0][r]);
  q[at] += area * (P[0].squaredNorm() - d1 * d1 - d2 * d2);
}

void AttributeQuadrics::merge(std::size_t w, std::size_t other) {
  for (std::size_t i = 0; i < stride_; ++i) data_[w * stride_ + i] += data_[other * stride_ + i];
}

void AttributeQuadrics::assemble(std::size_t a, std::size_t b, Eigen::MatrixXd& A, Eigen::VectorXd& bv, double& c) const {
  A.resize(n_, n_);
  bv.resize(n_);
  std::size_t at = 0;
  auto value = [&](std::size_t i) { return data_[a * stride_ + i] + (b != std::size_t(-1) ? data_[b * stride_ + i] : 0.0); };
  for (int r = 0; r < n_; ++r)
    for (int col = r; col < n_; ++col) A(r, col) = A(col, r) = value(at++);
  for (int r = 0; r < n_; ++r) bv[r] = value(at++);
  c = value(at);
}

double AttributeQuadrics::best_at(std::size_t a, std::size_t b, const Eigen::Vector3d& p, double* s) const {
  Eigen::MatrixXd A;
  Eigen::VectorXd bv;
  double c;
  assemble(a, b, A, bv, c);
  // For fixed p, the best s solves A_ss s = -(A_sp p + b_s).
  const Eigen::MatrixXd Ass = A.bottomRightCorner(k_, k_);
  const Eigen::VectorXd rhs = -(A.bottomLeftCorner(k_, 3) * p + bv.tail(k_));
  Eigen::VectorXd best = Ass.ldlt().solve(rhs);
  if (!best.allFinite()) {
    best.resize(k_);
    for (int j = 0; j < k_; ++j) best[j] = s[j];  // keep the current value
  }
  Eigen::VectorXd x(n_);
  x.head<3>() = p;
  x.tail(k_) = best;
  for (int j = 0; j < k_; ++j) s[j] = best[j];
  return std::max(0.0, x.dot(A * x) + 2 * bv.dot(x) + c);
}

}  // namespace lodkit::detail
