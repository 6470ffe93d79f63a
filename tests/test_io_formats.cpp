// Hand-written files in each format's dialects, with exact expected contents.
#include <gtest/gtest.h>
#include <lodkit/error.h>
#include <lodkit/inspect.h>
#include <lodkit/io.h>

#include <cstring>

#include "test_util.h"

namespace lodkit {
namespace {

Mesh obj(const std::string& text) { return read_mesh_from_memory(text, MeshFormat::Obj, "t.obj"); }
Mesh ply(const std::string& text) { return read_mesh_from_memory(text, MeshFormat::Ply, "t.ply"); }
Mesh off(const std::string& text) { return read_mesh_from_memory(text, MeshFormat::Off, "t.off"); }

TEST(Obj, PolygonsAreFanTriangulatedAndNegativeIndicesResolve) {
  const Mesh m = obj(
      "# a pentagon and a triangle given with relative indices\r\n"
      "o thing\ng group\nusemtl none\ns off\n"
      "v 0 0 0\nv 1 0 0\nv 1.5 1 0\nv 0.5 2 0\nv -0.5 1 0\n\n"
      "f 1 2 3 4 5\n"
      "v 0 0 1\n"
      "f -1 -5 -6\n");
  ASSERT_EQ(m.num_vertices(), 6);
  ASSERT_EQ(m.num_faces(), 4);
  EXPECT_EQ(m.triangles.row(0), Eigen::RowVector3i(0, 1, 2));
  EXPECT_EQ(m.triangles.row(2), Eigen::RowVector3i(0, 3, 4));
  EXPECT_EQ(m.triangles.row(3), Eigen::RowVector3i(5, 1, 0));
  EXPECT_EQ(m.positions(2, 0), 1.5);
}

TEST(Obj, CornersWithDifferentAttributesBecomeSeamVertices) {
  // A quad whose vertex 1 is used with two different texture coordinates.
  const Mesh m = obj(
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
      "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 0.5 0.5\n"
      "vn 0 0 1\n"
      "f 1/1/1 2/2/1 3/3/1\n"
      "f 1/5/1 3/3/1 4/4/1\n");
  ASSERT_EQ(m.num_vertices(), 5);  // 4 positions + vertex 1 again with uv 5
  EXPECT_EQ(m.triangles.row(1), Eigen::RowVector3i(4, 2, 3));
  EXPECT_EQ(m.positions.row(4), m.positions.row(0));
  EXPECT_EQ(m.attributes.uvs.row(4), Eigen::RowVector2d(0.5, 0.5));
  EXPECT_EQ(m.attributes.uvs.row(0), Eigen::RowVector2d(0, 0));
  EXPECT_EQ(m.attributes.normals.row(3), Eigen::RowVector3d(0, 0, 1));
  // Welded by position, the seam is invisible to topology.
  EXPECT_EQ(inspect(m).boundary_loops, 1);
}

TEST(Obj, VertexColoursAndPartialSyntax) {
  const Mesh m = obj("v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nvt 0.25\nf 1/1 2/1 3/1\n");
  ASSERT_TRUE(m.has_colours());
  EXPECT_EQ(m.attributes.colours.row(1), Eigen::RowVector4f(0, 1, 0, 1));
  EXPECT_EQ(m.attributes.uvs.row(2), Eigen::RowVector2d(0.25, 0));
}

TEST(Obj, ErrorsNameTheLine) {
  try {
    obj("v 0 0 0\nv 1 0 0\n\nv 0 1 0\nf 1 2 9\n");
    FAIL();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "t.obj: line 5: vertex index 9 is out of range (3 defined so far)");
  }
}

TEST(Ply, AnyNumericTypesAndFaceColours) {
  const Mesh m = ply(
      "ply\r\nformat ascii 1.0\r\ncomment made by hand\r\n"
      "element vertex 4\r\nproperty double x\r\nproperty float y\r\nproperty short z\r\n"
      "property uchar red\r\nproperty uchar green\r\nproperty uchar blue\r\n"
      "property float nx\r\nproperty float ny\r\nproperty float nz\r\nproperty float s\r\nproperty float t\r\n"
      "element face 1\r\nproperty list uint short vertex_indices\r\nproperty uchar red\r\n"
      "property uchar green\r\nproperty uchar blue\r\nproperty uchar alpha\r\n"
      "element camera 1\r\nproperty list uchar float params\r\nproperty int id\r\n"
      "end_header\r\n"
      "0 0 0 255 0 0 0 0 1 0 0\n1 0 0 0 255 0 0 0 1 1 0\n1 1 0 0 0 255 0 0 1 1 1\n0 1 0 0 0 0 0 0 1 0 1\n"
      "4 0 1 2 3 10 20 30 255\n"
      "2 0.5 0.25 7\n");
  ASSERT_EQ(m.num_vertices(), 4);
  ASSERT_EQ(m.num_faces(), 2);
  EXPECT_EQ(m.triangles.row(1), Eigen::RowVector3i(0, 2, 3));
  EXPECT_EQ(m.attributes.colours.row(1), Eigen::RowVector4f(0, 1, 0, 1));
  EXPECT_EQ(m.attributes.uvs.row(2), Eigen::RowVector2d(1, 1));
  EXPECT_EQ(m.attributes.normals.row(0), Eigen::RowVector3d(0, 0, 1));
  ASSERT_TRUE(m.has_face_colours());
  EXPECT_EQ(m.attributes.face_colours.row(1), Eigen::RowVector4f(10 / 255.f, 20 / 255.f, 30 / 255.f, 1));
}

TEST(Ply, FloatIndicesAreReadWhenWholeNumbers) {
  // They were skipped, leaving a mesh without faces and no word of it.
  std::string bytes =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar float vertex_indices\nend_header\n";
  const float values[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  bytes.append(reinterpret_cast<const char*>(values), sizeof values);
  bytes.push_back(3);
  const float indices[3] = {2, 0, 1};
  bytes.append(reinterpret_cast<const char*>(indices), sizeof indices);
  const Mesh m = ply(bytes);
  ASSERT_EQ(m.num_faces(), 1);
  EXPECT_EQ(m.triangles.row(0), Eigen::RowVector3i(2, 0, 1));
}

TEST(Ply, ElementsWithoutPropertiesAreNotLoopedOver) {
  // An element of 10^17 empty rows took a row loop that never ended (found by fuzzing).
  const Mesh m = ply(
      "ply\nformat ascii 1.0\nelement nothing 100000000000000000\nelement vertex 3\nproperty float x\n"
      "property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\n"
      "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(m.num_vertices(), 3);
  EXPECT_EQ(m.num_faces(), 1);
}

TEST(Ply, BigEndianBinaryWithIntCountsAndTriStrips) {
  std::string bytes =
      "ply\nformat binary_big_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
      "property float z\nelement tristrips 1\nproperty list int int vertex_indices\nend_header\n";
  auto put = [&](auto v) {
    char b[sizeof v];
    std::memcpy(b, &v, sizeof v);
    std::reverse(b, b + sizeof v);
    bytes.append(b, sizeof v);
  };
  const float xyz[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
  for (float f : xyz) put(f);
  put(std::int32_t(4));
  for (std::int32_t i : {0, 1, 2, 3}) put(i);
  const Mesh m = ply(bytes);
  ASSERT_EQ(m.num_faces(), 2);
  EXPECT_EQ(m.positions(3, 1), 1.0);
  // Strip 0 1 2 3: triangles (0 1 2) and (2 1 3), both facing +z.
  EXPECT_EQ(m.triangles.row(0), Eigen::RowVector3i(0, 1, 2));
  EXPECT_EQ(m.triangles.row(1), Eigen::RowVector3i(2, 1, 3));
}

TEST(Off, VariantsColoursAndComments) {
  const Mesh m = off(
      "# comment before the keyword\nCOFF\n4 1 0\n"
      "0 0 0 255 0 0 255\n1 0 0 0 255 0 255 # trailing comment\n1 1 0 0 0 255 255\n0 1 0 0.5 0.5 0.5 1.0\n"
      "4 0 1 2 3 0.25 0.5 0.75\n");
  ASSERT_EQ(m.num_faces(), 2);
  EXPECT_EQ(m.attributes.colours.row(1), Eigen::RowVector4f(0, 1, 0, 1));
  EXPECT_EQ(m.attributes.colours.row(3), Eigen::RowVector4f(0.5, 0.5, 0.5, 1));
  EXPECT_EQ(m.attributes.face_colours.row(1), Eigen::RowVector4f(0.25, 0.5, 0.75, 1));

  const Mesh n = off("NOFF 3 1 0\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n");
  EXPECT_EQ(n.attributes.normals.row(2), Eigen::RowVector3d(0, 0, 1));
}

TEST(Stl, AsciiFacetsAreWelded) {
  const Mesh m = read_mesh_from_memory(
      "solid t\n"
      "facet normal 0 0 1\n outer loop\n  vertex 0 0 0\n  vertex 1 0 0\n  vertex 0 1 0\n endloop\nendfacet\n"
      "facet normal 0 0 1\n outer loop\n  vertex 1 0 0\n  vertex 1 1 0\n  vertex 0 1 0\n endloop\nendfacet\n"
      "endsolid t\n",
      MeshFormat::Stl, "t.stl");
  EXPECT_EQ(m.num_vertices(), 4);
  EXPECT_EQ(m.num_faces(), 2);
  EXPECT_EQ(inspect(m).boundary_loops, 1);
}

TEST(Stl, BinaryStartingWithSolidIsStillBinary) {
  Mesh tet = test::tetrahedron();
  std::string bytes = write_mesh_to_memory(tet, MeshFormat::Stl);
  std::memcpy(bytes.data(), "solid but binary", 16);
  const Mesh m = read_mesh_from_memory(bytes, MeshFormat::Stl, "t.stl");
  EXPECT_EQ(m.num_vertices(), 4);
  EXPECT_EQ(m.num_faces(), 4);
}

TEST(Formats, NamesAndExtensions) {
  EXPECT_EQ(format_of("a/b/Mesh.PLY"), MeshFormat::Ply);
  EXPECT_EQ(format_of("x.drc"), MeshFormat::Draco);
  EXPECT_FALSE(format_of("x.gltf"));
  EXPECT_EQ(parse_format("draco"), MeshFormat::Draco);
  EXPECT_EQ(format_name(MeshFormat::Off), "off");
}

}  // namespace
}  // namespace lodkit
