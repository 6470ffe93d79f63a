// HausdorffChecker: whether two surfaces lie within a distance of each other, decided by the branch and
// bound of max_distance_bound.cpp, with no sampling: a yes is a proof, a no names a point farther.
#include <lodkit/error.h>
#include <lodkit/metrics.h>

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "metrics/aabb_tree.h"
#include "metrics/max_distance_bound.h"

namespace lodkit {
namespace {

// One direction: every vertex of `from` that a face uses is measured (its nearest face of `to` starts
// the bounds of its triangles), then the triangles are split only as far as the decision needs.
HausdorffCheck directed_check(const Mesh& from, const Mesh& to, const detail::AabbTree& tree,
                              std::span<const std::array<Index, 3>> to_neighbours, double distance,
                              long long max_splits) {
  const Index n = from.num_vertices();
  std::vector<char> used(static_cast<std::size_t>(n), 0);
  for (Index f = 0; f < from.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) used[from.triangles(f, k)] = 1;
  std::vector<Index> corner_face(static_cast<std::size_t>(n), -1);
  std::vector<double> d2(static_cast<std::size_t>(n), 0.0);
  tbb::parallel_for(tbb::blocked_range<Index>(0, n, 1024), [&](const tbb::blocked_range<Index>& r) {
    for (Index v = r.begin(); v != r.end(); ++v) {
      if (!used[v]) continue;
      const auto hit = tree.closest(from.positions.row(v).transpose());
      corner_face[v] = hit.face;
      d2[v] = hit.squared_distance;
    }
  });
  // The first of the farthest used vertices, for the same answer on any thread count.
  const Index first_used = static_cast<Index>(std::find(used.begin(), used.end(), 1) - used.begin());
  Index farthest = first_used;
  for (Index v = first_used + 1; v < n; ++v)
    if (used[v] && d2[v] > d2[farthest]) farthest = v;
  HausdorffCheck c;
  const double attained = std::sqrt(d2[farthest]);  // (a mesh with faces has a used vertex)
  const Eigen::Vector3d at = from.positions.row(farthest).transpose();
  const detail::MaxDistanceBound b = detail::bound_max_distance(
      from, to, tree, to_neighbours, corner_face, attained, at, {.max_splits = max_splits, .at_most = distance});
  c.attained = b.attained;
  c.attained_at = b.attained_at;
  c.bound = b.bound;
  c.within = b.bound <= distance;
  c.queries = b.queries + static_cast<long long>(std::count(used.begin(), used.end(), 1));
  return c;
}

}  // namespace

struct HausdorffChecker::State {
  const Mesh& reference;
  long long max_splits;
  detail::AabbTree tree;
  std::vector<std::array<Index, 3>> neighbours;  // detail::face_neighbours(reference)
};

HausdorffChecker::HausdorffChecker(const Mesh& reference, long long max_splits) {
  validate(reference, "Hausdorff check: the reference mesh");
  if (reference.num_faces() == 0) throw Error("Hausdorff check: the reference mesh has no faces");
  state_ = std::make_unique<State>(
      State{reference, max_splits, detail::AabbTree(reference), detail::face_neighbours(reference)});
}

HausdorffChecker::~HausdorffChecker() = default;

HausdorffCheck HausdorffChecker::check(const Mesh& other, double distance) const {
  validate(other, "Hausdorff check: the other mesh");
  if (other.num_faces() == 0) throw Error("Hausdorff check: the other mesh has no faces");
  if (!std::isfinite(distance) || distance < 0)
    throw Error(fmt::format("Hausdorff check: the distance must be finite and not negative, got {}", distance));
  const State& s = *state_;
  // The other surface first: usually the smaller, and where a simplification strays, it is usually
  // its own surface that lies farthest, so a "no" often comes before the reference is touched.
  const HausdorffCheck to_reference = directed_check(other, s.reference, s.tree, s.neighbours, distance, s.max_splits);
  if (!to_reference.within) return to_reference;
  const detail::AabbTree other_tree(other);
  const HausdorffCheck to_other =
      directed_check(s.reference, other, other_tree, detail::face_neighbours(other), distance, s.max_splits);
  HausdorffCheck c = to_other.attained > to_reference.attained ? to_other : to_reference;
  c.within = to_other.within;
  c.bound = std::max(to_reference.bound, to_other.bound);
  c.queries = to_reference.queries + to_other.queries;
  return c;
}

}  // namespace lodkit
