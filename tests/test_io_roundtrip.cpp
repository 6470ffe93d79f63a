// Write then read: every format must give back what it can carry, exactly where it promises to.
#include <gtest/gtest.h>
#include <lodkit/error.h>
#include <lodkit/inspect.h>
#include <lodkit/io.h>
#include <lodkit/primitives.h>

#include "test_util.h"

namespace lodkit {
namespace {

// A torus with every attribute: normals, UV seams, 8-bit vertex colours and face colours; positions
// that are not floats (so writers must keep doubles).
Mesh attributed_mesh() {
  Mesh m = make_torus({.major_radius = 1.1, .minor_radius = 0.3, .major_segments = 12,
                       .minor_segments = 6, .uvs = true});
  m.attributes.normals = compute_vertex_normals(m);
  m.attributes.colours.resize(m.num_vertices(), 4);
  for (Index v = 0; v < m.num_vertices(); ++v)
    m.attributes.colours.row(v) << float(v % 256) / 255.0f, float((7 * v) % 256) / 255.0f, 1.0f, 1.0f;
  m.attributes.face_colours.resize(m.num_faces(), 4);
  for (Index f = 0; f < m.num_faces(); ++f)
    m.attributes.face_colours.row(f) << float(f % 256) / 255.0f, 0.0f, float((3 * f) % 256) / 255.0f, 1.0f;
  return m;
}

void expect_same(const Mesh& a, const Mesh& b, bool face_colours) {
  ASSERT_EQ(a.num_vertices(), b.num_vertices());
  ASSERT_EQ(a.num_faces(), b.num_faces());
  EXPECT_EQ(a.positions, b.positions);
  EXPECT_EQ(a.triangles, b.triangles);
  EXPECT_EQ(a.attributes.normals, b.attributes.normals);
  EXPECT_EQ(a.attributes.uvs, b.attributes.uvs);
  EXPECT_EQ(a.attributes.colours, b.attributes.colours);
  if (face_colours) {
    EXPECT_EQ(a.attributes.face_colours, b.attributes.face_colours);
  }
}

class ExactRoundTrip : public ::testing::TestWithParam<std::tuple<std::string, PlyEncoding>> {};

TEST_P(ExactRoundTrip, PositionsTrianglesAndAttributesSurviveBitForBit) {
  const auto& [ext, encoding] = GetParam();
  test::ScratchDir dir("roundtrip");
  const Mesh m = attributed_mesh();
  WriteOptions w;
  w.ply_encoding = encoding;
  const auto path = dir / ("mesh." + ext);
  write_mesh(m, path, w);
  const Mesh back = read_mesh(path);
  Mesh expected = m;
  if (ext == "obj") {  // OBJ stores RGB only and no face colours
    expected.attributes.colours.col(3).setOnes();
  }
  expect_same(expected, back, ext != "obj");
  EXPECT_EQ(dir.entries(), 1u) << "no temporary files left behind";
}

std::string round_trip_name(const ::testing::TestParamInfo<ExactRoundTrip::ParamType>& p) {
  const char* const encodings[] = {"binary_le", "binary_be", "ascii"};
  return std::get<0>(p.param) + "_" + encodings[static_cast<int>(std::get<1>(p.param))];
}

INSTANTIATE_TEST_SUITE_P(
    Formats, ExactRoundTrip,
    ::testing::Values(std::tuple{std::string("obj"), PlyEncoding::BinaryLittleEndian},
                      std::tuple{std::string("off"), PlyEncoding::BinaryLittleEndian},
                      std::tuple{std::string("ply"), PlyEncoding::BinaryLittleEndian},
                      std::tuple{std::string("ply"), PlyEncoding::BinaryBigEndian},
                      std::tuple{std::string("ply"), PlyEncoding::Ascii}),
    round_trip_name);

TEST(RoundTrip, NonEightBitColoursAreKeptAsFloats) {
  Mesh m = test::single_triangle();
  m.attributes.colours = Colours::Constant(3, 4, 0.123f);
  for (const char* name : {"c.ply", "c.off"}) {
    const Mesh back = read_mesh_from_memory(write_mesh_to_memory(m, *parse_format(name + 2)),
                                            *parse_format(name + 2), name);
    EXPECT_EQ(back.attributes.colours, m.attributes.colours) << name;
  }
}

TEST(RoundTrip, FloatPositionsMakeCompactBinaryPly) {
  Mesh m = make_box({});  // every coordinate is +-0.5: exactly a float
  const std::string bytes = write_mesh_to_memory(m, MeshFormat::Ply);
  EXPECT_NE(bytes.find("property float x"), std::string::npos);
  m.positions(0, 0) = 0.1;  // not a float
  EXPECT_NE(write_mesh_to_memory(m, MeshFormat::Ply).find("property double x"), std::string::npos);
}

TEST(RoundTrip, StlWeldsBackToTheSameTopology) {
  const Mesh m = make_icosphere({.subdivisions = 2});
  for (bool binary : {true, false}) {
    WriteOptions w;
    w.stl_binary = binary;
    const Mesh back = read_mesh_from_memory(write_mesh_to_memory(m, MeshFormat::Stl, w), MeshFormat::Stl, "x.stl");
    EXPECT_EQ(back.num_vertices(), m.num_vertices());
    EXPECT_EQ(back.num_faces(), m.num_faces());
    const MeshReport r = inspect(back);
    EXPECT_TRUE(r.closed);
    EXPECT_EQ(*r.genus, 0);
    // STL is float32: every position is the float-rounded original.
    for (Index f = 0; f < m.num_faces(); ++f)
      for (int k = 0; k < 3; ++k)
        for (int i = 0; i < 3; ++i)
          EXPECT_EQ(back.positions(back.triangles(f, k), i),
                    double(float(m.positions(m.triangles(f, k), i))));
  }
}

// For each vertex of `b`, the distance to the nearest vertex of `a` (brute force; small meshes).
double max_vertex_distance(const Mesh& a, const Mesh& b) {
  double worst = 0;
  for (Index i = 0; i < b.num_vertices(); ++i) {
    double best = INFINITY;
    for (Index j = 0; j < a.num_vertices(); ++j) best = std::min(best, (a.positions.row(j) - b.positions.row(i)).norm());
    worst = std::max(worst, best);
  }
  return worst;
}

TEST(RoundTrip, DracoKeepsCountsAndQuantisesWithinItsStep) {
  const Mesh m = make_icosphere({.radius = 2, .subdivisions = 3});
  for (int bits : {0, 8, 14}) {
    WriteOptions w;
    w.draco.position_bits = bits;
    const Mesh back = read_mesh_from_memory(write_mesh_to_memory(m, MeshFormat::Draco, w), MeshFormat::Draco, "x.drc");
    EXPECT_EQ(back.num_vertices(), m.num_vertices()) << bits;
    EXPECT_EQ(back.num_faces(), m.num_faces()) << bits;
    const MeshReport r = inspect(back);
    EXPECT_TRUE(r.closed);
    EXPECT_EQ(*r.genus, 0);
    const double range = 4.0;  // Draco quantises over the largest box extent
    const double step = bits ? range / ((1 << bits) - 1) : 1e-6;
    EXPECT_LE(max_vertex_distance(m, back), step * std::sqrt(3.0)) << bits;
    EXPECT_GT(*r.volume, 0.0) << "orientation kept";
  }
}

TEST(RoundTrip, DracoCarriesNormalsUvsAndColours) {
  const Mesh m = attributed_mesh();
  const Mesh back = read_mesh_from_memory(write_mesh_to_memory(m, MeshFormat::Draco), MeshFormat::Draco, "x.drc");
  EXPECT_TRUE(back.has_normals());
  EXPECT_TRUE(back.has_uvs());
  EXPECT_TRUE(back.has_colours());
  EXPECT_EQ(back.num_faces(), m.num_faces());
}

TEST(RoundTrip, ObjPlyDracoObjChainKeepsCounts) {
  test::ScratchDir dir("chain");
  const Mesh m = make_uv_sphere({.segments = 24, .rings = 12, .uvs = true});
  write_mesh(m, dir / "a.obj");
  write_mesh(read_mesh(dir / "a.obj"), dir / "b.ply");
  write_mesh(read_mesh(dir / "b.ply"), dir / "c.drc");
  write_mesh(read_mesh(dir / "c.drc"), dir / "d.obj");
  const Mesh d = read_mesh(dir / "d.obj");
  EXPECT_EQ(d.num_vertices(), m.num_vertices());
  EXPECT_EQ(d.num_faces(), m.num_faces());
  EXPECT_TRUE(d.has_uvs());
  EXPECT_TRUE(inspect(d).closed);
}

TEST(RoundTrip, SeamsOfAUvSphereSurviveObj) {
  const Mesh m = make_uv_sphere({.segments = 16, .rings = 8, .uvs = true});
  const Mesh back = read_mesh_from_memory(write_mesh_to_memory(m, MeshFormat::Obj), MeshFormat::Obj, "s.obj");
  expect_same(m, back, false);
  EXPECT_EQ(inspect(back).duplicate_positions, inspect(m).duplicate_positions);
}

}  // namespace
}  // namespace lodkit
