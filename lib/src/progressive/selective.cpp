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
#include "metrics/aabb_tree.h"
#include "progressive/split_state.h"
#include "progressive/view_test.h"

namespace lodkit {

// The input (the finest level) and its tree, readied to tell which way the face nearest a point faces.
struct SelectiveRefiner::InputFacing {
  Mesh mesh;
  detail::AabbTree tree;  // over `mesh`, which it refers to
  explicit InputFacing(Mesh input) : mesh(std::move(input)), tree(mesh, {.copy_corners = false}) { tree.prepare_facing(); }
};

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

// What walking the uniform sequence finds: each split's dependencies (CSR), the last earlier split of
// its point, and its local deviation.
struct UniformWalk {
  std::vector<Index> start, dependencies, previous_at_point;
  std::vector<double> local;  // the distance between s's faces before and after the split, at samples
  std::vector<detail::NormalCone> cone;  // the normals of s's faces before and after the split
  Mesh input;  // the finest level: a vertex per point, faces numbered as the stream's
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
  walk.input.positions.resize(static_cast<Index>(points), 3);
  for (std::size_t p = 0; p < points; ++p) walk.input.positions.row(static_cast<Index>(p)) = state.positions[p].transpose();
  walk.input.triangles.resize(static_cast<Index>(pm.face_corners.size()), 3);
  for (std::size_t f = 0; f < pm.face_corners.size(); ++f)
    for (int k = 0; k < 3; ++k) walk.input.triangles(static_cast<Index>(f), k) = point_of(state.corners[3 * f + static_cast<std::size_t>(k)]);
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
  previous_at_point_ = std::move(walk.previous_at_point);
  // Which split makes each wedge and opens each face, and each point's wedges (for kept meshes).
  wedge_split_.assign(pm.wedge_point.size(), -1);
  face_split_.assign(pm.face_corners.size(), -1);
  for (std::size_t j = 0; j < n; ++j) {
    std::fill_n(wedge_split_.begin() + pm.splits[j].first_wedge, pm.splits[j].num_wedges, static_cast<Index>(j));
    std::fill_n(face_split_.begin() + pm.splits[j].first_face, pm.splits[j].num_faces, static_cast<Index>(j));
  }
  point_wedge_start_.assign(points + 1, 0);
  for (Index p : pm.wedge_point) ++point_wedge_start_[static_cast<std::size_t>(p) + 1];
  for (std::size_t p = 0; p < points; ++p) point_wedge_start_[p + 1] += point_wedge_start_[p];
  point_wedges_.resize(pm.wedge_point.size());
  std::vector<Index> next(point_wedge_start_.begin(), point_wedge_start_.end() - 1);
  for (std::size_t w = 0; w < pm.wedge_point.size(); ++w)
    point_wedges_[static_cast<std::size_t>(next[static_cast<std::size_t>(pm.wedge_point[w])]++)] = static_cast<Index>(w);
  // The faces ever with a corner at each point: those it starts with and those a split moves to or
  // from it (a face's corners change only so), for finding the faces a split can fold.
  input_ = std::make_shared<const InputFacing>(std::move(walk.input));
  {
    std::vector<std::pair<Index, Index>> at;  // (point, face)
    at.reserve(3 * pm.face_corners.size() + 2 * pm.corner_changes.size());
    for (std::size_t f = 0; f < pm.face_corners.size(); ++f)
      for (int k = 0; k < 3; ++k) at.emplace_back(pm.wedge_point[static_cast<std::size_t>(pm.face_corners[f][k])], static_cast<Index>(f));
    for (const CornerChange& c : pm.corner_changes)
      for (Index w : {c.coarse_wedge, c.fine_wedge}) at.emplace_back(pm.wedge_point[static_cast<std::size_t>(w)], c.corner / 3);
    point_face_start_.assign(points + 1, 0);
    for (const auto& [point, face] : at) ++point_face_start_[static_cast<std::size_t>(point) + 1];
    for (std::size_t p = 0; p < points; ++p) point_face_start_[p + 1] += point_face_start_[p];
    point_faces_.resize(at.size());
    std::vector<Index> next_face(point_face_start_.begin(), point_face_start_.end() - 1);
    for (const auto& [point, face] : at) point_faces_[static_cast<std::size_t>(next_face[static_cast<std::size_t>(point)]++)] = face;
    // Each point's list once per face, in place.
    Index kept = 0;
    for (std::size_t p = 0; p < points; ++p) {
      const auto first = point_faces_.begin() + point_face_start_[p], last = point_faces_.begin() + point_face_start_[p + 1];
      std::sort(first, last);
      const auto end = std::unique(first, last);
      point_face_start_[p] = kept;
      kept = static_cast<Index>(std::copy(first, end, point_faces_.begin() + kept) - point_faces_.begin());
    }
    point_face_start_[points] = kept;
    point_faces_.resize(static_cast<std::size_t>(kept));
    point_faces_.shrink_to_fit();
  }
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

SelectiveLevel SelectiveRefiner::apply_closed(std::vector<char> applied, const ViewTest* view) const {
  detail::SplitState state = detail::base_state(*pm_);
  for (std::size_t j = 0; j < applied.size(); ++j)
    if (applied[j]) detail::apply_split(*pm_, static_cast<Index>(j), true, state.positions, state.attributes, state.corners);
  std::vector<Index> unfolding;
  if (view && view->v.unfold) {
    std::vector<LevelSpan> spans = level_spans(applied);
    unfolding = unfold(state.positions, state.attributes, state.corners, applied, spans, nullptr);
  }
  SelectiveLevel out = level_of(state.positions, state.attributes, state.corners, applied, view);
  out.splits_unfolding = static_cast<Index>(unfolding.size());
  return out;
}

std::vector<Index> SelectiveRefiner::shown_faces(const std::vector<char>& applied) const {
  const ProgressiveMesh& pm = *pm_;
  std::vector<Index> faces(static_cast<std::size_t>(pm.base_faces));
  for (Index f = 0; f < pm.base_faces; ++f) faces[static_cast<std::size_t>(f)] = f;
  for (std::size_t j = 0; j < applied.size(); ++j)
    if (applied[j])
      for (Index f = pm.splits[j].first_face; f < pm.splits[j].first_face + pm.splits[j].num_faces; ++f) faces.push_back(f);
  return faces;
}

std::vector<SelectiveRefiner::LevelSpan> SelectiveRefiner::level_spans(const std::vector<char>& applied) const {
  const ProgressiveMesh& pm = *pm_;
  const Index n = static_cast<Index>(pm.splits.size());
  std::vector<LevelSpan> spans(first_at_point_.size());
  for (std::size_t p = 0; p < spans.size(); ++p)
    spans[p] = {made_by(static_cast<Index>(p)) + 1, first_at_point_[p] >= 0 ? first_at_point_[p] : n};
  for (std::size_t j = 0; j < applied.size(); ++j)
    if (applied[j]) spans[static_cast<std::size_t>(pm.splits[j].point)] = span_after(static_cast<Index>(j), true);
  return spans;
}

SelectiveRefiner::LevelSpan SelectiveRefiner::span_after(Index split, bool applied) const {
  const std::size_t j = static_cast<std::size_t>(split);
  if (applied) return {split + 1, next_at_point_[j] >= 0 ? next_at_point_[j] : static_cast<Index>(pm_->splits.size())};
  const Index before = previous_at_point_[j];
  return {(before >= 0 ? before : made_by(pm_->splits[j].point)) + 1, split};
}

bool SelectiveRefiner::folds(Index face, const std::vector<Eigen::Vector3d>& positions, const std::vector<Index>& corners,
                             const std::vector<char>& applied, const std::vector<LevelSpan>& spans) const {
  const ProgressiveMesh& pm = *pm_;
  const std::size_t f = static_cast<std::size_t>(face);
  const Index opened = face_split_[f];
  if (opened >= 0 && !applied[static_cast<std::size_t>(opened)]) return false;  // not shown
  // The uniform levels that hold the face as it is: those in which each corner's point stands where it
  // does (its corners change only with its splits). A face a uniform level has folds there or nowhere:
  // left as the level has it.
  Index lowest = opened + 1, highest = static_cast<Index>(pm.splits.size());
  std::array<Index, 3> point;
  for (std::size_t k = 0; k < 3; ++k) {
    point[k] = pm.wedge_point[static_cast<std::size_t>(corners[3 * f + k])];
    const LevelSpan& span = spans[static_cast<std::size_t>(point[k])];
    lowest = std::max(lowest, span[0]), highest = std::min(highest, span[1]);
  }
  if (lowest <= highest) return false;
  auto at = [&](std::size_t k) -> const Eigen::Vector3d& { return positions[static_cast<std::size_t>(point[k])]; };
  const Eigen::Vector3d normal = (at(1) - at(0)).cross(at(2) - at(0)), input = input_->tree.face_normal(face);
  if (input.squaredNorm() > 0 && !(normal.dot(input) > 0)) return true;  // against its own face (or without area)
  // Against the input's faces nearest its centroid, starting from its own (so that the answer, exact
  // up to the rounding of distances, is the same whichever state asks).
  Index hint = face;
  return input_->tree.facing_against_all_nearest((at(0) + at(1) + at(2)) / 3.0, normal, hint);
}

void SelectiveRefiner::append_faces_of(Index split, std::vector<Index>& faces) const {
  for (Index point : {pm_->splits[static_cast<std::size_t>(split)].point, pm_->base_points + split}) {
    const std::size_t p = static_cast<std::size_t>(point);
    faces.insert(faces.end(), point_faces_.begin() + point_face_start_[p], point_faces_.begin() + point_face_start_[p + 1]);
  }
}

std::vector<Index> SelectiveRefiner::unfold(std::vector<Eigen::Vector3d>& positions, std::vector<double>& attributes,
                                            std::vector<Index>& corners, std::vector<char>& applied,
                                            std::vector<LevelSpan>& spans, const std::vector<Index>* check) const {
  // Round by round: the faces that fold, the next split of each of their corners' points and what it
  // depends on, applied in order; then only the faces of the points those splits move can fold.
  const ProgressiveMesh& pm = *pm_;
  std::vector<Index> all, faces, round, stack;
  faces = check ? *check : shown_faces(applied);
  while (true) {
    round.clear();
    for (Index f : faces) {
      if (!folds(f, positions, corners, applied, spans)) continue;
      for (std::size_t k = 0; k < 3; ++k) {  // each corner's next split, where it has one
        const Index point = pm.wedge_point[static_cast<std::size_t>(corners[3 * static_cast<std::size_t>(f) + k])];
        if (const Index j = spans[static_cast<std::size_t>(point)][1]; j < static_cast<Index>(pm.splits.size())) stack.push_back(j);
      }
    }
    while (!stack.empty()) {
      const Index j = stack.back();
      stack.pop_back();
      if (applied[static_cast<std::size_t>(j)]) continue;
      applied[static_cast<std::size_t>(j)] = 1;
      round.push_back(j);
      for (Index d : dependencies(j))
        if (!applied[static_cast<std::size_t>(d)]) stack.push_back(d);
    }
    if (round.empty()) break;
    // In stream order, as refine() applies a set: a split applied later in the stream depends on none of these.
    std::sort(round.begin(), round.end());
    faces.clear();
    for (Index j : round) {
      detail::apply_split(pm, j, true, positions, attributes, corners);
      spans[static_cast<std::size_t>(pm.splits[static_cast<std::size_t>(j)].point)] = span_after(j, true);
      append_faces_of(j, faces);
    }
    all.insert(all.end(), round.begin(), round.end());
  }
  std::sort(all.begin(), all.end());
  return all;
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
  // Faces by number, then the wedges they use by number.
  const ProgressiveMesh& pm = *pm_;
  const std::vector<Index> faces = shown_faces(applied);
  ExtractedLevel e;
  e.level = static_cast<Index>(std::count(applied.begin(), applied.end(), 1));
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
  if (pm.knows_input_order())
    for (Index& origin : e.vertex_origin) origin = pm.wedge_input[static_cast<std::size_t>(origin)];
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

}  // namespace lodkit
