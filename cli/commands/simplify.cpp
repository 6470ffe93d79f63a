// lodkit simplify: edge-collapse simplification (quadric, hoppe, edge-length).
#include <lodkit/decimate.h>
#include <lodkit/error.h>
#include <lodkit/metrics.h>
#include <lodkit/progressive.h>
#include <lodkit/simplify.h>

#include <cstdio>
#include <fmt/format.h>
#include <memory>
#include <unistd.h>

#include "common.h"

namespace lodkit::cli {
namespace {

struct SimplifyCliOptions {
  std::string input, output;
  std::optional<std::string> format;
  std::string method = "quadric", placement = "optimal";
  std::optional<Index> faces;
  std::optional<double> ratio;
  std::optional<std::string> max_error, max_hausdorff;
  std::optional<double> pixel_error;  // --max-hausdorff from a screen-space budget
  double distance = ScreenSpaceBudget{}.distance, fov = ScreenSpaceBudget{}.fov_degrees,
         viewport = ScreenSpaceBudget{}.viewport_pixels;
  bool preserve_boundary = false, lock_boundary = false, allow_topology_change = false;
  bool measure = false, json = false, recompute_normals = false, no_inverted_faces = false, keep_orientation = false;
  bool no_attribute_fit = false;
  std::optional<std::string> inverted_faces;  // allow|avoid|refuse; unset: by method
  double max_normal_change = SimplifyOptions{}.max_normal_change_deg, crease_weight = SimplifyOptions{}.crease_weight;
  std::vector<double> attribute_weights;
  double feature_angle = 30.0, aspect_ratio = 0.1;
  bool accumulate_error = false;
  std::uint64_t seed = 1;
  double hoppe_samples = SimplifyOptions{}.hoppe_points_per_face;
  double hoppe_every_face = SimplifyOptions{}.hoppe_points_on_every_face;
  Index hoppe_min_points = SimplifyOptions{}.hoppe_min_points;
  double hoppe_crease_angle = SimplifyOptions{}.hoppe_crease_angle_deg;
  int hoppe_fit_passes = SimplifyOptions{}.hoppe_fit_passes;
  double hoppe_energy_from = SimplifyOptions{}.hoppe_energy_from;
  Index lane_faces = -1;  // unset: by method
  Index max_valence = -1;  // unset: by method
  int refit_passes = -1;   // unset: by method
  int refit_rms_passes = -1;  // unset: after the first stage
  double max_total_normal_change = -1;  // unset: by method
};

// "0.5" is absolute; "0.5%" is a percentage of the bounding-box diagonal.
double parse_error(const std::string& text, double diagonal, const char* option = "--max-error") {
  const LengthArgument error = parse_length(text, fmt::format("simplify: {}", option));
  return error.relative ? error.value * diagonal : error.value;
}

const char* reason_name(StopReason reason) {
  switch (reason) {
    case StopReason::TargetReached: return "target";
    case StopReason::ErrorLimit: return "error-limit";
    case StopReason::NoLegalCollapse: return "no-legal-collapse";
    case StopReason::HausdorffLimit: return "hausdorff-limit";
  }
  return "unknown";
}

// --max-hausdorff: the proof behind the output and the level that failed.
nlohmann::json within_json(const SimplifyResult::HausdorffLimit& w, double pct) {
  nlohmann::json j{{"max_distance", w.max_distance}, {"max_distance_percent", w.max_distance * pct},
                   {"bound", w.bound}, {"bound_percent", w.bound * pct}, {"checks", w.checks}};
  if (w.coarser_faces) {
    j["coarser_faces"] = *w.coarser_faces;
    j["coarser_attained"] = w.coarser_attained;
    j["coarser_attained_percent"] = w.coarser_attained * pct;
    j["coarser_at"] = {w.coarser_at.x(), w.coarser_at.y(), w.coarser_at.z()};
  }
  return j;
}

// When a rule with an option held edges back, name the option. Faces turning too far: CAD parts stop
// short at the default 60 degrees (docs/commands/simplify.md, "CAD parts that stop short"). (Without
// the checks, --allow-topology-change, nothing is blocked by flips.) The valence limit: a vertex with
// many faces. Seams, where the input has normals: flat shading splits every vertex by its normals, and
// then every edge is a seam.
std::optional<std::string> stop_hint(const SimplifyResult& r, const SimplifyCliOptions& o, const Mesh& input) {
  if (r.reason == StopReason::TargetReached) return std::nullopt;
  std::string hint;
  if (r.blocked.seams > 0 && input.has_normals() && !o.recompute_normals)
    hint = fmt::format("{} of the {} edges left are attribute seams; where the input's normals split its vertices "
                       "(flat shading), --recompute-normals ignores them and gives the output smooth normals",
                       r.blocked.seams, r.blocked.remaining);
  if (r.blocked.valence > 0)
    hint += fmt::format("{}{} of the {} edges left would give a vertex more faces than the valence limit; "
                        "--max-valence 0 lifts it",
                        hint.empty() ? "" : "; ", r.blocked.valence, r.blocked.remaining);
  if (r.blocked.flips > 0 && o.max_normal_change < 90)
    hint += fmt::format("{}{} of the {} edges left would turn a face by more than {:g} degrees; --max-normal-change 90 "
                        "lets faces turn further, which often takes CAD parts closer to the target",
                        hint.empty() ? "" : "; ", r.blocked.flips, r.blocked.remaining, o.max_normal_change);
  if (r.blocked.inverted > 0)
    hint += fmt::format("{}{} of the {} edges left would leave a face facing against the input; with "
                        "--inverted-faces avoid such a collapse waits until the others cost four times as much, so the run "
                        "goes on and may leave some",
                        hint.empty() ? "" : "; ", r.blocked.inverted, r.blocked.remaining);
  if (hint.empty()) return std::nullopt;
  return hint + " (docs/commands/simplify.md)";
}

nlohmann::json blocked_json(const BlockedEdges& b) {
  return {{"remaining", b.remaining}, {"locked", b.locked},   {"topology", b.topology},
          {"boundary", b.boundary},   {"seams", b.seams},     {"flips", b.flips},       {"inverted", b.inverted},
          {"slivers", b.slivers},     {"valence", b.valence},     {"error_limit", b.error_limit},
          {"cost", b.cost}};
}

// --measure, for every method: lodkit compare's distances, and the faces facing against the input face
// nearest their centroid (what SimplifyOptions::inverted_faces avoids or refuses).
struct Measured {
  Comparison distances;
  Index inverted_faces = 0;
};

// Nothing when the output has no faces (every face of the input was degenerate): there is no surface to
// measure, and failing there, after the output was written, would report a run that did its job as failed.
// Faces count as facing against the input as the method saw it: with its faces turned to agree where
// they did not (`reoriented` of them; orient_faces), else half of a shuffled input's would.
std::optional<Measured> measure(const Mesh& input, const Mesh& output, Index reoriented) {
  if (output.num_faces() == 0) return std::nullopt;
  if (reoriented == 0) return Measured{compare(input, output), count_flipped_faces(input, output)};
  Mesh turned = input;
  orient_consistently(turned);
  return Measured{compare(input, output), count_flipped_faces(turned, output)};
}

constexpr const char* kNotMeasured = "the output has no faces";

// j["measured"], or null and j["not_measured"] when there was nothing to measure.
void put_measured(nlohmann::json& j, const std::optional<Measured>& m) {
  if (!m) {
    j["measured"] = nullptr, j["not_measured"] = kNotMeasured;
    return;
  }
  const Comparison& c = m->distances;
  const Eigen::Vector3d& at = c.farther().max_at;  // on the input or on the output
  j["measured"] = {{"hausdorff", c.hausdorff}, {"hausdorff_percent", c.percent(c.hausdorff)},
                   {"hausdorff_at", {at.x(), at.y(), at.z()}},
                   {"hausdorff_bound", c.hausdorff_bound}, {"hausdorff_bound_percent", c.percent(c.hausdorff_bound)}, {"rms", c.rms},
                   {"rms_percent", c.percent(c.rms)}, {"inverted_faces", m->inverted_faces}};
  if (c.colour_rms) j["measured"]["colour_rms"] = *c.colour_rms;
  if (c.shading_rms_deg) j["measured"]["shading_rms_deg"] = *c.shading_rms_deg;
  if (c.uv_rms) j["measured"]["uv_rms"] = *c.uv_rms;
}

void print_measured(const std::optional<Measured>& m) {
  if (!m) {
    fmt::print(stderr, "  not measured: {}\n", kNotMeasured);
    return;
  }
  const Comparison& c = m->distances;
  const Eigen::Vector3d& at = c.farther().max_at;  // on the input or on the output
  fmt::print(stderr, "  measured: Hausdorff {:.6g} ({:.4f}%) at ({:.6g}, {:.6g}, {:.6g}), RMS {:.6g} ({:.4f}%), {} faces facing against the input\n",
             c.hausdorff, c.percent(c.hausdorff), at.x(), at.y(), at.z(), c.rms, c.percent(c.rms), m->inverted_faces);
  if (c.colour_rms) fmt::print(stderr, "  measured: colour RMS {:.6g} (both directions; channels 0..1)\n", *c.colour_rms);
  if (c.shading_rms_deg)
    fmt::print(stderr, "  measured: shading normals RMS {:.3f} deg (both directions)\n", *c.shading_rms_deg);
  if (c.uv_rms) fmt::print(stderr, "  measured: UV RMS {:.6g} (both directions, within charts)\n", *c.uv_rms);
}

int run_schroeder(const SimplifyCliOptions& o, const GlobalOptions& global, const Mesh& mesh, double diagonal) {
  DecimateOptions d;
  d.target_faces = o.faces;
  d.target_ratio = o.ratio;
  if (o.max_error) d.max_error = parse_error(*o.max_error, diagonal);
  d.feature_angle_deg = o.feature_angle;
  d.aspect_ratio = o.aspect_ratio;
  d.accumulate_error = o.accumulate_error;
  d.orient_faces = !o.keep_orientation;
  d.fit_attributes = !o.no_attribute_fit;
  if (o.inverted_faces) d.inverted_faces = *parse_inverted_faces(*o.inverted_faces);  // (checked by the option)
  if (o.no_inverted_faces) d.inverted_faces = InvertedFaces::Refuse;
  DecimateResult r = decimate(mesh, d);
  if (o.recompute_normals) r.mesh.attributes.normals = compute_vertex_normals(r.mesh);
  write_output(r.mesh, o.output, o.format, WriteOptions{}, {o.input});
  std::optional<Measured> measured;
  if (o.measure) measured = measure(mesh, r.mesh, r.reoriented_faces);
  const double pct = diagonal > 0 ? 100.0 / diagonal : 0.0;
  const auto& c = r.remaining_by_class;
  if (o.json) {
    nlohmann::json j{{"input", o.input}, {"output", o.output}, {"method", "schroeder"}, {"faces_in", r.faces_in},
                     {"faces_out", r.faces_out}, {"vertices_in", r.vertices_in}, {"vertices_out", r.vertices_out},
                     {"removed", r.removed}, {"reoriented_faces", r.reoriented_faces}, {"seconds", r.seconds}, {"error_estimate", r.error},
                     {"error_estimate_percent", r.error * pct}, {"target_reached", r.target_reached},
                     {"reason_text", r.reason_text},
                     {"remaining", {{"simple", c[0]}, {"complex", c[1]}, {"boundary", c[2]}, {"interior_edge", c[3]},
                                    {"corner", c[4]}, {"above_threshold", r.remaining_above_threshold},
                                    {"no_triangulation", r.remaining_no_triangulation}}}};
    if (r.attribute_fit) j["attribute_fit"] = attribute_fit_json(*r.attribute_fit);
    if (r.inverted_allowed_at) j["inverted_allowed_at_faces"] = *r.inverted_allowed_at;
    if (o.measure) put_measured(j, measured);
    fmt::print("{}\n", j.dump(2));
  } else if (!global.quiet) {
    fmt::print(stderr, "simplify (schroeder): {} -> {} faces, {} -> {} vertices in {:.3f} s\n", thousands(r.faces_in),
               thousands(r.faces_out), thousands(r.vertices_in), thousands(r.vertices_out), r.seconds);
    print_reoriented(r.reoriented_faces);
    fmt::print(stderr, "  largest removal error {:.6g} ({:.4f}% of the diagonal){}\n", r.error, r.error * pct,
               d.accumulate_error ? ", accumulated" : "");
    if (r.attribute_fit) print_attribute_fit(*r.attribute_fit);
    if (o.measure) print_measured(measured);
    fmt::print(stderr, "  {}\n", r.reason_text);
    if (!r.target_reached && r.remaining_inverted > 0 && d.inverted_faces == InvertedFaces::Refuse)
      fmt::print(stderr, "  hint: --inverted-faces avoid lets such a removal be once a pass's threshold is twice its "
                         "error; allow never checks\n");
  }
  return 0;
}

int run_simplify(SimplifyCliOptions o, const GlobalOptions& global) {
  // --format names the format of stdin and stdout ("-"); files go by their extension, so that
  // `simplify in.ply -o - --format off` reads PLY and writes OFF.
  if (o.format && o.input != "-" && o.output != "-")
    throw Error(fmt::format("simplify: --format {} names the format of stdin or stdout (-), and neither is used", *o.format));
  refuse_json_beside_stdout(o.json, o.output);
  const Mesh mesh = read_input(o.input, o.input == "-" ? o.format : std::nullopt);
  if (o.output != "-") o.format.reset();
  if (o.method == "schroeder") {
    const auto b = bounding_box(mesh);
    return run_schroeder(o, global, mesh, b.isEmpty() ? 0.0 : b.diagonal().norm());
  }
  SimplifyOptions s;
  s.method = *parse_method(o.method);
  s.placement = o.placement == "endpoint" ? Placement::Endpoint
                : o.placement == "midpoint" ? Placement::Midpoint : Placement::Optimal;
  s.target_faces = o.faces;
  s.target_ratio = o.ratio;
  const auto box = bounding_box(mesh);
  const double diagonal = box.isEmpty() ? 0.0 : box.diagonal().norm();
  if (o.max_error) s.max_error = parse_error(*o.max_error, diagonal);
  s.lock_boundary = o.lock_boundary;
  if (o.preserve_boundary) s.boundary_weight = 1000.0;
  s.preserve_topology = !o.allow_topology_change;
  s.max_normal_change_deg = o.max_normal_change;
  if (o.max_total_normal_change >= 0) s.max_total_normal_change_deg = o.max_total_normal_change;
  s.crease_weight = o.crease_weight;
  if (!o.attribute_weights.empty()) {
    if (o.attribute_weights.size() != 3)
      throw Error("simplify: --attribute-weights takes three numbers: normals,uvs,colours");
    s.attribute_weights = {o.attribute_weights[0], o.attribute_weights[1], o.attribute_weights[2]};
  }
  s.recompute_normals = o.recompute_normals;
  s.fit_attributes = !o.no_attribute_fit;
  s.orient_faces = !o.keep_orientation;
  if (o.inverted_faces) s.inverted_faces = parse_inverted_faces(*o.inverted_faces);
  if (o.no_inverted_faces) s.inverted_faces = InvertedFaces::Refuse;
  s.seed = o.seed;
  s.hoppe_points_per_face = o.hoppe_samples;
  s.hoppe_points_on_every_face = o.hoppe_every_face;
  s.hoppe_min_points = o.hoppe_min_points;
  s.hoppe_crease_angle_deg = o.hoppe_crease_angle;
  s.hoppe_fit_passes = o.hoppe_fit_passes;
  s.hoppe_energy_from = o.hoppe_energy_from;
  if (o.lane_faces >= 0) s.lane_faces = o.lane_faces;
  if (o.max_valence >= 0) s.max_valence = o.max_valence;
  if (o.refit_passes >= 0) s.refit_passes = o.refit_passes;
  if (o.refit_rms_passes >= 0) s.refit_rms_passes = o.refit_rms_passes;
  const bool show_progress = !global.quiet && !o.json && isatty(STDERR_FILENO) && mesh.num_faces() > 200'000;
  if (show_progress)
    s.progress = [](double f) {
      const int width = 40, filled = static_cast<int>(f * width);
      std::fprintf(stderr, "\rsimplify [%s%s] %3d%%", std::string(filled, '#').c_str(),
                   std::string(width - filled, ' ').c_str(), static_cast<int>(100 * f));
      if (f >= 1.0) std::fputc('\n', stderr);
    };

  // A pixel budget is a Hausdorff limit: the largest distance that projects to that many pixels at the
  // nearest point of the bounding sphere (as pm extract --pixel-error measures it).
  std::optional<double> limit;
  if (o.max_hausdorff) limit = parse_error(*o.max_hausdorff, diagonal, "--max-hausdorff");
  if (o.pixel_error) {
    limit = object_error_for_pixels(0.5 * diagonal, {*o.pixel_error, o.distance, o.fov, o.viewport});
    if (*limit == 0 && !global.quiet)
      fmt::print(stderr, "simplify: note: at --distance {:g} the eye is inside the bounding sphere (radius {:.6g}), where "
                 "any error can fill the screen: the output is the input\n", o.distance, 0.5 * diagonal);
  }
  const SimplifyResult r = limit ? simplify_within(mesh, *limit, s) : simplify(mesh, s);
  write_output(r.mesh, o.output, o.format, WriteOptions{}, {o.input});

  std::optional<Measured> measured;
  if (o.measure) measured = measure(mesh, r.mesh, r.reoriented_faces);
  const double pct = diagonal > 0 ? 100.0 / diagonal : 0.0;
  const std::optional<std::string> hint = stop_hint(r, o, mesh);
  if (o.json) {
    nlohmann::json j{{"input", o.input}, {"output", o.output}, {"method", o.method},
                     {"faces_in", r.faces_in}, {"faces_out", r.faces_out}, {"vertices_in", r.vertices_in},
                     {"vertices_out", r.vertices_out}, {"target_faces", r.target_faces},
                     {"collapses", r.collapses}, {"seconds", r.seconds}, {"error_estimate", r.error},
                     {"error_estimate_percent", r.error * pct}, {"reason", reason_name(r.reason)},
                     {"reason_text", r.reason_text}, {"locked_vertices", r.locked_vertices}, {"lanes", r.lanes},
                     {"dropped_degenerate_faces", r.dropped_degenerate_faces},
                     {"reoriented_faces", r.reoriented_faces}};
    if (r.reason != StopReason::TargetReached && !r.within) j["blocked"] = blocked_json(r.blocked);
    if (r.within) {
      j["hausdorff_limit"] = within_json(*r.within, pct);
      j.erase("error_estimate"), j.erase("error_estimate_percent");  // not estimated: proved instead
    }
    if (o.pixel_error)
      j["hausdorff_limit"]["view"] = {{"pixel_error", *o.pixel_error}, {"distance", o.distance}, {"fov", o.fov},
                                      {"viewport", o.viewport}};
    if (r.turn_limit_relaxed_at) j["turn_limit_relaxed_at_faces"] = *r.turn_limit_relaxed_at;
    if (r.hoppe_energy_from_faces) j["hoppe_energy_from_faces"] = *r.hoppe_energy_from_faces;
    if (r.hoppe_fit)
      j["hoppe_fit"] = {{"passes", r.hoppe_fit->passes}, {"energy_before", r.hoppe_fit->energy_before},
                        {"energy_after", r.hoppe_fit->energy_after}, {"points_sent_back", r.hoppe_fit->points_sent_back},
                        {"seconds", r.hoppe_fit->seconds}};
    if (r.attribute_fit) j["attribute_fit"] = attribute_fit_json(*r.attribute_fit);
    if (r.inverted_allowed_at) j["inverted_allowed_at_faces"] = *r.inverted_allowed_at;
    if (r.refit)
      j["refit"] = {{"passes", r.refit->passes}, {"steps", r.refit->steps}, {"rms_steps", r.refit->rms_steps},
                    {"moved_vertices", r.refit->moved_vertices},
                    {"inverted_before", r.refit->inverted_before}, {"inverted_after", r.refit->inverted_after},
                    {"turn_steps", r.refit->turn_steps},
                    {"sampled_max_before", r.refit->sampled_max_before},
                    {"sampled_max_before_percent", r.refit->sampled_max_before * pct},
                    {"sampled_max_after", r.refit->sampled_max_after},
                    {"sampled_max_after_percent", r.refit->sampled_max_after * pct},
                    {"sampled_rms_before", r.refit->sampled_rms_before},
                    {"sampled_rms_before_percent", r.refit->sampled_rms_before * pct},
                    {"sampled_rms_after", r.refit->sampled_rms_after},
                    {"sampled_rms_after_percent", r.refit->sampled_rms_after * pct}, {"seconds", r.refit->seconds}};
    if (hint) j["hint"] = *hint;
    if (o.measure) put_measured(j, measured);
    if (measured) {
      const Comparison& c = measured->distances;
      j["measured"]["mean"] = c.mean;
      j["measured"]["normal_deviation_mean_deg"] =
          0.5 * (c.a_to_b.normal_deviation_mean_deg + c.b_to_a.normal_deviation_mean_deg);
    }
    fmt::print("{}\n", j.dump(2));
  } else if (!global.quiet) {
    fmt::print(stderr, "simplify ({}): {} -> {} faces, {} -> {} vertices in {:.3f} s\n", o.method,
               thousands(r.faces_in), thousands(r.faces_out), thousands(r.vertices_in), thousands(r.vertices_out),
               r.seconds);
    print_reoriented(r.reoriented_faces);
    if (r.within)
      fmt::print(stderr, "  Hausdorff distance to the input proved at most {:.6g} ({:.4f}%), {} levels checked\n",
                 r.within->bound, r.within->bound * pct, r.within->checks);
    else
      fmt::print(stderr, "  error estimate {:.6g} ({:.4f}% of the diagonal)\n", r.error, r.error * pct);
    if (r.lanes > 1) fmt::print(stderr, "  {} slabs simplified side by side, then one queue for the rest\n", r.lanes);
    if (r.hoppe_energy_from_faces)
      fmt::print(stderr, "  the quadric error ranked the collapses down to {} faces, hoppe's energy from there\n",
                 thousands(*r.hoppe_energy_from_faces));
    if (r.refit)
      fmt::print(stderr, "  refit: largest sampled distance {:.4f}% -> {:.4f}%, RMS {:.5f}% -> {:.5f}%, in {} + {} steps ({:.3f} s)\n",
                 r.refit->sampled_max_before * pct, r.refit->sampled_max_after * pct, r.refit->sampled_rms_before * pct,
                 r.refit->sampled_rms_after * pct, r.refit->steps, r.refit->rms_steps, r.refit->seconds);
    if (r.refit && r.refit->inverted_before > 0)
      fmt::print(stderr, "  refit: {} of {} faces facing against the input turned to face it, in {} rounds\n",
                 r.refit->inverted_before - r.refit->inverted_after, r.refit->inverted_before, r.refit->turn_steps);
    if (r.hoppe_fit)
      fmt::print(stderr, "  hoppe's fit: energy {:.6g} -> {:.6g} ({:+.1f}%) in {} pass{}, {} moves sent back ({:.3f} s)\n",
                 r.hoppe_fit->energy_before, r.hoppe_fit->energy_after,
                 r.hoppe_fit->energy_before > 0 ? 100.0 * (r.hoppe_fit->energy_after / r.hoppe_fit->energy_before - 1) : 0.0,
                 r.hoppe_fit->passes, r.hoppe_fit->passes == 1 ? "" : "es", r.hoppe_fit->points_sent_back, r.hoppe_fit->seconds);
    if (r.attribute_fit) print_attribute_fit(*r.attribute_fit);
    if (r.dropped_degenerate_faces > 0)
      fmt::print(stderr, "  dropped {} degenerate faces of the input (corners not three distinct points)\n",
                 thousands(r.dropped_degenerate_faces));
    if (o.measure) print_measured(measured);
    fmt::print(stderr, "  {}\n", r.reason_text);
    if (hint) fmt::print(stderr, "  hint: {}\n", *hint);
  }
  if (r.reason != StopReason::TargetReached && !global.quiet && o.json) {
    fmt::print(stderr, "simplify: {}\n", r.reason_text);
    if (hint) fmt::print(stderr, "simplify: hint: {}\n", *hint);
  }
  return 0;
}

}  // namespace

Command add_simplify_command(CLI::App& app, const GlobalOptions& global) {
  auto opt = std::make_shared<SimplifyCliOptions>();
  CLI::App* sub = app.add_subcommand("simplify", "Simplify a mesh by edge collapses");
  sub->add_option("input", opt->input, "Input mesh, or - for stdin (with --format)")->required();
  sub->add_option("-o,--output", opt->output, "Output mesh, or - for stdout (with --format)")->required();
  sub->add_option("--format", opt->format, "Format of stdin/stdout")->check(format_validator());
  sub->add_option("--method", opt->method, "quadric (default), hoppe, edge-length, or schroeder (vertex decimation)")
      ->check(CLI::IsMember({"quadric", "hoppe", "edge-length", "schroeder"}))->capture_default_str();
  sub->add_option("--placement", opt->placement, "optimal, endpoint or midpoint")
      ->check(CLI::IsMember({"optimal", "endpoint", "midpoint"}))->capture_default_str();
  sub->add_option("--faces", opt->faces, "Target face count")->check(kNonNegative);
  sub->add_option("--ratio", opt->ratio, "Target as a fraction of the input faces (0-1)")->check(in_range(0.0, 1.0));
  sub->add_option("--max-error", opt->max_error, "Largest error per collapse: a distance, or N% of the diagonal");
  auto* max_hausdorff = sub->add_option("--max-hausdorff", opt->max_hausdorff,
                  "The coarsest result found whose Hausdorff distance to the input is proved at most this: a "
                  "distance, or N% of the diagonal (levels checked by branch and bound; slower)");
  auto* pixel_error = sub->add_option("--pixel-error", opt->pixel_error,
                  "The same limit from a screen-space budget: the distance that projects to this many pixels at "
                  "--distance, --fov and --viewport")->check(kNonNegative);
  pixel_error->excludes(max_hausdorff);
  sub->add_option("--distance", opt->distance, "Eye to bounding-sphere centre (with --pixel-error)")->needs(pixel_error)
      ->capture_default_str();
  sub->add_option("--fov", opt->fov, "Vertical field of view, degrees (with --pixel-error)")->needs(pixel_error)
      ->check(in_range(0.01, 179.99))->capture_default_str();
  sub->add_option("--viewport", opt->viewport, "Viewport height, pixels (with --pixel-error)")->needs(pixel_error)
      ->check(kPositive)->capture_default_str();
  sub->add_flag("--preserve-boundary", opt->preserve_boundary, "Weight boundary constraint planes 100x higher");
  sub->add_flag("--lock-boundary", opt->lock_boundary, "Never move or remove boundary vertices");
  sub->add_flag("--allow-topology-change", opt->allow_topology_change,
                "Skip the link condition and flip checks (shows how naive methods fail)");
  sub->add_option("--max-normal-change", opt->max_normal_change, "Largest turn of a face in one collapse (degrees)")
      ->check(in_range(1.0, 180.0))->capture_default_str();
  sub->add_option("--max-total-normal-change", opt->max_total_normal_change,
                  "Largest turn of a face from its input orientation over all collapses, never below "
                  "--max-normal-change (degrees; default 90 for quadric, 60 for hoppe and edge-length, raised "
                  "to 90 where 60 alone would stop the run short of its target; a value given here is kept)")
      ->check(in_range(1.0, 180.0));
  sub->add_option("--crease-weight", opt->crease_weight,
                  "Weight of the planes that keep thin fins, spikes and sharp ridges (quadric; 0 = off)")
      ->check(kNonNegative)->capture_default_str();
  sub->add_option("--attribute-weights", opt->attribute_weights,
                  "Weights of normal, UV and colour error against geometry, e.g. 0.5,1,1 (quadric: attribute quadrics; hoppe: E_scalar; default off)")
      ->delimiter(',')->check(kNonNegative);
  sub->add_option("--feature-angle", opt->feature_angle, "schroeder: dihedral angle that makes a feature edge (degrees)")
      ->check(in_range(0.1, 180.0))->capture_default_str();
  sub->add_option("--aspect-ratio", opt->aspect_ratio, "schroeder: smallest split-line quality for re-triangulation")
      ->check(kNonNegative)->capture_default_str();
  sub->add_flag("--accumulate-error", opt->accumulate_error, "schroeder: add each removal's error to its neighbours");
  sub->add_option("--seed", opt->seed, "Seed for hoppe's surface samples")->capture_default_str();
  sub->add_option("--hoppe-samples", opt->hoppe_samples,
                  "hoppe: random surface points per face besides the vertices, on average (fewer than 4 leave "
                  "the springs strong: slow and less accurate on smooth meshes)")
      ->check(in_range(0.0, 1000.0))->capture_default_str();
  sub->add_option("--hoppe-every-face", opt->hoppe_every_face,
                  "hoppe: of those, how many go on every face however small; the rest are spread by area "
                  "(default 2; 1000: all per face)")
      ->check(in_range(0.0, 1000.0))->capture_default_str();
  sub->add_option("--hoppe-min-points", opt->hoppe_min_points,
                  "hoppe: the fewest sample points in all; smaller meshes get more per face (0 = no floor)")
      ->check(kNonNegative)->capture_default_str();
  sub->add_option("--hoppe-crease-angle", opt->hoppe_crease_angle,
                  "hoppe: input edges whose faces turn by more than this get points along them, so that a sharp "
                  "edge cannot be bevelled unseen (degrees; 180 = none)")
      ->check(in_range(0.0, 180.0))->capture_default_str();
  sub->add_option("--hoppe-fit-passes", opt->hoppe_fit_passes,
                  "hoppe: after the collapses, move every vertex at once to lower E_dist + E_spring (Mesh "
                  "optimization's position step), in this many passes (0 = none)")
      ->check(kNonNegative)->capture_default_str();
  sub->add_option("--hoppe-energy-from", opt->hoppe_energy_from,
                  "hoppe: its energy ranks the collapses once the mesh is within this many times the face target; "
                  "the quadric error ranks the early, small ones, as well and in a fraction of the time (up to 1 = "
                  "the energy from the first collapse, as in the paper)")
      ->check(in_range(0.0, 1e9))->capture_default_str();
  sub->add_option("--lane-faces", opt->lane_faces,
                  "Meshes of twice this many faces are first simplified in slabs of about this many faces side by "
                  "side (0 = one queue throughout; default 125000 for quadric and edge-length, 8000 for hoppe)")
      ->check(kNonNegative);
  sub->add_option("--max-valence", opt->max_valence,
                  "No collapse may leave a vertex with more faces around it than this, unless it had as many before "
                  "(0 = no limit; default 24 for hoppe, which otherwise grows hubs on flat parts; none for the others)")
      ->check(kNonNegative);
  sub->add_option("--refit-passes", opt->refit_passes,
                  "After the collapses, fit every vertex to the input at once, towards the largest distances, in this "
                  "many sampling passes (0 = no refit; default 10 for quadric and hoppe on inputs up to 500,000 faces, "
                  "else 0)")
      ->check(CLI::Range(0, 1000));
  sub->add_option("--refit-rms-passes", opt->refit_rms_passes,
                  "Then fit the squared distances (the RMS) in this many passes, no sample getting farther than "
                  "the larger of its own distance and 0.9 times the largest (default 8 after a first stage, else 0; "
                  "given where the first stage is off, e.g. with --refit-passes 0, this stage runs alone)")
      ->check(CLI::Range(0, 1000));
  sub->add_flag("--recompute-normals", opt->recompute_normals,
                "Ignore the input's normals (flat shading makes every edge a seam) and write area-weighted ones");
  sub->add_flag("--no-attribute-fit", opt->no_attribute_fit,
                "Keep the normals, UVs and colours the collapses left, rather than fit them to the input's at the end "
                "(least squares over points on both surfaces; positions untouched). schroeder: write positions only");
  add_keep_orientation_flag(sub, opt->keep_orientation);
  add_inverted_faces_option(sub, opt->inverted_faces);
  sub->add_flag("--no-inverted-faces", opt->no_inverted_faces, "The same as --inverted-faces refuse")
      ->excludes("--inverted-faces");
  sub->add_flag("--measure", opt->measure, "Measure Hausdorff and RMS distance to the input (lodkit compare)");
  sub->add_flag("--json", opt->json, "Print the result as JSON on stdout");
  // An option the chosen method does not read would be ignored in silence: refuse it before anything is read.
  sub->parse_complete_callback([opt, sub] {
    const std::string& m = opt->method;
    auto refuse_unless = [&](bool applies, std::initializer_list<const char*> names, const char* which) {
      if (applies) return;
      for (const char* name : names)
        if (sub->count(name) > 0)
          throw CLI::ValidationError(name, fmt::format("applies to {}, not to --method {}", which, m));
    };
    refuse_unless(m != "schroeder",
                  {"--placement", "--preserve-boundary", "--lock-boundary", "--allow-topology-change",
                   "--max-normal-change", "--max-total-normal-change", "--crease-weight", "--attribute-weights",
                   "--lane-faces", "--max-valence", "--refit-passes", "--refit-rms-passes", "--max-hausdorff",
                   "--pixel-error"},
                  "the edge-collapse methods (quadric, hoppe, edge-length)");
    refuse_unless(m == "schroeder", {"--feature-angle", "--aspect-ratio", "--accumulate-error"}, "--method schroeder");
    refuse_unless(m == "hoppe", {"--seed", "--hoppe-samples", "--hoppe-every-face", "--hoppe-min-points",
                                 "--hoppe-crease-angle", "--hoppe-fit-passes", "--hoppe-energy-from"}, "--method hoppe");
    refuse_unless(m == "quadric", {"--crease-weight"}, "--method quadric");
  });
  sub->footer(R"(Stops at whichever comes first: --faces, --ratio or --max-error (default: half the faces).
--max-error bounds each collapse's error estimate, not the result's distance to the input (often 2-5x more);
--max-hausdorff bounds that distance, proved, and goes as far as the other limits allow; --pixel-error sets
it from what a viewer sees: pixels = distance * viewport / (2 * d * tan(fov / 2)), d = --distance - bounding radius.
Examples:
  lodkit simplify scan.ply -o scan_lo.ply --max-hausdorff 0.2% --json
  lodkit simplify scan.ply -o scan_far.ply --pixel-error 1 --distance 20 --fov 60 --viewport 1080
  lodkit simplify bunny.ply -o bunny_10k.ply --faces 10000
  lodkit simplify scan.obj -o scan_small.obj --ratio 0.05 --measure
  lodkit simplify part.stl -o part_lo.stl --max-error 0.1% --lock-boundary
  lodkit simplify spot.obj -o spot_small.obj --ratio 0.1 --attribute-weights 0,1,0
  lodkit simplify part.obj -o part_lo.obj --method schroeder --max-error 0.05% --feature-angle 30
  lodkit simplify fandisk.obj -o fandisk_lo.ply --ratio 0.1 --method hoppe
  lodkit simplify bunny.ply -o bunny_h.ply --ratio 0.1 --method hoppe --hoppe-fit-passes 3   # refit E in 3 passes
  lodkit simplify bunny.ply -o bunny_h.ply --ratio 0.1 --method hoppe --hoppe-energy-from 0   # the energy throughout
  lodkit simplify counter.ply -o counter_lo.ply --ratio 0.01 --max-normal-change 90
  lodkit simplify suzanne_flat.ply -o suzanne_lo.ply --ratio 0.1 --recompute-normals
  lodkit simplify scan_rgb.ply -o scan_lo.ply --ratio 0.1 --measure   # colours fitted to the input's; their RMS measured
  lodkit simplify human.obj -o human_lo.obj --ratio 0.1 --no-attribute-fit   # normals as the collapses left them
  lodkit simplify horse.ply -o horse_lo.ply --ratio 0.1 --inverted-faces refuse --measure
  lodkit simplify scan_1M.ply -o scan_lo.ply --ratio 0.1 --inverted-faces allow   # faster; faces may face against the input
  lodkit simplify scan.ply -o scan_fast.ply --ratio 0.1 --refit-passes 0   # 2-4x faster; errors as the collapses left them
  lodkit simplify scan.ply -o scan_h.ply --ratio 0.1 --refit-rms-passes 0  # the refit for the largest distances only
  lodkit simplify bunny.ply -o bunny_h.ply --ratio 0.1 --method hoppe --refit-passes 0   # hoppe's own positions, 1.2-1.4x faster
  lodkit simplify bunny.ply -o broken.ply --method edge-length --ratio 0.01 --allow-topology-change)");
  return {sub, [opt, &global] { return run_simplify(*opt, global); }};
}

}  // namespace lodkit::cli
