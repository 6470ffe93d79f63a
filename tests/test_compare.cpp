#include <gtest/gtest.h>
#include <lodkit/error.h>
#include <lodkit/metrics.h>
#include <lodkit/primitives.h>

#include <tbb/global_control.h>

namespace lodkit {
namespace {

TEST(Compare, IdenticalMeshesAreZeroApart) {
  const Mesh m = make_torus({.major_segments = 24, .minor_segments = 12});
  const Comparison c = compare(m, m);
  EXPECT_NEAR(c.hausdorff, 0.0, 1e-12);
  EXPECT_NEAR(c.rms, 0.0, 1e-12);
  EXPECT_NEAR(c.a_to_b.normal_deviation_max_deg, 0.0, 1e-6);
  EXPECT_GE(c.a_to_b.samples, 10 * m.num_faces());
}

TEST(Compare, PlaneAndDisplacedPlane) {
  const Mesh a = make_grid({.size = {2, 1}, .divisions_x = 8, .divisions_y = 4});
  Mesh b = a;
  b.positions.col(2).array() += 0.05;
  const Comparison c = compare(a, b);
  EXPECT_NEAR(c.hausdorff, 0.05, 1e-12);
  EXPECT_NEAR(c.mean, 0.05, 1e-12);
  EXPECT_NEAR(c.rms, 0.05, 1e-12);
  EXPECT_NEAR(c.percent(c.hausdorff), 100 * 0.05 / std::sqrt(5.0), 1e-9);
}

TEST(Compare, SphereAndScaledSphere) {
  // Both inscribed in their spheres with chordal error < 1e-3: the distance is 0.1 within that.
  const Mesh a = make_icosphere({.radius = 1.0, .tolerance = 5e-4});
  Mesh b = a;
  b.positions *= 1.1;
  const Comparison c = compare(a, b);
  EXPECT_NEAR(c.hausdorff, 0.1, 1e-3);
  EXPECT_NEAR(c.rms, 0.1, 1e-3);
  EXPECT_NEAR(c.a_to_b.normal_deviation_mean_deg, 0.0, 1e-6);  // same directions
}

TEST(Compare, OneSidedDistancesDifferForAPatchAndAPlane) {
  // A small patch floating 0.1 above the middle of a big plane: every point of the patch is 0.1 from
  // the plane, but the plane's far corners are far from the patch.
  const Mesh plane = make_grid({.size = {4, 4}, .divisions_x = 4, .divisions_y = 4});
  Mesh patch = make_grid({.size = {1, 1}, .divisions_x = 2, .divisions_y = 2});
  patch.positions.col(2).array() += 0.1;
  const Comparison c = compare(patch, plane);
  EXPECT_NEAR(c.a_to_b.max, 0.1, 1e-12);
  EXPECT_NEAR(c.b_to_a.max, std::sqrt(2 * 1.5 * 1.5 + 0.01), 1e-9);
  EXPECT_EQ(c.hausdorff, c.b_to_a.max);
}

TEST(Compare, FindsASingleSpike) {
  const Mesh flat = make_grid({.divisions_x = 10, .divisions_y = 10});
  Mesh spiky = flat;
  spiky.positions(60, 2) = 0.3;  // one interior vertex
  const Comparison c = compare(spiky, flat);
  EXPECT_NEAR(c.a_to_b.max, 0.3, 1e-12);
}

TEST(Compare, SameAnswerForAnyThreadCount) {
  const Mesh a = make_uv_sphere({.segments = 40, .rings = 20});
  const Mesh b = make_icosphere({.subdivisions = 3});
  Comparison one, many;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = compare(a, b);
  }
  many = compare(a, b);
  EXPECT_EQ(one.hausdorff, many.hausdorff);
  EXPECT_EQ(one.rms, many.rms);
  EXPECT_EQ(one.mean, many.mean);
  EXPECT_EQ(one.a_to_b.normal_deviation_mean_deg, many.a_to_b.normal_deviation_mean_deg);
}

void expect_same(const DirectedDistance& x, const DirectedDistance& y) {
  EXPECT_EQ(x.max, y.max);
  EXPECT_EQ(x.mean, y.mean);
  EXPECT_EQ(x.rms, y.rms);
  EXPECT_EQ(x.normal_deviation_mean_deg, y.normal_deviation_mean_deg);
  EXPECT_EQ(x.normal_deviation_max_deg, y.normal_deviation_max_deg);
  EXPECT_EQ(x.samples, y.samples);
}

TEST(Compare, AReferenceMeasuresEveryMeshAsCompareDoes) {
  const Mesh reference = make_icosphere({.subdivisions = 3});
  Mesh with_debris = make_uv_sphere({.segments = 16, .rings = 8});
  with_debris.positions.conservativeResize(with_debris.num_vertices() + 1, 3);
  with_debris.positions.row(with_debris.num_vertices() - 1) << 5, 5, 5;  // unreferenced, far away
  with_debris.triangles.conservativeResize(with_debris.num_faces() + 1, 3);
  with_debris.triangles.row(with_debris.num_faces() - 1) << 0, 0, 1;  // degenerate
  Mesh open = make_grid({.size = {2, 2}, .divisions_x = 6, .divisions_y = 6});
  const CompareReference measurer(reference, 20000);
  for (const Mesh& other : {make_uv_sphere({.segments = 24, .rings = 12}), make_box({}), with_debris, open}) {
    CompareOptions o;
    o.samples = 20000;
    const Comparison direct = compare(reference, other, o), shared = measurer.compare(other);
    expect_same(direct.a_to_b, shared.a_to_b);
    expect_same(direct.b_to_a, shared.b_to_a);
    EXPECT_EQ(direct.hausdorff, shared.hausdorff);
    EXPECT_EQ(direct.rms, shared.rms);
    EXPECT_EQ(direct.diagonal, shared.diagonal);
    // Fewer samples on the other mesh leave the reference's direction as it was.
    const Comparison sparse = measurer.compare(other, 2000);
    expect_same(direct.a_to_b, sparse.a_to_b);
    EXPECT_LT(sparse.b_to_a.samples, direct.b_to_a.samples);
    EXPECT_NEAR(sparse.b_to_a.rms, direct.b_to_a.rms, 0.05 * direct.b_to_a.rms);
  }
  EXPECT_THROW(measurer.compare(Mesh{}), Error);
  EXPECT_THROW(measurer.compare(open, 0), Error);
  EXPECT_THROW(CompareReference(Mesh{}, 100), Error);
  EXPECT_THROW(CompareReference(reference, 0), Error);
}

TEST(Compare, CountsEveryCornerAndEdgeOfEveryFace) {
  // Corners and edge midpoints shared by faces are measured once but counted, and refined, per face.
  const Mesh a = make_torus({.major_segments = 12, .minor_segments = 6});
  CompareOptions o;
  o.samples = 5000;
  o.refine_rounds = 0;
  const Comparison c = compare(a, a, o);
  EXPECT_EQ(c.a_to_b.samples, 6LL * a.num_faces() + 5000);
}

TEST(Compare, RefusesEmptyMeshes) { EXPECT_THROW(compare(Mesh{}, make_box({})), Error); }

}  // namespace
}  // namespace lodkit
