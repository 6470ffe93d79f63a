#include <gtest/gtest.h>
#include <lodkit/inspect.h>
#include <lodkit/primitives.h>

#include "test_util.h"

namespace lodkit {
namespace {

Mesh from(std::initializer_list<double> xyz, std::initializer_list<Index> tris) {
  Mesh m;
  m.positions.resize(static_cast<Index>(xyz.size() / 3), 3);
  std::copy(xyz.begin(), xyz.end(), m.positions.data());
  m.triangles.resize(static_cast<Index>(tris.size() / 3), 3);
  std::copy(tris.begin(), tris.end(), m.triangles.data());
  return m;
}

TEST(Inspect, TetrahedronIsAClosedGenusZeroSolid) {
  const MeshReport r = inspect(test::tetrahedron());
  EXPECT_EQ(r.vertices, 4);
  EXPECT_EQ(r.faces, 4);
  EXPECT_EQ(r.edges, 6);
  EXPECT_TRUE(r.closed);
  EXPECT_TRUE(r.manifold);
  EXPECT_TRUE(r.oriented);
  EXPECT_EQ(r.components, 1);
  EXPECT_EQ(r.euler_characteristic, 2);
  ASSERT_TRUE(r.genus);
  EXPECT_EQ(*r.genus, 0);
  ASSERT_TRUE(r.volume);
  EXPECT_NEAR(*r.volume, 1.0 / 6.0, 1e-15);
  EXPECT_NEAR(r.area, 1.5 + std::sqrt(3.0) / 2.0, 1e-12);
  EXPECT_NEAR(r.diagonal, std::sqrt(3.0), 1e-15);
}

TEST(Inspect, InvertedSolidHasNegativeVolume) {
  Mesh m = test::tetrahedron();
  m.triangles.col(1).swap(m.triangles.col(2));
  const MeshReport r = inspect(m);
  ASSERT_TRUE(r.volume);
  EXPECT_NEAR(*r.volume, -1.0 / 6.0, 1e-15);
}

TEST(Inspect, SingleTriangleHasOneBoundaryLoop) {
  const MeshReport r = inspect(test::single_triangle());
  EXPECT_FALSE(r.closed);
  EXPECT_TRUE(r.manifold);
  EXPECT_EQ(r.boundary_edges, 3);
  EXPECT_EQ(r.boundary_loops, 1);
  EXPECT_EQ(r.euler_characteristic, 1);
  EXPECT_EQ(*r.genus, 0);
  EXPECT_FALSE(r.volume);
}

TEST(Inspect, BowTieIsANonManifoldVertex) {
  // Two triangles touching at vertex 0 only.
  const Mesh m = from({0, 0, 0, 1, 0, 0, 1, 1, 0, -1, 0, 0, -1, -1, 0}, {0, 1, 2, 0, 3, 4});
  const MeshReport r = inspect(m);
  EXPECT_EQ(r.non_manifold_vertices, 1);
  EXPECT_EQ(r.non_manifold_edges, 0);
  EXPECT_FALSE(r.manifold);
  EXPECT_FALSE(r.genus);
  EXPECT_EQ(r.components, 1);
}

TEST(Inspect, ThreeFacesOnOneEdgeIsANonManifoldEdge) {
  const Mesh m = from({0, 0, 0, 1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1}, {0, 1, 2, 1, 0, 3, 0, 1, 4});
  const MeshReport r = inspect(m);
  EXPECT_EQ(r.non_manifold_edges, 1);
  EXPECT_FALSE(r.manifold);
}

TEST(Inspect, CountsInconsistentOrientationDuplicatesDegeneratesAndUnreferenced) {
  // Two triangles sharing edge 0-1 traversed the same way, a duplicate of the first face, a face with
  // a repeated vertex, a zero-area face, and an unused vertex 5.
  const Mesh m = from({0, 0, 0, 1, 0, 0, 0, 1, 0, 0, -1, 0, 2, 0, 0, 9, 9, 9},
                      {0, 1, 2, 0, 1, 3, 2, 1, 0, 0, 0, 1, 0, 1, 4});
  const MeshReport r = inspect(m);
  EXPECT_EQ(r.duplicate_faces, 1);
  EXPECT_EQ(r.degenerate_faces, 2);
  EXPECT_EQ(r.unreferenced_vertices, 1);
  EXPECT_GE(r.inconsistently_oriented_edges + r.non_manifold_edges, 1);
}

TEST(Inspect, SeamsAreWeldedForTopology) {
  const Mesh sphere = make_uv_sphere({.segments = 12, .rings = 6, .uvs = true});
  const MeshReport r = inspect(sphere);
  EXPECT_GT(r.duplicate_positions, 0);
  EXPECT_TRUE(r.closed);
  EXPECT_EQ(*r.genus, 0);
  EXPECT_EQ(r.euler_characteristic, 2);
  EXPECT_EQ(r.welded_vertices, 12 * 5 + 2);
  // One piece of atlas: the u = 0 / 1 seam and the split poles part no faces from the rest.
  EXPECT_EQ(r.uv_charts, Index(1));
}

TEST(Inspect, UvChartsAreThePiecesOfTheAtlas) {
  // A box whose six sides each have their own UVs: six charts; without UVs, none reported.
  Mesh box = make_box({});
  EXPECT_FALSE(inspect(box).uv_charts);
  box.attributes.uvs.resize(box.num_vertices(), 2);
  for (Index v = 0; v < box.num_vertices(); ++v) box.attributes.uvs.row(v) << double(v % 2), double((v / 2) % 2);
  // Split every vertex per face, each corner its own UV: no two faces share UVs at an edge unless the
  // two triangles of one side do.
  Mesh split;
  split.positions.resize(3 * box.num_faces(), 3);
  split.triangles.resize(box.num_faces(), 3);
  split.attributes.uvs.resize(3 * box.num_faces(), 2);
  for (Index f = 0; f < box.num_faces(); ++f) {
    const Eigen::Vector3d n = (box.positions.row(box.triangles(f, 1)) - box.positions.row(box.triangles(f, 0)))
                                  .cross(box.positions.row(box.triangles(f, 2)) - box.positions.row(box.triangles(f, 0)));
    int axis = 0;
    n.cwiseAbs().maxCoeff(&axis);
    for (int k = 0; k < 3; ++k) {
      const Index v = 3 * f + k;
      split.positions.row(v) = box.positions.row(box.triangles(f, k));
      split.triangles(f, k) = v;
      // The side's plane coordinates, moved to the side's own place in the atlas.
      const Eigen::Vector3d p = split.positions.row(v).transpose();
      split.attributes.uvs.row(v) << p[(axis + 1) % 3] + 2.0 * (axis + 3 * (n[axis] > 0)), p[(axis + 2) % 3];
    }
  }
  EXPECT_EQ(inspect(split).uv_charts, Index(6));
}

TEST(Inspect, GenusOfATorusAndOfTwoTori) {
  Mesh torus = make_torus({.major_segments = 16, .minor_segments = 8});
  MeshReport r = inspect(torus);
  EXPECT_EQ(*r.genus, 1);
  EXPECT_EQ(r.euler_characteristic, 0);
  // Two disjoint copies: two components, total genus 2.
  Mesh two = torus;
  two.positions.conservativeResize(2 * torus.num_vertices(), 3);
  two.positions.bottomRows(torus.num_vertices()) = torus.positions.array() + 5.0;
  two.triangles.conservativeResize(2 * torus.num_faces(), 3);
  two.triangles.bottomRows(torus.num_faces()) = torus.triangles.array() + torus.num_vertices();
  r = inspect(two);
  EXPECT_EQ(r.components, 2);
  EXPECT_EQ(*r.genus, 2);
}

TEST(Inspect, GridHasOneBoundaryLoopAndDiskTopology) {
  const MeshReport r = inspect(make_grid({.divisions_x = 7, .divisions_y = 5}));
  EXPECT_EQ(r.boundary_loops, 1);
  EXPECT_EQ(r.boundary_edges, 2 * (7 + 5));
  EXPECT_EQ(r.euler_characteristic, 1);
  EXPECT_NEAR(r.area, 1.0, 1e-12);
}

TEST(Inspect, EmptyMesh) {
  const MeshReport r = inspect(Mesh{});
  EXPECT_EQ(r.vertices, 0);
  EXPECT_FALSE(r.closed);
  EXPECT_EQ(r.components, 0);
  EXPECT_EQ(r.diagonal, 0.0);
}

TEST(Inspect, VolumeIsAccurateFarFromTheOrigin) {
  Mesh box = make_box({.size = {1, 2, 3}});
  box.positions.rowwise() += Eigen::RowVector3d(1e6, -1e6, 1e6);
  const MeshReport r = inspect(box);
  ASSERT_TRUE(r.volume);
  EXPECT_NEAR(*r.volume, 6.0, 1e-6);
}

}  // namespace
}  // namespace lodkit
