// Hoppe's fit after the collapses: the position step of Hoppe, DeRose, Duchamp, McDonald and Stuetzle,
// "Mesh optimization" (SIGGRAPH 1993), connectivity fixed. A collapse places its vertex once, fitted to
// the points around it at that moment; later collapses hand those points to other faces but never move
// the vertex again. Here every vertex is fitted at once. With each sample's barycentric weights on its
// face held, E = E_dist + E_spring + the boundary points' squared distances to their edges is a
// quadratic in the positions, with one matrix for x, y and z: one sparse Cholesky solve finds its
// least. Measuring again can only bring a point nearer its face than the held weights put it, so E
// after is at most the solve's value (the engine measures it, once it has sent back the moves that break
// its limits). A later pass first hands each sample to the nearest face at its
// face's corners (the paper's projection step).
//
// Every sum runs in face order (per-face terms side by side, then added in turn), so the result does not
// depend on the thread count.
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/geometry.h"
#include "simplify/hoppe_points.h"

namespace lodkit::detail {
namespace {

using Vec = Eigen::Vector3d;

std::vector<Index> alive_faces(const EngineState& s) {
  std::vector<Index> faces;
  for (std::size_t f = 0; f < s.face.size(); ++f)
    if (!s.face_dead[f]) faces.push_back(Index(f));
  return faces;
}

std::array<Vec, 3> corners(const EngineState& s, Index f) {
  return {s.position[s.corner_point(f, 0)], s.position[s.corner_point(f, 1)], s.position[s.corner_point(f, 2)]};
}

// Each edge of the current mesh once, as (lower point, higher point), sorted.
std::vector<std::pair<Index, Index>> edges_of(const EngineState& s, const std::vector<Index>& faces) {
  std::vector<std::pair<Index, Index>> edges;
  edges.reserve(3 * faces.size());
  for (Index f : faces)
    for (int k = 0; k < 3; ++k) {
      const Index a = s.corner_point(f, k), b = s.corner_point(f, (k + 1) % 3);
      edges.push_back({std::min(a, b), std::max(a, b)});
    }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  return edges;
}

// The boundary edges that hold points, in key order (the map's own order depends on which lane added first).
std::vector<std::uint64_t> curve_keys(const BoundaryCurves& curves) {
  std::vector<std::uint64_t> keys;
  for (const auto& [key, list] : curves.edge_points)
    if (!list.empty()) keys.push_back(key);
  std::sort(keys.begin(), keys.end());
  return keys;
}

// A boundary point x held at weight 1 - t on a and t on b: its squared distance there.
double on_edge_distance2(const EngineState& s, Index a, Index b, double t, const Vec& x) {
  return (s.position[a] + t * (s.position[b] - s.position[a]) - x).squaredNorm();
}

double spring_energy(const EngineState& s, const std::vector<std::pair<Index, Index>>& edges, double kappa) {
  double e = 0;
  for (const auto& [a, b] : edges) e += kappa * (s.position[a] - s.position[b]).squaredNorm();
  return e;
}

double spring_constant_of(const FaceSamples& samples, const std::vector<Index>& faces) {
  std::size_t points = 0;
  for (Index f : faces) points += samples[f].size();
  return spring_constant(faces.empty() ? 0.0 : double(points) / double(faces.size()));
}

// One face's part of the normal equations: its points' sum of b b^T, the sums b_k x^T (row k), and
// their squared distances, each point at its nearest point on the face.
struct FaceTerms {
  Eigen::Matrix3d bb = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d bx = Eigen::Matrix3d::Zero();
  double energy = 0;  ///< sum of squared distances
};

FaceTerms face_terms(const std::array<Vec, 3>& c, const std::vector<Sample>& points) {
  FaceTerms t;
  for (const Sample& p : points) {
    const Vec q = closest_point_on_triangle(p.x, c[0], c[1], c[2]);
    const Vec b = barycentric(c[0], c[1], c[2], q);
    t.energy += (q - p.x).squaredNorm();
    t.bb += b * b.transpose();
    t.bx += b * p.x.transpose();
  }
  return t;
}

std::vector<FaceTerms> all_face_terms(const EngineState& s, const FaceSamples& samples, const std::vector<Index>& faces) {
  std::vector<FaceTerms> terms(faces.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, faces.size(), 256), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i) terms[i] = face_terms(corners(s, faces[i]), samples[faces[i]]);
  });
  return terms;
}

// Each sample to the nearest of its face and the faces at its corners (the first on a tie), in face order.
void reassign_samples(const EngineState& s, FaceSamples& samples, const std::vector<Index>& faces) {
  std::vector<std::vector<std::pair<Index, Sample>>> leaving(faces.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, faces.size(), 64), [&](const tbb::blocked_range<std::size_t>& r) {
    std::vector<Index> near;
    for (std::size_t i = r.begin(); i < r.end(); ++i) {
      const Index f = faces[i];
      near.assign(1, f);
      for (int k = 0; k < 3; ++k)
        for (Index g : s.faces_of(s.corner_point(f, k)))
          if (!s.face_dead[g] && g != f) near.push_back(g);
      std::sort(near.begin() + 1, near.end());
      near.erase(std::unique(near.begin() + 1, near.end()), near.end());
      auto& list = samples[f];
      std::size_t kept = 0;
      for (Sample p : list) {
        Index best_face = f;
        double best = INFINITY;
        for (Index g : near) {
          const auto c = corners(s, g);
          if (const double d = (closest_point_on_triangle(p.x, c[0], c[1], c[2]) - p.x).squaredNorm(); d < best)
            best = d, best_face = g;
        }
        p.dist2 = best;
        if (best_face == f) list[kept++] = p;
        else leaving[i].push_back({best_face, p});
      }
      list.resize(kept);
    }
  });
  for (const auto& moves : leaving)
    for (const auto& [g, p] : moves) samples[g].push_back(p);
}

}  // namespace

double points_energy(const EngineState& s, const FaceSamples& samples, const BoundaryCurves& curves) {
  const std::vector<Index> faces = alive_faces(s);
  std::vector<double> per_face(faces.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, faces.size(), 256), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i) {
      const auto c = corners(s, faces[i]);
      double e = 0;
      for (const Sample& p : samples[faces[i]]) e += (closest_point_on_triangle(p.x, c[0], c[1], c[2]) - p.x).squaredNorm();
      per_face[i] = e;
    }
  });
  double energy = 0;
  for (double e : per_face) energy += e;
  for (std::uint64_t key : curve_keys(curves)) {
    const auto [a, b] = BoundaryCurves::edge_of(key);
    for (Index i : curves.edge_points.at(key)) {
      const Vec& x = curves.point[i];
      energy += on_edge_distance2(s, a, b, segment_parameter(x, s.position[a], s.position[b]), x);
    }
  }
  return energy + spring_energy(s, edges_of(s, faces), spring_constant_of(samples, faces));
}

std::optional<double> fit_points(EngineState& s, FaceSamples& samples, const BoundaryCurves& curves, bool reassign) {
  const std::vector<Index> faces = alive_faces(s);
  if (reassign) reassign_samples(s, samples, faces);
  // Unknowns: the points of live faces that may move.
  std::vector<Index> column(s.position.size(), -1), point_of;
  for (Index f : faces)
    for (int k = 0; k < 3; ++k)
      if (const Index p = s.corner_point(f, k); column[p] < 0 && !s.has(p, kLocked))
        column[p] = Index(point_of.size()), point_of.push_back(p);
  const Index n = Index(point_of.size());
  if (n == 0) return std::nullopt;

  // A term over corners c[0..m) with weights W (symmetric) and right-hand sides R (row per corner): the
  // fixed corners' share moves to the right-hand side.
  std::vector<Eigen::Triplet<double>> entries;
  Eigen::MatrixX3d rhs = Eigen::MatrixX3d::Zero(n, 3);
  auto add_term = [&](const Index* c, int m, auto&& weight, auto&& right) {
    for (int j = 0; j < m; ++j) {
      const Index cj = column[c[j]];
      if (cj < 0) continue;
      Eigen::RowVector3d r = right(j);
      for (int k = 0; k < m; ++k) {
        if (const Index ck = column[c[k]]; ck >= 0) entries.emplace_back(cj, ck, weight(j, k));
        else r -= weight(j, k) * s.position[c[k]].transpose();
      }
      rhs.row(cj) += r;
    }
  };
  double before = 0;  // E as the terms measure it
  const std::vector<FaceTerms> terms = all_face_terms(s, samples, faces);
  for (std::size_t i = 0; i < faces.size(); ++i) {
    const Index c[3] = {s.corner_point(faces[i], 0), s.corner_point(faces[i], 1), s.corner_point(faces[i], 2)};
    add_term(c, 3, [&](int j, int k) { return terms[i].bb(j, k); }, [&](int j) { return Eigen::RowVector3d(terms[i].bx.row(j)); });
    before += terms[i].energy;
  }
  for (std::uint64_t key : curve_keys(curves)) {
    const auto [a, b] = BoundaryCurves::edge_of(key);
    for (Index i : curves.edge_points.at(key)) {
      const Vec& x = curves.point[i];
      const double t = segment_parameter(x, s.position[a], s.position[b]);
      before += on_edge_distance2(s, a, b, t, x);
      const Index c[2] = {a, b};
      const double w[2] = {1 - t, t};
      add_term(c, 2, [&](int j, int k) { return w[j] * w[k]; }, [&](int j) { return Eigen::RowVector3d(w[j] * x.transpose()); });
    }
  }
  const double kappa = spring_constant_of(samples, faces);
  const std::vector<std::pair<Index, Index>> edges = edges_of(s, faces);
  before += spring_energy(s, edges, kappa);
  for (const auto& [a, b] : edges) {
    const Index c[2] = {a, b};
    add_term(c, 2, [&](int j, int k) { return j == k ? kappa : -kappa; }, [](int) { return Eigen::RowVector3d::Zero().eval(); });
  }
  // A pull of a millionth of the mean diagonal towards where each point is: a point whose faces hold no
  // samples (its springs weigh 1e-8 on fine data) stays put instead of leaving the matrix near singular.
  double diagonal = 0;
  for (const auto& e : entries)
    if (e.row() == e.col()) diagonal += e.value();
  const double pull = 1e-6 * diagonal / double(n);
  for (Index i = 0; i < n; ++i) entries.emplace_back(i, i, pull), rhs.row(i) += pull * s.position[point_of[i]].transpose();

  Eigen::SparseMatrix<double> system(n, n);
  system.setFromTriplets(entries.begin(), entries.end());
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(system);
  if (solver.info() != Eigen::Success) return std::nullopt;
  const Eigen::MatrixX3d solved = solver.solve(rhs);
  if (solver.info() != Eigen::Success || !solved.allFinite()) return std::nullopt;
  for (Index i = 0; i < n; ++i)
    if (s.representable(solved.row(i).transpose())) s.position[point_of[i]] = solved.row(i).transpose();

  return before;
}

}  // namespace lodkit::detail
