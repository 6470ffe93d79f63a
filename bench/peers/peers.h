#pragma once
// Adapters that run the peer simplifiers on a lodkit::Mesh. Each runs in its own translation unit so
// CGAL's heavy templates compile once, apart from everything else.
#include <lodkit/csg.h>
#include <lodkit/mesh.h>

#include <vector>

namespace lodkit::bench {

struct PeerRun {
  Mesh mesh;
  double seconds = 0;  ///< the simplification call only, not the conversions around it
  /// Per output vertex, the input vertex it is (moved, for the quadric peers): the peers keep input
  /// vertices, so their output carries those vertices' normals, UVs and colours (run_method() copies them).
  std::vector<Index> vertex_origin;
};

/// meshoptimizer's meshopt_simplify (attribute-free, error limit off), or meshopt_simplifySloppy.
PeerRun run_meshoptimizer(const Mesh& mesh, Index target_faces, bool sloppy);
/// OpenMesh's Decimater with ModQuadric and ModNormalFlipping, decimate_to_faces.
PeerRun run_openmesh(const Mesh& mesh, Index target_faces);
/// CGAL's edge_collapse with Garland-Heckbert plane policies; stops at 1.5 x target edges.
PeerRun run_cgal(const Mesh& mesh, Index target_faces);

/// Folds `op` over the operands with CGAL's Nef_polyhedron_3 (exact kernel), and converts back.
Mesh nef_fold(const std::vector<Mesh>& operands, BooleanOp op);

}  // namespace lodkit::bench
