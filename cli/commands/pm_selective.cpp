// lodkit pm extract --eye / --eye-path: selective (view-dependent) refinement of a .pm stream.
#include <lodkit/error.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <fmt/format.h>
#include <fstream>
#include <limits>
#include <sstream>

#include "commands/pm_command.h"

namespace lodkit::cli::pm {
namespace {

// One viewer of --eye-path (or --eye): where from, where to (unset: --look-at, or the model's centre),
// and the line it came from.
struct PathView {
  Eigen::Vector3d eye;
  std::optional<Eigen::Vector3d> look_at;
  int line = 0;
};

// An --eye-path file: a viewer per line, "x,y,z" or "x,y,z,lx,ly,lz" (the point looked at); blank lines
// and lines starting with # are skipped; commas or spaces between numbers.
std::vector<PathView> read_eye_path(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(fmt::format("{}: cannot open", path));
  std::vector<PathView> views;
  std::string text;
  for (int line = 1; std::getline(in, text); ++line) {
    std::replace(text.begin(), text.end(), ',', ' ');
    std::istringstream fields(text);
    std::vector<double> numbers;
    std::string field;
    while (fields >> field) {
      if (numbers.empty() && field.starts_with('#')) break;
      double x = 0;
      const auto [end, error] = std::from_chars(field.data(), field.data() + field.size(), x);
      if (error != std::errc() || end != field.data() + field.size() || !std::isfinite(x))
        throw Error(fmt::format("{}:{}: '{}' is not a finite number", path, line, field));
      numbers.push_back(x);
    }
    if (numbers.empty()) continue;
    if (numbers.size() != 3 && numbers.size() != 6)
      throw Error(fmt::format("{}:{}: expected 3 numbers (the eye) or 6 (and the point looked at), got {}", path, line, numbers.size()));
    PathView v{{numbers[0], numbers[1], numbers[2]}, std::nullopt, line};
    if (numbers.size() == 6) v.look_at = Eigen::Vector3d(numbers[3], numbers[4], numbers[5]);
    views.push_back(v);
  }
  if (views.empty()) throw Error(fmt::format("{}: no eye in the file", path));
  return views;
}

}  // namespace

// pm extract --eye / --eye-path: the splits each viewer needs, fine near the eye and coarse far away or
// out of view. Along a path one mesh is kept from view to view, so each view applies and undoes only
// the splits that change.
int run_selective(const PmCliOptions& o, const GlobalOptions& global, const std::vector<std::string>& inputs) {
  const bool path = o.eye_path.has_value();
  if (!o.pixel_error) throw Error(fmt::format("pm extract: {} needs a budget: --pixel-error", path ? "--eye-path" : "--eye"));
  if (o.faces || o.ratio || o.max_error) throw Error("pm extract: --eye selects by --pixel-error alone");
  if (o.prove_with) throw Error("pm extract: --prove-with proves uniform levels; it does not combine with --eye");
  if (o.input_order) throw Error("pm extract: a selectively refined mesh is in stream order; --input-order does not combine with --eye");
  if (path && !o.eye.empty()) throw Error("pm extract: give --eye or --eye-path, not both");
  if (path && o.output == "-") throw Error("pm extract: --eye-path writes files OUT_000 ...: give OUT a file name");
  if (o.morph_frames > 1 && !path) throw Error("pm extract: --morph-frames blends from view to view: it needs --eye-path");
  if (o.morph_frames > 1 && o.fit_attributes)
    throw Error("pm extract: --fit-attributes does not combine with --morph-frames (fitted values have no ancestors to blend from)");
  const auto start = std::chrono::steady_clock::now();
  const std::vector<PathView> lines = path ? read_eye_path(*o.eye_path) : std::vector<PathView>{{point_option(o.eye), {}, 0}};
  const PmReadResult r = read_pm_input(o.input);
  warn(r, global);
  const ProgressiveMesh& pm = r.pm;
  const LevelErrorKind kind = o.certified ? LevelErrorKind::Bound : LevelErrorKind::Measured;
  const char* what = kind == LevelErrorKind::Bound ? "error bound" : "measured deviation";
  const SelectiveRefiner refiner(pm);
  SelectiveMesh kept(refiner);
  std::optional<Mesh> finest;  // for --fit-attributes
  if (o.fit_attributes) finest = extract_level(pm, pm.max_level(), VertexOrder::Input).mesh;
  // Every viewer first, so that a bad line leaves no view written.
  std::vector<Viewpoint> viewers;
  for (const PathView& pv : lines) {
    Viewpoint& view = viewers.emplace_back();
    view.eye = pv.eye;
    view.look_at = pv.look_at ? *pv.look_at : o.look_at.empty() ? pm.bounds.center() : point_option(o.look_at);
    if (!o.no_cull && view.look_at == view.eye)
      throw Error(fmt::format("pm extract: {}the eye ({}, {}, {}) is at the point looked at ({}); give a --look-at away from it, "
                              "or --no-cull to refine in every direction",
                              path ? fmt::format("{}:{}: ", *o.eye_path, pv.line) : "", view.eye.x(), view.eye.y(), view.eye.z(),
                              pv.look_at ? "on its line" : o.look_at.empty() ? "the bounding box centre, with no --look-at" : "--look-at"));
    view.fov_degrees = o.fov;
    view.viewport_pixels = o.viewport;
    view.aspect = o.aspect;
    view.pixel_error = *o.pixel_error;
    view.cull = !o.no_cull;
    view.cull_backfaces = o.cull_backfaces;
    view.unfold = !o.allow_folds;
  }
  nlohmann::json reports = nlohmann::json::array();
  Index fewest = std::numeric_limits<Index>::max(), most = 0, changed = 0, unfolding_views = 0;
  double widest = 0;
  // With --morph-frames K, each step from one view to the next is K frames: K - 1 of the geomorph between
  // them (alpha 1/K ... (K-1)/K), then the view itself.
  const std::size_t per_step = static_cast<std::size_t>(o.morph_frames);
  Mesh frame;
  for (std::size_t i = 0; i < viewers.size(); ++i) {
    const Viewpoint& view = viewers[i];
    std::vector<std::string> morph_outputs;
    Index morph_vertices = 0;
    SelectiveLevel s;
    if (i > 0 && per_step > 1) {
      SelectiveMorph m = kept.morph_to_view(view, kind);
      for (std::size_t k = 1; k < per_step; ++k) {
        m.geomorph.evaluate(double(k) / double(per_step), frame);
        morph_outputs.push_back(numbered(o.output, (i - 1) * per_step + k));
        write_output(frame, morph_outputs.back(), o.format, WriteOptions{}, inputs);
      }
      morph_vertices = m.geomorph.fine.mesh.num_vertices();
      s = std::move(m.reached);
    } else {
      s = kept.adapt(view, kind);
    }
    std::optional<AttributeFitReport> fit;
    if (finest) fit = fit_attributes_to_input(*finest, s.extracted.mesh);
    const std::string output = path ? numbered(o.output, i * per_step) : o.output;
    write_output(s.extracted.mesh, output, o.format, WriteOptions{}, inputs);
    // A uniform level within the same budget, for comparison: the one `--distance` would pick from here.
    const ScreenSpaceBudget uniform{view.pixel_error, (pm.bounds.center() - view.eye).norm(), view.fov_degrees, view.viewport_pixels};
    const Index uniform_faces = pm.num_faces(level_for_view(pm, uniform, selection_kind(o)));
    const Index faces = s.extracted.mesh.num_faces();
    fewest = std::min(fewest, faces), most = std::max(most, faces), widest = std::max(widest, s.max_pixels);
    if (i > 0) changed += s.splits_refined + s.splits_coarsened;
    unfolding_views += s.splits_unfolding > 0;
    nlohmann::json j{{"output", output},
                     {"eye", {view.eye.x(), view.eye.y(), view.eye.z()}},
                     {"look_at", {view.look_at.x(), view.look_at.y(), view.look_at.z()}},
                     {"faces", faces},
                     {"vertices", s.extracted.mesh.num_vertices()},
                     {"splits_applied", s.splits_applied},
                     {"splits_refined", s.splits_refined},
                     {"splits_coarsened", s.splits_coarsened},
                     {"splits_unfolding", s.splits_unfolding},
                     {"error_bound", s.error_bound},
                     {"deviation", s.deviation},
                     {"max_pixels", s.max_pixels},
                     {"regions_out_of_view", s.regions_outside},
                     {"regions_facing_away", s.regions_facing_away},
                     {"uniform_level_faces", uniform_faces}};
    if (fit) j["attribute_fit"] = attribute_fit_json(*fit);
    if (!morph_outputs.empty()) j["morph_outputs"] = morph_outputs, j["morph_vertices"] = morph_vertices;
    if (!path && !o.json && !global.quiet) {
      fmt::print(stderr,
                 "pm extract: selective refinement for the eye at ({}, {}, {}): {} faces, {} vertices, {} of {} splits{}; {} "
                 "projects to at most {:.3g} px in view (budget {} px); deviation {:.6g}, bound {:.6g}{}{}; read {} bytes, "
                 "{:.1f} ms\n",
                 view.eye.x(), view.eye.y(), view.eye.z(), thousands(faces), thousands(s.extracted.mesh.num_vertices()),
                 thousands(s.splits_applied), thousands(pm.max_level()),
                 s.splits_unfolding ? fmt::format(" ({} to unfold faces that folded)", thousands(s.splits_unfolding)) : "", what, s.max_pixels, view.pixel_error, s.deviation,
                 s.error_bound, s.regions_outside ? fmt::format(", {} regions out of view left coarse", thousands(s.regions_outside)) : "",
                 s.regions_facing_away ? fmt::format(", {} facing away", thousands(s.regions_facing_away)) : "",
                 thousands(static_cast<long long>(r.bytes_read)),
                 1000 * std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
      fmt::print(stderr, "  a uniform level within the same budget from this distance has {} faces\n", thousands(uniform_faces));
      if (fit) print_attribute_fit(*fit);
    }
    reports.push_back(std::move(j));
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (o.json) {
    nlohmann::json j{{"file", o.input}, {"selective", true}, {"splits", pm.max_level()}, {"selected_by", what}};
    if (path) {
      j["eye_path"] = *o.eye_path;
      j["views"] = std::move(reports);
    } else {
      j.update(reports[0]);
    }
    j["bytes_read"] = r.bytes_read;
    j["seconds"] = seconds;
    fmt::print("{}\n", j.dump(2));
  } else if (path && !global.quiet) {
    fmt::print(stderr,
               "pm extract: {} views along {}, one mesh kept from view to view: {} to {} faces, {:.1f} of {} splits applied or "
               "undone per view after the first{}; {} projects to at most {:.3g} px in view (budget {} px); {}{} ... {} in {:.2f} s\n",
               viewers.size(), *o.eye_path, thousands(fewest), thousands(most),
               viewers.size() > 1 ? double(changed) / double(viewers.size() - 1) : 0.0, thousands(pm.max_level()),
               unfolding_views ? fmt::format(" ({} views refined further to unfold faces that folded)", unfolding_views) : "", what, widest,
               *o.pixel_error,
               per_step > 1 ? fmt::format("each change blended in over {} frames (geomorphs), views every {} frames: ", per_step, per_step) : "",
               numbered(o.output, 0), numbered(o.output, (viewers.size() - 1) * per_step), seconds);
  }
  return 0;
}

}  // namespace lodkit::cli::pm
