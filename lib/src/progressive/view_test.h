#pragma once
// A view's tests of selective refinement's regions (in the view cone, facing away, the pixels an error
// projects to) and the splits a view needs, shared by SelectiveRefiner and SelectiveMesh.
#include <lodkit/error.h>
#include <lodkit/progressive.h>

#include <cmath>
#include <fmt/format.h>
#include <numbers>
#include <string>
#include <vector>

#include "core/geometry.h"

namespace lodkit {
namespace detail {

// What a screen-space budget does not check itself (its field of view, viewport and pixel error are
// checked where the budget is used).
inline void check_viewpoint(const Viewpoint& v) {
  auto fail = [](const std::string& what) { throw Error("selective refinement: " + what); };
  if (!v.eye.allFinite() || !v.look_at.allFinite()) fail("the eye and the point looked at must be finite");
  if (v.cull && !((v.look_at - v.eye).norm() > 0)) fail("the point looked at must differ from the eye");
  if (!std::isfinite(v.viewport_pixels)) fail(fmt::format("viewport height must be positive, got {}", v.viewport_pixels));
  if (!(v.aspect > 0) || !std::isfinite(v.aspect)) fail(fmt::format("aspect ratio must be positive, got {}", v.aspect));
}

}  // namespace detail

// A view's tests of a region: in the view cone, facing away, and the pixels its error projects to.
struct SelectiveRefiner::ViewTest {
  ViewTest(const SelectiveRefiner& refiner, const Viewpoint& view, LevelErrorKind by)
      : r(refiner),
        v(view),
        kind(by),
        error(by == LevelErrorKind::Bound ? refiner.error_ : refiner.deviation_),
        reach_error(by == LevelErrorKind::Bound ? refiner.reach_bound_ : refiner.reach_deviation_) {
    detail::check_viewpoint(view);
    // Pixels per unit of error one unit from the eye (projected_pixels() checks the budget); a region's
    // error projects to that over its distance (error * H / (2 d tan(fov / 2))).
    const ScreenSpaceBudget budget{view.pixel_error, 1.0, view.fov_degrees, view.viewport_pixels};
    (void)object_error_for_pixels(0.0, budget);  // checks the pixel error
    per_unit = projected_pixels(1.0, 0.0, budget);
    const double tan_half = std::tan(0.5 * view.fov_degrees * std::numbers::pi / 180.0);
    // The cone around the frustum: its half-angle reaches the viewport's corners.
    const double cone = std::atan(tan_half * std::sqrt(1.0 + view.aspect * view.aspect));
    cone_cos = std::cos(cone), cone_sin = std::sin(cone);
    if (view.cull) axis = (view.look_at - view.eye).normalized();
  }

  // Where split j's region lies from the eye: the distance to its centre, the lower bound on the
  // distance to the view cone (p cos - a sin; exact beside its side), and its normals' angle.
  struct Seen {
    double distance, off_cone, phi;
  };
  Seen seen(std::size_t j) const {
    const Eigen::Vector3d d = r.centre_[j] - v.eye;
    Seen s{d.norm(), -INFINITY, 0.0};
    if (v.cull) {
      const double along = d.dot(axis), across = (d - along * axis).norm();
      s.off_cone = across * cone_cos - along * cone_sin;
    }
    if (v.cull_backfaces) s.phi = detail::direction_angle(r.cone_axis_[j], d);
    return s;
  }
  // The tests of a ball of this radius around the centre, with the normals' cone and an error there.
  // Each grows with the ball, so that of the ball holding every region below a split answers for all.
  bool in_view(const Seen& s, double radius) const { return s.off_cone <= radius; }
  // Facing away (Hoppe 1997, section 4.2): from every point of the ball, every normal of the cone
  // points away from the eye. With u the eye to the centre and phi its angle to the cone's axis, the
  // smallest (p - eye) . n is at least |u| cos(phi + half-angle) - radius. (A region's cone holds those
  // below it.)
  bool facing_away(const Seen& s, double radius, double half_angle) const {
    return v.cull_backfaces && s.distance > 0 && half_angle >= 0 && s.phi + half_angle < 0.5 * std::numbers::pi &&
           s.distance * std::cos(s.phi + half_angle) > radius;
  }
  double pixels(const Seen& s, double radius, double error_there) const {
    const double d = s.distance - radius;
    if (!(d > 0)) return error_there > 0 ? INFINITY : 0.0;
    return error_there * per_unit / d;
  }
  bool needs(const Seen& s, double radius, double error_there, double half_angle) const {
    return in_view(s, radius) && !facing_away(s, radius, half_angle) && pixels(s, radius, error_there) > v.pixel_error;
  }
  bool needs(std::size_t j) const { return needs(seen(j), r.radius_[j], error[j], r.cone_half_angle_[j]); }

  // The splits whose regions need refining, and their dependencies: down the hierarchy from the base
  // points, looking below a split only where a region there can need it (its reach, padded past
  // rounding). In stream order, where what is looked at lies in memory.
  std::vector<char> wanted() const {
    const ProgressiveMesh& pm = *r.pm_;
    const std::size_t n = pm.splits.size();
    std::vector<char> out(n, 0), look(n, 0);
    for (Index p = 0; p < pm.base_points; ++p)
      if (const Index j = r.first_at_point_[static_cast<std::size_t>(p)]; j >= 0) look[static_cast<std::size_t>(j)] = 1;
    for (std::size_t j = 0; j < n; ++j) {
      if (!look[j]) continue;
      const Seen s = seen(j);
      out[j] = needs(s, r.radius_[j], error[j], r.cone_half_angle_[j]);
      if (!out[j] && !needs(s, r.reach_radius_[j], reach_error[j], r.cone_half_angle_[j] + 1e-9)) continue;
      for (Index k : r.below(static_cast<Index>(j)))
        if (k >= 0) look[static_cast<std::size_t>(k)] = 1;
    }
    r.close(out);
    return out;
  }

  const SelectiveRefiner& r;
  const Viewpoint& v;
  LevelErrorKind kind;
  const std::vector<double>& error;
  const std::vector<double>& reach_error;  // the largest at or below each split
  double per_unit = 0, cone_cos = 1, cone_sin = 0;
  Eigen::Vector3d axis = Eigen::Vector3d::Zero();
};

}  // namespace lodkit
