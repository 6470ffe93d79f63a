#pragma once
// Hoppe's energy (Progressive meshes, SIGGRAPH 1996, section 4): E = E_dist + E_spring, where E_dist
// is the sum of squared distances from points sampled on the original surface to the current mesh
// and E_spring = kappa * sum of squared edge lengths. Every point belongs to the face it projects to.
// A collapse u -> v is scored by Delta E: the points of the faces around u and v are re-projected onto
// the faces around the merged vertex, whose position is optimised by alternating (a) projection of
// each point onto its nearest face and (b) the linear least-squares solve for the position given
// those projections, starting from the quadric-optimal position.
//
// With attribute weights, E_scalar joins them (the paper's section 4.2): each point also carries the
// input's attribute values there (normals, UVs, colours, scaled as the engine's wedges are: weight x the
// bounding-box diagonal, so that they count as distances), and E_scalar sums their squared differences
// from the current mesh's values interpolated at the point's projection. A collapse is scored with the
// merged wedges at their best values given the projections (one small least-squares solve per wedge).
// Values compare within a chart only (faces joined where no attribute seam parts them): across a UV seam
// the mesh interpolates another chart's values, so a point whose nearest face lies there counts none.
//
// Open boundaries are discontinuity curves in the paper's sense (its E_disc term): points sampled on
// the input's boundary edges belong to the nearest boundary edge of the current mesh, and a collapse
// along the boundary adds their squared distances to the edges around the merged vertex. Without that
// term nothing holds a boundary vertex to the boundary: E_dist only pulls the mesh towards the input
// points, so a boundary may drift over a hole (the bunny's base at 1 %: Hausdorff 2.8 %).
//
// This file scores one candidate collapse by that energy; hoppe_cost.cpp keeps the points on their faces
// as the collapses go (not public API).
#include <algorithm>
#include <array>
#include <utility>
#include <vector>

#include "core/bound_rows.h"
#include "core/geometry.h"
#include "simplify/hoppe_points.h"

namespace lodkit::detail {

/// The neighbours x of p with (p, x) a boundary edge: exactly one of p's faces has both.
void boundary_neighbours(const EngineState& s, Index p, std::vector<Index>& out);

/// Where x meets segment p w: the squared distance and the weight 1 - t of p in the nearest point.
inline std::pair<double, double> on_segment(const Eigen::Vector3d& x, const Eigen::Vector3d& p, const Eigen::Vector3d& w) {
  const double t = segment_parameter(x, p, w);
  return {(p + t * (w - p) - x).squaredNorm(), 1.0 - t};
}

/// Scores candidates against the shared sample points. Each thread that scores has its own scorer:
/// the scratch below is per candidate, the points are only read.
class HoppeScorer {
 public:
  HoppeScorer(const FaceSamples& face_samples, const BoundaryCurves& curves, const FaceValues& face_values,
              const std::vector<Index>& face_chart)
      : face_samples_(face_samples), curves_(curves), face_values_(face_values), face_chart_(face_chart) {}

  void set_attribute_dims(int k) { attribute_dims_ = k; }

  /// Scores the collapse u -> v into `out`: the merged vertex's position, Delta E as the cost and the
  /// farthest point's distance from the merged neighbourhood as the error. False where E is undefined
  /// (no face would be left around the merged vertex). `border_edge`: u v is a boundary edge.
  bool score(const EngineState& s, const Probe& probe, Index u, Index v, Freedom freedom, bool border_edge, Candidate& out);

 private:
  // A triangle of the new star, with its planes.
  struct Tri : TrianglePlanes {
    Eigen::Vector3d c[3];
    int moving;
    int side;  ///< the side opposite the moving corner, from corner moving + 1 to moving + 2
    // Per point, the moving corner's weight is a distance times one of these: set once per triangle,
    // not divided out at every point.
    double per_distance;  ///< that side's length over twice the area: weight per unit from the side
    double per_area;      ///< 1 / twice the area (0 for a degenerate triangle)
  };
  struct Nearest {
    double d2, b;           ///< squared distance; barycentric weight of the moving corner
    Eigen::Vector3d fixed;  ///< the projection minus b times the moving corner
  };
  // With E_scalar, per point beside its Nearest (not in it: the plain energy's loop stays as lean): the
  // star triangle it lies on and the weight there of the corner after the moving one.
  struct OnTriangle {
    int tri;
    double b_next;
  };

  // The nearest point to x on the new star (merged vertex at p), into nearest_ for every point. The
  // triangle a point's face becomes (its `home`) is nearly always the nearest, so it goes first and its
  // distance rules out nearly every other one through a cheap lower bound, computed for all triangles
  // at once. A point of a vanishing face has no home: the triangle with the lowest bound goes first.
  // The others left follow in index order, triangle 0 taking the first's place.
  // With kOnTriangle (E_scalar), also each point's triangle and second weight, into on_triangle_.
  template <bool kOnTriangle>
  void project_all(const Eigen::Vector3d& p, bool solve);

  // The weight at x's projection (`n`, on star triangle k) of the corner after the moving one, x being
  // the point of the last rows_.lower_bounds2().
  double weight_after_moving(std::size_t k, const Eigen::Vector3d& x, const Nearest& n) const;

  // The nearest point to x on star triangle k, x being the point of the last rows_.lower_bounds2().
  Nearest nearest_on(std::size_t k, const Eigen::Vector3d& x, const Eigen::Vector3d& p, bool solve) const;

  // The same for x inside t's prism, at signed distance `plane` from its plane: the nearest point is
  // x's foot on the plane, and the moving corner's weight is the foot's distance from the opposite
  // side over the corner's. (Most points are inside their face's prism: this skips the region walk.)
  static Nearest in_prism(const Eigen::Vector3d& x, const Tri& t, double plane, const Eigen::Vector3d& p, bool solve);

  // The nearest point to x on triangle t; with `solve`, also the barycentric weight of the moving
  // corner and the fixed remainder of the point.
  static Nearest on_triangle(const Eigen::Vector3d& x, const Tri& t, const Eigen::Vector3d& p, bool solve);

  // E_scalar after the collapse, each merged wedge at its best value given the points' projections
  // (nearest_): over the points on triangles whose moving corner is wedge w, the value a minimising
  // sum weight |y - b a|^2, y being the point's values less the fixed corners' share.
  double scalar_energy(const EngineState& s);

  // Collects the neighbourhood of u -> v: its points, the new star (corner -1 = the merged vertex),
  // and the rings of u, v and the merged vertex.
  void gather(const EngineState& s, const Probe& probe, Index u, Index v);

  // The wedges at the corners of star triangle f, the moving corner's being the one it merges into
  // (u's wedges through the probe's map), and that wedge's place in merged_.
  void add_star_wedges(const EngineState& s, const Probe& probe, Index f, Index u);

  // Adds q to the ascending list r unless it is there (rings hold a dozen points: cheaper than sorting).
  static void insert_sorted(std::vector<Index>& r, Index q);

  // The boundary points a collapse along the boundary moves (those of the boundary edges at u and v), and
  // the far ends of the boundary edges at the merged vertex. Nothing for any other collapse: a boundary
  // point only ever leaves the boundary along its own boundary (see Engine::structure).
  void gather_curves(const EngineState& s, Index u, Index v, bool border_edge);

  // The paper's schedule, from this neighbourhood's points per face.
  double spring_constant() const { return detail::spring_constant(faces_ > 0 ? double(point_count_) / faces_ : 0.0); }

  const FaceSamples& face_samples_;
  const BoundaryCurves& curves_;
  const FaceValues& face_values_;
  const std::vector<Index>& face_chart_;
  int attribute_dims_ = 0;  ///< E_scalar's values per point (0: no E_scalar)
  // Scratch for one candidate.
  std::vector<Index> curve_points_, curve_ends_, scratch_;
  static constexpr std::size_t kPointsPerFace = 16;
  /// Of a face's n points, every stride-th takes part in a score (at most kPointsPerFace), each standing
  /// for `stride` points.
  static std::size_t stride_of(std::size_t n) { return std::max<std::size_t>((n + kPointsPerFace - 1) / kPointsPerFace, 1); }
  std::vector<Eigen::Vector3d> points_;  ///< the points of the neighbourhood, side by side
  std::vector<double> dist2_;            ///< per point of points_: its squared distance before
  std::vector<Index> ring_u_, ring_v_, ring_;
  std::vector<double> weight_;
  std::vector<int> home_;  ///< per point of points_: the star triangle its face becomes, or -1
  std::size_t point_count_ = 0;
  std::vector<std::array<Index, 3>> star_;
  std::vector<Tri> tri_;
  std::vector<Nearest> nearest_;  ///< per point of points_: its projection onto the new star
  BoundRows rows_;  ///< the star's planes
  // A boundary point's projection (the surface points' are read from nearest_); each weighs 1.
  struct Projection {
    Eigen::Vector3d x;  // the sample point
    double b;
    Eigen::Vector3d fixed;
  };
  std::vector<Projection> curve_projections_;
  Index faces_ = 0;
  // E_scalar's scratch: the points' values (k per point of points_) and charts, per star triangle its
  // wedges, which merged wedge its moving corner is and its chart, and per merged wedge the sums of its solve.
  std::vector<double> values_;
  std::vector<Index> point_chart_;
  std::vector<OnTriangle> on_triangle_;  ///< per point of points_
  struct StarAttributes {
    std::array<Index, 3> wedges;  ///< the moving corner's: the wedge it merges into
    int slot;                     ///< that wedge's place in merged_
    Index chart;
  };
  std::vector<StarAttributes> star_attributes_;  ///< per triangle of star_
  struct Merged {
    Index wedge;
    double sum_b2, sum_y2;
    std::array<double, kMostAttributeDims> sum_by;
  };
  std::vector<Merged> merged_;
  double scalar_before_ = 0;

};

}  // namespace lodkit::detail
