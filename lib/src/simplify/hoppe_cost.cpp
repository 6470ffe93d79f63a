// Hoppe's energy (Progressive meshes, SIGGRAPH 1996, section 4): E = E_dist + E_spring, where E_dist
// is the sum of squared distances from points sampled on the original surface to the current mesh
// and E_spring = kappa * sum of squared edge lengths. Every point belongs to the face it projects to.
// A collapse u -> v is scored by Delta E: the points of the faces around u and v are re-projected onto
// the faces around the merged vertex, whose position is optimised by alternating (a) projection of
// each point onto its nearest face and (b) the linear least-squares solve for the position given
// those projections, starting from the quadric-optimal position.
#include <random>
#include <tbb/enumerable_thread_specific.h>

#include "core/geometry.h"
#include "simplify/engine.h"

namespace lodkit::detail {
namespace {

// Scores candidates against the shared sample points. Each thread that scores has its own scorer:
// the scratch below is per candidate, the points are only read.
class HoppeScorer {
  // A triangle of the new star, with its plane and the three planes through its edges at right angles
  // to it (outward normals).
  struct Tri {
    Eigen::Vector3d c[3], normal, edge_normal[3];
    double offset, edge_offset[3], area2;
    int moving;
  };
  struct Nearest {
    double d2, b;           ///< squared distance; barycentric weight of the moving corner
    Eigen::Vector3d fixed;  ///< the projection minus b times the moving corner
  };

 public:
  HoppeScorer(const std::vector<Eigen::Vector3d>& point, const std::vector<double>& dist2,
              const std::vector<std::vector<Index>>& face_points)
      : point_(point), dist2_(dist2), face_points_(face_points) {}

  bool score(const EngineState& s, Index u, Index v, Freedom freedom, Candidate& out) {
    gather(s, u, v);
    // Spring energy before: the edges at u and at v (the rest of the neighbourhood does not change).
    const double kappa = spring_constant();
    double before = 0;
    for (std::size_t j = 0; j < points_.size(); ++j) before += weight_[j] * dist2_[points_[j]];
    for (Index w : ring_u_) before += kappa * (s.position[u] - s.position[w]).squaredNorm();
    for (Index w : ring_v_)
      if (w != u) before += kappa * (s.position[v] - s.position[w]).squaredNorm();

    double worst = 0;  // largest squared point distance at the last evaluated position
    // With the projections held fixed, E at another position q is sum w |x - b q - f|^2 + springs: an
    // upper bound of the true E(q), since re-projecting can only bring points closer. So one projection
    // pass gives both the solve and a safe energy for the solved position.
    double solved_energy = 0, solved_worst = 0;
    auto energy = [&](const Eigen::Vector3d& p, bool solve, Eigen::Vector3d* improved) {
      // Project every point onto the new star; optionally solve for the position given the projections.
      double e = 0, sum_b2 = 0;
      worst = 0;
      projections_.clear();
      Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
      // The star's triangles, each with its plane and the three planes through its edges at right
      // angles to it (outward): together they bound the distance to the triangle from below.
      tri_.clear();
      for (const auto& t : star_) {
        Tri tri;
        for (int k = 0; k < 3; ++k) tri.c[k] = t[k] < 0 ? p : s.position[t[k]];
        tri.moving = t[0] < 0 ? 0 : t[1] < 0 ? 1 : 2;
        const Eigen::Vector3d n = (tri.c[1] - tri.c[0]).cross(tri.c[2] - tri.c[0]);
        tri.area2 = n.squaredNorm();
        const double len = std::sqrt(tri.area2);
        tri.normal = len > 0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
        tri.offset = tri.normal.dot(tri.c[0]);
        for (int k = 0; k < 3; ++k) {
          const Eigen::Vector3d outward = (tri.c[(k + 1) % 3] - tri.c[k]).cross(tri.normal);
          const double l = outward.norm();
          tri.edge_normal[k] = l > 0 ? Eigen::Vector3d(outward / l) : Eigen::Vector3d::Zero();
          tri.edge_offset[k] = tri.edge_normal[k].dot(tri.c[k]);
        }
        tri_.push_back(tri);
      }
      // (Projecting in parallel did not pay: a neighbourhood holds 50-300 points, a few microseconds.)
      for (std::size_t j = 0; j < points_.size(); ++j) {
        const Nearest n = nearest(point_[points_[j]], home_[j], p, solve);
        const double weight = weight_[j];
        e += weight * n.d2;
        worst = std::max(worst, n.d2);
        if (solve) {
          sum_b2 += weight * n.b * n.b;
          rhs += weight * n.b * (point_[points_[j]] - n.fixed);
          projections_.push_back({points_[j], weight, n.b, n.fixed});
        }
      }
      for (Index w : ring_) {
        e += kappa * (p - s.position[w]).squaredNorm();
        if (solve) rhs += kappa * s.position[w], sum_b2 += kappa;
      }
      if (solve && improved) {
        *improved = sum_b2 > 0 ? Eigen::Vector3d(rhs / sum_b2) : p;
        solved_energy = 0, solved_worst = 0;
        for (const Projection& pr : projections_) {
          const double d = (point_[pr.point] - pr.b * *improved - pr.fixed).squaredNorm();
          solved_energy += pr.weight * d;
          solved_worst = std::max(solved_worst, d);
        }
        for (Index w : ring_) solved_energy += kappa * (*improved - s.position[w]).squaredNorm();
      }
      return e;
    };

    // Start where the quadric puts the vertex (cheap, and close to the energy's optimum), project the
    // points once while setting up the least-squares solve, then evaluate the solved position.
    Eigen::Vector3d p = s.position[v];
    Eigen::Vector3d next;
    double e = 0, e_worst = 0;
    {
      if (freedom == Freedom::Free) {
        const Quadric q = s.quadric[u] + s.quadric[v];
        const Eigen::Vector3d mid = 0.5 * (s.position[u] + s.position[v]);
        Eigen::Vector3d best;
        p = q.truncated_minimiser_near(mid, best) && (best - mid).norm() <= 2.0 * (s.position[u] - s.position[v]).norm() ? best : mid;
      }
      e = energy(p, freedom == Freedom::Free, &next), e_worst = worst;
      if (freedom == Freedom::Free && solved_energy < e) e = solved_energy, p = next, e_worst = solved_worst;
    }
    out.position = p;
    out.cost = e - before;
    out.error = std::sqrt(e_worst);  // the farthest sample point from the merged neighbourhood
    return true;
  }

  // Squared lower bound of the distance from x to triangle t: the distance to its plane, combined at
  // right angles with how far x lies outside the planes through its edges.
  static double bound2(const Tri& t, const Eigen::Vector3d& x) {
    const double plane = t.normal.dot(x) - t.offset;
    const double outside = std::max({0.0, t.edge_normal[0].dot(x) - t.edge_offset[0],
                                     t.edge_normal[1].dot(x) - t.edge_offset[1], t.edge_normal[2].dot(x) - t.edge_offset[2]});
    return plane * plane + outside * outside;
  }

  // The nearest point to x on the new star (merged vertex at p). The triangle x's face becomes (`home`)
  // is nearly always the nearest, so it goes first and its distance rules out nearly every other one.
  // A point of a vanishing face has no home: the triangle with the lowest bound goes first, and the
  // bounds computed to find it are the ones the loop checks.
  Nearest nearest(const Eigen::Vector3d& x, int home, const Eigen::Vector3d& p, bool solve) {
    std::size_t first = home >= 0 ? std::size_t(home) : 0;
    if (home < 0) {
      bound2_.resize(tri_.size());
      for (std::size_t k = 0; k < tri_.size(); ++k)
        if ((bound2_[k] = bound2(tri_[k], x)) < bound2_[first]) first = k;
    }
    Nearest out{INFINITY, 0.0, Eigen::Vector3d::Zero()};
    for (std::size_t n = 0; n < tri_.size(); ++n) {
      const std::size_t k = n == 0 ? first : n == first ? 0 : n;
      const Tri& t = tri_[k];
      if (n > 0 && (home < 0 ? bound2_[k] : bound2(t, x)) >= out.d2) continue;
      const Eigen::Vector3d q = closest_point_on_triangle(x, t.c[0], t.c[1], t.c[2]);
      const double d = (q - x).squaredNorm();
      if (d >= out.d2) continue;
      out.d2 = d;
      if (solve) {
        // Barycentric weight of the moving corner, and the fixed remainder of q.
        const int m = t.moving;
        const Eigen::Vector3d e1 = t.c[(m + 1) % 3] - q, e2 = t.c[(m + 2) % 3] - q;
        out.b = t.area2 > 0 ? std::clamp(e1.cross(e2).dot(t.normal) / std::sqrt(t.area2), 0.0, 1.0) : 0.0;
        out.fixed = q - out.b * p;
      }
    }
    return out;
  }

 private:
  // Collects the neighbourhood of u -> v: its points, the new star (corner -1 = the merged vertex),
  // and the rings of u, v and the merged vertex.
  void gather(const EngineState& s, Index u, Index v) {
    points_.clear();
    weight_.clear();
    home_.clear();
    point_count_ = 0;
    star_.clear();
    ring_u_.clear(), ring_v_.clear(), ring_.clear();
    faces_ = 0;
    for (Index p : {u, v})
      for (Index f : s.faces_of(p)) {
        bool has_u = false, has_v = false;
        for (int k = 0; k < 3; ++k) has_u |= s.corner_point(f, k) == u, has_v |= s.corner_point(f, k) == v;
        if (p == v && has_u) continue;  // counted from u's side already
        ++faces_;
        // At most kPointsPerFace points of each face take part, each standing for its share: the
        // estimate of Delta E stays unbiased while coarse levels (100+ points per face) stay cheap.
        const auto& fp = face_points_[f];
        point_count_ += fp.size();
        const std::size_t stride = (fp.size() + kPointsPerFace - 1) / kPointsPerFace;
        const int home = has_u && has_v ? -1 : static_cast<int>(star_.size());  // its triangle in the new star
        for (std::size_t i = 0; i < fp.size(); i += std::max<std::size_t>(stride, 1)) {
          points_.push_back(fp[i]);
          weight_.push_back(double(stride ? stride : 1));
          home_.push_back(home);
        }
        for (int k = 0; k < 3; ++k) {
          const Index q = s.corner_point(f, k);
          if (q != u && q != v) ring_.push_back(q);
          if (p == u && q != u) ring_u_.push_back(q);
          if (p == v && q != v) ring_v_.push_back(q);
        }
        if (has_u && has_v) continue;  // vanishes
        std::array<Index, 3> t;
        for (int k = 0; k < 3; ++k) {
          const Index q = s.corner_point(f, k);
          t[k] = q == u || q == v ? -1 : q;
        }
        star_.push_back(t);
      }
    for (auto* r : {&ring_u_, &ring_v_, &ring_}) {
      std::sort(r->begin(), r->end());
      r->erase(std::unique(r->begin(), r->end()), r->end());
    }
  }

  // Hoppe's schedule: springs matter while there are few points per face (they keep vertices from
  // drifting where the data cannot hold them) and fade as points accumulate.
  double spring_constant() const {
    const double points_per_face = faces_ > 0 ? double(point_count_) / faces_ : 0.0;
    if (points_per_face < 4) return 1e-2;
    if (points_per_face < 8) return 1e-4;
    return 1e-8;
  }

  const std::vector<Eigen::Vector3d>& point_;
  const std::vector<double>& dist2_;  ///< per point: squared distance to its face
  const std::vector<std::vector<Index>>& face_points_;
  // Scratch for one candidate.
  static constexpr std::size_t kPointsPerFace = 16;
  std::vector<Index> points_, ring_u_, ring_v_, ring_;
  std::vector<double> weight_;
  std::vector<int> home_;  ///< per point of points_: the star triangle its face becomes, or -1
  std::size_t point_count_ = 0;
  std::vector<std::array<Index, 3>> star_;
  std::vector<Tri> tri_;
  std::vector<double> bound2_;  ///< nearest()'s bounds for a point without a home triangle
  struct Projection {
    Index point;
    double weight, b;
    Eigen::Vector3d fixed;
  };
  std::vector<Projection> projections_;
  Index faces_ = 0;
};

class HoppeCost final : public CostModel {
 public:
  HoppeCost(const SimplifyOptions& o, const EngineState& s) {
    // Points: every vertex position, plus `points_per_face` random points per face (seeded).
    const Mesh& m = *s.input;
    std::mt19937_64 rng(o.seed);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    face_points_.resize(s.face.size());
    std::vector<char> placed(s.position.size(), 0);
    double carry = 0;
    for (std::size_t f = 0; f < s.face.size(); ++f) {
      if (s.face_dead[f]) continue;
      for (int k = 0; k < 3; ++k) {
        const Index p = s.corner_point(Index(f), k);
        if (!placed[p]) placed[p] = 1, add_point(s.position[p], Index(f));
      }
      carry += o.hoppe_points_per_face;
      for (; carry >= 1.0; carry -= 1.0) {
        double a = unit(rng), b = unit(rng);
        if (a + b > 1) a = 1 - a, b = 1 - b;
        const Eigen::Vector3d p0 = m.positions.row(s.face[f][0]), p1 = m.positions.row(s.face[f][1]),
                              p2 = m.positions.row(s.face[f][2]);
        add_point(p0 + a * (p1 - p0) + b * (p2 - p0), Index(f));
      }
    }
  }

  bool wide_update() const override { return true; }
  bool costly() const override { return true; }

  bool score(const EngineState& s, const Probe&, Index u, Index v, Freedom freedom, Candidate& out) override {
    return scorers_.local().score(s, u, v, freedom, out);
  }

  void collapsed(EngineState& s, Index u, Index v, const std::vector<Index>& removed_faces) override {
    // Re-assign the points of the old neighbourhood to the faces now around v.
    std::vector<Index> moving;
    for (Index f : removed_faces) moving.insert(moving.end(), face_points_[f].begin(), face_points_[f].end());
    for (Index f : removed_faces) face_points_[f].clear();
    const std::vector<Index>& around = s.faces_of(v);
    for (Index f : around) {
      moving.insert(moving.end(), face_points_[f].begin(), face_points_[f].end());
      face_points_[f].clear();
    }
    (void)u;
    for (Index i : moving) {
      double best = INFINITY;
      Index best_face = -1;
      for (Index f : around) {
        const Eigen::Vector3d q = closest_point_on_triangle(point_[i], s.position[s.corner_point(f, 0)],
                                                            s.position[s.corner_point(f, 1)], s.position[s.corner_point(f, 2)]);
        const double d = (q - point_[i]).squaredNorm();
        if (d < best) best = d, best_face = f;
      }
      dist2_[i] = best;
      face_points_[best_face].push_back(i);
    }
  }

 private:
  void add_point(const Eigen::Vector3d& p, Index face) {
    face_points_[face].push_back(static_cast<Index>(point_.size()));
    point_.push_back(p);
    dist2_.push_back(0.0);
  }

  std::vector<Eigen::Vector3d> point_;
  std::vector<double> dist2_;
  std::vector<std::vector<Index>> face_points_;
  tbb::enumerable_thread_specific<HoppeScorer> scorers_{[this] { return HoppeScorer(point_, dist2_, face_points_); }};
};

}  // namespace

std::unique_ptr<CostModel> make_hoppe_cost(const SimplifyOptions& options, const EngineState& state) {
  return std::make_unique<HoppeCost>(options, state);
}

}  // namespace lodkit::detail
