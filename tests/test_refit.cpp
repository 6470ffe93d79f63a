// refit_to_input(): a simplification's vertices fitted to its input, with nothing else changed.
#include <gtest/gtest.h>
#include <lodkit/error.h>
#include <lodkit/inspect.h>
#include <lodkit/metrics.h>
#include <lodkit/primitives.h>
#include <lodkit/simplify.h>

#include <map>

#include "test_util.h"

namespace lodkit {
namespace {

SimplifyResult unrefit(const Mesh& mesh, double ratio) {
  SimplifyOptions o;
  o.target_ratio = ratio;
  o.refit_passes = 0;
  return simplify(mesh, o);
}

TEST(Refit, LowersTheCertifiedHausdorffDistanceAndKeepsEverythingButPositions) {
  for (const Mesh& fine : {test::bumpy_sphere(5, 0.03), make_torus({.major_segments = 128, .minor_segments = 48})}) {
    for (const double ratio : {0.05, 0.01}) {
      SCOPED_TRACE(ratio);
      const SimplifyResult coarse = unrefit(fine, ratio);
      Mesh refit = coarse.mesh;
      const RefitReport report = refit_to_input(fine, refit, {}, coarse.face_origin);
      EXPECT_GT(report.steps, 0);
      EXPECT_LT(report.sampled_max_after, report.sampled_max_before);
      EXPECT_GT(report.moved_vertices, 0);
      const Comparison before = compare(fine, coarse.mesh), after = compare(fine, refit);
      // Certified, not sampled: the largest distance anywhere on either surface went down.
      EXPECT_LT(after.hausdorff_bound, 0.9 * before.hausdorff);
      EXPECT_LT(after.rms, before.rms);
      // Only positions changed: same faces, same attributes, same topology, nothing flipped.
      EXPECT_EQ(refit.triangles, coarse.mesh.triangles);
      EXPECT_EQ(refit.num_vertices(), coarse.mesh.num_vertices());
      const MeshReport a = inspect(refit), b = inspect(coarse.mesh);
      EXPECT_TRUE(a.manifold);
      EXPECT_EQ(a.euler_characteristic, b.euler_characteristic);
      EXPECT_EQ(a.degenerate_faces, 0);
      EXPECT_EQ(count_flipped_faces(fine, refit), 0);
    }
  }
}

TEST(Refit, TheRmsStageLowersTheRmsAndKeepsTheLargestDistances) {
  for (const Mesh& fine : {test::bumpy_sphere(5, 0.03), make_torus({.major_segments = 128, .minor_segments = 48})}) {
    const SimplifyResult coarse = unrefit(fine, 0.02);
    Mesh first = coarse.mesh, both = coarse.mesh;
    const RefitReport a = refit_to_input(fine, first, {.rms_passes = 0}, coarse.face_origin);
    const RefitReport b = refit_to_input(fine, both, {}, coarse.face_origin);
    EXPECT_EQ(a.rms_steps, 0);
    EXPECT_GT(b.rms_steps, 0);
    // The guard: no sample got farther than the first stage's largest.
    EXPECT_EQ(b.sampled_max_after, a.sampled_max_after);
    EXPECT_LT(b.sampled_rms_after, 0.97 * a.sampled_rms_after);
    const Comparison ca = compare(fine, first), cb = compare(fine, both);
    EXPECT_LT(cb.rms, 0.97 * ca.rms);
    EXPECT_LT(cb.hausdorff_bound, 1.02 * ca.hausdorff);
    EXPECT_EQ(count_flipped_faces(fine, both), 0);
    EXPECT_TRUE(inspect(both).manifold);
  }
}

TEST(Refit, SamplesThatKeepTheirFaceLeaveTheLargestDistanceExactAndTheErrorsAsTheyWere) {
  for (const Mesh& fine : {test::bumpy_sphere(5, 0.03), make_torus({.major_segments = 128, .minor_segments = 48})}) {
    const SimplifyResult coarse = unrefit(fine, 0.05);
    // The largest sampled distance a refit reports is that of its samples at its result, exactly, even
    // where every sample that can keeps its face (their distances are upper bounds). A refit of one pass
    // measures every sample with a search and moves nothing.
    Mesh keeping = coarse.mesh;
    const RefitReport most = refit_to_input(fine, keeping, {.rms_passes = 0, .keep_face_below = 1}, coarse.face_origin);
    ASSERT_GT(most.steps, 1);
    Mesh again = keeping;
    const RefitReport measured = refit_to_input(fine, again, {.passes = 1, .rms_passes = 0}, coarse.face_origin);
    EXPECT_EQ(again.positions, keeping.positions);
    EXPECT_EQ(measured.sampled_max_before, most.sampled_max_after);

    // The default against every sample searched every pass: the same errors, within 5 %.
    Mesh searched = coarse.mesh, kept = coarse.mesh;
    refit_to_input(fine, searched, {.keep_face_below = 0}, coarse.face_origin);
    refit_to_input(fine, kept, {}, coarse.face_origin);
    EXPECT_NE(searched.positions, kept.positions);
    const Comparison a = compare(fine, searched), b = compare(fine, kept);
    EXPECT_LT(b.hausdorff_bound, 1.05 * a.hausdorff);
    EXPECT_LT(b.rms, 1.05 * a.rms);
    EXPECT_EQ(count_flipped_faces(fine, kept), 0);
    EXPECT_TRUE(inspect(kept).manifold);
  }
}

TEST(Refit, NoSampleKeepsAFaceWithoutArea) {
  // Every edge of the input is also a face without area, listed before the real faces, so that samples
  // nearest an edge find that face first. It has no inside: a sample that kept it would stay pulled
  // towards the edge (before the fix, Hausdorff +3.7 % against every sample searched).
  const Mesh clean = test::bumpy_sphere(5, 0.03);
  const Index n = clean.num_faces();
  Mesh fine = clean;
  fine.triangles.resize(4 * n, 3);
  for (Index f = 0; f < n; ++f)
    for (int k = 0; k < 3; ++k) {
      const Index a = clean.triangles(f, k), b = clean.triangles(f, (k + 1) % 3);
      fine.triangles.row(3 * f + k) << a, b, b;
    }
  fine.triangles.bottomRows(n) = clean.triangles;
  const SimplifyResult coarse = unrefit(clean, 0.05);
  Mesh searched = coarse.mesh, kept = coarse.mesh;
  refit_to_input(fine, searched, {.keep_face_below = 0});
  refit_to_input(fine, kept, {});
  EXPECT_LT(compare(clean, kept).hausdorff, 1.02 * compare(clean, searched).hausdorff);
}

TEST(Refit, SimplifyRunsItByDefaultForQuadricAndHoppeAndReportsIt) {
  const Mesh fine = test::bumpy_sphere(5, 0.03);
  SimplifyOptions o;
  o.target_ratio = 0.02;
  const SimplifyResult r = simplify(fine, o);
  ASSERT_TRUE(r.refit);
  EXPECT_GT(r.refit->passes, default_refit_passes(SimplifyMethod::Quadric, fine.num_faces()));  // and the RMS stage's
  EXPECT_GT(r.refit->rms_steps, 0);
  EXPECT_LT(r.refit->sampled_max_after, r.refit->sampled_max_before);
  const SimplifyResult without = unrefit(fine, 0.02);
  EXPECT_FALSE(without.refit);
  EXPECT_EQ(r.mesh.triangles, without.mesh.triangles);
  EXPECT_LT(compare(fine, r.mesh).hausdorff_bound, compare(fine, without.mesh).hausdorff);
  // hoppe too: the same faces, nearer the input, and fewer facing against it (its collapses allow them; the
  // refit does not add any and turns most of theirs).
  o.method = SimplifyMethod::Hoppe;
  const SimplifyResult hoppe = simplify(fine, o);
  ASSERT_TRUE(hoppe.refit);
  o.refit_passes = 0;
  const SimplifyResult hoppe_unrefit = simplify(fine, o);
  o.refit_passes.reset();
  EXPECT_FALSE(hoppe_unrefit.refit);
  EXPECT_EQ(hoppe.mesh.triangles, hoppe_unrefit.mesh.triangles);
  EXPECT_LT(compare(fine, hoppe.mesh).hausdorff_bound, compare(fine, hoppe_unrefit.mesh).hausdorff);
  EXPECT_LT(compare(fine, hoppe.mesh).rms, compare(fine, hoppe_unrefit.mesh).rms);
  EXPECT_LT(count_flipped_faces(fine, hoppe.mesh), count_flipped_faces(fine, hoppe_unrefit.mesh));  // 2 against 11
  o.method = SimplifyMethod::Quadric;
  // Off by default where it is not wanted: edge-length, large inputs, recorded collapses.
  EXPECT_EQ(default_refit_passes(SimplifyMethod::Hoppe, 1000), 10);
  EXPECT_EQ(default_refit_passes(SimplifyMethod::EdgeLength, 1000), 0);
  EXPECT_EQ(default_refit_passes(SimplifyMethod::Hoppe, 1'000'000), 0);
  EXPECT_EQ(default_refit_passes(SimplifyMethod::Quadric, 1'000'000), 0);
  o.record_collapses = true;
  EXPECT_FALSE(simplify(fine, o).refit);
}

TEST(Refit, SeamsStayClosedAndALockedBoundaryStaysPut) {
  // Vertices split by a UV seam share a position before, and still do after.
  const Mesh sphere = make_uv_sphere({.segments = 64, .rings = 32, .uvs = true});
  SimplifyOptions o;
  o.target_ratio = 0.05;
  const SimplifyResult r = simplify(sphere, o);
  ASSERT_TRUE(r.refit && r.refit->moved_vertices > 0);
  const SimplifyResult before = unrefit(sphere, 0.05);
  std::map<std::array<double, 3>, std::vector<Index>> by_position;
  for (Index v = 0; v < before.mesh.num_vertices(); ++v)
    by_position[{before.mesh.positions(v, 0), before.mesh.positions(v, 1), before.mesh.positions(v, 2)}].push_back(v);
  Index shared = 0;
  for (const auto& [position, vertices] : by_position)
    for (const Index v : vertices) {
      shared += vertices.size() > 1;
      EXPECT_EQ(r.mesh.positions.row(v), r.mesh.positions.row(vertices.front()));
    }
  EXPECT_GT(shared, 0);
  EXPECT_TRUE(inspect(r.mesh).closed);

  // A locked boundary does not move in the refit either.
  Mesh grid = make_grid({.divisions_x = 40, .divisions_y = 40});
  for (Index v = 0; v < grid.num_vertices(); ++v)
    grid.positions(v, 2) = 0.05 * std::sin(7 * grid.positions(v, 0)) * std::cos(5 * grid.positions(v, 1));
  SimplifyOptions locked;
  locked.target_ratio = 0.1;
  locked.lock_boundary = true;
  const SimplifyResult l = simplify(grid, locked);
  ASSERT_TRUE(l.refit && l.refit->moved_vertices > 0);
  locked.refit_passes = 0;
  const SimplifyResult l0 = simplify(grid, locked);
  const MeshReport report = inspect(l.mesh);
  EXPECT_EQ(report.boundary_edges, inspect(l0.mesh).boundary_edges);
  Index boundary_vertices = 0;
  for (Index v = 0; v < l0.mesh.num_vertices(); ++v) {
    const double x = l0.mesh.positions(v, 0), y = l0.mesh.positions(v, 1);
    const bool on_boundary = std::abs(std::abs(x) - 0.5) < 1e-12 || std::abs(std::abs(y) - 0.5) < 1e-12;
    if (!on_boundary) continue;
    ++boundary_vertices;
    EXPECT_EQ(l.mesh.positions.row(v), l0.mesh.positions.row(v));
  }
  EXPECT_EQ(boundary_vertices, 160);
}

TEST(Refit, AnExactSimplificationStaysExact) {
  // A finely tessellated cube simplifies to its 12 triangles with zero error: nothing to fit.
  const Mesh cube = make_box({.divisions = 8});
  SimplifyOptions o;
  o.target_faces = 12;
  const SimplifyResult r = simplify(cube, o);
  ASSERT_EQ(r.faces_out, 12);
  ASSERT_TRUE(r.refit);
  EXPECT_LT(r.refit->sampled_max_before, 1e-12);  // rounding of the quadrics' solve at most
  EXPECT_LE(r.refit->sampled_max_after, r.refit->sampled_max_before);
  EXPECT_LT(compare(cube, r.mesh).hausdorff, 1e-9);
  ASSERT_TRUE(inspect(r.mesh).volume);
  EXPECT_NEAR(*inspect(r.mesh).volume, 1.0, 1e-9);
}

TEST(Refit, SameResultForAnyNumberOfThreads) {
  const Mesh fine = test::bumpy_sphere(4, 0.04);
  const SimplifyResult coarse = unrefit(fine, 0.05);
  Mesh one = coarse.mesh, many = coarse.mesh;
  test::on_threads(1, [&] { refit_to_input(fine, one, {}, coarse.face_origin); });
  test::on_threads(4, [&] { refit_to_input(fine, many, {}, coarse.face_origin); });
  EXPECT_EQ(one.positions, many.positions);
  // The solve splits the points among as many tasks as the arena runs at once.
  for (const int concurrency : {3, 5}) {
    Mesh split = coarse.mesh;
    test::on_threads(concurrency, [&] { refit_to_input(fine, split, {}, coarse.face_origin); });
    EXPECT_EQ(one.positions, split.positions) << concurrency;
  }
}

TEST(Refit, NoFaceComesToFaceAgainstTheInputOnAThinLens) {
  // A coarse face of a thin lens lies nearer the far side than its own; moving it must not turn it
  // against the side it comes nearest.
  const Mesh lens = test::thin_lens();
  for (const double ratio : {0.05, 0.01}) {
    SCOPED_TRACE(ratio);
    const SimplifyResult before = unrefit(lens, ratio);
    SimplifyOptions o;
    o.target_ratio = ratio;
    const SimplifyResult after = simplify(lens, o);
    ASSERT_TRUE(after.refit);
    EXPECT_LE(count_flipped_faces(lens, after.mesh), count_flipped_faces(lens, before.mesh));
  }
}

// A square sheet of n x n quads at height z, facing up or down.
Mesh sheet(double z, int n, bool up) {
  Mesh m;
  m.positions.resize((n + 1) * (n + 1), 3);
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) m.positions.row(i * (n + 1) + j) << double(i) / n, double(j) / n, z;
  m.triangles.resize(2 * n * n, 3);
  Index row = 0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const Index a = i * (n + 1) + j, b = a + n + 1, c = b + 1, d = a + 1;
      if (up) m.triangles.row(row++) << a, b, c, m.triangles.row(row++) << a, c, d;
      else m.triangles.row(row++) << a, c, b, m.triangles.row(row++) << a, d, c;
    }
  return m;
}

TEST(Refit, FacesFacingAgainstTheInputTurnToTheSheetThatFacesTheirWay) {
  // Two sheets back to back a twentieth apart (the lower facing up, the upper down), as where two parts
  // touch, and a coarse copy of each lying nearer the other's: each face of the copy faces against the
  // input face nearest it. Moved onto its own sheet, every face faces the input's way and lies on it.
  const double gap = 0.05;
  const Mesh input = concatenated(sheet(0, 4, true), sheet(gap, 4, false));
  const Mesh swapped = concatenated(sheet(0.7 * gap, 1, true), sheet(0.3 * gap, 1, false));
  ASSERT_EQ(count_flipped_faces(input, swapped), 4);
  Mesh refit = swapped;
  const RefitReport report = refit_to_input(input, refit, {.passes = 0, .rms_passes = 1});  // that step alone
  EXPECT_EQ(report.inverted_before, 4);
  EXPECT_EQ(report.inverted_after, 0);
  EXPECT_GE(report.turn_steps, 1);
  EXPECT_EQ(count_flipped_faces(input, refit), 0);
  EXPECT_LT(compare(input, refit).hausdorff_bound, 1e-9);
  EXPECT_EQ(refit.triangles, swapped.triangles);
  // With both stages as simplify() runs them (here the first stage alone may turn them), where the copy
  // is the smaller, so that the sheets' rims set the largest distance.
  Mesh wider = input;
  wider.positions.leftCols(2) = (wider.positions.leftCols(2).array() * 1.5 - 0.25).matrix();
  Mesh both = swapped;
  refit_to_input(wider, both, {});
  EXPECT_EQ(count_flipped_faces(wider, both), 0);
  EXPECT_LE(compare(wider, both).hausdorff_bound, compare(wider, swapped).hausdorff);
  // Not at all where the caller allows such faces.
  Mesh allowed = swapped;
  EXPECT_EQ(refit_to_input(input, allowed, {.passes = 0, .avoid_inverted = false, .rms_passes = 1}).turn_steps, 0);
  EXPECT_EQ(count_flipped_faces(input, allowed), 4);
}

TEST(Refit, BadOptionsAreErrors) {
  const Mesh fine = test::bumpy_sphere(2, 0.03);
  Mesh coarse = unrefit(fine, 0.3).mesh;
  EXPECT_THROW(refit_to_input(fine, coarse, {.passes = -1}), Error);
  EXPECT_THROW(refit_to_input(fine, coarse, {.step = 0}), Error);
  EXPECT_THROW(refit_to_input(fine, coarse, {.step = 1.5}), Error);
  EXPECT_THROW(refit_to_input(fine, coarse, {.exponent = -1}), Error);
  const std::vector<Index> too_few(3, 0);
  EXPECT_THROW(refit_to_input(fine, coarse, {}, too_few), Error);
  SimplifyOptions o;
  o.refit_passes = -2;
  EXPECT_THROW(simplify(fine, o), Error);
  EXPECT_THROW(refit_to_input(fine, coarse, {.rms_passes = -1}), Error);
  EXPECT_THROW(refit_to_input(fine, coarse, {.rms_guard = 1.5}), Error);
  EXPECT_THROW(refit_to_input(fine, coarse, {.keep_face_below = -0.1}), Error);
  EXPECT_THROW(refit_to_input(fine, coarse, {.keep_face_below = 1.5}), Error);
  for (const double bad : {0.0, 200.0, std::nan("")}) {  // (a NaN turn limit let every face turn)
    EXPECT_THROW(refit_to_input(fine, coarse, {.max_step_turn_deg = bad}), Error) << bad;
    EXPECT_THROW(refit_to_input(fine, coarse, {.max_total_turn_deg = bad}), Error) << bad;
  }
  EXPECT_THROW(refit_to_input(fine, coarse, {.min_triangle_quality = 2}), Error);
  o.refit_passes.reset();
  o.refit_rms_passes = -1;
  EXPECT_THROW(simplify(fine, o), Error);
  // Zero passes change nothing.
  const Mesh copy = coarse;
  refit_to_input(fine, coarse, {.passes = 0, .rms_passes = 0});
  EXPECT_EQ(coarse.positions, copy.positions);
}

}  // namespace
}  // namespace lodkit
