#pragma once
// Edge and fan classification over faces given on (welded) point indices: shared by inspect(), which
// counts defects, and the simplifier, which locks them.
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

}  // namespace lodkit::detail
