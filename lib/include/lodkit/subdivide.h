#pragma once
// Subdivision surfaces through OpenSubdiv: Far::TopologyRefiner for the topology, Far::PrimvarRefiner
// for positions (vertex data), vertex colours (vertex data) and texture coordinates (face-varying
// data, so UV seams stay seams).
//
// Loop works on triangles; Catmull-Clark and bilinear work on polygons, so a mesh read with
// ReadOptions::polygon_sizes keeps its quads (the fan triangulation of each file polygon is undone).
// After one Catmull-Clark or bilinear level every face is a quad; lodkit meshes hold triangles, so
// each output quad is split along its shorter diagonal.
#include <lodkit/mesh.h>

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

namespace lodkit {

enum class SubdivisionScheme { Loop, CatmullClark, Bilinear };

/// How the surface meets its boundary (OpenSubdiv's VtxBoundaryInterpolation).
enum class BoundaryRule {
  None,           ///< boundary faces are not part of the limit surface (they shrink away)
  EdgeOnly,       ///< boundary edges are B-spline curves; corners are rounded
  EdgeAndCorner,  ///< as EdgeOnly, and valence-2 boundary corners stay sharp
};

/// Where UVs are interpolated linearly rather than smoothly (OpenSubdiv's FVarLinearInterpolation).
enum class UvRule {
  Smooth,        ///< smooth everywhere, including seams and boundaries (FVAR_LINEAR_NONE)
  CornersOnly,   ///< sharp only at UV corners (FVAR_LINEAR_CORNERS_ONLY)
  CornersPlus1,  ///< FVAR_LINEAR_CORNERS_PLUS1
  CornersPlus2,  ///< FVAR_LINEAR_CORNERS_PLUS2
  Boundaries,    ///< linear along seams and boundaries (FVAR_LINEAR_BOUNDARIES)
  Linear,        ///< linear everywhere: UVs do not move (FVAR_LINEAR_ALL)
};

struct SubdivideOptions {
  SubdivisionScheme scheme = SubdivisionScheme::Loop;
  int levels = 1;                  ///< ignored when `tolerance` is set
  /// Fewest levels whose surface is within this distance (symmetric Hausdorff) of the next level's.
  std::optional<double> tolerance{};
  bool tolerance_is_relative = false;  ///< tolerance as a fraction of the bounding-box diagonal
  int max_levels = 8;              ///< cap for the tolerance search
  BoundaryRule boundary = BoundaryRule::EdgeOnly;
  UvRule uv_rule = UvRule::CornersOnly;
  bool limit = false;              ///< move the final points onto the limit surface
  /// Most output triangles: more levels than this allows are refused before any work (faces grow 4x
  /// per level, and refining takes about 260 bytes a face, so the default stays near 13 GB). At most
  /// 2^31 - 1, the largest face index.
  std::int64_t max_faces = 50'000'000;
};

struct SubdivideResult {
  Mesh mesh;
  int levels = 0;
  /// With a tolerance: the Hausdorff distance between level k and level k + 1, for each k tried.
  std::vector<double> level_change;
};

/// Subdivides `mesh`. `polygon_sizes`, when given, are the corner counts of the file's polygons
/// (ReadOptions::polygon_sizes); without them every triangle is a face.
/// \throw Error for levels outside 0..max, an output of more than max_faces triangles, an empty mesh,
/// polygons that do not match the triangles, or topology OpenSubdiv rejects.
SubdivideResult subdivide(const Mesh& mesh, const SubdivideOptions& options = {},
                          std::span<const int> polygon_sizes = {});

}  // namespace lodkit
