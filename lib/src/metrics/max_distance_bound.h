#pragma once
// The largest distance from one surface to another, bracketed by branch and bound: a value attained
// at a point of the surface (below) and a proof that no point lies farther (above).
#include <lodkit/mesh.h>

#include <Eigen/Core>
#include <array>
#include <optional>
#include <span>
#include <vector>

namespace lodkit::detail {

class AabbTree;

struct MaxDistanceOptions {
  /// Stop once the bound above is within this fraction of the value attained.
  double tolerance = 1e-3;
  /// Stop after this many triangle splits, the bound above then as far as it got.
  long long max_splits = 1'000'000;
  /// A decision instead of a value: whether the maximum is at most this. Pieces are split only until
  /// their bounds are at most it, and the search stops as soon as a point lies farther (then
  /// attained > at_most; `bound` is then still an upper bound, infinite if the given `attained` already
  /// decided it), so it can be far cheaper than bracketing the value; `tolerance` is unused.
  std::optional<double> at_most{};
};

struct MaxDistanceBound {
  double attained = 0;  ///< the distance of a point of `from`: a lower bound of the maximum
  Eigen::Vector3d attained_at = Eigen::Vector3d::Zero();  ///< that point
  double bound = 0;     ///< no point of `from` is farther from `to` than this
  long long splits = 0;
  long long queries = 0;  ///< closest-point queries made
};

/// Across each edge k (corners k, k + 1) of each face, the face on the other side; -1 where the edge has
/// not exactly two faces. Positions are welded, so seams of attributes do not part faces.
std::vector<std::array<Index, 3>> face_neighbours(const Mesh& mesh);

/// The maximum over `from`'s surface of the distance to `to` (whose tree is `tree`). `corner_face`:
/// for each vertex of `from`, the face of `to` nearest it (a vertex no face uses is ignored).
/// `attained`: a distance already measured at `attained_at`, a point of `from`, and no less than any
/// vertex's distance.
///
/// Why it is a bound: the distance to any single triangle F is a convex function of the point, so over
/// a triangle T it peaks at a corner; and the distance to `to` is at most the distance to F. So
/// max over T ≤ max over T's corners of dist(corner, F), for any F. The faces nearest T's corners and
/// centroid make F's candidates; triangles whose bound exceeds what is attained are split in four
/// until it does not (by `tolerance`), largest bound first.
/// `to_neighbours`: face_neighbours(to), found once by a caller that measures many meshes against it.
MaxDistanceBound bound_max_distance(const Mesh& from, const Mesh& to, const AabbTree& tree,
                                    std::span<const std::array<Index, 3>> to_neighbours,
                                    std::span<const Index> corner_face,
                                    double attained, const Eigen::Vector3d& attained_at,
                                    const MaxDistanceOptions& options = {});

}  // namespace lodkit::detail
