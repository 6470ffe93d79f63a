#include "stability_suite.h"

#include <lodkit/primitives.h>

#include "test_util.h"

namespace lodkit::test {
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
  Mesh m = flat_shaded(bumpy_sphere(3, 0.01));
  m.attributes.normals.resize(0, 3);
  const Index n = m.num_vertices();
  m.positions.conservativeResize(n + 5, 3);
  m.positions.bottomRows(5).setConstant(7.0);
  return m;
}

Mesh grid_with_slivers() {
  Mesh g = make_grid({.divisions_x = 20, .divisions_y = 20});
  // Push some interior vertices onto a neighbour's edge line: zero-area triangles.
  for (Index v : {50, 51, 120, 200, 310}) g.positions(v, 0) = g.positions(v - 1, 0);
  return g;
}

// The shape manifold's tests cut with (../shared's manifold_Cray_right.obj): a box of 12 faces, as
// wide and as deep as floats go, its top at z = -100. Of the 64 ways to split its sides into triangles,
// 15 had hoppe place a corner beyond a float's range; this is one.
Mesh float_range_slab() {
  constexpr double w = 3.40282347e38;
  Mesh slab;
  slab.positions.resize(8, 3);
  for (Index i = 0; i < 8; ++i)  // corner i: bit 0 +x, bit 1 +y, bit 2 the top
    slab.positions.row(i) = Eigen::RowVector3d(i & 1 ? w : -w, i & 2 ? w : -w, i & 4 ? -100.0 : -w);
  const Index sides[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  const bool from_first_corner[6] = {false, true, true, false, true, true};
  slab.triangles.resize(12, 3);
  for (int s = 0; s < 6; ++s) {
    const Index* c = sides[s];
    const int k = from_first_corner[s] ? 0 : 1;  // the diagonal from corner k
    slab.triangles.row(2 * s) << c[k], c[k + 1], c[k + 2];
    slab.triangles.row(2 * s + 1) << c[k], c[k + 2], c[(k + 3) % 4];
  }
  return slab;
}

}  // namespace

std::vector<StabilityCase> stability_suite() {
  return {{"sharp_box", make_box({.size = {2, 1, 0.5}, .divisions = 10})},
          {"thin_plate", make_box({.size = {1, 1, 0.001}, .divisions = 12})},
          {"fine_cylinder", make_cylinder({.radius = 0.2, .height = 3, .segments = 64, .stacks = 30})},
          {"grid_with_hole", grid_with_hole()},
          {"shared_edge", two_boxes_sharing_an_edge()},
          {"soup_and_strays", unwelded_with_unreferenced()},
          {"slivers", grid_with_slivers()},
          {"noisy_sphere", bumpy_sphere(4, 0.03)},
          {"far_away", transformed(bumpy_sphere(4, 0.02), 1.0, 1e6)},
          {"tiny", transformed(bumpy_sphere(4, 0.02), 1e-6, 0.0)},
          {"uv_seams", make_uv_sphere({.segments = 48, .rings = 24, .uvs = true})},
          {"torus", make_torus({.major_segments = 64, .minor_segments = 16})},
          // As wide as floats go: 3.40282347e38 is the largest float as writers print it (9 digits),
          // a little above it as a double. An optimum outside the box lies beyond what a float holds.
          {"float_range_box", transformed(make_box({.size = {2, 2, 2}, .divisions = 6}), 3.40282347e38, 0.0)},
          {"float_range_slab", float_range_slab()}};
}

}  // namespace lodkit::test
