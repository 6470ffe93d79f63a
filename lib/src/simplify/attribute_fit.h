#pragma once
// fit_attributes_to_input() against an input whose tree the caller has (not public API).
#include <lodkit/simplify.h>

#include <optional>

#include "metrics/aabb_tree.h"

namespace lodkit::detail {

/// `input_tree`: a tree of `input`'s faces.
AttributeFitReport fit_attributes_to_input(const Mesh& input, const AabbTree& input_tree, Mesh& simplified,
                                           const AttributeFitOptions& options);

/// The attribute fit simplify() and simplify_within() end with, as `options` ask (fit_attributes; not with
/// record_collapses; normals not with recompute_normals), when the meshes share something to fit.
/// `input_tree`: a tree of `input`'s faces, or null to build one.
std::optional<AttributeFitReport> fit_simplified_attributes(const Mesh& input, const AabbTree* input_tree, Mesh& simplified,
                                                            const SimplifyOptions& options);

}  // namespace lodkit::detail
