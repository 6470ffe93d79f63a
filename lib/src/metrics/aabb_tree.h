#pragma once
// A bounding-volume hierarchy over a mesh's triangles for closest-point queries.
#include <lodkit/mesh.h>

#include <Eigen/Geometry>
#include <vector>

namespace lodkit::detail {

class AabbTree {
 public:
  explicit AabbTree(const Mesh& mesh);

  struct Hit {
    Eigen::Vector3d point;
    double squared_distance;
    Index face;
  };
  /// Closest point on the mesh to `p`. `hint` (a face likely to be close) speeds up the search.
  Hit closest(const Eigen::Vector3d& p, Index hint = -1) const;

 private:
  struct Node {
    Eigen::AlignedBox3d box;
    int first, count;  // leaf: range in order_; inner: count == 0, children at first and first + 1
  };
  void build(int node, int begin, int end, const std::vector<Eigen::Vector3d>& centroids);
  const Mesh& mesh_;
  std::vector<Node> nodes_;
  std::vector<Index> order_;
};

}  // namespace lodkit::detail
