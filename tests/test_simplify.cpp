// The simplifier's promises, checked on families of generated meshes for every method.
#include <gtest/gtest.h>
#include <lodkit/error.h>
#include <lodkit/inspect.h>
#include <lodkit/metrics.h>
#include <lodkit/primitives.h>
#include <lodkit/progressive.h>
#include <lodkit/simplify.h>

#include <algorithm>
#include <limits>
#include <numbers>
#include <random>

#include "simplify/queue.h"
#include "test_util.h"

namespace lodkit {
namespace {

struct Case {
  std::string name;
  Mesh mesh;
};

std::vector<Case> families() {
  return {{"bumpy_sphere", test::bumpy_sphere(4, 0.02)},
          {"torus", make_torus({.major_segments = 96, .minor_segments = 32})},
          {"uv_sphere_with_seams", make_uv_sphere({.segments = 48, .rings = 24, .uvs = true})},
          {"grid_with_boundary", make_grid({.divisions_x = 30, .divisions_y = 20})},
          {"cylinder", make_cylinder({.segments = 48, .stacks = 12})}};
}

class EveryMethod : public ::testing::TestWithParam<SimplifyMethod> {};

TEST_P(EveryMethod, KeepsTopologyAndOrientationAndHitsTheTarget) {
  for (const Case& c : families()) {
    SCOPED_TRACE(c.name);
    const MeshReport before = inspect(c.mesh);
    for (double ratio : {0.5, 0.1, 0.02}) {
      SCOPED_TRACE(ratio);
      SimplifyOptions o;
      o.method = GetParam();
      o.target_ratio = ratio;
      const SimplifyResult r = simplify(c.mesh, o);
      validate(r.mesh);
      const MeshReport after = inspect(r.mesh);
      EXPECT_TRUE(after.manifold);
      EXPECT_TRUE(after.oriented);
      EXPECT_EQ(after.euler_characteristic, before.euler_characteristic);
      EXPECT_EQ(after.boundary_loops, before.boundary_loops);
      EXPECT_EQ(after.components, before.components);
      EXPECT_EQ(after.closed, before.closed);
      EXPECT_EQ(after.degenerate_faces, 0);
      EXPECT_EQ(count_flipped_faces(c.mesh, r.mesh), 0);
      const Index target = static_cast<Index>(std::llround(ratio * c.mesh.num_faces()));
      if (r.reason == StopReason::TargetReached) {
        EXPECT_LE(r.faces_out, target);
        EXPECT_GE(r.faces_out, target - 1);  // one below only when no collapse removes a single face
      } else {
        ADD_FAILURE() << "stopped early: " << r.reason_text;
      }
      EXPECT_EQ(r.faces_out, r.mesh.num_faces());
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Methods, EveryMethod,
                         ::testing::Values(SimplifyMethod::Quadric, SimplifyMethod::Hoppe, SimplifyMethod::EdgeLength),
                         [](const auto& param_info) {
                           std::string s = to_string(param_info.param);
                           std::replace(s.begin(), s.end(), '-', '_');
                           return s;
                         });

TEST(Simplify, OneFaceLeftTakesABoundaryEdgeOrLandsOneBelow) {
  // A collapse removes two faces, or one on a boundary edge. With an odd number to remove, an open
  // mesh still lands exactly on the target; a closed one lands one below it.
  for (const Index target : {601, 333, 75}) {
    SCOPED_TRACE(target);
    SimplifyOptions o;
    o.target_faces = target;
    const Mesh grid = make_grid({.divisions_x = 30, .divisions_y = 20});  // 1,200 faces, open
    const SimplifyResult open = simplify(grid, o);
    EXPECT_EQ(open.reason, StopReason::TargetReached);
    EXPECT_EQ(open.faces_out, target);
    EXPECT_EQ(inspect(open.mesh).boundary_loops, 1);
    const Mesh sphere = make_uv_sphere({.segments = 32, .rings = 16});  // closed
    const SimplifyResult closed = simplify(sphere, o);
    EXPECT_EQ(closed.reason, StopReason::TargetReached);
    EXPECT_EQ(closed.faces_out, target - 1);
    EXPECT_TRUE(inspect(closed.mesh).manifold);
  }
}

TEST(Simplify, SameResultForAnyNumberOfThreads) {
  // Candidates are scored side by side (every edge at the start; hoppe's re-scored rings after each
  // collapse, and its batches of entries whose neighbourhood changed) but queued in a fixed order, so
  // the collapses cannot depend on the threads.
  Mesh m = make_icosphere({.subdivisions = 4});  // 7,680 edges: enough for the parallel start
  std::mt19937 random(11);
  std::uniform_real_distribution<double> bump(0.98, 1.02);
  for (Index v = 0; v < m.num_vertices(); ++v) m.positions.row(v) *= bump(random);
  for (const SimplifyMethod method : {SimplifyMethod::Quadric, SimplifyMethod::Hoppe}) {
    SCOPED_TRACE(to_string(method));
    SimplifyOptions o;
    o.method = method;
    o.target_ratio = 0.1;
    const SimplifyResult one = test::on_threads(1, [&] { return simplify(m, o); });
    const SimplifyResult many = test::on_threads(4, [&] { return simplify(m, o); });
    EXPECT_EQ(one.mesh.positions, many.mesh.positions);
    EXPECT_EQ(one.mesh.triangles, many.mesh.triangles);
    EXPECT_EQ(one.error, many.error);
  }
}

TEST(QuadHeap, FilterKeepsTheOrderAndMayEmptyTheHeap) {
  // The engine drops stale entries in bulk; what is left must pop in the same order as before.
  std::mt19937 random(7);
  std::uniform_int_distribution<int> value(0, 999);
  detail::QuadHeap<int, std::less<int>> heap;
  std::vector<int> kept;
  for (int i = 0; i < 5000; ++i) {
    const int x = value(random);
    heap.push(x);
    if (x % 3 != 0) kept.push_back(x);
  }
  heap.filter([](int x) { return x % 3 != 0; });
  ASSERT_EQ(heap.size(), kept.size());
  std::sort(kept.begin(), kept.end());
  for (const int x : kept) EXPECT_EQ(heap.pop(), x);
  EXPECT_TRUE(heap.empty());
  heap.push(1), heap.push(2);
  heap.filter([](int) { return false; });
  EXPECT_TRUE(heap.empty());
}

TEST(Simplify, OpenMeshWithBoundaryHitsOddTargetsExactly) {
  const Mesh grid = make_grid({.divisions_x = 20, .divisions_y = 20});
  for (Index target : {401, 400, 77, 10}) {
    SimplifyOptions o;
    o.target_faces = target;
    EXPECT_EQ(simplify(grid, o).faces_out, target);
  }
}

TEST(Simplify, FlatCubeFacesBecomeTwelveTrianglesWithZeroError) {
  const Mesh cube = make_box({.size = {2, 1, 1}, .divisions = 8});
  SimplifyOptions o;
  o.target_faces = 12;
  const SimplifyResult r = simplify(cube, o);
  EXPECT_EQ(r.faces_out, 12) << r.reason_text;
  // The estimate is the square root of a rounded quadric (10^-16 of the squared size: 10^-8); the
  // measured distance is exact.
  EXPECT_LT(r.error, 1e-7);
  EXPECT_LT(compare(cube, r.mesh).hausdorff, 1e-9);
  ASSERT_TRUE(inspect(r.mesh).volume);
  EXPECT_NEAR(*inspect(r.mesh).volume, 2.0, 1e-9);
}

TEST(Simplify, FlatGridBecomesTwoTrianglesWithZeroError) {
  const Mesh grid = make_grid({.size = {3, 2}, .divisions_x = 24, .divisions_y = 16});
  SimplifyOptions o;
  o.target_faces = 2;
  const SimplifyResult r = simplify(grid, o);
  EXPECT_EQ(r.faces_out, 2) << r.reason_text;
  EXPECT_LT(compare(grid, r.mesh).hausdorff, 1e-9);
  EXPECT_NEAR(inspect(r.mesh).area, 6.0, 1e-9);
}

// The most faces around any vertex of m (the grids here have one wedge per point).
Index most_faces_at_a_vertex(const Mesh& m) {
  std::vector<Index> faces(static_cast<std::size_t>(m.num_vertices()), 0);
  for (Index f = 0; f < m.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) ++faces[static_cast<std::size_t>(m.triangles(f, k))];
  return *std::max_element(faces.begin(), faces.end());
}

// On a flat part only hoppe's springs order the collapses, and the paper's schedule weakens them where
// points have piled up: the coarser a patch, the cheaper its next collapse. Without a limit a vertex
// gathers 36 faces on this grid (60-100 on a 20,000-face grid, which then takes 12 s to 1 %).
TEST(Simplify, HoppeGrowsNoHubsOnFlatParts) {
  const Mesh grid = make_grid({.divisions_x = 30, .divisions_y = 30});
  SimplifyOptions o{.method = SimplifyMethod::Hoppe, .target_ratio = 0.1};
  o.hoppe_min_points = 0;  // 4 random points per face, as a large mesh gets: the springs start strong
  o.hoppe_energy_from = 0;  // the energy ranks every collapse (the quadric stage grows no hubs here)
  const SimplifyResult r = simplify(grid, o);
  ASSERT_EQ(r.reason, StopReason::TargetReached) << r.reason_text;
  EXPECT_LE(most_faces_at_a_vertex(r.mesh), default_max_valence(SimplifyMethod::Hoppe));
  // Flat still; the boundary holds to within its samples' reach (corners are cut by 2e-6 with or without
  // the limit: hoppe weighs the boundary's points against its springs).
  EXPECT_EQ(r.mesh.positions.col(2).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_LT(compare(grid, r.mesh).hausdorff, 1e-5);
  EXPECT_NEAR(inspect(r.mesh).area, 1.0, 1e-5);
  o.max_valence = 0;  // no limit: the failure it prevents
  EXPECT_GT(most_faces_at_a_vertex(simplify(grid, o).mesh), default_max_valence(SimplifyMethod::Hoppe));
}

// A limit that every collapse would break stops the run short, and says so.
TEST(Simplify, ALegalCollapseIsNeverLeftBehind) {
  // An edge refused when rated (here: it would give a vertex too many faces) is rated again only when a
  // collapse keeps one of its ends; one that a collapse beside it made legal was never queued again, and
  // a grid to 8 faces with at most 7 faces a vertex stopped at 195-375 faces.
  // The engine rates what is left once more when its queue runs dry.
  const Mesh grid = make_grid({.divisions_x = 20, .divisions_y = 20});
  for (const SimplifyMethod method : {SimplifyMethod::Quadric, SimplifyMethod::Hoppe, SimplifyMethod::EdgeLength}) {
    SCOPED_TRACE(to_string(method));
    const SimplifyResult r = simplify(grid, {.method = method, .target_faces = 8, .max_valence = 7});
    EXPECT_EQ(r.reason, StopReason::TargetReached) << r.reason_text;
    EXPECT_EQ(r.faces_out, 8);
    EXPECT_LE(most_faces_at_a_vertex(r.mesh), 7);
  }
}

TEST(Simplify, ValenceLimitHoldsForAnyMethodAndIsReported) {
  // A torus (6 faces at every vertex) to 14 faces, the fewest a torus can have, with at most 8 around
  // a vertex: the run gets to 16-26 faces. (A grid gets to any target: a collapse that leaves no vertex
  // with more faces than before is always allowed, and its boundary vertices have few.)
  const Mesh torus = make_torus({});
  for (const SimplifyMethod method : {SimplifyMethod::Quadric, SimplifyMethod::Hoppe, SimplifyMethod::EdgeLength}) {
    SCOPED_TRACE(to_string(method));
    const SimplifyResult r = simplify(torus, {.method = method, .target_faces = 14, .max_valence = 8});
    EXPECT_LE(most_faces_at_a_vertex(r.mesh), 8);
    EXPECT_LT(r.faces_out, torus.num_faces() / 10);
    EXPECT_EQ(r.reason, StopReason::NoLegalCollapse);
    EXPECT_GT(r.blocked.valence, 0);
    EXPECT_NE(r.reason_text.find("blocked by the valence limit"), std::string::npos) << r.reason_text;
  }
}

// A thin blade (an icosphere flattened to 2 % thickness): the face planes of both sides contain
// the directions in which its rim can retreat, so plain quadrics erode the outline; the crease
// planes (on by default) must at least cut that erosion by a quarter, without costing much RMS (they
// trade a little: 1.06-1.11 times the RMS without them, at 3 % and 1 %).
TEST(Simplify, CreasePlanesKeepAThinBladesOutline) {
  Mesh blade = make_icosphere({.subdivisions = 5});
  blade.positions.col(1) *= 0.5;
  blade.positions.col(2) *= 0.02;
  for (double ratio : {0.03, 0.01}) {
    SCOPED_TRACE(ratio);
    SimplifyOptions o;
    o.target_ratio = ratio;
    const Comparison with = compare(blade, simplify(blade, o).mesh);
    o.crease_weight = 0;
    const Comparison without = compare(blade, simplify(blade, o).mesh);
    EXPECT_LT(with.a_to_b.max, 0.75 * without.a_to_b.max);
    EXPECT_LT(with.hausdorff, 0.75 * without.hausdorff);
    EXPECT_LT(with.rms, 1.15 * without.rms);
  }
}

TEST_P(EveryMethod, KeepsUvSeamsAligned) {
  const Mesh sphere = make_uv_sphere({.segments = 64, .rings = 32, .uvs = true});
  SimplifyOptions o;
  o.method = GetParam();
  o.target_ratio = 0.1;
  const SimplifyResult r = simplify(sphere, o);
  const Mesh& m = r.mesh;
  ASSERT_TRUE(m.has_uvs());
  // No face straddles the u = 0 / u = 1 seam (near the poles faces fan over many longitudes).
  EXPECT_LT(test::widest_u_span(m, 0.35), 0.5);
  // The u = 0 / u = 1 seam is intact: every seam vertex on one side has its twin, at the same
  // position with the same v, on the other.
  const test::SeamTwins seam = test::u_seam_twins(m);
  EXPECT_GE(seam.seam, 2);
  EXPECT_EQ(seam.without_twin, 0);
  // edge-length, whose costs ignore the UVs, pulls a pole (a wedge per face) onto the seam, and two of
  // the pole's wedges on one side end up with the same UVs: a vertex twice, the texture still whole.
  if (GetParam() != SimplifyMethod::EdgeLength) {
    EXPECT_EQ(seam.with_more_twins, 0);
  }
  EXPECT_TRUE(inspect(m).closed);
}

TEST(Simplify, FlatShadingIsNoSeamWhenNormalsAreRecomputed) {
  // A normal per face corner splits every vertex, so every edge is a seam and nothing may collapse;
  // recompute_normals welds the corners back, simplifies the shape and gives the output new normals.
  const Mesh smooth = test::bumpy_sphere(3, 0.02);  // 1,280 faces, closed, genus 0
  const Mesh flat = test::flat_shaded(smooth);
  SimplifyOptions o;
  o.target_faces = 128;
  const SimplifyResult kept = simplify(flat, o);
  EXPECT_EQ(kept.reason, StopReason::NoLegalCollapse);
  EXPECT_EQ(kept.faces_out, flat.num_faces());
  EXPECT_EQ(kept.blocked.seams, kept.blocked.remaining);

  o.recompute_normals = true;
  const SimplifyResult r = simplify(flat, o);
  ASSERT_EQ(r.reason, StopReason::TargetReached) << r.reason_text;
  EXPECT_EQ(r.faces_out, 128);
  const MeshReport after = inspect(r.mesh);
  EXPECT_TRUE(after.manifold && after.closed && after.oriented);
  EXPECT_EQ(after.euler_characteristic, 2);
  EXPECT_EQ(r.mesh.num_vertices(), 66);  // welded: V = F / 2 + 2
  EXPECT_EQ(count_flipped_faces(smooth, r.mesh), 0);
  // The output's normals are its own area-weighted vertex normals, unit length.
  ASSERT_TRUE(r.mesh.has_normals());
  const Normals expected = compute_vertex_normals(r.mesh);
  for (Index v = 0; v < r.mesh.num_vertices(); ++v) {
    EXPECT_NEAR(r.mesh.attributes.normals.row(v).norm(), 1.0, 1e-12);
    EXPECT_LT((r.mesh.attributes.normals.row(v) - expected.row(v)).norm(), 1e-12) << "vertex " << v;
  }
  // As accurate as simplifying the welded mesh (the same shape; only tie-breaks between equal costs
  // may differ, since the corners are numbered differently).
  SimplifyOptions plain;
  plain.target_faces = 128;
  const double welded = compare(smooth, simplify(smooth, plain).mesh).hausdorff;
  EXPECT_LT(compare(smooth, r.mesh).hausdorff, 1.1 * welded);

  o.record_collapses = true;
  EXPECT_THROW(simplify(flat, o), Error);
  EXPECT_THROW(simplify(smooth, o), Error);  // refused whatever the mesh holds
}

TEST(Simplify, LockedBoundaryStaysPutAndTheReasonIsGiven) {
  const Mesh grid = make_grid({.divisions_x = 10, .divisions_y = 10});
  SimplifyOptions o;
  o.target_faces = 2;
  o.lock_boundary = true;
  const SimplifyResult r = simplify(grid, o);
  EXPECT_EQ(r.reason, StopReason::NoLegalCollapse);
  EXPECT_GT(r.faces_out, 2);
  EXPECT_EQ(r.locked_vertices, 40);
  EXPECT_NE(r.reason_text.find("locked"), std::string::npos) << r.reason_text;
  EXPECT_EQ(inspect(r.mesh).boundary_edges, 40);
  EXPECT_GT(r.blocked.locked, 0);
}

// Counts the reasons of a run that stopped short; every edge left is counted once.
Index blocked_total(const BlockedEdges& b) {
  return b.locked + b.topology + b.boundary + b.seams + b.flips + b.slivers + b.error_limit + b.cost;
}

TEST(Simplify, StoppingShortCountsEveryEdgeLeftByItsReason) {
  // A thin torus (tube 1/20 of the ring): at the default 60 degrees both the link condition and the
  // flip limit hold edges back; at 90 degrees the same run gets further.
  const Mesh torus = make_torus({.minor_radius = 0.05, .major_segments = 96, .minor_segments = 8});
  SimplifyOptions o;
  o.target_faces = 16;
  const SimplifyResult r = simplify(torus, o);
  ASSERT_EQ(r.reason, StopReason::NoLegalCollapse) << r.reason_text;
  EXPECT_EQ(r.blocked.remaining, r.faces_out * 3 / 2);  // closed: every edge has two faces
  EXPECT_EQ(blocked_total(r.blocked), r.blocked.remaining);
  EXPECT_GT(r.blocked.flips, 0);
  EXPECT_GT(r.blocked.topology, 0);
  EXPECT_EQ(r.blocked.locked + r.blocked.boundary + r.blocked.seams + r.blocked.error_limit, 0);
  EXPECT_NE(r.reason_text.find(std::to_string(r.blocked.flips) + " blocked by face flips"), std::string::npos)
      << r.reason_text;

  o.max_normal_change_deg = 90;
  const SimplifyResult wider = simplify(torus, o);
  EXPECT_LT(wider.faces_out, r.faces_out) << wider.reason_text;
  EXPECT_EQ(inspect(wider.mesh).genus, 1);

  o.target_faces = 200;  // reachable: nothing is counted
  const SimplifyResult reached = simplify(torus, o);
  ASSERT_EQ(reached.reason, StopReason::TargetReached);
  EXPECT_EQ(reached.blocked.remaining, 0);
  EXPECT_EQ(blocked_total(reached.blocked), 0);
}

TEST(Simplify, ErrorLimitStopsEarly) {
  const Mesh m = test::bumpy_sphere(4, 0.02);
  SimplifyOptions o;
  o.target_faces = 20;
  o.max_error = 0.002;
  const SimplifyResult r = simplify(m, o);
  EXPECT_EQ(r.reason, StopReason::ErrorLimit) << r.reason_text;
  EXPECT_LE(r.error, 0.002);
  EXPECT_GT(r.faces_out, 20);
  EXPECT_GT(r.blocked.error_limit, 0);
  EXPECT_EQ(blocked_total(r.blocked), r.blocked.remaining);
}

TEST(Simplify, DirtyInputSimplifiesWithoutCrashing) {
  // A bumpy sphere plus: a fin (a triangle hanging on one of its edges: a non-manifold edge), a bow tie
  // touching a vertex, duplicate vertices (a second unwelded copy of some faces' corners), and
  // unreferenced vertices.
  Mesh m = test::bumpy_sphere(3, 0.01);
  const Index nv = m.num_vertices(), nf = m.num_faces();
  m.positions.conservativeResize(nv + 6, 3);
  m.positions.row(nv) << 0, 0, 3;          // fin apex on edge (t0, t1) of face 0
  m.positions.row(nv + 1) << 5, 5, 5;      // unreferenced
  m.positions.row(nv + 2) = m.positions.row(m.triangles(5, 0));  // duplicate position
  m.positions.row(nv + 3) << 2, 2, 2;
  m.positions.row(nv + 4) << 2, 3, 2;      // bow tie on vertex of face 9
  m.positions.row(nv + 5) << 9, 9, 9;      // unreferenced
  m.triangles.conservativeResize(nf + 2, 3);
  m.triangles.row(nf) << m.triangles(0, 1), m.triangles(0, 0), nv;
  m.triangles.row(nf + 1) << m.triangles(9, 0), nv + 3, nv + 4;
  m.triangles(5, 0) = nv + 2;
  for (SimplifyMethod method : {SimplifyMethod::Quadric, SimplifyMethod::Hoppe, SimplifyMethod::EdgeLength}) {
    SimplifyOptions o;
    o.method = method;
    o.target_ratio = 0.1;
    const SimplifyResult r = simplify(m, o);
    validate(r.mesh);
    EXPECT_GT(r.locked_vertices, 0);
    EXPECT_LT(r.faces_out, nf / 2);
    const MeshReport after = inspect(r.mesh);
    EXPECT_EQ(after.non_manifold_edges, 1);  // the fin's edge is locked, not repaired
  }
}

TEST(Simplify, ADroppedDegenerateFaceChangesNothingElse) {
  // A face with two corners on one position is dropped before the run; the faces after it then sit one
  // place further on than the engine's own lists of them, which the boundary and crease planes must
  // follow. The result is the clean mesh's, exactly: a box (creases) and a grid (a boundary).
  for (const Mesh& clean : {make_box({.size = {2, 1, 1}, .divisions = 6}), make_grid({.divisions_x = 16, .divisions_y = 12})}) {
    Mesh dirty = clean;
    const Index nv = clean.num_vertices(), nf = clean.num_faces();
    dirty.positions.conservativeResize(nv + 1, 3);
    dirty.positions.row(nv) = clean.positions.row(0);  // a second vertex on vertex 0's position
    dirty.triangles.resize(nf + 1, 3);
    dirty.triangles.row(0) << 0, nv, clean.triangles(0, 1);
    dirty.triangles.bottomRows(nf) = clean.triangles;
    SimplifyOptions o;
    o.target_ratio = 0.2;
    const SimplifyResult a = simplify(clean, o), b = simplify(dirty, o);
    EXPECT_EQ(b.dropped_degenerate_faces, 1);
    ASSERT_EQ(a.faces_out, b.faces_out);
    EXPECT_EQ(a.mesh.triangles, b.mesh.triangles);
    EXPECT_EQ(a.mesh.positions, b.mesh.positions);
    ASSERT_EQ(a.face_origin.size(), b.face_origin.size());
    for (std::size_t i = 0; i < a.face_origin.size(); ++i) EXPECT_EQ(b.face_origin[i], a.face_origin[i] + 1);
  }
}

// The largest angle between an output face's normal and its input face's (SimplifyResult::face_origin).
double largest_turn_deg(const Mesh& in, const SimplifyResult& r) {
  auto normal = [](const Mesh& m, Index f) {
    const Eigen::Vector3d a = m.positions.row(m.triangles(f, 0)), b = m.positions.row(m.triangles(f, 1)),
                          c = m.positions.row(m.triangles(f, 2));
    return Eigen::Vector3d((b - a).cross(c - a).normalized());
  };
  double worst = 0;
  for (Index f = 0; f < r.mesh.num_faces(); ++f) {
    const double cosine = std::clamp(normal(r.mesh, f).dot(normal(in, r.face_origin[f])), -1.0, 1.0);
    worst = std::max(worst, std::acos(cosine) * 180 / std::numbers::pi);
  }
  return worst;
}

TEST(Simplify, NoFaceTurnsFurtherFromItsInputSelfThanTheTotalLimit) {
  // Down to 1 % of a thin torus, faces turn far from their input orientation: as far as the total limit
  // lets them, and no further, though each collapse turns them less than that.
  const Mesh torus = make_torus({.minor_radius = 0.2, .major_segments = 96, .minor_segments = 24});
  for (const SimplifyMethod method : {SimplifyMethod::Quadric, SimplifyMethod::Hoppe}) {
    SimplifyOptions o;
    o.method = method;
    o.target_ratio = 0.01;
    o.max_normal_change_deg = 30;
    const SimplifyResult by_default = simplify(torus, o);
    const double by_method = by_default.turn_limit_relaxed_at ? 90.0 : default_max_total_normal_change(method);
    EXPECT_LE(largest_turn_deg(torus, by_default), by_method + 1e-3);
    for (const double total : {30.0, 45.0, 120.0}) {
      o.max_total_normal_change_deg = total;
      const double turn = largest_turn_deg(torus, simplify(torus, o));
      EXPECT_LE(turn, total + 1e-3) << total;
      if (total == 45.0) {
        EXPECT_GT(turn, 30.0);  // more than one collapse's turn
      }
    }
  }
}

TEST(Simplify, TheDefaultTurnLimitGivesWayRatherThanStopShort) {
  // To 20 and 24 faces of a torus, hoppe and edge-length stop at 24 and 26 under their default 60-degree
  // limit on a face's turn from its input shape. Rather than stop there, the run goes on with 90 degrees,
  // where no face faces against its input self; a limit the caller set stays put.
  const Mesh torus = make_torus({});
  for (const auto& [method, target] : {std::pair{SimplifyMethod::Hoppe, 20}, std::pair{SimplifyMethod::EdgeLength, 24}}) {
    SCOPED_TRACE(to_string(method));
    SimplifyOptions o;
    o.method = method;
    o.target_faces = target;
    // (hoppe's default quadric stage takes this torus to 40 faces another way, after which the energy
    // stops at 22, held back by flips: the relaxation is tested with the energy throughout.)
    o.hoppe_energy_from = 0;
    const SimplifyResult r = simplify(torus, o);
    EXPECT_EQ(r.reason, StopReason::TargetReached) << r.reason_text;
    EXPECT_EQ(r.faces_out, target);
    ASSERT_TRUE(r.turn_limit_relaxed_at.has_value());
    EXPECT_GT(*r.turn_limit_relaxed_at, target);
    EXPECT_NE(r.reason_text.find("90 degrees"), std::string::npos) << r.reason_text;
    const MeshReport report = inspect(r.mesh);
    EXPECT_TRUE(report.manifold);
    EXPECT_EQ(report.genus, 1);
    EXPECT_LE(largest_turn_deg(torus, r), 90.0 + 1e-3);

    o.max_total_normal_change_deg = 60;  // the same limit, set by the caller
    const SimplifyResult kept = simplify(torus, o);
    EXPECT_EQ(kept.faces_out, *r.turn_limit_relaxed_at);
    EXPECT_FALSE(kept.turn_limit_relaxed_at.has_value());
    EXPECT_EQ(kept.reason, StopReason::NoLegalCollapse);
    EXPECT_GT(kept.blocked.flips, 0);
    EXPECT_LE(largest_turn_deg(torus, kept), 60.0 + 1e-3);
    // No face newly faces against the input (tori this coarse cut through the tube at either limit:
    // hoppe 1 face at 20 and 2 at 24, edge-length a few).
    EXPECT_LE(count_flipped_faces(torus, r.mesh), count_flipped_faces(torus, kept.mesh));
  }
  // Where the default limit never stood in the way, nothing changes.
  SimplifyOptions o;
  o.method = SimplifyMethod::Hoppe;
  o.target_faces = 48;
  EXPECT_FALSE(simplify(torus, o).turn_limit_relaxed_at.has_value());
}

TEST(Simplify, FarFromTheOriginSimplifiesAsWellAsAtIt) {
  // A quadric's terms grow with the squared distance from the origin: a million units out their
  // rounding swamped the errors they rank, and the collapses went in near-random order (Hausdorff 2.5x
  // the centred run's, and a flipped face once faces could turn 90 degrees). The engine measures from
  // a point near the mesh.
  const Mesh near = test::bumpy_sphere(4, 0.02);
  Mesh far = near;
  far.positions.rowwise() += Eigen::RowVector3d(1e6, -2e6, 3e6);
  SimplifyOptions o;
  o.target_ratio = 0.1;
  const SimplifyResult a = simplify(near, o), b = simplify(far, o);
  ASSERT_EQ(a.faces_out, b.faces_out);
  EXPECT_LT(compare(far, b.mesh).hausdorff, 1.1 * compare(near, a.mesh).hausdorff);
  EXPECT_EQ(count_flipped_faces(far, b.mesh), 0);
}

TEST(Simplify, AShiftedCylinderSimplifiesTheSameWay) {
  // Collapses along a cylinder's straight sides cost nothing; rounding used to pick among them, so
  // shorter edge now, and every shift gives the same error. The refit's RMS stage moves the largest
  // distance off its samples, where positions that differ by rounding show: 0.01294-0.01310 over the
  // shifts, so with it the bound is 2 %; the collapses and the refit's first stage stay within 1 %.
  const Mesh cylinder = make_cylinder({.segments = 64, .stacks = 16});
  for (const int rms_passes : {0, kDefaultRefitRmsPasses}) {
    SimplifyOptions o;
    o.target_ratio = 0.03;
    o.refit_rms_passes = rms_passes;
    std::vector<double> errors;
    for (const double shift : {0.0, 0.37, 1.9, 5.3, 11.1}) {
      Mesh moved = cylinder;
      moved.positions.rowwise() += Eigen::RowVector3d(shift, 2 * shift, 3 * shift);
      errors.push_back(compare(moved, simplify(moved, o).mesh).hausdorff);
    }
    const auto [least, most] = std::minmax_element(errors.begin(), errors.end());
    EXPECT_LT(*most, (rms_passes == 0 ? 1.01 : 1.02) * *least) << *least << " .. " << *most;
  }
}

TEST(Simplify, TriangleSoupKeepsEveryTriangleAndSaysWhy) {
  // Separate triangles (a soup): every edge is a boundary edge, and collapsing one would delete its
  // whole triangle. hoppe has no surface left to measure its points against there; it crashed on such
  // a candidate (trimesh_soup.ply) before the link condition could refuse it.
  Mesh m;
  const Index n = 40;
  m.positions.resize(3 * n, 3);
  m.triangles.resize(n, 3);
  for (Index i = 0; i < n; ++i) {
    const double x = 2.0 * i, z = 0.1 * (i % 3);
    m.positions.row(3 * i) << x, 0, z;
    m.positions.row(3 * i + 1) << x + 1, 0.1 * (i % 5), 0;
    m.positions.row(3 * i + 2) << x, 1, -z;
    m.triangles.row(i) << 3 * i, 3 * i + 1, 3 * i + 2;
  }
  for (SimplifyMethod method : {SimplifyMethod::Quadric, SimplifyMethod::Hoppe, SimplifyMethod::EdgeLength}) {
    for (bool topology : {true, false}) {
      SCOPED_TRACE(to_string(method) + (topology ? " preserving topology" : " without checks"));
      SimplifyOptions o;
      o.method = method;
      o.target_ratio = 0.1;
      o.preserve_topology = topology;
      const SimplifyResult r = simplify(m, o);
      validate(r.mesh);
      if (topology || method == SimplifyMethod::Hoppe) {
        // Nothing can go without taking a component with it: every triangle stays, and the report
        // says the target was not reached and why.
        EXPECT_EQ(r.faces_out, n);
        EXPECT_EQ(r.mesh.positions, m.positions);
        EXPECT_NE(r.reason, StopReason::TargetReached);
        EXPECT_NE(r.reason_text.find("none of the"), std::string::npos) << r.reason_text;
      }
    }
  }
}

TEST(Simplify, RecordsEveryCollapse) {
  const Mesh m = test::bumpy_sphere(3, 0.01);
  SimplifyOptions o;
  o.target_ratio = 0.25;
  o.record_collapses = true;
  const SimplifyResult r = simplify(m, o);
  ASSERT_EQ(static_cast<Index>(r.records.size()), r.collapses);
  Index removed = 0;
  for (const CollapseRecord& c : r.records) removed += static_cast<Index>(c.removed_faces.size());
  EXPECT_EQ(removed, r.faces_in - r.faces_out);
}

TEST(Simplify, NaiveMethodWithoutChecksCanBreakTheModel) {
  // The failure lodkit keeps on purpose: with topology checks off, edge-length collapses change the
  // topology of a torus long before the target.
  const Mesh torus = make_torus({.major_segments = 48, .minor_segments = 12});
  SimplifyOptions o;
  o.method = SimplifyMethod::EdgeLength;
  o.preserve_topology = false;
  o.target_faces = 24;
  const MeshReport r = inspect(simplify(torus, o).mesh);
  EXPECT_FALSE(r.manifold && r.genus == 1 && r.degenerate_faces == 0 && r.duplicate_faces == 0);
}

TEST(Simplify, BadOptionsAreErrors) {
  const Mesh m = make_box({});
  EXPECT_THROW(simplify(m, {.target_ratio = 1.5}), Error);
  EXPECT_THROW(simplify(m, {.target_faces = -3}), Error);
  EXPECT_THROW(simplify(m, {.max_error = -1.0}), Error);
  EXPECT_THROW(simplify(m, {.lane_faces = -1}), Error);
  EXPECT_THROW(simplify(m, {.max_valence = -1}), Error);
  for (const double bad : {0.0, -10.0, 181.0, std::nan("")}) {
    SimplifyOptions o;
    o.max_total_normal_change_deg = bad;
    EXPECT_THROW(simplify(m, o), Error) << bad;
  }
  SimplifyOptions hoppe{.method = SimplifyMethod::Hoppe};
  for (const double bad : {-1.0, std::nan(""), 1e6}) {
    hoppe.hoppe_points_per_face = bad;
    EXPECT_THROW(simplify(m, hoppe), Error) << bad;
  }
  hoppe.hoppe_points_per_face = 1.0;
  hoppe.hoppe_min_points = -1;
  EXPECT_THROW(simplify(m, hoppe), Error);
  // Weights and floors that were taken as they came (a NaN weight made every cost NaN), and every entry
  // point that takes these options: simplify_within() set its base from a ratio of 1.5 unchecked.
  for (const double bad : {-1.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
    std::vector<SimplifyOptions> options(5);
    options[0].attribute_weights.normals = bad;
    options[1].attribute_weights.colours = bad;
    options[2].crease_weight = bad;
    options[3].boundary_weight = bad;
    options[4].min_triangle_quality = bad;
    for (std::size_t i = 0; i < options.size(); ++i) {
      EXPECT_THROW(simplify(m, options[i]), Error) << i << " " << bad;
      EXPECT_THROW(simplify_within(m, 0.1, options[i]), Error) << i << " " << bad;
      EXPECT_THROW(build_progressive_mesh(m, {.simplify = options[i]}), Error) << i << " " << bad;
    }
  }
  EXPECT_THROW(simplify_within(m, 0.1, {.target_ratio = 1.5}), Error);
}

// A long box of thin triangles is CAD in miniature. With one random point per face, the paper's spring
// schedule keeps the springs strong through most of the run and they drag vertices off the edges (the
// volume is off by 3e-6 to 3e-5 over seeds 1-8, and by 22 % at seed 7); with the default floor on the
// sample count the points hold the box, and hoppe, like quadric, lands on the box exactly (3e-11).
TEST(Simplify, HoppeSamplesSmallMeshesDenselyEnoughToKeepTheirCreases) {
  const Mesh box = make_box({.size = {4.0, 1.0, 1.0}, .divisions = 24});
  SimplifyOptions o{.method = SimplifyMethod::Hoppe, .target_ratio = 0.02};
  o.refit_passes = 0;  // the collapses' own positions: the refit would mend the sparse case below (3e-9)
  o.hoppe_energy_from = 0;  // the energy ranks every collapse (the quadric stage keeps the box exactly)
  auto volume_error = [&](const Mesh& m) { return std::abs(signed_volume(m) - 4.0) / 4.0; };
  const SimplifyResult dense = simplify(box, o);
  EXPECT_EQ(dense.faces_out, dense.target_faces);
  EXPECT_LT(volume_error(dense.mesh), 1e-9);
  const Eigen::Array3d lo = dense.mesh.positions.colwise().minCoeff(), hi = dense.mesh.positions.colwise().maxCoeff();
  for (Index i = 0; i < dense.mesh.num_vertices(); ++i) {
    const Eigen::Array3d p = dense.mesh.positions.row(i).transpose().array();
    EXPECT_NEAR(std::min((p - lo).abs().minCoeff(), (hi - p).abs().minCoeff()), 0.0, 1e-9) << i;  // on a side
  }
  o.hoppe_min_points = 0;  // the default 4 random points per face, no floor: dense enough too
  EXPECT_LT(volume_error(simplify(box, o).mesh), 1e-6);
  o.hoppe_points_per_face = 1;  // one per face: the springs pull vertices off the edges
  EXPECT_GT(volume_error(simplify(box, o).mesh), 1e-6);
}

// Two spheres of equal area, one tessellated 64 times more finely than the other, to 5 %. With every
// random point on a face of its own, E_dist weighs the surface by its tessellation: the fine sphere's
// points outnumber the coarse one's 64 to 1, and collapses on the coarse sphere look almost free.
// Spread by area, the points weigh both alike, as RMS does.
TEST(Simplify, HoppeSpreadsItsRandomPointsByArea) {
  Mesh coarse = make_icosphere({.subdivisions = 1}), fine = make_icosphere({.subdivisions = 4});
  fine.positions.col(0).array() += 3.0;
  const Mesh both = concatenated(coarse, fine);
  for (const std::uint64_t seed : {1, 2, 3}) {
    SimplifyOptions o{.method = SimplifyMethod::Hoppe, .target_ratio = 0.05};
    o.seed = seed;
    const SimplifyResult by_area = simplify(both, o);
    o.hoppe_points_on_every_face = 1000;  // all per face
    const SimplifyResult per_face = simplify(both, o);
    ASSERT_EQ(by_area.faces_out, by_area.target_faces);
    ASSERT_EQ(per_face.faces_out, per_face.target_faces);
    const Comparison a = compare(both, by_area.mesh), f = compare(both, per_face.mesh);
    EXPECT_LT(a.rms, 0.5 * f.rms) << "seed " << seed;  // 0.0052-0.0054 against 0.0155-0.0169
    EXPECT_LT(a.hausdorff, 0.5 * f.hausdorff) << "seed " << seed;  // 0.036-0.039 against 0.136-0.139
  }
  SimplifyOptions bad{.method = SimplifyMethod::Hoppe};
  for (const double points : {-1.0, 1001.0, std::nan("")}) {
    bad.hoppe_points_on_every_face = points;
    EXPECT_THROW(simplify(both, bad), Error) << points;
  }
}

// A flat ring between two circles: nothing but its two curved boundaries to lose. Removing a boundary
// vertex cuts a corner off a circle and costs E_dist nothing (the points stay in the plane), so only
// the boundary samples (the paper's E_disc) keep hoppe off the boundary while interior collapses are
// free. Without them this ring was off by 0.0033 at 40 % (and the shared annulus.obj by 0.55 % of its
// diagonal at 10 %).
TEST(Simplify, HoppeHoldsOpenBoundariesToTheirCurves) {
  constexpr int kSegments = 96, kRings = 12;
  Mesh ring;
  ring.positions.resize(kSegments * (kRings + 1), 3);
  for (int i = 0; i <= kRings; ++i)
    for (int j = 0; j < kSegments; ++j) {
      const double r = 0.5 + 0.5 * i / kRings, a = 2 * std::numbers::pi * j / kSegments;
      ring.positions.row(i * kSegments + j) << r * std::cos(a), r * std::sin(a), 0.0;
    }
  ring.triangles.resize(2 * kSegments * kRings, 3);
  for (int i = 0; i < kRings; ++i)
    for (int j = 0; j < kSegments; ++j) {
      const Index a = i * kSegments + j, b = i * kSegments + (j + 1) % kSegments, c = a + kSegments, d = b + kSegments;
      ring.triangles.row(2 * (i * kSegments + j)) << a, b, d;
      ring.triangles.row(2 * (i * kSegments + j) + 1) << a, d, c;
    }
  ASSERT_EQ(inspect(ring).boundary_loops, 2);
  const SimplifyResult r = simplify(ring, {.method = SimplifyMethod::Hoppe, .target_ratio = 0.4});
  EXPECT_EQ(r.faces_out, r.target_faces);
  EXPECT_EQ(inspect(r.mesh).boundary_loops, 2);
  EXPECT_LT(compare(ring, r.mesh).hausdorff, 1e-9);  // every boundary vertex kept, in place
}

// A cylinder's rims are sharp edges between the side's long thin triangles and the caps' fans. Without
// points along them E_dist sees a rim only through the few random points near it, and a collapse that
// bevels it costs next to nothing: the farthest points were all on the rims (as on the shared
// trimesh_counter at 10 %, before random points were spread by area: Hausdorff 0.174 % without the rim
// points, 0.059 % with them). Two random points per face, all of them on every face (none left to
// spread by area, which on this cylinder puts enough near the rims by itself); the floor on the point
// count is off, as on a mesh of 25k faces or more. No fit or refit after the collapses: they mend part of a
// bevel (seed 2: the rims without points 0.00315 -> 0.00272 by the fit), which is not what this test measures.
TEST(Simplify, HoppeSamplesSharpEdgesSoThatNoCollapseBevelsThem) {
  const Mesh cylinder = make_cylinder({.radius = 1.0, .height = 0.5, .segments = 256, .stacks = 4});
  for (const std::uint64_t seed : {1, 2, 3}) {
    SimplifyOptions o{.method = SimplifyMethod::Hoppe, .target_ratio = 0.25};
    o.hoppe_points_per_face = 2;
    o.hoppe_min_points = 0;
    o.hoppe_fit_passes = 0;
    o.refit_passes = 0;  // nor the refit, which mends the bevels too (seed 3: 0.00165 without the points, 0.00168 with)
    o.hoppe_energy_from = 0;  // the energy ranks every collapse: the points are what is tested
    o.seed = seed;
    const SimplifyResult with = simplify(cylinder, o);
    o.hoppe_crease_angle_deg = 180;  // no points along sharp edges
    const SimplifyResult without = simplify(cylinder, o);
    ASSERT_EQ(with.faces_out, with.target_faces);
    ASSERT_EQ(without.faces_out, without.target_faces);
    EXPECT_LT(compare(cylinder, with.mesh).hausdorff, 0.85 * compare(cylinder, without.mesh).hausdorff) << "seed " << seed;
  }
  SimplifyOptions bad{.method = SimplifyMethod::Hoppe};
  for (const double angle : {-1.0, 181.0, std::nan("")}) {
    bad.hoppe_crease_angle_deg = angle;
    EXPECT_THROW(simplify(cylinder, bad), Error) << angle;
  }
}

TEST(Simplify, AvoidingOrRefusingInvertedFacesLeavesNoneOnAThinLens) {
  const Mesh lens = test::thin_lens();
  SimplifyOptions o;
  o.target_ratio = 0.03;
  o.inverted_faces = InvertedFaces::Allow;
  const SimplifyResult plain = simplify(lens, o);
  ASSERT_GT(count_flipped_faces(lens, plain.mesh), 0) << "the lens no longer shows the failure this test guards";
  o.inverted_faces.reset();  // quadric's default
  EXPECT_EQ(count_flipped_faces(lens, simplify(lens, o).mesh), 0);
  for (const InvertedFaces mode : {InvertedFaces::Avoid, InvertedFaces::Refuse})
    for (const SimplifyMethod method : {SimplifyMethod::Quadric, SimplifyMethod::Hoppe}) {
      SCOPED_TRACE(to_string(method) + " " + to_string(mode));
      o.method = method;
      o.inverted_faces = mode;
      const SimplifyResult r = simplify(lens, o);
      EXPECT_EQ(r.reason, StopReason::TargetReached) << r.reason_text;
      if (mode == InvertedFaces::Refuse) {
        EXPECT_FALSE(r.inverted_allowed_at);
      }
      EXPECT_EQ(count_flipped_faces(lens, r.mesh), 0);
      const MeshReport after = inspect(r.mesh);
      EXPECT_TRUE(after.manifold);
      EXPECT_EQ(after.euler_characteristic, 2);
    }
}

TEST(Simplify, RefusingInvertedFacesSaysWhenItStopsShortAndAvoidingGoesOn) {
  // Down to a tetrahedron, a lens this thin must fold a face across: refusing, the run stops short and
  // counts the edges that rule held back; avoiding, such a collapse waits until the others cost several
  // times as much, so the run goes on and says from where it let such faces be.
  const Mesh lens = test::thin_lens();
  SimplifyOptions o;
  o.target_faces = 8;
  o.inverted_faces = InvertedFaces::Refuse;
  const SimplifyResult r = simplify(lens, o);
  EXPECT_EQ(r.reason, StopReason::NoLegalCollapse);
  EXPECT_GT(r.faces_out, 8);
  EXPECT_GT(r.blocked.inverted, 0);
  EXPECT_NE(r.reason_text.find("face against the input"), std::string::npos) << r.reason_text;
  EXPECT_EQ(count_flipped_faces(lens, r.mesh), 0);
  EXPECT_FALSE(r.inverted_allowed_at);

  o.inverted_faces = InvertedFaces::Avoid;
  const SimplifyResult avoided = simplify(lens, o);
  ASSERT_TRUE(avoided.inverted_allowed_at);
  // It waits for dearer collapses, not for every other: it let one be before refusing would have stopped,
  // but only once the lens was coarse (at 3 % it leaves none; see above).
  EXPECT_GT(*avoided.inverted_allowed_at, r.faces_out);
  EXPECT_LT(*avoided.inverted_allowed_at, 0.03 * lens.num_faces());
  EXPECT_LT(avoided.faces_out, r.faces_out);
  EXPECT_EQ(avoided.reason, StopReason::TargetReached) << avoided.reason_text;
  // Only where the others cost more, not for the rest of the run: no more such faces than with no check
  // at all.
  o.inverted_faces = InvertedFaces::Allow;
  EXPECT_LE(count_flipped_faces(lens, avoided.mesh), count_flipped_faces(lens, simplify(lens, o).mesh));
  EXPECT_NE(avoided.reason_text.find("let face against the input"), std::string::npos) << avoided.reason_text;
  EXPECT_TRUE(inspect(avoided.mesh).manifold);
}

// Plates standing across a sphere's surface, like teeth in a jaw: coarse plates face against the sphere
// they cross, and refusing that until nothing else is left spends the budget on the sphere. Avoiding, a
// collapse waits only until the others cost four times as much. (Measured: Hausdorff 0.046 allowing,
// with 28 such faces; 0.065 avoiding, with 2; 0.087 refusing, as avoiding was when it waited for all.)
TEST(Simplify, AvoidingInvertedFacesWaitsForDearerCollapsesNotForAll) {
  Mesh jaw = make_icosphere({.subdivisions = 4});
  const int plates = 24;
  for (int i = 0; i < plates; ++i) {
    Mesh plate = make_icosphere({.subdivisions = 2});
    plate.positions.col(0) *= 0.2, plate.positions.col(1) *= 0.02, plate.positions.col(2) *= 0.2;
    const Eigen::Matrix3d turn = Eigen::AngleAxisd(2 * std::numbers::pi * i / plates, Eigen::Vector3d::UnitZ()).matrix();
    for (Index v = 0; v < plate.num_vertices(); ++v)
      plate.positions.row(v) = (turn * (plate.positions.row(v).transpose() + Eigen::Vector3d(1, 0, 0))).transpose();
    Mesh both;
    both.positions.resize(jaw.num_vertices() + plate.num_vertices(), 3);
    both.positions << jaw.positions, plate.positions;
    both.triangles.resize(jaw.num_faces() + plate.num_faces(), 3);
    both.triangles << jaw.triangles, plate.triangles.array() + jaw.num_vertices();
    jaw = std::move(both);
  }
  SimplifyOptions o;
  o.target_faces = 300;
  o.refit_passes = 0;  // the collapses' waiting is the subject here (the refit's own check: test_refit.cpp)
  auto run = [&](InvertedFaces mode) {
    o.inverted_faces = mode;
    return simplify(jaw, o);
  };
  const SimplifyResult allowed = run(InvertedFaces::Allow), avoided = run(InvertedFaces::Avoid),
                       refused = run(InvertedFaces::Refuse);
  const Index flipped_allowed = count_flipped_faces(jaw, allowed.mesh);
  ASSERT_GT(flipped_allowed, 10) << "the plates no longer show the failure this test guards";
  EXPECT_EQ(count_flipped_faces(jaw, refused.mesh), 0);
  EXPECT_LT(4 * count_flipped_faces(jaw, avoided.mesh), flipped_allowed);
  EXPECT_EQ(avoided.faces_out, 300);
  EXPECT_LT(compare(jaw, avoided.mesh).hausdorff, 0.9 * compare(jaw, refused.mesh).hausdorff);
  EXPECT_TRUE(inspect(avoided.mesh).manifold);
}

TEST(Simplify, InvertedFacesModesHaveNames) {
  for (const InvertedFaces mode : {InvertedFaces::Allow, InvertedFaces::Avoid, InvertedFaces::Refuse})
    EXPECT_EQ(parse_inverted_faces(to_string(mode)), mode);
  EXPECT_FALSE(parse_inverted_faces("never"));
}

TEST(Simplify, IsDeterministic) {
  const Mesh m = test::bumpy_sphere(4, 0.02);
  SimplifyOptions o;
  o.target_ratio = 0.05;
  EXPECT_EQ(simplify(m, o).mesh.positions, simplify(m, o).mesh.positions);
}

}  // namespace
}  // namespace lodkit

namespace lodkit {
namespace {

// On a flat UV-mapped grid the right UV of any point is a linear function of its position.
double worst_uv_error(const Mesh& m) {
  double worst = 0;
  for (Index v = 0; v < m.num_vertices(); ++v) {
    const Eigen::RowVector2d expected(m.positions(v, 0) + 0.5, m.positions(v, 1) + 0.5);
    worst = std::max(worst, (m.attributes.uvs.row(v) - expected).norm());
  }
  return worst;
}

TEST(SimplifyAttributes, WeightedUvsFollowTheMovedVertices) {
  const Mesh grid = make_grid({.divisions_x = 16, .divisions_y = 16, .uvs = true});
  ASSERT_LT(worst_uv_error(grid), 1e-12);
  SimplifyOptions plain;
  plain.target_ratio = 0.1;
  plain.fit_attributes = false;
  const double without = worst_uv_error(simplify(grid, plain).mesh);
  SimplifyOptions weighted = plain;
  weighted.attribute_weights.uvs = 1.0;
  const SimplifyResult r = simplify(grid, weighted);
  EXPECT_LT(worst_uv_error(r.mesh), 1e-9);
  EXPECT_GT(without, 1e-3) << "the geometric-only run keeps stale UVs where vertices moved";
  // The attribute fit at the end (on by default) sets them right again, without weights.
  SimplifyOptions fitted = plain;
  fitted.fit_attributes = true;
  const SimplifyResult f = simplify(grid, fitted);
  ASSERT_TRUE(f.attribute_fit && f.attribute_fit->uvs);
  EXPECT_LT(worst_uv_error(f.mesh), 1e-5);
  EXPECT_EQ(r.faces_out, static_cast<Index>(std::llround(0.1 * grid.num_faces())));
}

TEST(SimplifyAttributes, WeightedColoursStayInRangeAndTheBorderStaysSharp) {
  // A bumpy sphere painted half red, half blue. With colour weights the merged wedges take optimised
  // colours: they must stay valid colours, and the red/blue border must stay a thin line of mixed
  // vertices rather than a smear.
  Mesh m = test::bumpy_sphere(4, 0.005);
  m.attributes.colours.resize(m.num_vertices(), 4);
  for (Index v = 0; v < m.num_vertices(); ++v)
    m.attributes.colours.row(v) = m.positions(v, 2) > 0 ? Eigen::RowVector4f(1, 0, 0, 1) : Eigen::RowVector4f(0, 0, 1, 1);
  auto mixed = [](const Mesh& out) {
    Index n = 0;
    for (Index v = 0; v < out.num_vertices(); ++v)
      n += out.attributes.colours(v, 0) > 0.05f && out.attributes.colours(v, 0) < 0.95f;
    return n;
  };
  SimplifyOptions o;
  o.target_ratio = 0.1;
  o.attribute_weights.colours = 1.0;
  const Mesh weighted = simplify(m, o).mesh;
  validate(weighted);
  EXPECT_TRUE(inspect(weighted).closed);
  for (Index v = 0; v < weighted.num_vertices(); ++v)
    for (int c = 0; c < 4; ++c) EXPECT_TRUE(weighted.attributes.colours(v, c) >= 0 && weighted.attributes.colours(v, c) <= 1);
  EXPECT_LE(mixed(weighted), weighted.num_vertices() / 4);
}

TEST(SimplifyAttributes, WeightedNormalsKeepTheShadingThatTheGeometryCannotSee) {
  // A flat grid whose normals lean outwards inside a disc (a shading bump with no bump): geometry
  // alone cannot tell its collapses apart, so without a normal weight the lean is smeared across the
  // grid (RMS 4.1 degrees with quadric, 4.6 with hoppe). With the weight, compare()'s shading-normal
  // deviation comes out under a tenth of that (0.08 and 0.06 degrees measured), for both costs.
  Mesh grid = make_grid({.divisions_x = 32, .divisions_y = 32});
  grid.attributes.normals.resize(grid.num_vertices(), 3);
  for (Index v = 0; v < grid.num_vertices(); ++v) {
    const Eigen::Vector2d at(grid.positions(v, 0), grid.positions(v, 1));
    const Eigen::Vector2d lean = at.norm() < 0.25 ? at : Eigen::Vector2d::Zero();
    grid.attributes.normals.row(v) = Eigen::Vector3d(lean.x(), lean.y(), 0.5).normalized();
  }
  for (const SimplifyMethod method : {SimplifyMethod::Quadric, SimplifyMethod::Hoppe}) {
    SimplifyOptions o{.method = method, .target_ratio = 0.1};
    const SimplifyResult plain = simplify(grid, o);
    o.attribute_weights.normals = 0.1;
    const SimplifyResult weighted = simplify(grid, o);
    EXPECT_EQ(weighted.reason, StopReason::TargetReached);
    const double without = *compare(grid, plain.mesh).shading_rms_deg, with = *compare(grid, weighted.mesh).shading_rms_deg;
    EXPECT_LT(with, 0.1 * without) << to_string(method) << ": " << with << " against " << without;
    EXPECT_TRUE(inspect(weighted.mesh).oriented);
  }
}

}  // namespace
}  // namespace lodkit
