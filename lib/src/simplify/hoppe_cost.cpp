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
#include <algorithm>
#include <array>
#include <bit>
#include <iterator>
#include <random>
#include <tbb/enumerable_thread_specific.h>

#include "core/bound_rows.h"
#include "core/geometry.h"
#include "core/union_find.h"
#include "core/uv_charts.h"
#include "simplify/hoppe_points.h"

namespace lodkit::detail {
namespace {

/// The neighbours x of p with (p, x) a boundary edge: exactly one of p's faces has both.
void boundary_neighbours(const EngineState& s, Index p, std::vector<Index>& out) {
  s.ring(p, out, true);
  std::size_t n = 0;
  for (std::size_t i = 0; i < out.size();) {
    std::size_t j = i;
    while (j < out.size() && out[j] == out[i]) ++j;
    if (j - i == 1) out[n++] = out[i];
    i = j;
  }
  out.resize(n);
}

/// Where x meets segment p w: the squared distance and the weight 1 - t of p in the nearest point.
inline std::pair<double, double> on_segment(const Eigen::Vector3d& x, const Eigen::Vector3d& p, const Eigen::Vector3d& w) {
  const double t = segment_parameter(x, p, w);
  return {(p + t * (w - p) - x).squaredNorm(), 1.0 - t};
}

// Scores candidates against the shared sample points. Each thread that scores has its own scorer:
// the scratch below is per candidate, the points are only read.
class HoppeScorer {
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

 public:
  HoppeScorer(const FaceSamples& face_samples, const BoundaryCurves& curves, const FaceValues& face_values,
              const std::vector<Index>& face_chart)
      : face_samples_(face_samples), curves_(curves), face_values_(face_values), face_chart_(face_chart) {}

  bool score(const EngineState& s, const Probe& probe, Index u, Index v, Freedom freedom, bool border_edge, Candidate& out) {
    gather(s, probe, u, v);
    // A collapse that removes every face around u and v (an isolated triangle) leaves the points no
    // surface to belong to: E is undefined there, so it is no candidate (the link condition refuses it
    // too, but only when it reaches the top of the queue).
    if (star_.empty()) return false;
    gather_curves(s, u, v, border_edge);
    // Spring energy before: the edges at u and at v (the rest of the neighbourhood does not change).
    const double kappa = spring_constant();
    double before = 0;
    for (std::size_t j = 0; j < points_.size(); ++j) before += weight_[j] * dist2_[j];
    for (Index c : curve_points_) before += curves_.dist2[c];
    for (Index w : ring_u_) before += kappa * (s.position[u] - s.position[w]).squaredNorm();
    for (Index w : ring_v_) before += kappa * (s.position[v] - s.position[w]).squaredNorm();  // (u is not in it)

    double worst = 0;  // largest squared point distance at the last evaluated position
    // With the projections held fixed, E at another position q is sum w |x - b q - f|^2 + springs: an
    // upper bound of the true E(q), since re-projecting can only bring points closer. So one projection
    // pass gives both the solve and a safe energy for the solved position.
    double solved_energy = 0, solved_worst = 0;
    Eigen::Vector3d solved;
    auto energy = [&](const Eigen::Vector3d& p, bool solve) {
      // Project every point onto the new star; optionally solve for the position given the projections.
      // (Sums in locals: the captured ones were stored back to memory at every point.)
      double e = 0, sum_b2 = 0, max_d2 = 0;
      curve_projections_.clear();
      Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
      // The star's triangles, with the planes that bound the distance to each from below.
      tri_.clear();
      for (const auto& t : star_) {
        Tri tri;
        for (int k = 0; k < 3; ++k) tri.c[k] = t[k] < 0 ? p : s.position[t[k]];
        tri.moving = t[0] < 0 ? 0 : t[1] < 0 ? 1 : 2;
        tri.side = (tri.moving + 1) % 3;
        tri.set(tri.c);
        tri.per_area = tri.twice_area > 0 ? 1.0 / tri.twice_area : 0.0;
        tri.per_distance = (tri.c[(tri.moving + 2) % 3] - tri.c[tri.side]).norm() * tri.per_area;
        tri_.push_back(tri);
      }
      // (Projecting in parallel did not pay: a neighbourhood holds 50-300 points, a few microseconds.)
      if (attribute_dims_ > 0) project_all<true>(p, true);
      else project_all<false>(p, solve);
      for (std::size_t j = 0; j < points_.size(); ++j) {
        const Nearest& n = nearest_[j];
        const double weight = weight_[j];
        e += weight * n.d2;
        max_d2 = std::max(max_d2, n.d2);
        if (solve) {
          sum_b2 += weight * n.b * n.b;
          rhs += weight * n.b * (points_[j] - n.fixed);
        }
      }
      for (Index c : curve_points_) {
        // The nearest of the boundary edges at the merged vertex.
        const Eigen::Vector3d& x = curves_.point[c];
        double d2 = INFINITY, b = 0;
        Index end = -1;
        for (Index w : curve_ends_)
          if (const auto [dw, bw] = on_segment(x, p, s.position[w]); dw < d2) d2 = dw, b = bw, end = w;
        e += d2;
        max_d2 = std::max(max_d2, d2);
        if (solve) {
          const Eigen::Vector3d fixed = (1 - b) * s.position[end];
          sum_b2 += b * b;
          rhs += b * (x - fixed);
          curve_projections_.push_back({x, b, fixed});
        }
      }
      for (Index w : ring_) {
        e += kappa * (p - s.position[w]).squaredNorm();
        if (solve) rhs += kappa * s.position[w], sum_b2 += kappa;
      }
      worst = max_d2;
      if (solve) {
        solved = sum_b2 > 0 ? Eigen::Vector3d(rhs / sum_b2) : p;
        double energy_there = 0, worst_there = 0;
        // The surface points' projections are read where they are (nearest_), then the boundary's.
        for (std::size_t j = 0; j < points_.size(); ++j) {
          const Nearest& n = nearest_[j];
          const double d = (points_[j] - n.b * solved - n.fixed).squaredNorm();
          energy_there += weight_[j] * d;
          worst_there = std::max(worst_there, d);
        }
        for (const Projection& pr : curve_projections_) {
          const double d = (pr.x - pr.b * solved - pr.fixed).squaredNorm();
          energy_there += d;
          worst_there = std::max(worst_there, d);
        }
        for (Index w : ring_) energy_there += kappa * (solved - s.position[w]).squaredNorm();
        solved_energy = energy_there, solved_worst = worst_there;
      }
      return e;
    };

    // Start where the quadric puts the vertex (cheap, and close to the energy's optimum), project the
    // points once while setting up the least-squares solve, then evaluate the solved position.
    Eigen::Vector3d p = s.position[v];
    double e = 0, e_worst = 0;
    {
      if (freedom == Freedom::Free) {
        const Quadric q = s.quadric[u] + s.quadric[v];
        const Eigen::Vector3d mid = 0.5 * (s.position[u] + s.position[v]);
        Eigen::Vector3d best;
        p = q.truncated_minimiser_near(mid, best) && (best - mid).norm() <= 2.0 * (s.position[u] - s.position[v]).norm() &&
                    s.representable(best)
                ? best
                : mid;
      }
      e = energy(p, freedom == Freedom::Free), e_worst = worst;
      if (freedom == Freedom::Free && solved_energy < e && s.representable(solved))
        e = solved_energy, p = solved, e_worst = solved_worst;
    }
    out.position = p;
    out.cost = e - before + (attribute_dims_ > 0 ? scalar_energy(s) - scalar_before_ : 0.0);
    out.error = std::sqrt(e_worst);  // the farthest sample point from the merged neighbourhood
    return true;
  }

  // The nearest point to x on the new star (merged vertex at p), into nearest_ for every point. The
  // triangle a point's face becomes (its `home`) is nearly always the nearest, so it goes first and its
  // distance rules out nearly every other one through a cheap lower bound, computed for all triangles
  // at once. A point of a vanishing face has no home: the triangle with the lowest bound goes first.
  // The others left follow in index order, triangle 0 taking the first's place.
  // With kOnTriangle (E_scalar), also each point's triangle and second weight, into on_triangle_.
  template <bool kOnTriangle>
  void project_all(const Eigen::Vector3d& p, bool solve) {
    const std::size_t m = tri_.size();
    rows_.resize(m);
    for (std::size_t i = 0; i < m; ++i) rows_.set(i, tri_[i]);
    nearest_.resize(points_.size());
    if constexpr (kOnTriangle) on_triangle_.resize(points_.size());
    for (std::size_t j = 0; j < points_.size(); ++j) {
      const Eigen::Vector3d& x = points_[j];
      const double* bounds = rows_.lower_bounds2(x);
      const std::size_t first = home_[j] >= 0 ? std::size_t(home_[j]) : rows_.lowest();
      Nearest& out = nearest_[j];
      out = nearest_on(first, x, p, solve);
      [[maybe_unused]] std::size_t on = first;
      auto try_triangle = [&](std::size_t k) {
        if (bounds[k] >= out.d2) return;
        const Nearest c = nearest_on(k, x, p, solve);
        if (c.d2 < out.d2) {
          out = c;
          if constexpr (kOnTriangle) on = k;
        }
      };
      if (m <= 64) {
        // The bounds below the first's distance as bits (usually none), bit n for the n-th tried.
        std::uint64_t near = rows_.below(out.d2) & ~(std::uint64_t(1) << first);
        for (near = (near & ~std::uint64_t(1)) | ((near & 1) << first); near; near &= near - 1) {
          const std::size_t n = std::size_t(std::countr_zero(near));
          try_triangle(n == first ? 0 : n);
        }
      } else {
        for (std::size_t n = 1; n < m; ++n) try_triangle(n == first ? 0 : n);
      }
      if constexpr (kOnTriangle) on_triangle_[j] = {static_cast<int>(on), weight_after_moving(on, x, out)};
    }
  }

  // The weight at x's projection (`n`, on star triangle k) of the corner after the moving one, x being
  // the point of the last rows_.lower_bounds2().
  double weight_after_moving(std::size_t k, const Eigen::Vector3d& x, const Nearest& n) const {
    const Tri& t = tri_[k];
    const int m = t.moving;
    if (rows_.inside_prism(k)) {
      // That corner faces the side from the corner after it to the moving one.
      const int side = (m + 2) % 3;
      const double per_distance = (t.c[m] - t.c[side]).norm() * t.per_area;
      return std::clamp((t.edge_offset[side] - t.edge_normal[side].dot(x)) * per_distance, 0.0, 1.0 - n.b);
    }
    const Eigen::Vector3d q = closest_point_on_triangle(x, t.c[0], t.c[1], t.c[2]);
    return std::clamp((t.c[(m + 2) % 3] - q).cross(t.c[m] - q).dot(t.normal) * t.per_area, 0.0, 1.0 - n.b);
  }

  // The nearest point to x on star triangle k, x being the point of the last rows_.lower_bounds2().
  Nearest nearest_on(std::size_t k, const Eigen::Vector3d& x, const Eigen::Vector3d& p, bool solve) const {
    return rows_.inside_prism(k) ? in_prism(x, tri_[k], rows_.plane_distances()[k], p, solve) : on_triangle(x, tri_[k], p, solve);
  }

  // The same for x inside t's prism, at signed distance `plane` from its plane: the nearest point is
  // x's foot on the plane, and the moving corner's weight is the foot's distance from the opposite
  // side over the corner's. (Most points are inside their face's prism: this skips the region walk.)
  static Nearest in_prism(const Eigen::Vector3d& x, const Tri& t, double plane, const Eigen::Vector3d& p, bool solve) {
    Nearest out{plane * plane, 0.0, Eigen::Vector3d::Zero()};
    if (solve) {
      const Eigen::Vector3d q = x - plane * t.normal;
      const double inside = t.edge_offset[t.side] - t.edge_normal[t.side].dot(x);
      out.b = std::clamp(inside * t.per_distance, 0.0, 1.0);
      out.fixed = q - out.b * p;
    }
    return out;
  }

  // The nearest point to x on triangle t; with `solve`, also the barycentric weight of the moving
  // corner and the fixed remainder of the point.
  static Nearest on_triangle(const Eigen::Vector3d& x, const Tri& t, const Eigen::Vector3d& p, bool solve) {
    const Eigen::Vector3d q = closest_point_on_triangle(x, t.c[0], t.c[1], t.c[2]);
    Nearest out{(q - x).squaredNorm(), 0.0, Eigen::Vector3d::Zero()};
    if (solve) {
      const int m = t.moving;
      const Eigen::Vector3d e1 = t.c[(m + 1) % 3] - q, e2 = t.c[(m + 2) % 3] - q;
      out.b = std::clamp(e1.cross(e2).dot(t.normal) * t.per_area, 0.0, 1.0);
      out.fixed = q - out.b * p;
    }
    return out;
  }

  // E_scalar after the collapse, each merged wedge at its best value given the points' projections
  // (nearest_): over the points on triangles whose moving corner is wedge w, the value a minimising
  // sum weight |y - b a|^2, y being the point's values less the fixed corners' share.
  double scalar_energy(const EngineState& s) {
    const std::size_t k = static_cast<std::size_t>(attribute_dims_);
    for (auto& m : merged_) m.sum_b2 = 0, m.sum_y2 = 0, m.sum_by.fill(0.0);
    for (std::size_t j = 0; j < points_.size(); ++j) {
      const Nearest& n = nearest_[j];
      const auto [tri, b_next] = on_triangle_[j];
      const StarAttributes& star = star_attributes_[std::size_t(tri)];
      if (star.chart != point_chart_[j]) continue;  // across a seam: not comparable
      const Tri& t = tri_[std::size_t(tri)];
      const auto& w = star.wedges;
      const double* next = &s.wedge_value[k * std::size_t(w[(t.moving + 1) % 3])];
      const double* last = &s.wedge_value[k * std::size_t(w[(t.moving + 2) % 3])];
      const double b_last = std::max(0.0, 1.0 - n.b - b_next), weight = weight_[j];
      Merged& m = merged_[std::size_t(star.slot)];
      const double* x = &values_[k * j];
      m.sum_b2 += weight * n.b * n.b;
      for (std::size_t d = 0; d < k; ++d) {
        const double y = x[d] - b_next * next[d] - b_last * last[d];
        m.sum_by[d] += weight * n.b * y;
        m.sum_y2 += weight * y * y;
      }
    }
    double e = 0;
    for (const Merged& m : merged_) {
      double explained = 0;
      if (m.sum_b2 > 0)
        for (std::size_t d = 0; d < k; ++d) explained += m.sum_by[d] * m.sum_by[d] / m.sum_b2;
      e += std::max(0.0, m.sum_y2 - explained);
    }
    return e;
  }

 private:
  // Collects the neighbourhood of u -> v: its points, the new star (corner -1 = the merged vertex),
  // and the rings of u, v and the merged vertex.
  void gather(const EngineState& s, const Probe& probe, Index u, Index v) {
    points_.clear();
    values_.clear();
    point_chart_.clear();
    star_attributes_.clear();
    merged_.clear();
    scalar_before_ = 0;
    const std::size_t dims = static_cast<std::size_t>(attribute_dims_);
    dist2_.clear();
    weight_.clear();
    home_.clear();
    point_count_ = 0;
    star_.clear();
    ring_u_.clear(), ring_v_.clear(), ring_.clear();
    faces_ = 0;
    // Each face's points are an array of their own: ask for every header, then every array, rather
    // than wait on one cache miss after another.
    for (Index p : {u, v})
      for (Index f : s.faces_of(p)) __builtin_prefetch(&face_samples_[f]), __builtin_prefetch(&s.face_point[f]);
    for (Index p : {u, v})
      for (Index f : s.faces_of(p)) __builtin_prefetch(face_samples_[f].data());
    for (Index p : {u, v})
      for (Index f : s.faces_of(p)) {
        bool has_u = false, has_v = false;
        for (int k = 0; k < 3; ++k) has_u |= s.corner_point(f, k) == u, has_v |= s.corner_point(f, k) == v;
        if (p == v && has_u) continue;  // counted from u's side already
        ++faces_;
        // At most kPointsPerFace points of each face take part, each standing for its share: the
        // estimate of Delta E stays unbiased while coarse levels (100+ points per face) stay cheap.
        const auto& fp = face_samples_[f];
        point_count_ += fp.size();
        const std::size_t stride = (fp.size() + kPointsPerFace - 1) / kPointsPerFace;
        const int home = has_u && has_v ? -1 : static_cast<int>(star_.size());  // its triangle in the new star
        for (std::size_t i = 0; i < fp.size(); i += std::max<std::size_t>(stride, 1)) {
          points_.push_back(fp[i].x);
          dist2_.push_back(fp[i].dist2);
          weight_.push_back(double(stride ? stride : 1));
          home_.push_back(home);
          if (dims > 0) {
            const double* x = &face_values_[f][(dims + 2) * i];
            values_.insert(values_.end(), x, x + dims);
            point_chart_.push_back(static_cast<Index>(x[dims + 1]));
            scalar_before_ += weight_.back() * x[dims];
          }
        }
        for (int k = 0; k < 3; ++k)
          if (const Index q = s.corner_point(f, k); q != p) insert_sorted(p == u ? ring_u_ : ring_v_, q);
        if (has_u && has_v) continue;  // vanishes
        std::array<Index, 3> t;
        for (int c = 0; c < 3; ++c) {
          const Index q = s.corner_point(f, c);
          t[c] = q == u || q == v ? -1 : q;
        }
        star_.push_back(t);
        if (dims > 0) add_star_wedges(s, probe, f, u);
      }
    // The merged vertex's ring: both rings but u and v (u is in neither: faces at v that have u
    // were taken from u's side).
    std::set_union(ring_u_.begin(), ring_u_.end(), ring_v_.begin(), ring_v_.end(), std::back_inserter(ring_));
    ring_.erase(std::remove(ring_.begin(), ring_.end(), v), ring_.end());
  }

  // The wedges at the corners of star triangle f, the moving corner's being the one it merges into
  // (u's wedges through the probe's map), and that wedge's place in merged_.
  void add_star_wedges(const EngineState& s, const Probe& probe, Index f, Index u) {
    std::array<Index, 3> w;
    int moving = 0;
    for (int c = 0; c < 3; ++c) {
      w[c] = s.face[f][c];
      const Index q = s.corner_point(f, c);
      if (star_.back()[c] >= 0) continue;
      moving = c;
      if (q == u)
        for (int i = 0; i < probe.wedge_map_size; ++i)
          if (probe.wedge_map[i].first == w[c]) w[c] = probe.wedge_map[i].second;
    }
    std::size_t slot = 0;
    while (slot < merged_.size() && merged_[slot].wedge != w[moving]) ++slot;
    if (slot == merged_.size()) merged_.push_back({w[moving], 0, 0, {}});
    star_attributes_.push_back({w, static_cast<int>(slot), face_chart_[f]});
  }

  // Adds q to the ascending list r unless it is there (rings hold a dozen points: cheaper than sorting).
  static void insert_sorted(std::vector<Index>& r, Index q) {
    auto at = r.end();
    while (at != r.begin() && *(at - 1) > q) --at;
    if (at == r.begin() || *(at - 1) != q) r.insert(at, q);
  }

  // The boundary points a collapse along the boundary moves (those of the boundary edges at u and v), and
  // the far ends of the boundary edges at the merged vertex. Nothing for any other collapse: a boundary
  // point only ever leaves the boundary along its own boundary (see Engine::structure).
  void gather_curves(const EngineState& s, Index u, Index v, bool border_edge) {
    curve_points_.clear();
    curve_ends_.clear();
    if (!border_edge || curves_.point.empty() || !s.has(u, kBorder) || !s.has(v, kBorder)) return;
    for (Index p : {u, v}) {
      boundary_neighbours(s, p, scratch_);
      for (Index x : scratch_) {
        if (x == u || x == v) {
          if (p == u)
            if (const auto* pts = curves_.points_of(u, v)) curve_points_.insert(curve_points_.end(), pts->begin(), pts->end());
          continue;
        }
        curve_ends_.push_back(x);
        if (const auto* pts = curves_.points_of(p, x)) curve_points_.insert(curve_points_.end(), pts->begin(), pts->end());
      }
    }
    if (curve_ends_.empty()) curve_points_.clear();
  }

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

 public:
  void set_attribute_dims(int k) { attribute_dims_ = k; }
};

class HoppeCost final : public CostModel {
 public:
  HoppeCost(const SimplifyOptions& o, const EngineState& s) {
    // Points: every vertex position, plus random points on the faces (seeded): `points_per_face` on
    // average, or more where that falls short of `min_points` in all; `points_on_every_face` of them on
    // every face, the rest spread by area (SimplifyOptions::hoppe_points_on_every_face says why).
    const Mesh& m = *s.input;
    const double per_face = random_points_per_face(o, s);
    const double on_every_face = std::min(per_face, o.hoppe_points_on_every_face);
    double area = 0;
    for (std::size_t f = 0; f < s.face.size(); ++f)
      if (!s.face_dead[f]) area += face_area(s, f);
    const double per_area = area > 0 ? (per_face - on_every_face) * double(s.alive_faces) / area : 0.0;
    for (const Eigen::Vector3d& p : s.position) margin_ = std::max(margin_, p.cwiseAbs().maxCoeff());
    margin_ *= 1e-9;
    std::mt19937_64 rng(o.seed);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    face_samples_.resize(s.face.size());
    dims_ = s.attribute_quadrics.dims();
    if (dims_ > 0) face_values_.resize(s.face.size()), find_charts(s);
    std::vector<char> placed(s.position.size(), 0);
    double carry = 0;
    for (std::size_t f = 0; f < s.face.size(); ++f) {
      if (s.face_dead[f]) continue;
      for (int k = 0; k < 3; ++k) {
        const Index p = s.corner_point(Index(f), k);
        if (!placed[p]) placed[p] = 1, add_point(s, s.position[p], Index(f), Eigen::Vector3d::Unit(k));
      }
      carry += per_area > 0 ? on_every_face + per_area * face_area(s, f) : per_face;
      for (; carry >= 1.0; carry -= 1.0) {
        double a = unit(rng), b = unit(rng);
        if (a + b > 1) a = 1 - a, b = 1 - b;
        const Eigen::Vector3d p0 = m.positions.row(s.face[f][0]).transpose() - s.origin,
                              p1 = m.positions.row(s.face[f][1]).transpose() - s.origin,
                              p2 = m.positions.row(s.face[f][2]).transpose() - s.origin;
        add_point(s, p0 + a * (p1 - p0) + b * (p2 - p0), Index(f), {1 - a - b, a, b});
      }
    }
    sample_boundary(s);
    sample_creases(s);
  }

  // Two points per boundary edge: where it starts (in its face's order, so each boundary vertex once)
  // and its midpoint.
  void sample_boundary(const EngineState& s) {
    for (const auto& [a, b] : s.input_boundary) {
      auto& list = curves_.edge_points[BoundaryCurves::edge_key(a, b)];
      for (const Eigen::Vector3d& x : {s.position[a], Eigen::Vector3d(0.5 * (s.position[a] + s.position[b]))}) {
        list.push_back(static_cast<Index>(curves_.point.size()));
        curves_.point.push_back(x);
        curves_.dist2.push_back(0.0);
      }
    }
  }

  // Points along the input's sharp edges (EngineState::sharp_edges), about one per average edge
  // length, each belonging to the edge's lower face. E_dist sees an edge only through the points near
  // it: with a few random points per long thin CAD triangle, a collapse that bevels a sharp edge moved
  // almost none of them and cost next to nothing.
  void sample_creases(const EngineState& s) {
    if (s.sharp_edges.empty()) return;
    double length = 0;
    std::size_t sides = 0;
    for (std::size_t f = 0; f < s.face.size(); ++f)
      if (!s.face_dead[f])
        for (int k = 0; k < 3; ++k, ++sides)
          length += (s.position[s.corner_point(Index(f), k)] - s.position[s.corner_point(Index(f), (k + 1) % 3)]).norm();
    const double spacing = length / double(sides);
    constexpr int kMostPerEdge = 32;
    for (const auto& [f, k] : s.sharp_edges) {
      const Eigen::Vector3d pa = s.position[s.corner_point(f, k)], pb = s.position[s.corner_point(f, (k + 1) % 3)];
      const int points = std::max(1, static_cast<int>(std::min((pb - pa).norm() / spacing, double(kMostPerEdge))));
      for (int i = 1; i <= points; ++i) {
        const double t = double(i) / (points + 1);
        Eigen::Vector3d weights = Eigen::Vector3d::Zero();
        weights[k] = 1 - t, weights[(k + 1) % 3] = t;
        add_point(s, pa + (pb - pa) * t, f, weights);
      }
    }
  }

  static double face_area(const EngineState& s, std::size_t f) {
    const Index i = static_cast<Index>(f);
    return triangle_area(s.position[s.corner_point(i, 0)], s.position[s.corner_point(i, 1)], s.position[s.corner_point(i, 2)]);
  }

  static double random_points_per_face(const SimplifyOptions& o, const EngineState& s) {
    std::size_t points = 0;
    for (std::size_t p = 0; p < s.position.size(); ++p) points += !s.point_faces[p].empty();
    const std::size_t faces = static_cast<std::size_t>(s.alive_faces);
    const std::size_t wanted = static_cast<std::size_t>(std::max<Index>(o.hoppe_min_points, 0));
    if (faces == 0 || points >= wanted) return o.hoppe_points_per_face;
    return std::max(o.hoppe_points_per_face, std::min(1000.0, double(wanted - points) / double(faces)));
  }

  bool wide_update() const override { return true; }
  bool costly() const override { return true; }

  bool score(const EngineState& s, const Probe& probe, Index u, Index v, Freedom freedom, Candidate& out) override {
    return scorers_.local().score(s, probe, u, v, freedom, probe.shared.size() == 1, out);
  }

  bool places_attributes() const override { return dims_ > 0; }

  void collapsed(EngineState& s, Index u, Index v, const Probe& probe) override {
    const std::vector<Index>& removed_faces = probe.shared;
    // Re-assign the points of the old neighbourhood to the faces now around v.
    // Each point with the index in `around` of the face it had (none for a vanished face's points).
    const std::vector<Index>& around = s.faces_of(v);
    const std::size_t none = around.size();
    // Named references rather than a structured binding: lambdas below use them, which clang
    // before 16 refuses for bindings.
    ReassignScratch& scratch = reassign_scratch_.local();
    auto& moving = scratch.moving;
    auto& values = scratch.values;
    auto& home_of = scratch.home_of;
    auto& rows = scratch.rows;
    auto& landed = scratch.landed;
    moving.clear(), values.clear(), home_of.clear(), landed.clear();
    auto take_values = [&](Index f) {  // with E_scalar, the values go along
      if (dims_ == 0) return;
      values.insert(values.end(), face_values_[f].begin(), face_values_[f].end());
      face_values_[f].clear();
    };
    for (Index f : removed_faces) {
      moving.insert(moving.end(), face_samples_[f].begin(), face_samples_[f].end());
      home_of.resize(moving.size(), none);
      std::vector<Sample>().swap(face_samples_[f]);  // gone for good: free it
      take_values(f);
      if (dims_ > 0) std::vector<double>().swap(face_values_[f]);
    }
    for (std::size_t i = 0; i < around.size(); ++i) {
      auto& list = face_samples_[around[i]];
      moving.insert(moving.end(), list.begin(), list.end());
      home_of.resize(moving.size(), i);
      list.clear();
      take_values(around[i]);
    }
    // Each point goes to its nearest face, the first in `around` on a tie (a vertex's point is on
    // every face at that vertex). The face it had, if any, is measured first; a face whose lower bound
    // exceeds that distance cannot be nearer (the margin covers the bounds' rounding), so only the few
    // others left are measured, in order.
    rows.resize(around.size());
    for (std::size_t i = 0; i < around.size(); ++i) {
      const Eigen::Vector3d c[3] = {s.position[s.corner_point(around[i], 0)], s.position[s.corner_point(around[i], 1)],
                                    s.position[s.corner_point(around[i], 2)]};
      TrianglePlanes planes;
      planes.set(c);
      rows.set(i, planes);
    }
    auto distance2 = [&](const Eigen::Vector3d& x, Index f) {
      const Eigen::Vector3d q = closest_point_on_triangle(x, s.position[s.corner_point(f, 0)], s.position[s.corner_point(f, 1)],
                                                          s.position[s.corner_point(f, 2)]);
      return (q - x).squaredNorm();
    };
    for (std::size_t j = 0; j < moving.size(); ++j) {
      Sample& sample = moving[j];
      const std::size_t home = home_of[j];
      const double* bounds = rows.lower_bounds2(sample.x);
      // Inside its face's prism (most points), the distance is the plane's: no region walk.
      double reach = INFINITY;
      if (home != none)
        reach = rows.inside_prism(home) ? bounds[home] : distance2(sample.x, around[home]);
      const double limit = std::isfinite(reach) ? (std::sqrt(reach) + margin_) * (std::sqrt(reach) + margin_) : INFINITY;
      double best = INFINITY;
      Index best_face = -1;
      for (std::size_t k = 0; k < around.size(); ++k) {
        if (k != home && bounds[k] > limit) continue;
        const double d = k == home ? reach : distance2(sample.x, around[k]);
        if (d < best) best = d, best_face = around[k];
      }
      sample.dist2 = best;
      face_samples_[best_face].push_back(sample);
      if (dims_ > 0) {
        const std::size_t k = static_cast<std::size_t>(dims_);
        const double* x = &values[(k + 2) * j];
        auto& list = face_values_[best_face];
        landed.push_back({best_face, list.size(), Eigen::Vector3d::Zero()});
        list.insert(list.end(), x, x + k + 2);  // its distance is set below, once the values are placed
      }
    }
    if (dims_ > 0) place_values(s, v, probe, moving, landed);
    if (removed_faces.size() == 1 && s.has(v, kBorder) && !curves_.point.empty()) reassign_boundary(s, u, v);
  }

  // After a collapse along the boundary: the points of the boundary edges u and v had go to the nearest
  // boundary edge at v.
  void reassign_boundary(const EngineState& s, Index u, Index v) {
    std::vector<Index> ends, moving;
    boundary_neighbours(s, v, ends);
    const std::lock_guard hold(curves_.lock);
    auto take = [&](Index a, Index b) {
      const auto it = curves_.edge_points.find(BoundaryCurves::edge_key(a, b));
      if (it == curves_.edge_points.end()) return;
      moving.insert(moving.end(), it->second.begin(), it->second.end());
      curves_.edge_points.erase(it);
    };
    take(u, v);
    for (Index x : ends) take(u, x), take(v, x);
    if (ends.empty()) return;  // (the engine never leaves a boundary vertex without boundary edges)
    for (Index i : moving) {
      double best = INFINITY;
      Index best_end = -1;
      for (Index x : ends)
        if (const double d = on_segment(curves_.point[i], s.position[v], s.position[x]).first; d < best) best = d, best_end = x;
      curves_.dist2[i] = best;
      curves_.edge_points[BoundaryCurves::edge_key(v, best_end)].push_back(i);
    }
  }

  // (With E_scalar the points stay on their faces: their values are kept beside them, face by face.)
  std::optional<double> fit(EngineState& s, int pass) override {
    return fit_points(s, face_samples_, curves_, pass > 0 && dims_ == 0);
  }
  double fit_measure(const EngineState& s) override { return points_energy(s, face_samples_, curves_); }

 private:
  // A point on `face` at barycentric `weights`; with E_scalar, the input's values there too.
  void add_point(const EngineState& s, const Eigen::Vector3d& p, Index face, const Eigen::Vector3d& weights) {
    face_samples_[face].push_back({p, 0.0});
    if (dims_ == 0) return;
    const std::size_t k = static_cast<std::size_t>(dims_);
    auto& list = face_values_[face];
    const std::size_t at = list.size();
    list.resize(at + k + 2, 0.0);
    for (int c = 0; c < 3; ++c)
      for (std::size_t d = 0; d < k; ++d) list[at + d] += weights[c] * s.wedge_value[k * std::size_t(s.face[face][c]) + d];
    list[at + k + 1] = static_cast<double>(face_chart_[face]);
  }

  // With E_scalar: per face, its chart, the faces joined across edges whose two faces share both
  // wedges (no attribute seam between them). A face keeps its chart: wedges merge within one.
  void find_charts(const EngineState& s) {
    UnionFind charts(s.face.size());
    unite_across_edges(
        Index(s.face.size()), [&](Index f, int k) { return s.corner_point(f, k); }, [&](Index f) { return s.face_dead[f] != 0; },
        [&](Index f, int k, Index g, int j) { return s.face[f][k] == s.face[g][j]; }, charts);
    face_chart_.resize(s.face.size());
    for (std::size_t f = 0; f < s.face.size(); ++f) face_chart_[f] = charts.find(int(f));
  }

  // With E_scalar, a reassigned point: its new face, its offset in face_values_ there, and (on its own
  // chart) its projection's barycentric weights.
  struct Landed {
    Index face;
    std::size_t at;
    Eigen::Vector3d weights;
  };

  // With E_scalar, after a collapse: the merged wedges at the values that minimise E_scalar over the points
  // now on the faces around v (as the score assumed), then every such point's distance measured again
  // (every face here has v at a corner). `landed`: per point of `moving`, its face and offset in
  // face_values_.
  void place_values(EngineState& s, Index v, const Probe& probe, const std::vector<Sample>& moving,
                    std::vector<Landed>& landed) {
    const std::size_t k = static_cast<std::size_t>(dims_);
    struct Sums {
      double b2 = 0;
      std::array<double, kMostAttributeDims> by{};
    };
    std::array<Sums, 2> sums{};
    auto merged_slot = [&](Index w) {
      for (int i = 0; i < probe.wedge_map_size; ++i)
        if (probe.wedge_map[i].second == w) return i;
      return -1;
    };
    for (std::size_t j = 0; j < moving.size(); ++j) {
      Landed& l = landed[j];
      const Index f = l.face;
      const double* x = &face_values_[f][l.at];
      if (face_chart_[f] != static_cast<Index>(x[k + 1])) continue;
      // The point's projection, found once: the solve and its distance after both read it.
      const Eigen::Vector3d c0 = s.position[s.corner_point(f, 0)], c1 = s.position[s.corner_point(f, 1)],
                            c2 = s.position[s.corner_point(f, 2)];
      const Eigen::Vector3d& w = l.weights = barycentric(c0, c1, c2, closest_point_on_triangle(moving[j].x, c0, c1, c2));
      int corner = 0;
      while (s.corner_point(f, corner) != v) ++corner;
      const int slot = merged_slot(s.face[f][corner]);
      if (slot < 0) continue;
      Sums& sum = sums[std::size_t(slot)];
      sum.b2 += w[corner] * w[corner];
      for (std::size_t d = 0; d < k; ++d) {
        double y = x[d];
        for (int c = 0; c < 3; ++c)
          if (c != corner) y -= w[c] * s.wedge_value[k * std::size_t(s.face[f][c]) + d];
        sum.by[d] += w[corner] * y;
      }
    }
    for (int i = 0; i < probe.wedge_map_size; ++i) {
      const auto [wu, wv] = probe.wedge_map[i];
      double* value = &s.wedge_value[k * std::size_t(wv)];
      const Sums& sum = sums[std::size_t(i)];
      // Where no point pins the value down, the attribute quadrics' choice.
      if (sum.b2 > 1e-12) for (std::size_t d = 0; d < k; ++d) value[d] = sum.by[d] / sum.b2;
      else s.attribute_quadrics.best_at(std::size_t(wu), std::size_t(wv), s.position[v], value);
    }
    for (const Landed& l : landed) {
      double* x = &face_values_[l.face][l.at];
      // Across a seam the faces interpolate another chart's values: nothing to compare there.
      x[k] = face_chart_[l.face] == static_cast<Index>(x[k + 1]) ? scalar_distance2(s, l.weights, x, l.face) : 0.0;
    }
  }

  // With E_scalar: the squared distance from a point's values to those the mesh interpolates at its
  // projection onto `face`, at barycentric `weights` there.
  double scalar_distance2(const EngineState& s, const Eigen::Vector3d& weights, const double* values, Index face) const {
    const std::size_t k = static_cast<std::size_t>(dims_);
    double d2 = 0;
    for (std::size_t d = 0; d < k; ++d) {
      double at = 0;
      for (int corner = 0; corner < 3; ++corner) at += weights[corner] * s.wedge_value[k * std::size_t(s.face[face][corner]) + d];
      d2 += (values[d] - at) * (values[d] - at);
    }
    return d2;
  }

  FaceSamples face_samples_;
  FaceValues face_values_;  ///< with E_scalar (attribute weights), else empty; k + 2 numbers per point: its
                            ///< values, their squared distance to the mesh's, and the point's chart
  std::vector<Index> face_chart_;  ///< with E_scalar: per face, its chart
  int dims_ = 0;            ///< attribute values per point (0: no E_scalar)
  // Scratch of collapsed(), per thread (lanes collapse side by side).
  struct ReassignScratch {
    std::vector<Sample> moving;
    std::vector<double> values;  ///< with E_scalar: dims_ + 2 per point of moving
    std::vector<std::size_t> home_of;  ///< per point of moving: its face's index in faces_of(v)
    BoundRows rows;
    std::vector<Landed> landed;  ///< with E_scalar: per point of moving
  };
  tbb::enumerable_thread_specific<ReassignScratch> reassign_scratch_;
  double margin_ = 0;  ///< slack for rounding in the lower bounds: 1e-9 of the input's extent
  BoundaryCurves curves_;
  tbb::enumerable_thread_specific<HoppeScorer> scorers_{[this] {
    HoppeScorer scorer(face_samples_, curves_, face_values_, face_chart_);
    scorer.set_attribute_dims(dims_);
    return scorer;
  }};
};

}  // namespace

std::unique_ptr<CostModel> make_hoppe_cost(const SimplifyOptions& options, const EngineState& state) {
  return std::make_unique<HoppeCost>(options, state);
}

}  // namespace lodkit::detail
