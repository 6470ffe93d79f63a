#pragma once
// decimate(): Schroeder, Zarge & Lorensen, "Decimation of triangle meshes" (SIGGRAPH 1992).
//
// Vertex removal rather than edge collapse: each vertex is classified from its star (the faces around
// it) and a feature angle; a removable vertex goes if it is close enough to the average plane of its
// star (simple vertices) or to the line through its two boundary or feature neighbours (boundary and
// interior-edge vertices); the hole is re-triangulated by recursive loop splitting. Passes repeat
// with a threshold that grows to `max_error` until the target is met.
//
// Topology is preserved: a removal is refused if its triangulation would create an edge or face that
// already exists (which would make the mesh non-manifold or change its genus), or flip a triangle
// against the star's average plane. Attributes are not carried: the output has positions only
// (vertices welded by position).
#include <lodkit/mesh.h>
#include <lodkit/simplify.h>

#include <array>
#include <optional>
#include <string>

namespace lodkit {

/// The classes of the paper. Which may be removed, and how, is the table in decimate.cpp.
enum class VertexClass { Simple, Complex, Boundary, InteriorEdge, Corner };

struct DecimateOptions {
  /// Largest distance of a removed vertex from its star's plane or feature line (absolute). Default:
  /// unbounded when a face target is given, else 0.5 % of the bounding-box diagonal.
  std::optional<double> max_error{};
  std::optional<Index> target_faces{};
  std::optional<double> target_ratio{};
  /// Edges whose faces' normals differ by more than this are feature edges.
  double feature_angle_deg = 30.0;
  /// A split line is acceptable when (minimum distance of loop vertices to its split plane) /
  /// (its length) reaches this.
  double aspect_ratio = 0.1;
  /// Add each removal's error to its neighbours (a conservative global bound).
  bool accumulate_error = false;
  /// First turn the faces of an inconsistently oriented input to agree (orient_consistently(), on a
  /// copy), as simplify() does (SimplifyOptions::orient_faces): a vertex whose faces disagree is complex.
  bool orient_faces = true;
  /// Give the output the input's vertex colours, its UVs, and its normals where they are one per
  /// position (vertices are welded by position, so hard edges cannot survive), then fit all three to
  /// the input's (fit_attributes_to_input()). UV seams count as feature edges, so that a vertex on a
  /// seam goes only along it and no new face straddles one; the output has a vertex for each side.
  /// Off: positions only, and seams are not features.
  bool fit_attributes = true;
  /// Removals that would leave a new face facing against the input face nearest its centroid
  /// (count_flipped_faces()'s rule; the checks against the star's plane and its corners' input
  /// normals let a fold through where the input is noisy or parts cross). Refuse: never (the output has
  /// none). Avoid: such a removal waits until a pass's threshold is twice its error, then is let be
  /// (DecimateResult::inverted_allowed_at). Allow: the paper's checks alone. Over the shared scans, CAD
  /// parts and attribute meshes at 10 % and 1 %, such faces: 3,224 with Allow, 2,820 with Avoid, 0 with
  /// Refuse, which costs reach where parts cross (docs/benchmarks-log.md, "Session 45").
  InvertedFaces inverted_faces = InvertedFaces::Refuse;
};

struct DecimateResult {
  Mesh mesh;
  Index faces_in = 0, faces_out = 0, vertices_in = 0, vertices_out = 0;
  Index removed = 0;
  Index reoriented_faces = 0;  ///< input faces turned to agree with their neighbours first (orient_faces)
  double error = 0.0;  ///< largest error of a removal (accumulated when asked)
  bool target_reached = false;
  std::string reason_text;
  /// Classes of the vertices that remain (Simple, Complex, Boundary, InteriorEdge, Corner).
  std::array<Index, 5> remaining_by_class{};
  Index remaining_above_threshold = 0;   ///< removable by class, but too far from plane or line
  Index remaining_no_triangulation = 0;  ///< close enough, but no split met the rules
  Index remaining_inverted = 0;  ///< of those, the last try left a face facing against the input
  /// InvertedFaces::Avoid: the faces there were when a removal was first let leave a face facing
  /// against the input; unset if none was.
  std::optional<Index> inverted_allowed_at{};
  /// What the fit of the normals and colours did, when the output has some (fit_attributes).
  std::optional<AttributeFitReport> attribute_fit{};
  double seconds = 0.0;
};

DecimateResult decimate(const Mesh& mesh, const DecimateOptions& options = {});

/// Classifies every vertex (welded by position); unreferenced vertices count as Complex.
std::array<Index, 5> count_vertex_classes(const Mesh& mesh, double feature_angle_deg = 30.0);

}  // namespace lodkit
