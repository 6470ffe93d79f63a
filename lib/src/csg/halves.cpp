// Joining the halves split_solid() made (or any two solids meeting face to face in a plane) without a
// boolean: drop the faces in the plane, weld the seam.
#include <lodkit/csg.h>

#include <algorithm>
#include <utility>
#include <vector>

namespace lodkit {
namespace {

// Without the faces lying in the plane (all three corners exactly on it).
Mesh without_faces_in_plane(const Mesh& m, int axis, double at) {
  Mesh out;
  out.positions = m.positions;
  out.triangles.resize(m.num_faces(), 3);
  Index kept = 0;
  for (Index f = 0; f < m.num_faces(); ++f) {
    bool in_plane = true;
    for (int k = 0; k < 3; ++k) in_plane = in_plane && m.positions(m.triangles(f, k), axis) == at;
    if (!in_plane) out.triangles.row(kept++) = m.triangles.row(f);
  }
  out.triangles.conservativeResize(kept, 3);
  return out;
}

// Every edge has exactly two faces, which traverse it in opposite directions.
bool is_closed_and_oriented(const Mesh& m) {
  std::vector<std::pair<Index, Index>> directed;
  directed.reserve(static_cast<std::size_t>(3 * m.num_faces()));
  for (Index f = 0; f < m.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) directed.emplace_back(m.triangles(f, k), m.triangles(f, (k + 1) % 3));
  std::sort(directed.begin(), directed.end());
  if (std::adjacent_find(directed.begin(), directed.end()) != directed.end()) return false;  // an edge twice one way
  for (const auto& [a, b] : directed)
    if (!std::binary_search(directed.begin(), directed.end(), std::pair{b, a})) return false;  // no partner
  return true;
}

}  // namespace

std::optional<Mesh> join_solids(const Mesh& below, const Mesh& above, int axis, double at) {
  if (below.num_faces() == 0) return above;
  if (above.num_faces() == 0) return below;
  Mesh joined = concatenated(without_faces_in_plane(below, axis, at), without_faces_in_plane(above, axis, at));
  const auto same = position_classes(joined);
  for (Index f = 0; f < joined.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) joined.triangles(f, k) = same[joined.triangles(f, k)];
  remove_unreferenced_vertices(joined);
  if (joined.num_faces() == 0 || !is_closed_and_oriented(joined)) return std::nullopt;
  return joined;
}

}  // namespace lodkit
