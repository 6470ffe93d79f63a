// hoppe's E_scalar: attribute values at the sample points, with --attribute-weights.
#include <gtest/gtest.h>
#include <lodkit/inspect.h>
#include <lodkit/metrics.h>
#include <lodkit/primitives.h>
#include <lodkit/simplify.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "test_util.h"

namespace lodkit {
namespace {

/// A flat n x n grid on [0,1]^2 whose vertex colours are red inside the disc of radius 0.3 about the
/// centre and blue outside: flat, so E_dist costs nothing anywhere and only the colours tell collapses apart.
Mesh colour_disc_grid(int n = 40) {
  Mesh m = make_grid({.size = {1.0, 1.0}, .divisions_x = n, .divisions_y = n});
  m.attributes.colours.resize(m.num_vertices(), 4);
  for (Index v = 0; v < m.num_vertices(); ++v) {
    const double x = m.positions(v, 0) + 0.5, y = m.positions(v, 1) + 0.5;  // the grid is centred
    const bool red = (x - 0.5) * (x - 0.5) + (y - 0.5) * (y - 0.5) < 0.09;
    m.attributes.colours.row(v) << (red ? 1.0f : 0.0f), 0.2f, (red ? 0.0f : 1.0f), 1.0f;
  }
  return m;
}

/// The colour RMS compare() measures between two coloured meshes.
double colour_rms(const Mesh& input, const Mesh& output) { return compare(input, output).colour_rms.value(); }

TEST(HoppeScalar, KeepsAColourDiscThatTheGeometryCannotSee) {
  const Mesh grid = colour_disc_grid();
  SimplifyOptions o{.method = SimplifyMethod::Hoppe, .target_ratio = 0.1};
  const SimplifyResult plain = simplify(grid, o);
  o.attribute_weights = {0, 0, 0.1};
  const SimplifyResult weighted = simplify(grid, o);
  EXPECT_EQ(weighted.faces_out, plain.faces_out);
  EXPECT_EQ(weighted.reason, StopReason::TargetReached);
  // Without the weights the colours ride along (0.23 measured); with them E_scalar keeps the ring of
  // faces that interpolates the disc's edge, and the colours come out exact.
  EXPECT_GT(colour_rms(grid, plain.mesh), 0.1);
  EXPECT_LT(colour_rms(grid, weighted.mesh), 1e-6);
  EXPECT_TRUE(inspect(weighted.mesh).oriented);
}

TEST(HoppeScalar, WeightsOnAMeshWithoutThoseAttributesChangeNothing) {
  const Mesh sphere = make_icosphere({.subdivisions = 3});
  SimplifyOptions o{.method = SimplifyMethod::Hoppe, .target_ratio = 0.1};
  const SimplifyResult plain = simplify(sphere, o);
  o.attribute_weights = {0, 0, 1};  // colours: the sphere has none
  const SimplifyResult weighted = simplify(sphere, o);
  EXPECT_EQ(weighted.mesh.positions, plain.mesh.positions);
  EXPECT_EQ(weighted.mesh.triangles, plain.mesh.triangles);
}

TEST(HoppeScalar, UvSeamsHoldAndTheShapeWithThem) {
  // Points near the u = 0 / u = 1 seam may be handed to faces across it, whose UVs come from the other
  // side: they count no E_scalar there, so the seam does not steer the collapses (when they counted, the
  // shared cow's RMS distance at 10 % rose by a fifth).
  const Mesh sphere = make_uv_sphere({.segments = 48, .rings = 24, .uvs = true});
  SimplifyOptions o{.method = SimplifyMethod::Hoppe, .target_ratio = 0.1};
  const SimplifyResult plain = simplify(sphere, o);
  o.attribute_weights = {0, 0.1, 0};
  const SimplifyResult r = simplify(sphere, o);
  EXPECT_EQ(r.reason, StopReason::TargetReached);
  const MeshReport report = inspect(r.mesh);
  EXPECT_TRUE(report.closed);
  EXPECT_EQ(report.euler_characteristic, 2);
  // No face straddles the seam: its UV triangle would span most of the texture (polar fans excepted).
  for (Index f = 0; f < r.mesh.num_faces(); ++f) {
    double lo = 1, hi = 0;
    bool polar = false;
    for (int k = 0; k < 3; ++k) {
      const auto uv = r.mesh.attributes.uvs.row(r.mesh.triangles(f, k));
      polar |= std::abs(uv[1] - 0.5) > 0.35;
      lo = std::min(lo, double(uv[0])), hi = std::max(hi, double(uv[0]));
    }
    if (!polar) {
      EXPECT_LT(hi - lo, 0.5) << "face " << f;
    }
  }
  // The shape holds: the UVs do not outweigh the distances.
  EXPECT_LT(compare(sphere, r.mesh).rms, 1.25 * compare(sphere, plain.mesh).rms);
}

/// A bumpy sphere cut into eight UV charts by the coordinate planes (each face goes to the octant of its
/// centroid), each chart one UV value, 10 apart: any value interpolated within a chart is exact, and
/// one interpolated across a seam far off.
Mesh octant_charted_sphere() {
  const Mesh sphere = test::bumpy_sphere(4, 0.03);
  Mesh m;
  std::map<std::pair<Index, int>, Index> vertex_of;  // (input vertex, chart) -> output vertex
  std::vector<Eigen::Vector3d> positions;
  std::vector<Eigen::Vector2d> uvs;
  m.triangles.resize(sphere.num_faces(), 3);
  for (Index f = 0; f < sphere.num_faces(); ++f) {
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k) centroid += sphere.positions.row(sphere.triangles(f, k)).transpose();
    const int chart = (centroid.x() > 0) + 2 * (centroid.y() > 0) + 4 * (centroid.z() > 0);
    for (int k = 0; k < 3; ++k) {
      const Index v = sphere.triangles(f, k);
      const auto [it, fresh] = vertex_of.try_emplace({v, chart}, Index(positions.size()));
      if (fresh) {
        const Eigen::Vector3d p = sphere.positions.row(v).transpose();
        positions.push_back(p);
        uvs.push_back(Eigen::Vector2d(10.0 * chart, 0.5));
      }
      m.triangles(f, k) = it->second;
    }
  }
  m.positions.resize(Index(positions.size()), 3);
  m.attributes.uvs.resize(Index(positions.size()), 2);
  for (std::size_t i = 0; i < positions.size(); ++i)
    m.positions.row(Index(i)) = positions[i].transpose(), m.attributes.uvs.row(Index(i)) = uvs[i].transpose();
  return m;
}

TEST(HoppeScalar, ValuesAcrossASeamDoNotCount) {
  // The UVs cost E_scalar nothing where they are compared within their chart, so the weights leave the
  // shape as it was. (Compared across the seams, points near them counted errors of about 10 and steered
  // the collapses: RMS distance x1.2 on the shared cow.)
  const Mesh m = octant_charted_sphere();
  SimplifyOptions o{.method = SimplifyMethod::Hoppe, .target_ratio = 0.1};
  const SimplifyResult plain = simplify(m, o);
  o.attribute_weights = {0, 0.1, 0};
  const SimplifyResult weighted = simplify(m, o);
  EXPECT_EQ(weighted.reason, StopReason::TargetReached);
  const double rms_plain = compare(m, plain.mesh).rms, rms_weighted = compare(m, weighted.mesh).rms;
  EXPECT_LT(rms_weighted, 1.05 * rms_plain) << rms_plain << " " << rms_weighted;
}

TEST(HoppeScalar, SameResultForAnyNumberOfThreads) {
  const Mesh grid = colour_disc_grid(64);  // 8,192 faces, in lanes of 1,000
  SimplifyOptions o{.method = SimplifyMethod::Hoppe, .target_ratio = 0.1, .lane_faces = 1000};
  o.attribute_weights = {0, 0, 0.1};
  const auto run = [&] { return simplify(grid, o); };
  const SimplifyResult one = test::on_threads(1, run), many = test::on_threads(4, run);
  EXPECT_GT(one.lanes, 1);
  EXPECT_EQ(one.mesh.positions, many.mesh.positions);
  EXPECT_EQ(one.mesh.triangles, many.mesh.triangles);
  EXPECT_EQ(one.mesh.attributes.colours, many.mesh.attributes.colours);
}

}  // namespace
}  // namespace lodkit
