#pragma once
// Edge and fan classification over faces given on (welded) point indices: shared by inspect(), which
// counts defects, and the simplifier, which locks them; and the faces that turn to make a mesh agree.
#include <lodkit/mesh.h>

#include <array>
#include <vector>

namespace lodkit::detail {

struct EdgeUse {
  Index lo, hi;  // endpoints, lo < hi
  int faces;     // how many faces use the edge
  bool consistent;  // for two faces: traversed in opposite directions
  Index face[2];    // the first two faces using it (indices into `faces`; -1 when fewer)
};

/// Every undirected edge of `faces` once, sorted by (lo, hi).
std::vector<EdgeUse> classify_edges(const std::vector<std::array<Index, 3>>& faces);

/// For each point, whether the faces around it fail to form a single fan (a "bow tie").
std::vector<char> non_manifold_fans(Index num_points, const std::vector<std::array<Index, 3>>& faces);

/// `mesh` itself, or, when `orient` and some of its faces disagree on orientation, `copy` made to hold it
/// with them turned (orient_consistently()); `turned` counts them. A mesh that agrees is not copied.
const Mesh& oriented(const Mesh& mesh, bool orient, Mesh& copy, Index& turned);

}  // namespace lodkit::detail
