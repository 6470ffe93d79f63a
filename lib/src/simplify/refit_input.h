#pragma once
// The input's side of refit_to_input(), made once for many refits against the same input
// (simplify_within() refits several levels of one progressive mesh).
#include <lodkit/simplify.h>

#include <Eigen/Core>
#include <span>
#include <vector>

#include "metrics/aabb_tree.h"

namespace lodkit::detail {

struct RefitInput {
  /// `facing`: ready the tree for the check of faces facing against the input (avoid_inverted).
  RefitInput(const Mesh& input, bool facing);
  const Mesh& mesh;
  AabbTree tree;
  std::vector<Eigen::Vector3d> samples;  ///< the input's points and edge midpoints
};

/// Whether a refit has anything to do (passes, and faces on both sides).
/// \throw Error for invalid options, or face origins that do not match the faces.
bool needs_refit(const Mesh& input, const Mesh& simplified, const RefitOptions& options,
                 std::span<const Index> face_origin);

/// refit_to_input() against a prepared input.
RefitReport refit_to_input(const RefitInput& input, Mesh& simplified, const RefitOptions& options,
                           std::span<const Index> face_origin = {});

}  // namespace lodkit::detail
