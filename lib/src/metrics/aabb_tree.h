#pragma once
// A bounding-volume hierarchy over a mesh's triangles for closest-point queries.
// Boxes are floats: the mesh's coordinates must lie within a float's range, as validate() requires
// of every mesh a public entry point takes.
#include <lodkit/mesh.h>

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

namespace lodkit::detail {

class AabbTree {
 public:
  // The layout's limits. A leaf's face count and first slot are packed into a quad (Quad::next).
  static constexpr Index kMostFaces = Index{1} << 29;
  static constexpr int kLeafSize = 4;  // faces a leaf holds at most
  static_assert(kLeafSize <= 4, "Quad::next holds a leaf's face count in two bits");
  // Surface-area splits stop this deep, median splits below: no tree is deeper than kMostDepth (a
  // median subtree of up to kMostFaces faces takes 28 levels), which the searches' stack is sized for.
  static constexpr int kSurfaceAreaDepth = 40;
  static constexpr int kMostDepth = kSurfaceAreaDepth + 28;

  struct Options {
    /// Keep a copy of every face's corners in the tree's order (72 bytes a face), which makes closest()
    /// about 15 % faster; facing_against() does not use it.
    bool copy_corners = true;
    /// Split nodes where the surface area heuristic says rather than at the median: on CAD meshes a
    /// query then visits half the nodes, on scans a tenth fewer; it takes about 1.7 times as long to
    /// build (igea_loop1: 0.19 s against 0.11 s on two cores).
    bool surface_area_splits = true;
  };
  AabbTree(const Mesh& mesh, const Options& options);
  explicit AabbTree(const Mesh& mesh) : AabbTree(mesh, Options{}) {}

  struct Hit {
    Eigen::Vector3d point;
    double squared_distance;
    Index face;
  };
  /// Closest point on the mesh to `p`. `hint` (a face likely to be close) speeds up the search.
  Hit closest(const Eigen::Vector3d& p, Index hint = -1) const;
  /// Closest point to `p` on face `face` alone (no search): an upper bound of closest()'s distance.
  Hit closest_on(const Eigen::Vector3d& p, Index face) const {
    const Eigen::Vector3d q = closest_on_face(p, face);
    return {q, (q - p).squaredNorm(), face};
  }

  /// The boxes (and copied corners) again, after the mesh's positions moved in place, its faces the
  /// same: the tree keeps its shape, so searches slow down as the positions drift, but every answer is
  /// as exact as a new tree's (and the same: see closest()). Much cheaper than building again. Not for
  /// a tree readied by prepare_facing().
  void refit();

  /// Readies facing_against(): each face's unit normal and each node's cone of normals.
  void prepare_facing();
  /// Face f's normal: unit where prepare_facing() ran (zero without area), else its corners' cross product.
  Eigen::Vector3d face_normal(Index f) const;
  /// Whether `normal` faces against (negative dot with) the normal of the face closest(p) finds; a
  /// face without area faces neither way. `hint`: a face near p, or -1; on return, a face near p to
  /// start from next time (the nearest, where there was none). Where the faces around the hint all lie
  /// within a narrow cone of normals far enough out from p, the answer follows without a search (see
  /// the .cpp); without prepare_facing(), every call searches. `hint_certificate`: the hint's
  /// certificate, where the caller keeps a copy of it (certificate(hint)), saving the two lookups. Safe
  /// to call from several threads.
  struct Certificate;
  bool facing_against(const Eigen::Vector3d& p, const Eigen::Vector3d& normal, Index& hint,
                      const Certificate* hint_certificate = nullptr) const;

  /// Closest point to `p` on the faces that face the way of `normal` (positive dot with it); face -1
  /// where none does. Needs prepare_facing().
  Hit closest_facing(const Eigen::Vector3d& p, const Eigen::Vector3d& normal) const;
  /// Whether a face facing the way of `normal` lies within sqrt(squared_distance) of p, give or take
  /// the rounding of distances: with the nearest face's distance, whether a face as near faces p's way
  /// (two faces that coincide facing opposite ways, or meet at the edge nearest p, tie).
  bool faces_way_within(const Eigen::Vector3d& p, const Eigen::Vector3d& normal, double squared_distance) const;
  /// Whether `normal` faces against every face nearest p: facing_against(), and no face as near facing
  /// its way (faces_way_within()). count_flipped_faces()'s rule; `hint` as for facing_against().
  bool facing_against_all_nearest(const Eigen::Vector3d& p, const Eigen::Vector3d& normal, Index& hint) const;

  /// What facing_against() may conclude without a search, for the faces of one leaf: a normal n with
  /// axis . n > min_dot |n|, asked about at a point p with 2 |p - anchor| < clearance, faces the same
  /// way as the face nearest p. 32 bytes: a caller that asks about the same place again and again may
  /// keep a copy beside its own data instead of looking it up each time.
  struct Certificate {
    Eigen::Vector3f axis = Eigen::Vector3f::Zero();
    float min_dot = 2;  // never
    Eigen::Vector3f anchor = Eigen::Vector3f::Zero();
    float clearance = 0;  // from the anchor, less its distance off the surface; 0: never

    /// Whether `normal` (not zero) at p surely faces the same way as the face nearest p.
    bool settles(const Eigen::Vector3d& p, const Eigen::Vector3d& normal) const {
      return turns_little(normal) && 2 * (p - anchor.cast<double>()).norm() < clearance * (1 - 1e-9);
    }
    /// The same, knowing that some input face lies within `distance` of p: the nearest one then lies
    /// within |p - anchor| + distance of the anchor (the bound settles() uses is 2 |p - anchor|).
    bool settles_within(const Eigen::Vector3d& p, const Eigen::Vector3d& normal, double distance) const {
      return turns_little(normal) && (p - anchor.cast<double>()).norm() + distance < clearance * (1 - 1e-9);
    }
    bool turns_little(const Eigen::Vector3d& normal) const {
      return axis.cast<double>().dot(normal) > min_dot * normal.norm();
    }
  };
  /// The certificate of the leaf that holds `face` (one that never settles before prepare_facing()).
  const Certificate& certificate(Index face) const {
    static const Certificate never;
    return leaf_of_.empty() ? never : certificates_[leaf_of_[face]];
  }

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
  // A face while the tree is built, in floats (they only decide the tree's shape, never an answer): its
  // centroid, and for surface-area splits its box.
  struct Centred {
    Eigen::Vector3f centre;
    Index face;
  };
  struct Boxed : Centred {
    Eigen::Vector3f lo, hi;
  };
  /// The tree over `entries` (Centred or Boxed), which it frees when done.
  template <typename Entry>
  void build_tree(std::vector<Entry>& entries);
  // The searches' layout: the tree with every other level left out. An inner node's quad holds the
  // nodes two levels below it (lanes 0-1 under its first child, 2-3 under its second; a child that is
  // a leaf takes its first lane itself), with their boxes side by side in floats rounded outwards:
  // one pop tests four boxes from two cache lines, where the binary tree took two pops and four
  // scattered boxes. Half the pops, and the same answers: the distances to the float boxes are lower
  // bounds of those to the exact boxes (see QuadDistances), so they rule out no face the exact ones
  // would keep.
  struct alignas(64) Quad {
    float lo[3][4], hi[3][4];  // per axis, per lane; an empty lane lies at infinity (node -1)
    std::int32_t node[4];      // per lane: its node in nodes_, or -1
    std::int32_t next[4];      // per lane: its own quad, or for a leaf -1 - (first slot * 4 + count - 1)
  };
  /// The tree over slots [begin, end) of `entries` (order_ to be): the top's splits side by side, down
  /// to parts of at most kParallelFaces faces (see the .cpp).
  struct Part;
  template <typename Entry>
  std::unique_ptr<Part> split_top(int begin, int end, int depth, std::vector<Entry>& entries) const;
  /// Fills in node `at` (at level `depth`) of `nodes` over those slots, its descendants from `next` on
  /// (advanced past them).
  template <typename Entry>
  void build(std::vector<Node>& nodes, int at, int& next, int begin, int end, int depth, std::vector<Entry>& entries) const;
  /// A leaf as Quad::next (and the search's stack) holds it: its first slot and face count, below 0.
  static int leaf_code(const Node& leaf) { return -1 - (leaf.first * 4 + leaf.count - 1); }
  /// The closest point to p on face f.
  Eigen::Vector3d closest_on_face(const Eigen::Vector3d& p, Index f) const;
  /// Appends the quad of inner node `node`, and those below it; returns its index.
  int build_quad(int node);
  /// Lane `lane` of `quad` as node `node`'s box, in floats rounded outwards.
  void set_lane_box(Quad& quad, int lane, int node) const;
  /// refit()'s boxes of node `node` and those below it.
  void refit_node(int node);
  /// What follows the positions once the boxes are known: extent_, and the copied corners (if kept).
  void read_positions();
  /// `box` extended by face f's corners.
  void extend_by_face(Eigen::AlignedBox3d& box, Index f) const;
  /// The depth-first search of the closest-point queries: visits the leaves nearer p than `bound` (which
  /// visit may lower as it goes), nearer first. enter(node, flag) passes over a node or gives the flag
  /// its subtree carries (see the .cpp); visit(slot, flag), slot a place in order_, returns true to stop.
  template <typename Enter, typename Visit>
  void descend(const Eigen::Vector3d& p, const double& bound, Enter enter, Visit visit) const;
  /// Distance from p to the nearest face whose normal is more than `angle` from unit `axis`, or
  /// `limit` if there is none nearer.
  double distance_to_turned(const Eigen::Vector3d& p, const Eigen::Vector3d& axis, double angle, double limit) const;
  /// The certificate of leaf node `leaf`.
  Certificate leaf_certificate(int leaf) const;
  /// facing_against()'s search: whether the face closest(p) finds faces against `normal`, without
  /// finding that face where its side is all that matters (see the .cpp). `unit`: normal / |normal|.
  bool nearest_faces_against(const Eigen::Vector3d& p, const Eigen::Vector3d& normal, const Eigen::Vector3d& unit,
                             Index& hint) const;
  const Mesh& mesh_;
  std::vector<Node> nodes_;
  std::vector<Quad> quads_;  // quads_[0]: the root's (none when the root is a leaf)
  double extent_ = 0;        // the largest coordinate's magnitude
  std::vector<Index> order_;
  std::vector<std::array<Eigen::Vector3d, 3>> corners_;  // per slot of order_ (or none): its face's corners
  // prepare_facing():
  std::vector<Eigen::Vector3d> normals_;  // per face, unit (zero: no area)
  std::vector<Cone> cones_;              // per node, while the certificates are found
  // Per node, for nearest_faces_against(): its cone in floats, as the sine of its half angle that a
  // unit normal n must clear for every face in it to face the same way as n (axis . n > sine; 2: never,
  // -2: always, where no face has area). 16 bytes.
  struct SideTest {
    Eigen::Vector3f axis = Eigen::Vector3f::Zero();
    float sine = 2;
    bool all_same(const Eigen::Vector3d& unit) const { return axis.cast<double>().dot(unit) > sine; }
  };
  std::vector<SideTest> sides_;
  // One per leaf, not per face (a 32 MB table on 1M faces).
  std::vector<Certificate> certificates_;  // per leaf, in node order
  std::vector<std::int32_t> leaf_of_;      // per face: its leaf's index in certificates_
};

}  // namespace lodkit::detail
