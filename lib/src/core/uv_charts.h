#pragma once
// UV charts: the pieces of a mesh's texture atlas that are continuous on the surface, and what it
// takes to compare two meshes' texture coordinates within them (compare(), the attribute fit).
#include <lodkit/mesh.h>

#include <map>
#include <utility>
#include <vector>

namespace lodkit::detail {

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
