// Hoppe's energy of one candidate collapse: see hoppe_scorer.h.
#include "simplify/hoppe_scorer.h"

#include <algorithm>
#include <bit>
#include <iterator>

namespace lodkit::detail {

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

bool HoppeScorer::score(const EngineState& s, const Probe& probe, Index u, Index v, Freedom freedom, bool border_edge, Candidate& out) {
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

template <bool kOnTriangle>
void HoppeScorer::project_all(const Eigen::Vector3d& p, bool solve) {
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

double HoppeScorer::weight_after_moving(std::size_t k, const Eigen::Vector3d& x, const Nearest& n) const {
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

HoppeScorer::Nearest HoppeScorer::nearest_on(std::size_t k, const Eigen::Vector3d& x, const Eigen::Vector3d& p, bool solve) const {
  return rows_.inside_prism(k) ? in_prism(x, tri_[k], rows_.plane_distances()[k], p, solve) : on_triangle(x, tri_[k], p, solve);
}

HoppeScorer::Nearest HoppeScorer::in_prism(const Eigen::Vector3d& x, const Tri& t, double plane, const Eigen::Vector3d& p, bool solve) {
  Nearest out{plane * plane, 0.0, Eigen::Vector3d::Zero()};
  if (solve) {
    const Eigen::Vector3d q = x - plane * t.normal;
    const double inside = t.edge_offset[t.side] - t.edge_normal[t.side].dot(x);
    out.b = std::clamp(inside * t.per_distance, 0.0, 1.0);
    out.fixed = q - out.b * p;
  }
  return out;
}

HoppeScorer::Nearest HoppeScorer::on_triangle(const Eigen::Vector3d& x, const Tri& t, const Eigen::Vector3d& p, bool solve) {
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

double HoppeScorer::scalar_energy(const EngineState& s) {
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

void HoppeScorer::gather(const EngineState& s, const Probe& probe, Index u, Index v) {
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
    for (Index f : s.faces_of(p)) {
      // Every line of the points that take part (at most kPointsPerFace of them, strided), not just the first.
      const auto& fp = face_samples_[f];
      const char* at = reinterpret_cast<const char*>(fp.data());
      const std::size_t stride = stride_of(fp.size());
      for (std::size_t i = 0; i < fp.size(); i += stride) __builtin_prefetch(at + i * sizeof(Sample));
    }
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
      const std::size_t stride = stride_of(fp.size());
      const int home = has_u && has_v ? -1 : static_cast<int>(star_.size());  // its triangle in the new star
      for (std::size_t i = 0; i < fp.size(); i += stride) {
        points_.push_back(fp[i].x);
        dist2_.push_back(fp[i].dist2);
        weight_.push_back(double(stride));
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

void HoppeScorer::add_star_wedges(const EngineState& s, const Probe& probe, Index f, Index u) {
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

void HoppeScorer::insert_sorted(std::vector<Index>& r, Index q) {
  auto at = r.end();
  while (at != r.begin() && *(at - 1) > q) --at;
  if (at == r.begin() || *(at - 1) != q) r.insert(at, q);
}

void HoppeScorer::gather_curves(const EngineState& s, Index u, Index v, bool border_edge) {
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

}  // namespace lodkit::detail
