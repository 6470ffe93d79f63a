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
          {"torus", make_torus({.major_segments = 64, .minor_segments = 16})}};
}

}  // namespace lodkit::test
