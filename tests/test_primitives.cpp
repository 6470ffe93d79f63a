#include <gtest/gtest.h>
#include <lodkit/error.h>
#include <lodkit/inspect.h>
#include <lodkit/primitives.h>

#include <cmath>
#include <functional>
#include <numbers>
#include <random>
#include <vector>

#include "core/bound_rows.h"
#include "core/geometry.h"

namespace lodkit {
namespace {

constexpr double kPi = std::numbers::pi;

void expect_closed_solid(const Mesh& m, long long genus, double volume, double rel_tol) {
  const MeshReport r = inspect(m);
  EXPECT_TRUE(r.closed);
  EXPECT_TRUE(r.oriented);
  EXPECT_EQ(r.components, 1);
  EXPECT_EQ(r.degenerate_faces, 0);
  EXPECT_EQ(r.duplicate_faces, 0);
  ASSERT_TRUE(r.genus);
  EXPECT_EQ(*r.genus, genus);
  ASSERT_TRUE(r.volume);
  EXPECT_GT(*r.volume, 0.0) << "outward orientation";
  EXPECT_NEAR(*r.volume, volume, rel_tol * volume);
}

TEST(Primitives, ClosedSolidsAreOutwardManifoldsOfTheRightGenus) {
  expect_closed_solid(make_box({.size = {1, 2, 3}, .divisions = 4}), 0, 6.0, 1e-12);
  expect_closed_solid(make_square_pyramid({.base = 2, .height = 3}), 0, 4.0, 1e-12);
  // Inscribed tessellations: volume a little below the true one.
  expect_closed_solid(make_uv_sphere({.radius = 2, .segments = 64, .rings = 32}), 0, 4.0 / 3 * kPi * 8, 0.01);
  expect_closed_solid(make_icosphere({.radius = 2, .subdivisions = 4}), 0, 4.0 / 3 * kPi * 8, 0.01);
  expect_closed_solid(make_cylinder({.radius = 1, .height = 2, .segments = 128, .stacks = 3}), 0, 2 * kPi, 0.001);
  expect_closed_solid(make_cone({.radius = 1, .height = 3, .segments = 128}), 0, kPi, 0.001);
  expect_closed_solid(make_torus({.major_radius = 2, .minor_radius = 0.5, .major_segments = 128,
                                  .minor_segments = 64}),
                      1, 2 * kPi * kPi * 2 * 0.25, 0.005);
  // With UV seams the topology is the same.
  expect_closed_solid(make_uv_sphere({.segments = 16, .rings = 8, .uvs = true}), 0, 4.0 / 3 * kPi, 0.1);
  expect_closed_solid(make_torus({.major_segments = 24, .minor_segments = 12, .uvs = true}), 1,
                      2 * kPi * kPi * 0.0625, 0.1);
}

TEST(Primitives, GridIsAFlatSheetFacingUp) {
  const Mesh g = make_grid({.size = {4, 2}, .divisions_x = 8, .divisions_y = 4, .uvs = true});
  EXPECT_EQ(g.num_faces(), 64);
  EXPECT_EQ(g.num_vertices(), 45);
  for (Index f = 0; f < g.num_faces(); ++f) {
    const auto t = g.triangles.row(f);
    const Eigen::Vector3d n = (g.positions.row(t[1]) - g.positions.row(t[0]))
                                  .cross(g.positions.row(t[2]) - g.positions.row(t[0]));
    EXPECT_GT(n.z(), 0.0);
  }
  EXPECT_EQ(g.attributes.uvs.row(44), Eigen::RowVector2d(1, 1));
}

// Largest distance from points sampled densely on the true surface to the mesh (brute force).
double sampled_deviation(const Mesh& m, const std::function<Eigen::Vector3d(double, double)>& surface,
                         int samples_u, int samples_v) {
  double worst = 0.0;
  for (int i = 0; i < samples_u; ++i)
    for (int j = 0; j <= samples_v; ++j) {
      const Eigen::Vector3d p = surface((i + 0.37) / samples_u, static_cast<double>(j) / samples_v);
      double best = INFINITY;
      for (Index f = 0; f < m.num_faces(); ++f) {
        const auto t = m.triangles.row(f);
        const Eigen::Vector3d q = detail::closest_point_on_triangle(
            p, m.positions.row(t[0]), m.positions.row(t[1]), m.positions.row(t[2]));
        best = std::min(best, (q - p).norm());
      }
      worst = std::max(worst, best);
    }
  return worst;
}

TEST(Primitives, ToleranceBoundsTheTrueSurfaceAndIsNotExceededByFar) {
  const double r = 1.5, tol = 0.01;
  const Mesh sphere = make_uv_sphere({.radius = r, .tolerance = tol});
  const double dev = sampled_deviation(
      sphere,
      [&](double u, double v) {
        const double phi = 2 * kPi * u, theta = kPi * v;
        return Eigen::Vector3d(r * std::sin(theta) * std::cos(phi), r * std::sin(theta) * std::sin(phi),
                               r * std::cos(theta));
      },
      97, 61);
  EXPECT_LE(dev, tol);
  EXPECT_GT(dev, 0.4 * tol) << "tessellation much finer than needed";

  const Mesh ico = make_icosphere({.radius = r, .tolerance = tol});
  EXPECT_LE(sampled_deviation(ico, [&](double u, double v) {
              const double phi = 2 * kPi * u, theta = kPi * v;
              return Eigen::Vector3d(r * std::sin(theta) * std::cos(phi),
                                     r * std::sin(theta) * std::sin(phi), r * std::cos(theta));
            }, 53, 37), tol);

  const Mesh torus = make_torus({.major_radius = 1, .minor_radius = 0.3, .tolerance = tol});
  EXPECT_LE(sampled_deviation(torus, [&](double u, double v) {
              const double phi = 2 * kPi * u, theta = 2 * kPi * v, ring = 1 + 0.3 * std::cos(theta);
              return Eigen::Vector3d(ring * std::cos(phi), ring * std::sin(phi), 0.3 * std::sin(theta));
            }, 71, 47), tol);
}

TEST(Primitives, CircleSegmentsAreTheFewestWithinTolerance) {
  for (double tol : {0.5, 0.1, 0.01, 1e-4}) {
    const int n = circle_segments_for_tolerance(1.0, tol);
    EXPECT_LE(circle_chordal_error(1.0, n), tol);
    if (n > 3) {
      EXPECT_GT(circle_chordal_error(1.0, n - 1), tol);
    }
  }
  const Mesh cyl = make_cylinder({.radius = 1, .tolerance = 0.01});
  const int n = circle_segments_for_tolerance(1.0, 0.01);
  EXPECT_EQ(cyl.num_vertices(), 2 * n + 2);
  EXPECT_EQ(circle_segments_for_tolerance(1.0, 5.0), 3);
}

TEST(Primitives, FinerToleranceNeverGivesFewerFaces) {
  Index previous = 0;
  for (double tol : {0.1, 0.03, 0.01, 0.003}) {
    const Index faces = make_torus({.tolerance = tol}).num_faces();
    EXPECT_GE(faces, previous);
    previous = faces;
  }
}

TEST(Primitives, BadParametersAreClearErrors) {
  EXPECT_THROW(make_uv_sphere({.radius = -1}), Error);
  EXPECT_THROW(make_uv_sphere({.segments = 2}), Error);
  EXPECT_THROW(make_torus({.major_radius = 1, .minor_radius = 2}), Error);
  EXPECT_THROW(make_cylinder({.tolerance = 0.0}), Error);
  EXPECT_THROW(make_box({.size = {1, 0, 1}}), Error);
  EXPECT_THROW(make_icosphere({.subdivisions = 11}), Error);
  try {
    make_cone({.height = NAN});
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("cone: height"), std::string::npos) << e.what();
  }
  // A tolerance too fine names the shape and the tolerance asked for (the torus gave each direction
  // half of it, and its message named the half: "tolerance: 5e-13 is too fine").
  for (auto [make, expected] : std::initializer_list<std::pair<std::function<Mesh()>, const char*>>{
           {[] { return make_torus({.tolerance = 1e-12}); }, "torus: tolerance 1e-12 is too fine"},
           {[] { return make_cylinder({.tolerance = 1e-12}); }, "cylinder: tolerance 1e-12 is too fine"},
           {[] { return make_cone({.tolerance = 1e-12}); }, "cone: tolerance 1e-12 is too fine"},
           // A radius so large that tolerance / radius vanishes next to 1: the segment estimate was an
           // infinite double cast to int (undefined behaviour; found by fuzzing a CSG tree).
           {[] { return make_cylinder({.radius = 4e59, .tolerance = 0.01}); }, "cylinder: tolerance 0.01 is too fine"},
           {[] { return make_torus({.major_radius = 4e59, .minor_radius = 1, .tolerance = 0.01}); }, "torus: tolerance 0.01"}}) {
    try {
      make();
      ADD_FAILURE() << expected;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  }
}

// Each count is within its range, but their product is not: a box of 65536 divisions (51.5 billion
// faces) overflowed the face index and wrote out of bounds; a grid as fine ran out of memory after
// 38 s. Both are refused before anything is built, naming the count; the largest allowed still builds.
TEST(Primitives, CountsWhoseProductIsTooManyFacesAreRefusedBeforeBuilding) {
  const auto refusal = [](auto&& make) -> std::string {
    try {
      make();
    } catch (const Error& e) {
      return e.what();
    }
    return "built";
  };
  EXPECT_NE(refusal([] { return make_box({.divisions = 65536}); }).find("box: 65536 divisions make 51539607552 faces"),
            std::string::npos);
  EXPECT_NE(refusal([] { return make_grid({.divisions_x = 65536, .divisions_y = 65536}); }).find("8589934592 faces"),
            std::string::npos);
  EXPECT_NE(refusal([] { return make_torus({.major_segments = 65536, .minor_segments = 65536}); }).find("torus:"),
            std::string::npos);
  EXPECT_NE(refusal([] { return make_cylinder({.segments = 65536, .stacks = 65536}); }).find("cylinder:"),
            std::string::npos);
  EXPECT_NE(refusal([] { return make_uv_sphere({.segments = 65536, .rings = 65536}); }).find("sphere:"),
            std::string::npos);
  EXPECT_NE(refusal([] { return make_uv_sphere({.tolerance = 1e-12}); }).find("tolerance too small"), std::string::npos);
  // The limit is 65536 by 1024 divisions of a grid, 2^27 faces (too large to build in a test): one more
  // row is refused, and the longest allowed strip builds.
  EXPECT_EQ(2 * std::int64_t{65536} * 1024, kMostPrimitiveFaces);
  EXPECT_NE(refusal([] { return make_grid({.divisions_x = 65536, .divisions_y = 1025}); }).find("134348800 faces"),
            std::string::npos);
  EXPECT_EQ(make_grid({.divisions_x = 65536, .divisions_y = 1}).num_faces(), 2 * 65536);
}

TEST(Geometry, TrianglePlanesBoundTheDistanceFromBelowAndMeetItInsideThePrism) {
  // Random triangles (some thin, some slivers) and points: the bound never exceeds the squared
  // distance beyond rounding (a sliver's normal is too uncertain: its bound is 0), and equals it (the
  // plane distance) for points above the triangle's interior.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> coord(-1.0, 1.0);
  auto random_point = [&] { return Eigen::Vector3d(coord(rng), coord(rng), coord(rng)); };
  int inside = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    Eigen::Vector3d c[3] = {random_point(), random_point(), random_point()};
    if (trial % 10 == 0) c[2] = c[0] + 1e-7 * random_point() + 0.5 * (c[1] - c[0]);  // a sliver
    if (trial % 10 == 5) c[2] = c[0] + 1e-3 * random_point() + 0.5 * (c[1] - c[0]);  // thin, still bounded
    detail::TrianglePlanes planes;
    const double area2 = planes.set(c);
    EXPECT_NEAR(area2, (c[1] - c[0]).cross(c[2] - c[0]).squaredNorm(), 1e-12);
    for (int k = 0; k < 20; ++k) {
      const Eigen::Vector3d x = 2.0 * random_point();
      const double d2 = (detail::closest_point_on_triangle(x, c[0], c[1], c[2]) - x).squaredNorm();
      const double bound = planes.lower_bound2(x);
      EXPECT_LE(bound, d2 * (1 + 1e-9) + 1e-15) << "trial " << trial;
      if (trial % 10 != 0 && trial % 10 != 5) {
        // Above the interior (barycentric weights all positive): the bound is the distance.
        const double a = std::uniform_real_distribution<double>(0.05, 0.9)(rng);
        const double b = std::uniform_real_distribution<double>(0.05, 0.95 - a)(rng);
        const Eigen::Vector3d above = c[0] + a * (c[1] - c[0]) + b * (c[2] - c[0]) + 0.3 * planes.normal;
        const double exact = (detail::closest_point_on_triangle(above, c[0], c[1], c[2]) - above).squaredNorm();
        EXPECT_NEAR(planes.lower_bound2(above), exact, 1e-12);
        ++inside;
      }
    }
  }
  EXPECT_GT(inside, 0);
  const Eigen::Vector3d sliver[3] = {{0, 0, 0}, {1, 0, 0}, {0.5, 1e-9, 0}};
  detail::TrianglePlanes planes;
  planes.set(sliver);
  EXPECT_FALSE(planes.bounds);
  EXPECT_EQ(planes.lower_bound2(Eigen::Vector3d(0.5, 3, 1)), 0.0);
}

TEST(Geometry, BoundRowsGiveEachTrianglesBoundAndPlaneDistanceAndTheExactDistanceInsideItsPrism) {
  // Many triangles at once (their count not a multiple of the vector width; every tenth a sliver):
  // the same bounds as TrianglePlanes one by one, the signed plane distances, and where a bound equals
  // its plane distance squared (no edge plane has x outside), the squared distance itself: hoppe's
  // scorer takes it there instead of walking the triangle's regions.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> coord(-1.0, 1.0);
  auto random_point = [&] { return Eigen::Vector3d(coord(rng), coord(rng), coord(rng)); };
  constexpr std::size_t kTriangles = 13;
  std::vector<std::array<Eigen::Vector3d, 3>> tris(kTriangles);
  std::vector<detail::TrianglePlanes> planes(kTriangles);
  detail::BoundRows rows;
  rows.resize(kTriangles);
  for (std::size_t i = 0; i < kTriangles; ++i) {
    tris[i] = {random_point(), random_point(), random_point()};
    if (i % 10 == 3) tris[i][2] = tris[i][0] + 1e-7 * random_point() + 0.5 * (tris[i][1] - tris[i][0]);
    planes[i].set(tris[i].data());
    rows.set(i, planes[i]);
  }
  int exact = 0, walked = 0;
  for (int trial = 0; trial < 5000; ++trial) {
    const Eigen::Vector3d x = 1.5 * random_point();
    const double* bounds = rows.lower_bounds2(x);
    const double* plane = rows.plane_distances();
    for (std::size_t i = 0; i < kTriangles; ++i) {
      EXPECT_NEAR(bounds[i], planes[i].lower_bound2(x), 1e-12);
      if (!planes[i].bounds) {
        EXPECT_EQ(bounds[i], 0.0);
        continue;
      }
      EXPECT_NEAR(plane[i], planes[i].normal.dot(x) - planes[i].offset, 1e-12);
      const double d2 = (detail::closest_point_on_triangle(x, tris[i][0], tris[i][1], tris[i][2]) - x).squaredNorm();
      if (bounds[i] == plane[i] * plane[i]) {
        EXPECT_NEAR(bounds[i], d2, 1e-12 * (1 + d2)) << "trial " << trial << ", triangle " << i;
        ++exact;
      } else {
        EXPECT_LT(bounds[i], d2 * (1 + 1e-9) + 1e-15);
        ++walked;
      }
    }
  }
  EXPECT_GT(exact, 1000);
  EXPECT_GT(walked, 1000);
}

TEST(Geometry, BoundRowsKernelsAgreeBitForBitAndPickTheSameTriangles) {
  // hoppe's scorer takes the lowest bound's triangle first (for a point with no home), then asks
  // which others have a bound below that distance. The AVX2 kernel must give exactly the plain one's
  // bounds, plane distances, bits and lowest triangle, or the result would depend on the CPU; the
  // bits and the lowest must be what a scan of the bounds gives (the first of equal lowest ones).
  std::mt19937 rng(12);
  std::uniform_real_distribution<double> coord(-1.0, 1.0);
  auto random_point = [&] { return Eigen::Vector3d(coord(rng), coord(rng), coord(rng)); };
  for (const std::size_t count : {std::size_t(1), std::size_t(7), std::size_t(13), std::size_t(64)}) {
    detail::BoundRows rows;
    rows.resize(count);
    for (std::size_t i = 0; i < count; ++i) {
      Eigen::Vector3d c[3] = {random_point(), random_point(), random_point()};
      if (i % 5 == 2) c[0] = Eigen::Vector3d(0, 0, 0), c[1] = {1, 0, 0}, c[2] = {0, 1, 0};  // equal bounds: ties
      detail::TrianglePlanes planes;
      planes.set(c);
      rows.set(i, planes);
    }
    for (int trial = 0; trial < 500; ++trial) {
      const Eigen::Vector3d x = 1.5 * random_point();
      const double limit = coord(rng) + 1.0;
      std::vector<double> bounds[2], plane[2];
      std::uint64_t below[2];
      std::size_t lowest[2];
      for (int plain = 0; plain < 2; ++plain) {
        detail::BoundRows::use_vector_kernel(plain == 0);
        const double* b = rows.lower_bounds2(x);
        below[plain] = rows.below(limit);
        lowest[plain] = rows.lowest();
        bounds[plain].assign(b, b + count);
        plane[plain].assign(rows.plane_distances(), rows.plane_distances() + count);
      }
      detail::BoundRows::use_vector_kernel(true);
      EXPECT_EQ(bounds[0], bounds[1]);
      EXPECT_EQ(plane[0], plane[1]);
      EXPECT_EQ(below[0], below[1]);
      EXPECT_EQ(lowest[0], lowest[1]);
      const auto scan = std::size_t(std::min_element(bounds[0].begin(), bounds[0].end()) - bounds[0].begin());
      EXPECT_EQ(lowest[0], scan);
      for (std::size_t i = 0; i < count; ++i)
        EXPECT_EQ((below[0] >> i) & 1, bounds[0][i] < limit ? 1u : 0u) << "triangle " << i;
      if (count < 64) {
        EXPECT_EQ(below[0] >> count, 0u) << "no bits past the last triangle";
      }
    }
  }
}

TEST(Geometry, LocalOriginIsExactToMeasureFromAndNearAFarMesh) {
  // Boxes far from zero, near it, across it, and below it: every p in the box has p - o exact, so it
  // comes back as p.
  std::mt19937 rng(11);
  const std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> boxes = {
      {{1e6 - 1, -2e6 - 1, 3e6 - 1}, {1e6 + 1, -2e6 + 1, 3e6 + 1}},
      {{0.3, 0.31, 7.0}, {1.2, 0.5, 27.9}},
      {{-1, -0.5, 1e-9}, {1, 0.5, 1}},
      {{-8.0, -1e-3, -3.0}, {-2.0, -1e-4, -2.9}}};
  for (const auto& [lo, hi] : boxes) {
    const Eigen::Vector3d o = detail::local_origin(Eigen::AlignedBox3d(lo, hi));
    for (int i = 0; i < 3; ++i) {
      std::uniform_real_distribution<double> coordinate(lo[i], hi[i]);
      for (int k = 0; k < 1000; ++k) {
        const double x = k == 0 ? lo[i] : k == 1 ? hi[i] : coordinate(rng);
        const double local = x - o[i];
        ASSERT_EQ(local + o[i], x) << x << " from " << o[i];
        ASSERT_EQ(x - local, o[i]) << x << " from " << o[i];  // the subtraction lost nothing
      }
    }
  }
  // Far from zero, the origin is inside the box; across or near zero, it is zero.
  const Eigen::Vector3d far = detail::local_origin(Eigen::AlignedBox3d(boxes[0].first, boxes[0].second));
  EXPECT_TRUE(Eigen::AlignedBox3d(boxes[0].first, boxes[0].second).contains(far));
  EXPECT_EQ(detail::local_origin(Eigen::AlignedBox3d(boxes[2].first, boxes[2].second)), Eigen::Vector3d::Zero());
  EXPECT_EQ(detail::local_origin(Eigen::AlignedBox3d()), Eigen::Vector3d::Zero());
}

}  // namespace
}  // namespace lodkit
