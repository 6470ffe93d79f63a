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

  /// Readies facing_against(): each face's unit normal and each node's cone of normals.
  void prepare_facing();
  /// Whether `normal` faces against (negative dot with) the normal of the face closest(p) finds; a
  /// face without area faces neither way. `hint`: a face near p, or -1; on return, a face near p to
  /// start from next time. Where the faces around the hint all lie within a narrow cone of normals
  /// far enough out from p, the answer follows without a search (see the .cpp). Needs prepare_facing();
  /// safe to call from several threads.
  bool facing_against(const Eigen::Vector3d& p, const Eigen::Vector3d& normal, Index& hint) const;

 private:
  struct Node {
    Eigen::AlignedBox3d box;
    int first, count;  // leaf: range in order_; inner: count == 0, children at first and first + 1
  };
  struct Cone {
    Eigen::Vector3d axis;
    double half_angle;  // radians, never too small; < 0: the node has no face with area
    double cos_half = 1, sin_half = 0;  // set once every cone is known
    double min_facing_dot = 2;  // facing_against() may skip its search for a normal n with axis . n above this
  };
  /// Fills in `node` over slots [begin, end); its descendants take indices from `free` on.
  void build(int node, int free, int begin, int end, const std::vector<Eigen::Vector3d>& centroids);
  /// Distance from p to the nearest face whose normal is more than `angle` from unit `axis`, or
  /// `limit` if there is none nearer.
  double distance_to_turned(const Eigen::Vector3d& p, const Eigen::Vector3d& axis, double angle, double limit) const;
  /// For leaf node `leaf`: how far from its box's centre every face keeps within kTurn of its cone.
  double clearance(int leaf) const;
  const Mesh& mesh_;
  std::vector<Node> nodes_;
  std::vector<Index> order_;
  // prepare_facing():
  std::vector<Eigen::Vector3d> normals_;  // per face, unit (zero: no area)
  std::vector<Cone> cones_;              // per node
  std::vector<int> leaf_of_;             // per face
  mutable std::vector<float> clearance_;  // per node, filled in on first use (-1: not yet)
};

}  // namespace lodkit::detail
