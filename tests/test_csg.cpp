// CSG: volumes obey inclusion-exclusion, results are closed outward manifolds, degenerate cases are
// right, bad inputs are refused with the reason, trees parse with clear errors.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <lodkit/csg.h>
#include <lodkit/error.h>
#include <lodkit/inspect.h>
#include <lodkit/primitives.h>

#include "test_util.h"

namespace lodkit {
namespace {

Mesh moved(Mesh m, double x, double y, double z) {
  m.positions.rowwise() += Eigen::RowVector3d(x, y, z);
  return m;
}

double volume_of(const Mesh& m) {
  const MeshReport r = inspect(m);
  return r.volume.value_or(0.0);
}

void expect_solid(const Mesh& m) {
  const MeshReport r = inspect(m);
  EXPECT_TRUE(r.closed);
  EXPECT_TRUE(r.manifold);
  EXPECT_TRUE(r.oriented);
  ASSERT_TRUE(r.volume);
  EXPECT_GT(*r.volume, 0.0);
  // (Corefinement may leave needle triangles whose double-precision area rounds to zero; CGAL's exact
  // predicates see them as proper triangles, and boolean() has checked the result for
  // self-intersections, so they are not counted against it here.)
  EXPECT_EQ(r.duplicate_faces, 0);
}

TEST(Csg, VolumesObeyInclusionExclusion) {
  const std::vector<std::pair<Mesh, Mesh>> pairs{
      {make_uv_sphere({.tolerance = 0.01}), moved(make_uv_sphere({.radius = 0.8, .tolerance = 0.01}), 0.9, 0.2, 0.1)},
      {make_box({}), moved(make_box({.size = {1, 2, 0.5}}), 0.5, 0.3, 0.2)},
      {make_icosphere({.subdivisions = 3}), moved(make_box({.size = {1.2, 1.2, 1.2}}), 0.7, 0.7, 0.7)}};
  for (const auto& [a, b] : pairs) {
    const double va = volume_of(a), vb = volume_of(b);
    const BooleanResult u = boolean(a, b, BooleanOp::Union), i = boolean(a, b, BooleanOp::Intersection),
                        d = boolean(a, b, BooleanOp::Difference);
    for (const BooleanResult* r : {&u, &i, &d}) expect_solid(r->mesh);
    EXPECT_NEAR(u.volume, va + vb - i.volume, 1e-9 * (va + vb));
    EXPECT_NEAR(d.volume, va - i.volume, 1e-9 * (va + vb));
    EXPECT_GT(i.volume, 0.0);
    EXPECT_NEAR(u.volume, volume_of(u.mesh), 1e-12);
  }
  // Exact values for axis-aligned boxes.
  const BooleanResult i = boolean(make_box({}), moved(make_box({}), 0.5, 0.5, 0.5), BooleanOp::Intersection);
  EXPECT_NEAR(i.volume, 0.125, 1e-12);
}

TEST(Csg, CoplanarAndDegenerateCases) {
  const Mesh c = make_box({});
  // Shared face.
  BooleanResult r = boolean(c, moved(c, 1, 0, 0), BooleanOp::Union);
  expect_solid(r.mesh);
  EXPECT_NEAR(r.volume, 2.0, 1e-12);
  EXPECT_EQ(boolean(c, moved(c, 1, 0, 0), BooleanOp::Intersection).mesh.num_faces(), 0);
  EXPECT_NEAR(boolean(c, moved(c, 1, 0, 0), BooleanOp::Difference).volume, 1.0, 1e-12);
  // Coplanar faces, offset by half.
  r = boolean(c, moved(c, 0.5, 0, 0), BooleanOp::Union);
  expect_solid(r.mesh);
  EXPECT_NEAR(r.volume, 1.5, 1e-12);
  // Identical operands (offset by 0).
  EXPECT_NEAR(boolean(c, c, BooleanOp::Union).volume, 1.0, 1e-12);
  EXPECT_NEAR(boolean(c, c, BooleanOp::Intersection).volume, 1.0, 1e-12);
  EXPECT_EQ(boolean(c, c, BooleanOp::Difference).mesh.num_faces(), 0);
  // One inside the other: a hollow box has two shells.
  const Mesh inner = make_box({.size = {0.5, 0.5, 0.5}});
  EXPECT_NEAR(boolean(c, inner, BooleanOp::Union).volume, 1.0, 1e-12);
  r = boolean(c, inner, BooleanOp::Difference);
  EXPECT_NEAR(r.volume, 0.875, 1e-12);
  EXPECT_EQ(inspect(r.mesh).components, 2);
  EXPECT_TRUE(inspect(r.mesh).closed);
  // Disjoint: empty intersection.
  EXPECT_EQ(boolean(c, moved(c, 3, 0, 0), BooleanOp::Intersection).mesh.num_faces(), 0);
  // Touching along an edge: two shells side by side, said in a warning.
  r = boolean(c, moved(c, 1, 1, 0), BooleanOp::Union);
  EXPECT_NEAR(r.volume, 2.0, 1e-12);
  ASSERT_FALSE(r.warnings.empty());
  EXPECT_NE(r.warnings[0].find("only touch"), std::string::npos);
}

TEST(Csg, BoxMinusThroughCylinderHasGenusOne) {
  const BooleanResult r = boolean(make_box({.size = {2, 2, 1}}), make_cylinder({.radius = 0.4, .height = 2, .tolerance = 0.005}),
                                  BooleanOp::Difference);
  expect_solid(r.mesh);
  EXPECT_EQ(*inspect(r.mesh).genus, 1);
}

TEST(Csg, BadOperandsAreRefusedWithTheReason) {
  const Mesh c = make_box({});
  const Mesh open = make_grid({});
  try {
    boolean(open, c, BooleanOp::Union, {}, "plate.ply", "box.ply");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("plate.ply: is not closed"), std::string::npos) << e.what();
  }
  // Two interpenetrating boxes in one mesh intersect themselves.
  Mesh twisted = c;
  const Mesh other = moved(c, 0.5, 0.5, 0.5);
  twisted.positions.conservativeResize(16, 3);
  twisted.positions.bottomRows(8) = other.positions;
  twisted.triangles.conservativeResize(24, 3);
  twisted.triangles.bottomRows(12) = other.triangles.array() + 8;
  try {
    boolean(twisted, c, BooleanOp::Union, {}, "twisted.obj", "box");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("twisted.obj: intersects itself ("), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("face pairs)"), std::string::npos) << e.what();
  }
  // Inside out: turned around with a warning, and the result is right.
  Mesh inverted = moved(c, 0.5, 0, 0);
  inverted.triangles.col(1).swap(inverted.triangles.col(2));
  const BooleanResult r = boolean(c, inverted, BooleanOp::Union, {}, "a", "inverted");
  EXPECT_NEAR(r.volume, 1.5, 1e-12);
  ASSERT_FALSE(r.warnings.empty());
  EXPECT_NE(r.warnings[0].find("inverted: was inside out"), std::string::npos);
}

TEST(Csg, ExactConstructionsGiveTheSameResult) {
  const Mesh a = make_uv_sphere({.tolerance = 0.02}), b = moved(make_box({}), 0.4, 0.1, -0.2);
  const BooleanResult fast = boolean(a, b, BooleanOp::Difference);
  const BooleanResult exact = boolean(a, b, BooleanOp::Difference, {.exact = true});
  EXPECT_TRUE(exact.used_exact);
  expect_solid(exact.mesh);
  EXPECT_NEAR(fast.volume, exact.volume, 1e-9);
}

TEST(CsgTree, ExamplesEvaluateToSolidsOfTheRightGenus) {
  const std::filesystem::path data = std::filesystem::path(LODKIT_SOURCE_DIR) / "data" / "csg";
  const std::vector<std::pair<std::string, long long>> cases{{"plate_with_holes.json", 5}, {"bracket.json", 2}, {"housing.json", 5}};
  for (const auto& [file, genus] : cases) {
    SCOPED_TRACE(file);
    const CsgResult r = evaluate(read_csg(data / file), {.tolerance = 0.01});
    expect_solid(r.mesh);
    EXPECT_EQ(*inspect(r.mesh).genus, genus);
    EXPECT_GT(r.operations, 0);
  }
}

TEST(CsgTree, TransformsComposeScaleRotateTranslate) {
  // A unit box scaled x2 in x, turned 90 degrees about z, then moved: it spans y in [9, 11].
  const CsgNode n = parse_csg(R"({"primitive": "box", "transform": {"scale": [2, 1, 1],
      "rotate": {"axis": [0, 0, 1], "degrees": 90}, "translate": [0, 10, 0]}})", "t.json", ".");
  const CsgResult r = evaluate(n);
  const auto box = bounding_box(r.mesh);
  EXPECT_NEAR(box.min().y(), 9.0, 1e-12);
  EXPECT_NEAR(box.max().y(), 11.0, 1e-12);
  EXPECT_NEAR(box.max().x() - box.min().x(), 1.0, 1e-12);
  EXPECT_NEAR(r.volume, 2.0, 1e-12);
  // A mirror keeps the solid outward.
  const CsgResult m = evaluate(parse_csg(R"({"primitive": "cone", "transform": {"scale": [-1, 1, 1]}})", "m.json", "."));
  EXPECT_GT(m.volume, 0.0);
}

TEST(CsgTree, BadNodesAreNamedByTheirJsonPath) {
  auto error_of = [](const std::string& text) {
    try {
      parse_csg(text, "model.json", ".");
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(error_of(R"({"op": "union", "children": [{"primitive": "box"}, {"primitive": "blob"}]})"),
            "model.json: $.children[1].primitive: must be box, sphere, cylinder, cone or torus");
  EXPECT_EQ(error_of(R"({"op": "xor", "children": [{"primitive": "box"}]})"),
            "model.json: $.op: must be \"union\", \"difference\" or \"intersection\"");
  EXPECT_NE(error_of(R"({"op": "union"})").find("$: an operation needs \"children\""), std::string::npos);
  EXPECT_NE(error_of(R"({"primitive": "box", "colour": 3})").find("$.colour: unknown key"), std::string::npos);
  EXPECT_NE(error_of(R"({"primitive": "box", "transform": {"spin": 3}})").find("$.transform.spin: unknown transform"), std::string::npos);
  EXPECT_NE(error_of(R"({"primitive": "box", "transform": {"scale": 0}})").find("must not be zero"), std::string::npos);
  EXPECT_NE(error_of("{not json").find("model.json: not valid JSON"), std::string::npos);
  // A number past a double is nlohmann's out_of_range, not a parse_error: it escaped as a foreign
  // exception naming no file (found by fuzzing).
  EXPECT_NE(error_of(R"({"primitive": "sphere", "radius": 3e777})").find("model.json: not valid JSON"), std::string::npos);
  EXPECT_THROW(evaluate(parse_csg(R"({"primitive": "sphere", "radius": -1})", "s.json", ".")), Error);
}

TEST(CsgTree, ManyPartUnionsAreExactWhetherPartsOverlapTouchOrStandApart) {
  // Five unit cubes along x at a spacing s: overlapping (s < 1) they fuse into one box of length
  // 4s + 1; touching (s = 1) they fuse too; apart (s > 1) the union keeps five shells. The parts are
  // reduced in parallel, so the same tree is also evaluated twice to check the result repeats.
  auto row_of_cubes = [](double spacing) {
    std::string children;
    for (int i = 0; i < 5; ++i)
      children += fmt::format(R"({}{{"primitive": "box", "transform": {{"translate": [{}, 0, 0]}}}})", i ? ", " : "", i * spacing);
    return parse_csg(fmt::format(R"({{"op": "union", "children": [{}]}})", children), "row.json", ".");
  };
  for (const double spacing : {0.5, 0.75, 1.0, 1.5}) {
    SCOPED_TRACE(spacing);
    const CsgNode tree = row_of_cubes(spacing);
    const CsgResult r = evaluate(tree);
    expect_solid(r.mesh);
    const bool apart = spacing > 1.0;
    EXPECT_NEAR(r.volume, apart ? 5.0 : 4 * spacing + 1, 1e-9);
    EXPECT_EQ(inspect(r.mesh).components, apart ? 5 : 1);
    EXPECT_EQ(r.operations, apart ? 0 : 4);  // apart: one bounding-box test, no boolean at all
    const CsgResult again = evaluate(tree);
    EXPECT_EQ(again.mesh.positions, r.mesh.positions);
    EXPECT_EQ(again.mesh.triangles, r.mesh.triangles);
  }
}

TEST(Csg, NeedlesWhoseCornersRoundToOnePointAreDroppedNotRefused) {
  // A unit cube against a copy turned by 1e-14 degrees: the exact result has needle triangles
  // whose two close corners round to the same double. Such a needle is gone after rounding (as if
  // its short edge had been collapsed); before, the result was refused as unconnectable.
  const std::pair<const char*, const char*> cases[] = {{"difference", "[1, 2, 3], \"degrees\": 3e-14"},
                                                       {"difference", "[1, 1, 0], \"degrees\": 1e-14"},
                                                       {"union", "[2, -1, 5], \"degrees\": 1e-14"}};
  for (const auto& [op, rotation] : cases) {
    SCOPED_TRACE(fmt::format("{} {}", op, rotation));
    const CsgResult r = evaluate(parse_csg(
        fmt::format(R"({{"op": "{}", "children": [{{"primitive": "box"}}, {{"primitive": "box", "transform": {{"rotate": {{"axis": {}}}, "translate": [0.5, 0.5, 0]}}}}]}})",
                    op, rotation),
        "turned.json", "."));
    expect_solid(r.mesh);
    EXPECT_NEAR(r.volume, std::string(op) == "union" ? 1.75 : 0.75, 1e-9);
  }
}

TEST(CsgSplit, HalvesOfASolidJoinBackToTheSameSolid) {
  // Convex, curved, and with a hole (the torus's cross-section through its axis is two discs).
  const std::vector<Mesh> solids{make_box({.size = {2, 1, 0.5}}), make_uv_sphere({.tolerance = 0.01}),
                                 make_torus({.major_radius = 1, .minor_radius = 0.3, .tolerance = 0.01})};
  for (const Mesh& solid : solids) {
    const MeshReport whole = inspect(solid);
    for (int axis = 0; axis < 3; ++axis)
      for (const double at : {-0.1234, 0.0, 0.0371, 0.2}) {
        SCOPED_TRACE(fmt::format("{} faces, axis {}, at {}", solid.num_faces(), axis, at));
        const auto [below, above] = split_solid(solid, axis, at);
        expect_solid(below);
        expect_solid(above);
        EXPECT_LE(below.positions.col(axis).maxCoeff(), at);
        EXPECT_GE(above.positions.col(axis).minCoeff(), at);
        EXPECT_NEAR(volume_of(below) + volume_of(above), *whole.volume, 1e-12 * *whole.volume);
        const std::optional<Mesh> joined = join_solids(below, above, axis, at);
        ASSERT_TRUE(joined);
        expect_solid(*joined);
        const MeshReport r = inspect(*joined);
        EXPECT_NEAR(*r.volume, *whole.volume, 1e-12 * *whole.volume);
        EXPECT_EQ(r.components, whole.components);
        EXPECT_EQ(r.genus, whole.genus);
      }
  }
  // A plane that misses the solid leaves it whole on one side.
  const Mesh box = make_box({});
  EXPECT_EQ(split_solid(box, 0, 0.5).first.triangles, box.triangles);  // touching is missing
  EXPECT_EQ(split_solid(box, 2, -3).second.triangles, box.triangles);
  EXPECT_EQ(split_solid(box, 2, -3).first.num_faces(), 0);
}

TEST(CsgSplit, SolidsWhoseSeamsDoNotMatchAreNotJoined) {
  // Two boxes face to face in x = 0.5, but the second's face is larger: the seam edges differ, so only
  // a union can combine them.
  const Mesh small = make_box({}), large = moved(make_box({.size = {1, 2, 2}}), 1, 0, 0);
  EXPECT_FALSE(join_solids(small, large, 0, 0.5));
}

TEST(CsgTree, ADifferenceOfManyPartsIsTheSameSolidWhetherSplitOrNot) {
  // A plate minus a 6 x 4 grid of cylinders: 24 cutting parts, so it is cut between two groups and
  // joined again. Same volume, one component, one hole per cylinder, and a result that repeats.
  std::string children = R"({"primitive": "box", "size": [6, 4, 0.5]})";
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 4; ++j)
      children += fmt::format(R"(, {{"primitive": "cylinder", "radius": 0.3, "height": 1, "transform": {{"translate": [{}, {}, 0]}}}})",
                              i - 2.5, j - 1.5);
  const CsgNode tree = parse_csg(fmt::format(R"({{"op": "difference", "children": [{}]}})", children), "plate.json", ".");
  const CsgResult whole = evaluate(tree, {.tolerance = 0.002, .split_at_parts = 0});
  const CsgResult split = evaluate(tree, {.tolerance = 0.002});
  EXPECT_EQ(whole.operations, 1);
  EXPECT_GE(split.operations, 2);  // the halves' differences (the cut and the join are not booleans)
  for (const CsgResult* r : {&whole, &split}) {
    expect_solid(r->mesh);
    const MeshReport report = inspect(r->mesh);
    EXPECT_EQ(report.components, 1);
    EXPECT_EQ(report.genus, 24);
  }
  EXPECT_NEAR(split.volume, whole.volume, 1e-12 * whole.volume);
  const CsgResult again = evaluate(tree, {.tolerance = 0.002});
  EXPECT_EQ(again.mesh.positions, split.mesh.positions);
  EXPECT_EQ(again.mesh.triangles, split.mesh.triangles);
}

}  // namespace
}  // namespace lodkit
