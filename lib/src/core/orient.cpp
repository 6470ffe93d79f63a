// orient_consistently(): the faces of each orientable patch turned to agree with one another.
#include <lodkit/mesh.h>

#include <algorithm>
#include <array>
#include <vector>

#include "core/topology.h"

namespace lodkit {
namespace {

// The faces orient_consistently() turns, ascending (none when every patch agrees with itself).
std::vector<Index> faces_to_turn(const Mesh& mesh) {
  // Faces on welded positions (as inspect() and the simplifier see them); a face without three distinct
  // points joins nothing and is left as it is.
  const Eigen::VectorX<Index> point = position_classes(mesh);
  std::vector<std::array<Index, 3>> faces;
  std::vector<Index> face_of;  // per entry of `faces`: its face in the mesh
  faces.reserve(static_cast<std::size_t>(mesh.num_faces()));
  face_of.reserve(faces.capacity());
  for (Index f = 0; f < mesh.num_faces(); ++f) {
    const std::array<Index, 3> p{point[mesh.triangles(f, 0)], point[mesh.triangles(f, 1)], point[mesh.triangles(f, 2)]};
    if (p[0] == p[1] || p[1] == p[2] || p[0] == p[2]) continue;
    faces.push_back(p);
    face_of.push_back(f);
  }
  const std::vector<detail::EdgeUse> edges = detail::classify_edges(faces);
  bool disagree = false;
  for (const detail::EdgeUse& e : edges) disagree |= e.faces == 2 && !e.consistent;
  if (!disagree) return {};

  // Patches: faces joined across manifold edges (two faces each). Per face, whether it turns relative
  // to its patch's first face: across an edge both faces run the same way, one of them must turn.
  const std::size_t n = faces.size();
  std::vector<Index> start(n + 1, 0);
  for (const detail::EdgeUse& e : edges)
    if (e.faces == 2) ++start[e.face[0] + 1], ++start[e.face[1] + 1];
  for (std::size_t i = 0; i < n; ++i) start[i + 1] += start[i];
  struct Link {
    Index face;
    bool turn;  // the two faces run the edge the same way
  };
  std::vector<Link> links(static_cast<std::size_t>(start[n]));
  std::vector<Index> fill(start.begin(), start.end() - 1);
  for (const detail::EdgeUse& e : edges) {
    if (e.faces != 2) continue;
    links[fill[e.face[0]]++] = {e.face[1], !e.consistent};
    links[fill[e.face[1]]++] = {e.face[0], !e.consistent};
  }

  std::vector<Index> patch(n, -1);
  std::vector<char> turn(n, 0);
  std::vector<Index> members, turned;
  for (std::size_t seed = 0; seed < n; ++seed) {
    if (patch[seed] >= 0) continue;
    members.assign(1, Index(seed));
    patch[seed] = Index(seed);
    bool orientable = true, closed = true, disagreed = false;
    for (std::size_t next = 0; next < members.size(); ++next) {
      const Index f = members[next];
      closed &= start[f + 1] - start[f] == 3;  // every edge shared with one other face
      for (Index i = start[f]; i < start[f + 1]; ++i) {
        const Link& l = links[i];
        disagreed |= l.turn;
        const char want = turn[f] ^ char(l.turn);
        if (patch[l.face] < 0) {
          patch[l.face] = Index(seed), turn[l.face] = want;
          members.push_back(l.face);
        } else if (turn[l.face] != want) {
          orientable = false;  // a Moebius band: no turning makes every edge agree
        }
      }
    }
    // A patch that agreed with itself, or cannot, stays as it is.
    if (!disagreed || !orientable) continue;
    // Which of the patch's two orientations: a closed patch the one that encloses a positive volume
    // (normals outwards); an open one the one most of its area had already.
    double volume = 0, area_kept = 0, area_turned = 0;
    const Eigen::Vector3d centre = mesh.positions.row(mesh.triangles(face_of[seed], 0)).transpose();
    for (Index f : members) {
      const Index g = face_of[f];
      const Eigen::Vector3d a = mesh.positions.row(mesh.triangles(g, 0)).transpose() - centre,
                            b = mesh.positions.row(mesh.triangles(g, 1)).transpose() - centre,
                            c = mesh.positions.row(mesh.triangles(g, 2)).transpose() - centre;
      const double sign = turn[f] ? -1.0 : 1.0;
      volume += sign * a.dot(b.cross(c));
      (turn[f] ? area_turned : area_kept) += (b - a).cross(c - a).norm();
    }
    const bool flip_all = closed && volume != 0 ? volume < 0 : area_turned > area_kept;
    for (Index f : members)
      if ((turn[f] != 0) != flip_all) turned.push_back(face_of[f]);
  }
  std::sort(turned.begin(), turned.end());
  return turned;
}

void turn_faces(Mesh& mesh, const std::vector<Index>& faces) {
  for (Index f : faces) std::swap(mesh.triangles(f, 1), mesh.triangles(f, 2));
}

}  // namespace

Index orient_consistently(Mesh& mesh) {
  const std::vector<Index> faces = faces_to_turn(mesh);
  turn_faces(mesh, faces);
  return static_cast<Index>(faces.size());
}

namespace detail {

const Mesh& oriented(const Mesh& mesh, bool orient, Mesh& copy, Index& turned) {
  const std::vector<Index> faces = orient ? faces_to_turn(mesh) : std::vector<Index>{};
  turned = static_cast<Index>(faces.size());
  if (faces.empty()) return mesh;
  copy = mesh;
  turn_faces(copy, faces);
  return copy;
}

}  // namespace detail

}  // namespace lodkit
