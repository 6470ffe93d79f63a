#pragma once
// The face count a simplification is asked for, shared by simplify() and simplify_within() so that a
// ratio means the same count in both.
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

}  // namespace lodkit::detail
