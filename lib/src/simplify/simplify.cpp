// simplify(): the options checked, the target found, the engine run; and the methods' defaults and names.
#include <lodkit/error.h>
#include <lodkit/simplify.h>

#include <chrono>
#include <cmath>
#include <fmt/format.h>
#include <optional>
#include <tbb/task_group.h>
#include <utility>

#include "core/geometry.h"
#include "simplify/attribute_fit.h"
#include "simplify/collapse_engine.h"
#include "simplify/refit_input.h"
#include "simplify/target.h"

namespace lodkit {

namespace detail {

void check_options(const SimplifyOptions& options) {
  if (options.target_ratio && !(*options.target_ratio >= 0 && *options.target_ratio <= 1))
    throw Error(fmt::format("simplify: ratio must be between 0 and 1, got {}", *options.target_ratio));
  if (options.target_faces && *options.target_faces < 0)
    throw Error(fmt::format("simplify: face target must not be negative, got {}", *options.target_faces));
  if (options.max_error && !(*options.max_error >= 0))
    throw Error(fmt::format("simplify: max error must not be negative, got {}", *options.max_error));
  if (!(options.max_normal_change_deg > 0 && options.max_normal_change_deg <= 180))
    throw Error("simplify: max normal change must be in (0, 180] degrees");
  if (options.max_total_normal_change_deg &&
      !(*options.max_total_normal_change_deg > 0 && *options.max_total_normal_change_deg <= 180))
    throw Error(fmt::format("simplify: max total normal change must be in (0, 180] degrees, got {}",
                            *options.max_total_normal_change_deg));
  if (options.refit_passes && *options.refit_passes < 0)
    throw Error(fmt::format("simplify: refit passes must not be negative, got {}", *options.refit_passes));
  if (options.refit_rms_passes && *options.refit_rms_passes < 0)
    throw Error(fmt::format("simplify: refit RMS passes must not be negative, got {}", *options.refit_rms_passes));
  if (options.lane_faces && *options.lane_faces < 0)
    throw Error(fmt::format("simplify: faces per lane must not be negative, got {}", *options.lane_faces));
  if (options.max_valence && *options.max_valence < 0)
    throw Error(fmt::format("simplify: the valence limit must not be negative, got {}", *options.max_valence));
  if (!(options.hoppe_points_per_face >= 0 && options.hoppe_points_per_face <= 1000))
    throw Error(fmt::format("simplify: hoppe's random points per face must be between 0 and 1000, got {}",
                            options.hoppe_points_per_face));
  if (!(options.hoppe_points_on_every_face >= 0 && options.hoppe_points_on_every_face <= 1000))
    throw Error(fmt::format("simplify: hoppe's random points on every face must be between 0 and 1000, got {}",
                            options.hoppe_points_on_every_face));
  if (options.hoppe_min_points < 0)
    throw Error(fmt::format("simplify: hoppe's minimum sample points must not be negative, got {}", options.hoppe_min_points));
  if (!(options.hoppe_crease_angle_deg >= 0 && options.hoppe_crease_angle_deg <= 180))
    throw Error(fmt::format("simplify: hoppe's crease angle must be between 0 and 180 degrees, got {}",
                            options.hoppe_crease_angle_deg));
  if (!(std::isfinite(options.hoppe_energy_from) && options.hoppe_energy_from >= 0))
    throw Error(fmt::format("simplify: hoppe's energy-from factor must be finite and not negative, got {}",
                            options.hoppe_energy_from));
  if (options.hoppe_fit_passes < 0)
    throw Error(fmt::format("simplify: hoppe's fit passes must not be negative, got {}", options.hoppe_fit_passes));
  const AttributeWeights& w = options.attribute_weights;
  for (const auto& [name, weight] : {std::pair{"normals", w.normals}, {"UVs", w.uvs}, {"colours", w.colours}})
    if (!(std::isfinite(weight) && weight >= 0))
      throw Error(fmt::format("simplify: the {} weight must be finite and not negative, got {}", name, weight));
  if (!(std::isfinite(options.crease_weight) && options.crease_weight >= 0))
    throw Error(fmt::format("simplify: the crease weight must be finite and not negative, got {}", options.crease_weight));
  if (!(std::isfinite(options.boundary_weight) && options.boundary_weight >= 0))
    throw Error(fmt::format("simplify: the boundary weight must be finite and not negative, got {}", options.boundary_weight));
  if (!(options.min_triangle_quality >= 0 && options.min_triangle_quality <= 1))
    throw Error(fmt::format("simplify: the triangle quality floor must be between 0 and 1, got {}",
                            options.min_triangle_quality));
}

}  // namespace detail

SimplifyResult simplify(const Mesh& mesh, const SimplifyOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  validate(mesh, "simplify");
  detail::check_options(options);
  // With no limit at all, half the faces.
  const Index target = !options.target_faces && !options.target_ratio && !options.max_error
                           ? mesh.num_faces() / 2
                           : detail::requested_faces(mesh, options);
  if (options.recompute_normals && options.record_collapses)
    throw Error("simplify: recompute_normals cannot be combined with record_collapses");
  // A copy without normals: the engine welds vertices that differed only by them.
  Mesh positions_only;
  if (options.recompute_normals && mesh.has_normals()) {
    positions_only = mesh;
    positions_only.attributes.normals.resize(0, 3);
  }
  const Mesh& engine_input = positions_only.empty() ? mesh : positions_only;
  std::optional<detail::Engine> engine;
  engine.emplace(engine_input, options);
  // Faces that disagree on orientation lock their edges' ends. The engine's setup finds them, so only
  // such an input pays for the turning and a second setup. (Recorded collapses name the caller's corners:
  // build_progressive_mesh() turns its input itself.)
  Mesh turned;
  Index turned_faces = 0;
  if (options.orient_faces && !options.record_collapses && engine->faces_disagree()) {
    turned = engine_input;
    turned_faces = orient_consistently(turned);
    if (turned_faces > 0) engine.emplace(turned, options);
  }
  const Mesh& reference = turned_faces > 0 ? turned : mesh;  // what the refit fits to
  // The input's side of the refit (its tree, its samples) is made beside the collapses, which leave a core
  // idle while one queue finishes; it serves the refit and the attribute fit both.
  std::optional<detail::RefitInput> fitted_to;
  RefitOptions refit = detail::refit_options(mesh, options, detail::starting_total_turn_deg(options));
  tbb::task_group beside;
  if (detail::refits(refit) && !options.record_collapses && target < mesh.num_faces())
    beside.run([&] { fitted_to.emplace(reference, refit.avoid_inverted); });
  SimplifyResult r = engine->run(target);
  beside.wait();
  engine.reset();
  r.reoriented_faces = turned_faces;
  // The faces keep within the limits the collapses kept: the same turn from their input faces.
  if (r.turn_limit_relaxed_at) refit.max_total_turn_deg = detail::kRelaxedTotalTurnDeg;
  if (fitted_to && r.collapses > 0 && detail::needs_refit(reference, r.mesh, refit, r.face_origin))
    r.refit = detail::refit_to_input(*fitted_to, r.mesh, refit, r.face_origin);
  if (options.recompute_normals) r.mesh.attributes.normals = compute_vertex_normals(r.mesh);
  if (r.collapses > 0) r.attribute_fit = detail::fit_simplified_attributes(reference, fitted_to ? &fitted_to->tree : nullptr, r.mesh, options);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

namespace detail {

RefitOptions refit_options(const Mesh& mesh, const SimplifyOptions& options, double total_turn_deg) {
  // The refit makes no face face against the input unless that was asked for: hoppe's collapses allow
  // such faces by default (they cost its energy little), but a refit that moves every vertex at once
  // would otherwise add some.
  const InvertedFaces inverted = options.inverted_faces.value_or(InvertedFaces::Avoid);
  const int passes = options.preserve_topology ? options.refit_passes.value_or(default_refit_passes(options.method, mesh.num_faces())) : 0;
  // The second stage follows the first by default; given where the first is off, it runs alone.
  const int rms_passes = options.preserve_topology ? options.refit_rms_passes.value_or(passes > 0 ? kDefaultRefitRmsPasses : 0) : 0;
  // hoppe's energy fits the squared distances already, and a refit weighted less steeply keeps its RMS
  // (bunny -> 1 %: RMS 0.127 % -> 0.111 % with exponent 2, 0.122 % with 6; docs/benchmarks-log.md).
  return {.passes = passes,
          .exponent = options.method == SimplifyMethod::Hoppe ? 2.0 : 6.0,
          .max_step_turn_deg = std::min(30.0, options.max_normal_change_deg),
          .max_total_turn_deg = total_turn_deg,
          .min_triangle_quality = options.min_triangle_quality,
          .avoid_inverted = inverted != InvertedFaces::Allow,
          .fix_boundary = options.lock_boundary,
          .rms_passes = rms_passes};
}

}  // namespace detail

int attribute_values_per_vertex(const Mesh& mesh) {
  return 3 * mesh.has_normals() + 2 * mesh.has_uvs() + 4 * mesh.has_colours();
}

Index default_lane_faces(SimplifyMethod method) { return method == SimplifyMethod::Hoppe ? 8000 : 125000; }

int default_refit_passes(SimplifyMethod method, Index input_faces) {
  return method != SimplifyMethod::EdgeLength && input_faces <= 500'000 ? 10 : 0;
}

Index default_max_valence(SimplifyMethod method) { return method == SimplifyMethod::Hoppe ? 24 : 0; }

InvertedFaces default_inverted_faces(SimplifyMethod method) {
  return method == SimplifyMethod::Quadric ? InvertedFaces::Avoid : InvertedFaces::Allow;
}

double default_max_total_normal_change(SimplifyMethod method) { return method == SimplifyMethod::Quadric ? 90.0 : 60.0; }

std::string to_string(SimplifyMethod method) {
  switch (method) {
    case SimplifyMethod::Quadric: return "quadric";
    case SimplifyMethod::Hoppe: return "hoppe";
    case SimplifyMethod::EdgeLength: return "edge-length";
  }
  return "?";
}

std::optional<SimplifyMethod> parse_method(const std::string& name) {
  for (const SimplifyMethod method : {SimplifyMethod::Quadric, SimplifyMethod::Hoppe, SimplifyMethod::EdgeLength})
    if (name == to_string(method)) return method;
  return std::nullopt;
}

std::string to_string(InvertedFaces mode) {
  switch (mode) {
    case InvertedFaces::Allow: return "allow";
    case InvertedFaces::Avoid: return "avoid";
    case InvertedFaces::Refuse: return "refuse";
  }
  return "?";
}

std::optional<InvertedFaces> parse_inverted_faces(const std::string& name) {
  for (const InvertedFaces mode : {InvertedFaces::Allow, InvertedFaces::Avoid, InvertedFaces::Refuse})
    if (name == to_string(mode)) return mode;
  return std::nullopt;
}

}  // namespace lodkit

