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

TEST(Compare, RefusesEmptyMeshes) { EXPECT_THROW(compare(Mesh{}, make_box({})), Error); }

}  // namespace
}  // namespace lodkit
