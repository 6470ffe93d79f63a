#include <lodkit/error.h>
#include <lodkit/primitives.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <fmt/format.h>
#include <numbers>
#include <optional>
#include <vector>

#include "core/geometry.h"

namespace lodkit {
namespace {

constexpr double kPi = std::numbers::pi;

class MeshBuilder {
 public:
  Index vertex(double x, double y, double z) {
    xyz_.insert(xyz_.end(), {x, y, z});
    return static_cast<Index>(xyz_.size() / 3 - 1);
  }
  void uv(double u, double v) { uv_.insert(uv_.end(), {u, v}); }
  void triangle(Index a, Index b, Index c) { tri_.insert(tri_.end(), {a, b, c}); }
  void quad(Index a, Index b, Index c, Index d) {  // CCW a b c d
    triangle(a, b, c);
    triangle(a, c, d);
  }
  Mesh build() const {
    Mesh m;
    const auto nv = static_cast<Index>(xyz_.size() / 3);
    m.positions = Eigen::Map<const Positions>(xyz_.data(), nv, 3);
    m.triangles = Eigen::Map<const Triangles>(tri_.data(), static_cast<Index>(tri_.size() / 3), 3);
    if (!uv_.empty()) m.attributes.uvs = Eigen::Map<const TexCoords>(uv_.data(), nv, 2);
    return m;
  }

 private:
  std::vector<double> xyz_, uv_;
  std::vector<Index> tri_;
};

void require(bool ok, const char* shape, const std::string& what) {
  if (!ok) throw Error(fmt::format("{}: {}", shape, what));
}
void require_positive(double v, const char* shape, const char* name) {
  require(std::isfinite(v) && v > 0, shape, fmt::format("{} must be positive, got {}", name, v));
}
void require_count(int n, int minimum, const char* shape, const char* name) {
  require(n >= minimum && n <= 1 << 16, shape,
          fmt::format("{} must be between {} and 65536, got {}", name, minimum, n));
}
// Counts are checked one at a time, so their product may still be more than memory (or a face index)
// holds: a box of 65536 divisions would be 51.5 billion faces.
void require_faces(std::int64_t faces, const char* shape, const std::string& how) {
  require(faces <= kMostPrimitiveFaces, shape,
          fmt::format("{} make {} faces, more than the {} a generated mesh may have", how, faces, kMostPrimitiveFaces));
}

// The largest gap between a sphere of `radius` about the origin and a triangle: every point of the
// sphere is at most this far from a closed mesh that is star-shaped about the origin.
double sphere_gap(double radius, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                  const Eigen::Vector3d& c) {
  return radius - detail::closest_point_on_triangle(Eigen::Vector3d::Zero(), a, b, c).norm();
}

Eigen::Vector3d on_sphere(double radius, int ring, int rings, int segment, int segments) {
  const double theta = kPi * ring / rings;
  const double phi = 2 * kPi * (segment % segments) / segments;
  if (ring == 0) return {0, 0, radius};
  if (ring == rings) return {0, 0, -radius};
  return {radius * std::sin(theta) * std::cos(phi), radius * std::sin(theta) * std::sin(phi),
          radius * std::cos(theta)};
}

}  // namespace

double circle_chordal_error(double radius, int segments) {
  return radius * (1.0 - std::cos(kPi / segments));
}

namespace {

constexpr int kMostSegments = 1 << 16;

// The fewest segments within `tolerance` (positive), or none past kMostSegments. The estimate is
// infinite where tolerance / radius vanishes next to 1 (a radius of 4e59 cast it to int: undefined
// behaviour, found by fuzzing CSG trees), so it is checked as a double first.
std::optional<int> fewest_segments(double radius, double tolerance) {
  if (tolerance >= radius) return 3;
  const double estimate = std::ceil(kPi / std::acos(1.0 - tolerance / radius));
  if (!(estimate <= 2.0 * kMostSegments)) return std::nullopt;
  int n = std::max(static_cast<int>(estimate), 3);
  while (n > 3 && circle_chordal_error(radius, n - 1) <= tolerance) --n;  // guard rounding
  while (n <= kMostSegments && circle_chordal_error(radius, n) > tolerance) ++n;
  if (n > kMostSegments) return std::nullopt;
  return n;
}

std::string too_fine(double tolerance, double radius, const char* share = "") {
  return fmt::format("tolerance {} is too fine: a circle of radius {} would need more than 65,536 segments{}", tolerance,
                     radius, share);
}

}  // namespace

int circle_segments_for_tolerance(double radius, double tolerance, const char* shape) {
  require_positive(tolerance, shape, "tolerance");
  const std::optional<int> n = fewest_segments(radius, tolerance);
  require(n.has_value(), shape, too_fine(tolerance, radius));
  return *n;
}

double uv_sphere_chordal_error(double radius, int segments, int rings) {
  // By symmetry one quad per band between two rings decides the bound.
  double worst = 0.0;
  for (int i = 0; i < rings; ++i) {
    const Eigen::Vector3d a = on_sphere(radius, i, rings, 0, segments),
                          b = on_sphere(radius, i + 1, rings, 0, segments),
                          c = on_sphere(radius, i + 1, rings, 1, segments),
                          d = on_sphere(radius, i, rings, 1, segments);
    if (i == 0) {
      worst = std::max(worst, sphere_gap(radius, a, b, c));  // north cap triangle
    } else if (i + 1 == rings) {
      worst = std::max(worst, sphere_gap(radius, a, b, d));  // south cap triangle
    } else {
      worst = std::max({worst, sphere_gap(radius, a, b, c), sphere_gap(radius, a, c, d)});
    }
  }
  return worst;
}

double torus_chordal_error(double major_radius, double minor_radius, int major_segments,
                           int minor_segments) {
  // The mesh is a polygonal tube around a polygonal core circle: the two sagittas add.
  return circle_chordal_error(major_radius + minor_radius, major_segments) +
         circle_chordal_error(minor_radius, minor_segments);
}

Mesh make_box(const BoxOptions& o) {
  for (int k = 0; k < 3; ++k) require_positive(o.size[k], "box", "size");
  require_count(o.divisions, 1, "box", "divisions");
  require_faces(12 * std::int64_t{o.divisions} * o.divisions, "box", fmt::format("{} divisions", o.divisions));
  const int d = o.divisions;
  // Lattice coordinate k/d along each axis, so shared edges of neighbouring faces get identical
  // positions and weld exactly.
  auto coord = [&](int axis, int k) { return o.size[axis] * (static_cast<double>(k) / d - 0.5); };
  MeshBuilder b;
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;  // u x v = +axis
      std::vector<Index> ids((d + 1) * (d + 1));
      for (int j = 0; j <= d; ++j)
        for (int i = 0; i <= d; ++i) {
          double p[3];
          p[axis] = side ? o.size[axis] / 2 : -o.size[axis] / 2;
          p[u] = coord(u, i);
          p[v] = coord(v, j);
          ids[j * (d + 1) + i] = b.vertex(p[0], p[1], p[2]);
        }
      for (int j = 0; j < d; ++j)
        for (int i = 0; i < d; ++i) {
          const Index a = ids[j * (d + 1) + i], bb = ids[j * (d + 1) + i + 1],
                      c = ids[(j + 1) * (d + 1) + i + 1], dd = ids[(j + 1) * (d + 1) + i];
          if (side) b.quad(a, bb, c, dd);
          else b.quad(a, dd, c, bb);
        }
    }
  Mesh mesh = b.build();
  weld_identical_vertices(mesh);
  return mesh;
}

Mesh make_uv_sphere(const UvSphereOptions& o) {
  require_positive(o.radius, "sphere", "radius");
  int segments = o.segments, rings = o.rings;
  if (o.tolerance) {
    require_positive(*o.tolerance, "sphere", "tolerance");
    rings = 2;
    while (uv_sphere_chordal_error(o.radius, 2 * rings, rings) > *o.tolerance) {
      ++rings;
      require(4 * std::int64_t{rings} * (rings - 1) <= kMostPrimitiveFaces, "sphere",
              fmt::format("tolerance too small: it needs more than the {} faces a generated mesh may have",
                          kMostPrimitiveFaces));
    }
    segments = 2 * rings;
  }
  require_count(segments, 3, "sphere", "segments");
  require_count(rings, 2, "sphere", "rings");
  require_faces(2 * std::int64_t{segments} * (rings - 1), "sphere", fmt::format("{} segments and {} rings", segments, rings));
  MeshBuilder b;
  if (!o.uvs) {
    const Index north = b.vertex(0, 0, o.radius);
    for (int i = 1; i < rings; ++i)
      for (int j = 0; j < segments; ++j) {
        const Eigen::Vector3d p = on_sphere(o.radius, i, rings, j, segments);
        b.vertex(p.x(), p.y(), p.z());
      }
    const Index south = b.vertex(0, 0, -o.radius);
    auto at = [&](int i, int j) { return 1 + (i - 1) * segments + (j % segments); };
    for (int j = 0; j < segments; ++j) {
      b.triangle(north, at(1, j), at(1, j + 1));
      for (int i = 1; i + 1 < rings; ++i) b.quad(at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
      b.triangle(south, at(rings - 1, j + 1), at(rings - 1, j));
    }
    return b.build();
  }
  // With UVs: rings - 1 rows of segments + 1 vertices (the u = 0 and u = 1 columns are a seam),
  // plus one pole vertex per segment at each end, with u at the middle of its segment.
  const Index first_row = segments;  // index of the first vertex of ring 1
  auto at = [&](int i, int j) -> Index {
    if (i == 0) return j;
    if (i == rings) return first_row + (rings - 1) * (segments + 1) + j;
    return first_row + (i - 1) * (segments + 1) + j;
  };
  for (int i = 0; i <= rings; ++i) {
    const bool pole = i == 0 || i == rings;
    for (int j = 0; j < (pole ? segments : segments + 1); ++j) {
      const Eigen::Vector3d p = on_sphere(o.radius, i, rings, j, segments);
      b.vertex(p.x(), p.y(), p.z());
      b.uv((j + (pole ? 0.5 : 0.0)) / segments, 1.0 - static_cast<double>(i) / rings);
    }
  }
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      if (i == 0) b.triangle(at(0, j), at(1, j), at(1, j + 1));
      else if (i == rings - 1) b.triangle(at(i, j), at(i + 1, j), at(i, j + 1));
      else b.quad(at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
    }
  return b.build();
}

namespace {

double icosphere_error(const Mesh& m, double radius) {
  double worst = 0.0;
  for (Index f = 0; f < m.num_faces(); ++f) {
    const auto t = m.triangles.row(f);
    worst = std::max(worst, sphere_gap(radius, m.positions.row(t[0]), m.positions.row(t[1]),
                                       m.positions.row(t[2])));
  }
  return worst;
}

Mesh subdivide_on_sphere(const Mesh& in, double radius) {
  // Each edge gets one midpoint, shared by both faces (keyed by its sorted endpoints).
  std::vector<std::vector<std::pair<Index, Index>>> mid(static_cast<std::size_t>(in.num_vertices()));
  std::vector<double> xyz(in.positions.data(), in.positions.data() + in.positions.size());
  auto midpoint = [&](Index a, Index b) {
    if (a > b) std::swap(a, b);
    for (auto [other, id] : mid[a])
      if (other == b) return id;
    Eigen::Vector3d p = 0.5 * (in.positions.row(a) + in.positions.row(b)).transpose();
    p *= radius / p.norm();
    const auto id = static_cast<Index>(xyz.size() / 3);
    xyz.insert(xyz.end(), {p.x(), p.y(), p.z()});
    mid[a].push_back({b, id});
    return id;
  };
  std::vector<Index> tri;
  for (Index f = 0; f < in.num_faces(); ++f) {
    const Index a = in.triangles(f, 0), b = in.triangles(f, 1), c = in.triangles(f, 2);
    const Index ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
    tri.insert(tri.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
  }
  Mesh out;
  out.positions = Eigen::Map<const Positions>(xyz.data(), static_cast<Index>(xyz.size() / 3), 3);
  out.triangles = Eigen::Map<const Triangles>(tri.data(), static_cast<Index>(tri.size() / 3), 3);
  return out;
}

}  // namespace

Mesh make_icosphere(const IcosphereOptions& o) {
  require_positive(o.radius, "icosphere", "radius");
  if (!o.tolerance) require(o.subdivisions >= 0 && o.subdivisions <= 10, "icosphere",
                            fmt::format("subdivisions must be 0 to 10, got {}", o.subdivisions));
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  const double s = o.radius / std::sqrt(1.0 + t * t);
  MeshBuilder b;
  const double v[12][3] = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                           {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (const auto& p : v) b.vertex(s * p[0], s * p[1], s * p[2]);
  const int f[20][3] = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11},
                        {1, 5, 9}, {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                        {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8}, {3, 8, 9},
                        {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  for (const auto& tri : f) b.triangle(tri[0], tri[1], tri[2]);
  Mesh mesh = b.build();
  if (o.tolerance) {
    require_positive(*o.tolerance, "icosphere", "tolerance");
    while (icosphere_error(mesh, o.radius) > *o.tolerance) {
      require(mesh.num_faces() < 20 * (1 << 20), "icosphere", "tolerance too small");
      mesh = subdivide_on_sphere(mesh, o.radius);
    }
    return mesh;
  }
  for (int level = 0; level < o.subdivisions; ++level) mesh = subdivide_on_sphere(mesh, o.radius);
  return mesh;
}

Mesh make_cylinder(const CylinderOptions& o) {
  require_positive(o.radius, "cylinder", "radius");
  require_positive(o.height, "cylinder", "height");
  const int n = o.tolerance ? circle_segments_for_tolerance(o.radius, *o.tolerance, "cylinder") : o.segments;
  require_count(n, 3, "cylinder", "segments");
  require_count(o.stacks, 1, "cylinder", "stacks");
  require_faces(std::int64_t{n} * (2 * std::int64_t{o.stacks} + 2), "cylinder",
                fmt::format("{} segments and {} stacks", n, o.stacks));
  MeshBuilder b;
  const double h = o.height;
  for (int i = 0; i <= o.stacks; ++i) {
    const double z = h * (static_cast<double>(i) / o.stacks - 0.5);
    for (int j = 0; j < n; ++j) {
      const double phi = 2 * kPi * j / n;
      b.vertex(o.radius * std::cos(phi), o.radius * std::sin(phi), z);
    }
  }
  auto at = [&](int i, int j) { return i * n + (j % n); };
  const Index bottom = b.vertex(0, 0, -h / 2), top = b.vertex(0, 0, h / 2);
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < o.stacks; ++i) b.quad(at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i + 1, j));
    b.triangle(bottom, at(0, j + 1), at(0, j));
    b.triangle(top, at(o.stacks, j), at(o.stacks, j + 1));
  }
  return b.build();
}

Mesh make_cone(const ConeOptions& o) {
  require_positive(o.radius, "cone", "radius");
  require_positive(o.height, "cone", "height");
  const int n = o.tolerance ? circle_segments_for_tolerance(o.radius, *o.tolerance, "cone") : o.segments;
  require_count(n, 3, "cone", "segments");
  MeshBuilder b;
  for (int j = 0; j < n; ++j) {
    const double phi = 2 * kPi * j / n;
    b.vertex(o.radius * std::cos(phi), o.radius * std::sin(phi), -o.height / 2);
  }
  const Index apex = b.vertex(0, 0, o.height / 2), centre = b.vertex(0, 0, -o.height / 2);
  for (int j = 0; j < n; ++j) {
    b.triangle(j, (j + 1) % n, apex);
    b.triangle(centre, (j + 1) % n, j);
  }
  return b.build();
}

Mesh make_torus(const TorusOptions& o) {
  require_positive(o.major_radius, "torus", "major radius");
  require_positive(o.minor_radius, "torus", "minor radius");
  require(o.minor_radius < o.major_radius, "torus", "minor radius must be smaller than major radius");
  int nu = o.major_segments, nv = o.minor_segments;
  if (o.tolerance) {
    const double t = *o.tolerance;
    require_positive(t, "torus", "tolerance");
    // Split the budget evenly, then coarsen each direction while the bound still holds. (The
    // message names the tolerance asked for, not its half.)
    const double outer = o.major_radius + o.minor_radius;
    const std::optional<int> around = fewest_segments(outer, t / 2), across = fewest_segments(o.minor_radius, t / 2);
    require(around && across, "torus", too_fine(t, around ? o.minor_radius : outer, " for half of it"));
    nu = *around;
    nv = *across;
    while (nu > 3 && torus_chordal_error(o.major_radius, o.minor_radius, nu - 1, nv) <= t) --nu;
    while (nv > 3 && torus_chordal_error(o.major_radius, o.minor_radius, nu, nv - 1) <= t) --nv;
  }
  require_count(nu, 3, "torus", "major segments");
  require_count(nv, 3, "torus", "minor segments");
  require_faces(2 * std::int64_t{nu} * nv, "torus", fmt::format("{} by {} segments", nu, nv));
  MeshBuilder b;
  const int cu = o.uvs ? nu + 1 : nu, cv = o.uvs ? nv + 1 : nv;
  for (int i = 0; i < cu; ++i)
    for (int j = 0; j < cv; ++j) {
      const double phi = 2 * kPi * (i % nu) / nu, theta = 2 * kPi * (j % nv) / nv;
      const double ring = o.major_radius + o.minor_radius * std::cos(theta);
      b.vertex(ring * std::cos(phi), ring * std::sin(phi), o.minor_radius * std::sin(theta));
      if (o.uvs) b.uv(static_cast<double>(i) / nu, static_cast<double>(j) / nv);
    }
  auto at = [&](int i, int j) { return o.uvs ? i * cv + j : (i % nu) * nv + (j % nv); };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) b.quad(at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
  return b.build();
}

Mesh make_grid(const GridOptions& o) {
  require_positive(o.size.x(), "grid", "size x");
  require_positive(o.size.y(), "grid", "size y");
  require_count(o.divisions_x, 1, "grid", "divisions x");
  require_count(o.divisions_y, 1, "grid", "divisions y");
  require_faces(2 * std::int64_t{o.divisions_x} * o.divisions_y, "grid",
                fmt::format("{} by {} divisions", o.divisions_x, o.divisions_y));
  MeshBuilder b;
  const int nx = o.divisions_x, ny = o.divisions_y;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      const double u = static_cast<double>(i) / nx, v = static_cast<double>(j) / ny;
      b.vertex(o.size.x() * (u - 0.5), o.size.y() * (v - 0.5), 0.0);
      if (o.uvs) b.uv(u, v);
    }
  auto at = [&](int i, int j) { return j * (nx + 1) + i; };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) b.quad(at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
  return b.build();
}

Mesh make_square_pyramid(const PyramidOptions& o) {
  require_positive(o.base, "pyramid", "base");
  require_positive(o.height, "pyramid", "height");
  const double s = o.base / 2;
  MeshBuilder b;
  const Index p0 = b.vertex(-s, -s, 0), p1 = b.vertex(s, -s, 0), p2 = b.vertex(s, s, 0),
              p3 = b.vertex(-s, s, 0), apex = b.vertex(0, 0, o.height);
  b.quad(p0, p3, p2, p1);  // base, facing -z
  b.triangle(p0, p1, apex);
  b.triangle(p1, p2, apex);
  b.triangle(p2, p3, apex);
  b.triangle(p3, p0, apex);
  return b.build();
}

}  // namespace lodkit
