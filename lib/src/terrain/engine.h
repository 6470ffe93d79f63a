#pragma once
// The terrain generator in two stages. OpenSubdiv's Far::TopologyRefiner refines the (irregular) base
// to a coarse level k, and lodkit computes positions, keys and colours level by level through the
// refiner's parent-child relations. Below level k every coarse triangle refines into a regular
// triangular lattice of side n = 2^m (m = levels - k), whose topology is closed-form: points and
// triangles get global indices by arithmetic, so patches are generated independently, in parallel
// and in file order, without holding the whole mesh.
//
// Global vertex order: the coarse vertices; then, edge by edge, the n - 1 points inside each coarse
// edge (from its first vertex to its second); then, face by face, the (n - 1)(n - 2) / 2 points
// inside each coarse face. Face order: coarse face by coarse face, n^2 triangles each.
#include <lodkit/terrain.h>

#include <array>
#include <utility>
#include <cstdint>
#include <vector>

namespace lodkit::detail {

struct TerrainPoint {
  Eigen::Vector3d position;
  std::uint64_t key = 0;
  std::uint8_t level = 0;
  std::uint8_t colour = 0;  ///< palette index
};

struct Rgb {
  std::uint8_t r, g, b;
};
/// Water, sand, grass, forest, rock, snow.
const std::array<Rgb, 6>& terrain_palette();

class TerrainEngine {
 public:
  TerrainEngine(const Mesh& base, const TerrainOptions& options);

  int coarse_level() const { return coarse_level_; }
  int side() const { return n_; }  ///< lattice side n = 2^m
  std::int64_t num_vertices() const { return num_vertices_; }
  std::int64_t num_faces() const { return num_faces_; }
  Index num_coarse_vertices() const { return static_cast<Index>(points_.size()); }
  Index num_coarse_edges() const { return static_cast<Index>(edges_.size()); }
  Index num_coarse_faces() const { return static_cast<Index>(faces_.size()); }
  const TerrainPoint& coarse_point(Index v) const { return points_[static_cast<std::size_t>(v)]; }
  bool coloured() const { return colour_; }

  /// The n + 1 points along coarse edge e, from its first vertex to its second.
  void refine_edge(Index e, std::vector<TerrainPoint>& out) const;
  /// The lattice of coarse face f: row j (0..n) holds points i = 0..n - j, where (i, j) is
  /// c0 + i/n (c1 - c0) + j/n (c2 - c0) before displacement. `scratch` is reused edge storage.
  void refine_face(Index f, std::vector<TerrainPoint>& lattice, std::vector<TerrainPoint>& scratch) const;

  std::size_t lattice_size() const { return static_cast<std::size_t>((n_ + 1) * (n_ + 2) / 2); }
  std::size_t lattice_index(int i, int j) const {
    return static_cast<std::size_t>(j * (n_ + 1) - j * (j - 1) / 2 + i);
  }
  std::int64_t first_edge_point() const { return static_cast<std::int64_t>(points_.size()); }
  std::int64_t first_face_point() const {
    return first_edge_point() + static_cast<std::int64_t>(edges_.size()) * (n_ - 1);
  }
  std::int64_t points_inside_face() const { return static_cast<std::int64_t>(n_ - 1) * (n_ - 2) / 2; }

  /// Global vertex index of every lattice point of face f (same layout as refine_face).
  void lattice_vertex_indices(Index f, std::vector<std::int64_t>& out) const;

  /// Calls emit(i0, j0, i1, j1, i2, j2) for the n^2 triangles of a patch, in output order.
  template <typename Emit>
  void for_each_lattice_triangle(Emit&& emit) const {
    for (int j = 0; j < n_; ++j)
      for (int i = 0; i + j < n_; ++i) {
        emit(i, j, i + 1, j, i, j + 1);
        if (i + j + 2 <= n_) emit(i + 1, j, i + 1, j + 1, i, j + 1);
      }
  }

  /// Palette index of a face with these corners: the majority, else the corner with the least key.
  static std::uint8_t face_colour(const TerrainPoint& a, const TerrainPoint& b, const TerrainPoint& c);

 private:
  /// Lattice (i, j) of point t = 0..n along side k of a patch: side k runs from corner k to corner
  /// k + 1, so the sides are (t, 0), (n - t, t) and (0, n - t).
  std::pair<int, int> side_point(int k, int t) const {
    if (k == 0) return {t, 0};
    if (k == 1) return {n_ - t, t};
    return {0, n_ - t};
  }
  TerrainPoint midpoint(const TerrainPoint& a, const TerrainPoint& b, int direction, int level) const;
  void build_coarse_levels(const Mesh& base);

  struct Edge {
    std::array<Index, 2> v;
    int direction;  ///< index into directions_
  };
  struct Face {
    std::array<Index, 3> v;
    std::array<Index, 3> e;  ///< e[k] joins v[k] and v[(k + 1) % 3]
    int direction;
  };

  TerrainOptions options_;
  int levels_ = 0, coarse_level_ = 0, n_ = 1;
  bool colour_ = false, closed_base_ = false;
  std::vector<double> sigma_;  ///< by level, [0] unused
  std::vector<Eigen::Vector3d> directions_;  ///< original face normals, then original edge directions
  std::vector<TerrainPoint> points_;  ///< coarse level
  std::vector<Edge> edges_;
  std::vector<Face> faces_;
  std::int64_t num_vertices_ = 0, num_faces_ = 0;
};

/// Welded, compacted triangle base with its attributes dropped. \throw Error if unusable.
Mesh prepare_terrain_base(const Mesh& base);
/// terrain_size() of a base prepare_terrain_base() has already prepared.
TerrainSize prepared_terrain_size(const Mesh& base, int levels);

}  // namespace lodkit::detail
