#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModNormalFlippingT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>
#include <chrono>
#include <vector>

#include "peers/peers.h"

namespace lodkit::bench {

PeerRun run_openmesh(const Mesh& mesh, Index target_faces) {
  using OMesh = OpenMesh::TriMesh_ArrayKernelT<>;
  OMesh om;
  std::vector<OMesh::VertexHandle> vh;
  OpenMesh::VPropHandleT<Index> origin;  // survives the collapses and the garbage collection
  om.add_property(origin);
  for (Index v = 0; v < mesh.num_vertices(); ++v) {
    vh.push_back(om.add_vertex(OMesh::Point(float(mesh.positions(v, 0)), float(mesh.positions(v, 1)), float(mesh.positions(v, 2)))));
    om.property(origin, vh.back()) = v;
  }
  for (Index f = 0; f < mesh.num_faces(); ++f)
    om.add_face(vh[mesh.triangles(f, 0)], vh[mesh.triangles(f, 1)], vh[mesh.triangles(f, 2)]);  // complex faces are skipped
  const auto t0 = std::chrono::steady_clock::now();
  OpenMesh::Decimater::DecimaterT<OMesh> decimater(om);
  OpenMesh::Decimater::ModQuadricT<OMesh>::Handle quadric;
  OpenMesh::Decimater::ModNormalFlippingT<OMesh>::Handle flipping;
  decimater.add(quadric);
  decimater.add(flipping);
  decimater.module(quadric).unset_max_err();
  decimater.initialize();
  decimater.decimate_to_faces(0, static_cast<std::size_t>(target_faces));
  om.garbage_collection();
  PeerRun run;
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  run.mesh.positions.resize(static_cast<Index>(om.n_vertices()), 3);
  run.vertex_origin.resize(om.n_vertices());
  for (auto v : om.vertices()) {
    for (int k = 0; k < 3; ++k) run.mesh.positions(v.idx(), k) = om.point(v)[k];
    run.vertex_origin[static_cast<std::size_t>(v.idx())] = om.property(origin, v);
  }
  run.mesh.triangles.resize(static_cast<Index>(om.n_faces()), 3);
  for (auto f : om.faces()) {
    int k = 0;
    for (auto v : om.fv_range(f)) run.mesh.triangles(f.idx(), k++) = v.idx();
  }
  return run;
}

}  // namespace lodkit::bench
