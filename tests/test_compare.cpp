#include <gtest/gtest.h>
#include <limits>
#include <numbers>
#include <lodkit/error.h>
#include <lodkit/metrics.h>
#include <lodkit/primitives.h>

#include <lodkit/simplify.h>


#include "core/uv_charts.h"
#include "metrics/aabb_tree.h"
#include "test_util.h"

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

TEST(Compare, ShadingNormalsAreComparedWhereBothMeshesHaveThem) {
  // A flat grid whose normals lean in x by an amount that varies across it (all in the xz-plane, so
  // interpolation matters and stays there), against the same normals turned 10 degrees about y: 10
  // degrees apart everywhere, both ways. A normal that vanishes counts 90; no normals, no figures.
  Mesh a = make_grid({.divisions_x = 8, .divisions_y = 8});
  a.attributes.normals.resize(a.num_vertices(), 3);
  for (Index v = 0; v < a.num_vertices(); ++v)
    a.attributes.normals.row(v) = Eigen::Vector3d(0.6 * a.positions(v, 0), 0.0, 1.0).normalized();
  Mesh b = a;
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(10.0 * std::numbers::pi / 180, Eigen::Vector3d::UnitY()).toRotationMatrix();
  for (Index v = 0; v < b.num_vertices(); ++v) b.attributes.normals.row(v) = (turn * b.attributes.normals.row(v).transpose()).transpose();
  const Comparison c = compare(a, b);
  ASSERT_TRUE(c.shading_rms_deg && c.a_to_b.shading_max_deg && c.b_to_a.shading_rms_deg);
  EXPECT_NEAR(*c.shading_rms_deg, 10.0, 1e-4);
  EXPECT_NEAR(*c.a_to_b.shading_max_deg, 10.0, 1e-4);
  EXPECT_NEAR(*c.b_to_a.shading_max_deg, 10.0, 1e-4);
  EXPECT_NEAR(*compare(a, a).shading_rms_deg, 0.0, 1e-6);
  Mesh vanishing = a;
  vanishing.attributes.normals.setZero();
  EXPECT_NEAR(*compare(a, vanishing).a_to_b.shading_max_deg, 90.0, 1e-9);
  Mesh plain = a;
  plain.attributes.normals.resize(0, 3);
  EXPECT_FALSE(compare(a, plain).shading_rms_deg);
  EXPECT_FALSE(compare(plain, a).b_to_a.shading_max_deg);
  EXPECT_FALSE(compare(a, b).colour_rms);
}

TEST(Compare, UvsAreComparedWhereBothMeshesHaveThem) {
  // A grid's UVs shifted by (0.01, 0.02): that far apart everywhere, both ways, over all the area.
  const Mesh a = make_grid({.divisions_x = 8, .divisions_y = 8, .uvs = true});
  ASSERT_TRUE(a.has_uvs());
  Mesh b = a;
  b.attributes.uvs.col(0).array() += 0.01;
  b.attributes.uvs.col(1).array() += 0.02;
  const Comparison c = compare(a, b);
  const double apart = std::hypot(0.01, 0.02);
  ASSERT_TRUE(c.uv_rms && c.a_to_b.uv_max && c.b_to_a.uv_rms);
  EXPECT_NEAR(*c.uv_rms, apart, 1e-6);
  EXPECT_NEAR(*c.a_to_b.uv_max, apart, 1e-6);
  EXPECT_NEAR(*c.b_to_a.uv_max, apart, 1e-6);
  EXPECT_DOUBLE_EQ(c.a_to_b.uv_compared, 1.0);
  EXPECT_DOUBLE_EQ(c.b_to_a.uv_compared, 1.0);
  EXPECT_NEAR(*compare(a, a).uv_rms, 0.0, 1e-12);
  Mesh plain = a;
  plain.attributes.uvs.resize(0, 2);
  EXPECT_FALSE(compare(a, plain).uv_rms);
  EXPECT_FALSE(compare(plain, a).b_to_a.uv_max);
}

TEST(Compare, UvsAreNotComparedAcrossASeam) {
  // A torus's UVs wrap both ways: one chart that meets itself along two seams. The same torus turned
  // about its axis by 1/200 of a turn is 0.005 apart in u everywhere, except that a point next to the
  // u seam has its nearest point across it, about 1 apart: such points are left out, not counted.
  const Mesh a = make_torus({.major_segments = 64, .minor_segments = 16, .uvs = true});
  ASSERT_TRUE(a.has_uvs());
  Mesh b = a;
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(2 * std::numbers::pi / 200, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  for (Index v = 0; v < b.num_vertices(); ++v) b.positions.row(v) = (turn * b.positions.row(v).transpose()).transpose();
  const Comparison c = compare(a, b);
  ASSERT_TRUE(c.uv_rms);
  EXPECT_NEAR(*c.uv_rms, 0.005, 2e-4);
  EXPECT_LT(*c.a_to_b.uv_max, 0.006);
  EXPECT_LT(*c.b_to_a.uv_max, 0.006);
  // What is left out is the strip the turn carries across the seam: 1/200 of the area, each way.
  EXPECT_NEAR(c.a_to_b.uv_compared, 1.0 - 1.0 / 200, 2e-3);
  EXPECT_NEAR(c.b_to_a.uv_compared, 1.0 - 1.0 / 200, 2e-3);
}

TEST(UvCharts, SeamsPartChartsAndNormalSeamsDoNot) {
  // A grid cut down the middle of its atlas: the right half's UVs moved by 0.5 in u, so the vertices
  // on x = 0 are split into two with other UVs. Two charts, each half's faces in one. Splitting a
  // vertex by its normals alone (same UVs) parts nothing; a torus's wrapping UVs are one chart.
  Mesh grid = make_grid({.divisions_x = 4, .divisions_y = 2, .uvs = true});
  const Index before = grid.num_vertices();
  std::vector<Index> twin(static_cast<std::size_t>(before), -1);
  auto right = [&](Index f) { return grid.positions.row(grid.triangles(f, 0)).x() + grid.positions.row(grid.triangles(f, 1)).x() +
                                         grid.positions.row(grid.triangles(f, 2)).x() > 0; };
  for (Index f = 0; f < grid.num_faces(); ++f) {
    if (!right(f)) continue;
    for (int k = 0; k < 3; ++k) {
      const Index v = grid.triangles(f, k);
      if (std::abs(grid.positions(v, 0)) > 1e-12) continue;
      if (twin[v] < 0) {
        twin[v] = grid.num_vertices();
        grid.positions.conservativeResize(twin[v] + 1, 3);
        grid.positions.row(twin[v]) = grid.positions.row(v);
        grid.attributes.uvs.conservativeResize(twin[v] + 1, 2);
        grid.attributes.uvs.row(twin[v]) = grid.attributes.uvs.row(v);
      }
      grid.triangles(f, k) = twin[v];
    }
  }
  for (Index v = 0; v < grid.num_vertices(); ++v)
    if (grid.positions(v, 0) > 1e-12 || v >= before) grid.attributes.uvs(v, 0) += 0.5;
  const std::vector<Index> charts = detail::uv_charts(grid);
  ASSERT_EQ(charts.size(), static_cast<std::size_t>(grid.num_faces()));
  for (Index f = 0; f < grid.num_faces(); ++f) EXPECT_EQ(charts[f] != charts[0], right(f) != right(0)) << f;
  EXPECT_EQ(*std::max_element(charts.begin(), charts.end()), 1);
  // The same cut with the UVs left alone (a normal seam, say): one chart.
  Mesh same = grid;
  for (Index v = 0; v < same.num_vertices(); ++v)
    if (same.positions(v, 0) > 1e-12 || v >= before) same.attributes.uvs(v, 0) -= 0.5;
  const std::vector<Index> one = detail::uv_charts(same);
  EXPECT_EQ(*std::max_element(one.begin(), one.end()), 0);
  const std::vector<Index> torus = detail::uv_charts(make_torus({.major_segments = 12, .minor_segments = 6, .uvs = true}));
  EXPECT_EQ(*std::max_element(torus.begin(), torus.end()), 0);
}

TEST(Compare, ColoursAreComparedWhereBothMeshesHaveThem) {
  // The same sphere with every red raised by 0.1 (and its colours a gradient, so that interpolation
  // matters): 0.1 apart everywhere, both ways; no colours on one side, no colour figures.
  Mesh a = make_icosphere({.subdivisions = 2});
  a.attributes.colours.resize(a.num_vertices(), 4);
  for (Index v = 0; v < a.num_vertices(); ++v)
    a.attributes.colours.row(v) << 0.5f + 0.4f * float(a.positions(v, 0)), 0.5f, 0.2f, 1.0f;
  Mesh b = a;
  b.attributes.colours.col(0).array() += 0.1f;
  const Comparison c = compare(a, b);
  ASSERT_TRUE(c.colour_rms && c.a_to_b.colour_rms && c.b_to_a.colour_max);
  EXPECT_NEAR(*c.colour_rms, 0.1, 1e-6);
  EXPECT_NEAR(*c.a_to_b.colour_max, 0.1, 1e-6);
  EXPECT_NEAR(*c.b_to_a.colour_rms, 0.1, 1e-6);
  EXPECT_NEAR(*compare(a, a).colour_rms, 0.0, 1e-12);
  Mesh plain = a;
  plain.attributes.colours.resize(0, 4);
  EXPECT_FALSE(compare(a, plain).colour_rms);
  EXPECT_FALSE(compare(plain, a).a_to_b.colour_max);
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
  const Comparison one = test::on_threads(1, [&] { return compare(a, b); });
  const Comparison many = test::on_threads(4, [&] { return compare(a, b); });
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
  // Corners and edge midpoints shared by faces are measured once but counted per face.
  const Mesh a = make_torus({.major_segments = 12, .minor_segments = 6});
  CompareOptions o;
  o.samples = 5000;
  const Comparison c = compare(a, a, o);
  EXPECT_EQ(c.a_to_b.samples, 6LL * a.num_faces() + 5000);
}

// The largest distance from `from` to `to` over a barycentric grid of n x n steps on every face,
// corners and edges included: a search denser than compare()'s, by brute force.
double dense_max(const Mesh& from, const Mesh& to, int n) {
  const detail::AabbTree tree(to);
  double worst = 0;
  for (Index f = 0; f < from.num_faces(); ++f) {
    const Eigen::Vector3d a = from.positions.row(from.triangles(f, 0)), b = from.positions.row(from.triangles(f, 1)),
                          c = from.positions.row(from.triangles(f, 2));
    for (int i = 0; i <= n; ++i)
      for (int j = 0; i + j <= n; ++j)
        worst = std::max(worst, tree.closest(a + (b - a) * i / n + (c - a) * j / n).squared_distance);
  }
  return std::sqrt(worst);
}

// The maximum compare() reports is attained (no more than the dense search can find, bar rounding),
// within the tolerance of its bound, and the bound is no less than the dense search finds.
void expect_brackets(const Mesh& a, const Mesh& b, const CompareOptions& o, int n) {
  const Comparison c = compare(a, b, o);
  const detail::AabbTree tree_a(a), tree_b(b);
  for (const auto& [d, dense, from, to] : {std::tuple{c.a_to_b, dense_max(a, b, n), &tree_a, &tree_b},
                                           std::tuple{c.b_to_a, dense_max(b, a, n), &tree_b, &tree_a}}) {
    // The maximum is attained where it says: a point of the first surface, that far from the second.
    EXPECT_LT(from->closest(d.max_at).squared_distance, 1e-24);
    EXPECT_NEAR(std::sqrt(to->closest(d.max_at).squared_distance), d.max, 1e-12);
    EXPECT_NEAR((d.max_at - d.max_nearest).norm(), d.max, 1e-12);
    EXPECT_LE(dense, d.max_bound * (1 + 1e-12));
    EXPECT_LE(d.max, d.max_bound);
    if (o.max_splits > 0) {
      EXPECT_LE(d.max_bound, d.max * (1 + o.hausdorff_tolerance) + 1e-12);
      EXPECT_GE(d.max, dense / (1 + o.hausdorff_tolerance) - 1e-12);
    }
  }
  EXPECT_EQ(c.hausdorff_bound, std::max(c.a_to_b.max_bound, c.b_to_a.max_bound));
}

TEST(Compare, CertifiesAMaximumBetweenSamples) {
  // A flat square 0.2 above a V-shaped valley of slope 0.5: the distance peaks along the valley's line
  // x = 0, which no vertex or edge midpoint of the square lies on, at 0.2 / sqrt(1 + 0.5^2).
  Mesh valley;
  valley.positions.resize(6, 3);
  valley.positions << -1, -1, 0.5, 0, -1, 0, 1, -1, 0.5, -1, 1, 0.5, 0, 1, 0, 1, 1, 0.5;
  valley.triangles.resize(4, 3);
  valley.triangles << 0, 1, 4, 0, 4, 3, 1, 2, 5, 1, 5, 4;
  Mesh square;
  square.positions.resize(4, 3);
  square.positions << -0.5, -0.5, 0.2, 0.3, -0.5, 0.2, 0.3, 0.5, 0.2, -0.5, 0.5, 0.2;
  square.triangles.resize(2, 3);
  square.triangles << 0, 1, 2, 0, 2, 3;
  const double exact = 0.2 / std::sqrt(1.25);
  CompareOptions o;
  o.samples = 10'000;
  const Comparison c = compare(valley, square, o);
  EXPECT_LE(c.b_to_a.max, exact * (1 + 1e-12));
  EXPECT_GE(c.b_to_a.max_bound, exact * (1 - 1e-12));
  EXPECT_LE(c.b_to_a.max_bound, c.b_to_a.max * (1 + o.hausdorff_tolerance));
  // With a tolerance of 1e-9 the search closes in on the line itself.
  o.hausdorff_tolerance = 1e-9;
  const DirectedDistance d = compare(valley, square, o).b_to_a;
  EXPECT_NEAR(d.max, exact, 1e-9);
  EXPECT_NEAR(d.max_at.x(), 0.0, 1e-6);  // on the valley's line
  EXPECT_NEAR(d.max_at.z(), 0.2, 1e-12);
  EXPECT_NEAR(std::abs(d.max_nearest.x()), 0.2 * 0.5 / 1.25, 1e-6);  // the foot on either arm
}

TEST(Compare, CertifiesADegenerateFaceAcrossAnEdgeCheaply) {
  // A zero-area face along y = 0.5 on a flat square of two triangles, crossing their shared diagonal.
  // Every distance from it to the square is 0, but no one face of the square holds both ends of a
  // piece that crosses the diagonal: quartering such pieces took the million splits allowed (2.2 s on
  // a fuzzed 23-face mesh against itself) and certified only 2e-6. Halving them settles it at once.
  Mesh square;
  square.positions.resize(4, 3);
  square.positions << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0;
  square.triangles.resize(2, 3);
  square.triangles << 0, 1, 2, 0, 2, 3;
  Mesh segment;
  segment.positions.resize(3, 3);
  segment.positions << 0.2, 0.5, 0, 0.8, 0.5, 0, 0.5, 0.5, 0;
  segment.triangles.resize(1, 3);
  segment.triangles << 0, 1, 2;
  CompareOptions o;
  o.samples = 1000;
  const DirectedDistance d = compare(segment, square, o).a_to_b;
  EXPECT_LT(d.max_bound, 1e-12);
  EXPECT_LT(d.max_queries, 1000);
}

TEST(Compare, AHoleUnderAFaceIsNotCovered) {
  // A square 0.1 above a plane with a square hole of half-width 0.25 that no corner of the square lies
  // over: the farthest point is over the hole's centre, sqrt(0.1^2 + 0.25^2) from its rim. The faces
  // around the hole must not be taken to cover it.
  const Mesh grid = make_grid({.size = {2, 2}, .divisions_x = 8, .divisions_y = 8});
  Mesh holed = grid;
  std::vector<Index> kept;
  for (Index f = 0; f < grid.num_faces(); ++f) {
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k) centroid += grid.positions.row(grid.triangles(f, k)).transpose() / 3.0;
    if (std::abs(centroid.x()) > 0.25 || std::abs(centroid.y()) > 0.25) kept.push_back(f);
  }
  holed.triangles = grid.triangles(kept, Eigen::all);
  ASSERT_EQ(holed.num_faces(), grid.num_faces() - 8);
  Mesh square;
  square.positions.resize(4, 3);
  square.positions << -0.9, -0.7, 0.1, 0.8, -0.7, 0.1, 0.8, 0.9, 0.1, -0.9, 0.9, 0.1;
  square.triangles.resize(2, 3);
  square.triangles << 0, 1, 2, 0, 2, 3;
  const double exact = std::sqrt(0.1 * 0.1 + 0.25 * 0.25);
  CompareOptions o;
  o.samples = 1000;
  for (long long splits : {0LL, 1'000'000LL}) {
    o.max_splits = splits;
    const Comparison c = compare(square, holed, o);
    EXPECT_LE(c.a_to_b.max, exact * (1 + 1e-12));
    EXPECT_GE(c.a_to_b.max_bound, exact * (1 - 1e-12));
    if (splits > 0) {
      EXPECT_LE(c.a_to_b.max_bound, c.a_to_b.max * (1 + o.hausdorff_tolerance));
    }
  }
}

TEST(Compare, CertifiesAsCheaplyAgainstAnInsideOutSurface) {
  // Distances do not depend on which way faces point, and neither does the bound: the faces of the
  // other surface covering a triangle may all face away from it.
  const Mesh fine = test::bumpy_sphere(3, 0.05);
  SimplifyOptions so;
  so.target_faces = 200;
  const Mesh coarse = simplify(fine, so).mesh;
  Mesh inside_out = fine;
  inside_out.triangles.col(1).swap(inside_out.triangles.col(2));
  const Comparison straight = compare(coarse, fine), reversed = compare(coarse, inside_out);
  EXPECT_EQ(straight.hausdorff, reversed.hausdorff);
  // (Equal but for rounding: reversing a triangle's corners changes the order of a closest point's sums.)
  EXPECT_NEAR(straight.hausdorff_bound, reversed.hausdorff_bound, 1e-12 * straight.hausdorff_bound);
  EXPECT_EQ(straight.a_to_b.max_queries, reversed.a_to_b.max_queries);
  EXPECT_EQ(straight.b_to_a.max_queries, reversed.b_to_a.max_queries);
}

TEST(Compare, BracketsTheMaximumOfASimplifiedSurface) {
  // A bumpy sphere and its simplification, closed and with seams (flat-shaded: three vertices of its
  // own per face), and an open bumpy patch: the bound holds, with no split at all, against a dense
  // brute-force search, and the split search ends within its tolerance.
  const Mesh fine = test::bumpy_sphere(3, 0.05);
  SimplifyOptions so;
  so.target_faces = 80;
  const Mesh coarse = simplify(fine, so).mesh;
  Mesh patch = make_grid({.size = {2, 2}, .divisions_x = 24, .divisions_y = 24});
  for (Index v = 0; v < patch.num_vertices(); ++v)
    patch.positions(v, 2) = 0.05 * std::sin(7 * patch.positions(v, 0)) * std::cos(5 * patch.positions(v, 1));
  so.target_faces = 60;
  const Mesh coarse_patch = simplify(patch, so).mesh;
  CompareOptions o;
  o.samples = 20'000;
  for (long long splits : {0LL, 1'000'000LL}) {
    SCOPED_TRACE(splits);
    o.max_splits = splits;
    expect_brackets(fine, coarse, o, 24);
    expect_brackets(test::flat_shaded(fine), test::flat_shaded(coarse), o, 24);
    expect_brackets(patch, coarse_patch, o, 24);
  }
}

// The bench's "flipped faces": a face facing against the input's nearest face counts, but where two
// input faces coincide facing opposite ways (boxes stacked face to face), the one facing its way is as
// near, and the face does not count. A mesh measured against itself has none; turned, every face but
// those on the contact square.
TEST(FlippedFaces, CountFacesAgainstTheNearestInputFacesAndNoneAgainstThemselves) {
  BoxOptions options;
  options.divisions = 6;
  Mesh lower = make_box(options), upper = make_box(options);
  upper.positions.col(2).array() += 1.0;  // its bottom lies on the lower box's top, facing down
  const Mesh stacked = concatenated(lower, upper);
  EXPECT_EQ(count_flipped_faces(stacked, stacked), 0);
  Mesh turned = stacked;
  turned.triangles.col(1).swap(turned.triangles.col(2));
  const Index contact_square = 2 * options.divisions * options.divisions;  // faces a side
  EXPECT_EQ(count_flipped_faces(stacked, turned), stacked.num_faces() - 2 * contact_square);
  // One box turned inside out: the contact square still has faces facing both ways, so only its
  // other five sides count.
  Mesh one_turned = concatenated(lower, upper);
  one_turned.triangles.bottomRows(upper.num_faces()).col(1).swap(one_turned.triangles.bottomRows(upper.num_faces()).col(2));
  EXPECT_EQ(count_flipped_faces(stacked, one_turned), upper.num_faces() * 5 / 6);
}

TEST(Compare, RefusesEmptyMeshes) { EXPECT_THROW(compare(Mesh{}, make_box({})), Error); }

TEST(Compare, RefusesATolerancePastItsRange) {
  const Mesh box = make_box({});
  for (const double bad : {-1e-3, std::nan(""), std::numeric_limits<double>::infinity()}) {
    EXPECT_THROW(compare(box, box, {.hausdorff_tolerance = bad}), Error) << bad;
    EXPECT_THROW(CompareReference(box, 100, {.hausdorff_tolerance = bad}), Error) << bad;
  }
  EXPECT_THROW(compare(box, box, {.max_splits = -1}), Error);
  EXPECT_NO_THROW(compare(box, box, {.hausdorff_tolerance = 0}));
}

// 2·10⁹ samples (about 200 GB) ran out of memory with a message naming nothing; now a refusal up front.
TEST(Compare, RefusesMoreSamplesThanMemoryHolds) {
  const Mesh box = make_box({});
  try {
    compare(box, box, {.samples = 2'000'000'000});
    ADD_FAILURE() << "2e9 samples were taken";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("about 200 GB"), std::string::npos) << e.what();
  }
  EXPECT_THROW(compare(box, box, {.samples = 0}), Error);
}

// The closest-point tree keeps boxes in float: a coordinate of 3e80 (a fuzzed OBJ) made NaN bins and
// wrong answers. Refused by name; far from the origin but inside float range still measures.
TEST(Compare, RefusesCoordinatesBeyondWhatItMeasures) {
  Mesh far = make_box({});
  far.positions(0, 0) = 3e80;
  for (const char* method : {"compare", "simplify"}) {
    try {
      if (std::string(method) == "compare") compare(far, far);
      else simplify(far, {.target_faces = 8});
      ADD_FAILURE() << method << " measured a mesh at 3e80";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("a coordinate of 3e+80"), std::string::npos) << e.what();
    }
  }
  Mesh big = make_box({});
  big.positions *= 1e29;
  const Comparison c = compare(big, big);
  EXPECT_LT(c.hausdorff, 1e29 * 1e-12);  // rounding at that scale
}

}  // namespace
}  // namespace lodkit
