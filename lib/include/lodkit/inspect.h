#pragma once
// inspect(): what a mesh is, before any algorithm trusts it.
//
// Topology is computed on vertices welded by exact position, so a UV or normal seam is not reported
// as a boundary. Counts follow the usual definitions:
//   - a boundary edge has one incident face, a non-manifold edge three or more;
//   - a non-manifold vertex has faces around it that do not form one fan (a "bow tie");
//   - an edge used twice in the same direction is inconsistently oriented;
//   - Euler characteristic chi = V - E + F over referenced welded vertices; for an orientable
//     2-manifold, genus g = (2C - chi - B) / 2 with C components and B boundary loops.
#include <lodkit/mesh.h>

#include <Eigen/Geometry>
#include <optional>

namespace lodkit {

struct MeshReport {
  Index vertices = 0;  ///< rows in the vertex arrays (seam copies included)
  Index faces = 0;
  Index welded_vertices = 0;       ///< distinct positions among referenced vertices
  Index duplicate_positions = 0;   ///< vertices whose position repeats an earlier one
  Index unreferenced_vertices = 0;
  Index edges = 0;                 ///< distinct undirected edges (welded)
  Eigen::AlignedBox3d bounds;
  double diagonal = 0.0;

  Index components = 0;            ///< face-connected (through shared welded vertices)
  Index boundary_edges = 0;
  Index boundary_loops = 0;
  Index non_manifold_edges = 0;
  Index non_manifold_vertices = 0;
  Index inconsistently_oriented_edges = 0;
  Index degenerate_faces = 0;      ///< repeated vertex or zero area
  Index duplicate_faces = 0;       ///< same three welded vertices as an earlier face

  bool manifold = false;           ///< no non-manifold edges or vertices
  bool oriented = false;           ///< manifold and consistently oriented
  /// Manifold meshes: whether turning faces can make every edge agree (lodkit convert --orient, or
  /// orient_consistently()); false for a Moebius band or a Klein bottle.
  std::optional<bool> orientable;
  bool closed = false;             ///< manifold, non-empty and without boundary
  long long euler_characteristic = 0;
  std::optional<long long> genus;  ///< when oriented (orientable 2-manifold)

  double area = 0.0;
  std::optional<double> volume;    ///< signed, when closed and oriented; negative = inside out

  bool has_normals = false, has_uvs = false, has_colours = false, has_face_colours = false;
  /// With UVs: the pieces of the texture atlas, faces joined across every edge whose ends have the same
  /// UVs on both sides (UV seams part them; what compare() and the attribute fit compare UVs within).
  std::optional<Index> uv_charts;
};

MeshReport inspect(const Mesh& mesh);

}  // namespace lodkit
