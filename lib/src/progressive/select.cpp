// Choosing a level: by face count, by object-space error, or by what a viewer can see.
#include <lodkit/error.h>
#include <lodkit/progressive.h>

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <iterator>
#include <limits>
#include <numbers>

namespace lodkit {

double bounding_radius(const ProgressiveMesh& pm) {
  return pm.bounds.isEmpty() ? 0.0 : 0.5 * pm.bounds.diagonal().norm();
}

namespace {

// The object-space length that one pixel spans at the nearest point of the bounding sphere; 0 when the
// eye is inside it.
double length_per_pixel(double radius, const ScreenSpaceBudget& view) {
  if (!(view.fov_degrees > 0 && view.fov_degrees < 180))
    throw Error(fmt::format("screen-space budget: field of view must be in (0, 180) degrees, got {}", view.fov_degrees));
  if (!(view.viewport_pixels > 0))
    throw Error(fmt::format("screen-space budget: viewport height must be positive, got {}", view.viewport_pixels));
  if (!std::isfinite(view.distance)) throw Error("screen-space budget: distance must be finite");
  const double d = view.distance - radius;
  if (!(d > 0)) return 0.0;
  return 2.0 * d * std::tan(0.5 * view.fov_degrees * std::numbers::pi / 180.0) / view.viewport_pixels;
}

}  // namespace

double projected_pixels(double error, double radius, const ScreenSpaceBudget& view) {
  const double length = length_per_pixel(radius, view);
  if (!(length > 0)) return error > 0 ? std::numeric_limits<double>::infinity() : 0.0;
  return error / length;
}

double object_error_for_pixels(double radius, const ScreenSpaceBudget& view) {
  if (!(view.pixel_error >= 0) || !std::isfinite(view.pixel_error))
    throw Error(fmt::format("screen-space budget: pixel error must be finite and not negative, got {}", view.pixel_error));
  return view.pixel_error * length_per_pixel(radius, view);
}

Index level_for_faces(const ProgressiveMesh& pm, Index faces) {
  // Face counts grow with the level: binary search for the last level with at most `faces`.
  Index lo = 0, hi = pm.max_level();
  if (pm.num_faces(0) > faces) return 0;
  while (lo < hi) {
    const Index mid = lo + (hi - lo + 1) / 2;
    if (pm.num_faces(mid) <= faces) lo = mid;
    else hi = mid - 1;
  }
  return lo;
}

double level_error(const ProgressiveMesh& pm, Index level, LevelErrorKind kind) {
  const double bound = pm.level_error[static_cast<std::size_t>(level)];
  if (kind == LevelErrorKind::Bound || pm.measured.empty()) return bound;
  // The last measurement at or below `level`; before the first one, nothing better than the bound.
  const auto after = std::upper_bound(pm.measured.begin(), pm.measured.end(), level,
                                      [](Index l, const LevelMeasurement& m) { return l < m.level; });
  return after == pm.measured.begin() ? bound : std::min(bound, std::prev(after)->hausdorff);
}

Index level_for_error(const ProgressiveMesh& pm, double max_error, LevelErrorKind kind) {
  if (!(max_error >= 0)) throw Error(fmt::format("progressive mesh: error budget must not be negative, got {}", max_error));
  // Errors do not increase with the level: the first level within budget is the coarsest.
  for (Index level = 0; level <= pm.max_level(); ++level)
    if (level_error(pm, level, kind) <= max_error) return level;
  return pm.max_level();
}

Index level_for_view(const ProgressiveMesh& pm, const ScreenSpaceBudget& view, LevelErrorKind kind) {
  if (!(view.pixel_error >= 0)) throw Error(fmt::format("screen-space budget: pixel error must not be negative, got {}", view.pixel_error));
  const double radius = bounding_radius(pm);
  for (Index level = 0; level <= pm.max_level(); ++level)
    if (projected_pixels(level_error(pm, level, kind), radius, view) <= view.pixel_error) return level;
  return pm.max_level();
}

void validate(const ProgressiveMesh& pm, const std::string& context) {
  auto fail = [&](const std::string& what) { throw Error(fmt::format("{}: {}", context, what)); };
  const std::size_t nw = pm.wedge_point.size(), nf = pm.face_corners.size();
  const std::size_t dims = static_cast<std::size_t>(pm.attribute_dims);
  if (pm.base_points < 0 || pm.base_wedges < 0 || pm.base_faces < 0) fail("negative base counts");
  if (pm.base_positions.size() != static_cast<std::size_t>(pm.base_points)) fail("base positions do not match the base point count");
  if (pm.wedge_parent.size() != nw || pm.wedge_attributes.size() != dims * nw) fail("per-wedge arrays differ in length");
  if (pm.level_error.size() != pm.splits.size() + 1) fail("one error bound per level is needed");
  if (static_cast<std::size_t>(pm.num_wedges(pm.max_level())) != nw || static_cast<std::size_t>(pm.num_faces(pm.max_level())) != nf)
    fail("the last split does not end at the wedge and face counts");
  // As for any mesh: squares of coordinates past a float's range overflow every distance.
  for (Index p = 0; p < pm.base_points; ++p)
    if (!within_coordinate_range(pm.base_positions[static_cast<std::size_t>(p)]))
      fail(fmt::format("base point {} lies beyond the range of a float (or is not finite)", p));
  for (std::size_t j = 0; j < pm.splits.size(); ++j)
    for (const Eigen::Vector3d& p : {pm.splits[j].position, pm.splits[j].coarse_position, pm.splits[j].new_position})
      if (!within_coordinate_range(p)) fail(fmt::format("split {} places a point beyond the range of a float (or not finite)", j));
  for (Index w = 0; w < pm.base_wedges; ++w)
    if (pm.wedge_point[w] < 0 || pm.wedge_point[w] >= pm.base_points) fail(fmt::format("base wedge {} has no base point", w));
  for (Index f = 0; f < pm.base_faces; ++f)
    for (Index w : pm.face_corners[f])
      if (w < 0 || w >= pm.base_wedges) fail(fmt::format("base face {} uses wedge {} outside the base", f, w));
  for (std::size_t j = 0; j < pm.splits.size(); ++j) {
    const VertexSplit& s = pm.splits[j];
    const Index level = static_cast<Index>(j), t = pm.base_points + level;
    if (s.point < 0 || s.point >= t) fail(fmt::format("split {} splits point {}, which does not exist yet", j, s.point));
    if (s.first_wedge != pm.num_wedges(level) || s.first_face != pm.num_faces(level) || s.num_wedges < 0 || s.num_faces < 0)
      fail(fmt::format("split {} does not continue the wedge and face numbering", j));
    const Index wedges = pm.num_wedges(level + 1), faces = pm.num_faces(level + 1);
    if (static_cast<std::size_t>(wedges) > nw || static_cast<std::size_t>(faces) > nf) fail(fmt::format("split {} runs past the end", j));
    for (Index w = s.first_wedge; w < wedges; ++w)
      if (pm.wedge_point[w] != t || pm.wedge_parent[w] < -1 || pm.wedge_parent[w] >= s.first_wedge)
        fail(fmt::format("split {}: wedge {} belongs elsewhere", j, w));
    for (Index f = s.first_face; f < faces; ++f)
      for (Index w : pm.face_corners[f])
        if (w < 0 || w >= wedges) fail(fmt::format("split {}: face {} uses a wedge outside the level", j, f));
    if (s.first_change < 0 || s.num_changes < 0 ||
        static_cast<std::size_t>(s.first_change) + static_cast<std::size_t>(s.num_changes) > pm.corner_changes.size())
      fail(fmt::format("split {}: corner changes out of range", j));
    for (Index i = 0; i < s.num_changes; ++i) {
      const CornerChange& c = pm.corner_changes[static_cast<std::size_t>(s.first_change + i)];
      if (c.corner < 0 || c.corner >= 3 * faces || c.coarse_wedge < 0 || c.coarse_wedge >= s.first_wedge ||
          c.fine_wedge < s.first_wedge || c.fine_wedge >= wedges || pm.wedge_point[c.coarse_wedge] != s.point)
        fail(fmt::format("split {}: an invalid corner change", j));
    }
    if (s.first_attribute_change < 0 || s.num_attribute_changes < 0 ||
        static_cast<std::size_t>(s.first_attribute_change) + static_cast<std::size_t>(s.num_attribute_changes) > pm.attribute_changes.size())
      fail(fmt::format("split {}: attribute changes out of range", j));
    for (Index i = 0; i < s.num_attribute_changes; ++i) {
      const AttributeChange& a = pm.attribute_changes[static_cast<std::size_t>(s.first_attribute_change + i)];
      if (a.wedge < 0 || a.wedge >= wedges || a.first_value < 0 ||
          static_cast<std::size_t>(a.first_value) + 2 * dims > pm.attribute_values.size())
        fail(fmt::format("split {}: an invalid attribute change", j));
    }
  }
  for (std::size_t i = 0; i < pm.measured.size(); ++i) {
    const LevelMeasurement& m = pm.measured[i];
    if (m.level < 0 || m.level > pm.max_level() || (i > 0 && m.level <= pm.measured[i - 1].level))
      fail(fmt::format("measured level {} is out of order or range", m.level));
    if (!(m.hausdorff >= 0 && m.rms >= 0 && std::isfinite(m.hausdorff) && std::isfinite(m.rms)))
      fail(fmt::format("measured level {} has an invalid distance", m.level));
  }
  if (pm.knows_input_order() && (pm.wedge_input.size() != nw || pm.face_input.size() != nf))
    fail("the input order does not cover every wedge and face");
}

}  // namespace lodkit
