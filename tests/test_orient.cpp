// orient_consistently(), and the methods on an input whose faces disagree on orientation.
#include <gtest/gtest.h>
#include <lodkit/decimate.h>
#include <lodkit/inspect.h>
#include <lodkit/primitives.h>
#include <lodkit/progressive.h>
#include <lodkit/simplify.h>

#include <cmath>
#include <numbers>
#include <random>

#include "test_util.h"

namespace lodkit {
namespace {

void turn(Mesh& mesh, Index f) { std::swap(mesh.triangles(f, 1), mesh.triangles(f, 2)); }

/// `mesh` with each face turned with probability 1/2 (seeded); `turned` counts them.
Mesh shuffled(const Mesh& mesh, Index& turned, unsigned seed = 3) {
  Mesh out = mesh;
  std::mt19937 rng(seed);
  turned = 0;
  for (Index f = 0; f < out.num_faces(); ++f)
    if (rng() & 1) turn(out, f), ++turned;
  return out;
}

/// A Moebius band: `n` quads around a loop, each two triangles, the last joined to the first with a half twist.
Mesh moebius_band(int n = 24) {
  Mesh m;
  m.positions.resize(2 * n, 3);
  for (int i = 0; i < n; ++i) {
    const double t = 2 * std::numbers::pi * i / n, half = 0.5 * t;
    for (int side = 0; side < 2; ++side) {
      const double s = side ? 0.3 : -0.3;
      m.positions.row(2 * i + side) << (1 + s * std::cos(half)) * std::cos(t), (1 + s * std::cos(half)) * std::sin(t),
          s * std::sin(half);
    }
  }
  m.triangles.resize(2 * n, 3);
  for (int i = 0; i < n; ++i) {
    const Index a = 2 * i, b = 2 * i + 1;
    // The last quad meets the first column turned over: its sides swap.
    const Index c = i + 1 < n ? 2 * (i + 1) : 1, d = i + 1 < n ? 2 * (i + 1) + 1 : 0;
    m.triangles.row(2 * i) << a, c, b;
    m.triangles.row(2 * i + 1) << b, c, d;
  }
  return m;
}

TEST(Orient, TurnsAShuffledSphereBackFaceForFace) {
  const Mesh sphere = make_icosphere({.subdivisions = 3});
  ASSERT_GT(*inspect(sphere).volume, 0);
  Index turned = 0;
  Mesh m = shuffled(sphere, turned);
  ASSERT_GT(turned, 100);
  EXPECT_FALSE(inspect(m).oriented);
  // Closed: the orientation that encloses a positive volume, which is the sphere's own.
  EXPECT_EQ(orient_consistently(m), turned);
  EXPECT_EQ(m.triangles, sphere.triangles);
  EXPECT_EQ(orient_consistently(m), 0);  // nothing left to do
}

TEST(Orient, TurnsAnInsideOutShuffledSphereOutwards) {
  Mesh inside_out = make_icosphere({.subdivisions = 2});
  for (Index f = 0; f < inside_out.num_faces(); ++f) turn(inside_out, f);
  Index turned = 0;
  Mesh m = shuffled(inside_out, turned, 5);
  // Every face still inside out gets turned: those the shuffle left.
  EXPECT_EQ(orient_consistently(m), m.num_faces() - turned);
  const MeshReport r = inspect(m);
  EXPECT_TRUE(r.oriented);
  EXPECT_GT(*r.volume, 0);
}

TEST(Orient, LeavesPatchesThatAgreeAsTheyAre) {
  // A sphere inside out but consistent stays inside out: only disagreement is mended.
  Mesh inside_out = make_icosphere({.subdivisions = 2});
  for (Index f = 0; f < inside_out.num_faces(); ++f) turn(inside_out, f);
  Mesh m = inside_out;
  EXPECT_EQ(orient_consistently(m), 0);
  EXPECT_EQ(m.triangles, inside_out.triangles);
  // Beside a shuffled one, in one mesh: only the shuffled part changes.
  Mesh sphere = make_icosphere({.subdivisions = 2});
  sphere.positions.col(0).array() += 3.0;  // apart: faces join where their corners coincide
  Index turned = 0;
  Mesh both = concatenated(inside_out, shuffled(sphere, turned));
  EXPECT_EQ(orient_consistently(both), turned);
  EXPECT_EQ(both.triangles, concatenated(inside_out, sphere).triangles);
}

TEST(Orient, OpenPatchKeepsTheWayMostOfItsAreaFaced) {
  const Mesh grid = make_grid({.divisions_x = 12, .divisions_y = 12});
  Mesh m = grid;
  for (Index f = 0; f < m.num_faces(); f += 5) turn(m, f);  // a fifth turned
  EXPECT_EQ(orient_consistently(m), (m.num_faces() + 4) / 5);
  EXPECT_EQ(m.triangles, grid.triangles);
  // The other way round: four fifths turned, the patch ends up facing -z.
  Mesh most = grid;
  for (Index f = 0; f < most.num_faces(); ++f)
    if (f % 5 != 0) turn(most, f);
  EXPECT_EQ(orient_consistently(most), (most.num_faces() + 4) / 5);
  for (Index f = 0; f < most.num_faces(); ++f) {
    const Eigen::Vector3d a = most.positions.row(most.triangles(f, 0)), b = most.positions.row(most.triangles(f, 1)),
                          c = most.positions.row(most.triangles(f, 2));
    EXPECT_LT((b - a).cross(c - a).z(), 0) << "face " << f;
  }
}

TEST(Orient, JoinsFacesByPositionAcrossUnweldedVertices) {
  // Three vertices per face (a soup of one sphere): faces still meet where their corners coincide.
  const Mesh soup = test::flat_shaded(make_icosphere({.subdivisions = 2}));
  Index turned = 0;
  Mesh m = shuffled(soup, turned);
  EXPECT_EQ(orient_consistently(m), turned);
  EXPECT_EQ(m.triangles, soup.triangles);
}

TEST(Orient, LeavesANonOrientableBandAlone) {
  const Mesh band = moebius_band();
  ASSERT_FALSE(inspect(band).oriented);
  Mesh m = band;
  EXPECT_EQ(orient_consistently(m), 0);
  EXPECT_EQ(m.triangles, band.triangles);
}

// inspect() tells a band that no turning can orient (info's hint said --orient would) from a mesh
// whose faces only disagree, and from one that agrees already.
TEST(Orient, InspectSaysWhetherAMeshCanBeOriented) {
  const MeshReport band = inspect(moebius_band());
  ASSERT_TRUE(band.orientable.has_value());
  EXPECT_FALSE(*band.orientable);
  EXPECT_GT(band.inconsistently_oriented_edges, 0);
  Index turned = 0;
  const Mesh sphere = make_icosphere({.subdivisions = 2});
  const MeshReport mixed = inspect(shuffled(sphere, turned));
  ASSERT_GT(turned, 0);
  EXPECT_FALSE(mixed.oriented);
  EXPECT_EQ(mixed.orientable, std::optional<bool>(true));
  EXPECT_EQ(inspect(sphere).orientable, std::optional<bool>(true));
  // A band beside an orientable sphere: not orientable as a whole.
  EXPECT_EQ(inspect(concatenated(moebius_band(), sphere)).orientable, std::optional<bool>(false));
}

TEST(Orient, EmptyAndDegenerateFacesAreLeft) {
  Mesh empty;
  EXPECT_EQ(orient_consistently(empty), 0);
  Mesh m = make_icosphere({.subdivisions = 1});
  const Index n = m.num_faces();
  m.triangles.conservativeResize(n + 1, 3);
  m.triangles.row(n) << 0, 0, 1;  // no three distinct corners: joins nothing
  turn(m, 3);
  EXPECT_EQ(orient_consistently(m), 1);
  EXPECT_EQ(m.triangles.row(n), Eigen::RowVector3i(0, 0, 1));
}

// The methods on a shuffled sphere: without turning, the disagreeing edges lock their ends and
// nothing reaches the target; turned first, every method does, with the topology kept and faces agreeing.
class ShuffledInput : public ::testing::Test {
 protected:
  void SetUp() override { input = shuffled(test::bumpy_sphere(3, 0.02), turned); }
  Mesh input;
  Index turned = 0;
};

void expect_oriented_sphere(const Mesh& out) {
  const MeshReport r = inspect(out);
  EXPECT_TRUE(r.oriented);
  EXPECT_TRUE(r.closed);
  EXPECT_EQ(r.euler_characteristic, 2);
  EXPECT_GT(*r.volume, 0);
}

TEST_F(ShuffledInput, EveryCollapseMethodReachesItsTarget) {
  for (const SimplifyMethod method : {SimplifyMethod::Quadric, SimplifyMethod::Hoppe, SimplifyMethod::EdgeLength}) {
    SCOPED_TRACE(to_string(method));
    SimplifyOptions o;
    o.method = method;
    o.target_faces = input.num_faces() / 10;
    const SimplifyResult r = simplify(input, o);
    EXPECT_EQ(r.reoriented_faces, turned);
    EXPECT_EQ(r.reason, StopReason::TargetReached);
    EXPECT_LE(r.faces_out, *o.target_faces);
    expect_oriented_sphere(r.mesh);

    o.orient_faces = false;
    const SimplifyResult kept = simplify(input, o);
    EXPECT_EQ(kept.reoriented_faces, 0);
    EXPECT_EQ(kept.reason, StopReason::NoLegalCollapse);
    EXPECT_GT(kept.faces_out, 4 * *o.target_faces);
  }
}

TEST_F(ShuffledInput, SchroederReachesItsTarget) {
  DecimateOptions o;
  o.target_faces = input.num_faces() / 10;
  const DecimateResult r = decimate(input, o);
  EXPECT_EQ(r.reoriented_faces, turned);
  EXPECT_TRUE(r.target_reached);
  expect_oriented_sphere(r.mesh);
  o.orient_faces = false;
  EXPECT_FALSE(decimate(input, o).target_reached);
}

TEST_F(ShuffledInput, ProgressiveMeshRefinesToTheTurnedInput) {
  ProgressiveOptions po;
  po.base_faces = 20;
  const ProgressiveMesh pm = build_progressive_mesh(input, po);
  EXPECT_LE(pm.num_faces(0), 20);
  Mesh turned_input = input;
  orient_consistently(turned_input);
  const ExtractedLevel full = extract_level(pm, pm.max_level(), VertexOrder::Input);
  EXPECT_EQ(full.mesh.triangles, turned_input.triangles);
  EXPECT_EQ(full.mesh.positions, turned_input.positions);
  expect_oriented_sphere(extract_level(pm, pm.max_level() / 2, VertexOrder::Input).mesh);
}

TEST_F(ShuffledInput, SimplifyWithinAHausdorffLimitTurnsItToo) {
  SimplifyOptions o;
  o.target_faces = input.num_faces() / 10;
  const double limit = 0.05 * inspect(input).diagonal;
  const SimplifyResult r = simplify_within(input, limit, o);
  EXPECT_EQ(r.reoriented_faces, turned);
  EXPECT_LE(r.faces_out, *o.target_faces);
  ASSERT_TRUE(r.within);
  EXPECT_LE(r.within->bound, limit);
  expect_oriented_sphere(r.mesh);
}

}  // namespace
}  // namespace lodkit
