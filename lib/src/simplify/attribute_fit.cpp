// fit_attributes_to_input(): a simplification's vertex normals, colours and UVs set to the values that
// best match the input's, positions and faces unchanged.
//
// A collapse keeps one wedge's normal and colour (or, with attribute weights, the value its quadric
// finds best for the neighbourhood at that moment); later collapses widen the faces around it, and the
// refit moves it, but nothing sets the value again. Here every value is fitted at once, the way the
// refit fits positions: points are sampled on both surfaces, and each pairs the value one surface has
// there with the value the other has at its closest point. The output's values interpolate linearly
// over each face, so the pairs are linear in the unknown vertex values, and one sparse least-squares
// solve gives all of them (one matrix, a column per channel). Output vertices split by a seam are
// separate unknowns, so a hard edge stays hard. Normals are renormalised after, colours clamped to
// 0..1. UVs have a solve of their own: a pair counts for them only within a chart (as compare() measures
// them: charts matched by vote, and the point's UV near its closest face's), since across a UV seam the
// other side's values belong to another piece of the atlas. Sums run in sample order, so the result does
// not depend on the thread count.
#include <lodkit/error.h>
#include <lodkit/simplify.h>

#include <Eigen/SparseCholesky>
#include <fmt/format.h>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <span>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/geometry.h"
#include "core/interpolate.h"
#include "core/uv_charts.h"
#include "metrics/aabb_tree.h"
#include "simplify/attribute_fit.h"

namespace lodkit {
namespace {

using Vec = Eigen::Vector3d;

// The channels fitted, those both meshes have: normals (3) and colours (4), in one solve; UVs (2) in
// another (their pairs differ). Values are laid out in that order: kUvAt is where UVs start.
struct Channels {
  bool normals = false, colours = false, uvs = false;
  int shared() const { return 3 * normals + 4 * colours; }  // the first solve's
  int count() const { return shared() + 2 * uvs; }
};
constexpr int kMostChannels = 9, kUvAt = 7;

// Mesh m's values at vertex v: the first solve's channels from out[0], UVs at out[kUvAt].
void values_at(const Mesh& m, const Channels& ch, Index v, double* out) {
  int at = 0;
  if (ch.normals)
    for (int d = 0; d < 3; ++d) out[at++] = m.attributes.normals(v, d);
  if (ch.colours)
    for (int d = 0; d < 4; ++d) out[at++] = m.attributes.colours(v, d);
  if (ch.uvs)
    for (int d = 0; d < 2; ++d) out[kUvAt + d] = m.attributes.uvs(v, d);
}

std::array<Vec, 3> corners(const Mesh& m, Index f) {
  return {m.positions.row(m.triangles(f, 0)).transpose(), m.positions.row(m.triangles(f, 1)).transpose(),
          m.positions.row(m.triangles(f, 2)).transpose()};
}

// Mesh m's values at point p of face f, interpolated, laid out as values_at() lays them out.
void values_on(const Mesh& m, const Channels& ch, Index f, const Vec& p, double* out) {
  const Vec w = detail::face_weights(m, f, p);
  if (ch.normals) Eigen::Vector3d::Map(out) = detail::interpolate(m, f, w, m.attributes.normals);
  if (ch.colours) Eigen::Vector4d::Map(out + 3 * ch.normals) = detail::interpolate(m, f, w, m.attributes.colours);
  if (ch.uvs) Eigen::Vector2d::Map(out + kUvAt) = detail::interpolate(m, f, w, m.attributes.uvs);
}

// One pair: the output face, the weights of its corners at the point, the value the output should have
// there, and how much the pair weighs (its share of area). For UVs also the input face, and whether the
// two points' UVs compare (detail::uv_comparable()).
struct Pair {
  Index face;
  Vec bary;
  std::array<double, kMostChannels> target;
  double weight;
  Index input_face = -1;
  bool uv_near = false;
};

// The n x n split of face c's centroids (n by area): where the output is sampled.
template <typename Visit>
void split_centroids(const std::array<Vec, 3>& c, int n, Visit visit) {
  for (int i = 0; i < n; ++i)
    for (int j = 0; i + j < n; ++j)
      for (int up = 0; up < (i + j + 1 < n ? 2 : 1); ++up) {
        const double a = (i + (up ? 2.0 : 1.0) / 3) / n, b = (j + (up ? 2.0 : 1.0) / 3) / n;
        const Vec bary(1 - a - b, a, b);
        visit(bary, bary[0] * c[0] + bary[1] * c[1] + bary[2] * c[2]);
      }
}

// Whether every row of m is the first (a constant carries through the collapses as it is).
template <typename Matrix>
bool constant(const Matrix& m) {
  for (Eigen::Index r = 1; r < m.rows(); ++r)
    if (m.row(r) != m.row(0)) return false;
  return true;
}

// What the two meshes share that the options ask to fit (a constant attribute of the input has nothing to fit).
Channels channels(const Mesh& input, const Mesh& simplified, const AttributeFitOptions& options) {
  Channels ch;
  ch.normals = options.normals && input.has_normals() && simplified.has_normals() && !constant(input.attributes.normals);
  ch.colours = options.colours && input.has_colours() && simplified.has_colours() && !constant(input.attributes.colours);
  ch.uvs = options.uvs && input.has_uvs() && simplified.has_uvs() && !constant(input.attributes.uvs);
  return ch;
}

bool fits_anything(const Mesh& input, const Mesh& simplified, const AttributeFitOptions& options) {
  return channels(input, simplified, options).count() > 0;
}

// The output's vertices on a UV seam (other UVs at the same point), and for each the input's UVs at its
// place on the input's seam: the nearest point to it on a seam edge of the input faces around the input
// face nearest it. There each takes the UVs of the face on that edge, in a chart partnered with its own,
// whose UVs lie nearest those it has (the side of the seam it is on, also where a chart meets itself),
// interpolated along the edge alone. Twins across a seam thus take the UVs the input has at one point,
// each in its own piece of the atlas, and go on meeting exactly as the input's do. A seam vertex with no
// such edge and face within its faces' UV reach keeps its UVs.
struct SeamUvs {
  std::vector<char> on_seam;  // per output vertex
  Eigen::MatrixXd uv;         // per output vertex (rows of the others unused)
};

SeamUvs seam_uvs(const Mesh& input, const detail::AabbTree& input_tree, const std::vector<Index>& input_charts,
                 const Mesh& out, const std::vector<Index>& output_charts, const detail::ChartPartners& charts) {
  const Index n = out.num_vertices();
  SeamUvs seam{std::vector<char>(static_cast<std::size_t>(n), 0), out.attributes.uvs.cast<double>()};
  const Eigen::VectorX<Index> point = position_classes(out);
  std::vector<Index> first_at(static_cast<std::size_t>(point.size() ? point.maxCoeff() + 1 : 0), -1);
  std::vector<char> seam_point(first_at.size(), 0);
  for (Index v = 0; v < n; ++v) {
    Index& first = first_at[std::size_t(point[v])];
    if (first < 0) first = v;
    else if (out.attributes.uvs.row(v) != out.attributes.uvs.row(first)) seam_point[std::size_t(point[v])] = 1;
  }
  std::vector<Index> chart_of(static_cast<std::size_t>(n), -1);  // each output vertex's chart (a wedge lies in one)
  std::vector<double> reach2(static_cast<std::size_t>(n), 0.0);   // its faces' longest UV side, squared
  for (Index f = 0; f < out.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      const std::size_t v = std::size_t(out.triangles(f, k));
      chart_of[v] = output_charts[std::size_t(f)];
      reach2[v] = std::max(reach2[v], detail::longest_uv_side2(out, f));
    }
  // The input's faces around each of its points (by position).
  const Eigen::VectorX<Index> at = position_classes(input);
  const std::size_t input_points = static_cast<std::size_t>(at.size() ? at.maxCoeff() + 1 : 0);
  std::vector<Index> start(input_points + 1, 0), faces_at;
  for (Index f = 0; f < input.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) ++start[std::size_t(at[input.triangles(f, k)]) + 1];
  for (std::size_t i = 0; i < input_points; ++i) start[i + 1] += start[i];
  faces_at.resize(std::size_t(start.back()));
  std::vector<Index> fill(start.begin(), start.end() - 1);
  for (Index f = 0; f < input.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) faces_at[std::size_t(fill[std::size_t(at[input.triangles(f, k)])]++)] = f;
  auto faces_around = [&](Index point_class) {
    return std::span<const Index>(faces_at.data() + start[std::size_t(point_class)], faces_at.data() + start[std::size_t(point_class) + 1]);
  };
  // Face f's corner at point class c (-1 if none), and its UVs there.
  auto corner_at = [&](Index f, Index c) {
    for (int k = 0; k < 3; ++k)
      if (at[input.triangles(f, k)] == c) return input.triangles(f, k);
    return Index(-1);
  };
  auto uv_of = [&](Index vertex) { return Eigen::Vector2d(input.attributes.uvs.row(vertex).transpose().cast<double>()); };

  for (Index v = 0; v < n; ++v) {
    if (!seam_point[std::size_t(point[v])] || chart_of[std::size_t(v)] < 0) continue;
    seam.on_seam[std::size_t(v)] = 1;
    const Vec p = out.positions.row(v).transpose();
    const Index near = input_tree.closest(p).face;
    // The nearest point on a seam edge (two faces on it with other UVs at an end) of the faces around.
    double best_d2 = INFINITY, t = 0;
    Index edge_a = -1, edge_b = -1;
    for (int k = 0; k < 3; ++k)
      for (Index f : faces_around(at[input.triangles(near, k)]))
        for (int e = 0; e < 3; ++e) {
          const Index a = input.triangles(f, e), b = input.triangles(f, (e + 1) % 3), ca = at[a], cb = at[b];
          bool on_seam = false;
          for (Index g : faces_around(ca))
            if (g != f)
              if (const Index gb = corner_at(g, cb); gb >= 0) on_seam |= uv_of(corner_at(g, ca)) != uv_of(a) || uv_of(gb) != uv_of(b);
          if (!on_seam) continue;
          const Vec pa = input.positions.row(a).transpose(), pb = input.positions.row(b).transpose();
          const double s = detail::segment_parameter(p, pa, pb), d2 = (pa + s * (pb - pa) - p).squaredNorm();
          if (d2 < best_d2) best_d2 = d2, t = s, edge_a = ca, edge_b = cb;
        }
    if (edge_a < 0) continue;
    // That point in each face on the edge, in a partner chart: the UVs nearest this vertex's own.
    const Eigen::Vector2d own = out.attributes.uvs.row(v).transpose().cast<double>();
    double best = reach2[std::size_t(v)];
    for (Index f : faces_around(edge_a)) {
      const Index fb = corner_at(f, edge_b);
      if (fb < 0 || !charts.partners(chart_of[std::size_t(v)], input_charts[std::size_t(f)])) continue;
      const Eigen::Vector2d uv = (1 - t) * uv_of(corner_at(f, edge_a)) + t * uv_of(fb);
      if ((uv - own).squaredNorm() >= best) continue;
      best = (uv - own).squaredNorm();
      seam.uv.row(v) = uv.transpose();
    }
  }
  return seam;
}

}  // namespace

namespace detail {

AttributeFitReport fit_attributes_to_input(const Mesh& input, const AabbTree& input_tree, Mesh& simplified,
                                           const AttributeFitOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  AttributeFitReport report;
  const Channels ch = channels(input, simplified, options);
  const Index n = simplified.num_vertices();
  if (ch.count() == 0 || simplified.num_faces() == 0 || input.num_faces() == 0) return report;

  // Samples on the output: about samples_per_face per face on average, more on larger faces.
  std::vector<double> area(static_cast<std::size_t>(simplified.num_faces()));
  double total_area = 0;
  for (Index f = 0; f < simplified.num_faces(); ++f) {
    const auto c = corners(simplified, f);
    total_area += area[f] = triangle_area(c[0], c[1], c[2]);
  }
  const double per_area = total_area > 0 ? options.samples_per_face * simplified.num_faces() / total_area : 0.0;
  std::vector<int> split(area.size());
  std::vector<std::size_t> first(area.size() + 1, 0);
  for (std::size_t f = 0; f < area.size(); ++f) {
    split[f] = std::clamp(static_cast<int>(std::ceil(std::sqrt(area[f] * per_area))), 1, 64);
    first[f + 1] = first[f] + static_cast<std::size_t>(split[f]) * static_cast<std::size_t>(split[f]);
  }
  // The input gives every stride-th face's centroid, at least four times as many points as the output
  // (as many: the human at 1 %, shading error 21.45 degrees against 20.94 with every face).
  const std::size_t out_samples = first.back(), input_faces = static_cast<std::size_t>(input.num_faces());
  const std::size_t stride = std::max<std::size_t>(1, input_faces / (4 * out_samples));
  const std::size_t in_samples = (input_faces + stride - 1) / stride;
  std::vector<Pair> pairs(out_samples + in_samples);

  // Output -> input: the input's value at the closest point.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, area.size(), 64), [&](const tbb::blocked_range<std::size_t>& r) {
    Index hint = -1;
    for (std::size_t f = r.begin(); f < r.end(); ++f) {
      std::size_t at = first[f];
      const double weight = area[f] / double(split[f] * split[f]);
      split_centroids(corners(simplified, Index(f)), split[f], [&](const Vec& bary, const Vec& p) {
        const auto hit = input_tree.closest(p, hint);
        hint = hit.face;
        Pair& pair = pairs[at++];
        pair = {Index(f), bary, {}, weight, hit.face};
        values_on(input, ch, hit.face, hit.point, pair.target.data());
        if (ch.uvs)
          pair.uv_near = detail::uv_comparable(simplified, Index(f), input, hit.face,
                                               detail::interpolate(simplified, Index(f), bary, simplified.attributes.uvs));
      });
    }
  });
  // Input -> output: each input face's centroid and its value there, at the output's closest point.
  const AabbTree output_tree(simplified);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, in_samples, 256), [&](const tbb::blocked_range<std::size_t>& r) {
    Index hint = -1;
    for (std::size_t i = r.begin(); i < r.end(); ++i) {
      const Index g = static_cast<Index>(i * stride);
      const auto c = corners(input, g);
      const Vec centroid = (c[0] + c[1] + c[2]) / 3.0;
      const auto hit = output_tree.closest(centroid, hint);
      hint = hit.face;
      Pair& pair = pairs[out_samples + i];
      pair = {hit.face, face_weights(simplified, hit.face, hit.point), {}, double(stride) * triangle_area(c[0], c[1], c[2]), g};
      values_on(input, ch, g, centroid, pair.target.data());
      if (ch.uvs) pair.uv_near = detail::uv_comparable(input, g, simplified, hit.face, Eigen::Vector2d::Map(pair.target.data() + kUvAt));
    }
  });

  // UVs: the pairs within a chart (the output's charts matched to the input's by vote, both ways at once).
  // A vertex on a UV seam is not fitted: each side's fit would pull its twins across the seam apart.
  // It takes the input's UVs at its place instead (seam_uvs()), and the fit holds it there.
  std::vector<char> uv_pair;
  SeamUvs seam;
  if (ch.uvs) {
    const std::vector<Index> output_charts = detail::uv_charts(simplified), input_charts = detail::uv_charts(input);
    detail::ChartPartners charts;
    for (const Pair& p : pairs) charts.vote(output_charts[p.face], input_charts[p.input_face], p.weight);
    charts.settle();
    uv_pair.resize(pairs.size());
    for (std::size_t i = 0; i < pairs.size(); ++i)
      uv_pair[i] = pairs[i].uv_near && charts.partners(output_charts[pairs[i].face], input_charts[pairs[i].input_face]);
    seam = seam_uvs(input, input_tree, input_charts, simplified, output_charts, charts);
  }

  double present[kMostChannels];
  // One least-squares solve over the pairs `counts` admits, for the `dims` channels from `first_channel`.
  // Normal equations: each face's part summed over its pairs in sample order (a triplet per pair came
  // to 9 per pair, 144 MB on a million-face input), then the faces' parts in face order. A faint pull
  // towards each vertex's present value keeps one that no pair sees (a sliver's corner) where it is;
  // a strong one holds the vertices `held` marks (empty: none) at `held_values`' rows.
  auto solve = [&](auto counts, int first_channel, int dims, const std::vector<char>& held,
                   const Eigen::MatrixXd& held_values) -> std::optional<Eigen::MatrixXd> {
    struct FaceTerms {
      Eigen::Matrix3d bb = Eigen::Matrix3d::Zero();                                  // sum of w b b^T
      Eigen::Matrix<double, 3, kMostChannels> bt = Eigen::Matrix<double, 3, kMostChannels>::Zero();  // sum of w b target^T
    };
    std::vector<FaceTerms> terms(area.size());
    for (std::size_t i = 0; i < pairs.size(); ++i) {
      const Pair& p = pairs[i];
      if (!(p.weight > 0) || !counts(i)) continue;
      FaceTerms& t = terms[std::size_t(p.face)];
      t.bb += p.weight * p.bary * p.bary.transpose();
      t.bt += p.weight * p.bary * Eigen::Map<const Eigen::Matrix<double, 1, kMostChannels>>(p.target.data());
    }
    std::vector<Eigen::Triplet<double>> entries;
    entries.reserve(9 * terms.size() + std::size_t(n));
    Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n, dims);
    double diagonal = 0;
    for (std::size_t f = 0; f < terms.size(); ++f)
      for (int j = 0; j < 3; ++j) {
        const Index vj = simplified.triangles(Index(f), j);
        for (int k = 0; k < 3; ++k) entries.emplace_back(vj, simplified.triangles(Index(f), k), terms[f].bb(j, k));
        diagonal += terms[f].bb(j, j);
        rhs.row(vj) += terms[f].bt.row(j).segment(first_channel, dims);
      }
    const double pull = std::max(1e-6 * diagonal / double(n), std::numeric_limits<double>::min());
    for (Index v = 0; v < n; ++v) {
      if (!held.empty() && held[std::size_t(v)]) {
        entries.emplace_back(v, v, 1e9 * pull);
        rhs.row(v) += 1e9 * pull * held_values.row(v);
        continue;
      }
      entries.emplace_back(v, v, pull);
      values_at(simplified, ch, v, present);
      for (int d = 0; d < dims; ++d) rhs(v, d) += pull * present[first_channel + d];
    }
    Eigen::SparseMatrix<double> system(n, n);
    system.setFromTriplets(entries.begin(), entries.end());
    const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(system);
    if (solver.info() != Eigen::Success) return std::nullopt;
    Eigen::MatrixXd solved = solver.solve(rhs);
    if (solver.info() != Eigen::Success || !solved.allFinite()) return std::nullopt;
    return solved;
  };

  Channels done;
  if (ch.shared() > 0)
    if (const auto solved = solve([](std::size_t) { return true; }, 0, ch.shared(), {}, {})) {
      for (Index v = 0; v < n; ++v) {
        int at = 0;
        if (ch.normals) {
          const Vec normal = solved->row(v).segment<3>(0).transpose();
          // (A value that cancels out keeps the present normal: there is no direction to give it.)
          if (normal.norm() > 1e-12) simplified.attributes.normals.row(v) = normal.normalized().transpose();
          at = 3;
        }
        if (ch.colours)
          for (int d = 0; d < 4; ++d)
            simplified.attributes.colours(v, d) = static_cast<float>(std::clamp((*solved)(v, at + d), 0.0, 1.0));
      }
      done.normals = ch.normals, done.colours = ch.colours;
    }
  if (ch.uvs)
    if (const auto solved = solve([&](std::size_t i) { return uv_pair[i] != 0; }, kUvAt, 2, seam.on_seam, seam.uv)) {
      for (Index v = 0; v < n; ++v) {
        const auto& uv = seam.on_seam[std::size_t(v)] ? seam.uv : *solved;
        for (int d = 0; d < 2; ++d) simplified.attributes.uvs(v, d) = uv(v, d);
      }
      done.uvs = true;
    }
  if (done.count() == 0) return report;
  report.normals = done.normals;
  report.colours = done.colours;
  report.uvs = done.uvs;
  report.samples = static_cast<long long>(pairs.size());
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

std::optional<AttributeFitReport> fit_simplified_attributes(const Mesh& input, const AabbTree* input_tree, Mesh& simplified,
                                                            const SimplifyOptions& options) {
  const AttributeFitOptions fit{.normals = !options.recompute_normals};
  if (!options.fit_attributes || options.record_collapses || !fits_anything(input, simplified, fit)) return std::nullopt;
  if (input_tree) return fit_attributes_to_input(input, *input_tree, simplified, fit);
  return fit_attributes_to_input(input, AabbTree(input), simplified, fit);
}

}  // namespace detail

AttributeFitReport fit_attributes_to_input(const Mesh& input, Mesh& simplified, const AttributeFitOptions& options) {
  if (!(options.samples_per_face > 0))
    throw Error(fmt::format("attribute fit: samples per face must be positive, got {}", options.samples_per_face));
  if (!fits_anything(input, simplified, options)) return {};
  return detail::fit_attributes_to_input(input, detail::AabbTree(input), simplified, options);
}

}  // namespace lodkit
