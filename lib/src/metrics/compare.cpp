#include <lodkit/error.h>
#include <lodkit/metrics.h>

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <numbers>
#include <tbb/parallel_for.h>
#include <vector>

#include "metrics/aabb_tree.h"

namespace lodkit {
namespace {

struct Sample {
  Eigen::Vector3d point;
  Index face;     // face of the sampled mesh the point lies on
  double weight;  // area represented (0 for vertex and edge samples: they count for the maximum only)
};

Eigen::Vector3d corner(const Mesh& m, Index f, int k) { return m.positions.row(m.triangles(f, k)); }

Eigen::Vector3d face_normal(const Mesh& m, Index f) {
  const Eigen::Vector3d n = (corner(m, f, 1) - corner(m, f, 0)).cross(corner(m, f, 2) - corner(m, f, 0));
  const double len = n.norm();
  return len > 0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
}

// k stratified points inside face f: the R2 sequence folded into the triangle.
void sample_face(const Mesh& m, Index f, long long k, double weight, std::vector<Sample>& out) {
  const Eigen::Vector3d a = corner(m, f, 0), b = corner(m, f, 1), c = corner(m, f, 2);
  constexpr double g1 = 0.7548776662466927, g2 = 0.5698402909980532;  // R2 (plastic number)
  for (long long j = 0; j < k; ++j) {
    double u = std::fmod(0.5 + g1 * static_cast<double>(j + 1), 1.0);
    double v = std::fmod(0.5 + g2 * static_cast<double>(j + 1), 1.0);
    if (u + v > 1) u = 1 - u, v = 1 - v;
    out.push_back({a + u * (b - a) + v * (c - a), f, weight / static_cast<double>(k)});
  }
}

std::vector<Sample> sample_surface(const Mesh& m, long long face_samples) {
  std::vector<Sample> out;
  const Index nf = m.num_faces();
  std::vector<double> area(static_cast<std::size_t>(nf));
  double total = 0;
  for (Index f = 0; f < nf; ++f) {
    area[f] = 0.5 * (corner(m, f, 1) - corner(m, f, 0)).cross(corner(m, f, 2) - corner(m, f, 0)).norm();
    total += area[f];
  }
  out.reserve(static_cast<std::size_t>(face_samples + 4 * nf));
  // Vertices and edge points: where maxima of piecewise-linear distances often sit.
  for (Index f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d p = corner(m, f, k), q = corner(m, f, (k + 1) % 3);
      out.push_back({p, f, 0.0});
      out.push_back({0.5 * (p + q), f, 0.0});
    }
  // Face interiors, allotted by area with a running remainder so the total is exact.
  double carry = 0;
  for (Index f = 0; f < nf; ++f) {
    const double share = total > 0 ? face_samples * area[f] / total : double(face_samples) / nf;
    carry += share;
    const auto k = static_cast<long long>(std::floor(carry));
    carry -= static_cast<double>(k);
    sample_face(m, f, std::max<long long>(k, 1), area[f], out);
  }
  return out;
}

struct Measured {
  double distance, angle_deg;
};

std::vector<Measured> measure(const std::vector<Sample>& samples, const Mesh& from, const Mesh& to,
                              const detail::AabbTree& tree) {
  std::vector<Measured> result(samples.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, samples.size(), 1024), [&](const auto& range) {
    Index hint = -1;
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      const auto hit = tree.closest(samples[i].point, hint);
      hint = hit.face;
      const Eigen::Vector3d n0 = face_normal(from, samples[i].face), n1 = face_normal(to, hit.face);
      // atan2 keeps small angles accurate where acos(dot) would lose them.
      result[i] = {std::sqrt(hit.squared_distance), std::atan2(n0.cross(n1).norm(), n0.dot(n1)) * 180.0 / std::numbers::pi};
    }
  });
  return result;
}

DirectedDistance directed(const Mesh& from, const Mesh& to, long long face_samples, const CompareOptions& o) {
  const detail::AabbTree tree(to);
  std::vector<Sample> samples = sample_surface(from, face_samples);
  std::vector<Measured> measured = measure(samples, from, to, tree);

  DirectedDistance d;
  double weight = 0, sum = 0, sum2 = 0, angle_sum = 0;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    d.max = std::max(d.max, measured[i].distance);
    const double w = samples[i].weight;
    // Normals are compared at face samples only: at a vertex or on an edge the nearest face is ambiguous.
    if (w > 0) d.normal_deviation_max_deg = std::max(d.normal_deviation_max_deg, measured[i].angle_deg);
    weight += w;
    sum += w * measured[i].distance;
    sum2 += w * measured[i].distance * measured[i].distance;
    angle_sum += w * measured[i].angle_deg;
  }
  if (weight > 0) {
    d.mean = sum / weight;
    d.rms = std::sqrt(sum2 / weight);
    d.normal_deviation_mean_deg = angle_sum / weight;
  }
  d.samples = static_cast<long long>(samples.size());

  // Refine around the worst samples: resample their faces 256x more densely until the maximum settles.
  for (int round = 0; round < o.refine_rounds; ++round) {
    std::vector<std::size_t> order(samples.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    const std::size_t top = std::min<std::size_t>(order.size(), 64);
    std::partial_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(top), order.end(),
                      [&](std::size_t a, std::size_t b) {
                        return measured[a].distance != measured[b].distance ? measured[a].distance > measured[b].distance
                                                                             : a < b;
                      });
    std::vector<Index> faces;
    for (std::size_t i = 0; i < top; ++i) faces.push_back(samples[order[i]].face);
    std::sort(faces.begin(), faces.end());
    faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
    std::vector<Sample> dense;
    for (Index f : faces) sample_face(from, f, 256, 0.0, dense);
    const std::vector<Measured> dm = measure(dense, from, to, tree);
    double new_max = d.max;
    for (const Measured& m : dm) new_max = std::max(new_max, m.distance);
    d.samples += static_cast<long long>(dense.size());
    const bool settled = new_max <= d.max * (1 + o.refine_tolerance);
    d.max = new_max;
    samples = std::move(dense);
    measured = dm;
    if (settled) break;
  }
  return d;
}

}  // namespace

Comparison compare(const Mesh& a, const Mesh& b, const CompareOptions& options) {
  if (a.num_faces() == 0) throw Error("compare: the first mesh has no faces");
  if (b.num_faces() == 0) throw Error("compare: the second mesh has no faces");
  const long long samples =
      options.samples.value_or(std::max<long long>(10'000, 10LL * std::max(a.num_faces(), b.num_faces())));
  if (samples <= 0) throw Error(fmt::format("compare: samples must be positive, got {}", samples));
  Comparison c;
  c.a_to_b = directed(a, b, samples, options);
  c.b_to_a = directed(b, a, samples, options);
  c.hausdorff = std::max(c.a_to_b.max, c.b_to_a.max);
  c.mean = 0.5 * (c.a_to_b.mean + c.b_to_a.mean);
  c.rms = std::sqrt(0.5 * (c.a_to_b.rms * c.a_to_b.rms + c.b_to_a.rms * c.b_to_a.rms));
  const auto box = bounding_box(a);
  c.diagonal = box.isEmpty() ? 0.0 : box.diagonal().norm();
  return c;
}

Index count_flipped_faces(const Mesh& reference, const Mesh& mesh) {
  if (reference.num_faces() == 0) return 0;
  const detail::AabbTree tree(reference);
  Index flipped = 0;
  for (Index f = 0; f < mesh.num_faces(); ++f) {
    const Eigen::Vector3d a = corner(mesh, f, 0), b = corner(mesh, f, 1), c = corner(mesh, f, 2);
    const auto hit = tree.closest((a + b + c) / 3.0);
    const Eigen::Vector3d p = corner(reference, hit.face, 0), q = corner(reference, hit.face, 1),
                          r = corner(reference, hit.face, 2);
    if ((b - a).cross(c - a).dot((q - p).cross(r - p)) < 0) ++flipped;
  }
  return flipped;
}

}  // namespace lodkit
