// CGAL's Nef_polyhedron_3 booleans: the classic exact (and slow) path lodkit's corefinement is
// measured against.
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Nef_polyhedron_3.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/boost/graph/convert_nef_polyhedron_to_polygon_mesh.h>
#include <vector>

#include "peers/peers.h"

namespace lodkit::bench {
namespace {

using Kernel = CGAL::Exact_predicates_exact_constructions_kernel;
using SMesh = CGAL::Surface_mesh<Kernel::Point_3>;
using Nef = CGAL::Nef_polyhedron_3<Kernel>;

Nef to_nef(const Mesh& m) {
  SMesh sm;
  std::vector<SMesh::Vertex_index> v;
  for (Index i = 0; i < m.num_vertices(); ++i) v.push_back(sm.add_vertex({m.positions(i, 0), m.positions(i, 1), m.positions(i, 2)}));
  for (Index f = 0; f < m.num_faces(); ++f) sm.add_face(v[m.triangles(f, 0)], v[m.triangles(f, 1)], v[m.triangles(f, 2)]);
  return Nef(sm);
}

}  // namespace

Mesh nef_fold(const std::vector<Mesh>& operands, BooleanOp op) {
  Nef acc = to_nef(operands[0]);
  for (std::size_t i = 1; i < operands.size(); ++i) {
    const Nef next = to_nef(operands[i]);
    acc = op == BooleanOp::Union ? acc + next : op == BooleanOp::Difference ? acc - next : acc * next;
  }
  SMesh out;
  CGAL::convert_nef_polyhedron_to_polygon_mesh(acc, out, true);
  Mesh m;
  m.positions.resize(static_cast<Index>(out.number_of_vertices()), 3);
  for (auto v : out.vertices()) {
    const auto& p = out.point(v);
    m.positions.row(static_cast<Index>(v.idx())) << CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z());
  }
  m.triangles.resize(static_cast<Index>(out.number_of_faces()), 3);
  for (auto f : out.faces()) {
    int k = 0;
    for (auto v : CGAL::vertices_around_face(out.halfedge(f), out)) m.triangles(static_cast<Index>(f.idx()), k++) = static_cast<Index>(v.idx());
  }
  return m;
}

}  // namespace lodkit::bench
