// Joining the halves split_solid() made (or any two solids meeting face to face in a plane) without a
// boolean: drop the faces in the plane, weld the seam.
#include <lodkit/csg.h>

#include <array>
#include <vector>

#include "core/topology.h"

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

}  // namespace

std::optional<Mesh> join_solids(const Mesh& below, const Mesh& above, int axis, double at) {
  if (below.num_faces() == 0) return above;
  if (above.num_faces() == 0) return below;
  // (concatenated() drops attributes, so welding identical vertices welds equal positions.)
  Mesh joined = concatenated(without_faces_in_plane(below, axis, at), without_faces_in_plane(above, axis, at));
  weld_identical_vertices(joined);
  remove_unreferenced_vertices(joined);
  // Closed and consistently oriented: every edge has two faces that traverse it in opposite directions.
  std::vector<std::array<Index, 3>> faces(static_cast<std::size_t>(joined.num_faces()));
  for (Index f = 0; f < joined.num_faces(); ++f) faces[f] = {joined.triangles(f, 0), joined.triangles(f, 1), joined.triangles(f, 2)};
  if (faces.empty()) return std::nullopt;
  for (const detail::EdgeUse& e : detail::classify_edges(faces))
    if (e.faces != 2 || !e.consistent) return std::nullopt;
  return joined;
}

}  // namespace lodkit
