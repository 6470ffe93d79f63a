// Progressive meshes in memory: exact refinement, navigation, agreement with simplify(), geomorphs and
// level selection.
#include <gtest/gtest.h>
#include <lodkit/error.h>
#include <lodkit/metrics.h>
#include <lodkit/primitives.h>
#include <lodkit/progressive.h>

#include <cmath>
#include <map>
#include <numbers>
#include <random>
#include <set>

#include "test_util.h"

namespace lodkit {
namespace {

void expect_identical(const Mesh& a, const Mesh& b, const std::string& what) { EXPECT_EQ(test::difference(a, b), "") << what; }

/// A mesh with everything a real file can have besides clean triangles: an unreferenced vertex, an
/// exact duplicate vertex used by one corner, a degenerate face, per-face colours.
Mesh awkward_mesh() {
  Mesh m = test::bumpy_sphere(2, 0.05);
  const Index n = m.num_vertices();
  m.positions.conservativeResize(n + 2, 3);
  m.positions.row(n) = Eigen::RowVector3d(5, 5, 5);       // unreferenced
  m.positions.row(n + 1) = m.positions.row(m.triangles(0, 0));  // duplicate of a used vertex
  m.triangles(0, 0) = n + 1;
  const Index f = m.num_faces();
  m.triangles.conservativeResize(f + 1, 3);
  m.triangles.row(f) << 1, 1, 2;  // degenerate
  m.attributes.face_colours.resize(f + 1, 4);
  for (Index i = 0; i <= f; ++i) m.attributes.face_colours.row(i) << float(i % 7) / 7.0f, 0.5f, float(i % 3) / 3.0f, 1.0f;
  return m;
}

TEST(ProgressiveMesh, FullRefinementReproducesTheInputExactly) {
  for (const Mesh& input : {test::bumpy_sphere(3, 0.05), test::seamed_uv_sphere(), make_grid({}), awkward_mesh()}) {
    const ProgressiveMesh pm = build_progressive_mesh(input);
    validate(pm);
    EXPECT_GT(pm.max_level(), 0);
    EXPECT_LT(pm.num_faces(0), input.num_faces() / 4);
    const ExtractedLevel full = extract_level(pm, pm.max_level());
    expect_identical(full.mesh, input, "finest level");
  }
}

TEST(ProgressiveMesh, EveryMethodBuildsAndRefinesExactly) {
  const Mesh input = test::bumpy_sphere(2, 0.05);
  for (SimplifyMethod method : {SimplifyMethod::Quadric, SimplifyMethod::Hoppe, SimplifyMethod::EdgeLength}) {
    ProgressiveOptions o;
    o.simplify.method = method;
    const ProgressiveMesh pm = build_progressive_mesh(input, o);
    validate(pm);
    expect_identical(extract_level(pm, pm.max_level()).mesh, input, to_string(method));
  }
}

TEST(ProgressiveMesh, LevelsEqualSimplifyToTheSameFaceCount) {
  for (const SimplifyMethod method : {SimplifyMethod::Quadric, SimplifyMethod::Hoppe})
    for (const Mesh& input : {test::bumpy_sphere(3, 0.05), test::seamed_uv_sphere(), make_grid({})}) {
      ProgressiveOptions o;
      o.simplify.method = method;
      const ProgressiveMesh pm = build_progressive_mesh(input, o);
      for (Index level : {Index(0), pm.max_level() / 7, pm.max_level() / 2, pm.max_level() - 1}) {
        SimplifyOptions so{.method = method};
        // A level keeps the collapses' positions and values; simplify() would refit them (quadric), fit them
        // (hoppe) and fit the normals and colours.
        so.refit_passes = 0;
        so.hoppe_fit_passes = 0;
        so.fit_attributes = false;
        so.hoppe_energy_from = 0;  // a progressive mesh's collapses are ranked by hoppe's energy throughout
        so.target_faces = pm.num_faces(level);
        const SimplifyResult r = simplify(input, so);
        const ExtractedLevel e = extract_level(pm, level);
        expect_identical(e.mesh, r.mesh, to_string(method) + " level " + std::to_string(level));
        EXPECT_EQ(e.vertex_origin, r.vertex_origin);
      }
    }
}

TEST(ProgressiveMesh, LevelsEqualSimplifyWithAttributeAwareCosts) {
  // quadric's attribute quadrics, and hoppe's E_scalar, whose collapses place the values themselves.
  for (const SimplifyMethod method : {SimplifyMethod::Quadric, SimplifyMethod::Hoppe}) {
    SCOPED_TRACE(to_string(method));
    ProgressiveOptions o;
    o.simplify.method = method;
    o.simplify.attribute_weights.uvs = method == SimplifyMethod::Hoppe ? 0.1 : 1.0;
    o.simplify.attribute_weights.normals = method == SimplifyMethod::Hoppe ? 0.05 : 0.5;
    const Mesh input = test::seamed_uv_sphere();
    const ProgressiveMesh pm = build_progressive_mesh(input, o);
    EXPECT_FALSE(pm.attribute_changes.empty());
    for (Index level : {Index(0), pm.max_level() / 3}) {
      SimplifyOptions so = o.simplify;
      so.refit_passes = 0;
      so.hoppe_fit_passes = 0;
      so.fit_attributes = false;
      so.hoppe_energy_from = 0;  // as the progressive mesh's collapses
      so.target_faces = pm.num_faces(level);
      const SimplifyResult r = simplify(input, so);
      const Mesh m = extract_level(pm, level).mesh;
      ASSERT_EQ(m.num_vertices(), r.mesh.num_vertices());
      EXPECT_TRUE(m.triangles == r.mesh.triangles);
      EXPECT_TRUE(m.positions == r.mesh.positions);
      // Wedges the cost never touched keep their input values here and come back rescaled from
      // simplify(): equal to rounding.
      EXPECT_LT((m.attributes.uvs - r.mesh.attributes.uvs).cwiseAbs().maxCoeff(), 1e-12);
      EXPECT_LT((m.attributes.normals - r.mesh.attributes.normals).cwiseAbs().maxCoeff(), 1e-12);
    }
    expect_identical(extract_level(pm, pm.max_level()).mesh, input, "finest level");
  }
}

TEST(ProgressiveMesh, AProvedLevelIsWithinItsLimitAndNoFinerThanSelection) {
  // prove_level_within() checks levels between the measured ones: its level is never finer than the one
  // selection picks from the stored distances, and compare() finds it within the limit.
  const Mesh input = test::bumpy_sphere(3, 0.05);
  ProgressiveMesh pm = build_progressive_mesh(input);
  measure_levels(pm, input);
  const double diagonal = bounding_box(input).diagonal().norm();
  for (const double percent : {0.3, 1.0, 4.0}) {
    const double limit = percent / 100 * diagonal;
    const ProvedLevel p = prove_level_within(pm, input, limit);
    EXPECT_LE(p.level, level_for_error(pm, limit, LevelErrorKind::Measured)) << percent;
    EXPECT_LE(p.proof.bound, limit);
    EXPECT_LE(compare(input, extract_level(pm, p.level).mesh).hausdorff, limit) << percent;
  }
  EXPECT_THROW(prove_level_within(pm, make_box({}), 0.01), Error);  // not the input
  EXPECT_THROW(prove_level_within(pm, input, -1.0), Error);
}

TEST(ProgressiveMesh, APixelBudgetIsTheDistanceThatProjectsToIt) {
  // object_error_for_pixels() inverts projected_pixels(); inside the sphere no error fits.
  for (const double pixels : {0.25, 1.0, 3.0}) {
    const ScreenSpaceBudget view{pixels, 7.0, 45.0, 1440.0};
    const double error = object_error_for_pixels(2.0, view);
    EXPECT_NEAR(error, pixels * 2 * 5.0 * std::tan(std::numbers::pi / 8) / 1440.0, 1e-15);
    EXPECT_NEAR(projected_pixels(error, 2.0, view), pixels, 1e-12);
  }
  EXPECT_EQ(object_error_for_pixels(2.0, {1.0, 1.5, 60.0, 1080.0}), 0.0);
  EXPECT_THROW(object_error_for_pixels(2.0, {-1.0, 10.0, 60.0, 1080.0}), Error);
  EXPECT_THROW(object_error_for_pixels(2.0, {1.0, 10.0, 0.0, 1080.0}), Error);
}

TEST(ProgressiveMesh, RandomWalksAgreeWithDirectExtraction) {
  const Mesh input = test::seamed_uv_sphere();
  ProgressiveOptions o;
  o.simplify.attribute_weights.uvs = 1.0;  // attribute changes must be undone too
  const ProgressiveMesh pm = build_progressive_mesh(input, o);
  PMCursor cursor(pm);
  std::mt19937 rng(3);
  for (int step = 0; step < 40; ++step) {
    const Index target = std::uniform_int_distribution<Index>(0, pm.max_level())(rng);
    if (step % 2) {
      cursor.go_to(target);
    } else {  // single steps
      while (cursor.level() < target) ASSERT_TRUE(cursor.refine());
      while (cursor.level() > target) ASSERT_TRUE(cursor.coarsen());
    }
    ASSERT_EQ(cursor.level(), target);
    expect_identical(cursor.extract().mesh, extract_level(pm, target).mesh, "walk to " + std::to_string(target));
  }
  cursor.go_to(pm.max_level());
  EXPECT_FALSE(cursor.refine());
  cursor.go_to(0);
  EXPECT_FALSE(cursor.coarsen());
}

TEST(ProgressiveMesh, EveryLevelIsAClosedManifoldWithTheSameGenus) {
  const Mesh input = make_torus({});
  const ProgressiveMesh pm = build_progressive_mesh(input);
  PMCursor cursor(pm);
  for (Index level = 0; level <= pm.max_level(); level += std::max<Index>(1, pm.max_level() / 25)) {
    cursor.go_to(level);
    const Mesh m = cursor.extract().mesh;
    // Euler characteristic of a torus (welded by position) is 0; every edge has exactly two faces.
    std::map<std::pair<Index, Index>, int> edges;
    const Eigen::VectorX<Index> cls = position_classes(m);
    std::set<Index> points;
    for (Index f = 0; f < m.num_faces(); ++f)
      for (int k = 0; k < 3; ++k) {
        const Index a = cls[m.triangles(f, k)], b = cls[m.triangles(f, (k + 1) % 3)];
        points.insert(a);
        edges[{std::min(a, b), std::max(a, b)}]++;
      }
    for (const auto& [e, n] : edges) ASSERT_EQ(n, 2) << "level " << level;
    EXPECT_EQ(Index(points.size()) - Index(edges.size()) + m.num_faces(), 0) << "level " << level;
    // Near the base the torus is a handful of faces whose nearest input face can lie across the hole.
    if (m.num_faces() >= input.num_faces() / 10) {
      EXPECT_EQ(count_flipped_faces(input, m), 0) << "level " << level;
    }
  }
}

TEST(ProgressiveMesh, ErrorBoundHoldsAndShrinksWithTheLevel) {
  const Mesh input = test::bumpy_sphere(3, 0.08);
  const ProgressiveMesh pm = build_progressive_mesh(input);
  EXPECT_EQ(pm.level_error.back(), 0.0);
  for (std::size_t i = 1; i < pm.level_error.size(); ++i) EXPECT_LE(pm.level_error[i], pm.level_error[i - 1]);
  for (Index level : {Index(0), pm.max_level() / 10, pm.max_level() / 3, pm.max_level() - 2}) {
    const Comparison c = compare(input, extract_level(pm, level).mesh);
    EXPECT_LE(c.hausdorff, pm.level_error[level] * (1 + 1e-9)) << "level " << level;
  }
}

TEST(ProgressiveMesh, MeasuredLevelsPickWhatAViewerNeeds) {
  const Mesh input = test::bumpy_sphere(3, 0.08);
  ProgressiveOptions po;
  po.measure_levels = true;
  const ProgressiveMesh pm = build_progressive_mesh(input, po);
  ASSERT_GE(pm.measured.size(), 5u);
  EXPECT_EQ(pm.measured.front().level, 0);
  EXPECT_EQ(pm.measured.back().level, pm.max_level());
  EXPECT_EQ(pm.measured.back().hausdorff, 0.0);
  CompareOptions co;
  co.samples = 10000;  // what measure_levels() uses for an input this small
  for (std::size_t i = 0; i + 1 < pm.measured.size(); ++i) {
    const LevelMeasurement& m = pm.measured[i];
    // Levels about sqrt(2) apart in faces; values are compare()'s certified bound (raised to stay
    // monotone) or the level's own bound where lower.
    EXPECT_LT(m.level, pm.measured[i + 1].level);
    if (pm.measured[i + 1].level < pm.max_level()) {
      EXPECT_LE(pm.num_faces(pm.measured[i + 1].level), std::ceil(1.4143 * pm.num_faces(m.level)));
    }
    EXPECT_GE(m.hausdorff, pm.measured[i + 1].hausdorff);
    const Comparison c = compare(input, extract_level(pm, m.level, VertexOrder::Stream).mesh, co);
    EXPECT_GE(m.hausdorff, c.hausdorff) << "level " << m.level;
    EXPECT_GE(m.hausdorff, std::min(c.hausdorff_bound, pm.level_error[m.level])) << "level " << m.level;
    EXPECT_DOUBLE_EQ(m.rms, c.rms) << "level " << m.level;
    EXPECT_LE(m.hausdorff, pm.level_error[m.level] * (1 + 1e-9)) << "level " << m.level;
    EXPECT_GT(m.hausdorff, 0.0);
  }
  // A sample count below the 10,000 floor holds for both sides: each level is what compare() gives at it.
  ProgressiveMesh sparse = pm;
  MeasureLevelsOptions few;
  few.samples = 2000;
  measure_levels(sparse, input, few);
  co.samples = 2000;
  for (std::size_t i = 0; i + 1 < sparse.measured.size(); ++i)
    EXPECT_DOUBLE_EQ(sparse.measured[i].rms,
                     compare(input, extract_level(pm, sparse.measured[i].level, VertexOrder::Stream).mesh, co).rms)
        << "level " << sparse.measured[i].level;
  // Between measured levels, a level takes the coarser one's value.
  const LevelMeasurement& a = pm.measured[2];
  EXPECT_EQ(level_error(pm, a.level, LevelErrorKind::Measured), std::min(a.hausdorff, pm.level_error[a.level]));
  EXPECT_EQ(level_error(pm, pm.measured[3].level - 1, LevelErrorKind::Measured),
            std::min(a.hausdorff, pm.level_error[pm.measured[3].level - 1]));
  EXPECT_EQ(level_error(pm, a.level, LevelErrorKind::Bound), pm.level_error[a.level]);

  // The level chosen by measured error is within budget by compare() and much coarser than the one the
  // loose bound picks; the next coarser level is not within budget.
  for (std::size_t i : {std::size_t(1), pm.measured.size() / 2, pm.measured.size() - 2}) {
    const double budget = pm.measured[i].hausdorff;
    const Index by_measure = level_for_error(pm, budget, LevelErrorKind::Measured);
    const Index by_bound = level_for_error(pm, budget, LevelErrorKind::Bound);
    EXPECT_LE(compare(input, extract_level(pm, by_measure).mesh, co).hausdorff, budget) << budget;
    EXPECT_LE(pm.num_faces(by_measure), pm.num_faces(by_bound)) << budget;
    if (i < pm.measured.size() - 2) {
      EXPECT_LT(2 * pm.num_faces(by_measure), pm.num_faces(by_bound)) << budget;
    }
    if (by_measure > 0) {
      EXPECT_GT(level_error(pm, by_measure - 1, LevelErrorKind::Measured), budget);
    }
  }
  // Whatever the budget, the level chosen is proved within it: a measured level (compare's certified
  // bound) or one whose guaranteed bound is. A level between two measured ones is never chosen on the
  // coarser one's value alone, because that level comes first.
  for (int k = 0; k <= 40; ++k) {
    const double budget = pm.measured.back().hausdorff * std::pow(1.25, k);
    const Index chosen = level_for_error(pm, budget, LevelErrorKind::Measured);
    const bool measured = std::any_of(pm.measured.begin(), pm.measured.end(),
                                      [&](const LevelMeasurement& m) { return m.level == chosen && m.hausdorff <= budget; });
    EXPECT_TRUE(measured || pm.level_error[chosen] <= budget || chosen == pm.max_level()) << budget;
  }
  // A viewer at the distance where the middle measured level's error is one pixel.
  const double radius = bounding_radius(pm), error = pm.measured[pm.measured.size() / 2].hausdorff;
  const ScreenSpaceBudget view{1.0, radius + error * 1080.0 / (2 * std::tan(std::numbers::pi / 6)) * 1.001, 60.0, 1080.0};
  const Index seen = level_for_view(pm, view, LevelErrorKind::Measured);
  EXPECT_EQ(seen, pm.measured[pm.measured.size() / 2].level);
  EXPECT_LE(projected_pixels(level_error(pm, seen, LevelErrorKind::Measured), radius, view), 1.0);
  EXPECT_LT(2 * pm.num_faces(seen), pm.num_faces(level_for_view(pm, view)));
  // Measuring against a different mesh is refused.
  ProgressiveMesh other = build_progressive_mesh(input);
  EXPECT_THROW(measure_levels(other, test::bumpy_sphere(2, 0.08)), Error);
}

TEST(ProgressiveMesh, BaseFacesStopsEarly) {
  const Mesh input = test::bumpy_sphere(3, 0.05);
  ProgressiveOptions o;
  o.base_faces = 500;
  const ProgressiveMesh pm = build_progressive_mesh(input, o);
  EXPECT_LE(pm.num_faces(0), 500);
  EXPECT_GE(pm.num_faces(0), 498);
  EXPECT_THROW(build_progressive_mesh(input, {{}, Index(-1)}), Error);
}

TEST(ProgressiveMesh, AncestorsLeadToCoarserWedgesOfTheSamePointFamily) {
  const ProgressiveMesh pm = build_progressive_mesh(test::seamed_uv_sphere());
  PMCursor cursor(pm);
  const Index fine = pm.max_level(), coarse = pm.max_level() / 4;
  for (Index w = 0; w < pm.num_wedges(fine); ++w) {
    const Index a = cursor.ancestor(w, coarse);
    ASSERT_GE(a, 0);
    EXPECT_LT(a, pm.num_wedges(coarse));
    if (w < pm.num_wedges(coarse)) {
      EXPECT_EQ(a, w);
    }
  }
}

TEST(Geomorph, EndpointsAreTheTwoLevels) {
  const Mesh input = test::seamed_uv_sphere();
  const ProgressiveMesh pm = build_progressive_mesh(input);
  const Index from = pm.max_level() / 5, to = pm.max_level() / 2;
  const Geomorph g = make_geomorph(pm, from, to);
  const Mesh end = g.at(1.0), start = g.at(0.0);
  expect_identical(end, extract_level(pm, to).mesh, "alpha = 1");
  EXPECT_TRUE(start.triangles == end.triangles);
  // At alpha = 0 every vertex sits where its ancestor is in the coarse level, so the surface is the
  // coarse level's: zero distance both ways, and the same area.
  const Mesh coarse = extract_level(pm, from).mesh;
  const Comparison c = compare(coarse, start);
  EXPECT_LT(c.hausdorff, 1e-12);
  const ExtractedLevel coarse_level = extract_level(pm, from);
  for (Index v = 0; v < start.num_vertices(); ++v) {
    const Eigen::RowVector3d p = start.positions.row(v);
    bool found = false;
    for (Index u = 0; u < coarse.num_vertices() && !found; ++u) found = coarse.positions.row(u) == p;
    ASSERT_TRUE(found) << "vertex " << v << " is not at a coarse vertex";
  }
  // Halfway, positions are the average.
  const Mesh half = g.at(0.5);
  EXPECT_LT((half.positions - 0.5 * (start.positions + end.positions)).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_THROW(make_geomorph(pm, to, from), Error);
  for (const double outside : {-0.5, 2.0, std::nan("")}) EXPECT_THROW(g.at(outside), Error) << outside;  // (extrapolated)
}

TEST(LevelSelection, PixelBudgetPicksTheCoarsestLevelWithinBudget) {
  const ProgressiveMesh pm = build_progressive_mesh(test::bumpy_sphere(3, 0.05));
  const double radius = bounding_radius(pm);
  for (double pixels : {0.5, 1.0, 4.0}) {
    for (double distance : {3.0, 10.0, 40.0}) {
      ScreenSpaceBudget view{pixels, distance, 60.0, 1080.0};
      const Index level = level_for_view(pm, view);
      EXPECT_LE(projected_pixels(pm.level_error[level], radius, view), pixels);
      if (level > 0) {
        EXPECT_GT(projected_pixels(pm.level_error[level - 1], radius, view), pixels);
      }
    }
  }
  // Farther away never needs a finer level.
  EXPECT_LE(level_for_view(pm, {1.0, 50.0, 60.0, 1080.0}), level_for_view(pm, {1.0, 5.0, 60.0, 1080.0}));
  // Inside the bounding sphere: the finest level.
  EXPECT_EQ(level_for_view(pm, {1.0, 0.5 * radius, 60.0, 1080.0}), pm.max_level());
  EXPECT_THROW(level_for_view(pm, {1.0, 10.0, 0.0, 1080.0}), Error);
  // pixels = error * H / (2 d tan(fov/2)): 0.01 at d = 10 - r over 1000 px, 90 degrees.
  EXPECT_NEAR(projected_pixels(0.01, 1.0, {1.0, 11.0, 90.0, 1000.0}), 0.01 * 1000 / 20.0, 1e-12);
}

TEST(LevelSelection, FaceCountsAndErrors) {
  const ProgressiveMesh pm = build_progressive_mesh(test::bumpy_sphere(3, 0.05));
  const Index full = pm.num_faces(pm.max_level());
  EXPECT_EQ(level_for_faces(pm, full), pm.max_level());
  EXPECT_EQ(level_for_faces(pm, 0), 0);
  const Index l = level_for_faces(pm, full / 2);
  EXPECT_LE(pm.num_faces(l), full / 2);
  EXPECT_GT(pm.num_faces(l + 1), full / 2);
  const double budget = pm.level_error[pm.max_level() / 2];
  const Index e = level_for_error(pm, budget);
  EXPECT_LE(pm.level_error[e], budget);
  if (e > 0) {
    EXPECT_GT(pm.level_error[e - 1], budget);
  }
}

}  // namespace
}  // namespace lodkit
