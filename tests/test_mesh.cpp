#include <gtest/gtest.h>

#include <random>
#include <lodkit/error.h>
#include <lodkit/mesh.h>

#include <cmath>

#include "test_util.h"

namespace lodkit {
namespace {

TEST(Validate, AcceptsAGoodMesh) { EXPECT_NO_THROW(validate(test::tetrahedron())); }

TEST(Validate, RejectsOutOfRangeIndexNamingTheContext) {
  Mesh m = test::tetrahedron();
  m.triangles(2, 1) = 4;
  try {
    validate(m, "thing.ply");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("thing.ply: face 2 refers to vertex 4"), std::string::npos) << e.what();
  }
}

TEST(Validate, RejectsNegativeIndexAndNaNAndMismatchedAttributes) {
  Mesh m = test::tetrahedron();
  m.triangles(0, 0) = -1;
  EXPECT_THROW(validate(m), Error);
  m = test::tetrahedron();
  m.positions(1, 2) = std::nan("");
  EXPECT_THROW(validate(m), Error);
  m = test::tetrahedron();
  m.attributes.uvs = TexCoords::Zero(3, 2);
  EXPECT_THROW(validate(m), Error);
  m = test::tetrahedron();
  m.attributes.face_colours = Colours::Ones(3, 4);
  EXPECT_THROW(validate(m), Error);
  m = test::tetrahedron();
  m.attributes.normals = Normals::Zero(4, 3);
  m.attributes.normals(0, 0) = INFINITY;
  EXPECT_THROW(validate(m), Error);
}

TEST(Weld, MergesOnlyIdenticalVerticesAndKeepsSeams) {
  Mesh m;
  m.positions.resize(5, 3);
  m.positions << 0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 0, 0, -0.0, 0, 0;  // 3 and 4 repeat 1 and 0
  m.triangles.resize(2, 3);
  m.triangles << 0, 1, 2, 4, 2, 3;
  Mesh plain = m;
  EXPECT_EQ(weld_identical_vertices(plain), 2);
  EXPECT_EQ(plain.num_vertices(), 3);
  EXPECT_EQ(plain.triangles.row(1), Eigen::RowVector3i(0, 2, 1));

  // Different UVs make vertex 3 a seam copy of vertex 1: it must survive.
  m.attributes.uvs = TexCoords::Zero(5, 2);
  m.attributes.uvs(3, 0) = 0.5;
  EXPECT_EQ(weld_identical_vertices(m), 1);
  EXPECT_EQ(m.num_vertices(), 4);
  EXPECT_EQ(m.attributes.uvs.rows(), 4);
}

TEST(Weld, ClassesMatchABruteForceComparison) {
  // Many repeats of a few negative, zero and positive values: every vertex's class is the lowest
  // vertex whose position and normal compare equal (-0 == +0).
  std::mt19937 random(3);
  const double values[] = {-2.5, -1.0, -0.0, 0.0, 1.0, 1e-300, -1e300};
  std::uniform_int_distribution<int> pick(0, 6);
  Mesh m;
  m.positions.resize(400, 3);
  m.attributes.normals.resize(400, 3);
  for (Index v = 0; v < 400; ++v)
    for (int k = 0; k < 3; ++k) {
      m.positions(v, k) = values[pick(random)] * (k == 0 ? 1 : 0);
      m.attributes.normals(v, k) = values[pick(random) % 3];
    }
  const std::vector<Index> classes = identical_vertex_classes(m);
  for (Index v = 0; v < 400; ++v) {
    Index first = v;
    for (Index u = 0; u < v && first == v; ++u)
      if (m.positions.row(u) == m.positions.row(v) && m.attributes.normals.row(u) == m.attributes.normals.row(v))
        first = u;
    EXPECT_EQ(classes[v], first) << v;
  }
}

TEST(RemoveUnreferenced, KeepsOrderAndAttributes) {
  Mesh m = test::single_triangle();
  m.positions.conservativeResize(5, 3);
  m.positions.row(3) << 9, 9, 9;
  m.positions.row(4) << 2, 0, 0;
  m.attributes.colours = Colours::Zero(5, 4);
  m.attributes.colours(4, 0) = 1;
  m.triangles.row(0) << 0, 4, 2;
  EXPECT_EQ(remove_unreferenced_vertices(m), 2);
  ASSERT_EQ(m.num_vertices(), 3);
  EXPECT_EQ(m.triangles.row(0), Eigen::RowVector3i(0, 2, 1));  // old 2 -> 1, old 4 -> 2
  EXPECT_EQ(m.positions.row(1), Eigen::RowVector3d(0, 1, 0));
  EXPECT_EQ(m.positions(2, 0), 2.0);
  EXPECT_EQ(m.attributes.colours(2, 0), 1.0f);
}

TEST(PositionClasses, MapsEachVertexToTheFirstWithItsPosition) {
  Mesh m = test::single_triangle();
  m.positions.conservativeResize(4, 3);
  m.positions.row(3) << 1, 0, 0;
  const auto cls = position_classes(m);
  EXPECT_EQ(cls[3], 1);
  EXPECT_EQ(cls[2], 2);
}

TEST(VertexNormals, PointOutwardOnAClosedMesh) {
  const Mesh m = test::tetrahedron();
  const Normals n = compute_vertex_normals(m);
  const Eigen::RowVector3d centre = m.positions.colwise().mean();
  for (Index v = 0; v < 4; ++v) {
    EXPECT_NEAR(n.row(v).norm(), 1.0, 1e-12);
    EXPECT_GT(n.row(v).dot(m.positions.row(v) - centre), 0.0);
  }
}

}  // namespace
}  // namespace lodkit
