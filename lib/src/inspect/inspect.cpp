#include <lodkit/inspect.h>

#include <algorithm>
#include <unordered_set>
#include <vector>

#include "core/hash.h"
#include "core/topology.h"
#include "core/union_find.h"
#include "core/uv_charts.h"

namespace lodkit {
namespace {

struct SortedTriangle {
  Index a, b, c;
  bool operator==(const SortedTriangle&) const = default;
};
struct SortedTriangleHash {
  std::size_t operator()(const SortedTriangle& t) const {
    return detail::mix64((std::uint64_t(std::uint32_t(t.a)) << 32 | std::uint32_t(t.b)) ^
                         detail::mix64(std::uint32_t(t.c)));
  }
};

// Faces on welded vertices (classes `cls`), without those that repeat a welded vertex.
std::vector<std::array<Index, 3>> welded_faces(const Mesh& mesh, const Eigen::VectorX<Index>& cls) {
  std::vector<std::array<Index, 3>> faces;
  faces.reserve(static_cast<std::size_t>(mesh.num_faces()));
  for (Index f = 0; f < mesh.num_faces(); ++f) {
    const auto t = mesh.triangles.row(f);
    const std::array<Index, 3> w{cls[t[0]], cls[t[1]], cls[t[2]]};
    if (w[0] != w[1] && w[1] != w[2] && w[0] != w[2]) faces.push_back(w);
  }
  return faces;
}

// Whether turning faces can make every edge of a manifold mesh agree: orient_consistently() turns
// every patch that can be, so edges that still disagree on a turned copy lie in a non-orientable one.
bool can_be_oriented(const Mesh& mesh, const Eigen::VectorX<Index>& cls) {
  Mesh turned;
  turned.positions = mesh.positions;
  turned.triangles = mesh.triangles;
  orient_consistently(turned);
  for (const detail::EdgeUse& e : detail::classify_edges(welded_faces(turned, cls)))
    if (e.faces == 2 && !e.consistent) return false;
  return true;
}

}  // namespace

MeshReport inspect(const Mesh& mesh) {
  MeshReport r;
  r.vertices = mesh.num_vertices();
  r.faces = mesh.num_faces();
  r.has_normals = mesh.has_normals();
  r.has_uvs = mesh.has_uvs();
  r.has_colours = mesh.has_colours();
  r.has_face_colours = mesh.has_face_colours();
  if (r.has_uvs && r.faces > 0) {
    const std::vector<Index> charts = detail::uv_charts(mesh);
    r.uv_charts = *std::max_element(charts.begin(), charts.end()) + 1;
  }
  r.bounds = bounding_box(mesh);
  r.diagonal = r.bounds.isEmpty() ? 0.0 : r.bounds.diagonal().norm();

  const Eigen::VectorX<Index> cls = position_classes(mesh);
  std::vector<char> referenced(static_cast<std::size_t>(r.vertices), 0);
  std::vector<char> welded_referenced(static_cast<std::size_t>(r.vertices), 0);
  for (Index v = 0; v < r.vertices; ++v) r.duplicate_positions += cls[v] != v;

  // Faces on welded vertices; topologically degenerate ones take no part in the topology.
  std::vector<std::array<Index, 3>> faces;
  faces.reserve(static_cast<std::size_t>(r.faces));
  std::unordered_set<SortedTriangle, SortedTriangleHash> seen;
  seen.reserve(static_cast<std::size_t>(r.faces));
  for (Index f = 0; f < r.faces; ++f) {
    const auto t = mesh.triangles.row(f);
    for (int k = 0; k < 3; ++k) referenced[t[k]] = 1;
    const std::array<Index, 3> w{cls[t[0]], cls[t[1]], cls[t[2]]};
    const Eigen::Vector3d a = mesh.positions.row(t[0]), b = mesh.positions.row(t[1]),
                          c = mesh.positions.row(t[2]);
    const Eigen::Vector3d cross = (b - a).cross(c - a);
    r.area += 0.5 * cross.norm();
    if (w[0] == w[1] || w[1] == w[2] || w[0] == w[2]) {
      ++r.degenerate_faces;
      continue;
    }
    if (cross.squaredNorm() == 0.0) ++r.degenerate_faces;
    std::array<Index, 3> s = w;
    std::sort(s.begin(), s.end());
    if (!seen.insert({s[0], s[1], s[2]}).second) ++r.duplicate_faces;
    for (Index v : w) welded_referenced[v] = 1;
    faces.push_back(w);
  }
  for (Index v = 0; v < r.vertices; ++v) {
    r.unreferenced_vertices += !referenced[v];
    r.welded_vertices += welded_referenced[v];
  }

  detail::UnionFind boundary(static_cast<std::size_t>(r.vertices));
  std::vector<char> on_boundary(static_cast<std::size_t>(r.vertices), 0);
  for (const detail::EdgeUse& e : detail::classify_edges(faces)) {
    ++r.edges;
    if (e.faces == 1) {
      ++r.boundary_edges;
      boundary.unite(e.lo, e.hi);
      on_boundary[e.lo] = on_boundary[e.hi] = 1;
    } else if (e.faces == 2) {
      r.inconsistently_oriented_edges += !e.consistent;
    } else {
      ++r.non_manifold_edges;
    }
  }
  for (Index v = 0; v < r.vertices; ++v)
    if (on_boundary[v] && boundary.find(v) == v) ++r.boundary_loops;

  detail::UnionFind parts(static_cast<std::size_t>(r.vertices));
  for (const auto& f : faces) parts.unite(f[0], f[1]), parts.unite(f[1], f[2]);
  for (Index v = 0; v < r.vertices; ++v)
    if (welded_referenced[v] && parts.find(v) == v) ++r.components;

  for (char bad : detail::non_manifold_fans(r.vertices, faces)) r.non_manifold_vertices += bad;
  r.manifold = r.non_manifold_edges == 0 && r.non_manifold_vertices == 0;
  r.oriented = r.manifold && r.inconsistently_oriented_edges == 0;
  if (r.manifold) r.orientable = r.oriented || can_be_oriented(mesh, cls);
  r.closed = r.manifold && r.boundary_edges == 0 && !faces.empty();
  r.euler_characteristic = static_cast<long long>(r.welded_vertices) - r.edges +
                           static_cast<long long>(faces.size());
  if (r.oriented) {
    const long long twice_genus = 2LL * r.components - r.euler_characteristic - r.boundary_loops;
    if (twice_genus >= 0 && twice_genus % 2 == 0) r.genus = twice_genus / 2;
  }
  if (r.closed && r.oriented) r.volume = signed_volume(mesh);
  return r;
}

}  // namespace lodkit
