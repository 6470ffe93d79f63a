// The quadric's minimisers (regularised for the quadric cost, truncated for hoppe's start): exact
// where the planes pin a point, and anchored along the directions they leave free (a plane leaves
// two, two planes a line).
#include <gtest/gtest.h>

#include "simplify/quadric.h"

namespace lodkit::detail {
namespace {

// Both minimisers, so each test checks each.
bool regularised(const Quadric& q, const Eigen::Vector3d& anchor, Eigen::Vector3d& out) {
  return q.minimiser_near(anchor, out);
}
bool truncated(const Quadric& q, const Eigen::Vector3d& anchor, Eigen::Vector3d& out) {
  return q.truncated_minimiser_near(anchor, out);
}
using Minimiser = bool (*)(const Quadric&, const Eigen::Vector3d&, Eigen::Vector3d&);
const Minimiser kMinimisers[] = {regularised, truncated};

Quadric plane_through(const Eigen::Vector3d& normal, const Eigen::Vector3d& point, double weight = 1.0) {
  const Eigen::Vector3d n = normal.normalized();
  return Quadric::plane(n, -n.dot(point), weight);
}

TEST(Quadric, ThreePlanesMeetAtTheirCorner) {
  for (Minimiser minimise : kMinimisers) {
    SCOPED_TRACE(minimise == regularised ? "regularised" : "truncated");
    const Eigen::Vector3d corner(0.3, -1.2, 2.5);
    const Quadric q = plane_through({1, 0, 0}, corner) + plane_through({0, 1, 0.2}, corner, 2.0) +
                      plane_through({0.1, 0, 1}, corner, 0.5);
    Eigen::Vector3d p;
    ASSERT_TRUE(minimise(q, {5, 5, 5}, p));
    EXPECT_LT((p - corner).norm(), 1e-12);
    EXPECT_LT(q.evaluate(p), 1e-20);
  }
}

TEST(Quadric, OnePlaneProjectsTheAnchor) {
  for (Minimiser minimise : kMinimisers) {
    SCOPED_TRACE(minimise == regularised ? "regularised" : "truncated");
    const Quadric q = plane_through({0, 0, 1}, {0, 0, 1});  // z = 1
    const Eigen::Vector3d anchor(0.4, -0.7, 3.0);
    Eigen::Vector3d p;
    ASSERT_TRUE(minimise(q, anchor, p));
    // Moved onto the plane; the free directions (x, y) stay at the anchor.
    EXPECT_NEAR(p.z(), 1.0, 1e-6);
    EXPECT_NEAR(p.x(), anchor.x(), 1e-12);
    EXPECT_NEAR(p.y(), anchor.y(), 1e-12);
  }
}

TEST(Quadric, TwoPlanesProjectTheAnchorOntoTheirLine) {
  for (Minimiser minimise : kMinimisers) {
    SCOPED_TRACE(minimise == regularised ? "regularised" : "truncated");
    // A crease along the x axis (y = 0 and z = 0), its two faces folded 90 degrees.
    const Quadric q = plane_through({0, 1, 0}, {0, 0, 0}) + plane_through({0, 0, 1}, {0, 0, 0});
    const Eigen::Vector3d anchor(2.5, 0.3, -0.2);
    Eigen::Vector3d p;
    ASSERT_TRUE(minimise(q, anchor, p));
    EXPECT_LT((p - Eigen::Vector3d(2.5, 0, 0)).norm(), 1e-6);
  }
}

TEST(Quadric, NearlyFlatPlanesBehaveLikeOnePlane) {
  for (Minimiser minimise : kMinimisers) {
    SCOPED_TRACE(minimise == regularised ? "regularised" : "truncated");
    // Two planes 1e-6 rad apart: the tiny eigenvalue must not throw the point along their line.
    const Quadric q = plane_through({0, 0, 1}, {0, 0, 0}) + plane_through({0, 1e-6, 1}, {0, 0, 0});
    const Eigen::Vector3d anchor(1, 2, 0.5);
    Eigen::Vector3d p;
    ASSERT_TRUE(minimise(q, anchor, p));
    EXPECT_LT(std::abs(p.z()), 1e-6);
    EXPECT_LT((p.head<2>() - anchor.head<2>()).norm(), 1e-3);
  }
}

TEST(Quadric, NoPlanesConstrainNothing) {
  for (Minimiser minimise : kMinimisers) {
    SCOPED_TRACE(minimise == regularised ? "regularised" : "truncated");
    Eigen::Vector3d p;
    EXPECT_FALSE(minimise(Quadric{}, {1, 2, 3}, p));
  }
}

}  // namespace
}  // namespace lodkit::detail
