// HausdorffChecker (a proved yes or a point farther) and simplify_within() built on it.
#include <gtest/gtest.h>
#include <lodkit/error.h>
#include <lodkit/inspect.h>
#include <lodkit/metrics.h>
#include <lodkit/primitives.h>
#include <lodkit/simplify.h>

#include <cmath>

#include "test_util.h"

namespace lodkit {
namespace {

TEST(HausdorffCheck, DecidesAPlaneAndADisplacedPlaneAtTheirExactDistance) {
  const Mesh a = make_grid({.size = {2, 1}, .divisions_x = 8, .divisions_y = 4});
  Mesh b = a;
  b.positions.col(2).array() += 0.05;
  const HausdorffChecker checker(a);
  const HausdorffCheck above = checker.check(b, 0.05 * (1 + 1e-9));
  EXPECT_TRUE(above.within);
  EXPECT_LE(above.bound, 0.05 * (1 + 1e-9));
  EXPECT_NEAR(above.attained, 0.05, 1e-12);
  const HausdorffCheck below = checker.check(b, 0.05 * (1 - 1e-6));
  EXPECT_FALSE(below.within);
  EXPECT_GT(below.attained, 0.05 * (1 - 1e-6));
}

TEST(HausdorffCheck, AgreesWithCompareOnASimplifiedSurface) {
  // Its answer brackets compare()'s: a limit just above compare's proved bound passes, and a limit just
  // below a distance compare attained at a point fails, naming a point farther than the limit. Both
  // directions are tried: a sphere's simplification lies inside it (its points near the input), while a
  // patch against a larger plane is far one way only.
  const Mesh fine = test::bumpy_sphere(3, 0.05);
  SimplifyOptions o;
  o.target_ratio = 0.05;
  const Mesh coarse = simplify(fine, o).mesh;
  const Comparison c = compare(fine, coarse);
  const HausdorffChecker checker(fine);
  const HausdorffCheck yes = checker.check(coarse, c.hausdorff_bound * (1 + 1e-6));
  EXPECT_TRUE(yes.within);
  EXPECT_LE(yes.bound, c.hausdorff_bound * (1 + 1e-6));
  EXPECT_GE(yes.bound, c.hausdorff * (1 - 1e-9));  // no proof goes below a distance attained
  const HausdorffCheck no = checker.check(coarse, c.hausdorff * (1 - 1e-3));
  EXPECT_FALSE(no.within);
  EXPECT_GT(no.attained, c.hausdorff * (1 - 1e-3));
  EXPECT_LE(no.attained, c.hausdorff_bound);

  const Mesh plane = make_grid({.size = {4, 4}, .divisions_x = 4, .divisions_y = 4});
  Mesh patch = make_grid({.size = {1, 1}, .divisions_x = 2, .divisions_y = 2});
  patch.positions.col(2).array() += 0.1;
  const double far_corner = std::sqrt(2 * 1.5 * 1.5 + 0.01);  // the plane's corners, from the patch
  for (const bool patch_first : {true, false}) {
    const HausdorffChecker one(patch_first ? patch : plane);
    const Mesh& other = patch_first ? plane : patch;
    EXPECT_TRUE(one.check(other, far_corner * (1 + 1e-9)).within);
    const HausdorffCheck miss = one.check(other, 1.0);
    EXPECT_FALSE(miss.within);
    EXPECT_GT(miss.attained, 1.0);
  }
}

TEST(SimplifyWithin, RefitLevelsGoCoarserAndStayProvedWithin) {
  // By default (quadric) the levels are refit before they are checked: the output has no more faces
  // than the collapses' own level, is proved and measured within the limit, and a refit level at most
  // 1/16 of its faces coarser was checked and failed.
  const Mesh fine = test::bumpy_sphere(4, 0.04);
  const double diagonal = bounding_box(fine).diagonal().norm();
  SimplifyOptions unrefit;
  unrefit.refit_passes = 0;
  for (const double percent : {0.3, 1.0}) {
    SCOPED_TRACE(percent);
    const double limit = percent / 100 * diagonal;
    const SimplifyResult r = simplify_within(fine, limit);
    const SimplifyResult plain = simplify_within(fine, limit, unrefit);
    ASSERT_TRUE(r.within && r.refit);
    EXPECT_LT(r.faces_out, plain.faces_out);
    EXPECT_LE(r.within->bound, limit);
    const Comparison c = compare(fine, r.mesh);
    EXPECT_LE(c.hausdorff, limit);
    ASSERT_TRUE(r.within->coarser_faces);
    EXPECT_LT(*r.within->coarser_faces, r.faces_out);
    EXPECT_LE(r.faces_out - *r.within->coarser_faces, std::max<Index>(2, r.faces_out / 16));
    EXPECT_GT(r.within->coarser_attained, limit);
    const MeshReport report = inspect(r.mesh);
    EXPECT_TRUE(report.closed);
    EXPECT_EQ(report.euler_characteristic, inspect(fine).euler_characteristic);
    EXPECT_EQ(count_flipped_faces(fine, r.mesh), 0);
  }
}

TEST(HausdorffCheck, RefusesEmptyMeshesAndBadLimits) {
  EXPECT_THROW(HausdorffChecker(Mesh{}), Error);
  const Mesh box = make_box({});
  const HausdorffChecker checker(box);
  EXPECT_THROW(checker.check(Mesh{}, 1.0), Error);
  EXPECT_THROW(checker.check(box, -1.0), Error);
  EXPECT_THROW(checker.check(box, std::nan("")), Error);
  // A surface is 0 from itself, up to rounding (a centroid's distance comes out near 1e-17).
  const HausdorffCheck self = checker.check(box, 1e-12);
  EXPECT_TRUE(self.within);
  EXPECT_LE(self.bound, 1e-15);
}

TEST(SimplifyWithin, TheLevelFoundIsWithinAndALevelJustCoarserIsNot) {
  // The collapses' own levels (no refit): the search over the progressive mesh.
  const Mesh fine = test::bumpy_sphere(3, 0.05);
  const double diagonal = bounding_box(fine).diagonal().norm();
  SimplifyOptions unrefit;
  unrefit.refit_passes = 0;
  for (const double percent : {0.2, 1.0, 3.0}) {
    const double limit = percent / 100 * diagonal;
    const SimplifyResult r = simplify_within(fine, limit, unrefit);
    EXPECT_FALSE(r.refit);
    ASSERT_TRUE(r.within);
    EXPECT_EQ(r.reason, StopReason::HausdorffLimit) << r.reason_text;
    EXPECT_LE(r.within->bound, limit);
    EXPECT_GT(r.within->checks, 0);
    EXPECT_LT(r.faces_out, fine.num_faces());
    // Measured independently: within the limit; and a level at most 1/256 of the faces coarser lies
    // beyond it.
    EXPECT_LE(compare(fine, r.mesh).hausdorff, limit);
    ASSERT_TRUE(r.within->coarser_faces);
    EXPECT_LT(*r.within->coarser_faces, r.faces_out);
    EXPECT_LE(r.faces_out - *r.within->coarser_faces, std::max<Index>(2, r.faces_out / 256));
    EXPECT_GT(r.within->coarser_attained, limit);
    SimplifyOptions o;
    o.refit_passes = 0;  // the levels checked are the collapses' own, as a progressive mesh keeps them
    o.target_faces = *r.within->coarser_faces;
    const SimplifyResult coarser = simplify(fine, o);
    ASSERT_EQ(coarser.faces_out, *r.within->coarser_faces);
    EXPECT_GT(compare(fine, coarser.mesh).hausdorff_bound, limit);
    // The output is simplify()'s to the same face count without a refit, and keeps the topology.
    o.target_faces = r.faces_out;
    const SimplifyResult same = simplify(fine, o);
    EXPECT_EQ(same.mesh.positions, r.mesh.positions);
    EXPECT_EQ(same.mesh.triangles, r.mesh.triangles);
    const MeshReport report = inspect(r.mesh);
    EXPECT_TRUE(report.closed);
    EXPECT_EQ(report.euler_characteristic, inspect(fine).euler_characteristic);
  }
}

TEST(SimplifyWithin, SameAnswerForAnyThreadCount) {
  const Mesh fine = test::bumpy_sphere(3, 0.05);
  const double limit = 0.01 * bounding_box(fine).diagonal().norm();
  const SimplifyResult one = test::on_threads(1, [&] { return simplify_within(fine, limit); });
  const SimplifyResult many = test::on_threads(4, [&] { return simplify_within(fine, limit); });
  EXPECT_EQ(one.mesh.positions, many.mesh.positions);
  EXPECT_EQ(one.mesh.triangles, many.mesh.triangles);
  EXPECT_EQ(one.within->bound, many.within->bound);
  EXPECT_EQ(one.within->checks, many.within->checks);
  EXPECT_EQ(one.within->coarser_attained, many.within->coarser_attained);
}

TEST(SimplifyWithin, StopsAtTheTargetOrTheInputAndRefusesBadLimits) {
  const Mesh fine = test::bumpy_sphere(2, 0.05);
  // A limit no level exceeds: the target is the output, proved by the collapses' guaranteed bound alone.
  SimplifyOptions o;
  o.target_faces = 100;
  const SimplifyResult generous = simplify_within(fine, 10.0, o);
  EXPECT_EQ(generous.reason, StopReason::TargetReached) << generous.reason_text;
  EXPECT_LE(generous.faces_out, 100);
  EXPECT_LE(generous.within->bound, 10.0);
  // A limit of 0: only the input itself is 0 from the input.
  const SimplifyResult none = simplify_within(fine, 0.0);
  EXPECT_EQ(none.faces_out, fine.num_faces());
  EXPECT_EQ(none.mesh.positions, fine.positions);
  EXPECT_THROW(simplify_within(fine, -1.0), Error);
  EXPECT_THROW(simplify_within(fine, INFINITY), Error);
}

}  // namespace
}  // namespace lodkit
