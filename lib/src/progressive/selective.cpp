// Selective refinement: any dependency-closed set of splits, applied in stream order.
//
// Why the dependencies make it valid: split j rewrites only the faces around its point s (corners move
// to the new point t, two faces open along s-l and s-r). Its dependencies are the splits that created s
// and every split that created or changed a face around s in level j - 1. Closed under dependencies,
// a set holds every split that ever touched those faces (each such split depends on the one before
// it), among them every earlier split of s (the last one's faces are still around s), so in the
// selective mesh s has exactly the faces, with exactly the corners, it has in level j - 1, and the
// split does there what it does in the uniform sequence. Positions elsewhere may be coarser, so a face
// can fold where a uniform level would not; the topology is always the input's.
#include <lodkit/error.h>
#include <lodkit/progressive.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fmt/format.h>
#include <numbers>

#include "core/geometry.h"
#include "progressive/split_state.h"

namespace lodkit {
namespace {

// Whether any of the eight flags from `at` is set.
bool any_set(const char* at) {
  std::uint64_t word;
  std::memcpy(&word, at, 8);
  return word != 0;
}

// Removes one occurrence of f from the list, if there.
void erase_one(std::vector<Index>& list, Index f) {
  if (const auto it = std::find(list.begin(), list.end(), f); it != list.end()) {
    *it = list.back();
    list.pop_back();
  }
}

// The largest distance from `points` to the nearest of `triangles` (corner positions, three per triangle).
double farthest_from(const std::vector<Eigen::Vector3d>& points, const std::vector<Eigen::Vector3d>& triangles) {
  double farthest = 0;
  for (const Eigen::Vector3d& x : points) {
    double nearest = INFINITY;
    // A point already within the farthest so far cannot raise it: stop looking.
    for (std::size_t i = 0; i < triangles.size() && nearest > farthest; i += 3)
      nearest = std::min(nearest, (detail::closest_point_on_triangle(x, triangles[i], triangles[i + 1], triangles[i + 2]) - x).squaredNorm());
    if (std::isfinite(nearest)) farthest = std::max(farthest, nearest);
  }
  return std::sqrt(farthest);
}

constexpr std::size_t kMostSampledFaces = 64;

// What a screen-space budget does not check itself (its field of view, viewport and pixel error are
// checked where the budget is used).
void check_view(const Viewpoint& v) {
  auto fail = [](const std::string& what) { throw Error("selective refinement: " + what); };
  if (!v.eye.allFinite() || !v.look_at.allFinite()) fail("the eye and the point looked at must be finite");
  if (v.cull && !((v.look_at - v.eye).norm() > 0)) fail("the point looked at must differ from the eye");
  if (!std::isfinite(v.viewport_pixels)) fail(fmt::format("viewport height must be positive, got {}", v.viewport_pixels));
  if (!(v.aspect > 0) || !std::isfinite(v.aspect)) fail(fmt::format("aspect ratio must be positive, got {}", v.aspect));
}

// What walking the uniform sequence finds: each split's dependencies (CSR), the last earlier split of
// its point, and its local deviation.
struct UniformWalk {
  std::vector<Index> start, dependencies, previous_at_point;
  std::vector<double> local;  // the distance between s's faces before and after the split, at samples
  std::vector<detail::NormalCone> cone;  // the normals of s's faces before and after the split
};

// A point's faces (three corners each) and, when asked, samples on them: the point, its edges'
// midpoints (each once) and the faces' centroids.
void star(const detail::SplitState& state, const ProgressiveMesh& pm, const std::vector<Index>& faces, Index point,
          std::vector<Eigen::Vector3d>& triangles, std::vector<Eigen::Vector3d>* samples) {
  const Eigen::Vector3d& at = state.positions[static_cast<std::size_t>(point)];
  if (samples) samples->push_back(at);
  std::vector<Index> ends;  // the points whose edge to `point` has its midpoint sampled
  for (Index f : faces) {
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k) {
      const Index corner = state.corners[3 * static_cast<std::size_t>(f) + k];
      const Index end = pm.wedge_point[static_cast<std::size_t>(corner)];
      const Eigen::Vector3d& x = state.positions[static_cast<std::size_t>(end)];
      triangles.push_back(x);
      centroid += x / 3.0;
      // Two faces share each edge, and the point's own corner has no edge.
      if (!samples || end == point || std::find(ends.begin(), ends.end(), end) != ends.end()) continue;
      ends.push_back(end);
      samples->push_back(0.5 * (x + at));
    }
    if (samples) samples->push_back(centroid);
  }
}

// The cone of the faces' normals (unit axis, half-angle): around their mean direction, wide enough for
// the farthest; the whole sphere when they cancel out. Faces without area have no normal.
detail::NormalCone normal_cone(const std::vector<Eigen::Vector3d>& triangles) {
  std::vector<Eigen::Vector3d> normals;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < triangles.size(); i += 3) {
    const Eigen::Vector3d n = (triangles[i + 1] - triangles[i]).cross(triangles[i + 2] - triangles[i]);
    if (!(n.norm() > 0)) continue;
    normals.push_back(n.normalized());
    sum += normals.back();
  }
  if (normals.empty()) return {Eigen::Vector3d::UnitZ(), -1.0};  // empty: any cone holds it
  if (!(sum.norm() > 1e-9 * double(normals.size()))) return {Eigen::Vector3d::UnitZ(), std::numbers::pi};
  const Eigen::Vector3d axis = sum.normalized();
  double widest = 0;
  for (const Eigen::Vector3d& n : normals) widest = std::max(widest, detail::direction_angle(n, axis));
  return {axis, widest};
}

// Replays every split in order, keeping each point's faces and each face's last split.
UniformWalk walk_uniform_sequence(const ProgressiveMesh& pm) {
  const std::size_t n = pm.splits.size();
  const std::size_t points = static_cast<std::size_t>(pm.num_points(pm.max_level()));
  auto point_of = [&](Index wedge) { return pm.wedge_point[static_cast<std::size_t>(wedge)]; };
  UniformWalk walk;
  walk.start.assign(n + 1, 0);
  walk.previous_at_point.assign(n, -1);
  walk.local.assign(n, 0.0);
  walk.cone.resize(n);
  detail::SplitState state = detail::base_state(pm);
  std::vector<std::vector<Index>> faces_at(points);
  std::vector<Index> stamp(pm.face_corners.size(), -1), last_at_point(points, -1);
  auto add_face = [&](Index f) {
    for (int k = 0; k < 3; ++k)
      faces_at[static_cast<std::size_t>(point_of(state.corners[3 * static_cast<std::size_t>(f) + k]))].push_back(f);
  };
  for (Index f = 0; f < pm.base_faces; ++f) add_face(f);
  std::vector<Index> found;
  std::vector<Eigen::Vector3d> coarse_triangles, coarse_samples, fine_triangles, fine_samples;
  const double rounding = 1e-12 * bounding_radius(pm);
  for (std::size_t j = 0; j < n; ++j) {
    const VertexSplit& split = pm.splits[j];
    const std::size_t s = static_cast<std::size_t>(split.point);
    const Index t = pm.base_points + static_cast<Index>(j);
    found.clear();
    if (split.point >= pm.base_points) found.push_back(split.point - pm.base_points);  // s's own split
    for (Index f : faces_at[s])
      if (stamp[static_cast<std::size_t>(f)] >= 0) found.push_back(stamp[static_cast<std::size_t>(f)]);
    std::sort(found.begin(), found.end());
    found.erase(std::unique(found.begin(), found.end()), found.end());
    walk.dependencies.insert(walk.dependencies.end(), found.begin(), found.end());
    walk.start[j + 1] = static_cast<Index>(walk.dependencies.size());
    walk.previous_at_point[j] = last_at_point[s];
    last_at_point[s] = static_cast<Index>(j);

    // Samples against triangles cost the square of the point's valence: past kMostSampledFaces, the
    // farthest any vertex moves instead (cheap, and no less than the distance between the stars).
    const bool sampled = faces_at[s].size() <= kMostSampledFaces;
    coarse_triangles.clear(), coarse_samples.clear(), fine_triangles.clear(), fine_samples.clear();
    star(state, pm, faces_at[s], split.point, coarse_triangles, sampled ? &coarse_samples : nullptr);

    // The split itself: corners that move to another point take their face along.
    const CornerChange* c = pm.corner_changes.data() + split.first_change;
    for (Index i = 0; i < split.num_changes; ++i) {
      const std::size_t corner = static_cast<std::size_t>(c[i].corner);
      const Index f = static_cast<Index>(corner / 3), from = point_of(state.corners[corner]), to = point_of(c[i].fine_wedge);
      state.corners[corner] = c[i].fine_wedge;
      stamp[corner / 3] = static_cast<Index>(j);
      if (from == to) continue;
      erase_one(faces_at[static_cast<std::size_t>(from)], f);
      faces_at[static_cast<std::size_t>(to)].push_back(f);
    }
    for (Index f = split.first_face; f < split.first_face + split.num_faces; ++f) {
      add_face(f);
      stamp[static_cast<std::size_t>(f)] = static_cast<Index>(j);
    }
    state.positions[s] = split.position;

    star(state, pm, faces_at[s], split.point, fine_triangles, sampled ? &fine_samples : nullptr);
    star(state, pm, faces_at[static_cast<std::size_t>(t)], t, fine_triangles, sampled ? &fine_samples : nullptr);
    walk.cone[j] = detail::enclosing_cone(normal_cone(coarse_triangles), normal_cone(fine_triangles));
    double& local = walk.local[j];
    if (sampled) {
      local = std::max(farthest_from(fine_samples, coarse_triangles), farthest_from(coarse_samples, fine_triangles));
    } else {
      local = std::max((split.position - split.coarse_position).norm(), (split.new_position - split.coarse_position).norm());
    }
    if (local <= rounding) local = 0;  // a split within a plane (else an eye inside its ball refines it)
  }
  return walk;
}

}  // namespace

SelectiveRefiner::SelectiveRefiner(const ProgressiveMesh& pm) : pm_(&pm) {
  validate(pm);
  const std::size_t n = pm.splits.size();
  const std::size_t points = static_cast<std::size_t>(pm.num_points(pm.max_level()));
  // A stream read in part ends above the input: what its last level is from the input adds to every
  // region's error (a distance to the input is within that to the last level plus theirs apart).
  beyond_bound_ = pm.level_error.back();
  beyond_deviation_ = level_error(pm, pm.max_level(), LevelErrorKind::Measured);
  UniformWalk walk = walk_uniform_sequence(pm);
  dependency_start_ = std::move(walk.start);
  dependencies_ = std::move(walk.dependencies);

  // Regions, from the finest level up: the ball of a point before split j holds its balls after the
  // split and the new point's.
  std::vector<detail::Ball> ball(points);
  for (std::size_t p = 0; p < points; ++p) ball[p] = {p < static_cast<std::size_t>(pm.base_points) ? pm.base_positions[p]
                                                                                                  : pm.splits[p - pm.base_points].new_position, 0.0};
  for (const VertexSplit& split : pm.splits) ball[static_cast<std::size_t>(split.point)].centre = split.position;
  centre_.resize(n);
  radius_.resize(n);
  error_.resize(n);
  for (std::size_t j = n; j-- > 0;) {
    const VertexSplit& split = pm.splits[j];
    detail::Ball& b = ball[static_cast<std::size_t>(split.point)];
    b = detail::enclosing_ball(b, ball[static_cast<std::size_t>(pm.base_points) + j]);
    centre_[j] = b.centre;
    radius_[j] = b.radius;
    error_[j] = (split.coarse_position - b.centre).norm() + b.radius + beyond_bound_;
  }
  // Deviations, from the finest level up: the split's own, plus the larger of what the two points
  // after it deviate by (a distance to a surface within that of the finer one), never past the bound.
  next_at_point_.assign(n, -1);
  first_at_point_.assign(points, -1);
  for (std::size_t j = n; j-- > 0;) {
    if (const Index previous = walk.previous_at_point[j]; previous >= 0) next_at_point_[static_cast<std::size_t>(previous)] = static_cast<Index>(j);
    first_at_point_[static_cast<std::size_t>(pm.splits[j].point)] = static_cast<Index>(j);
  }
  wedge_split_.assign(pm.wedge_point.size(), -1);
  for (std::size_t j = 0; j < n; ++j)
    std::fill_n(wedge_split_.begin() + pm.splits[j].first_wedge, pm.splits[j].num_wedges, static_cast<Index>(j));
  deviation_.resize(n);
  std::vector<detail::NormalCone>& cone = walk.cone;
  for (std::size_t j = n; j-- > 0;) {
    const std::array<Index, 2> after = below(static_cast<Index>(j));
    double finer = 0;
    for (Index k : after)
      if (k >= 0) {
        finer = std::max(finer, deviation_[static_cast<std::size_t>(k)]);
        // The normals of every face the region can show: its own split's and those below.
        cone[j] = detail::enclosing_cone(cone[j], cone[static_cast<std::size_t>(k)]);
      }
    deviation_[j] = std::min(error_[j], walk.local[j] + finer + beyond_deviation_);
  }
  cone_axis_.resize(n);
  cone_half_angle_.resize(n);
  for (std::size_t j = 0; j < n; ++j) cone_axis_[j] = cone[j].axis, cone_half_angle_[j] = cone[j].half_angle;

  // What a view may find below each split, so that it need not look: a ball around the region's centre
  // holding every region below (padded past rounding), and the largest errors there.
  reach_radius_ = radius_;
  reach_bound_ = error_;
  reach_deviation_ = deviation_;
  const double pad = 1e-9 * bounding_radius(pm);
  for (std::size_t j = n; j-- > 0;) {
    for (Index k : below(static_cast<Index>(j)))
      if (k >= 0) {
        const std::size_t i = static_cast<std::size_t>(k);
        reach_radius_[j] = std::max(reach_radius_[j], (centre_[i] - centre_[j]).norm() + reach_radius_[i]);
        reach_bound_[j] = std::max(reach_bound_[j], reach_bound_[i]);
        reach_deviation_[j] = std::max(reach_deviation_[j], reach_deviation_[i]);
      }
    reach_radius_[j] += pad;
  }
}

std::array<Index, 2> SelectiveRefiner::below(Index split) const {
  const std::size_t j = static_cast<std::size_t>(split);
  return {next_at_point_[j], first_at_point_[static_cast<std::size_t>(pm_->base_points) + j]};
}

std::span<const Index> SelectiveRefiner::dependencies(Index split) const {
  const std::size_t j = static_cast<std::size_t>(split);
  return {dependencies_.data() + dependency_start_[j], dependencies_.data() + dependency_start_[j + 1]};
}

void SelectiveRefiner::close(std::vector<char>& wanted) const {
  // Dependencies are earlier: one pass from the last split down closes the set (eight flags at a time
  // where none is set: a view wants few of a large stream's splits).
  for (std::size_t j = wanted.size(); j-- > 0;) {
    if (j >= 7 && (j & 7) == 7 && !any_set(wanted.data() + j - 7)) {
      j -= 7;
      continue;
    }
    if (wanted[j])
      for (Index d : dependencies(static_cast<Index>(j))) wanted[static_cast<std::size_t>(d)] = 1;
  }
}

std::vector<Index> SelectiveRefiner::frontier(const std::vector<char>& applied) const {
  // The splits not applied just below an applied one in the hierarchy, or at its top: a point's first
  // split not applied (its split before, and the one that made it, are).
  std::vector<Index> out;
  for (Index p = 0; p < pm_->base_points; ++p)
    if (const Index j = first_at_point_[static_cast<std::size_t>(p)]; j >= 0 && !applied[static_cast<std::size_t>(j)]) out.push_back(j);
  for (std::size_t j = 0; j < applied.size(); ++j)
    if (applied[j])
      for (Index k : below(static_cast<Index>(j)))
        if (k >= 0 && !applied[static_cast<std::size_t>(k)]) out.push_back(k);
  return out;
}

void SelectiveRefiner::check_size(const std::vector<char>& wanted) const {
  if (wanted.size() != pm_->splits.size())
    throw Error(fmt::format("selective refinement: {} entries given for {} splits", wanted.size(), pm_->splits.size()));
}

SelectiveLevel SelectiveRefiner::refine(std::vector<char> wanted) const {
  check_size(wanted);
  close(wanted);
  return apply_closed(wanted, nullptr);
}

SelectiveLevel SelectiveRefiner::apply_closed(const std::vector<char>& applied, const ViewTest* view) const {
  detail::SplitState state = detail::base_state(*pm_);
  for (std::size_t j = 0; j < applied.size(); ++j)
    if (applied[j]) detail::apply_split(*pm_, static_cast<Index>(j), true, state.positions, state.attributes, state.corners);
  return level_of(state.positions, state.attributes, state.corners, applied, view);
}

SelectiveLevel SelectiveRefiner::level_of(const std::vector<Eigen::Vector3d>& positions, const std::vector<double>& attributes,
                                          const std::vector<Index>& corners, const std::vector<char>& applied,
                                          const ViewTest* view) const {
  const std::vector<Index> coarse = frontier(applied);
  SelectiveLevel out;
  out.extracted = mesh_of(positions, attributes, corners, applied);
  out.splits_applied = out.extracted.level;
  out.error_bound = beyond_bound_, out.deviation = beyond_deviation_;  // where every split is applied
  // The error: at each point, the bound before its first split not applied.
  for (Index j : coarse) {
    out.error_bound = std::max(out.error_bound, error_[static_cast<std::size_t>(j)]);
    out.deviation = std::max(out.deviation, deviation_[static_cast<std::size_t>(j)]);
  }
  if (view) report_view(*view, coarse, out);
  return out;
}

ExtractedLevel SelectiveRefiner::mesh_of(const std::vector<Eigen::Vector3d>& positions, const std::vector<double>& attributes,
                                         const std::vector<Index>& corners, const std::vector<char>& applied) const {
  // Faces by number (the base's, then those each applied split opens), then the wedges they use by number.
  const ProgressiveMesh& pm = *pm_;
  std::vector<Index> faces(static_cast<std::size_t>(pm.base_faces));
  for (Index f = 0; f < pm.base_faces; ++f) faces[static_cast<std::size_t>(f)] = f;
  ExtractedLevel e;
  for (std::size_t j = 0; j < applied.size(); ++j) {
    if (!applied[j]) continue;
    for (Index f = pm.splits[j].first_face; f < pm.splits[j].first_face + pm.splits[j].num_faces; ++f) faces.push_back(f);
    ++e.level;
  }
  const std::size_t wedges = pm.wedge_point.size();
  std::vector<char> used(wedges, 0);
  for (Index f : faces)
    for (int k = 0; k < 3; ++k) used[static_cast<std::size_t>(corners[3 * static_cast<std::size_t>(f) + k])] = 1;
  std::vector<Index> row_of(wedges, -1);
  for (std::size_t w = 0; w < wedges; ++w)
    if (used[w]) row_of[w] = static_cast<Index>(e.vertex_wedge.size()), e.vertex_wedge.push_back(static_cast<Index>(w));
  const Index nv = static_cast<Index>(e.vertex_wedge.size()), nf = static_cast<Index>(faces.size());
  Mesh& m = e.mesh;
  detail::size_level_mesh(pm, nv, nf, m);
  e.vertex_origin = e.vertex_wedge;
  for (Index row = 0; row < nv; ++row) {
    const Index w = e.vertex_wedge[static_cast<std::size_t>(row)];
    detail::put_wedge(pm, positions, attributes, w, m, row);
  }
  for (Index i = 0; i < nf; ++i) {
    const std::size_t f = static_cast<std::size_t>(faces[static_cast<std::size_t>(i)]);
    for (int k = 0; k < 3; ++k) m.triangles(i, k) = row_of[static_cast<std::size_t>(corners[3 * f + k])];
    if (pm.has_face_colours) m.attributes.face_colours.row(i) = pm.face_colours.row(static_cast<Index>(f));
  }
  return e;
}

Index SelectiveRefiner::ancestor(Index wedge, const std::vector<char>& applied) const {
  for (Index j; (j = wedge_split_[static_cast<std::size_t>(wedge)]) >= 0 && !applied[static_cast<std::size_t>(j)];)
    wedge = pm_->wedge_parent[static_cast<std::size_t>(wedge)];
  return wedge;
}

// A view's tests of a region: in the view cone, facing away, and the pixels its error projects to.
struct SelectiveRefiner::ViewTest {
  ViewTest(const SelectiveRefiner& refiner, const Viewpoint& view, LevelErrorKind by)
      : r(refiner),
        v(view),
        kind(by),
        error(by == LevelErrorKind::Bound ? refiner.error_ : refiner.deviation_),
        reach_error(by == LevelErrorKind::Bound ? refiner.reach_bound_ : refiner.reach_deviation_) {
    check_view(view);
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

std::vector<char> SelectiveRefiner::splits_for_view(const Viewpoint& view, LevelErrorKind kind) const {
  return ViewTest(*this, view, kind).wanted();
}

std::vector<char> SelectiveRefiner::regions_needing_refinement(const Viewpoint& view, LevelErrorKind kind) const {
  const ViewTest test(*this, view, kind);
  std::vector<char> out(pm_->splits.size(), 0);
  for (std::size_t j = 0; j < out.size(); ++j) out[j] = test.needs(j);
  return out;
}

void SelectiveRefiner::report_view(const ViewTest& test, const std::vector<Index>& coarse, SelectiveLevel& out) const {
  // What the viewer sees: the regions left coarse, each at its point's first split not applied.
  for (Index j : coarse) {
    const std::size_t i = static_cast<std::size_t>(j);
    const ViewTest::Seen seen = test.seen(i);
    const double radius = radius_[i];
    if (!test.in_view(seen, radius)) ++out.regions_outside;
    else if (test.facing_away(seen, radius, cone_half_angle_[i])) ++out.regions_facing_away;
    else out.max_pixels = std::max(out.max_pixels, test.pixels(seen, radius, test.error[i]));
  }
  // A stream read in part: where every split is applied, its last level's error, at the nearest.
  const Viewpoint& view = test.v;
  const double beyond = test.kind == LevelErrorKind::Bound ? beyond_bound_ : beyond_deviation_;
  if (beyond > 0) {
    const ScreenSpaceBudget whole{view.pixel_error, (pm_->bounds.center() - view.eye).norm(), view.fov_degrees, view.viewport_pixels};
    out.max_pixels = std::max(out.max_pixels, projected_pixels(beyond, bounding_radius(*pm_), whole));
  }
}

SelectiveLevel SelectiveRefiner::refine_for_view(const Viewpoint& view, LevelErrorKind kind) const {
  const ViewTest test(*this, view, kind);
  return apply_closed(test.wanted(), &test);
}

SelectiveMesh::SelectiveMesh(const SelectiveRefiner& refiner) : refiner_(&refiner) {
  detail::SplitState base = detail::base_state(*refiner.pm_);
  positions_ = std::move(base.positions);
  attributes_ = std::move(base.attributes);
  corners_ = std::move(base.corners);
  applied_.assign(refiner.pm_->splits.size(), 0);
}

SelectiveMesh::Change SelectiveMesh::change_to(const std::vector<char>& wanted) const {
  // A step's few splits (skipped eight at a time where none changes).
  Change c;
  const std::size_t n = applied_.size();
  for (std::size_t j = 0; j < n; ++j) {
    if ((j & 7) == 0 && j + 8 <= n && std::memcmp(applied_.data() + j, wanted.data() + j, 8) == 0) {
      j += 7;
      continue;
    }
    if (applied_[j] != wanted[j]) (applied_[j] ? c.undo : c.redo).push_back(static_cast<Index>(j));
  }
  return c;
}

// Undone from the last: a later split left applied depends on none of these (the set stays closed), so
// each one's faces hold just what it wrote. New ones are applied in order, as refine() applies them.
void SelectiveMesh::undo(const std::vector<Index>& splits) {
  for (auto j = splits.rbegin(); j != splits.rend(); ++j) {
    detail::apply_split(*refiner_->pm_, *j, false, positions_, attributes_, corners_);
    applied_[static_cast<std::size_t>(*j)] = 0;
  }
}

void SelectiveMesh::redo(const std::vector<Index>& splits) {
  for (Index j : splits) {
    detail::apply_split(*refiner_->pm_, j, true, positions_, attributes_, corners_);
    applied_[static_cast<std::size_t>(j)] = 1;
  }
}

SelectiveLevel SelectiveMesh::move_to(const std::vector<char>& wanted, const SelectiveRefiner::ViewTest* view) {
  const Change c = change_to(wanted);
  undo(c.undo);
  redo(c.redo);
  SelectiveLevel out = refiner_->level_of(positions_, attributes_, corners_, applied_, view);
  out.splits_refined = static_cast<Index>(c.redo.size()), out.splits_coarsened = static_cast<Index>(c.undo.size());
  return out;
}

SelectiveMorph SelectiveMesh::morph(const std::vector<char>& wanted, const SelectiveRefiner::ViewTest* view) {
  // Through the union of both sets (closed, as both are): its connectivity, with each vertex's ancestor
  // in the set before (read from the arrays as they were) and in the new set (once it is reached).
  const ProgressiveMesh& pm = *refiner_->pm_;
  const Change c = change_to(wanted);
  const std::vector<char> before = applied_;
  const std::vector<Eigen::Vector3d> positions_before = positions_;
  const std::vector<double> attributes_before = attributes_;
  redo(c.redo);
  SelectiveMorph out;
  Geomorph& g = out.geomorph;
  g.fine = refiner_->mesh_of(positions_, attributes_, corners_, applied_);
  undo(c.undo);
  out.reached = refiner_->level_of(positions_, attributes_, corners_, applied_, view);
  out.reached.splits_refined = static_cast<Index>(c.redo.size()), out.reached.splits_coarsened = static_cast<Index>(c.undo.size());
  g.coarse_level = static_cast<Index>(std::count(before.begin(), before.end(), 1));
  g.fine_level = out.reached.splits_applied;

  Mesh& end = g.fine.mesh;
  Mesh start;
  detail::size_level_mesh(pm, end.num_vertices(), 0, start);
  for (Index row = 0; row < end.num_vertices(); ++row) {
    const Index w = g.fine.vertex_wedge[static_cast<std::size_t>(row)];
    detail::put_wedge(pm, positions_before, attributes_before, refiner_->ancestor(w, before), start, row);
    detail::put_wedge(pm, positions_, attributes_, refiner_->ancestor(w, applied_), end, row);
  }
  g.start_positions = std::move(start.positions);
  g.start_normals = std::move(start.attributes.normals);
  g.start_uvs = std::move(start.attributes.uvs);
  g.start_colours = std::move(start.attributes.colours);
  return out;
}

SelectiveLevel SelectiveMesh::go_to(std::vector<char> wanted) {
  refiner_->check_size(wanted);
  refiner_->close(wanted);
  return move_to(wanted, nullptr);
}

SelectiveLevel SelectiveMesh::adapt(const Viewpoint& view, LevelErrorKind kind) {
  const SelectiveRefiner::ViewTest test(*refiner_, view, kind);
  return move_to(test.wanted(), &test);
}

SelectiveMorph SelectiveMesh::morph_to(std::vector<char> wanted) {
  refiner_->check_size(wanted);
  refiner_->close(wanted);
  return morph(wanted, nullptr);
}

SelectiveMorph SelectiveMesh::morph_to_view(const Viewpoint& view, LevelErrorKind kind) {
  const SelectiveRefiner::ViewTest test(*refiner_, view, kind);
  return morph(test.wanted(), &test);
}

}  // namespace lodkit
