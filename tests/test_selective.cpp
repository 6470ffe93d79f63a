// Selective refinement: any dependency-closed set of splits gives a valid mesh with the input's
// topology, prefixes give the uniform levels exactly, the error bound holds, and a viewer's mesh is
// fine near the eye, coarse far away and out of view.
#include <gtest/gtest.h>
#include <lodkit/error.h>
#include <lodkit/inspect.h>
#include <lodkit/metrics.h>
#include <lodkit/pm_io.h>
#include <lodkit/primitives.h>
#include <lodkit/progressive.h>
#include <lodkit/terrain.h>

#include <fmt/format.h>
#include <numbers>
#include <random>

#include "core/geometry.h"
#include "test_util.h"

namespace lodkit {
namespace {

void expect_identical(const Mesh& a, const Mesh& b, const std::string& what) { EXPECT_EQ(test::difference(a, b), "") << what; }

Mesh small_terrain(int levels = 5) {
  TerrainOptions o;
  o.levels = levels;
  o.colour = true;
  return generate_terrain(make_terrain_base(TerrainBase::Grid), o).mesh;
}

std::vector<Mesh> inputs() { return {test::bumpy_sphere(3, 0.05), test::seamed_uv_sphere(), make_grid({}), small_terrain(4)}; }

TEST(SelectiveRefinement, NoSplitsGiveTheBaseAndEverySplitTheFinestLevel) {
  for (const Mesh& input : inputs()) {
    const ProgressiveMesh pm = build_progressive_mesh(input);
    const SelectiveRefiner refiner(pm);
    const std::size_t n = pm.splits.size();
    ASSERT_GT(n, 10u);
    expect_identical(refiner.refine(std::vector<char>(n, 0)).extracted.mesh, extract_level(pm, 0, VertexOrder::Stream).mesh, "none");
    const SelectiveLevel all = refiner.refine(std::vector<char>(n, 1));
    expect_identical(all.extracted.mesh, extract_level(pm, pm.max_level(), VertexOrder::Stream).mesh, "all");
    EXPECT_EQ(all.splits_applied, pm.max_level());
    EXPECT_EQ(all.error_bound, 0.0);
    // Asking for the last split alone asks for every split its point's neighbourhood ever saw.
    std::vector<char> last(n, 0);
    last.back() = 1;
    EXPECT_GT(refiner.refine(last).splits_applied, 1);
  }
}

TEST(SelectiveRefinement, PrefixesGiveTheUniformLevelsExactly) {
  for (const Mesh& input : inputs()) {
    const ProgressiveMesh pm = build_progressive_mesh(input);
    const SelectiveRefiner refiner(pm);
    for (Index level : {Index(1), pm.max_level() / 3, pm.max_level() / 2, pm.max_level() - 1}) {
      std::vector<char> wanted(pm.splits.size(), 0);
      std::fill(wanted.begin(), wanted.begin() + level, 1);
      const SelectiveLevel s = refiner.refine(wanted);
      EXPECT_EQ(s.splits_applied, level);  // a prefix is closed: dependencies are earlier
      expect_identical(s.extracted.mesh, extract_level(pm, level, VertexOrder::Stream).mesh, fmt::format("level {}", level));
      EXPECT_LE(s.error_bound, pm.level_error[static_cast<std::size_t>(level)] * (1 + 1e-12));
    }
  }
}

TEST(SelectiveRefinement, EveryClosedSetGivesAValidMeshWithTheInputsTopology) {
  std::mt19937 rng(11);
  for (const Mesh& input : inputs()) {
    const ProgressiveMesh pm = build_progressive_mesh(input);
    const SelectiveRefiner refiner(pm);
    const std::size_t n = pm.splits.size();
    for (std::size_t j = 0; j < n; ++j)
      for (Index d : refiner.dependencies(static_cast<Index>(j))) ASSERT_LT(d, static_cast<Index>(j));
    const MeshReport finest = inspect(extract_level(pm, pm.max_level(), VertexOrder::Stream).mesh);
    for (double density : {0.001, 0.01, 0.05, 0.2}) {
      for (int trial = 0; trial < 5; ++trial) {
        std::bernoulli_distribution pick(density);
        std::vector<char> wanted(n);
        for (char& w : wanted) w = pick(rng);
        const SelectiveLevel s = refiner.refine(wanted);
        const Mesh& m = s.extracted.mesh;
        // The faces are the base's and those the closed set's splits open.
        std::vector<char> closed = wanted;
        for (std::size_t j = n; j-- > 0;)
          if (closed[j])
            for (Index d : refiner.dependencies(static_cast<Index>(j))) closed[static_cast<std::size_t>(d)] = 1;
        Index faces = pm.base_faces, applied = 0;
        for (std::size_t j = 0; j < n; ++j)
          if (closed[j]) faces += pm.splits[j].num_faces, ++applied;
        EXPECT_EQ(s.splits_applied, applied);
        EXPECT_EQ(m.num_faces(), faces);
        for (Index f = 0; f < m.num_faces(); ++f)
          ASSERT_TRUE(m.triangles(f, 0) != m.triangles(f, 1) && m.triangles(f, 1) != m.triangles(f, 2) &&
                      m.triangles(f, 0) != m.triangles(f, 2));
        const MeshReport r = inspect(m);
        const std::string what = fmt::format("density {}, trial {}: {} of {} splits", density, trial, s.splits_applied, n);
        EXPECT_EQ(r.non_manifold_edges, 0) << what;
        EXPECT_EQ(r.non_manifold_vertices, 0) << what;
        EXPECT_EQ(r.inconsistently_oriented_edges, 0) << what;
        EXPECT_EQ(r.euler_characteristic, finest.euler_characteristic) << what;
        EXPECT_EQ(r.boundary_loops, finest.boundary_loops) << what;
        EXPECT_EQ(r.components, finest.components) << what;
        EXPECT_EQ(r.unreferenced_vertices, 0) << what;
      }
    }
  }
}

TEST(SelectiveRefinement, VerticesNameTheirInputVertexWhenTheStreamKnowsIt) {
  // Built in memory, a stream knows the input's numbering: each vertex of a selective mesh (and of a
  // level in stream order) names the input vertex it stands for, as simplify() does. With every split
  // applied, that vertex is where the input's is.
  const Mesh input = test::seamed_uv_sphere();
  const ProgressiveMesh pm = build_progressive_mesh(input);
  ASSERT_TRUE(pm.knows_input_order());
  const SelectiveRefiner refiner(pm);
  std::vector<char> some(pm.splits.size(), 0);
  for (std::size_t j = 0; j < some.size(); j += 5) some[j] = 1;
  for (const ExtractedLevel& e : {refiner.refine(some).extracted, refiner.refine(std::vector<char>(pm.splits.size(), 1)).extracted,
                                  extract_level(pm, pm.max_level() / 2, VertexOrder::Stream)}) {
    ASSERT_EQ(e.vertex_origin.size(), static_cast<std::size_t>(e.mesh.num_vertices()));
    for (std::size_t v = 0; v < e.vertex_origin.size(); ++v)
      ASSERT_EQ(e.vertex_origin[v], pm.wedge_input[static_cast<std::size_t>(e.vertex_wedge[v])]);
  }
  const ExtractedLevel all = refiner.refine(std::vector<char>(pm.splits.size(), 1)).extracted;
  for (Index v = 0; v < all.mesh.num_vertices(); ++v)
    ASSERT_EQ(all.mesh.positions.row(v), input.positions.row(all.vertex_origin[static_cast<std::size_t>(v)])) << v;
  // A stream without the numbering (quantised, not --keep-order): the wedge, as documented.
  PmWriteOptions w;
  w.position_bits = 14;
  const ProgressiveMesh read = read_pm_from_memory(write_pm_to_memory(pm, w), "q.pm").pm;
  ASSERT_FALSE(read.knows_input_order());
  const ExtractedLevel q = SelectiveRefiner(read).refine(some).extracted;
  EXPECT_EQ(q.vertex_origin, q.vertex_wedge);
}

TEST(SelectiveRefinement, TheErrorBoundHoldsAgainstTheFinestLevel) {
  std::mt19937 rng(5);
  for (const Mesh& input : {test::bumpy_sphere(3, 0.08), small_terrain(5)}) {
    const ProgressiveMesh pm = build_progressive_mesh(input);
    const SelectiveRefiner refiner(pm);
    const ExtractedLevel finest_level = extract_level(pm, pm.max_level(), VertexOrder::Stream);
    const Mesh& finest = finest_level.mesh;
    for (double density : {0.002, 0.02, 0.1}) {
      std::bernoulli_distribution pick(density);
      std::vector<char> wanted(pm.splits.size());
      for (char& w : wanted) w = pick(rng);
      const SelectiveLevel s = refiner.refine(wanted);
      const Comparison c = compare(finest, s.extracted.mesh);
      EXPECT_GT(s.error_bound, 0.0);
      EXPECT_LE(c.hausdorff, s.error_bound * (1 + 1e-9)) << "density " << density;
      // What the bound bounds: each finest vertex's distance to its ancestor in the selective mesh.
      std::vector<Index> row_of(pm.wedge_point.size(), -1);
      const ExtractedLevel& e = s.extracted;
      for (std::size_t r = 0; r < e.vertex_wedge.size(); ++r) row_of[static_cast<std::size_t>(e.vertex_wedge[r])] = static_cast<Index>(r);
      double farthest = 0;
      for (Index v = 0; v < finest.num_vertices(); ++v) {
        Index w = finest_level.vertex_wedge[static_cast<std::size_t>(v)];
        while (row_of[static_cast<std::size_t>(w)] < 0) w = pm.wedge_parent[static_cast<std::size_t>(w)];
        farthest = std::max(farthest, (finest.positions.row(v) - e.mesh.positions.row(row_of[static_cast<std::size_t>(w)])).norm());
      }
      EXPECT_LE(farthest, s.error_bound * (1 + 1e-9)) << "density " << density;
      EXPECT_GT(farthest, 0.5 * s.error_bound) << "density " << density;  // and not far looser
    }
  }
}

TEST(SelectiveRefinement, AViewerGetsDetailNearTheEyeOnly) {
  // A terrain seen from just above one corner, looking across it, in a small viewport (so that its
  // 64 x 64 grid spans a viewer's range of detail).
  const ProgressiveMesh pm = build_progressive_mesh(small_terrain(6));
  const SelectiveRefiner refiner(pm);
  Viewpoint view;
  view.eye = {-0.55, -0.55, 0.05};
  view.look_at = {0.5, 0.5, 0.0};
  view.viewport_pixels = 100;
  view.pixel_error = 2.0;
  const SelectiveLevel s = refiner.refine_for_view(view);
  const Mesh& m = s.extracted.mesh;
  EXPECT_LE(s.max_pixels, view.pixel_error);
  EXPECT_GT(s.max_pixels, 0.5 * view.pixel_error);  // not far finer than asked
  EXPECT_GT(m.num_faces(), pm.base_faces);
  EXPECT_LT(m.num_faces(), pm.num_faces(pm.max_level()));
  // Vertices in the quarter nearest the eye against the farthest quarter.
  int near = 0, far = 0;
  for (Index v = 0; v < m.num_vertices(); ++v) {
    const double x = m.positions(v, 0), y = m.positions(v, 1);
    near += x < -0.25 && y < -0.25;
    far += x > 0.25 && y > 0.25;
  }
  EXPECT_GT(near, 3 * far / 2) << near << " near, " << far << " far";
  // The eye is inside the bounding sphere: a uniform level within the budget everywhere is the finest.
  const ScreenSpaceBudget uniform{view.pixel_error, (pm.bounds.center() - view.eye).norm(), view.fov_degrees, view.viewport_pixels};
  EXPECT_EQ(level_for_view(pm, uniform), pm.max_level());

  // Looking away from above, nothing is in view: the base mesh, every region outside.
  Viewpoint away = view;
  away.eye = {0, 0, 2};
  away.look_at = {0, 0, 3};
  const SelectiveLevel a = refiner.refine_for_view(away);
  EXPECT_EQ(a.splits_applied, 0);
  EXPECT_GT(a.regions_outside, 0);
  EXPECT_EQ(a.max_pixels, 0.0);
  // Without culling, the same eye refines what lies behind it.
  away.cull = false;
  EXPECT_GT(refiner.refine_for_view(away).splits_applied, 0);
  // From far away with a generous budget the base is enough; a budget of zero pixels refines all in view.
  Viewpoint far_view = view;
  far_view.eye = {0, 0, 1000};
  far_view.look_at = {0, 0, 0};
  far_view.pixel_error = 5;
  EXPECT_EQ(refiner.refine_for_view(far_view).splits_applied, 0);
  far_view.pixel_error = 0;
  EXPECT_EQ(refiner.refine_for_view(far_view).splits_applied, pm.max_level());
}

TEST(SelectiveRefinement, TheMeasuredDeviationIsWhatTheViewerSees) {
  // A flat grid down to its two triangles deviates nowhere: a view by deviation needs only the base.
  {
    ProgressiveOptions two_faces;
    two_faces.base_faces = 2;
    const ProgressiveMesh pm = build_progressive_mesh(make_grid({}), two_faces);
    ASSERT_EQ(pm.base_faces, 2);
    const SelectiveRefiner refiner(pm);
    for (Index j = 0; j < pm.max_level(); ++j) EXPECT_LT(refiner.region_deviation(j), 1e-12);
    Viewpoint view;
    view.eye = {0.4, 0.4, 0.05};
    view.pixel_error = 0.01;
    const SelectiveLevel s = refiner.refine_for_view(view, LevelErrorKind::Measured);
    EXPECT_EQ(s.splits_applied, 0);
    EXPECT_LT(compare(extract_level(pm, pm.max_level()).mesh, s.extracted.mesh).hausdorff, 1e-12);
    EXPECT_EQ(refiner.refine_for_view(view).splits_applied, pm.max_level());  // the bound sees edges
  }
  // On a bumpy sphere, a terrain and a cone (whose apex and base centre split among hundreds of faces,
  // where the deviation is their points' displacement), the distance compare() measures is close to
  // the deviation, below the bound, and the view by deviation is coarser than by the bound (far coarser
  // on the sphere and the terrain, whose bounds grow sideways).
  ConeOptions fan;
  fan.segments = 300;
  for (const Mesh& input : {test::bumpy_sphere(4, 0.05), small_terrain(6), make_cone(fan)}) {
    const bool cone = input.num_faces() == 2 * fan.segments;
    const ProgressiveMesh pm = build_progressive_mesh(input);
    const SelectiveRefiner refiner(pm);
    for (Index j = 0; j < pm.max_level(); ++j) ASSERT_LE(refiner.region_deviation(j), refiner.region_error(j));
    const Mesh finest = extract_level(pm, pm.max_level(), VertexOrder::Stream).mesh;
    Viewpoint view;
    view.eye = pm.bounds.center() + Eigen::Vector3d(0.2, 0.3, 1.0).normalized() * 2 * bounding_radius(pm);
    view.look_at = pm.bounds.center();
    view.viewport_pixels = 200;
    const SelectiveLevel by_bound = refiner.refine_for_view(view), by_deviation = refiner.refine_for_view(view, LevelErrorKind::Measured);
    EXPECT_LT((cone ? 1 : 3) * by_deviation.extracted.mesh.num_faces(), (cone ? 1 : 2) * by_bound.extracted.mesh.num_faces());
    EXPECT_LE(by_deviation.max_pixels, view.pixel_error);
    const double measured = compare(finest, by_deviation.extracted.mesh).hausdorff;
    EXPECT_LT(measured, 2 * by_deviation.deviation);
    EXPECT_GT(measured, 0.5 * by_deviation.deviation);
    EXPECT_LT(measured, by_deviation.error_bound);
  }
}

TEST(SelectiveRefinement, NormalConesHoldBothCones) {
  std::mt19937 rng(3);
  std::normal_distribution<double> gauss;
  std::uniform_real_distribution<double> angle(0.0, 1.5);
  auto random_axis = [&] { return Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng)).normalized(); };
  for (int trial = 0; trial < 1000; ++trial) {
    const detail::NormalCone a{random_axis(), angle(rng)}, b{random_axis(), angle(rng)};
    const detail::NormalCone c = detail::enclosing_cone(a, b);
    ASSERT_NEAR(c.axis.norm(), 1.0, 1e-12);
    // Each input cone's axis and its farthest direction from c's axis lie within c.
    for (const detail::NormalCone& in : {a, b}) {
      EXPECT_LE(detail::direction_angle(c.axis, in.axis) + in.half_angle, c.half_angle + 1e-12) << trial;
    }
    EXPECT_LE(c.half_angle, std::numbers::pi);
  }
}

TEST(SelectiveRefinement, RegionsFacingAwayStayCoarseWhenAsked) {
  // A closed bumpy sphere seen from +z: culling back faces thins the far hemisphere only.
  const ProgressiveMesh pm = build_progressive_mesh(test::bumpy_sphere(4, 0.03));
  const SelectiveRefiner refiner(pm);
  Viewpoint view;
  view.eye = {0, 0, 3};
  view.look_at = {0, 0, 0};
  view.viewport_pixels = 400;
  const SelectiveLevel all = refiner.refine_for_view(view, LevelErrorKind::Measured);
  view.cull_backfaces = true;
  const SelectiveLevel front = refiner.refine_for_view(view, LevelErrorKind::Measured);
  EXPECT_EQ(all.regions_facing_away, 0);
  EXPECT_GT(front.regions_facing_away, 0);
  EXPECT_LT(front.extracted.mesh.num_faces(), all.extracted.mesh.num_faces());
  EXPECT_EQ(inspect(front.extracted.mesh).euler_characteristic, 2);
  auto count = [](const Mesh& m, double from, double to) {
    int n = 0;
    for (Index v = 0; v < m.num_vertices(); ++v) n += m.positions(v, 2) >= from && m.positions(v, 2) < to;
    return n;
  };
  const Mesh &a = all.extracted.mesh, &f = front.extracted.mesh;
  EXPECT_GE(count(f, 0.3, 2), count(a, 0.3, 2) * 95 / 100);  // the side facing the eye as before
  EXPECT_LT(count(f, -2, -0.3), count(a, -2, -0.3) * 8 / 10) << count(f, -2, -0.3) << " of " << count(a, -2, -0.3)
      << "; facing the eye " << count(f, 0.3, 2) << " of " << count(a, 0.3, 2);  // the far side coarser
}

TEST(SelectiveRefinement, AStreamReadInPartCountsItsLastLevelsError) {
  // The first half of the splits, as a prefix read of the stream: every split applied is still the
  // last level's error away from the input, and the bound says so.
  const Mesh input = test::bumpy_sphere(3, 0.08);
  const ProgressiveMesh pm = build_progressive_mesh(input);
  PmReadOptions half;
  half.max_faces = pm.num_faces(pm.max_level() / 2);
  const ProgressiveMesh prefix = read_pm_from_memory(write_pm_to_memory(pm), "half.pm", half).pm;
  ASSERT_LT(prefix.max_level(), pm.max_level());
  const SelectiveRefiner refiner(prefix);
  const SelectiveLevel all = refiner.refine(std::vector<char>(prefix.splits.size(), 1));
  EXPECT_EQ(all.error_bound, prefix.level_error.back());
  EXPECT_GT(all.error_bound, 0.0);
  EXPECT_LE(compare(input, all.extracted.mesh).hausdorff, all.error_bound);
  for (Index j = 0; j < prefix.max_level(); ++j) EXPECT_GE(refiner.region_error(j), prefix.level_error.back());
  // A viewer close by needs more than the prefix holds, and is told so.
  Viewpoint near;
  near.eye = {0, 0, 1.5};
  near.pixel_error = 0.5;
  const SelectiveLevel seen = refiner.refine_for_view(near, LevelErrorKind::Bound);
  EXPECT_EQ(seen.splits_applied, prefix.max_level());
  EXPECT_GT(seen.max_pixels, near.pixel_error);
}

TEST(SelectiveRefinement, BadViewsAndRequestsAreClearErrors) {
  const ProgressiveMesh pm = build_progressive_mesh(test::bumpy_sphere(2, 0.05));
  const SelectiveRefiner refiner(pm);
  auto bad = [&](auto change, const std::string& words) {
    Viewpoint v;
    change(v);
    try {
      refiner.refine_for_view(v);
      ADD_FAILURE() << "accepted: " << words;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
  };
  bad([](Viewpoint& v) { v.eye.x() = NAN; }, "must be finite");
  bad([](Viewpoint& v) { v.look_at = v.eye; }, "must differ from the eye");
  bad([](Viewpoint& v) { v.fov_degrees = 180; }, "field of view");
  bad([](Viewpoint& v) { v.viewport_pixels = 0; }, "viewport height");
  bad([](Viewpoint& v) { v.aspect = -1; }, "aspect ratio");
  bad([](Viewpoint& v) { v.pixel_error = -1; }, "pixel error");
  EXPECT_THROW(refiner.refine(std::vector<char>(3, 1)), Error);
  SelectiveMesh mesh(refiner);
  EXPECT_THROW(mesh.go_to(std::vector<char>(3, 1)), Error);
  Viewpoint nowhere;
  nowhere.look_at = nowhere.eye;
  EXPECT_THROW(mesh.adapt(nowhere), Error);
  EXPECT_EQ(std::count(mesh.applied().begin(), mesh.applied().end(), 1), 0);  // a refused view changes nothing
}

TEST(SelectiveRefinement, TheHierarchyFindsEveryRegionAViewNeeds) {
  // splits_for_view() looks only where a region below a split can need refining; it must find what
  // testing every region finds, from eyes near and far, inside and out, any way round.
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> coordinate(-3, 3), pixels(0.2, 8);
  for (const Mesh& input : {test::bumpy_sphere(4, 0.04), small_terrain(5), test::seamed_uv_sphere()}) {
    const ProgressiveMesh pm = build_progressive_mesh(input);
    const SelectiveRefiner refiner(pm);
    Index found = 0;
    for (int trial = 0; trial < 60; ++trial) {
      Viewpoint view;
      view.eye = {coordinate(rng), coordinate(rng), coordinate(rng)};
      view.eye *= trial % 4 == 0 ? 0.2 : 1.0;  // some inside
      view.look_at = trial % 3 == 0 ? Eigen::Vector3d(coordinate(rng), coordinate(rng), coordinate(rng)) : pm.bounds.center();
      view.pixel_error = pixels(rng);
      view.viewport_pixels = 800;
      view.cull = trial % 5 != 4;
      view.cull_backfaces = trial % 2 == 1;
      const LevelErrorKind kind = trial % 3 == 1 ? LevelErrorKind::Bound : LevelErrorKind::Measured;
      std::vector<char> every = refiner.regions_needing_refinement(view, kind);
      for (std::size_t j = every.size(); j-- > 0;)
        if (every[j])
          for (Index d : refiner.dependencies(static_cast<Index>(j))) every[static_cast<std::size_t>(d)] = 1;
      const std::vector<char> walked = refiner.splits_for_view(view, kind);
      ASSERT_EQ(walked, every) << "trial " << trial;
      found += std::count(walked.begin(), walked.end(), 1);
    }
    EXPECT_GT(found, 0);
  }
}

// The same selective level from a kept mesh as from the base: mesh, wedges and errors.
void expect_same_level(const SelectiveLevel& kept, const SelectiveLevel& fresh, const std::string& what) {
  expect_identical(kept.extracted.mesh, fresh.extracted.mesh, what);
  EXPECT_EQ(kept.extracted.vertex_wedge, fresh.extracted.vertex_wedge) << what;
  EXPECT_EQ(kept.splits_applied, fresh.splits_applied) << what;
  EXPECT_EQ(kept.error_bound, fresh.error_bound) << what;
  EXPECT_EQ(kept.deviation, fresh.deviation) << what;
  EXPECT_EQ(kept.max_pixels, fresh.max_pixels) << what;
  EXPECT_EQ(kept.regions_outside, fresh.regions_outside) << what;
  EXPECT_EQ(kept.regions_facing_away, fresh.regions_facing_away) << what;
  EXPECT_EQ(kept.splits_unfolding, fresh.splits_unfolding) << what;
}

// Faces that fold in a kept mesh's state: shown, and facing against their own face in the input (the
// finest level), where that has area.
struct FoldCount {
  std::vector<Eigen::Vector3d> input_normal;  // per face of the stream

  FoldCount(const ProgressiveMesh& pm, const SelectiveRefiner& refiner) {
    SelectiveMesh finest(refiner);
    finest.go_to(std::vector<char>(pm.splits.size(), 1));
    for (Index f = 0; f < Index(pm.face_corners.size()); ++f) input_normal.push_back(normal(finest, f));
  }
  static Eigen::Vector3d normal(const SelectiveMesh& m, Index f) {
    const Eigen::Vector3d &a = m.wedge_position(m.face_corner(f, 0)), &b = m.wedge_position(m.face_corner(f, 1)),
                          &c = m.wedge_position(m.face_corner(f, 2));
    return (b - a).cross(c - a);
  }
  Index operator()(const SelectiveMesh& m) const {
    Index folded = 0;
    for (Index f = 0; f < Index(input_normal.size()); ++f)
      folded += m.face_shown(f) && input_normal[std::size_t(f)].squaredNorm() > 0 && !(normal(m, f).dot(input_normal[std::size_t(f)]) > 0);
    return folded;
  }
};

Mesh fractal_pyramid() {
  TerrainOptions o;
  o.levels = 5;
  return generate_terrain(make_terrain_base(TerrainBase::Pyramid), o).mesh;
}

// Eyes around the centre at `distance` bounding radii, from below, level and above.
std::vector<Viewpoint> views_around(const ProgressiveMesh& pm, double distance) {
  std::vector<Viewpoint> out;
  for (int azimuth = 0; azimuth < 360; azimuth += 45)
    for (int elevation : {-60, 0, 60}) {
      const double a = azimuth * std::numbers::pi / 180, e = elevation * std::numbers::pi / 180;
      Viewpoint& v = out.emplace_back();
      v.look_at = pm.bounds.center();
      v.eye = v.look_at + distance * bounding_radius(pm) * Eigen::Vector3d(std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e));
      v.viewport_pixels = 400;
    }
  return out;
}

TEST(SelectiveRefinement, ViewsRefineWhereMixedLevelsFold) {
  // A split's neighbours can be coarser or finer than in its uniform level, so a face can fold where no
  // uniform level's does: close views of a fractal pyramid fold faces against their own input faces,
  // and of a very bumpy sphere against the input faces nearest them (compare's count). Unfolded, no
  // face does either; the view's own splits are all applied, with those that unfold counted, and only
  // views that folded need any.
  for (const Mesh& shape : {fractal_pyramid(), test::bumpy_sphere(4, 0.15)}) {
    const ProgressiveMesh pm = build_progressive_mesh(shape);
    const SelectiveRefiner refiner(pm);
    const FoldCount folds(pm, refiner);
    const Mesh input = extract_level(pm, pm.max_level()).mesh;
    SelectiveMesh raw(refiner), unfolded(refiner);
    for (std::size_t n = 0; n <= pm.splits.size(); n += pm.splits.size() / 8) {  // the uniform levels do not fold
      std::vector<char> prefix(pm.splits.size(), 0);
      std::fill_n(prefix.begin(), n, 1);
      raw.go_to(prefix);
      ASSERT_EQ(folds(raw), 0) << "level " << n;
    }
    int folding = 0, views = 0;
    for (const LevelErrorKind kind : {LevelErrorKind::Bound, LevelErrorKind::Measured})
      for (double distance : {0.6, 1.2})
        for (Viewpoint view : views_around(pm, distance)) {
          const std::string what = fmt::format("{} faces, view {}", shape.num_faces(), views++);
          view.pixel_error = 0.5;
          view.unfold = false;
          const SelectiveLevel as_is = raw.adapt(view, kind);
          const Index folded = folds(raw), against = count_flipped_faces(input, as_is.extracted.mesh);
          ASSERT_EQ(raw.applied(), refiner.splits_for_view(view, kind)) << what;
          EXPECT_EQ(as_is.splits_unfolding, 0) << what;
          view.unfold = true;
          const SelectiveLevel s = unfolded.adapt(view, kind);
          expect_same_level(s, refiner.refine_for_view(view, kind), what);
          EXPECT_EQ(folds(unfolded), 0) << what << ": " << folded << " folded";
          // (Faces as a uniform level has them are left so; none of those shown here faces against.)
          EXPECT_EQ(count_flipped_faces(input, s.extracted.mesh), 0) << what << ": " << against << " against";
          Index more = 0;
          for (std::size_t j = 0; j < pm.splits.size(); ++j) {
            ASSERT_TRUE(unfolded.applied()[j] || !raw.applied()[j]) << what;
            more += unfolded.applied()[j] && !raw.applied()[j];
            if (unfolded.applied()[j]) {
              for (Index d : refiner.dependencies(Index(j))) ASSERT_TRUE(unfolded.applied()[std::size_t(d)]) << what;
            }
          }
          EXPECT_EQ(s.splits_unfolding, more) << what;
          EXPECT_EQ(s.splits_applied, as_is.splits_applied + more) << what;
          EXPECT_EQ(more > 0, folded + against > 0) << what;
          folding += folded + against > 0;
        }
    EXPECT_GE(folding, 4) << "of " << views << " views of " << shape.num_faces() << " faces";  // the test needs views that fold
  }
}

TEST(SelectiveMesh, EveryStateIsTheSetsMeshWhateverCameBefore) {
  // Random closed sets one after another, sparse and dense, every split and none: each state equals
  // refine() of its set from the base, bit for bit, and says how many splits it applied and undid.
  std::mt19937 rng(23);
  for (const Mesh& input : inputs()) {
    const ProgressiveMesh pm = build_progressive_mesh(input);
    const SelectiveRefiner refiner(pm);
    const std::size_t n = pm.splits.size();
    SelectiveMesh mesh(refiner);
    std::vector<char> before(n, 0);
    for (int step = 0; step < 24; ++step) {
      std::vector<char> wanted(n, step % 8 == 7 ? 1 : 0);
      if (step % 8 < 6) {
        std::bernoulli_distribution pick(std::array{0.001, 0.01, 0.05, 0.2, 0.5, 0.02}[step % 8]);
        for (char& w : wanted) w = pick(rng);
      }
      const SelectiveLevel kept = mesh.go_to(wanted), fresh = refiner.refine(wanted);
      const std::string what = fmt::format("step {}: {} of {} splits", step, fresh.splits_applied, n);
      expect_same_level(kept, fresh, what);
      Index refined = 0, coarsened = 0;
      for (std::size_t j = 0; j < n; ++j) {
        refined += !before[j] && mesh.applied()[j];
        coarsened += before[j] && !mesh.applied()[j];
      }
      EXPECT_EQ(kept.splits_refined, refined) << what;
      EXPECT_EQ(kept.splits_coarsened, coarsened) << what;
      before = mesh.applied();
    }
  }
}

TEST(SelectiveMesh, FollowsAMovingViewerChangingOnlyWhatTheViewChanges) {
  // An eye circling a bumpy sphere and moving in: each view kept is refine_for_view()'s, and a small
  // step applies and undoes far fewer splits than the mesh holds.
  const ProgressiveMesh pm = build_progressive_mesh(test::bumpy_sphere(4, 0.03));
  const SelectiveRefiner refiner(pm);
  SelectiveMesh mesh(refiner);
  Index changed = 0, held = 0;
  for (int frame = 0; frame < 40; ++frame) {
    Viewpoint view;
    const double angle = 0.05 * frame, distance = 3.0 - 0.03 * frame;
    view.eye = {distance * std::sin(angle), 0.3, distance * std::cos(angle)};
    view.look_at = {0, 0, 0};
    view.viewport_pixels = 600;
    // Three legs: by the deviation, then culling back faces, then by the bound.
    view.cull_backfaces = frame >= 20 && frame < 30;
    const LevelErrorKind kind = frame >= 30 ? LevelErrorKind::Bound : LevelErrorKind::Measured;
    const SelectiveLevel kept = mesh.adapt(view, kind), fresh = refiner.refine_for_view(view, kind);
    expect_same_level(kept, fresh, fmt::format("frame {}", frame));
    EXPECT_EQ(kept.splits_unfolding, 0) << "frame " << frame;  // (this sphere's views do not fold)
    EXPECT_EQ(mesh.applied(), refiner.splits_for_view(view, kind)) << "frame " << frame;
    if (frame % 10 != 0) {  // within a leg
      changed += kept.splits_refined + kept.splits_coarsened;
      held += kept.splits_applied;
    }
  }
  EXPECT_GT(held, 0);
  EXPECT_LT(changed, held / 20) << changed << " splits changed, " << held << " held";
}

// A renderer's copy of a kept mesh: a slot per wedge and per face of the stream, filled from the mesh's
// state, and the mesh those buffers draw (shown faces by number, the wedges they use by number).
struct Buffers {
  const ProgressiveMesh& pm;
  std::vector<Eigen::Vector3d> position;
  std::vector<double> values;
  std::vector<std::array<Index, 3>> corners;
  std::vector<char> shown;

  Buffers(const ProgressiveMesh& p, const SelectiveMesh& m)
      : pm(p), position(p.wedge_point.size()), values(p.wedge_point.size() * std::size_t(p.attribute_dims)),
        corners(p.face_corners.size()), shown(p.face_corners.size()) {
    for (Index w = 0; w < Index(position.size()); ++w) upload_wedge(m, w);
    for (Index f = 0; f < Index(corners.size()); ++f) upload_face(m, f);
  }
  void upload_wedge(const SelectiveMesh& m, Index w) {
    position[std::size_t(w)] = m.wedge_position(w);
    const std::span<const double> v = m.wedge_values(w);
    std::copy(v.begin(), v.end(), values.begin() + std::ptrdiff_t(v.size()) * w);
  }
  void upload_face(const SelectiveMesh& m, Index f) {
    shown[std::size_t(f)] = m.face_shown(f);
    for (int k = 0; k < 3; ++k) corners[std::size_t(f)][std::size_t(k)] = m.face_corner(f, k);
  }
  Mesh draw() const {
    std::vector<Index> row(position.size(), -1), wedges;
    for (std::size_t f = 0; f < corners.size(); ++f)
      if (shown[f])
        for (Index w : corners[f]) row[std::size_t(w)] = 0;
    for (std::size_t w = 0; w < row.size(); ++w)
      if (row[w] == 0) row[w] = Index(wedges.size()), wedges.push_back(Index(w));
    Mesh m;
    m.positions.resize(Index(wedges.size()), 3);
    if (pm.has_normals) m.attributes.normals.resize(Index(wedges.size()), 3);
    if (pm.has_uvs) m.attributes.uvs.resize(Index(wedges.size()), 2);
    if (pm.has_colours) m.attributes.colours.resize(Index(wedges.size()), 4);
    for (Index i = 0; i < Index(wedges.size()); ++i) {
      const std::size_t w = std::size_t(wedges[std::size_t(i)]);
      m.positions.row(i) = position[w].transpose();
      const double* v = values.data() + w * std::size_t(pm.attribute_dims);
      if (pm.has_normals) for (int d = 0; d < 3; ++d) m.attributes.normals(i, d) = *v++;
      if (pm.has_uvs) for (int d = 0; d < 2; ++d) m.attributes.uvs(i, d) = *v++;
      if (pm.has_colours) for (int d = 0; d < 4; ++d) m.attributes.colours(i, d) = float(*v++);
    }
    std::vector<std::size_t> faces;
    for (std::size_t f = 0; f < corners.size(); ++f)
      if (shown[f]) faces.push_back(f);
    m.triangles.resize(Index(faces.size()), 3);
    if (pm.has_face_colours) m.attributes.face_colours.resize(Index(faces.size()), 4);
    for (Index i = 0; i < Index(faces.size()); ++i) {
      for (int k = 0; k < 3; ++k) m.triangles(i, k) = row[std::size_t(corners[faces[std::size_t(i)]][std::size_t(k)])];
      if (pm.has_face_colours) m.attributes.face_colours.row(i) = pm.face_colours.row(Index(faces[std::size_t(i)]));
    }
    return m;
  }
};

TEST(SelectiveMesh, StepsNameEverySlotTheyChange) {
  // A renderer's buffers, filled once and then only where a step says: after every step they draw the
  // mesh refine() gives for the set, bit for bit, and a small step names few slots.
  std::mt19937 rng(31);
  for (const Mesh& input : inputs()) {
    const ProgressiveMesh pm = build_progressive_mesh(input);
    const SelectiveRefiner refiner(pm);
    const std::size_t n = pm.splits.size();
    SelectiveMesh mesh(refiner);
    Buffers buffers(pm, mesh);
    for (int step = 0; step < 12; ++step) {
      std::vector<char> wanted(n, step == 10 ? 1 : 0);
      if (step < 10) {
        std::bernoulli_distribution pick(std::array{0.001, 0.01, 0.05, 0.2, 0.5}[step % 5]);
        for (char& w : wanted) w = pick(rng);
      }
      const std::vector<char> before = mesh.applied();
      const SelectiveChanges c = mesh.step_to(wanted);
      for (Index w : c.wedges) buffers.upload_wedge(mesh, w);
      for (Index f : c.faces) buffers.upload_face(mesh, f);
      const std::string what = fmt::format("{} faces, step {}", input.num_faces(), step);
      expect_identical(buffers.draw(), refiner.refine(wanted).extracted.mesh, what);
      Index refined = 0, coarsened = 0;
      for (std::size_t j = 0; j < n; ++j) refined += !before[j] && mesh.applied()[j], coarsened += before[j] && !mesh.applied()[j];
      EXPECT_EQ(c.splits_refined, refined) << what;
      EXPECT_EQ(c.splits_coarsened, coarsened) << what;
      EXPECT_TRUE(std::is_sorted(c.wedges.begin(), c.wedges.end()) && std::is_sorted(c.faces.begin(), c.faces.end())) << what;
      if (refined + coarsened < Index(n) / 20) {
        EXPECT_LT(c.faces.size(), pm.face_corners.size() / 4) << what;
      }
    }
  }
}

// A mesh's faces with area as comparable rows: per corner its position and attribute values, each face
// turned to start at its least corner, the faces sorted. Faces with two corners at one place are left
// out and counted.
std::vector<std::vector<double>> faces_with_area(const Mesh& m, Index& without) {
  std::vector<std::vector<double>> out;
  without = 0;
  for (Index f = 0; f < m.num_faces(); ++f) {
    std::array<std::vector<double>, 3> corner;
    for (int k = 0; k < 3; ++k) {
      const Index v = m.triangles(f, k);
      for (int d = 0; d < 3; ++d) corner[k].push_back(m.positions(v, d));
      if (m.has_normals()) for (int d = 0; d < 3; ++d) corner[k].push_back(m.attributes.normals(v, d));
      if (m.has_uvs()) for (int d = 0; d < 2; ++d) corner[k].push_back(m.attributes.uvs(v, d));
      if (m.has_colours()) for (int d = 0; d < 4; ++d) corner[k].push_back(m.attributes.colours(v, d));
    }
    auto at = [&](int k) { return m.positions.row(m.triangles(f, k)); };
    if (at(0) == at(1) || at(1) == at(2) || at(0) == at(2)) {
      ++without;
      continue;
    }
    const int first = static_cast<int>(std::min_element(corner.begin(), corner.end()) - corner.begin());
    std::vector<double>& row = out.emplace_back();
    for (int k = 0; k < 3; ++k) row.insert(row.end(), corner[(first + k) % 3].begin(), corner[(first + k) % 3].end());
  }
  std::sort(out.begin(), out.end());
  return out;
}

// A morph from the state `before` (its mesh) to `reached`: the connectivity of both sets together, at
// alpha 0 the faces of `before` exactly and nothing else with area, at 1 those of `reached`.
void expect_morph_between(const SelectiveRefiner& refiner, const SelectiveMorph& m, const SelectiveLevel& before,
                          const std::vector<char>& applied_before, const std::vector<char>& applied_after, const std::string& what) {
  std::vector<char> both = applied_before;
  for (std::size_t j = 0; j < both.size(); ++j) both[j] |= applied_after[j];
  const SelectiveLevel joint = refiner.refine(both);
  const Geomorph& g = m.geomorph;
  EXPECT_EQ(g.fine.mesh.triangles, joint.extracted.mesh.triangles) << what;
  EXPECT_EQ(g.fine.vertex_wedge, joint.extracted.vertex_wedge) << what;
  EXPECT_EQ(g.coarse_level, before.splits_applied) << what;
  EXPECT_EQ(g.fine_level, m.reached.splits_applied) << what;
  for (const auto& [alpha, state] : {std::pair{0.0, &before}, std::pair{1.0, &m.reached}}) {
    Index degenerate = 0, none = 0;
    const auto morphed = faces_with_area(g.at(alpha), degenerate);
    const auto expected = faces_with_area(state->extracted.mesh, none);
    ASSERT_EQ(none, 0) << what;  // (the inputs have no such faces)
    EXPECT_TRUE(morphed == expected) << what << ", alpha " << alpha << ": " << morphed.size() << " faces with area, "
                                     << expected.size() << " expected";
    EXPECT_EQ(degenerate, joint.extracted.mesh.num_faces() - state->extracted.mesh.num_faces()) << what << ", alpha " << alpha;
  }
  // Between the ends every vertex is on its way: none leaves the box of its two ends.
  const Mesh half = g.at(0.5);
  for (Index v = 0; v < half.num_vertices(); ++v)
    for (int d = 0; d < 3; ++d)
      ASSERT_TRUE(half.positions(v, d) >= std::min(g.start_positions(v, d), g.fine.mesh.positions(v, d)) &&
                  half.positions(v, d) <= std::max(g.start_positions(v, d), g.fine.mesh.positions(v, d))) << what;
}

TEST(SelectiveMesh, AMorphStartsAtTheStateBeforeAndEndsAtTheNewOne) {
  // Random sets one after another, refining and coarsening at once: each morph's ends look exactly like
  // the two states (positions and attributes), its connectivity is both sets', and the state reached is
  // refine()'s for the new set, as go_to() would leave it.
  std::mt19937 rng(29);
  for (const Mesh& input : inputs()) {
    const ProgressiveMesh pm = build_progressive_mesh(input);
    const SelectiveRefiner refiner(pm);
    const std::size_t n = pm.splits.size();
    SelectiveMesh mesh(refiner);
    SelectiveLevel before = refiner.refine(std::vector<char>(n, 0));
    for (int step = 0; step < 10; ++step) {
      std::vector<char> wanted(n, step == 8 ? 1 : 0);
      if (step < 8) {
        std::bernoulli_distribution pick(std::array{0.01, 0.05, 0.2, 0.5}[step % 4]);
        for (char& w : wanted) w = pick(rng);
      }
      const std::vector<char> applied_before = mesh.applied();
      const SelectiveMorph m = mesh.morph_to(wanted);
      const SelectiveLevel fresh = refiner.refine(wanted);
      const std::string what = fmt::format("{} faces, step {}: {} -> {} of {} splits", input.num_faces(), step,
                                           before.splits_applied, fresh.splits_applied, n);
      expect_same_level(m.reached, fresh, what);
      expect_morph_between(refiner, m, before, applied_before, mesh.applied(), what);
      before = fresh;
    }
  }
}

TEST(SelectiveMesh, MorphsFromViewToViewAsAdaptMoves) {
  const ProgressiveMesh pm = build_progressive_mesh(test::seamed_uv_sphere());
  const SelectiveRefiner refiner(pm);
  SelectiveMesh morphing(refiner), moving(refiner);
  SelectiveLevel before = refiner.refine(std::vector<char>(pm.splits.size(), 0));
  Index refined = 0, coarsened = 0;
  for (int frame = 0; frame < 12; ++frame) {
    Viewpoint view;
    const double angle = 0.4 * frame, distance = 2.0 + 0.5 * std::sin(frame);
    view.eye = {distance * std::sin(angle), 0.2, distance * std::cos(angle)};
    view.look_at = {0, 0, 0};
    view.viewport_pixels = 400;
    const std::vector<char> applied_before = morphing.applied();
    const SelectiveMorph m = morphing.morph_to_view(view, LevelErrorKind::Measured);
    const SelectiveLevel kept = moving.adapt(view, LevelErrorKind::Measured);
    const std::string what = fmt::format("frame {}", frame);
    expect_same_level(m.reached, kept, what);
    EXPECT_EQ(m.reached.splits_refined, kept.splits_refined) << what;
    EXPECT_EQ(m.reached.splits_coarsened, kept.splits_coarsened) << what;
    expect_morph_between(refiner, m, before, applied_before, morphing.applied(), what);
    refined += m.reached.splits_refined, coarsened += m.reached.splits_coarsened;
    before = kept;
  }
  EXPECT_GT(refined, 0);
  EXPECT_GT(coarsened, 0);  // both ways blend
}

TEST(SelectiveMesh, UnfoldsAlikeWhateverCameBefore) {
  // Close views of the fractal pyramid, with random sets and views left folded between them:
  // each view kept, stepped into a renderer's buffers or morphed to is refine_for_view()'s, unfolded,
  // whatever state came before.
  std::mt19937 rng(37);
  const ProgressiveMesh pm = build_progressive_mesh(fractal_pyramid());
  const SelectiveRefiner refiner(pm);
  const FoldCount folds(pm, refiner);
  const std::size_t n = pm.splits.size();
  const LevelErrorKind kind = LevelErrorKind::Bound;
  SelectiveMesh kept(refiner), stepping(refiner), morphing(refiner);
  Buffers buffers(pm, stepping);
  auto upload = [&](const SelectiveChanges& c) {
    for (Index w : c.wedges) buffers.upload_wedge(stepping, w);
    for (Index f : c.faces) buffers.upload_face(stepping, f);
  };
  SelectiveLevel before = refiner.refine(std::vector<char>(n, 0));
  int unfolding_views = 0, folded_states = 0;
  const std::vector<Viewpoint> views = views_around(pm, 0.6);
  for (std::size_t i = 0; i < views.size(); ++i) {
    const std::string what = fmt::format("view {}", i);
    if (i % 4 == 2) {  // a random set
      std::bernoulli_distribution pick(0.05);
      std::vector<char> wanted(n);
      for (char& w : wanted) w = pick(rng);
      const SelectiveLevel fresh = refiner.refine(wanted);
      expect_same_level(kept.go_to(wanted), fresh, what + ", a set");
      upload(stepping.step_to(wanted));
      expect_identical(buffers.draw(), fresh.extracted.mesh, what + ", a set stepped to");
      const std::vector<char> applied_before = morphing.applied();
      const SelectiveMorph m = morphing.morph_to(wanted);
      expect_morph_between(refiner, m, before, applied_before, morphing.applied(), what + ", a set morphed to");
      before = m.reached;
    }
    if (i % 2 == 1) {  // another view, left folded
      Viewpoint other = views[(i + 9) % views.size()];
      other.pixel_error = 0.5;
      other.unfold = false;
      const SelectiveLevel fresh = refiner.refine_for_view(other, kind);
      expect_same_level(kept.adapt(other, kind), fresh, what + ", another view");
      folded_states += folds(kept) > 0;
      upload(stepping.step_to_view(other, kind));
      expect_identical(buffers.draw(), fresh.extracted.mesh, what + ", another view stepped to");
      const std::vector<char> applied_before = morphing.applied();
      const SelectiveMorph m = morphing.morph_to_view(other, kind);
      expect_morph_between(refiner, m, before, applied_before, morphing.applied(), what + ", another view morphed to");
      before = m.reached;
    }
    Viewpoint view = views[i];
    view.pixel_error = 0.5;
    const SelectiveLevel fresh = refiner.refine_for_view(view, kind);
    expect_same_level(kept.adapt(view, kind), fresh, what);
    EXPECT_EQ(folds(kept), 0) << what;
    const SelectiveChanges c = stepping.step_to_view(view, kind);
    upload(c);
    expect_identical(buffers.draw(), fresh.extracted.mesh, what + ", stepped");
    EXPECT_EQ(c.splits_unfolding, fresh.splits_unfolding) << what;
    const std::vector<char> applied_before = morphing.applied();
    const SelectiveMorph m = morphing.morph_to_view(view, kind);
    expect_same_level(m.reached, fresh, what + ", morphed");
    expect_morph_between(refiner, m, before, applied_before, morphing.applied(), what + ", morphed");
    before = m.reached;
    unfolding_views += fresh.splits_unfolding > 0;
  }
  // The test needs views that unfold, and states left folded for the next view to find.
  EXPECT_GE(unfolding_views, 3);
  EXPECT_GE(folded_states, 2);
}

}  // namespace
}  // namespace lodkit
