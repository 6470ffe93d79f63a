#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Count_stop_predicate.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/GarlandHeckbert_plane_policies.h>
#include <CGAL/Surface_mesh_simplification/edge_collapse.h>
#include <chrono>
#include <vector>

#include "peers/peers.h"

namespace lodkit::bench {

PeerRun run_cgal(const Mesh& mesh, Index target_faces) {
  using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
  using SMesh = CGAL::Surface_mesh<Kernel::Point_3>;
  namespace SMS = CGAL::Surface_mesh_simplification;
  SMesh sm;
  std::vector<SMesh::Vertex_index> vi;
  auto origin = sm.add_property_map<SMesh::Vertex_index, Index>("v:origin", -1).first;  // kept by collect_garbage
  for (Index v = 0; v < mesh.num_vertices(); ++v) {
    vi.push_back(sm.add_vertex({mesh.positions(v, 0), mesh.positions(v, 1), mesh.positions(v, 2)}));
    origin[vi.back()] = v;
  }
  for (Index f = 0; f < mesh.num_faces(); ++f)
    sm.add_face(vi[mesh.triangles(f, 0)], vi[mesh.triangles(f, 1)], vi[mesh.triangles(f, 2)]);  // null if not manifold
  const auto t0 = std::chrono::steady_clock::now();
  SMS::Count_stop_predicate<SMesh> stop(static_cast<std::size_t>(1.5 * target_faces));
  SMS::GarlandHeckbert_plane_policies<SMesh, Kernel> policies(sm);
  SMS::edge_collapse(sm, stop, CGAL::parameters::get_cost(policies.get_cost()).get_placement(policies.get_placement()));
  sm.collect_garbage();
  PeerRun run;
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  run.mesh.positions.resize(static_cast<Index>(sm.number_of_vertices()), 3);
  run.vertex_origin.resize(sm.number_of_vertices());
  for (auto v : sm.vertices()) {
    const auto& p = sm.point(v);
    run.mesh.positions.row(static_cast<Index>(v.idx())) << p.x(), p.y(), p.z();
    run.vertex_origin[v.idx()] = origin[v];
  }
  run.mesh.triangles.resize(static_cast<Index>(sm.number_of_faces()), 3);
  for (auto f : sm.faces()) {
    int k = 0;
    for (auto v : CGAL::vertices_around_face(sm.halfedge(f), sm)) run.mesh.triangles(static_cast<Index>(f.idx()), k++) = static_cast<Index>(v.idx());
  }
  return run;
}

}  // namespace lodkit::bench
