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
  /// far enough out from p, the answer follows without a search (see the .cpp); without
  /// prepare_facing(), every call searches. Safe to call from several threads.
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
  };
  // Per face, its leaf's certificate for facing_against(): a normal n with axis . n > min_dot |n|,
  // asked about at a point p with 2 |p - anchor| < clearance, needs no search. 32 bytes, read by face
  // number: the caller's hint is usually the face it is looking at.
  struct Facing {
    Eigen::Vector3f axis = Eigen::Vector3f::Zero();
    float min_dot = 2;  // never
    Eigen::Vector3f anchor = Eigen::Vector3f::Zero();
    float clearance = 0;  // from the anchor, less its distance off the surface; 0: never
  };
  /// Fills in `node` over slots [begin, end); its descendants take indices from `free` on.
  void build(int node, int free, int begin, int end, const std::vector<Eigen::Vector3d>& centroids);
  /// Distance from p to the nearest face whose normal is more than `angle` from unit `axis`, or
  /// `limit` if there is none nearer.
  double distance_to_turned(const Eigen::Vector3d& p, const Eigen::Vector3d& axis, double angle, double limit) const;
  /// The certificate of every face in leaf node `leaf`.
  void set_facing(int leaf);
  const Mesh& mesh_;
  std::vector<Node> nodes_;
  std::vector<Index> order_;
  // prepare_facing():
  std::vector<Eigen::Vector3d> normals_;  // per face, unit (zero: no area)
  std::vector<Cone> cones_;              // per node
  std::vector<Facing> facing_;           // per face
};

}  // namespace lodkit::detail
