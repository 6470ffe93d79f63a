#pragma once
// What simplify() and simplify_within() must agree on: the face count asked for (so that a ratio means
// the same count in both) and the refit after the collapses.
#include <lodkit/simplify.h>

#include <algorithm>
#include <cmath>

namespace lodkit::detail {

/// \throw Error for options out of their range (a ratio past 1, a weight that is negative or NaN, ...).
void check_options(const SimplifyOptions& options);

/// The largest of target_faces and target_ratio of the input's faces (rounded); 0 when neither is set.
inline Index requested_faces(const Mesh& mesh, const SimplifyOptions& options) {
  Index target = 0;
  if (options.target_faces) target = std::max(target, *options.target_faces);
  if (options.target_ratio)
    target = std::max(target, static_cast<Index>(std::llround(*options.target_ratio * mesh.num_faces())));
  return target;
}

/// The total turn a default limit relaxes to where it alone would stop a run short (Engine::relax_total_turn()):
/// the most that never lets a face face against its input self.
constexpr double kRelaxedTotalTurnDeg = 90.0;

/// How far a face may turn from its input orientation over all collapses, before any relaxation (the
/// engine's starting limit; SimplifyOptions::max_total_normal_change_deg).
inline double starting_total_turn_deg(const SimplifyOptions& options) {
  return std::max(options.max_total_normal_change_deg.value_or(default_max_total_normal_change(options.method)),
                  options.max_normal_change_deg);
}

/// The refit's options from the simplification's of `mesh`: its passes in both stages (by method and size
/// where unset; none without preserve_topology), its limits, and weights by method. `total_turn_deg`:
/// how far a face may turn from its reference orientation (see refit_to_input()).
RefitOptions refit_options(const Mesh& mesh, const SimplifyOptions& options, double total_turn_deg);

/// Whether a refit with these options does anything.
inline bool refits(const RefitOptions& options) { return options.passes + options.rms_passes > 0; }

}  // namespace lodkit::detail
