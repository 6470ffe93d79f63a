#pragma once
// UV charts: the pieces of a mesh's texture atlas that are continuous on the surface, and what it
// takes to compare two meshes' texture coordinates within them (compare(), the attribute fit).
#include <lodkit/mesh.h>

#include <algorithm>
#include <cstdint>
#include <map>
#include <unordered_map>
#include <utility>
#include <vector>

#include "core/union_find.h"

namespace lodkit::detail {

/// Charts of any kind of value (UVs here, all of a wedge's attributes in hoppe's E_scalar): unites in
/// `sets` (one per face) each face with the first face that used each of its edges, the edge found by
/// its two points (`point(f, k)` for corner k of face f, either way round), when both ends carry the
/// same values: `same(f, k, g, j)` for corner k of f and corner j of g at one point. Faces `skip(f)`
/// names take no part.
template <typename Point, typename Skip, typename Same>
void unite_across_edges(Index faces, Point point, Skip skip, Same same, UnionFind& sets) {
  std::unordered_map<std::uint64_t, std::pair<Index, int>> first_use;  // edge -> face and the corner it starts at
  first_use.reserve(static_cast<std::size_t>(3 * faces / 2 + 1));
  for (Index f = 0; f < faces; ++f) {
    if (skip(f)) continue;
    for (int k = 0; k < 3; ++k) {
      const Index a = point(f, k), b = point(f, (k + 1) % 3);
      if (a == b) continue;
      const std::uint64_t key = (std::uint64_t(std::uint32_t(std::min(a, b))) << 32) | std::uint32_t(std::max(a, b));
      const auto [it, fresh] = first_use.try_emplace(key, f, k);
      if (fresh) continue;
      const auto [g, side] = it->second;
      // g's corners at this edge's first and second point (the edge may run either way).
      const bool same_way = point(g, side) == a;
      const int ga = same_way ? side : (side + 1) % 3, gb = same_way ? (side + 1) % 3 : side;
      if (same(f, k, g, ga) && same(f, (k + 1) % 3, g, gb)) sets.unite(int(f), int(g));
    }
  }
}

/// Per face of `mesh` (which must have UVs), its chart: faces are joined across every edge whose two
/// ends sit at the same positions with the same UVs on both sides. A UV seam (the same points, other
/// UVs) parts charts; a normal seam alone does not. Charts are numbered from 0 in face order.
std::vector<Index> uv_charts(const Mesh& mesh);

/// Which charts of one mesh stand for which of another's, by vote: pairs of points, one on each mesh
/// (a point and its closest point on the other), each vote for their two charts with their area. Two
/// charts are partners when most of one's area lands on the other, either way round. Votes are summed
/// in the order given: the same votes give the same answer.
class ChartPartners {
 public:
  void vote(Index from_chart, Index to_chart, double area) { votes_[{from_chart, to_chart}] += area; }
  /// After the votes, before partners().
  void settle();
  bool partners(Index from_chart, Index to_chart) const;

 private:
  std::map<std::pair<Index, Index>, double> votes_;
  std::map<Index, std::pair<double, Index>> best_from_, best_to_;  // chart -> (area, its best partner)
};

/// The longest side of face f's UV triangle, squared.
double longest_uv_side2(const Mesh& m, Index f);

/// Whether `uv` lies within face f's UV triangle or no farther from it than sqrt(reach2). A chart may
/// meet itself along a seam (a torus cut open once, UVs that wrap around), where a point's closest
/// point across the seam is in the same chart but in another piece of the atlas, most often far off:
/// this tells the two apart where charts cannot.
bool near_uv_triangle(const Mesh& m, Index f, const Eigen::Vector2d& uv, double reach2);

/// Whether the UVs at a point of `from`'s face `from_face` (`uv`) and at its closest point on `to`'s
/// face `to_face` compare: within the larger of the two faces' longest UV sides (a coarse face's UV may
/// be off by a fine face's whole UV extent and still lie in the same piece of the atlas).
inline bool uv_comparable(const Mesh& from, Index from_face, const Mesh& to, Index to_face, const Eigen::Vector2d& uv) {
  return near_uv_triangle(to, to_face, uv, std::max(longest_uv_side2(from, from_face), longest_uv_side2(to, to_face)));
}

}  // namespace lodkit::detail
