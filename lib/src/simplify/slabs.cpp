#include "simplify/slabs.h"

#include <algorithm>
#include <cmath>

namespace lodkit::detail {

Slabs cut_into_slabs(const EngineState& s, Index count, bool shifted) {
  Eigen::AlignedBox3d box;
  for (const auto& p : s.position) box.extend(p);
  int axis = 0;
  box.diagonal().maxCoeff(&axis);
  const Index faces = static_cast<Index>(s.face.size());
  std::vector<double> centre(static_cast<std::size_t>(faces), 0.0);  // three times the centroid's
  std::vector<double> sorted;
  sorted.reserve(static_cast<std::size_t>(s.alive_faces));
  for (Index f = 0; f < faces; ++f) {
    if (s.face_dead[f]) continue;
    for (int k = 0; k < 3; ++k) centre[f] += s.position[s.corner_point(f, k)][axis];
    sorted.push_back(centre[f]);
  }
  // The cuts: the face centres at 1/count, 2/count, ... of the way (shifted: 1/2count, 3/2count, ...),
  // each selection on what is left.
  std::vector<double> cut;
  const std::size_t cuts = shifted ? std::size_t(count) : std::size_t(count) - 1;
  for (auto from = sorted.begin(); cut.size() < cuts && !sorted.empty();) {
    const std::size_t twice = shifted ? 2 * cut.size() + 1 : 2 * cut.size() + 2;  // in halves of a slab
    const auto at = sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() * twice / (2 * std::size_t(count)));
    std::nth_element(from, at, sorted.end());
    cut.push_back(*at);
    from = at;
  }

  Slabs out;
  out.faces.assign(cut.size() + 1, 0);
  out.region.assign(s.position.size(), -2);
  for (Index f = 0; f < faces; ++f) {
    if (s.face_dead[f]) continue;
    const Index slab = static_cast<Index>(std::upper_bound(cut.begin(), cut.end(), centre[f]) - cut.begin());
    ++out.faces[slab];
    for (int k = 0; k < 3; ++k) {
      Index& r = out.region[s.corner_point(f, k)];
      r = r == -2 || r == slab ? slab : -1;
    }
  }
  for (Index f = 0; f < faces; ++f)
    if (!s.face_dead[f] && (out.region[s.corner_point(f, 0)] < 0 || out.region[s.corner_point(f, 1)] < 0 ||
                            out.region[s.corner_point(f, 2)] < 0))
      ++out.rim_faces;
  return out;
}

Index lane_pass_stop(Index alive, Index target, Index rim_faces) {
  // stop - target >= 3 rim (1 - stop / alive), solved for stop.
  if (alive <= 0) return target;
  const double three_rims = 3.0 * rim_faces;
  return static_cast<Index>(std::ceil((target + three_rims) / (1.0 + three_rims / alive)));
}

}  // namespace lodkit::detail
