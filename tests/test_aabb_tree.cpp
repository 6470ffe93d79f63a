// The closest-point tree against brute force: closest() and facing_against() must give the answers a
// scan over every face gives, whatever the hint, where facing_against() skips its search or not.
#include <gtest/gtest.h>
#include <lodkit/error.h>
#include <lodkit/primitives.h>

#include <random>

#include "core/geometry.h"
#include "metrics/aabb_tree.h"
#include "test_util.h"

namespace lodkit {
namespace {

using detail::AabbTree;

Eigen::Vector3d corner(const Mesh& m, Index f, int k) { return m.positions.row(m.triangles(f, k)); }

// The lowest-numbered face at the least distance, and that distance squared.
std::pair<Index, double> brute_closest(const Mesh& m, const Eigen::Vector3d& p) {
  std::pair<Index, double> best{-1, std::numeric_limits<double>::infinity()};
  for (Index f = 0; f < m.num_faces(); ++f) {
    const double d = (detail::closest_point_on_triangle(p, corner(m, f, 0), corner(m, f, 1), corner(m, f, 2)) - p).squaredNorm();
    if (d < best.second) best = {f, d};
  }
  return best;
}

bool brute_facing_against(const Mesh& m, const Eigen::Vector3d& p, const Eigen::Vector3d& normal) {
  const Index f = brute_closest(m, p).first;
  const Eigen::Vector3d n = (corner(m, f, 1) - corner(m, f, 0)).cross(corner(m, f, 2) - corner(m, f, 0));
  return n.norm() > 0 && n.normalized().dot(normal) < 0;
}

// Points near the surface (a face's random point, pushed off it a little), each with the face it came
// from, and normals from that face's own to well past a right angle from it.
struct Probe {
  Eigen::Vector3d point, normal;
  Index source;
};
std::vector<Probe> probes_near(const Mesh& m, int count, double offset, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0, 1), turn(-2.0, 2.0);
  std::uniform_int_distribution<Index> face(0, m.num_faces() - 1);
  std::vector<Probe> probes;
  for (int i = 0; i < count; ++i) {
    const Index f = face(rng);
    double a = unit(rng), b = unit(rng);
    if (a + b > 1) a = 1 - a, b = 1 - b;
    const Eigen::Vector3d p0 = corner(m, f, 0), e1 = corner(m, f, 1) - p0, e2 = corner(m, f, 2) - p0;
    const Eigen::Vector3d n = e1.cross(e2).normalized();
    const Eigen::Vector3d t = e1.normalized(), s = n.cross(t);
    const Eigen::Vector3d point = p0 + a * e1 + b * e2 + (unit(rng) - 0.5) * offset * n;
    // A turn of up to ~115 degrees about a random direction in the face's plane.
    const double angle = turn(rng), spin = 6.283185307179586 * unit(rng);
    const Eigen::Vector3d axis = std::cos(spin) * t + std::sin(spin) * s;
    probes.push_back({point, Eigen::AngleAxisd(angle, axis) * n, f});
  }
  return probes;
}

// With and without the tree's copy of the corners (whose faces are first ruled out by their own boxes),
// split by surface area or at the median.
// A triangle with a repeated corner is a segment: its closest point is the segment's. Each edge
// region of the kernel divided by its edge's squared length, 0/0 for the repeated one, giving a NaN
// point; `lodkit compare` on an STL of one such facet then found no nearest face and crashed (fuzzing).
TEST(ClosestPointOnTriangle, ARepeatedCornerIsASegment) {
  const Eigen::Vector3d a(0, 0, 0), c(2, 1, 0);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-2, 3);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d p(u(rng), u(rng), u(rng));
    const Eigen::Vector3d expected = a + detail::segment_parameter(p, a, c) * (c - a);
    for (const auto& [x, y, z] : {std::array{a, a, c}, std::array{a, c, a}, std::array{c, a, a}, std::array{a, c, c}}) {
      const Eigen::Vector3d q = detail::closest_point_on_triangle(p, x, y, z);
      ASSERT_TRUE(q.allFinite()) << p.transpose();
      EXPECT_NEAR((q - expected).norm(), 0.0, 1e-12) << p.transpose();
    }
  }
  const Eigen::Vector3d p(1, 1, 1);
  EXPECT_EQ(detail::closest_point_on_triangle(p, a, a, a), a);
}

TEST(AabbTree, ClosestMatchesBruteForceWhateverTheHint) {
  const Mesh torus = make_torus({});
  for (const AabbTree::Options& options : {AabbTree::Options{}, AabbTree::Options{.copy_corners = false},
                                           AabbTree::Options{.copy_corners = false, .surface_area_splits = false}}) {
    const AabbTree tree(torus, options);
    std::mt19937 rng(3);
    std::uniform_int_distribution<Index> face(0, torus.num_faces() - 1);
    for (const Probe& probe : probes_near(torus, 400, 0.5, 11)) {
      const auto [face_expected, d_expected] = brute_closest(torus, probe.point);
      for (const Index hint : {Index{-1}, probe.source, face(rng)}) {
        const AabbTree::Hit hit = tree.closest(probe.point, hint);
        EXPECT_EQ(hit.face, face_expected);
        EXPECT_EQ(hit.squared_distance, d_expected);
      }
    }
  }
}

// refit(): the mesh's positions move in place, far enough that faces change places between leaves, and
// the refit tree answers as brute force does on the moved mesh (and as a tree built anew on it).
TEST(AabbTree, RefitAnswersAsBruteForceAfterThePositionsMove) {
  for (const AabbTree::Options& options : {AabbTree::Options{}, AabbTree::Options{.copy_corners = false},
                                           AabbTree::Options{.surface_area_splits = false}}) {
    Mesh torus = make_torus({});
    AabbTree tree(torus, options);
    std::mt19937 rng(5);
    std::normal_distribution<double> jitter(0.0, 0.08);
    for (int round = 0; round < 3; ++round) {
      for (Index v = 0; v < torus.num_vertices(); ++v) {
        const double x = torus.positions(v, 0), y = torus.positions(v, 1);
        torus.positions(v, 0) = 1.3 * x + jitter(rng), torus.positions(v, 1) = y + 0.4 * x + jitter(rng);
        torus.positions(v, 2) += 0.5 * x * x + jitter(rng);
      }
      tree.refit();
      const AabbTree fresh(torus, options);
      for (const Probe& probe : probes_near(torus, 300, 0.5, 31 + round)) {
        const auto [face_expected, d_expected] = brute_closest(torus, probe.point);
        const AabbTree::Hit hit = tree.closest(probe.point, probe.source);
        EXPECT_EQ(hit.face, face_expected);
        EXPECT_EQ(hit.squared_distance, d_expected);
        EXPECT_EQ(fresh.closest(probe.point).face, hit.face);
      }
    }
  }
  // A tree readied for the facing checks keeps per-face normals and cones it would not refit.
  const Mesh box = make_box({});
  AabbTree prepared(box);
  prepared.prepare_facing();
  EXPECT_THROW(prepared.refit(), Error);
}

// The search reads its boxes as floats, with a margin for rounding that grows with the coordinates:
// far from the origin it must still find the exact nearest face (the margin may only cost time), and
// trees of a leaf or two (no level to skip) must answer too.
TEST(AabbTree, ClosestMatchesBruteForceFarFromTheOriginAndOnTinyTrees) {
  TorusOptions small;
  small.major_radius = 1e-3, small.minor_radius = 2.5e-4;
  // (At 1000, a float is 6e-5 apart from the next: coarser than the 1e-3 torus's smaller faces, and far
  // coarser than the probes' distances.)
  for (const Eigen::Vector3d& offset : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1000.3, -999.7, 1000.1), Eigen::Vector3d(3e5, -1e6, 7e4)}) {
    Mesh torus = make_torus(small);
    torus.positions.rowwise() += offset.transpose();
    const AabbTree tree(torus);
    for (const Probe& probe : probes_near(torus, 500, 2e-6, 5)) {
      const auto [face_expected, d_expected] = brute_closest(torus, probe.point);
      const AabbTree::Hit hit = tree.closest(probe.point, -1);
      EXPECT_EQ(hit.face, face_expected) << "offset " << offset.transpose();
      EXPECT_EQ(hit.squared_distance, d_expected);
    }
  }
  // Beyond a float's range (squared distances past 3.4e38) the boxes are read in doubles.
  Mesh huge = make_torus({});
  huge.positions *= 1e30;
  const AabbTree huge_tree(huge);
  for (const Probe& probe : probes_near(huge, 200, 0.3e30, 7)) {
    const auto [face_expected, d_expected] = brute_closest(huge, probe.point);
    EXPECT_EQ(huge_tree.closest(probe.point).face, face_expected);
  }
  // Where a float rounds a point's gap to a box up past the best distance so far, the box must stay in
  // the search: p lies 4e-5 below face 0 at height z0 ~ 1000, where floats lie 6.1e-5 apart (so p may
  // round to the float below z0's), and the hint, a wide face centred far off in the other leaf, lies
  // 1.01 times that below p.
  for (int k = 0; k < 64; ++k) {
    const double z0 = 1000 + (k % 2 ? 0.37e-6 * k : std::ldexp(k, -10)), gap = 4e-5;
    Mesh m;
    m.positions.resize(24, 3);
    m.triangles.resize(8, 3);
    auto add = [&](int f, Eigen::Vector3d a, Eigen::Vector3d b, Eigen::Vector3d c) {
      m.positions.row(3 * f) = a.transpose(), m.positions.row(3 * f + 1) = b.transpose(), m.positions.row(3 * f + 2) = c.transpose();
      m.triangles.row(f) = Eigen::Matrix<Index, 1, 3>(3 * f, 3 * f + 1, 3 * f + 2);
    };
    add(0, {0, 0, z0}, {1, 0, z0}, {0, 1, z0});
    for (int f = 1; f < 4; ++f) add(f, {2.0 * f, 0, z0 + 1}, {2.0 * f + 1, 0, z0 + 1}, {2.0 * f, 1, z0 + 1});
    const double below = z0 - gap - 1.01 * gap;
    add(4, {-1, -1, below}, {60, -1, below}, {-1, 3, below});
    for (int f = 5; f < 8; ++f) add(f, {20.0 + f, 0, z0 + 1}, {21.0 + f, 0, z0 + 1}, {20.0 + f, 1, z0 + 1});
    const AabbTree tree(m);
    const Eigen::Vector3d p(0.2, 0.2, z0 - gap);
    EXPECT_EQ(tree.closest(p, 4).face, 0) << "z0 " << z0;
  }
  // Faces whose centroids crowd towards one end at every scale (at 2^-k, many coinciding in floats):
  // equal bins split them unevenly, and where all of a node's centroids coincide the split falls back on
  // the median.
  {
    const int faces = 3000;
    Mesh crowded;
    crowded.positions.resize(3 * faces, 3);
    crowded.triangles.resize(faces, 3);
    for (int f = 0; f < faces; ++f) {
      const double x = std::ldexp(1.0, -(f % 1000)) + 1e-3 * (f / 1000), size = 1e-6;
      crowded.positions.row(3 * f) = Eigen::RowVector3d(x, 0, 0);
      crowded.positions.row(3 * f + 1) = Eigen::RowVector3d(x + size, 0, 0);
      crowded.positions.row(3 * f + 2) = Eigen::RowVector3d(x, size, 0.01 * f);
      crowded.triangles.row(f) = Eigen::Matrix<Index, 1, 3>(3 * f, 3 * f + 1, 3 * f + 2);
    }
    const AabbTree tree(crowded);
    for (const Probe& probe : probes_near(crowded, 200, 1e-3, 13)) {
      const auto [face_expected, d_expected] = brute_closest(crowded, probe.point);
      EXPECT_EQ(tree.closest(probe.point).face, face_expected);
    }
  }
  for (const int faces : {1, 3, 4, 5, 7, 9, 17}) {
    Mesh strip;
    strip.positions.resize(faces + 2, 3);
    strip.triangles.resize(faces, 3);
    for (int i = 0; i < faces + 2; ++i) strip.positions.row(i) = Eigen::RowVector3d(0.5 * i, i % 2, 0.1 * i * i);
    for (int f = 0; f < faces; ++f) strip.triangles.row(f) = Eigen::Matrix<Index, 1, 3>(f, f + 1, f + 2);
    const AabbTree tree(strip);
    for (const Probe& probe : probes_near(strip, 50, 1.0, 9)) {
      const auto [face_expected, d_expected] = brute_closest(strip, probe.point);
      const AabbTree::Hit hit = tree.closest(probe.point);
      EXPECT_EQ(hit.face, face_expected) << faces << " faces";
      EXPECT_EQ(hit.squared_distance, d_expected);
    }
  }
}

// Every answer of a prepared tree on m, at probes near it `offsets` off the surface (each from three
// hints: none, the probe's own face, a random one; and again from the hint it left), must be the
// brute-force one (and the hint left where there was none, the nearest face), and both answers must
// occur, so that neither a constant nor a skip that always says "no" passes.
void expect_brute_force_answers(const Mesh& m, std::initializer_list<double> offsets, int probes, unsigned seed,
                                bool surface_area_splits = true) {
  AabbTree tree(m, {.copy_corners = true, .surface_area_splits = surface_area_splits});
  tree.prepare_facing();
  std::mt19937 rng(seed);
  std::uniform_int_distribution<Index> face(0, m.num_faces() - 1);
  int against = 0, total = 0;
  for (const double offset : offsets) {
    for (const Probe& probe : probes_near(m, probes, offset, seed + static_cast<unsigned>(offset * 1000))) {
      const bool expected = brute_facing_against(m, probe.point, probe.normal);
      for (Index hint : {Index{-1}, probe.source, face(rng)}) {
        const bool without_hint = hint < 0;
        ASSERT_EQ(tree.facing_against(probe.point, probe.normal, hint), expected)
            << "point " << probe.point.transpose() << " normal " << probe.normal.transpose();
        ASSERT_GE(hint, 0);
        // Without a hint, it leaves the nearest face as the next one: a far face (the nearest the
        // search did not pass over) would make every later call search again.
        if (without_hint) {
          ASSERT_EQ(hint, brute_closest(m, probe.point).first);
        }
        ASSERT_EQ(tree.facing_against(probe.point, probe.normal, hint), expected);
      }
      against += expected;
      ++total;
    }
  }
  EXPECT_GT(against, total / 20);
  EXPECT_LT(against, total - total / 20);
}

// closest_facing(): the nearest point on the faces that face the given way, as a scan over them finds
// it, and no face where none does. Between a thin lens's sheets and where tori cross, the nearest face
// often faces the other way, so a search that ignored the side would fail.
TEST(AabbTree, ClosestFacingMatchesBruteForce) {
  TorusOptions torus_options;
  torus_options.major_segments = 24, torus_options.minor_segments = 12;
  Mesh crossed = make_torus(torus_options);
  crossed.positions.col(2) *= -1;  // mirrored: faces inward, crossing the first torus
  crossed.positions.col(0).array() += 0.5;
  for (const Mesh& m : {test::thin_lens(), concatenated(make_torus(torus_options), crossed)}) {
    AabbTree tree(m);
    tree.prepare_facing();
    int differs = 0;
    for (const Probe& probe : probes_near(m, 600, 0.05, 41)) {
      double expected = std::numeric_limits<double>::infinity();
      for (Index f = 0; f < m.num_faces(); ++f) {
        const Eigen::Vector3d a = corner(m, f, 0), b = corner(m, f, 1), c = corner(m, f, 2);
        if ((b - a).cross(c - a).dot(probe.normal) > 0)
          expected = std::min(expected, (detail::closest_point_on_triangle(probe.point, a, b, c) - probe.point).squaredNorm());
      }
      const AabbTree::Hit hit = tree.closest_facing(probe.point, probe.normal);
      ASSERT_GE(hit.face, 0);
      EXPECT_DOUBLE_EQ(hit.squared_distance, expected);
      EXPECT_NEAR((hit.point - probe.point).squaredNorm(), expected, 1e-12);
      const Eigen::Vector3d n = (corner(m, hit.face, 1) - corner(m, hit.face, 0)).cross(corner(m, hit.face, 2) - corner(m, hit.face, 0));
      EXPECT_GT(n.dot(probe.normal), 0);
      differs += hit.squared_distance > tree.closest(probe.point).squared_distance;
    }
    EXPECT_GT(differs, 30);  // the side mattered
  }
  const Mesh one = test::single_triangle();
  AabbTree tree(one);
  tree.prepare_facing();
  const Eigen::Vector3d n = (corner(one, 0, 1) - corner(one, 0, 0)).cross(corner(one, 0, 2) - corner(one, 0, 0));
  EXPECT_EQ(tree.closest_facing(corner(one, 0, 0), -n).face, -1);
  EXPECT_EQ(tree.closest_facing(corner(one, 0, 0), n).face, 0);
}

// A quad's empty lane (beside a child that is a leaf) has a box at infinity. A search whose bound was
// still infinite entered it as node -1 and read the side test before the first: undefined behaviour
// that a release build answered right by luck and AddressSanitizer caught (session 53,
// scripts/sanitize.sh). closest_facing() keeps an infinite bound until it finds a face facing the way
// asked: here a flat sheet, which the search passes over whole for facing up, and one upright
// triangle apart, a leaf of its own that is entered and faces neither way. Nothing faces down.
TEST(AabbTree, SearchesWithoutABoundPassOverEmptyLanes) {
  GridOptions grid;
  grid.divisions_x = 37, grid.divisions_y = 23;
  Mesh scene = make_grid(grid);
  const Index base = scene.num_vertices();
  scene.positions.conservativeResize(base + 3, 3);
  scene.positions.bottomRows(3) << 5, 0, 0, 5, 1, 0, 5, 0, 1;  // facing along x
  scene.triangles.conservativeResize(scene.num_faces() + 1, 3);
  scene.triangles.bottomRows(1) << base, base + 1, base + 2;
  for (const AabbTree::Options& options : {AabbTree::Options{}, AabbTree::Options{.surface_area_splits = false}}) {
    AabbTree tree(scene, options);
    tree.prepare_facing();
    for (const Eigen::Vector3d& p : {Eigen::Vector3d(0.1, 0.2, 0.3), Eigen::Vector3d(4, 0.5, 0.5), Eigen::Vector3d(-2, 5, -1)}) {
      const AabbTree::Hit none = tree.closest_facing(p, -Eigen::Vector3d::UnitZ());
      EXPECT_EQ(none.face, -1);
      EXPECT_EQ(none.squared_distance, std::numeric_limits<double>::infinity());
      const auto [face, d] = brute_closest(scene, p);
      EXPECT_EQ(tree.closest(p).face, face);
      EXPECT_EQ(tree.closest(p).squared_distance, d);
      EXPECT_GE(tree.closest_facing(p, Eigen::Vector3d::UnitZ()).squared_distance, d);
    }
  }
}

// A thin lens has two sheets a hundredth apart, facing opposite ways: near the rim and between the
// sheets, the nearest face may lie on the far sheet, where a skip on the near sheet's cone would be
// wrong.
// (With median splits too: the simplifier's tree of the input.)
TEST(AabbTree, FacingAgainstMatchesBruteForceOnTwoCloseSheets) {
  for (const bool surface_area_splits : {true, false})
    expect_brute_force_answers(test::thin_lens(), {0.0, 0.004, 0.03}, 1500, 17, surface_area_splits);
}

// Where the search cannot pass over a node for its side: two tori that cross each other (faces of
// one inside the other, as in a scan of crossing parts) and a box's 90-degree edges, whose nodes hold
// faces that face both ways. The answer must still be that of the nearest face, ties to the lowest
// number, whether the first search settles it or the second has to look for a nearer face.
TEST(AabbTree, FacingAgainstMatchesBruteForceOnCrossingPartsAndSharpEdges) {
  TorusOptions torus_options;
  torus_options.major_segments = 24, torus_options.minor_segments = 12;
  Mesh crossed = make_torus(torus_options);
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(1.5707963267948966, Eigen::Vector3d::UnitX()).toRotationMatrix();
  crossed.positions = (crossed.positions * turn.transpose()).rowwise() + Eigen::RowVector3d(1.0, 0.0, 0.0);
  BoxOptions box_options;
  box_options.divisions = 6;
  for (const bool surface_area_splits : {true, false}) {
    expect_brute_force_answers(concatenated(make_torus(torus_options), crossed), {0.0, 0.05, 0.4}, 800, 23, surface_area_splits);
    expect_brute_force_answers(make_box(box_options), {0.0, 0.05, 0.4}, 800, 29, surface_area_splits);
  }
}

// faces_way_within() at the nearest face's distance: whether a face as near faces the normal's way.
// Points all around a box, so that many lie nearest one of its edges or corners, where faces tie.
TEST(AabbTree, FacesWayWithinFindsTheFacesTyingAtEdgesAndCorners) {
  BoxOptions box_options;
  box_options.divisions = 3;
  const Mesh box = make_box(box_options);
  AabbTree tree(box), unprepared(box);
  tree.prepare_facing();
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> coordinate(-1.0, 1.0), component(-1.0, 1.0);
  int ties = 0;
  for (int i = 0; i < 3000; ++i) {
    const Eigen::Vector3d p(coordinate(rng), coordinate(rng), coordinate(rng));
    const Eigen::Vector3d n(component(rng), component(rng), component(rng));
    const double d = std::sqrt(brute_closest(box, p).second);
    bool expected = false, against = false;
    for (Index f = 0; f < box.num_faces(); ++f) {
      const double e = (detail::closest_point_on_triangle(p, corner(box, f, 0), corner(box, f, 1), corner(box, f, 2)) - p).norm();
      const Eigen::Vector3d m = (corner(box, f, 1) - corner(box, f, 0)).cross(corner(box, f, 2) - corner(box, f, 0));
      if (e <= d + 1e-9) expected |= m.dot(n) > 0, against |= m.dot(n) < 0;
    }
    ties += expected && against;  // nearest faces facing both ways: the nearest one alone would not do
    EXPECT_EQ(tree.faces_way_within(p, n, d * d), expected) << p.transpose() << " / " << n.transpose();
    EXPECT_EQ(unprepared.faces_way_within(p, n, d * d), expected) << "without prepare_facing()";
  }
  EXPECT_GT(ties, 100);
}

TEST(AabbTree, FacingAgainstHandlesFacesWithoutAreaAndFacesBackToBackPreparedOrNot) {
  // A square twice, once each way (back to back), and a face of no area beside them.
  Mesh m;
  m.positions.resize(7, 3);
  m.positions << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 2, 0, 0, 3, 0, 0, 4, 0, 0;
  m.triangles.resize(5, 3);
  m.triangles << 0, 1, 2, 0, 2, 3, 0, 2, 1, 0, 3, 2, 4, 5, 6;
  AabbTree tree(m), unprepared(m);
  tree.prepare_facing();
  const Eigen::Vector3d up(0, 0, 1);
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(0.3, 0.6, 0.1), Eigen::Vector3d(0.7, 0.2, -0.2),
                                   Eigen::Vector3d(3.0, 0.0, 0.5), Eigen::Vector3d(3.0, 0.1, 0.0)})
    for (const Eigen::Vector3d& n : {up, Eigen::Vector3d(-up), Eigen::Vector3d(0.3, 0.2, 0.9)})
      for (Index hint = -1; hint < m.num_faces(); ++hint) {
        Index h = hint, h2 = hint;
        EXPECT_EQ(tree.facing_against(p, n, h), brute_facing_against(m, p, n)) << p.transpose() << " / " << n.transpose();
        EXPECT_EQ(unprepared.facing_against(p, n, h2), brute_facing_against(m, p, n)) << "without prepare_facing()";
      }
}

}  // namespace
}  // namespace lodkit
