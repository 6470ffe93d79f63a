// Hoppe's energy as the engine's cost (Progressive meshes, SIGGRAPH 1996, section 4): the points
// sampled on the input (its vertices, random points on its faces, points along its boundaries and sharp
// edges), each kept on the current face it projects to as the collapses go. Scoring a candidate against
// them is hoppe_scorer.h's; the fit after the collapses is hoppe_fit.cpp's.
#include <algorithm>
#include <random>
#include <tbb/enumerable_thread_specific.h>

#include "core/bound_rows.h"
#include "core/geometry.h"
#include "core/union_find.h"
#include "core/uv_charts.h"
#include "simplify/hoppe_points.h"
#include "simplify/hoppe_scorer.h"

namespace lodkit::detail {
namespace {

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
    if (o.hoppe_energy_from > 1 && !o.record_collapses) by_quadric_ = make_quadric_cost(o);
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

  // (The quadric's scores change only at the collapse's own edges.)
  bool wide_update() const override { return !by_quadric_; }
  bool costly() const override { return true; }
  bool scores_by_quadric() const override { return by_quadric_ != nullptr; }
  void own_scores() override { by_quadric_.reset(); }

  bool score(const EngineState& s, const Probe& probe, Index u, Index v, Freedom freedom, Candidate& out) override {
    if (by_quadric_) return leaves_a_face(s, probe, u, v) && by_quadric_->score(s, probe, u, v, freedom, out);
    return scorers_.local().score(s, probe, u, v, freedom, probe.shared.size() == 1, out);
  }

  // A collapse that removes every face at u and v (an isolated triangle, without the topology checks)
  // leaves their points no face to go to. The energy refuses it (HoppeScorer::score()); the quadric
  // stage must too. The vanishing faces are in both lists.
  static bool leaves_a_face(const EngineState& s, const Probe& probe, Index u, Index v) {
    return s.faces_of(u).size() + s.faces_of(v).size() > 2 * probe.shared.size();
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

  std::unique_ptr<CostModel> by_quadric_;  ///< scores in place of the energy until own_scores()
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
