#include <lodkit/inspect.h>

#include <algorithm>
#include <unordered_set>
#include <vector>

#include "core/hash.h"
#include "core/union_find.h"

namespace lodkit {
namespace {

struct HalfEdge {
  Index lo, hi;   // welded endpoints, lo < hi
  bool forward;   // the face traverses lo -> hi
  bool operator<(const HalfEdge& o) const { return lo != o.lo ? lo < o.lo : hi < o.hi; }
};

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

// A vertex is manifold when the faces around it form a single fan: link its neighbours through
// the faces (each face joins its two other corners) and count the connected pieces.
Index count_non_manifold_vertices(Index num_vertices, const std::vector<std::array<Index, 3>>& faces) {
  std::vector<Index> start(static_cast<std::size_t>(num_vertices) + 1, 0);
  for (const auto& f : faces)
    for (Index v : f) ++start[v + 1];
  for (Index v = 0; v < num_vertices; ++v) start[v + 1] += start[v];
  std::vector<std::pair<Index, Index>> links(start.back());
  std::vector<Index> fill(start.begin(), start.end() - 1);
  for (const auto& f : faces)
    for (int k = 0; k < 3; ++k) links[fill[f[k]]++] = {f[(k + 1) % 3], f[(k + 2) % 3]};

  Index count = 0;
  std::vector<Index> local;
  for (Index v = 0; v < num_vertices; ++v) {
    const Index b = start[v], e = start[v + 1];
    if (e - b < 2) continue;
    local.clear();
    for (Index i = b; i < e; ++i) local.push_back(links[i].first), local.push_back(links[i].second);
    std::sort(local.begin(), local.end());
    local.erase(std::unique(local.begin(), local.end()), local.end());
    detail::UnionFind uf(local.size());
    auto id = [&](Index x) {
      return static_cast<int>(std::lower_bound(local.begin(), local.end(), x) - local.begin());
    };
    std::size_t pieces = local.size();
    for (Index i = b; i < e; ++i)
      if (uf.unite(id(links[i].first), id(links[i].second))) --pieces;
    if (pieces > 1) ++count;
  }
  return count;
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

  // Edges: sort the half-edges so each undirected edge's uses are adjacent.
  std::vector<HalfEdge> half;
  half.reserve(3 * faces.size());
  for (const auto& f : faces)
    for (int k = 0; k < 3; ++k) {
      const Index a = f[k], b = f[(k + 1) % 3];
      half.push_back({std::min(a, b), std::max(a, b), a < b});
    }
  std::sort(half.begin(), half.end());
  detail::UnionFind boundary(static_cast<std::size_t>(r.vertices));
  std::vector<char> on_boundary(static_cast<std::size_t>(r.vertices), 0);
  for (std::size_t i = 0; i < half.size();) {
    std::size_t j = i;
    while (j < half.size() && half[j].lo == half[i].lo && half[j].hi == half[i].hi) ++j;
    const std::size_t uses = j - i;
    ++r.edges;
    if (uses == 1) {
      ++r.boundary_edges;
      boundary.unite(half[i].lo, half[i].hi);
      on_boundary[half[i].lo] = on_boundary[half[i].hi] = 1;
    } else if (uses == 2) {
      if (half[i].forward == half[i + 1].forward) ++r.inconsistently_oriented_edges;
    } else {
      ++r.non_manifold_edges;
    }
    i = j;
  }
  for (Index v = 0; v < r.vertices; ++v)
    if (on_boundary[v] && boundary.find(v) == v) ++r.boundary_loops;

  detail::UnionFind parts(static_cast<std::size_t>(r.vertices));
  for (const auto& f : faces) parts.unite(f[0], f[1]), parts.unite(f[1], f[2]);
  for (Index v = 0; v < r.vertices; ++v)
    if (welded_referenced[v] && parts.find(v) == v) ++r.components;

  r.non_manifold_vertices = count_non_manifold_vertices(r.vertices, faces);
  r.manifold = r.non_manifold_edges == 0 && r.non_manifold_vertices == 0;
  r.oriented = r.manifold && r.inconsistently_oriented_edges == 0;
  r.closed = r.manifold && r.boundary_edges == 0 && !faces.empty();
  r.euler_characteristic = static_cast<long long>(r.welded_vertices) - r.edges +
                           static_cast<long long>(faces.size());
  if (r.oriented) {
    const long long twice_genus = 2LL * r.components - r.euler_characteristic - r.boundary_loops;
    if (twice_genus >= 0 && twice_genus % 2 == 0) r.genus = twice_genus / 2;
  }
  if (r.closed && r.oriented) {
    // Tetrahedra from the box centre, not the origin: exact for closed meshes and free of the
    // cancellation that far-from-origin coordinates would cause.
    const Eigen::Vector3d o = r.bounds.center();
    double six_volume = 0.0;
    for (Index f = 0; f < r.faces; ++f) {
      const auto t = mesh.triangles.row(f);
      const Eigen::Vector3d a = mesh.positions.row(t[0]).transpose() - o,
                            b = mesh.positions.row(t[1]).transpose() - o,
                            c = mesh.positions.row(t[2]).transpose() - o;
      six_volume += a.dot(b.cross(c));
    }
    r.volume = six_volume / 6.0;
  }
  return r;
}

}  // namespace lodkit
