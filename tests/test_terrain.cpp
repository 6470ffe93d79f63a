// Fractal terrain: closedness and genus, thread and level consistency, displacement statistics
// (variance per level, Hurst exponent from a variogram), the streamed PLY against the in-memory mesh,
// and bad options.
#include <lodkit/error.h>
#include <lodkit/inspect.h>
#include <lodkit/io.h>
#include <lodkit/primitives.h>
#include <lodkit/terrain.h>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <unordered_map>

#include "test_util.h"

namespace lodkit {
namespace {

bool same_terrain(const Terrain& a, const Terrain& b) {
  return a.mesh.positions == b.mesh.positions && a.mesh.triangles == b.mesh.triangles &&
         a.mesh.attributes.face_colours == b.mesh.attributes.face_colours && a.keys == b.keys &&
         a.vertex_level == b.vertex_level;
}

TEST(Terrain, SizesFollowTheSubdivisionCounts) {
  const Mesh grid = make_terrain_base(TerrainBase::Grid);
  for (int levels : {0, 1, 3, 7}) {
    TerrainOptions o;
    o.levels = levels;
    const Terrain t = generate_terrain(grid, o);
    const TerrainSize size = terrain_size(grid, levels);
    const long long n = 1LL << levels;
    EXPECT_EQ(t.mesh.num_faces(), 2 * n * n);
    EXPECT_EQ(t.mesh.num_vertices(), (n + 1) * (n + 1));
    EXPECT_EQ(size.faces, t.mesh.num_faces());
    EXPECT_EQ(size.vertices, t.mesh.num_vertices());
  }
}

TEST(Terrain, ZeroLevelsOrZeroSigmaKeepTheBaseSurface) {
  const Mesh pyramid = make_terrain_base(TerrainBase::Pyramid);
  TerrainOptions o;
  o.levels = 0;
  EXPECT_EQ(generate_terrain(pyramid, o).mesh.positions, pyramid.positions);
  o.levels = 7;
  o.sigma = 0.0;
  const Terrain flat = generate_terrain(pyramid, o);
  EXPECT_NEAR(inspect(flat.mesh).area, inspect(pyramid).area, 1e-10);
}

// Closed bases stay closed, manifold and oriented, with the base's genus: through the patch path alone
// (colour off, 5 levels) and through OpenSubdiv's coarse levels plus patches (colour on forces the
// palette's 4 levels into the coarse stage).
TEST(Terrain, ClosedBaseStaysClosedWithItsGenus) {
  TorusOptions torus_options;
  torus_options.major_segments = 8;
  torus_options.minor_segments = 6;
  for (const Mesh& base : {test::tetrahedron(), make_icosphere({.radius = 1.0, .subdivisions = 1}),
                           make_torus(torus_options)}) {
    const MeshReport before = inspect(base);
    for (bool colour : {false, true}) {
      TerrainOptions o;
      o.levels = 5;
      o.colour = colour;
      o.sigma = 0.05;
      const Terrain t = generate_terrain(base, o);
      const MeshReport after = inspect(t.mesh);
      EXPECT_TRUE(after.closed);
      EXPECT_TRUE(after.oriented);
      EXPECT_EQ(after.boundary_edges, 0);
      EXPECT_EQ(after.euler_characteristic, before.euler_characteristic);
      EXPECT_EQ(after.genus, before.genus);
      EXPECT_EQ(after.welded_vertices, t.mesh.num_vertices()) << "every point is made exactly once";
      EXPECT_GT(*after.volume, 0.0);
    }
  }
}

TEST(Terrain, IdenticalForAnyThreadCountAndAcrossRuns) {
  const Mesh pyramid = make_terrain_base(TerrainBase::Pyramid);
  TerrainOptions o;
  o.levels = 8;
  o.colour = true;
  o.threads = 1;
  const Terrain one = generate_terrain(pyramid, o);
  o.threads = 2;
  const Terrain two = generate_terrain(pyramid, o);
  o.threads = 0;
  const Terrain all = generate_terrain(pyramid, o);
  EXPECT_TRUE(same_terrain(one, two));
  EXPECT_TRUE(same_terrain(one, all));

  test::ScratchDir dir("terrain_threads");
  o.threads = 1;
  write_terrain_ply(pyramid, o, dir / "one.ply");
  o.threads = 2;
  write_terrain_ply(pyramid, o, dir / "two.ply");
  EXPECT_EQ(test::read_bytes(dir / "one.ply"), test::read_bytes(dir / "two.ply"));

  o.seed = 2;
  EXPECT_NE(generate_terrain(pyramid, o).mesh.positions, one.mesh.positions) << "the seed matters";
}

// Generating 8 levels and then 10 gives identical points for all of the first 8 (and the coarse and
// patch stages split differently in the two runs).
TEST(Terrain, FinerLevelsKeepCoarserPointsBitIdentical) {
  for (TerrainBase kind : {TerrainBase::Grid, TerrainBase::Pyramid}) {
    const Mesh base = make_terrain_base(kind);
    TerrainOptions o;
    o.levels = 8;
    const Terrain coarse = generate_terrain(base, o);
    o.levels = 10;
    const Terrain fine = generate_terrain(base, o);
    std::unordered_map<std::uint64_t, Index> by_key;
    for (Index v = 0; v < fine.mesh.num_vertices(); ++v) by_key.emplace(fine.keys[static_cast<std::size_t>(v)], v);
    ASSERT_EQ(by_key.size(), fine.keys.size()) << "keys are unique";
    Index mismatches = 0;
    for (Index v = 0; v < coarse.mesh.num_vertices(); ++v) {
      const auto it = by_key.find(coarse.keys[static_cast<std::size_t>(v)]);
      ASSERT_NE(it, by_key.end());
      if (coarse.mesh.positions.row(v) != fine.mesh.positions.row(it->second) ||
          coarse.vertex_level[static_cast<std::size_t>(v)] != fine.vertex_level[static_cast<std::size_t>(it->second)])
        ++mismatches;
    }
    EXPECT_EQ(mismatches, 0);
  }
}

/// Heights of a grid terrain on its (n+1)^2 lattice, indexed [j][i]; x, y must be exact lattice points.
struct HeightLattice {
  int n;
  std::vector<double> z;
  double at(int i, int j) const { return z[static_cast<std::size_t>(j * (n + 1) + i)]; }
};

HeightLattice lattice_of(const Terrain& t, int levels) {
  HeightLattice h{1 << levels, {}};
  h.z.assign(static_cast<std::size_t>((h.n + 1) * (h.n + 1)), std::nan(""));
  for (Index v = 0; v < t.mesh.num_vertices(); ++v) {
    const double x = (t.mesh.positions(v, 0) + 0.5) * h.n, y = (t.mesh.positions(v, 1) + 0.5) * h.n;
    const int i = static_cast<int>(x), j = static_cast<int>(y);
    EXPECT_EQ(i, x);
    EXPECT_EQ(j, y);
    h.z[static_cast<std::size_t>(j * (h.n + 1) + i)] = t.mesh.positions(v, 2);
  }
  for (double z : h.z) EXPECT_FALSE(std::isnan(z));
  return h;
}

// On the grid every displacement is vertical, so a point's displacement is its height minus the mean
// of its parents' heights. Their sample variance per level must match sigma_l^2.
TEST(Terrain, DisplacementVarianceMatchesSigmaPerLevel) {
  const Mesh grid = make_terrain_base(TerrainBase::Grid);
  TerrainOptions o;
  o.levels = 9;
  o.roughness = 0.7;
  o.sigma = 0.2;
  o.sigma_is_relative = false;
  o.seed = 11;
  const Terrain t = generate_terrain(grid, o);
  const HeightLattice h = lattice_of(t, o.levels);
  for (int level = 1; level <= o.levels; ++level) {
    const int s = h.n >> level;
    double sum = 0, sum2 = 0;
    long long count = 0;
    for (int j = 0; j <= h.n; j += s)
      for (int i = 0; i <= h.n; i += s) {
        const bool odd_i = (i / s) % 2 == 1, odd_j = (j / s) % 2 == 1;
        if (!odd_i && !odd_j) continue;
        // The square's diagonal runs from (0, 0) to (1, 1).
        const double parents = odd_i && !odd_j ? h.at(i - s, j) + h.at(i + s, j)
                               : !odd_i        ? h.at(i, j - s) + h.at(i, j + s)
                                               : h.at(i - s, j - s) + h.at(i + s, j + s);
        const double d = h.at(i, j) - 0.5 * parents;
        sum += d, sum2 += d * d, ++count;
      }
    const double sigma = terrain_sigma(grid, o, level);
    const double variance = sum2 / static_cast<double>(count);
    EXPECT_NEAR(sum / static_cast<double>(count), 0.0, 5.0 * sigma / std::sqrt(static_cast<double>(count)));
    if (count >= 50) {  // relative standard error of a variance estimate: sqrt(2 / N)
      EXPECT_NEAR(variance / (sigma * sigma), 1.0, 5.0 * std::sqrt(2.0 / static_cast<double>(count)))
          << "level " << level << " with " << count << " samples";
    }
  }
}

// Fractional Brownian surfaces have a variogram gamma(d) = 1/2 E[(z(x + d) - z(x))^2] ~ d^(2H). Midpoint
// displacement from a deterministic base adds the base's own smooth trend, which holds no variance
// at scales above the base and enters the variogram as a d^2 term (1-D analysis: gamma_l is
// proportional to 4^(-lH) - 4^(-l)). So fit gamma(d) = A d^(2H) + B d^2 over lags 2..64 lattice steps
// (lag 1 is the resolution cutoff, where pairs of finest-level points dominate): for each H the
// best A, B solve a 2x2 least-squares problem on relative residuals; keep the H with the least
// residual. A plain log-log slope ignores the trend and reads H = 0.9 as 0.78.
double estimate_hurst(const HeightLattice& h) {
  std::vector<double> lags, gammas;
  for (int lag = 2; lag <= 64; lag *= 2) {
    double sum = 0;
    long long count = 0;
    for (int j = 0; j <= h.n; ++j)
      for (int i = 0; i + lag <= h.n; ++i) {
        const double dx = h.at(i + lag, j) - h.at(i, j), dy = h.at(j, i + lag) - h.at(j, i);
        sum += dx * dx + dy * dy, count += 2;
      }
    lags.push_back(lag);
    gammas.push_back(0.5 * sum / static_cast<double>(count));
  }
  double best_h = 0, best_residual = std::numeric_limits<double>::infinity();
  for (double H = 0.05; H <= 1.3; H += 0.001) {
    // Columns u = d^(2H) / gamma, w = d^2 / gamma; minimise sum (A u + B w - 1)^2.
    double uu = 0, uw = 0, ww = 0, u1 = 0, w1 = 0;
    for (std::size_t k = 0; k < lags.size(); ++k) {
      const double u = std::pow(lags[k], 2 * H) / gammas[k], w = lags[k] * lags[k] / gammas[k];
      uu += u * u, uw += u * w, ww += w * w, u1 += u, w1 += w;
    }
    const double det = uu * ww - uw * uw;
    const double A = (u1 * ww - w1 * uw) / det, B = (w1 * uu - u1 * uw) / det;
    double residual = 0;
    for (std::size_t k = 0; k < lags.size(); ++k) {
      const double r = (A * std::pow(lags[k], 2 * H) + B * lags[k] * lags[k]) / gammas[k] - 1.0;
      residual += r * r;
    }
    if (residual < best_residual) best_residual = residual, best_h = H;
  }
  return best_h;
}

TEST(Terrain, HurstExponentEstimatedFromTheSurfaceMatchesRoughness) {
  const Mesh grid = make_terrain_base(TerrainBase::Grid);
  for (std::uint64_t seed : {5u, 6u})
    for (double H : {0.3, 0.5, 0.8, 0.9}) {
      TerrainOptions o;
      o.levels = 9;
      o.roughness = H;
      o.seed = seed;
      const double estimate = estimate_hurst(lattice_of(generate_terrain(grid, o), o.levels));
      EXPECT_NEAR(estimate, H, 0.1) << "requested H = " << H << ", seed " << seed;
    }
}

TEST(Terrain, StreamedPlyIsTheInMemoryMesh) {
  const Mesh pyramid = make_terrain_base(TerrainBase::Pyramid);
  TerrainOptions o;
  o.levels = 7;
  o.colour = true;
  const Terrain t = generate_terrain(pyramid, o);
  test::ScratchDir dir("terrain_stream");
  const TerrainWriteStats stats = write_terrain_ply(pyramid, o, dir / "t.ply");
  EXPECT_EQ(stats.bytes, static_cast<std::int64_t>(std::filesystem::file_size(dir / "t.ply")));
  const Mesh read = read_mesh(dir / "t.ply");
  EXPECT_EQ(read.triangles, t.mesh.triangles);
  EXPECT_EQ(read.positions, t.mesh.positions.cast<float>().cast<double>());
  EXPECT_EQ(read.attributes.face_colours, t.mesh.attributes.face_colours);
  EXPECT_EQ(dir.entries(), 1u) << "no temporary file left";
}

TEST(Terrain, ColoursComeFromThePaletteAndFollowHeight) {
  const Mesh pyramid = make_terrain_base(TerrainBase::Pyramid);
  TerrainOptions o;
  o.levels = 8;
  o.colour = true;
  const Terrain t = generate_terrain(pyramid, o);
  ASSERT_TRUE(t.mesh.has_face_colours());
  std::map<std::array<float, 3>, std::pair<double, long long>> mean_height;  // colour -> (sum z, count)
  for (Index f = 0; f < t.mesh.num_faces(); ++f) {
    const auto c = t.mesh.attributes.face_colours.row(f);
    double z = 0;
    for (int k = 0; k < 3; ++k) z += t.mesh.positions(t.mesh.triangles(f, k), 2) / 3;
    auto& [sum, count] = mean_height[{c[0], c[1], c[2]}];
    sum += z, ++count;
  }
  EXPECT_GE(mean_height.size(), 4u);
  EXPECT_LE(mean_height.size(), 6u);
  const auto mean = [&](std::array<float, 3> rgb) {
    const auto& [sum, count] = mean_height.at(rgb);
    return sum / static_cast<double>(count);
  };
  // Snow sits higher than grass on average.
  const std::array<float, 3> snow{244 / 255.0f, 246 / 255.0f, 250 / 255.0f}, grass{96 / 255.0f, 152 / 255.0f, 64 / 255.0f};
  ASSERT_TRUE(mean_height.count(snow) && mean_height.count(grass));
  EXPECT_GT(mean(snow), mean(grass));
}

TEST(Terrain, BadOptionsAndBasesAreRefused) {
  const Mesh grid = make_terrain_base(TerrainBase::Grid);
  auto fails = [&](const Mesh& base, TerrainOptions o, const std::string& needle) {
    try {
      generate_terrain(base, o);
      ADD_FAILURE() << "expected an error mentioning " << needle;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  fails(grid, {.levels = 16}, "levels");
  fails(grid, {.levels = -1}, "levels");
  fails(grid, {.levels = 15}, "2^31");
  fails(grid, {.roughness = 0.0}, "roughness");
  fails(grid, {.roughness = 1.5}, "roughness");
  fails(grid, {.sigma = std::nan("")}, "sigma");
  fails(grid, {.sigma = -1.0}, "sigma");
  fails(grid, {.threads = -2}, "threads");
  fails(Mesh{}, {}, "no faces");
  Mesh degenerate = grid;
  degenerate.triangles(0, 1) = degenerate.triangles(0, 0);
  fails(degenerate, {}, "repeats a vertex");
  Mesh nan_base = grid;
  nan_base.positions(1, 1) = std::nan("");
  fails(nan_base, {}, "terrain base");
}

}  // namespace
}  // namespace lodkit
