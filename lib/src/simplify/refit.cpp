// refit_to_input(): a simplification's vertices moved to fit the input better, connectivity unchanged.
//
// The collapses place each vertex once, from the quadrics (or hoppe's points) of its neighbourhood at
// that moment; later collapses around it never move it again, and nothing looks at the largest
// distances. Here the whole output is fitted at once, as in Hoppe et al.'s "Mesh optimization" (1993)
// with connectivity fixed, but towards the largest distances rather than their squares' sum:
// iteratively reweighted least squares over points sampled on both surfaces.
//
// Each pass measures every sample: the input's points and edge midpoints against the output, and a
// barycentric grid on each output face against the input. (After the first measure, most samples
// are measured against the face they were nearest before, without a search: see sample().) A sample
// at distance d that lies at barycentric b on an output face (or whose nearest output point does)
// comes nearer by b_k (u . delta) when that face's corner k moves by delta, to first order, u the unit
// direction from the sample towards the other surface. Each vertex solves a 3x3 weighted least-squares
// problem for the delta that takes its samples' distances to zero, weights (d / d_max)^exponent, clamps
// it to the distance of its farthest sample, and all vertices step a fraction of it at once. A pass that finds the largest
// distance lower keeps the step and grows the fraction; one that does not goes back to the best
// positions and halves it. Faces may not turn more than a limit per step or from their reference
// orientation (their input face's, else their own before the refit), lose quality below the
// simplifier's floor, or (when asked) come to face against the input.
//
// Then a second stage fits the squared distances (the RMS), with unit weights, under a guard: no sample
// may get farther than the larger of its own distance at the best positions so far and rms_guard times
// the largest, so the largest distances stay where the first stage left them. A step whose samples
// break the guard sends the corners of their faces back and measures again, up to four times; one
// that still breaks it, or does not lower the sum of squares, goes back and halves the fraction.
#include <lodkit/error.h>
#include <lodkit/simplify.h>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_arena.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <span>
#include <unordered_map>

#include "core/geometry.h"
#include "core/huge_pages.h"
#include "simplify/refit_input.h"
#include "simplify/target.h"

namespace lodkit {
namespace {

using Vec = Eigen::Vector3d;

// Where p's foot on the plane of triangle (a, b, c) lies inside the triangle, that foot is p's nearest
// point on it: the foot and its barycentric weights. Where it lies outside, p's nearest face may be a
// neighbour; nothing then, nor for a sliver (its angle at a under about 1e-5 rad), whose plane is too
// uncertain to say.
struct Foot {
  Vec point, bary;
};
std::optional<Foot> foot_inside(const Vec& p, const Vec& a, const Vec& b, const Vec& c) {
  const auto vw = detail::plane_weights(a, b, c, p, 1e-10);
  if (!vw) return std::nullopt;
  const double v = vw->x(), w = vw->y();
  if (!(v >= 0 && w >= 0 && v + w <= 1)) return std::nullopt;
  return Foot{a + v * (b - a) + w * (c - a), Vec(1 - v - w, v, w)};
}

// p's nearest point on `tree`'s mesh (and, with `bary`, its barycentric weights on that face); or,
// where p lies within sqrt(below2) of face `last` (-1: none) and projects inside it, its foot on `last`
// (`kept` says which). corners(face, k): the face's corners.
template <typename Corners>
detail::AabbTree::Hit nearest(const detail::AabbTree& tree, const Vec& p, Index last, double below2, Corners corners,
                              bool& kept, Vec* bary = nullptr) {
  kept = false;
  if (last >= 0 && below2 > 0)
    if (const auto foot = foot_inside(p, corners(last, 0), corners(last, 1), corners(last, 2))) {
      if (const double d2 = (foot->point - p).squaredNorm(); d2 < below2) {
        kept = true;
        if (bary) *bary = foot->bary;
        return {foot->point, d2, last};
      }
    }
  const auto hit = tree.closest(p, last);
  if (bary) *bary = detail::barycentric(corners(hit.face, 0), corners(hit.face, 1), corners(hit.face, 2), hit.point);
  return hit;
}

std::uint64_t edge_key(Index a, Index b) {
  return (static_cast<std::uint64_t>(std::min(a, b)) << 32) | static_cast<std::uint32_t>(std::max(a, b));
}

// One sample's pull on the output face it lies on (output samples) or nearest (input samples).
struct Pull {
  Index face = -1;
  Vec bary = Vec::Zero();
  Vec direction = Vec::Zero();  // unit: the face moving along it comes nearer the other surface here
  double distance = 0;
  Index hint = -1;  // output samples: the input face nearest when last measured
  bool kept_face = false;  // measured against the face of the measure before, without a search
};

class Refitter {
 public:
  Refitter(const detail::RefitInput& input, Mesh& output, std::span<const Index> face_origin, const RefitOptions& options)
      : output_(output), o_(options), input_mesh_(input.mesh), input_tree_(input.tree), input_samples_(input.samples) {
    weld_output();
    // Each face's reference orientation: its input face's where known, else its own before the refit.
    reference_.resize(corners_.size());
    for (std::size_t f = 0; f < corners_.size(); ++f) {
      const bool known = f < face_origin.size() && face_origin[f] >= 0 && face_origin[f] < input_mesh_.num_faces();
      reference_[f] = known ? input_normal(face_origin[f]) : normal(static_cast<Index>(f));
    }
    find_fixed_points();
    // Output samples: a barycentric grid of n steps a side, n so that the output has about half as many
    // samples as the input has faces (a coarse face stands for many input faces), within [2, 12]. Twice
    // as many changed the errors by under 1 % on the shared meshes (docs/benchmarks-log.md, "Session 35").
    const double ratio = static_cast<double>(input_mesh_.num_faces()) / std::max<Index>(1, output.num_faces());
    const int n = std::clamp(static_cast<int>(std::ceil(std::sqrt(ratio))), 2, 12);
    for (int i = 0; i <= n; ++i)
      for (int j = 0; i + j <= n; ++j) grid_.push_back(Vec(i, j, n - i - j) / n);
    detail::resize_huge(input_pulls_, input_samples_.size());
    detail::resize_huge(output_pulls_, static_cast<std::size_t>(output.num_faces()) * grid_.size());
    face_hint_.assign(static_cast<std::size_t>(output.num_faces()), -1);
  }

  RefitReport run() {
    RefitReport report;
    const std::vector<Vec> start = points_;
    fit_squares(report, turn_inverted(report, fit_largest(report)));
    for (std::size_t p = 0; p < points_.size(); ++p) report.moved_vertices += points_[p] != start[p];
    refresh_output();
    return report;
  }

 private:
  // One point per position: seam vertices move together.
  void weld_output() {
    const Eigen::VectorX<Index> cls = position_classes(output_);
    point_of_.resize(static_cast<std::size_t>(output_.num_vertices()));
    std::vector<Index> point_of_class(static_cast<std::size_t>(output_.num_vertices()), -1);
    for (Index v = 0; v < output_.num_vertices(); ++v) {
      Index& p = point_of_class[cls[v]];
      if (p < 0) p = static_cast<Index>(points_.size()), points_.push_back(output_.positions.row(v).transpose());
      point_of_[v] = p;
    }
    corners_.resize(static_cast<std::size_t>(output_.num_faces()));
    for (Index f = 0; f < output_.num_faces(); ++f)
      for (int k = 0; k < 3; ++k) corners_[f][k] = point_of_[output_.triangles(f, k)];
  }

  // Vertices on edges of more than two faces, and on the boundary when it is fixed, stay put.
  void find_fixed_points() {
    fixed_.assign(points_.size(), false);
    std::unordered_map<std::uint64_t, int> edge_faces;
    for (const auto& c : corners_)
      for (int k = 0; k < 3; ++k) ++edge_faces[edge_key(c[k], c[(k + 1) % 3])];
    for (const auto& [edge, faces] : edge_faces)
      if (faces > 2 || (faces == 1 && o_.fix_boundary)) fixed_[edge >> 32] = fixed_[edge & 0xffffffffu] = true;
  }

  Vec corner(Index f, int k) const { return points_[corners_[f][k]]; }
  Vec normal(Index f) const { return (corner(f, 1) - corner(f, 0)).cross(corner(f, 2) - corner(f, 0)); }
  Vec centroid(Index f) const { return (corner(f, 0) + corner(f, 1) + corner(f, 2)) / 3; }
  Vec input_corner(Index g, int k) const { return input_mesh_.positions.row(input_mesh_.triangles(g, k)).transpose(); }
  Vec input_normal(Index g) const { return (input_corner(g, 1) - input_corner(g, 0)).cross(input_corner(g, 2) - input_corner(g, 0)); }

  // Every sample's distance and pull at the current positions; returns the largest distance.
  // With `only_moved`, only the samples on (output) or nearest (input) a face with a point moved since the
  // last measure are measured again: the others' distances cannot have grown, since the face they were
  // measured to is where it was, so the pulls stay upper bounds (the RMS stage's guard needs no more).
  // With `keep_face_below` > 0, a sample nearer than that to the face it was last measured against,
  // whose nearest point on that face lies inside it, keeps the face without a search (see
  // RefitOptions::keep_face_below): it mostly still is the nearest, since the steps are small, and its
  // distance is an upper bound either way. The largest distance stays exact: kept samples farther than
  // the largest searched one are searched.
  double sample(bool only_moved = false, double keep_face_below = 0) {
    std::vector<char> moved;
    if (only_moved) {
      moved.resize(points_.size());
      for (std::size_t p = 0; p < points_.size(); ++p) moved[p] = points_[p] != measured_at_[p];
    }
    auto needs = [&](Index face) {
      if (!only_moved) return true;
      const auto& c = corners_[face];
      return moved[c[0]] || moved[c[1]] || moved[c[2]];
    };
    measured_at_ = points_;
    refresh_output();
    // Built once; then its boxes follow the moves (the same answers as a new tree, in less time).
    if (output_tree_) output_tree_->refit();
    else output_tree_.emplace(output_);
    const detail::AabbTree& output_tree = *output_tree_;
    const std::size_t per_face = grid_.size();
    const double keep2 = keep_face_below * keep_face_below;
    auto measure_input = [&](std::size_t s, double below2) {
      const Vec& p = input_samples_[s];
      Pull& pull = input_pulls_[s];
      const auto hit = nearest(output_tree, p, pull.face, below2, [&](Index f, int k) { return corner(f, k); }, pull.kept_face,
                               &pull.bary);
      pull.face = hit.face;
      pull.distance = std::sqrt(hit.squared_distance);
      pull.direction = pull.distance > 0 ? Vec((p - hit.point) / pull.distance) : Vec::Zero();
    };
    auto measure_output = [&](std::size_t s, double below2) {
      const Index f = static_cast<Index>(s / per_face);
      const Vec& b = grid_[s % per_face];
      const Vec q = b[0] * corner(f, 0) + b[1] * corner(f, 1) + b[2] * corner(f, 2);
      Pull& pull = output_pulls_[s];
      const auto hit = nearest(input_tree_, q, pull.hint, below2, [&](Index g, int k) { return input_corner(g, k); }, pull.kept_face);
      pull.hint = hit.face;
      pull.face = f;
      pull.bary = b;
      pull.distance = std::sqrt(hit.squared_distance);
      pull.direction = pull.distance > 0 ? Vec((hit.point - q) / pull.distance) : Vec::Zero();
    };
    // The largest distance among the searched samples, and among those that kept their face.
    struct Largest {
      double searched = 0, kept = 0;
      static Largest of(Largest a, Largest b) { return {std::max(a.searched, b.searched), std::max(a.kept, b.kept)}; }
    };
    auto largest_of = [&](std::vector<Pull>& pulls, const auto& measure, auto&& which, double below2) {
      return tbb::parallel_reduce(
          tbb::blocked_range<std::size_t>(0, pulls.size()), Largest{},
          [&](const tbb::blocked_range<std::size_t>& range, Largest largest) {
            for (std::size_t s = range.begin(); s != range.end(); ++s) {
              if (which(s)) measure(s, below2);
              double& into = pulls[s].kept_face ? largest.kept : largest.searched;
              into = std::max(into, pulls[s].distance);
            }
            return largest;
          },
          Largest::of);
    };
    auto both = [&](auto&& which_input, auto&& which_output, double below2) {
      return Largest::of(largest_of(input_pulls_, measure_input, which_input, below2),
                         largest_of(output_pulls_, measure_output, which_output, below2));
    };
    Largest largest = both([&](std::size_t s) { return needs(input_pulls_[s].face); },
                           [&](std::size_t s) { return needs(output_pulls_[s].face); }, keep2);
    // Kept samples farther than every searched one are searched. Once is enough: the searched largest
    // stays at least `above`, and the samples still kept lie within it.
    while (largest.kept > largest.searched) {
      const double above = largest.searched;
      largest = both([&](std::size_t s) { return input_pulls_[s].kept_face && input_pulls_[s].distance > above; },
                     [&](std::size_t s) { return output_pulls_[s].kept_face && output_pulls_[s].distance > above; }, 0);
    }
    return largest.searched;
  }

  static constexpr double kGrow = 1.25;

  // The fraction of each vertex's move a step takes: it grows after a kept step (but the first) and
  // halves after a failed one; a stage ends when it falls below a sixteenth of where it started.
  struct StepFraction {
    double value, first;
    void kept(int pass) {
      if (pass > 0) value = std::min(1.0, value * kGrow);
    }
    bool failed() { return (value *= 0.5) >= first / 16; }
  };
  static constexpr int kGuardRounds = 4;  // send-backs per step before the RMS stage gives the step up

  double measure(RefitReport& report, double keep_face_below = 0) {
    ++report.passes;
    return sample(/*only_moved=*/false, keep_face_below);
  }
  // Side by side in a split fixed by the sample count alone (parallel_deterministic_reduce), so the
  // same bits for any number of threads.
  double sum_of_squares() const {
    double sum = 0;
    for (const auto* pulls : {&input_pulls_, &output_pulls_})
      sum += tbb::parallel_deterministic_reduce(
          tbb::blocked_range<std::size_t>(0, pulls->size(), 16384), 0.0,
          [pulls = pulls](const tbb::blocked_range<std::size_t>& range, double part) {
            for (std::size_t s = range.begin(); s != range.end(); ++s) part += (*pulls)[s].distance * (*pulls)[s].distance;
            return part;
          },
          std::plus<double>());
    return sum;
  }
  double sampled_rms(double sum) const { return std::sqrt(sum / std::max<std::size_t>(1, input_pulls_.size() + output_pulls_.size())); }

  // The first stage: towards the largest sampled distance (weights (d / d_max)^exponent). Returns that
  // distance where the pulls are left as measured at the positions it keeps, so the next stage need not
  // measure them again.
  std::optional<double> fit_largest(RefitReport& report) {
    if (o_.passes == 0) return std::nullopt;
    std::vector<Vec> best = points_, step(points_.size(), Vec::Zero());
    double best_max = std::numeric_limits<double>::infinity(), best_rms = 0;
    StepFraction scale{o_.step, o_.step};
    bool best_measured = false;
    for (int pass = 0; pass < o_.passes; ++pass) {
      const double sampled_max = measure(report, pass == 0 ? 0.0 : o_.keep_face_below * best_max);
      const double rms = sampled_rms(sum_of_squares());
      if (pass == 0) report.sampled_max_before = sampled_max, report.sampled_rms_before = rms;
      best_measured = sampled_max < best_max;
      if (best_measured) {
        best_max = sampled_max, best_rms = rms, best = points_, report.steps += pass > 0;
        if (sampled_max == 0 || pass + 1 == o_.passes) break;
        solve(sampled_max, o_.exponent, step);
        scale.kept(pass);
      } else if (!scale.failed()) {  // farther: back to the best positions, with half the step
        break;
      }
      propose(best, step, scale.value);
    }
    points_ = best;
    report.sampled_max_after = best_max;
    report.sampled_rms_after = best_rms;
    return best_measured ? std::optional(best_max) : std::nullopt;
  }

  // The second stage: towards the least sum of squared sampled distances, under the guard.
  // `measured`: the largest sampled distance, where the pulls are those of the current positions.
  void fit_squares(RefitReport& report, std::optional<double> measured) {
    if (o_.rms_passes == 0) return;
    std::vector<Vec> best = points_, step(points_.size(), Vec::Zero());
    Guard guard;  // each sample's at the best positions
    double best_sum = std::numeric_limits<double>::infinity(), first_largest = 0, limit = 0;
    StepFraction scale{o_.step, o_.step};
    for (int pass = 0; pass < o_.rms_passes; ++pass) {
      // Where the first stage ended on a step it undid, its pulls are those of the undone positions: measured
      // again, keeping faces below its largest distance as every later pass does (a full search cost a
      // seventh of the refit on igea -> 10 %).
      double largest = pass == 0 && measured ? *measured
                                             : measure(report, o_.keep_face_below * (pass == 0 ? report.sampled_max_after : first_largest));
      if (pass == 0) {
        first_largest = largest, limit = o_.rms_guard * largest;
        if (o_.passes == 0) report.sampled_max_before = largest, report.sampled_rms_before = sampled_rms(sum_of_squares());
      }
      const bool within = pass == 0 || keep_within(best, guard, largest);
      const double sum = sum_of_squares();
      if (within && sum < best_sum) {
        best_sum = sum, best = points_, report.rms_steps += pass > 0;
        report.sampled_max_after = std::max(report.sampled_max_after, largest);
        report.sampled_rms_after = sampled_rms(sum);
        guard = guard_at(limit);
        if (pass + 1 == o_.rms_passes) break;
        solve(largest, 0.0, step);
        scale.kept(pass);
      } else if (!scale.failed()) {
        break;
      }
      propose(best, step, scale.value);
    }
    points_ = best;
  }

  // Per sample, the farthest it may get: the larger of its distance now and `limit` (with a margin for
  // rounding: a sample that stays put must not break it by an ulp).
  struct Guard {
    std::vector<double> input, output;
  };
  Guard guard_at(double limit) const {
    Guard guard;
    for (const auto& [pulls, allowed] : {std::pair{&input_pulls_, &guard.input}, std::pair{&output_pulls_, &guard.output}}) {
      allowed->resize(pulls->size());
      tbb::parallel_for(std::size_t{0}, pulls->size(), [&, pulls = pulls, allowed = allowed](std::size_t s) {
        (*allowed)[s] = std::max(limit, (*pulls)[s].distance) + 1e-9 * limit;
      });
    }
    return guard;
  }

  // Samples past their guard send the corners of their faces back to `kept`; those faces' neighbours then
  // have new shapes, which hold_back() checks again, and what moved is measured again (its largest
  // distance into `largest`), up to kGuardRounds times. Expects the pulls measured at the current
  // positions; returns whether every sample is within its guard.
  bool keep_within(const std::vector<Vec>& kept, const Guard& guard, double& largest) {
    for (int round = 0;; ++round) {
      bool within = true, sent_back = false;
      for (const auto& [pulls, allowed] : {std::pair{&input_pulls_, &guard.input}, std::pair{&output_pulls_, &guard.output}})
        for (const Index face : faces_past(*pulls, *allowed)) {
          within = false;
          for (const Index p : corners_[face])
            if (points_[p] != kept[p]) points_[p] = kept[p], sent_back = true;
        }
      if (within || !sent_back || round == kGuardRounds) return within;
      hold_back(kept);
      largest = sample(/*only_moved=*/true);
    }
  }

  // The faces of the samples farther than allowed (few: found side by side, a pass over every sample).
  static std::vector<Index> faces_past(const std::vector<Pull>& pulls, const std::vector<double>& allowed) {
    using Faces = std::vector<Index>;
    return tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, pulls.size()), Faces{},
        [&](const tbb::blocked_range<std::size_t>& range, Faces faces) {
          for (std::size_t s = range.begin(); s != range.end(); ++s)
            if (pulls[s].distance > allowed[s]) faces.push_back(pulls[s].face);
          return faces;
        },
        [](Faces a, const Faces& b) {
          a.insert(a.end(), b.begin(), b.end());
          return a;
        });
  }

  // Between the stages (avoid_inverted): faces facing against the input face nearest their centroid move
  // towards the nearest input face that faces their way. The collapses let such faces be where the
  // others cost far more, and they lie where two sheets of the input face each other: parts in contact
  // or back to back, a thin part's two sides, crossing components. Such a face's own sheet is almost
  // always within the error already (on the shared meshes at 10 % and 1 %, its centroid lies 0.01-0.63
  // times the Hausdorff distance from it), so the move costs little, and it is held to that by the RMS
  // stage's guard: no sample may get farther than the larger of its own distance and rms_guard times
  // the largest (the largest itself as the limit left 7 fewer such faces over the shared meshes, at RMS
  // x 1.0005). Each face moves its centroid onto that sheet, points shared by several such faces by their
  // mean; a round is kept only if fewer such faces are left. `measured`: as fit_squares() takes it;
  // returns the same for the positions kept.
  std::optional<double> turn_inverted(RefitReport& report, std::optional<double> measured) {
    if (!o_.avoid_inverted) return measured;
    std::vector<Index> inverted = inverted_faces();
    report.inverted_before = report.inverted_after = static_cast<Index>(inverted.size());
    if (inverted.empty()) return measured;
    double largest = measured ? *measured : measure(report, o_.keep_face_below * report.sampled_max_after);
    const Guard guard = guard_at(o_.rms_guard * largest);
    std::vector<Vec> kept = points_, move(inverted.size());
    std::vector<Vec> step(points_.size());
    std::vector<int> count(points_.size());
    for (int round = 0; round < kTurnRounds && !inverted.empty(); ++round) {
      tbb::parallel_for(std::size_t{0}, inverted.size(), [&](std::size_t i) {
        const Index f = inverted[i];
        const Vec at = centroid(f);
        const auto hit = input_tree_.closest_facing(at, normal(f));
        move[i] = hit.face >= 0 ? Vec(hit.point - at) : Vec::Zero();
      });
      std::fill(step.begin(), step.end(), Vec::Zero());
      std::fill(count.begin(), count.end(), 0);
      for (std::size_t i = 0; i < inverted.size(); ++i)
        for (const Index p : corners_[inverted[i]]) step[p] += move[i], ++count[p];
      for (std::size_t p = 0; p < points_.size(); ++p)
        if (count[p] > 0 && !fixed_[p]) points_[p] = kept[p] + step[p] / count[p];
      hold_back(kept);
      largest = sample(/*only_moved=*/true);
      const bool within = keep_within(kept, guard, largest);
      std::vector<Index> left = within ? inverted_faces() : inverted;
      if (left.size() >= inverted.size()) {
        points_ = kept;
        largest = sample(/*only_moved=*/true);
        break;
      }
      kept = points_, inverted = std::move(left), ++report.turn_steps;
    }
    report.inverted_after = static_cast<Index>(inverted.size());
    if (report.turn_steps > 0) report.sampled_max_after = std::max(report.sampled_max_after, largest);
    return largest;
  }

  // The output faces facing against the input face nearest their centroid.
  std::vector<Index> inverted_faces() {
    std::vector<char> against(corners_.size());
    tbb::parallel_for(std::size_t{0}, corners_.size(), [&](std::size_t f) {
      const Index face = static_cast<Index>(f);
      against[f] = input_tree_.facing_against(centroid(face), normal(face), face_hint_[f]);
    });
    std::vector<Index> faces;
    for (std::size_t f = 0; f < against.size(); ++f)
      if (against[f]) faces.push_back(static_cast<Index>(f));
    return faces;
  }
  static constexpr int kTurnRounds = 16;  // (4: on the counter at 10 %, 13 such faces left instead of 8)

  // Each point's least-squares move: the delta that would take its samples' distances to zero.
  void solve(double sampled_max, double exponent, std::vector<Vec>& step) const {
    const std::size_t n = points_.size();
    // Per point: its normal matrix's upper triangle (xx, xy, xz, yy, yz, zz: the matrix is symmetric),
    // its right-hand side and its farthest sample, side by side.
    struct Sums {
      std::array<double, 6> upper{};
      Vec rhs = Vec::Zero();
      double farthest = 0;
    };
    std::vector<Sums> sums(n);
    // Side by side, each task summing for its own range of points over every sample, so each point's
    // sums add up in sample order whatever the number of tasks (the same bits as one task). Every task
    // reads every sample, so more than a few would read more than they save.
    const std::size_t tasks = std::clamp<std::size_t>(tbb::this_task_arena::max_concurrency(), 1, 4);
    tbb::parallel_for(std::size_t{0}, tasks, [&](std::size_t task) {
      const Index from = static_cast<Index>(n * task / tasks), to = static_cast<Index>(n * (task + 1) / tasks);
      for (const auto* pulls : {&input_pulls_, &output_pulls_})
        for (const Pull& pull : *pulls) {
          if (pull.distance == 0) continue;
          const auto& c = corners_[pull.face];
          const auto mine = [&](int k) { return c[k] >= from && c[k] < to && !(pull.bary[k] <= 0); };
          if (!mine(0) && !mine(1) && !mine(2)) continue;
          const double weight = exponent == 0 ? 1.0 : std::pow(pull.distance / sampled_max, exponent);
          const Vec& u = pull.direction;
          const std::array<double, 6> uu{u[0] * u[0], u[0] * u[1], u[0] * u[2], u[1] * u[1], u[1] * u[2], u[2] * u[2]};
          for (int k = 0; k < 3; ++k) {
            if (!mine(k)) continue;
            const double b = pull.bary[k];
            Sums& sum = sums[c[k]];
            const double scale = weight * b * b;
            for (int e = 0; e < 6; ++e) sum.upper[e] += scale * uu[e];
            sum.farthest = std::max(sum.farthest, pull.distance);
            sum.rhs += weight * b * pull.distance * u;
          }
        }
    });
    tbb::parallel_for(std::size_t{0}, n, [&](std::size_t p) {
      step[p].setZero();
      const auto& [m, rhs, farthest] = sums[p];
      const double trace = m[0] + (m[3] + m[5]);  // summed as Eigen's trace() sums
      if (fixed_[p] || !(trace > 0)) return;
      // Regularised: directions no sample constrains (along a flat surface) stay put.
      const double lift = 1e-3 * trace;
      Eigen::Matrix3d a;
      a << m[0] + lift, m[1], m[2], m[1], m[3] + lift, m[4], m[2], m[4], m[5] + lift;
      step[p] = a.ldlt().solve(rhs);
      if (!step[p].allFinite()) step[p].setZero();  // (huge or tiny coordinates)
      // No farther than its farthest sample: a poorly constrained solve can ask for far more.
      if (const double length = step[p].norm(); length > farthest) step[p] *= farthest / length;
    });
  }

  // points = kept + scale * step, less what hold_back() sends back.
  void propose(const std::vector<Vec>& kept, const std::vector<Vec>& step, double scale) {
    for (std::size_t p = 0; p < points_.size(); ++p) points_[p] = kept[p] + scale * step[p];
    hold_back(kept);
  }

  // Sends the points of every face that breaks a limit back to `kept`, until none does: a turn of more
  // than max_step_turn_deg from `kept`, or of more than max_total_turn_deg from the face's reference
  // orientation; quality below the floor and below kept's; or (avoid_inverted) facing against the input
  // face nearest its centroid where it did not at `kept`, so that no face comes to that in any step.
  // A point beyond the coordinates validate() takes goes back first.
  // (Checking that once at the end instead, sending points back to where they started, undid the
  // refit around crossing parts: ogre at 1 %, Hausdorff 0.685 -> 0.850 %.)
  void hold_back(const std::vector<Vec>& kept) {
    for (std::size_t p = 0; p < points_.size(); ++p)  // near a float's range, a step can leave it
      if (!within_coordinate_range(points_[p])) points_[p] = kept[p];
    const double cos_step = std::cos(o_.max_step_turn_deg * M_PI / 180);
    const double cos_total = std::cos(o_.max_total_turn_deg * M_PI / 180);
    std::vector<char> bad(corners_.size());
    for (bool changed = true; changed;) {
      changed = false;
      tbb::parallel_for(std::size_t{0}, corners_.size(), [&](std::size_t f) {
        const auto& c = corners_[f];
        bad[f] = 0;
        if (points_[c[0]] == kept[c[0]] && points_[c[1]] == kept[c[1]] && points_[c[2]] == kept[c[2]]) return;
        const Vec now = normal(static_cast<Index>(f));
        const Vec before = (kept[c[1]] - kept[c[0]]).cross(kept[c[2]] - kept[c[0]]);
        const double quality = detail::triangle_quality(points_[c[0]], points_[c[1]], points_[c[2]], now.norm());
        bad[f] = now.dot(before) < cos_step * now.norm() * before.norm() ||
                 now.dot(reference_[f]) < cos_total * now.norm() * reference_[f].norm() ||
                 (quality < o_.min_triangle_quality &&
                  quality < detail::triangle_quality(kept[c[0]], kept[c[1]], kept[c[2]], before.norm()));
        if (bad[f] || !o_.avoid_inverted) return;
        Index& hint = face_hint_[f];
        if (input_tree_.facing_against(centroid(static_cast<Index>(f)), now, hint)) {
          Index kept_hint = hint;
          bad[f] = !input_tree_.facing_against((kept[c[0]] + kept[c[1]] + kept[c[2]]) / 3, before, kept_hint);
        }
      });
      for (std::size_t f = 0; f < corners_.size(); ++f)
        if (bad[f])
          for (const Index p : corners_[f])
            if (points_[p] != kept[p]) points_[p] = kept[p], changed = true;
    }
  }

  void refresh_output() {
    for (Index v = 0; v < output_.num_vertices(); ++v) output_.positions.row(v) = points_[point_of_[v]].transpose();
  }

  Mesh& output_;
  const RefitOptions& o_;
  const Mesh& input_mesh_;
  const detail::AabbTree& input_tree_;
  std::vector<Vec> points_;                    // the output's positions, one per welded point
  std::vector<Index> point_of_;                // per output vertex
  std::vector<std::array<Index, 3>> corners_;  // per output face, its points
  std::vector<bool> fixed_;
  std::vector<Vec> reference_;                 // per output face: the orientation its turn is measured from
  const std::vector<Vec>& input_samples_;
  std::vector<Vec> grid_;
  std::vector<Pull> input_pulls_, output_pulls_;
  std::vector<Index> face_hint_;  // per output face: an input face near its centroid (facing_against's hint)
  std::vector<Vec> measured_at_;  // the positions the pulls were last measured at
  std::optional<detail::AabbTree> output_tree_;  // over output_, whose positions move in place
};

}  // namespace

namespace detail {

bool needs_refit(const Mesh& input, const Mesh& simplified, const RefitOptions& options,
                 std::span<const Index> face_origin) {
  if (options.passes < 0) throw Error(fmt::format("refit: passes must not be negative, got {}", options.passes));
  if (!(options.step > 0 && options.step <= 1)) throw Error(fmt::format("refit: step must be in (0, 1], got {}", options.step));
  if (options.rms_passes < 0) throw Error(fmt::format("refit: RMS passes must not be negative, got {}", options.rms_passes));
  if (!(options.rms_guard >= 0 && options.rms_guard <= 1))
    throw Error(fmt::format("refit: the RMS guard must be in [0, 1], got {}", options.rms_guard));
  if (!(options.keep_face_below >= 0 && options.keep_face_below <= 1))
    throw Error(fmt::format("refit: keep_face_below must be in [0, 1], got {}", options.keep_face_below));
  if (!(options.max_step_turn_deg > 0 && options.max_step_turn_deg <= 180))
    throw Error(fmt::format("refit: the turn per step must be in (0, 180] degrees, got {}", options.max_step_turn_deg));
  if (!(options.max_total_turn_deg > 0 && options.max_total_turn_deg <= 180))
    throw Error(fmt::format("refit: the total turn must be in (0, 180] degrees, got {}", options.max_total_turn_deg));
  if (!(options.min_triangle_quality >= 0 && options.min_triangle_quality <= 1))
    throw Error(fmt::format("refit: the triangle quality floor must be in [0, 1], got {}", options.min_triangle_quality));
  if (!(options.exponent >= 0 && options.exponent <= 64))
    throw Error(fmt::format("refit: exponent must be between 0 and 64, got {}", options.exponent));
  if (!face_origin.empty() && face_origin.size() != static_cast<std::size_t>(simplified.num_faces()))
    throw Error(fmt::format("refit: {} face origins for {} faces", face_origin.size(), simplified.num_faces()));
  return refits(options) && input.num_faces() > 0 && simplified.num_faces() > 0;
}

// The input's points (once per position; vertices no face uses are not part of the surface) and its
// edges' midpoints. Where the input's edges are long against the distances, the largest distance can
// lie between vertices: the bunny at 10 % came to 0.219 % certified Hausdorff with points and face
// centroids as samples, 0.132 % with points and edge midpoints.
RefitInput::RefitInput(const Mesh& input, bool facing) : mesh(input), tree(input) {
  if (facing) tree.prepare_facing();
  const Eigen::VectorX<Index> cls = position_classes(input);
  std::vector<char> used(static_cast<std::size_t>(input.num_vertices()), 0);
  std::vector<std::uint64_t> edges;
  reserve_huge(edges, 3 * static_cast<std::size_t>(input.num_faces()));
  for (Index f = 0; f < input.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      const Index a = cls[input.triangles(f, k)], b = cls[input.triangles(f, (k + 1) % 3)];
      used[a] = 1;
      if (a != b) edges.push_back(edge_key(a, b));
    }
  tbb::parallel_sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  reserve_huge(samples, static_cast<std::size_t>(std::count(used.begin(), used.end(), 1)) + edges.size());
  for (Index v = 0; v < input.num_vertices(); ++v)
    if (used[v]) samples.push_back(input.positions.row(v).transpose());
  for (const std::uint64_t e : edges)
    samples.push_back(0.5 * (input.positions.row(static_cast<Index>(e >> 32)) +
                             input.positions.row(static_cast<Index>(e & 0xffffffffu))).transpose());
}

RefitReport refit_to_input(const RefitInput& input, Mesh& simplified, const RefitOptions& options,
                           std::span<const Index> face_origin) {
  const auto start = std::chrono::steady_clock::now();
  RefitReport report;
  if (!needs_refit(input.mesh, simplified, options, face_origin)) return report;
  report = Refitter(input, simplified, face_origin, options).run();
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

}  // namespace detail

RefitReport refit_to_input(const Mesh& input, Mesh& simplified, const RefitOptions& options,
                           std::span<const Index> face_origin) {
  if (!detail::needs_refit(input, simplified, options, face_origin)) return {};
  return detail::refit_to_input(detail::RefitInput(input, options.avoid_inverted), simplified, options, face_origin);
}

}  // namespace lodkit
