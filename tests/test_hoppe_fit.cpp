// hoppe's fit after the collapses (SimplifyOptions::hoppe_fit_passes): the position step of "Mesh
// optimization", held to the collapses' limits.
#include <gtest/gtest.h>
#include <lodkit/error.h>
#include <lodkit/inspect.h>
#include <lodkit/metrics.h>
#include <lodkit/primitives.h>
#include <lodkit/simplify.h>

#include <cmath>
#include <numbers>

#include "test_util.h"

namespace lodkit {
namespace {

SimplifyResult hoppe(const Mesh& mesh, double ratio, int fit_passes) {
  SimplifyOptions o{.method = SimplifyMethod::Hoppe, .target_ratio = ratio};
  o.hoppe_fit_passes = fit_passes;
  o.refit_passes = 0;  // hoppe's fit alone: the refit that follows by default would move the vertices again
  return simplify(mesh, o);
}

Eigen::Vector3d unit_normal(const Mesh& m, Index f) {
  const Eigen::Vector3d a = m.positions.row(m.triangles(f, 0)), b = m.positions.row(m.triangles(f, 1)),
                        c = m.positions.row(m.triangles(f, 2));
  return (b - a).cross(c - a).normalized();
}

// The fit moves vertices only: the same faces, and the energy it reports and the RMS distance both lower.
TEST(HoppeFit, LowersTheEnergyAndTheRmsDistanceWithTheConnectivityUnchanged) {
  const Mesh sphere = test::bumpy_sphere(4, 0.05);
  for (const double ratio : {0.1, 0.3}) {
    SCOPED_TRACE(ratio);
    const SimplifyResult unfit = hoppe(sphere, ratio, 0), fit = hoppe(sphere, ratio, 1), three = hoppe(sphere, ratio, 3);
    EXPECT_FALSE(unfit.hoppe_fit);
    ASSERT_TRUE(fit.hoppe_fit && three.hoppe_fit);
    ASSERT_EQ(fit.mesh.triangles, unfit.mesh.triangles);
    ASSERT_EQ(three.mesh.triangles, unfit.mesh.triangles);
    EXPECT_NE(fit.mesh.positions, unfit.mesh.positions);
    EXPECT_EQ(fit.hoppe_fit->passes, 1);
    EXPECT_LT(fit.hoppe_fit->energy_after, 0.95 * fit.hoppe_fit->energy_before);
    // Later passes hand the points to their nearest faces and lower it further.
    EXPECT_EQ(three.hoppe_fit->energy_before, fit.hoppe_fit->energy_before);
    EXPECT_LT(three.hoppe_fit->energy_after, fit.hoppe_fit->energy_after);
    EXPECT_LT(compare(sphere, fit.mesh).rms, 0.97 * compare(sphere, unfit.mesh).rms);
    EXPECT_EQ(inspect(fit.mesh).euler_characteristic, 2);
    EXPECT_TRUE(inspect(fit.mesh).manifold);
  }
}

// At 10 % of the bumpy sphere the solve would turn some faces too far: those moves are sent back, and no
// face turns further from where the collapses left it than one collapse may turn it (60 degrees), nor
// from its input face past hoppe's 60-degree limit where it kept within it.
TEST(HoppeFit, SendsBackTheMovesThatWouldTurnAFaceTooFar) {
  const Mesh sphere = test::bumpy_sphere(4, 0.05);
  const SimplifyResult unfit = hoppe(sphere, 0.1, 0), fit = hoppe(sphere, 0.1, 3);
  ASSERT_TRUE(fit.hoppe_fit);
  EXPECT_GT(fit.hoppe_fit->points_sent_back, 0) << "the sphere no longer exercises the limits";
  const double cos_limit = std::cos(60.0 * std::numbers::pi / 180.0);
  for (Index f = 0; f < fit.mesh.num_faces(); ++f) {
    const Eigen::Vector3d was = unit_normal(unfit.mesh, f), now = unit_normal(fit.mesh, f);
    const Eigen::Vector3d input = unit_normal(sphere, fit.face_origin[std::size_t(f)]);
    EXPECT_GE(now.dot(was), cos_limit - 1e-9) << "face " << f;
    if (was.dot(input) >= cos_limit) {
      EXPECT_GE(now.dot(input), cos_limit - 1e-9) << "face " << f;
    }
  }
}

// A wavy square patch: open, with a boundary whose points the fit holds to their edges.
Mesh wavy_patch() {
  Mesh patch = make_grid({.size = {1.0, 1.0}, .divisions_x = 40, .divisions_y = 40});
  for (Index v = 0; v < patch.num_vertices(); ++v)
    patch.positions(v, 2) = 0.05 * std::sin(7 * patch.positions(v, 0)) * std::cos(5 * patch.positions(v, 1));
  return patch;
}

// The fit's sums run in face order and its boundary edges in key order (the lanes fill the map in any
// order), so lanes on one thread or four give the same bits, over passes that hand points to new faces.
TEST(HoppeFit, SameResultForAnyNumberOfThreads) {
  const Mesh patch = wavy_patch();
  SimplifyOptions o{.method = SimplifyMethod::Hoppe, .target_ratio = 0.1, .lane_faces = 400};
  o.hoppe_fit_passes = 3;
  const auto run = [&] { return simplify(patch, o); };
  const SimplifyResult one = test::on_threads(1, run), many = test::on_threads(4, run);
  EXPECT_EQ(one.lanes, 8);
  ASSERT_TRUE(one.hoppe_fit && many.hoppe_fit);
  EXPECT_GT(one.hoppe_fit->passes, 1);
  EXPECT_EQ(one.hoppe_fit->energy_after, many.hoppe_fit->energy_after);
  EXPECT_EQ(one.mesh.positions, many.mesh.positions);
  EXPECT_EQ(one.mesh.triangles, many.mesh.triangles);
}

// A locked boundary stays where the input has it; the rest of the patch is fitted.
TEST(HoppeFit, LeavesALockedBoundaryInPlace) {
  const Mesh patch = wavy_patch();
  SimplifyOptions o{.method = SimplifyMethod::Hoppe, .target_ratio = 0.1};
  o.lock_boundary = true;
  const SimplifyResult r = simplify(patch, o);
  o.hoppe_fit_passes = 0;
  const SimplifyResult unfit = simplify(patch, o);
  ASSERT_TRUE(r.hoppe_fit);
  ASSERT_EQ(r.vertex_origin, unfit.vertex_origin);
  Index moved = 0, boundary = 0;
  for (Index v = 0; v < r.mesh.num_vertices(); ++v) {
    const Eigen::Vector3d p = patch.positions.row(r.vertex_origin[std::size_t(v)]);
    if (std::abs(std::abs(p.x()) - 0.5) < 1e-12 || std::abs(std::abs(p.y()) - 0.5) < 1e-12) {
      ++boundary;
      EXPECT_EQ(Eigen::Vector3d(r.mesh.positions.row(v)), p) << "vertex " << v;
    }
    moved += r.mesh.positions.row(v) != unfit.mesh.positions.row(v);
  }
  EXPECT_EQ(boundary, 160);
  EXPECT_GT(moved, r.mesh.num_vertices() / 4);
}

// No fit where a progressive mesh records the collapses (its levels keep their positions), without
// the topology checks, or for the other methods; a negative pass count is refused.
TEST(HoppeFit, RunsOnlyForHoppeAndPlainRuns) {
  const Mesh sphere = test::bumpy_sphere(3, 0.05);
  SimplifyOptions o{.method = SimplifyMethod::Hoppe, .target_ratio = 0.2};
  EXPECT_TRUE(simplify(sphere, o).hoppe_fit);
  o.record_collapses = true;
  EXPECT_FALSE(simplify(sphere, o).hoppe_fit);
  o.record_collapses = false;
  o.preserve_topology = false;
  EXPECT_FALSE(simplify(sphere, o).hoppe_fit);
  EXPECT_FALSE(simplify(sphere, {.target_ratio = 0.2}).hoppe_fit);
  o.preserve_topology = true;
  o.hoppe_fit_passes = -1;
  EXPECT_THROW(simplify(sphere, o), Error);
}

}  // namespace
}  // namespace lodkit
