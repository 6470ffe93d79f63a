#include <lodkit/error.h>
#include <lodkit/metrics.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fmt/format.h>
#include <limits>
#include <numbers>
#include <span>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <vector>

#include "core/geometry.h"
#include "core/huge_pages.h"
#include "core/interpolate.h"
#include "core/uv_charts.h"
#include "metrics/aabb_tree.h"
#include "metrics/max_distance_bound.h"

namespace lodkit {
namespace {

// A surface's samples. Vertex and edge-midpoint samples repeat in every face around them; each
// distinct point is measured once and its distance shared by the samples at it (a third of the
// queries on a closed mesh). Samples keep their faces, so refinement sees every face around a worst
// point, as when each was measured on its own.
struct SampleSet {
  struct Point {
    Eigen::Vector3d position;
    Index face;  // the face of the sample that introduced the point: its normal is compared
  };
  struct Sample {
    std::uint32_t point;
    Index face;     // face of the sampled mesh the sample lies on
    double weight;  // area represented (0 for vertex and edge samples: they count for the maximum only)
  };
  std::vector<Point> points;
  std::vector<Sample> samples;
  std::size_t first_face_point = 0;  // points before it are vertices and edge midpoints
  std::vector<std::uint32_t> vertex_point;  // each vertex's point (kNone for a vertex no face uses)
};

Eigen::Vector3d corner(const Mesh& m, Index f, int k) { return m.positions.row(m.triangles(f, k)); }

Eigen::Vector3d face_normal(const Mesh& m, Index f) {
  const Eigen::Vector3d n = (corner(m, f, 1) - corner(m, f, 0)).cross(corner(m, f, 2) - corner(m, f, 0));
  const double len = n.norm();
  return len > 0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
}

// k stratified points inside face f, each a sample of its own, into out's points from `point` on and
// its samples from `sample` on: the R2 sequence folded into the triangle.
void sample_face(const Mesh& m, Index f, std::size_t point, std::size_t sample, std::size_t k, double weight,
                 SampleSet& out) {
  const Eigen::Vector3d a = corner(m, f, 0), b = corner(m, f, 1), c = corner(m, f, 2);
  constexpr double g1 = 0.7548776662466927, g2 = 0.5698402909980532;  // R2 (plastic number)
  for (std::size_t j = 0; j < k; ++j) {
    double u = std::fmod(0.5 + g1 * static_cast<double>(j + 1), 1.0);
    double v = std::fmod(0.5 + g2 * static_cast<double>(j + 1), 1.0);
    if (u + v > 1) u = 1 - u, v = 1 - v;
    out.points[point + j] = {a + u * (b - a) + v * (c - a), f};
    out.samples[sample + j] = {static_cast<std::uint32_t>(point + j), f, weight / static_cast<double>(k)};
  }
}

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

// Every face's corners and edge midpoints, in face order, each distinct vertex or edge measured once.
void sample_vertices_and_edges(const Mesh& m, SampleSet& out) {
  const Index nv = m.num_vertices(), nf = m.num_faces();
  std::vector<std::uint32_t>& vertex_point = out.vertex_point;
  detail::assign_huge(vertex_point, static_cast<std::size_t>(nv), kNone);
  // Edges grouped by their lower vertex: slots [first[lo], first[lo + 1]), filled[lo] of them in use.
  std::vector<std::uint32_t> first, filled;
  detail::assign_huge(first, static_cast<std::size_t>(nv) + 1, std::uint32_t{0});
  detail::assign_huge(filled, static_cast<std::size_t>(nv), std::uint32_t{0});
  for (Index f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) ++first[std::min(m.triangles(f, k), m.triangles(f, (k + 1) % 3)) + 1];
  for (Index v = 0; v < nv; ++v) first[v + 1] += first[v];
  auto edge_point = detail::huge_vector<std::pair<Index, std::uint32_t>>(first.back());  // (upper vertex, point)
  for (Index f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      const Index a = m.triangles(f, k), b = m.triangles(f, (k + 1) % 3);
      if (vertex_point[a] == kNone) {
        vertex_point[a] = static_cast<std::uint32_t>(out.points.size());
        out.points.push_back({corner(m, f, k), f});
      }
      out.samples.push_back({vertex_point[a], f, 0.0});
      const Index lo = std::min(a, b), hi = std::max(a, b);
      auto* const begin = &edge_point[first[lo]];
      auto* const end = begin + filled[lo];
      auto* const found = std::find_if(begin, end, [hi](const auto& e) { return e.first == hi; });
      if (found == end) {
        *end = {hi, static_cast<std::uint32_t>(out.points.size())};
        ++filled[lo];
        // 0.5 (p + q) is the same double whichever way round the edge is met.
        out.points.push_back({0.5 * (corner(m, f, k) + corner(m, f, (k + 1) % 3)), f});
      }
      out.samples.push_back({found == end ? end->second : found->second, f, 0.0});
    }
}

SampleSet sample_surface(const Mesh& m, long long face_samples) {
  const Index nf = m.num_faces();
  if (6 * static_cast<long long>(nf) + std::max<long long>(face_samples, nf) >= std::numeric_limits<std::uint32_t>::max())
    throw Error(fmt::format("compare: too many samples ({} faces, {} face samples)", nf, face_samples));
  auto area = detail::huge_vector<double>(static_cast<std::size_t>(nf));
  double total = 0;
  for (Index f = 0; f < nf; ++f) {
    area[f] = 0.5 * (corner(m, f, 1) - corner(m, f, 0)).cross(corner(m, f, 2) - corner(m, f, 0)).norm();
    total += area[f];
  }
  SampleSet out;
  detail::reserve_huge(out.samples, static_cast<std::size_t>(face_samples + 7 * nf));
  detail::reserve_huge(out.points, static_cast<std::size_t>(face_samples + 3 * nf));
  // Vertices and edge points: where maxima of piecewise-linear distances often sit.
  sample_vertices_and_edges(m, out);
  out.first_face_point = out.points.size();
  // Face interiors, allotted by area with a running remainder so the total is exact, each face's
  // after the faces before it; then placed side by side.
  auto first = detail::huge_vector<std::size_t>(static_cast<std::size_t>(nf) + 1);
  double carry = 0;
  for (Index f = 0; f < nf; ++f) {
    const double share = total > 0 ? face_samples * area[f] / total : double(face_samples) / nf;
    carry += share;
    const auto k = static_cast<long long>(std::floor(carry));
    carry -= static_cast<double>(k);
    first[f + 1] = first[f] + static_cast<std::size_t>(std::max<long long>(k, 1));
  }
  const std::size_t first_face_sample = out.samples.size();
  out.points.resize(out.first_face_point + first[nf]);
  out.samples.resize(first_face_sample + first[nf]);
  tbb::parallel_for(Index{0}, nf, [&](Index f) {
    sample_face(m, f, out.first_face_point + first[f], first_face_sample + first[f], first[f + 1] - first[f], area[f], out);
  });
  return out;
}

struct Measured {
  double distance, angle_deg;
  Index nearest;  // the face of the other mesh nearest the point
  double colour;  // the colour difference there (both meshes coloured), else 0
  double shading_deg;  // the angle between the shading normals there (both meshes with normals), else 0
  double uv;           // the distance between the UVs there (both meshes with UVs), else 0
  bool uv_near;        // its UV and its closest point's compare (detail::uv_comparable())
};

// The unit shading normal mesh m interpolates at weights w over face f (zero where the corners' cancel).
Eigen::Vector3d shading_normal_at(const Mesh& m, Index f, const Eigen::Vector3d& w) {
  const Eigen::Vector3d n = detail::interpolate(m, f, w, m.attributes.normals);
  const double length = n.norm();
  return length > 0 ? Eigen::Vector3d(n / length) : Eigen::Vector3d::Zero();
}

// The angle between two vectors in degrees (atan2 keeps small angles accurate where acos(dot) would
// lose them); 90 when either is zero.
double angle_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  if (a.isZero() || b.isZero()) return 90.0;
  return std::atan2(a.cross(b).norm(), a.dot(b)) * 180.0 / std::numbers::pi;
}

std::vector<Eigen::Vector3d> face_normals(const Mesh& m) {
  auto normals = detail::huge_vector<Eigen::Vector3d>(static_cast<std::size_t>(m.num_faces()));
  tbb::parallel_for(Index{0}, m.num_faces(), [&](Index f) { normals[f] = face_normal(m, f); });
  return normals;
}

// Each distinct point's distance to `to`, and at face samples (the only ones whose normals are compared)
// the angle between its face's normal and the normal of the face it is closest to.
std::vector<Measured> measure(const SampleSet& set, const Mesh& from, const Mesh& to, const detail::AabbTree& tree) {
  auto result = detail::huge_vector<Measured>(set.points.size());
  const std::vector<Eigen::Vector3d> from_normals = face_normals(from), to_normals = face_normals(to);
  const bool colours = from.has_colours() && to.has_colours();
  const bool normals = from.has_normals() && to.has_normals();
  const bool uvs = from.has_uvs() && to.has_uvs();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, set.points.size(), 1024), [&](const auto& range) {
    Index hint = -1;
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      const auto hit = tree.closest(set.points[i].position, hint);
      hint = hit.face;
      const SampleSet::Point& p = set.points[i];
      double colour = 0, shading = 0, uv = 0;
      bool uv_near = false;
      if (colours || normals || uvs) {
        // The point's weights on its face, and its nearest point's on the other mesh's face.
        const Eigen::Vector3d w0 = detail::face_weights(from, p.face, p.position), w1 = detail::face_weights(to, hit.face, hit.point);
        if (colours)
          colour = (detail::interpolate(from, p.face, w0, from.attributes.colours) - detail::interpolate(to, hit.face, w1, to.attributes.colours)).norm();
        if (normals) shading = angle_deg(shading_normal_at(from, p.face, w0), shading_normal_at(to, hit.face, w1));
        if (uvs) {
          const Eigen::Vector2d here = detail::interpolate(from, p.face, w0, from.attributes.uvs);
          uv = (here - detail::interpolate(to, hit.face, w1, to.attributes.uvs)).norm();
          uv_near = detail::uv_comparable(from, p.face, to, hit.face, here);
        }
      }
      // (A face without area has a zero normal, which counts 0 degrees here.)
      double angle = 0;
      if (i >= set.first_face_point) {
        const Eigen::Vector3d& n0 = from_normals[p.face];
        const Eigen::Vector3d& n1 = to_normals[hit.face];
        angle = std::atan2(n0.cross(n1).norm(), n0.dot(n1)) * 180.0 / std::numbers::pi;
      }
      result[i] = {std::sqrt(hit.squared_distance), angle, hit.face, colour, shading, uv, uv_near};
    }
  });
  return result;
}

// Texture coordinates compare within a chart only: across a UV seam the atlas jumps to another piece,
// and a point whose nearest point lies there has no UV distance to speak of. Which chart of `to`
// stands for which of `from` is found by vote: a pair of charts counts when most of one's face samples
// (by area) land on the other. A chart may also meet itself along a seam (a torus cut open once, UVs
// that wrap around): a point there counts only when its UV lies near the nearest face's UV triangle.
// Fills the direction's UV figures.
void measure_uvs(const SampleSet& sampled, const std::vector<Measured>& measured, std::span<const Index> from_charts,
                 std::span<const Index> to_charts, DirectedDistance& d) {
  detail::ChartPartners charts;
  for (const SampleSet::Sample& s : sampled.samples)
    if (s.weight > 0) charts.vote(from_charts[sampled.points[s.point].face], to_charts[measured[s.point].nearest], s.weight);
  charts.settle();
  double weight = 0, compared = 0, uv2 = 0, uv_max = 0;
  for (const SampleSet::Sample& s : sampled.samples) {
    const Measured& m = measured[s.point];
    weight += s.weight;
    if (!m.uv_near || !charts.partners(from_charts[sampled.points[s.point].face], to_charts[m.nearest])) continue;
    compared += s.weight;
    uv2 += s.weight * m.uv * m.uv;
    uv_max = std::max(uv_max, m.uv);
  }
  d.uv_rms = compared > 0 ? std::sqrt(uv2 / compared) : 0.0;
  d.uv_max = uv_max;
  d.uv_compared = weight > 0 ? compared / weight : 0.0;
}

DirectedDistance directed(const Mesh& from, const SampleSet& sampled, const Mesh& to, const detail::AabbTree& tree,
                          std::span<const std::array<Index, 3>> to_neighbours, std::span<const Index> from_charts,
                          std::span<const Index> to_charts, const CompareOptions& o) {
  const std::vector<Measured> measured = measure(sampled, from, to, tree);
  DirectedDistance d;
  if (from.has_uvs() && to.has_uvs()) measure_uvs(sampled, measured, from_charts, to_charts, d);
  double weight = 0, sum = 0, sum2 = 0, angle_sum = 0, colour2 = 0, colour_max = 0, shading2 = 0, shading_max = 0;
  std::uint32_t farthest = 0;
  for (const SampleSet::Sample& s : sampled.samples) {
    const Measured& m = measured[s.point];
    if (m.distance > d.max) d.max = m.distance, farthest = s.point;
    const double w = s.weight;
    // Normals are compared at face samples only: at a vertex or on an edge the nearest face is ambiguous.
    if (w > 0) d.normal_deviation_max_deg = std::max(d.normal_deviation_max_deg, m.angle_deg);
    weight += w;
    sum += w * m.distance;
    sum2 += w * m.distance * m.distance;
    angle_sum += w * m.angle_deg;
    colour2 += w * m.colour * m.colour;
    colour_max = std::max(colour_max, m.colour);
    shading2 += w * m.shading_deg * m.shading_deg;
    shading_max = std::max(shading_max, m.shading_deg);
  }
  if (weight > 0) {
    d.mean = sum / weight;
    d.rms = std::sqrt(sum2 / weight);
    d.normal_deviation_mean_deg = angle_sum / weight;
  }
  if (from.has_colours() && to.has_colours()) {
    d.colour_rms = weight > 0 ? std::sqrt(colour2 / weight) : 0.0;
    d.colour_max = colour_max;
  }
  if (from.has_normals() && to.has_normals()) {
    d.shading_rms_deg = weight > 0 ? std::sqrt(shading2 / weight) : 0.0;
    d.shading_max_deg = shading_max;
  }
  d.samples = static_cast<long long>(sampled.samples.size());

  // The maximum, bracketed: the samples' largest distance (vertices included) is only a lower bound of it.
  auto corner_face = detail::huge_vector<Index>(sampled.vertex_point.size(), -1);
  for (std::size_t v = 0; v < sampled.vertex_point.size(); ++v)
    if (const std::uint32_t p = sampled.vertex_point[v]; p != kNone) corner_face[v] = measured[p].nearest;
  const detail::MaxDistanceBound bound = detail::bound_max_distance(
      from, to, tree, to_neighbours, corner_face, d.max, sampled.points[farthest].position,
      {.tolerance = o.hausdorff_tolerance, .max_splits = o.max_splits});
  d.max = bound.attained;
  d.max_at = bound.attained_at;
  d.max_nearest = tree.closest(d.max_at).point;
  d.max_bound = bound.bound;
  d.max_queries = bound.queries;
  return d;
}

// Each sample holds about 100 bytes while it is measured (10 M: 1 GB): past this, a clear refusal
// rather than running out of memory part way.
constexpr long long kMostSamples = 150'000'000;

void check_options(const CompareOptions& o) {
  if (!(std::isfinite(o.hausdorff_tolerance) && o.hausdorff_tolerance >= 0))
    throw Error(fmt::format("compare: the Hausdorff tolerance must be finite and not negative, got {}", o.hausdorff_tolerance));
  if (o.max_splits < 0) throw Error(fmt::format("compare: the split limit must not be negative, got {}", o.max_splits));
}

void check_samples(long long samples) {
  if (samples <= 0) throw Error(fmt::format("compare: samples must be positive, got {}", samples));
  if (samples > kMostSamples)
    throw Error(fmt::format("compare: {} samples a direction would take about {:.0f} GB (about 100 bytes a sample); "
                            "at most {} (ask for fewer with --samples)",
                            samples, 1e-9 * 100.0 * static_cast<double>(samples), kMostSamples));
}

Comparison combine(const Mesh& a, DirectedDistance a_to_b, DirectedDistance b_to_a) {
  Comparison c;
  c.a_to_b = a_to_b;
  c.b_to_a = b_to_a;
  c.hausdorff = std::max(c.a_to_b.max, c.b_to_a.max);
  c.hausdorff_bound = std::max(c.a_to_b.max_bound, c.b_to_a.max_bound);
  c.mean = 0.5 * (c.a_to_b.mean + c.b_to_a.mean);
  c.rms = std::sqrt(0.5 * (c.a_to_b.rms * c.a_to_b.rms + c.b_to_a.rms * c.b_to_a.rms));
  if (c.a_to_b.colour_rms && c.b_to_a.colour_rms)
    c.colour_rms = std::sqrt(0.5 * (*c.a_to_b.colour_rms * *c.a_to_b.colour_rms + *c.b_to_a.colour_rms * *c.b_to_a.colour_rms));
  if (c.a_to_b.shading_rms_deg && c.b_to_a.shading_rms_deg)
    c.shading_rms_deg =
        std::sqrt(0.5 * (*c.a_to_b.shading_rms_deg * *c.a_to_b.shading_rms_deg + *c.b_to_a.shading_rms_deg * *c.b_to_a.shading_rms_deg));
  if (c.a_to_b.uv_rms && c.b_to_a.uv_rms)
    c.uv_rms = std::sqrt(0.5 * (*c.a_to_b.uv_rms * *c.a_to_b.uv_rms + *c.b_to_a.uv_rms * *c.b_to_a.uv_rms));
  const auto box = bounding_box(a);
  c.diagonal = box.isEmpty() ? 0.0 : box.diagonal().norm();
  return c;
}

}  // namespace

long long default_face_samples(Index faces) { return std::clamp<long long>(10LL * faces, 10'000, kMostSamples); }

struct CompareReference::State {
  const Mesh& mesh;
  long long face_samples;
  CompareOptions options;
  detail::AabbTree tree;
  SampleSet sampled;
  std::vector<std::array<Index, 3>> neighbours;  // detail::face_neighbours(mesh)
  std::vector<Index> charts;                     // detail::uv_charts(mesh), when it has UVs
};

// The UV charts of a mesh with UVs (none without: nothing to compare).
std::vector<Index> charts_of(const Mesh& m) { return m.has_uvs() ? detail::uv_charts(m) : std::vector<Index>{}; }

CompareReference::CompareReference(const Mesh& reference, long long face_samples, const CompareOptions& options) {
  validate(reference, "compare: the first mesh");
  if (reference.num_faces() == 0) throw Error("compare: the first mesh has no faces");
  check_options(options);
  check_samples(face_samples);
  state_ = std::make_unique<State>(State{reference, face_samples, options, detail::AabbTree(reference),
                                         sample_surface(reference, face_samples), detail::face_neighbours(reference),
                                         charts_of(reference)});
}

CompareReference::~CompareReference() = default;

Comparison CompareReference::compare(const Mesh& other, std::optional<long long> other_face_samples) const {
  validate(other, "compare: the second mesh");
  if (other.num_faces() == 0) throw Error("compare: the second mesh has no faces");
  const State& s = *state_;
  const long long other_samples = other_face_samples.value_or(s.face_samples);
  check_samples(other_samples);
  // Side by side: each direction's serial part (the other's tree, the other's samples) overlaps the
  // other's parallel queries.
  DirectedDistance to_other, to_reference;
  const std::vector<Index> other_charts = s.mesh.has_uvs() ? charts_of(other) : std::vector<Index>{};
  tbb::parallel_invoke(
      [&] {
        to_other = directed(s.mesh, s.sampled, other, detail::AabbTree(other), detail::face_neighbours(other), s.charts,
                            other_charts, s.options);
      },
      [&] {
        to_reference = directed(other, sample_surface(other, other_samples), s.mesh, s.tree, s.neighbours, other_charts,
                                s.charts, s.options);
      });
  return combine(s.mesh, to_other, to_reference);
}

Comparison compare(const Mesh& a, const Mesh& b, const CompareOptions& options) {
  validate(a, "compare: the first mesh");
  validate(b, "compare: the second mesh");
  if (a.num_faces() == 0) throw Error("compare: the first mesh has no faces");
  if (b.num_faces() == 0) throw Error("compare: the second mesh has no faces");
  check_options(options);
  const long long samples = options.samples.value_or(default_face_samples(std::max(a.num_faces(), b.num_faces())));
  check_samples(samples);
  // One direction at a time, so that only one surface's samples are held at once.
  const bool uvs = a.has_uvs() && b.has_uvs();
  const std::vector<Index> a_charts = uvs ? charts_of(a) : std::vector<Index>{}, b_charts = uvs ? charts_of(b) : std::vector<Index>{};
  const auto one_way = [&](const Mesh& from, std::span<const Index> from_charts, const Mesh& to, std::span<const Index> to_charts) {
    return directed(from, sample_surface(from, samples), to, detail::AabbTree(to), detail::face_neighbours(to), from_charts,
                    to_charts, options);
  };
  const DirectedDistance a_to_b = one_way(a, a_charts, b, b_charts);
  return combine(a, a_to_b, one_way(b, b_charts, a, a_charts));
}

Index count_flipped_faces(const Mesh& reference, const Mesh& mesh) {
  validate(reference, "flipped faces: the reference mesh");
  validate(mesh, "flipped faces: the mesh");
  if (reference.num_faces() == 0) return 0;
  const detail::AabbTree tree(reference);
  Index flipped = 0, hint = -1;
  for (Index f = 0; f < mesh.num_faces(); ++f) {
    const Eigen::Vector3d a = corner(mesh, f, 0), b = corner(mesh, f, 1), c = corner(mesh, f, 2);
    flipped += tree.facing_against_all_nearest((a + b + c) / 3.0, (b - a).cross(c - a), hint);
  }
  return flipped;
}

}  // namespace lodkit
