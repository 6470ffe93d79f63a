// Subdivision through OpenSubdiv: refined points against OpenSubdiv's own refinement stencils, limit
// points against its limit stencils (patch evaluation, an independent path), topology kept, UVs as
// face-varying data, quads recovered from files, the tolerance search, bad input.
#include <lodkit/error.h>
#include <lodkit/inspect.h>
#include <lodkit/io.h>
#include <lodkit/primitives.h>
#include <lodkit/subdivide.h>

#include <gtest/gtest.h>
#include <opensubdiv/far/stencilTable.h>
#include <opensubdiv/far/stencilTableFactory.h>
#include <opensubdiv/far/topologyDescriptor.h>
#include <opensubdiv/far/topologyRefinerFactory.h>

#include <memory>

#include "test_util.h"

namespace lodkit {
namespace {

namespace Far = OpenSubdiv::Far;
namespace Sdc = OpenSubdiv::Sdc;

/// The unit cube [-1, 1]^3 as six outward quads, stored the way the readers store polygons: fan
/// triangles plus the polygon sizes.
struct QuadMesh {
  Mesh mesh;
  std::vector<int> sizes;
  std::vector<int> corners;  // quads, for OpenSubdiv directly
};

QuadMesh quad_cube() {
  QuadMesh q;
  q.mesh.positions.resize(8, 3);
  q.mesh.positions << -1, -1, -1, 1, -1, -1, 1, 1, -1, -1, 1, -1, -1, -1, 1, 1, -1, 1, 1, 1, 1, -1, 1, 1;
  q.corners = {0, 3, 2, 1, 4, 5, 6, 7, 0, 1, 5, 4, 1, 2, 6, 5, 2, 3, 7, 6, 3, 0, 4, 7};
  q.mesh.triangles.resize(12, 3);
  for (int f = 0; f < 6; ++f) {
    const int* c = &q.corners[static_cast<std::size_t>(4 * f)];
    q.mesh.triangles.row(2 * f) << c[0], c[1], c[2];
    q.mesh.triangles.row(2 * f + 1) << c[0], c[2], c[3];
    q.sizes.push_back(4);
  }
  return q;
}

struct Point {
  double v[3];
  void Clear(void* = nullptr) { v[0] = v[1] = v[2] = 0; }
  void AddWithWeight(const Point& s, double w) {
    for (int k = 0; k < 3; ++k) v[k] += w * s.v[k];
  }
};

std::unique_ptr<Far::TopologyRefiner> make_refiner(const Mesh& mesh, const std::vector<int>& sizes,
                                                   const std::vector<int>& corners, Sdc::SchemeType scheme) {
  Far::TopologyDescriptor desc;
  desc.numVertices = mesh.num_vertices();
  desc.numFaces = static_cast<int>(sizes.size());
  desc.numVertsPerFace = sizes.data();
  desc.vertIndicesPerFace = corners.data();
  Sdc::Options sdc;
  sdc.SetVtxBoundaryInterpolation(Sdc::Options::VTX_BOUNDARY_EDGE_ONLY);
  using Factory = Far::TopologyRefinerFactory<Far::TopologyDescriptor>;
  return std::unique_ptr<Far::TopologyRefiner>(Factory::Create(desc, Factory::Options(scheme, sdc)));
}

std::vector<Point> control_points(const Mesh& mesh) {
  std::vector<Point> points(static_cast<std::size_t>(mesh.num_vertices()));
  for (Index v = 0; v < mesh.num_vertices(); ++v)
    for (int k = 0; k < 3; ++k) points[v].v[k] = mesh.positions(v, k);
  return points;
}

/// Largest distance from any expected point to its nearest mesh vertex, and from any vertex to its
/// nearest expected point: zero when the two point sets coincide.
double set_distance(const Mesh& mesh, const std::vector<Eigen::Vector3d>& expected) {
  double worst = 0;
  std::vector<double> nearest_to_vertex(static_cast<std::size_t>(mesh.num_vertices()), 1e300);
  for (const Eigen::Vector3d& p : expected) {
    double best = 1e300;
    for (Index v = 0; v < mesh.num_vertices(); ++v) {
      const double d = (mesh.positions.row(v).transpose() - p).norm();
      best = std::min(best, d);
      nearest_to_vertex[v] = std::min(nearest_to_vertex[v], d);
    }
    worst = std::max(worst, best);
  }
  for (double d : nearest_to_vertex) worst = std::max(worst, d);
  return worst;
}

/// A stencil table (refinement or limit) applied to the control mesh's positions.
template <typename Table>
std::vector<Eigen::Vector3d> applied(const Table& table, const Mesh& control) {
  const std::vector<Point> cvs = control_points(control);
  std::vector<Point> values(static_cast<std::size_t>(table.GetNumStencils()));
  table.UpdateValues(cvs.data(), values.data());
  std::vector<Eigen::Vector3d> out;
  for (const Point& p : values) out.emplace_back(p.v[0], p.v[1], p.v[2]);
  return out;
}

/// Limit positions at the (i / n, j / n) lattice of every ptex face (quads: the full square;
/// triangles: i + j <= n), from OpenSubdiv's limit stencils over an adaptively refined copy.
std::vector<Eigen::Vector3d> limit_lattice(const Mesh& control, const std::vector<int>& sizes,
                                           const std::vector<int>& corners, Sdc::SchemeType scheme, int n) {
  auto refiner = make_refiner(control, sizes, corners, scheme);
  refiner->RefineAdaptive(Far::TopologyRefiner::AdaptiveOptions(10));
  std::vector<std::vector<double>> s_values, t_values;
  Far::LimitStencilTableFactoryReal<double>::LocationArrayVec locations;
  for (std::size_t f = 0; f < sizes.size(); ++f) {
    std::vector<double> s, t;
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i)
        if (sizes[f] == 4 || i + j <= n) s.push_back(double(i) / n), t.push_back(double(j) / n);
    s_values.push_back(std::move(s));
    t_values.push_back(std::move(t));
  }
  for (std::size_t f = 0; f < sizes.size(); ++f) {
    Far::LimitStencilTableFactoryReal<double>::LocationArray a;
    a.ptexIdx = static_cast<int>(f);
    a.numLocations = static_cast<int>(s_values[f].size());
    a.s = s_values[f].data();
    a.t = t_values[f].data();
    locations.push_back(a);
  }
  Far::LimitStencilTableFactoryReal<double>::Options options;
  options.generate1stDerivatives = false;
  std::unique_ptr<const Far::LimitStencilTableReal<double>> table(
      Far::LimitStencilTableFactoryReal<double>::Create(*refiner, locations, nullptr, nullptr, options));
  return applied(*table, control);
}

/// Points of uniform level `levels` from OpenSubdiv's refinement stencils.
std::vector<Eigen::Vector3d> refined_points(const Mesh& control, const std::vector<int>& sizes,
                                            const std::vector<int>& corners, Sdc::SchemeType scheme, int levels) {
  auto refiner = make_refiner(control, sizes, corners, scheme);
  refiner->RefineUniform(Far::TopologyRefiner::UniformOptions(levels));
  Far::StencilTableFactoryReal<double>::Options options;
  options.generateIntermediateLevels = false;
  options.generateOffsets = true;
  std::unique_ptr<const Far::StencilTableReal<double>> table(
      Far::StencilTableFactoryReal<double>::Create(*refiner, options));
  return applied(*table, control);
}

TEST(Subdivide, CatmullClarkCubeMatchesOpenSubdivStencils) {
  const QuadMesh cube = quad_cube();
  SubdivideOptions o;
  o.scheme = SubdivisionScheme::CatmullClark;
  o.levels = 3;
  const SubdivideResult refined = subdivide(cube.mesh, o, cube.sizes);
  EXPECT_EQ(refined.mesh.num_faces(), 6 * 64 * 2);
  EXPECT_LT(set_distance(refined.mesh, refined_points(cube.mesh, cube.sizes, cube.corners, Sdc::SCHEME_CATMARK, 3)), 1e-12);
  o.limit = true;
  const SubdivideResult limit = subdivide(cube.mesh, o, cube.sizes);
  EXPECT_LT(set_distance(limit.mesh, limit_lattice(cube.mesh, cube.sizes, cube.corners, Sdc::SCHEME_CATMARK, 8)), 1e-9);
  const MeshReport report = inspect(limit.mesh);
  EXPECT_TRUE(report.closed);
  EXPECT_EQ(report.genus, 0);
}

TEST(Subdivide, LoopTetrahedronMatchesOpenSubdivStencils) {
  const Mesh tet = test::tetrahedron();
  std::vector<int> sizes(static_cast<std::size_t>(tet.num_faces()), 3);
  std::vector<int> corners(tet.triangles.data(), tet.triangles.data() + 3 * tet.num_faces());
  SubdivideOptions o;
  o.scheme = SubdivisionScheme::Loop;
  o.levels = 3;
  const SubdivideResult refined = subdivide(tet, o);
  EXPECT_EQ(refined.mesh.num_faces(), 4 * 64);
  EXPECT_LT(set_distance(refined.mesh, refined_points(tet, sizes, corners, Sdc::SCHEME_LOOP, 3)), 1e-12);
  o.limit = true;
  const SubdivideResult limit = subdivide(tet, o);
  EXPECT_LT(set_distance(limit.mesh, limit_lattice(tet, sizes, corners, Sdc::SCHEME_LOOP, 8)), 1e-9);
  EXPECT_TRUE(inspect(limit.mesh).closed);
}

TEST(Subdivide, KeepsTopologyAndShrinksTowardTheLimit) {
  TorusOptions t;
  t.major_segments = 12;
  t.minor_segments = 8;
  const Mesh torus = make_torus(t);
  for (SubdivisionScheme scheme : {SubdivisionScheme::Loop, SubdivisionScheme::CatmullClark, SubdivisionScheme::Bilinear}) {
    SubdivideOptions o;
    o.scheme = scheme;
    o.levels = 2;
    const Mesh out = subdivide(torus, o).mesh;
    const MeshReport r = inspect(out);
    EXPECT_TRUE(r.closed && r.oriented);
    EXPECT_EQ(r.genus, 1);
    if (scheme == SubdivisionScheme::Bilinear)
      EXPECT_NEAR(*r.volume, signed_volume(torus), 1e-9) << "bilinear refinement leaves the surface in place";
    else
      EXPECT_LT(*r.volume, signed_volume(torus)) << "smoothing a convex-ish polyhedron shrinks it";
  }
}

TEST(Subdivide, UvsAreFaceVaryingAndSeamsSurvive) {
  // Bilinear scheme, linear UVs on a flat grid: every UV is the planar map of its point.
  GridOptions g;
  g.divisions_x = g.divisions_y = 3;
  g.uvs = true;
  const Mesh grid = make_grid(g);
  SubdivideOptions o;
  o.scheme = SubdivisionScheme::Bilinear;
  o.levels = 2;
  o.uv_rule = UvRule::Linear;
  const Mesh flat = subdivide(grid, o).mesh;
  ASSERT_TRUE(flat.has_uvs());
  for (Index v = 0; v < flat.num_vertices(); ++v) {
    EXPECT_NEAR(flat.attributes.uvs(v, 0), flat.positions(v, 0) + 0.5, 1e-12);
    EXPECT_NEAR(flat.attributes.uvs(v, 1), flat.positions(v, 1) + 0.5, 1e-12);
  }
  // A UV sphere's seam: split vertices stay split (several UVs per position), the surface closed.
  UvSphereOptions s;
  s.segments = 12;
  s.rings = 6;
  s.uvs = true;
  const Mesh sphere = make_uv_sphere(s);
  o.scheme = SubdivisionScheme::Loop;
  o.uv_rule = UvRule::CornersOnly;
  const Mesh smooth = subdivide(sphere, o).mesh;
  const MeshReport r = inspect(smooth);
  EXPECT_TRUE(r.closed);
  EXPECT_GT(r.duplicate_positions, 0) << "the seam is still there";
  for (Index v = 0; v < smooth.num_vertices(); ++v) {
    EXPECT_GE(smooth.attributes.uvs(v, 0), -1e-12);
    EXPECT_LE(smooth.attributes.uvs(v, 0), 1 + 1e-12);
  }
}

TEST(Subdivide, ReadersKeepQuadsForCatmullClark) {
  test::ScratchDir dir("subdivide_quads");
  test::write_text(dir / "cube.obj",
                   "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n"
                   "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n");
  std::vector<int> sizes;
  ReadOptions read;
  read.polygon_sizes = &sizes;
  const Mesh obj = read_mesh(dir / "cube.obj", read);
  EXPECT_EQ(sizes, std::vector<int>(6, 4));
  write_mesh(obj, dir / "cube.off");
  read_mesh(dir / "cube.off", read);
  EXPECT_EQ(sizes, std::vector<int>(12, 3)) << "the writer stored triangles";
  SubdivideOptions o;
  o.scheme = SubdivisionScheme::CatmullClark;
  o.levels = 2;
  read_mesh(dir / "cube.obj", read);
  const QuadMesh cube = quad_cube();
  EXPECT_LT(set_distance(subdivide(obj, o, sizes).mesh, refined_points(cube.mesh, cube.sizes, cube.corners, Sdc::SCHEME_CATMARK, 2)),
            1e-12);
}

TEST(Subdivide, ToleranceStopsAtTheFirstLevelCloseToTheNext) {
  const Mesh ico = make_icosphere({.radius = 1.0, .subdivisions = 0});
  SubdivideOptions o;
  o.tolerance = 0.01;
  const SubdivideResult r = subdivide(ico, o);
  ASSERT_EQ(r.level_change.size(), static_cast<std::size_t>(r.levels) + 1);
  EXPECT_LE(r.level_change.back(), 0.01);
  for (int k = 0; k < r.levels; ++k) EXPECT_GT(r.level_change[static_cast<std::size_t>(k)], 0.01);
  EXPECT_EQ(r.mesh.num_faces(), 20 << (2 * r.levels));
  o.max_levels = 1;
  EXPECT_THROW(subdivide(ico, o), Error);
}

// Faces grow 4x a level, and refining holds about 260 bytes a face: levels that would pass max_faces
// are refused before any work, with the count they would make. The count is exact: Loop 20 x 4^L on
// an icosahedron; Catmull-Clark 6 quads x 4 corners, x 4^(L - 1) quads, x 2 triangles on a cube.
TEST(Subdivide, RefusesLevelsThatWouldPassTheFaceLimit) {
  const Mesh ico = make_icosphere({.radius = 1.0, .subdivisions = 0});
  SubdivideOptions o;
  o.levels = 3;
  o.max_faces = 20 * 64;
  EXPECT_EQ(subdivide(ico, o).mesh.num_faces(), 20 * 64);  // exactly at the limit
  o.max_faces = 20 * 64 - 1;
  try {
    subdivide(ico, o);
    ADD_FAILURE() << "3 levels of 1,280 faces passed a limit of 1,279";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("would make 1280 triangles"), std::string::npos) << e.what();
  }
  // The tolerance search stops at the limit too, rather than refine past it.
  o = {};
  o.tolerance = 1e-9;
  o.max_faces = 20 * 16;
  try {
    subdivide(ico, o);
    ADD_FAILURE() << "the tolerance search went past the limit";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("3 levels would make 1280 triangles"), std::string::npos) << e.what();
  }
  // A cube of 6 quads: 2 levels make 6 x 4 x 4 quads, 192 triangles.
  const std::vector<int> quads(6, 4);
  const Mesh cube = make_box({});
  o = {};
  o.scheme = SubdivisionScheme::CatmullClark;
  o.levels = 2;
  o.max_faces = 191;
  EXPECT_THROW(subdivide(cube, o, quads), Error);
  o.max_faces = 192;
  EXPECT_EQ(subdivide(cube, o, quads).mesh.num_faces(), 192);
  o.max_faces = 0;
  EXPECT_THROW(subdivide(cube, o, quads), Error);
}

TEST(Subdivide, BadInputIsRefused) {
  const Mesh ico = make_icosphere({.radius = 1.0, .subdivisions = 0});
  EXPECT_THROW(subdivide(Mesh{}, {}), Error);
  EXPECT_THROW(subdivide(ico, {.levels = 11}), Error);
  EXPECT_THROW(subdivide(ico, {.levels = -1}), Error);
  SubdivideOptions o;
  o.tolerance = -1.0;
  EXPECT_THROW(subdivide(ico, o), Error);
  o = {};
  o.scheme = SubdivisionScheme::CatmullClark;
  const std::vector<int> wrong{4, 4};
  EXPECT_THROW(subdivide(ico, o, wrong), Error);
  Mesh nan_mesh = ico;
  nan_mesh.positions(0, 0) = std::nan("");
  EXPECT_THROW(subdivide(nan_mesh, {}), Error);
}

}  // namespace
}  // namespace lodkit
