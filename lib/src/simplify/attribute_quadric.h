#pragma once
// Attribute-aware quadrics (Garland & Heckbert, "Simplifying surfaces with color and texture using
// quadric error metrics", 1998): each face is a triangle in R^(3+k) whose extra coordinates are its
// corners' attributes (normals, UVs, colours, scaled by user weights); the quadric of a wedge measures
// squared distance to the planes of its faces in that space. The simplifier keeps one per wedge, so
// the two sides of a seam keep separate attribute errors.
#include <Eigen/Dense>
#include <vector>

namespace lodkit::detail {

class AttributeQuadrics {
 public:
  /// k attribute dimensions per wedge; 0 turns the whole thing off.
  void reset(int k, std::size_t wedges) {
    k_ = k;
    n_ = 3 + k;
    stride_ = n_ * (n_ + 1) / 2 + n_ + 1;
    data_.assign(k ? wedges * stride_ : 0, 0.0);
  }
  int dims() const { return k_; }
  bool enabled() const { return k_ > 0; }

  /// Adds face (p[i], s[i]) with weight `area` to wedge w's quadric.
  void add_face(std::size_t w, const Eigen::Vector3d p[3], const double* const s[3], double area);
  /// q(w) += q(other)
  void merge(std::size_t w, std::size_t other);
  /// The error of placing wedges a + b at position p with their best attribute value, written to `s`.
  double best_at(std::size_t a, std::size_t b, const Eigen::Vector3d& p, double* s) const;

 private:
  // Assembles (A, b, c) of a, or of a + b when b != npos.
  void assemble(std::size_t a, std::size_t b, Eigen::MatrixXd& A, Eigen::VectorXd& bv, double& c) const;
  int k_ = 0, n_ = 3;
  std::size_t stride_ = 0;
  std::vector<double> data_;
};

}  // namespace lodkit::detail
