#pragma once
// What simplify() and simplify_within() must agree on: the face count asked for (so that a ratio means
// the same count in both) and the refit after the collapses.
#include <lodkit/simplify.h>

#include <algorithm>
#include <cmath>

namespace lodkit::detail {

/// The largest of target_faces and target_ratio of the input's faces (rounded); 0 when neither is set.
inline Index requested_faces(const Mesh& mesh, const SimplifyOptions& options) {
  Index target = 0;
  if (options.target_faces) target = std::max(target, *options.target_faces);
  if (options.target_ratio)
    target = std::max(target, static_cast<Index>(std::llround(*options.target_ratio * mesh.num_faces())));
  return target;
}

/// The refit passes `options` ask for (by method and size when unset), or 0 where no refit runs.
inline int refit_passes(const Mesh& mesh, const SimplifyOptions& options) {
  if (!options.preserve_topology) return 0;
  return options.refit_passes.value_or(default_refit_passes(options.method, mesh.num_faces()));
}

/// The refit's options from the simplification's: its limits, and weights by method. `total_turn_deg`:
/// how far a face may turn from its reference orientation (see refit_to_input()).
RefitOptions refit_options(const SimplifyOptions& options, int passes, double total_turn_deg);

}  // namespace lodkit::detail
