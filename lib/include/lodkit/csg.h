#pragma once
// Constructive solid geometry: booleans of closed meshes through CGAL's corefinement
// (Polygon_mesh_processing::corefine_and_compute_*, exact predicates), and CSG trees of primitives,
// meshes and transforms read from JSON.
//
// Inputs are checked first: each must be closed, free of self-intersections and bound a volume;
// an inward-facing input is turned outward with a warning. Results are closed, 2-manifold and
// outward-oriented. When the inexact-constructions kernel cannot deliver a valid result, the
// operation is redone with exact constructions (or always, with `exact`).
#include <lodkit/mesh.h>

#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace lodkit {

enum class BooleanOp { Union, Difference, Intersection };

struct BooleanOptions {
  bool exact = false;  ///< use exact constructions from the start
  /// Check the operands (closed, no self-intersections, bounds a volume). Results of boolean() pass
  /// these checks by construction, so chains of operations may skip them.
  bool check_operands = true;
};

struct BooleanResult {
  Mesh mesh;
  double volume = 0.0;
  bool used_exact = false;
  std::vector<std::string> warnings;
  double seconds = 0.0;
};

/// a op b. `name_a` and `name_b` name the inputs in messages.
/// \throw Error naming the input and its defect (open, self-intersecting with N face pairs, not a volume).
BooleanResult boolean(const Mesh& a, const Mesh& b, BooleanOp op, const BooleanOptions& options = {},
                      const std::string& name_a = "A", const std::string& name_b = "B");

/// The operand checks of boolean() on their own.
/// \throw Error naming the mesh and its defect.
void check_solid(const Mesh& mesh, const std::string& name);

/// True when `mesh` is a set of closed shells that neither intersect nor nest: then it is already the
/// union of its shells (a quick test before uniting many separate parts).
bool are_separate_solids(const Mesh& mesh);

/// Cuts a closed solid by the plane `coordinate[axis] == at` into the closed solids below and above
/// it (either is empty when the plane misses the solid). The halves share the cut face exactly, so
/// join_solids() makes the solid again. Vertices within 1e-12 of the bounding-box diagonal of the
/// plane are moved onto it first.
/// \throw Error when a half would not be a valid solid after rounding to doubles.
std::pair<Mesh, Mesh> split_solid(const Mesh& solid, int axis, double at);

/// The solid made of `below` and `above` when they meet only face to face in the plane
/// `coordinate[axis] == at` (as split_solid()'s halves do, also after each has been cut away from
/// the plane): their faces in that plane are dropped and the seam is welded. Nothing when the
/// seams do not match vertex for vertex (then a union is needed).
std::optional<Mesh> join_solids(const Mesh& below, const Mesh& above, int axis, double at);

/// A node of a CSG tree: an operation over children, a primitive, or a mesh file; each may carry a
/// transform (applied to the node's result).
struct CsgNode {
  enum class Kind { Operation, Primitive, MeshFile } kind = Kind::Primitive;
  BooleanOp op = BooleanOp::Union;
  std::vector<CsgNode> children;
  std::string primitive;                    ///< box, sphere, cylinder, cone, torus
  std::vector<std::pair<std::string, double>> parameters;
  std::vector<double> size;                 ///< box size (1 or 3 values)
  std::filesystem::path mesh;
  Eigen::Matrix4d transform = Eigen::Matrix4d::Identity();
  std::string json_path = "$";              ///< where the node sits in the file, for messages
};

/// Parses a tree. Mesh paths are resolved against `base_dir`.
/// \throw Error "<name>: <json path>: <problem>".
CsgNode parse_csg(const std::string& json_text, const std::string& name, const std::filesystem::path& base_dir);
CsgNode read_csg(const std::filesystem::path& path);

struct CsgOptions {
  double tolerance = 0.01;  ///< chordal tolerance for every curved primitive
  bool exact = false;
  /// A difference with at least this many cutting parts is cut by a plane between two groups of them
  /// into two smaller differences that run in parallel, and joined again; 0 never splits.
  std::size_t split_at_parts = 16;
};

struct CsgResult {
  Mesh mesh;
  double volume = 0.0;
  int primitives = 0, operations = 0;
  std::vector<std::string> warnings;
  double seconds = 0.0;
};

CsgResult evaluate(const CsgNode& tree, const CsgOptions& options = {});

std::string to_string(BooleanOp op);

}  // namespace lodkit
