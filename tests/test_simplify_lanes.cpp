// Slabs simplified side by side first (SimplifyOptions::lane_faces): the promises of one queue, the
// same answer for any thread count, and errors close to one queue's.
#include <gtest/gtest.h>
#include <lodkit/inspect.h>
#include <lodkit/metrics.h>
#include <lodkit/primitives.h>
#include <lodkit/simplify.h>

#include <tbb/global_control.h>

#include "test_util.h"

namespace lodkit {
namespace {

void expect_valid(const Mesh& input, const SimplifyResult& r, Index target) {
  const MeshReport before = inspect(input), after = inspect(r.mesh);
  EXPECT_TRUE(after.manifold);
  EXPECT_TRUE(after.oriented);
  EXPECT_EQ(after.euler_characteristic, before.euler_characteristic);
  EXPECT_EQ(after.boundary_loops, before.boundary_loops);
  EXPECT_EQ(after.components, before.components);
  EXPECT_EQ(after.degenerate_faces, 0);
  EXPECT_EQ(count_flipped_faces(input, r.mesh), 0);
  EXPECT_EQ(r.reason, StopReason::TargetReached) << r.reason_text;
  EXPECT_LE(r.faces_out, target);
  EXPECT_GE(r.faces_out, target - 1);
}

TEST(SimplifyLanes, KeepTheInvariantsAndStayCloseToOneQueue) {
  const Mesh m = make_torus({.major_segments = 256, .minor_segments = 40});  // 20,480 faces: 8 slabs
  for (const double ratio : {0.1, 0.01}) {
    SCOPED_TRACE(ratio);
    const Index target = static_cast<Index>(std::llround(ratio * m.num_faces()));
    SimplifyOptions o{.target_ratio = ratio, .lane_faces = 0};
    const SimplifyResult one = simplify(m, o);
    o.lane_faces = 2500;
    const SimplifyResult lanes = simplify(m, o);
    EXPECT_EQ(one.lanes, 1);
    EXPECT_EQ(lanes.lanes, 8);
    expect_valid(m, lanes, target);
    // The rims wait for the last part; the surface should hardly notice.
    const Comparison a = compare(m, one.mesh), b = compare(m, lanes.mesh);
    EXPECT_LE(b.rms, 1.05 * a.rms);
    EXPECT_LE(b.hausdorff, 1.25 * a.hausdorff);
  }
}

TEST(SimplifyLanes, KeepBoundariesAndSeams) {
  const Mesh grid = make_grid({.divisions_x = 200, .divisions_y = 100});
  const Mesh sphere = make_uv_sphere({.segments = 192, .rings = 96, .uvs = true});
  for (const Mesh* m : {&grid, &sphere}) {
    const SimplifyOptions o{.target_ratio = 0.05, .lane_faces = 4000};
    const SimplifyResult r = simplify(*m, o);
    EXPECT_GE(r.lanes, 4);
    expect_valid(*m, r, static_cast<Index>(std::llround(0.05 * m->num_faces())));
  }
}

TEST(SimplifyLanes, SameResultForAnyNumberOfThreads) {
  const Mesh m = test::bumpy_sphere(5, 0.02);
  const SimplifyOptions o{.target_ratio = 0.05, .lane_faces = 2500};
  SimplifyResult one;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = simplify(m, o);
  }
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 4);
  const SimplifyResult many = simplify(m, o);
  EXPECT_EQ(one.lanes, 8);
  EXPECT_EQ(one.mesh.positions, many.mesh.positions);
  EXPECT_EQ(one.mesh.triangles, many.mesh.triangles);
  EXPECT_EQ(one.error, many.error);
}

}  // namespace
}  // namespace lodkit
