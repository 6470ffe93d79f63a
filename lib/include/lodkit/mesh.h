#pragma once
// lodkit::Mesh: the one plain value type every algorithm takes and returns.
//
// A triangle mesh stored as row-major Eigen matrices: one row of `positions` per vertex and one row of
// `triangles` per face, counter-clockwise seen from outside. Attributes are optional; each present
// per-vertex attribute has exactly one row per vertex. A vertex whose position equals another's but
// whose attributes differ (a UV or normal seam) stays a separate vertex; algorithms weld by position
// for topology and keep such seams intact (Hoppe's "wedges").
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

namespace lodkit {

using Index = std::int32_t;
using Positions = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
using Triangles = Eigen::Matrix<Index, Eigen::Dynamic, 3, Eigen::RowMajor>;
using Normals = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
using TexCoords = Eigen::Matrix<double, Eigen::Dynamic, 2, Eigen::RowMajor>;
/// RGBA in [0, 1]; 8-bit file colours map to k/255 and back exactly.
using Colours = Eigen::Matrix<float, Eigen::Dynamic, 4, Eigen::RowMajor>;

struct Attributes {
  Normals normals;        ///< empty, or one unit normal per vertex
  TexCoords uvs;          ///< empty, or one (u, v) per vertex
  Colours colours;        ///< empty, or one RGBA per vertex
  Colours face_colours;   ///< empty, or one RGBA per face
};

struct Mesh {
  Positions positions;
  Triangles triangles;
  Attributes attributes;

  Index num_vertices() const { return static_cast<Index>(positions.rows()); }
  Index num_faces() const { return static_cast<Index>(triangles.rows()); }
  bool empty() const { return positions.rows() == 0 && triangles.rows() == 0; }
  bool has_normals() const { return attributes.normals.rows() > 0; }
  bool has_uvs() const { return attributes.uvs.rows() > 0; }
  bool has_colours() const { return attributes.colours.rows() > 0; }
  bool has_face_colours() const { return attributes.face_colours.rows() > 0; }
};

/// The largest coordinate magnitude lodkit takes: a float's range, since the closest-point search
/// keeps its boxes in float (and squared distances, areas and quadrics stay far from overflowing).
/// Every double that rounds to a finite float is in: the largest float written to 9 digits,
/// 3.40282347e38, lies a little above it and is what writers print for it.
inline constexpr double kLargestCoordinate = 0x1.fffffefffffffp127;  // just below 2^128 - 2^103
static_assert(kLargestCoordinate > std::numeric_limits<float>::max());

/// Whether every coordinate of p lies within ±kLargestCoordinate. Algorithms that place vertices
/// (an optimum can lie outside the input's box) keep to it, so their outputs can be written.
inline bool within_coordinate_range(const Eigen::Vector3d& p) {
  return p.cwiseAbs().maxCoeff() <= kLargestCoordinate;
}

/// Checks the invariants every algorithm relies on: finite coordinates within ±kLargestCoordinate,
/// finite attributes, indices in range, attribute row counts matching vertices (or faces). Cheap (one
/// pass).
/// \throw Error naming `context` (usually the file name) and the first problem found.
void validate(const Mesh& mesh, const std::string& context = "mesh");

/// Axis-aligned bounding box of the positions (empty box for an empty mesh).
Eigen::AlignedBox3d bounding_box(const Mesh& mesh);

/// Merges vertices with bit-identical positions *and* identical attributes (exact welding; seams
/// survive). Unreferenced vertices are kept. Returns the number of vertices removed.
Index weld_identical_vertices(Mesh& mesh);

/// For each vertex, the lowest-index vertex with a bit-identical position and identical attributes
/// (itself if none): the classes weld_identical_vertices() merges.
std::vector<Index> identical_vertex_classes(const Mesh& mesh);

/// Removes vertices that no face references, keeping the order of the rest. Returns how many.
Index remove_unreferenced_vertices(Mesh& mesh);

/// For each vertex, the index of the first vertex with a bit-identical position: the map algorithms
/// use to weld seams for topology while keeping the seam vertices themselves.
Eigen::VectorX<Index> position_classes(const Mesh& mesh);

/// Turns faces (swaps two corners) so that neighbours agree on orientation: two faces that share an
/// edge (vertices welded by position) run it in opposite directions. Only patches (faces joined across
/// edges of two faces) that disagree somewhere change, and only where they can: a non-orientable patch
/// (a Moebius band) stays as it is. A closed patch ends up enclosing a positive volume (normals
/// outwards), an open one facing the way most of its area faced. Returns the number of faces turned.
Index orient_consistently(Mesh& mesh);

/// Signed enclosed volume (divergence theorem, about the bounding-box centre for precision). Meaningful
/// for closed, consistently oriented meshes; negative when faces point inward.
double signed_volume(const Mesh& mesh);

/// Both meshes in one: b's vertices and faces appended after a's (attributes dropped).
Mesh concatenated(const Mesh& a, const Mesh& b);
/// All parts in one, in order (attributes dropped); one copy, however many parts.
Mesh concatenated(std::span<const Mesh> parts);

/// Area-weighted vertex normals (unit length; zero only for isolated vertices).
Normals compute_vertex_normals(const Mesh& mesh);

}  // namespace lodkit
