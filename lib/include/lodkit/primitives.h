#pragma once
// Primitive solids and surfaces, z up, centred on the origin unless stated.
//
// Closed primitives are 2-manifold and oriented outward (positive volume). Curved ones take their
// resolution either as segment counts or as a chordal `tolerance`: the coarsest tessellation such that
// no point of the true surface is farther than `tolerance` from the mesh (bounds in primitives.cpp).
// A given tolerance overrides the segment counts.
#include <lodkit/mesh.h>

#include <cstdint>
#include <optional>

namespace lodkit {

/// The most faces a generated primitive may have (about 6.5 GB while it is built): each count is
/// checked on its own (segments, divisions: 65536 at most), and this bounds their product.
inline constexpr std::int64_t kMostPrimitiveFaces = std::int64_t{1} << 27;

struct BoxOptions {
  Eigen::Vector3d size{1.0, 1.0, 1.0};
  int divisions = 1;  ///< each face is a divisions x divisions grid of quads (2 triangles each)
};

struct UvSphereOptions {
  double radius = 1.0;
  int segments = 32;  ///< around the z axis
  int rings = 16;     ///< pole to pole
  std::optional<double> tolerance{};
  bool uvs = false;   ///< equirectangular UVs; the u = 0/1 seam and the poles become split vertices
};

struct IcosphereOptions {
  double radius = 1.0;
  int subdivisions = 3;  ///< 20 * 4^subdivisions faces
  std::optional<double> tolerance{};
};

struct CylinderOptions {
  double radius = 1.0;
  double height = 2.0;  ///< from z = -height/2 to +height/2
  int segments = 32;
  int stacks = 1;
  std::optional<double> tolerance{};
};

struct ConeOptions {
  double radius = 1.0;  ///< of the base at z = -height/2; apex at z = +height/2
  double height = 2.0;
  int segments = 32;
  std::optional<double> tolerance{};
};

struct TorusOptions {
  double major_radius = 1.0;  ///< centre of the tube to the z axis
  double minor_radius = 0.25; ///< radius of the tube
  int major_segments = 48;
  int minor_segments = 16;
  std::optional<double> tolerance{};
  bool uvs = false;
};

struct GridOptions {
  Eigen::Vector2d size{1.0, 1.0};  ///< in x and y, at z = 0, facing +z
  int divisions_x = 10;
  int divisions_y = 10;
  bool uvs = false;
};

struct PyramidOptions {
  double base = 1.0;    ///< side of the square base at z = 0
  double height = 1.0;  ///< apex at (0, 0, height)
};

Mesh make_box(const BoxOptions& options = {});
Mesh make_uv_sphere(const UvSphereOptions& options = {});
Mesh make_icosphere(const IcosphereOptions& options = {});
Mesh make_cylinder(const CylinderOptions& options = {});
Mesh make_cone(const ConeOptions& options = {});
Mesh make_torus(const TorusOptions& options = {});
Mesh make_grid(const GridOptions& options = {});
Mesh make_square_pyramid(const PyramidOptions& options = {});

/// Fewest segments of a circle of `radius` whose sagitta r (1 - cos(pi / n)) is at most `tolerance`
/// (at least 3). \throw Error "<shape>: ..." if tolerance is not positive or needs more than 65,536.
int circle_segments_for_tolerance(double radius, double tolerance, const char* shape = "circle");

/// Upper bounds of the distance from the true surface to the tessellation, for reporting.
double uv_sphere_chordal_error(double radius, int segments, int rings);
double circle_chordal_error(double radius, int segments);
double torus_chordal_error(double major_radius, double minor_radius, int major_segments,
                           int minor_segments);

}  // namespace lodkit
