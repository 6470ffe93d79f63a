// The stability suite's fast part: meshes built to make simplifiers fail. The default method must
// never output a non-manifold edge it did not get, a flipped face, a non-finite coordinate, or a
// changed genus, components or boundary count — at any target, down to the smallest legal mesh.
#include <gtest/gtest.h>
#include <lodkit/inspect.h>
#include <lodkit/metrics.h>
#include <lodkit/primitives.h>
#include <lodkit/simplify.h>

#include <random>

#include "test_util.h"

namespace lodkit {
namespace {

Mesh transformed(Mesh m, double scale, double offset) {
  m.positions = (m.positions.array() * scale + offset).matrix();
  return m;
}

Mesh grid_with_hole() {
  Mesh g = make_grid({.divisions_x = 30, .divisions_y = 30});
  Mesh out = g;
  Index kept = 0;
  for (Index f = 0; f < g.num_faces(); ++f) {
    const Eigen::RowVector3d c = (g.positions.row(g.triangles(f, 0)) + g.positions.row(g.triangles(f, 1)) +
                                  g.positions.row(g.triangles(f, 2))) / 3.0;
    if (c.norm() > 0.2) out.triangles.row(kept++) = g.triangles.row(f);
  }
  out.triangles.conservativeResize(kept, 3);
  remove_unreferenced_vertices(out);
  return out;
}

Mesh two_boxes_sharing_an_edge() {
  Mesh a = make_box({.divisions = 6});
  Mesh b = a;
  b.positions.rowwise() += Eigen::RowVector3d(1, 1, 0);
  return concatenated(a, b);  // the shared edge is welded by position: non-manifold
}

Mesh unwelded_with_unreferenced() {
  // Every face with its own three vertices (a "soup" of a closed surface), plus stray vertices.
  const Mesh s = test::bumpy_sphere(3, 0.01);
  Mesh m;
  m.positions.resize(3 * s.num_faces() + 5, 3);
  m.triangles.resize(s.num_faces(), 3);
  for (Index f = 0; f < s.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      m.positions.row(3 * f + k) = s.positions.row(s.triangles(f, k));
      m.triangles(f, k) = 3 * f + k;
    }
  m.positions.bottomRows(5).setConstant(7.0);
  return m;
}

Mesh grid_with_slivers() {
  Mesh g = make_grid({.divisions_x = 20, .divisions_y = 20});
  // Push some interior vertices onto a neighbour's edge line: zero-area triangles.
  for (Index v : {50, 51, 120, 200, 310}) g.positions(v, 0) = g.positions(v - 1, 0);
  return g;
}

struct Case {
  std::string name;
  Mesh mesh;
};

std::vector<Case> suite() {
  return {{"sharp_box", make_box({.size = {2, 1, 0.5}, .divisions = 10})},
          {"thin_plate", make_box({.size = {1, 1, 0.001}, .divisions = 12})},
          {"fine_cylinder", make_cylinder({.radius = 0.2, .height = 3, .segments = 64, .stacks = 30})},
          {"grid_with_hole", grid_with_hole()},
          {"shared_edge", two_boxes_sharing_an_edge()},
          {"soup_and_strays", unwelded_with_unreferenced()},
          {"slivers", grid_with_slivers()},
          {"noisy_sphere", test::bumpy_sphere(4, 0.03)},
          {"far_away", transformed(test::bumpy_sphere(4, 0.02), 1.0, 1e6)},
          {"tiny", transformed(test::bumpy_sphere(4, 0.02), 1e-6, 0.0)},
          {"uv_seams", make_uv_sphere({.segments = 48, .rings = 24, .uvs = true})},
          {"torus", make_torus({.major_segments = 64, .minor_segments = 16})}};
}

TEST(Stability, DefaultMethodStaysValidOnTheSuite) {
  for (const Case& c : suite()) {
    SCOPED_TRACE(c.name);
    const MeshReport before = inspect(c.mesh);
    for (double ratio : {0.1, 0.01, 0.0}) {
      SCOPED_TRACE(ratio);
      SimplifyOptions o;
      o.target_ratio = ratio;
      const SimplifyResult r = simplify(c.mesh, o);
      ASSERT_TRUE(r.mesh.positions.allFinite());
      validate(r.mesh);
      const MeshReport after = inspect(r.mesh);
      EXPECT_LE(after.non_manifold_edges, before.non_manifold_edges);
      EXPECT_EQ(after.euler_characteristic, before.euler_characteristic);
      EXPECT_EQ(after.components, before.components);
      EXPECT_EQ(after.boundary_loops, before.boundary_loops);
      if (before.genus) {
        ASSERT_TRUE(after.genus);
        EXPECT_EQ(*after.genus, *before.genus);
      }
      // Faces against the nearest input face, while the output still follows the input; at the
      // extremes (a torus of nine vertices) "nearest" loses its meaning: then a closed mesh must at
      // least stay outward.
      if (ratio >= 0.1) {
        EXPECT_EQ(count_flipped_faces(c.mesh, r.mesh), 0);
      }
      if (before.volume && after.volume) {
        EXPECT_GT(*after.volume * *before.volume, 0.0);
      }
      EXPECT_LT(r.faces_out, c.mesh.num_faces());
      if (r.reason != StopReason::TargetReached) {
        EXPECT_FALSE(r.reason_text.empty());
      }
    }
  }
}

}  // namespace
}  // namespace lodkit
