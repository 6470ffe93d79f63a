#pragma once
// Fractal terrain by consistent midpoint displacement (Fournier, Fussell & Carpenter 1982).
//
// Every triangle of a base mesh is split 1-to-4, `levels` times (Loop refinement topology, from
// OpenSubdiv). Existing points never move; each new edge midpoint is the average of its edge's end
// points plus a Gaussian displacement with standard deviation sigma_l = sigma0 * 2^(-l * H) at the
// level l = 1..levels where it appears (H: `roughness`, the Hurst exponent).
//
// Internal consistency: the random for a point depends only on the point. Base vertex i has the key
// mix(i); a midpoint's key is an order-independent hash of its edge's two keys; the Gaussian is indexed
// by (key, seed). So the result does not depend on traversal order or thread count, and a terrain
// refined further keeps every coarser point bit-identical (8 levels, then 10: same first 8).
//
// External consistency: a midpoint is a function of its edge alone, so the faces on either side of an
// edge make the same point and the surface never cracks; a closed base stays closed and manifold.
// Displacement direction:
//   - points inside an original (level-0) face move along that face's unit normal;
//   - points on an original edge move along a direction the two sides agree on: `up` for height
//     fields (EdgeDirection::Up, the default for bases with a boundary), or the normalised sum of the
//     edge's adjacent original face normals (EdgeDirection::FaceNormals, the default for closed bases);
//   - original vertices stay where they are.
//
// Colour (optional): points up to `palette_level` take a colour from a height palette (water, sand,
// grass, forest, rock, snow) spread over the height range of those points; each deeper midpoint takes
// the colour of one of its two end points, chosen by a Boolean random keyed like the displacement.
// Faces are flat-coloured: the colour most of their corners share (ties: the corner with the least
// key). Height is z - z_centre for bases with a boundary and the distance to the base's centroid for
// closed bases.
#include <lodkit/mesh.h>

#include <cstdint>
#include <filesystem>
#include <vector>

namespace lodkit {

enum class TerrainBase {
  Grid,     ///< the unit square [-0.5, 0.5]^2 at z = 0 as two triangles
  Pyramid,  ///< the four sides of a square pyramid (base 1, height 0.5), open at the bottom
};
Mesh make_terrain_base(TerrainBase base);

enum class EdgeDirection {
  Auto,         ///< Up for bases with a boundary, FaceNormals for closed ones
  Up,           ///< TerrainOptions::up
  FaceNormals,  ///< normalised sum of the original edge's adjacent face normals
};

struct TerrainOptions {
  int levels = 8;             ///< 1-to-4 splits; 0 returns the base. At most 15.
  double roughness = 0.8;     ///< H in (0, 1]: higher is smoother
  double sigma = 0.1;         ///< sigma0: absolute, or a fraction of the base's bounding-box diagonal
  bool sigma_is_relative = true;
  std::uint64_t seed = 1;
  EdgeDirection edge_direction = EdgeDirection::Auto;
  Eigen::Vector3d up{0.0, 0.0, 1.0};
  bool colour = false;        ///< per-face palette colours
  int palette_level = 4;      ///< points of this level or coarser are coloured by height
  int threads = 0;            ///< 0: all hardware threads. The result never depends on it.
};

struct Terrain {
  Mesh mesh;                             ///< face_colours set when options.colour
  std::vector<std::uint64_t> keys;       ///< per vertex: the key its random is drawn from
  std::vector<std::uint8_t> vertex_level;  ///< per vertex: 0 for base vertices, else the level it appeared at
};

/// sigma_l for midpoints that appear at `level` (1-based), with sigma0 resolved against `base`.
double terrain_sigma(const Mesh& base, const TerrainOptions& options, int level);

/// Vertex and face counts of a terrain before generating it (for memory planning).
struct TerrainSize {
  std::int64_t vertices = 0, faces = 0;
};
TerrainSize terrain_size(const Mesh& base, int levels);

/// The terrain in memory. The base's seams are welded by position first (attributes are dropped).
/// \throw Error for an empty or invalid base, non-triangle topology OpenSubdiv rejects, options out
/// of range, or a result above 2^31 - 1 vertices or faces.
Terrain generate_terrain(const Mesh& base, const TerrainOptions& options = {});

struct TerrainWriteStats {
  std::int64_t vertices = 0, faces = 0, bytes = 0;
};

/// Writes the terrain as binary little-endian PLY (float32 positions, per-face uchar colours) while
/// generating it, without holding the mesh: memory is about one byte per face plus the coarse levels.
/// Atomic: temporary file, then rename. Same vertices and faces, in the same order, as
/// generate_terrain().
TerrainWriteStats write_terrain_ply(const Mesh& base, const TerrainOptions& options,
                                    const std::filesystem::path& path);

}  // namespace lodkit
