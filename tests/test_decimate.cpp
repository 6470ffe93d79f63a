// Schroeder vertex decimation: exact answers on hand-built meshes, invariants on families.
#include <gtest/gtest.h>
#include <lodkit/decimate.h>
#include <lodkit/error.h>
#include <lodkit/inspect.h>
#include <lodkit/metrics.h>
#include <lodkit/primitives.h>

#include <random>

#include "test_util.h"

namespace lodkit {
namespace {

enum { kSimple, kComplex, kBoundary, kInteriorEdge, kCorner };

TEST(Decimate, ClassCountsOnHandBuiltMeshesAreExact) {
  // A cube split 2 x 2 per face: 8 corners, 12 edge midpoints on feature lines, 6 face centres.
  const auto cube = count_vertex_classes(make_box({.divisions = 2}));
  EXPECT_EQ(cube, (std::array<Index, 5>{6, 0, 0, 12, 8}));
  // A flat 2 x 2 grid: the centre is simple, the 8 others on the boundary.
  const auto grid = count_vertex_classes(make_grid({.divisions_x = 2, .divisions_y = 2}));
  EXPECT_EQ(grid, (std::array<Index, 5>{1, 0, 8, 0, 0}));
  // A bow tie: two triangles sharing only vertex 0, which is complex.
  Mesh bow;
  bow.positions.resize(5, 3);
  bow.positions << 0, 0, 0, 1, 0, 0, 1, 1, 0, -1, 0, 0, -1, -1, 0;
  bow.triangles.resize(2, 3);
  bow.triangles << 0, 1, 2, 0, 3, 4;
  EXPECT_EQ(count_vertex_classes(bow), (std::array<Index, 5>{0, 1, 4, 0, 0}));
  // A square pyramid: the apex has four feature edges (a corner), as do the base corners.
  EXPECT_EQ(count_vertex_classes(make_square_pyramid({})), (std::array<Index, 5>{0, 0, 0, 0, 5}));
}

TEST(Decimate, FlatGridBecomesTwoTrianglesOnItsCornersWithZeroError) {
  const Mesh grid = make_grid({.size = {3, 2}, .divisions_x = 24, .divisions_y = 16});
  const DecimateResult r = decimate(grid, {.max_error = 1e-9});
  EXPECT_EQ(r.faces_out, 2);
  EXPECT_EQ(r.error, 0.0);
  ASSERT_EQ(r.mesh.num_vertices(), 4);
  for (Index v = 0; v < 4; ++v) {
    EXPECT_EQ(std::abs(r.mesh.positions(v, 0)), 1.5);
    EXPECT_EQ(std::abs(r.mesh.positions(v, 1)), 1.0);
  }
  EXPECT_NEAR(inspect(r.mesh).area, 6.0, 1e-12);
}

TEST(Decimate, FineCubeKeepsItsCornersAndFeatureEdgesExactly) {
  const Mesh cube = make_box({.size = {2, 1, 1}, .divisions = 8});
  const DecimateResult r = decimate(cube, {.max_error = 1e-9});
  EXPECT_EQ(r.faces_out, 12);
  ASSERT_EQ(r.mesh.num_vertices(), 8);
  for (Index v = 0; v < 8; ++v) {
    EXPECT_EQ(std::abs(r.mesh.positions(v, 0)), 1.0);
    EXPECT_EQ(std::abs(r.mesh.positions(v, 1)), 0.5);
    EXPECT_EQ(std::abs(r.mesh.positions(v, 2)), 0.5);
  }
  // 18 edges: the 12 feature edges of the box plus one diagonal per face.
  const MeshReport rep = inspect(r.mesh);
  EXPECT_EQ(rep.edges, 18);
  EXPECT_NEAR(*rep.volume, 2.0, 1e-12);
  EXPECT_EQ(count_vertex_classes(r.mesh)[kCorner], 8);
}

// An open mesh: the upper half of a UV sphere (one circular boundary).
Mesh dome() {
  const Mesh s = make_uv_sphere({.segments = 48, .rings = 24});
  Mesh m = s;
  Index kept = 0;
  for (Index f = 0; f < s.num_faces(); ++f) {
    bool upper = true;
    for (int k = 0; k < 3; ++k) upper &= s.positions(s.triangles(f, k), 2) >= -1e-12;
    if (upper) m.triangles.row(kept++) = s.triangles.row(f);
  }
  m.triangles.conservativeResize(kept, 3);
  remove_unreferenced_vertices(m);
  return m;
}

TEST(Decimate, OutputsStayManifoldUnflippedWithTheSameEulerCharacteristic) {
  const std::vector<std::pair<std::string, Mesh>> family{
      {"bumpy_sphere", test::bumpy_sphere(4, 0.01, 11)},
      {"torus", make_torus({.major_segments = 64, .minor_segments = 24})},
      {"dome", dome()},
      {"cylinder", make_cylinder({.segments = 48, .stacks = 10})}};
  for (const auto& [name, mesh] : family) {
    SCOPED_TRACE(name);
    const MeshReport before = inspect(mesh);
    for (double ratio : {0.5, 0.2, 0.05}) {
      SCOPED_TRACE(ratio);
      const DecimateResult r = decimate(mesh, {.target_ratio = ratio});
      validate(r.mesh);
      const MeshReport after = inspect(r.mesh);
      EXPECT_TRUE(after.manifold);
      EXPECT_TRUE(after.oriented);
      EXPECT_EQ(after.euler_characteristic, before.euler_characteristic);
      EXPECT_EQ(after.boundary_loops, before.boundary_loops);
      EXPECT_EQ(after.degenerate_faces, 0);
      EXPECT_EQ(after.duplicate_faces, 0);
      EXPECT_LT(r.faces_out, mesh.num_faces());
      if (after.volume) {
        EXPECT_GT(*after.volume, 0.0);
      }
      EXPECT_EQ(count_flipped_faces(mesh, r.mesh), 0);
    }
  }
}

// The paper's checks (each new face against the star's plane, its corners against their input normals)
// let a fold through on a noisy sphere: a face turned 121 degrees from the input face nearest it. Such
// removals are refused by default, and the output then has none.
TEST(Decimate, RefusesRemovalsThatLeaveAFaceFacingAgainstTheInput) {
  const Mesh noisy = test::bumpy_sphere(4, 0.03);
  DecimateOptions paper{.target_ratio = 0.1};
  paper.inverted_faces = InvertedFaces::Allow;
  EXPECT_GT(count_flipped_faces(noisy, decimate(noisy, paper).mesh), 0);
  const DecimateResult r = decimate(noisy, {.target_ratio = 0.1});
  EXPECT_EQ(count_flipped_faces(noisy, r.mesh), 0);
  EXPECT_FALSE(r.inverted_allowed_at);
  // Avoid lets such a removal be once the pass's threshold is twice its error, and says from where.
  DecimateOptions avoid{.target_ratio = 0.1};
  avoid.inverted_faces = InvertedFaces::Avoid;
  const DecimateResult waited = decimate(noisy, avoid);
  if (count_flipped_faces(noisy, waited.mesh) > 0) {
    EXPECT_TRUE(waited.inverted_allowed_at);
  }
  const MeshReport after = inspect(r.mesh);
  EXPECT_TRUE(after.closed && after.manifold);
  EXPECT_EQ(after.euler_characteristic, 2);
}

TEST(Decimate, OpenMeshKeepsItsBoundaryWithinTheAccumulatedBound) {
  const Mesh m = dome();
  const double t = 0.03;
  const DecimateResult r = decimate(m, {.max_error = t, .accumulate_error = true});
  EXPECT_LE(r.error, t);
  EXPECT_LT(r.faces_out, 2 * m.num_faces() / 3);
  // Every input boundary vertex (z = 0) is within the bound of the output's boundary polyline.
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> boundary;
  for (Index f = 0; f < r.mesh.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d a = r.mesh.positions.row(r.mesh.triangles(f, k)),
                            b = r.mesh.positions.row(r.mesh.triangles(f, (k + 1) % 3));
      if (std::abs(a.z()) < 1e-12 && std::abs(b.z()) < 1e-12) boundary.push_back({a, b});
    }
  ASSERT_FALSE(boundary.empty());
  for (Index v = 0; v < m.num_vertices(); ++v) {
    if (std::abs(m.positions(v, 2)) > 1e-12) continue;
    const Eigen::Vector3d p = m.positions.row(v);
    double best = INFINITY;
    for (const auto& [a, b] : boundary) {
      const double t01 = std::clamp((p - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
      best = std::min(best, (a + t01 * (b - a) - p).norm());
    }
    EXPECT_LE(best, r.error + 1e-12) << "boundary vertex " << v;
  }
  EXPECT_LE(compare(m, r.mesh).a_to_b.max, t * 1.5);
}

TEST(Decimate, ReportsWhyItStops) {
  const DecimateResult r = decimate(make_box({.divisions = 4}), {.target_faces = 4});
  EXPECT_FALSE(r.target_reached);
  EXPECT_EQ(r.faces_out, 12);
  EXPECT_EQ(r.remaining_by_class[kCorner], 8);
  EXPECT_NE(r.reason_text.find("8 corner"), std::string::npos) << r.reason_text;
}

TEST(Decimate, CarriesColoursAndSmoothNormalsAndFitsThem) {
  // Vertices are welded by position, so an output vertex takes the first input vertex's values there;
  // the fit then brings them nearer the input's. A painted sphere with smooth normals keeps both; a
  // box with a normal per side (hard edges, several normals at a position) keeps no normals; off,
  // positions only.
  Mesh sphere = test::bumpy_sphere(4, 0.01);
  sphere.attributes.normals = compute_vertex_normals(sphere);
  sphere.attributes.colours.resize(sphere.num_vertices(), 4);
  for (Index v = 0; v < sphere.num_vertices(); ++v)
    sphere.attributes.colours.row(v) << float(0.5 + 0.4 * sphere.positions(v, 0)), 0.3f, 0.2f, 1.0f;
  const DecimateResult r = decimate(sphere, {.target_ratio = 0.1});
  ASSERT_TRUE(r.attribute_fit && r.attribute_fit->normals && r.attribute_fit->colours);
  ASSERT_TRUE(r.mesh.has_normals() && r.mesh.has_colours());
  const Comparison c = compare(sphere, r.mesh);
  EXPECT_LT(*c.colour_rms, 0.01);
  EXPECT_LT(*c.shading_rms_deg, 5.0);
  for (Index v = 0; v < r.mesh.num_vertices(); ++v) EXPECT_NEAR(r.mesh.attributes.normals.row(v).norm(), 1.0, 1e-9);

  Mesh box = test::flat_shaded(make_box({.divisions = 4}));
  const DecimateResult hard = decimate(box, {.target_faces = 12});
  EXPECT_FALSE(hard.mesh.has_normals());
  EXPECT_FALSE(hard.attribute_fit);

  DecimateOptions off{.target_ratio = 0.1};
  off.fit_attributes = false;
  const DecimateResult plain = decimate(sphere, off);
  EXPECT_FALSE(plain.mesh.has_normals() || plain.mesh.has_colours() || plain.attribute_fit);
  EXPECT_EQ(plain.mesh.positions, r.mesh.positions);
  EXPECT_EQ(plain.mesh.triangles, r.mesh.triangles);
}

TEST(Decimate, KeepsUvSeamsAsFeatureLinesAndTheirUvsOnEachSide) {
  // A UV sphere's u = 0 / u = 1 seam runs pole to pole. Seam edges count as feature edges, so a vertex
  // on the seam goes only along it (the line split keeps it), and each side of the line takes its own
  // faces' UVs: no face straddles the seam, and every seam vertex has its twin across it.
  const Mesh sphere = make_uv_sphere({.segments = 64, .rings = 32, .uvs = true});
  const test::SeamTwins before = test::u_seam_twins(sphere);
  const DecimateResult r = decimate(sphere, {.target_ratio = 0.25});
  EXPECT_TRUE(r.target_reached) << r.reason_text;
  const Mesh& m = r.mesh;
  ASSERT_TRUE(m.has_uvs());
  ASSERT_TRUE(r.attribute_fit && r.attribute_fit->uvs);
  EXPECT_LT(test::widest_u_span(m), 0.5);
  const test::SeamTwins seam = test::u_seam_twins(m);
  EXPECT_GE(seam.seam, 2);
  EXPECT_LT(seam.seam, before.seam);  // some went, along the line
  EXPECT_EQ(seam.without_twin, 0);
  EXPECT_EQ(seam.with_more_twins, 0);
  const MeshReport report = inspect(m);
  EXPECT_TRUE(report.closed && report.manifold);
  EXPECT_EQ(report.euler_characteristic, 2);
  EXPECT_LT(*compare(sphere, m).uv_rms, 0.005);

  DecimateOptions off{.target_ratio = 0.25};
  off.fit_attributes = false;
  EXPECT_FALSE(decimate(sphere, off).mesh.has_uvs());
}

TEST(Decimate, HitsReachableTargetsAndRejectsBadOptions) {
  const Mesh m = test::bumpy_sphere(4, 0.005, 11);
  const DecimateResult r = decimate(m, {.target_faces = 1001});
  EXPECT_TRUE(r.target_reached) << r.reason_text;
  EXPECT_EQ(r.faces_out, 1000);  // closed: even face counts only, one below an odd target
  EXPECT_THROW(decimate(m, {.target_ratio = 2.0}), Error);
  EXPECT_THROW(decimate(m, {.max_error = -1.0}), Error);
  EXPECT_THROW(decimate(m, {.feature_angle_deg = 0.0}), Error);
}

}  // namespace
}  // namespace lodkit
