// lodkit pm build|info|extract|geomorph: progressive meshes and the .pm stream.
#include <lodkit/error.h>
#include <lodkit/pm_io.h>
#include <lodkit/progressive.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <limits>
#include <memory>
#include <sstream>

#include "common.h"

namespace lodkit::cli {
namespace {

namespace fs = std::filesystem;

struct PmCliOptions {
  // build
  std::string input, output, method = "quadric";
  std::optional<std::string> format;
  std::optional<Index> base_faces;
  int quantize = 0;
  bool draco = false, keep_order = false, json = false, measure = false, drop_normals = false, keep_orientation = false;
  Index block = 1024;
  std::vector<double> attribute_weights;
  std::optional<std::string> inverted_faces;  // allow|avoid|refuse; unset: by method, as simplify
  // extract / geomorph
  std::optional<Index> faces, from, to;
  std::optional<double> ratio, pixel_error, alpha, max_error;
  double distance = 10.0, fov = 60.0, viewport = 1080.0;
  int frames = 0;
  bool input_order = false, certified = false, fit_attributes = false;
  std::optional<std::string> prove_with;  // extract: the mesh the stream was built from
  std::vector<double> eye, look_at;        // extract: selective refinement for this viewer
  std::optional<std::string> eye_path;     // extract: ... for each viewer of this file
  int morph_frames = 1;                    // extract --eye-path: frames per step, the last the view itself
  double aspect = 16.0 / 9.0;
  bool no_cull = false, cull_backfaces = false, allow_folds = false;
  std::optional<Index> rows;
};

// A stream from a file, or from stdin when `path` is "-".
PmReadResult read_pm_input(const std::string& path, const PmReadOptions& options = {}) {
  return path == "-" ? read_pm_from_memory(read_stdin(), "<stdin>", options) : read_pm(path, options);
}

int run_build(const PmCliOptions& o, const GlobalOptions& global) {
  refuse_json_beside_stdout(o.json, o.output);
  Mesh mesh = read_input(o.input, o.format);
  // Flat shading splits every vertex by its normals: every edge is then a seam and nothing collapses.
  const bool had_normals = mesh.has_normals();
  if (o.drop_normals) mesh.attributes.normals.resize(0, 3);
  refuse_to_overwrite(o.output, {o.input});
  // Faces that disagree on orientation lock their shared edges' ends: turned first, as simplify turns
  // them, so that the stream's full level is the turned input.
  const Index reoriented = o.keep_orientation ? 0 : orient_consistently(mesh);
  ProgressiveOptions p;
  p.simplify.method = *parse_method(o.method);
  p.simplify.orient_faces = false;  // turned above, or kept as asked
  if (o.inverted_faces) p.simplify.inverted_faces = parse_inverted_faces(*o.inverted_faces);
  p.base_faces = o.base_faces;
  if (!o.attribute_weights.empty()) {
    if (o.attribute_weights.size() != 3) throw Error("pm build: --attribute-weights takes three numbers: normals,uvs,colours");
    p.simplify.attribute_weights = {o.attribute_weights[0], o.attribute_weights[1], o.attribute_weights[2]};
  }
  const auto start = std::chrono::steady_clock::now();
  ProgressiveMesh pm = build_progressive_mesh(mesh, p);
  const double build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const auto t0 = std::chrono::steady_clock::now();
  if (o.measure) measure_levels(pm, mesh);
  const double measure_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  PmWriteOptions w;
  w.position_bits = o.quantize;
  w.draco_base = o.draco;
  if (o.keep_order) w.keep_order = true;
  w.splits_per_block = o.block;
  const auto t1 = std::chrono::steady_clock::now();
  PmStreamStats stats;
  if (o.output == "-") {
    write_stdout(write_pm_to_memory(pm, w, &stats));  // (to another process: progressive transmission)
  } else {
    stats = write_pm(pm, o.output, w);
  }
  const double write_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
  const double bits_per_vertex = 8.0 * double(stats.total_bytes) / std::max<Index>(1, mesh.num_vertices());
  if (o.json) {
    fmt::print("{}\n", nlohmann::json{{"input", o.input}, {"output", o.output}, {"method", o.method},
                                      {"faces", mesh.num_faces()}, {"vertices", mesh.num_vertices()},
                                      {"reoriented_faces", reoriented},
                                      {"base_faces", pm.num_faces(0)}, {"splits", pm.max_level()},
                                      {"build_seconds", build_seconds}, {"write_seconds", write_seconds},
                                      {"measured_levels", pm.measured.size()}, {"measure_seconds", measure_seconds},
                                      {"bytes", stats.total_bytes}, {"base_bytes", stats.base_bytes},
                                      {"split_bytes", stats.split_bytes}, {"order_bytes", stats.order_bytes},
                                      {"bits_per_vertex", bits_per_vertex}, {"position_bits", o.quantize}}
                           .dump(2));
  } else if (!global.quiet) {
    fmt::print(stderr, "pm build ({}): {} faces -> base of {} faces + {} splits in {:.3f} s\n", o.method,
               thousands(mesh.num_faces()), thousands(pm.num_faces(0)), thousands(pm.max_level()), build_seconds);
    print_reoriented(reoriented);
    if (o.measure)
      fmt::print(stderr, "  measured {} levels' distances to the input in {:.3f} s\n", pm.measured.size(), measure_seconds);
    if (had_normals && !o.drop_normals && 2 * pm.num_faces(0) > mesh.num_faces())
      fmt::print(stderr, "  hint: the base keeps {} of {} faces; where the input's normals split its vertices (flat "
                         "shading) every edge is a seam, and --drop-normals builds without them\n",
                 thousands(pm.num_faces(0)), thousands(mesh.num_faces()));
    fmt::print(stderr, "  {}: {} bytes ({:.1f} bits per input vertex; base {}, splits {}, order {}) written in {:.3f} s\n",
               o.output == "-" ? "<stdout>" : o.output, thousands(static_cast<long long>(stats.total_bytes)), bits_per_vertex,
               thousands(static_cast<long long>(stats.base_bytes)), thousands(static_cast<long long>(stats.split_bytes)),
               thousands(static_cast<long long>(stats.order_bytes + stats.extra_bytes)), write_seconds);
  }
  return 0;
}

void warn(const PmReadResult& r, const GlobalOptions& global) {
  if (!r.warning.empty() && !global.quiet) fmt::print(stderr, "warning: {}\n", r.warning);
}

int run_info(const PmCliOptions& o, const GlobalOptions& global) {
  const PmReadResult r = read_pm_input(o.input);
  warn(r, global);
  const ProgressiveMesh& pm = r.pm;
  const double diagonal = pm.bounds.isEmpty() ? 0.0 : pm.bounds.diagonal().norm();
  const double pct = diagonal > 0 ? 100.0 / diagonal : 0.0;
  const bool measured = !pm.measured.empty();
  // A table of about `rows` levels, spaced evenly in log(faces), always with the base and the top.
  const Index rows = std::max<Index>(2, o.rows.value_or(12));
  std::vector<Index> levels;
  const double f0 = std::max<Index>(1, pm.num_faces(0)), f1 = std::max<Index>(1, pm.num_faces(pm.max_level()));
  for (Index i = 0; i < rows; ++i) {
    const double faces = f0 * std::pow(f1 / f0, double(i) / double(rows - 1));
    const Index level = level_for_faces(pm, static_cast<Index>(std::llround(faces)));
    if (levels.empty() || levels.back() != level) levels.push_back(level);
  }
  if (levels.back() != pm.max_level()) levels.push_back(pm.max_level());
  if (o.json) {
    nlohmann::json table = nlohmann::json::array();
    for (Index l : levels) {
      nlohmann::json row{{"level", l}, {"faces", pm.num_faces(l)}, {"vertices", pm.num_wedges(l)},
                         {"error_bound", pm.level_error[static_cast<std::size_t>(l)]},
                         {"error_bound_percent", pm.level_error[static_cast<std::size_t>(l)] * pct}};
      if (measured) {
        const double m = level_error(pm, l, LevelErrorKind::Measured);
        row["measured_error"] = m;
        row["measured_error_percent"] = m * pct;
      }
      table.push_back(row);
    }
    nlohmann::json ladder = nlohmann::json::array();
    for (const LevelMeasurement& m : pm.measured)
      ladder.push_back({{"level", m.level}, {"faces", pm.num_faces(m.level)}, {"hausdorff", m.hausdorff}, {"rms", m.rms}});
    fmt::print("{}\n", nlohmann::json{{"file", o.input}, {"bytes", r.bytes_read}, {"complete", r.complete},
                                      {"warning", r.warning}, {"position_bits", r.position_bits},
                                      {"splits", pm.max_level()}, {"base_faces", pm.num_faces(0)},
                                      {"faces", pm.num_faces(pm.max_level())}, {"vertices", pm.num_wedges(pm.max_level())},
                                      {"bits_per_vertex", 8.0 * double(r.bytes_read) / std::max<Index>(1, pm.num_wedges(pm.max_level()))},
                                      {"base_bytes", r.stats.base_bytes}, {"split_bytes", r.stats.split_bytes},
                                      {"order_bytes", r.stats.order_bytes}, {"input_order", pm.knows_input_order()},
                                      {"diagonal", diagonal}, {"levels", table}, {"measured_levels", ladder}}
                           .dump(2));
    return 0;
  }
  fmt::print("{}: progressive mesh, {} ({}), {} bytes = {:.1f} bits per vertex\n", o.input == "-" ? "<stdin>" : o.input,
             r.position_bits ? fmt::format("{}-bit positions", r.position_bits) : std::string("lossless"),
             pm.knows_input_order() ? "input order kept" : "stream order", thousands(static_cast<long long>(r.bytes_read)),
             8.0 * double(r.bytes_read) / std::max<Index>(1, pm.num_wedges(pm.max_level())));
  fmt::print("  base {} faces, {} splits up to {} faces, {} vertices; base {} bytes, splits {} bytes\n",
             thousands(pm.num_faces(0)), thousands(pm.max_level()), thousands(pm.num_faces(pm.max_level())),
             thousands(pm.num_wedges(pm.max_level())), thousands(static_cast<long long>(r.stats.base_bytes)),
             thousands(static_cast<long long>(r.stats.split_bytes)));
  fmt::print("  {:>9}  {:>11}  {:>11}  {:>13}  {:>9}{}\n", "level", "faces", "vertices", "error bound", "% diag",
             measured ? fmt::format("  {:>13}  {:>9}", "measured", "% diag") : "");
  for (Index l : levels) {
    const double bound = pm.level_error[static_cast<std::size_t>(l)], m = level_error(pm, l, LevelErrorKind::Measured);
    fmt::print("  {:>9}  {:>11}  {:>11}  {:>13.6g}  {:>9.4f}{}\n", l, thousands(pm.num_faces(l)), thousands(pm.num_wedges(l)),
               bound, bound * pct, measured ? fmt::format("  {:>13.6g}  {:>9.4f}", m, m * pct) : "");
  }
  if (measured)
    fmt::print("  measured: Hausdorff distance to the input at {} levels, certified by compare (a level between two\n"
               "  shows the coarser one's); the error bound is guaranteed by the collapses alone, and looser\n",
               pm.measured.size());
  return 0;
}

/// By the measured distance (the bound where the stream has none), unless the bound is asked for.
LevelErrorKind selection_kind(const PmCliOptions& o) {
  return o.certified ? LevelErrorKind::Bound : LevelErrorKind::Measured;
}

/// The viewer of --pixel-error, --distance, --fov and --viewport (with --pixel-error given).
ScreenSpaceBudget view_of(const PmCliOptions& o) { return {*o.pixel_error, o.distance, o.fov, o.viewport}; }

/// The level the selection options ask for, and a sentence saying why.
Index choose_level(const PmCliOptions& o, const PmReadResult& r, std::string& why) {
  const ProgressiveMesh& pm = r.pm;
  if (o.faces) {
    why = fmt::format("at most {} faces", *o.faces);
    return level_for_faces(pm, *o.faces);
  }
  if (o.ratio) {
    // Of the finest level, which a prefix read does not hold: the header's count.
    const Index faces = static_cast<Index>(std::llround(*o.ratio * double(r.total_faces)));
    why = fmt::format("ratio {} = at most {} faces", *o.ratio, faces);
    return level_for_faces(pm, faces);
  }
  const LevelErrorKind kind = selection_kind(o);
  const char* what = kind == LevelErrorKind::Measured && !pm.measured.empty() ? "measured error" : "error bound";
  if (o.max_error) {
    why = fmt::format("{} at most {}", what, *o.max_error);
    return level_for_error(pm, *o.max_error, kind);
  }
  const ScreenSpaceBudget view = view_of(o);
  const Index level = level_for_view(pm, view, kind);
  why = fmt::format("{} px budget at distance {}, fov {} deg, {} px viewport: {} projects to {:.3g} px", *o.pixel_error,
                    o.distance, o.fov, o.viewport, what,
                    projected_pixels(level_error(pm, level, kind), bounding_radius(pm), view));
  return level;
}

// --eye and --look-at: CLI11 takes exactly three numbers.
Eigen::Vector3d point_option(const std::vector<double>& xyz) { return {xyz[0], xyz[1], xyz[2]}; }

// out.ply -> out_000.ply, out_001.ply, ...: the frames of a geomorph or the views of a path.
std::string numbered(const std::string& output, std::size_t i) {
  const fs::path out(output);
  return (out.parent_path() / fmt::format("{}_{:03d}{}", out.stem().string(), i, out.extension().string())).string();
}

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

int run_extract(const PmCliOptions& o, const GlobalOptions& global) {
  const std::vector<std::string> inputs{o.input, o.prove_with.value_or(""), o.eye_path.value_or("")};
  refuse_to_overwrite(o.output, inputs);  // before reading: fail fast
  refuse_json_beside_stdout(o.json, o.output);
  if (!o.eye.empty() || o.eye_path) return run_selective(o, global, inputs);
  for (const auto& [given, flag] : {std::pair{!o.look_at.empty(), "--look-at"}, {o.no_cull, "--no-cull"},
                                     {o.cull_backfaces, "--cull-backfaces"}, {o.allow_folds, "--allow-folds"}})
    if (given) throw Error(fmt::format("pm extract: {} needs --eye or --eye-path", flag));
  const int given = o.faces.has_value() + o.ratio.has_value() + o.pixel_error.has_value() + o.max_error.has_value();
  if (given != 1) throw Error("pm extract: give exactly one of --faces, --ratio, --max-error or --pixel-error");
  if (o.prove_with && !o.max_error && !o.pixel_error)
    throw Error("pm extract: --prove-with needs an error budget: --max-error or --pixel-error");
  // Progressive read: only the blocks the chosen level needs (the input order comes after them all). A
  // proof may check any level, and the attribute fit needs the finest: they read them all.
  PmReadOptions ro;
  if (!o.input_order && !o.prove_with && !o.fit_attributes) {
    ro.max_faces = o.faces;
    ro.max_ratio = o.ratio;
    ro.max_error = o.max_error;
    if (o.pixel_error) ro.view = view_of(o);
    ro.select_by = selection_kind(o);
  }
  const auto start = std::chrono::steady_clock::now();
  const PmReadResult r = read_pm_input(o.input, ro);
  warn(r, global);
  std::string why;
  Index level = 0;
  std::optional<SimplifyResult::HausdorffLimit> proof;
  if (o.prove_with) {
    // The budget as a distance, then the coarsest level found proved within it against the input.
    const Mesh input = read_input(*o.prove_with, std::nullopt, {}, nullptr);
    if (input.num_faces() != r.pm.source_faces())
      throw Error(fmt::format("{}: has {} faces, but the finest level of {} has {}: --prove-with needs the mesh the "
                              "stream was built from", *o.prove_with, input.num_faces(), o.input, r.pm.source_faces()));
    const double budget = o.max_error ? *o.max_error : object_error_for_pixels(bounding_radius(r.pm), view_of(o));
    ProvedLevel proved = prove_level_within(r.pm, input, budget);
    level = proved.level;
    proof = proved.proof;
    why = fmt::format("the coarsest level found within a budget of {:.6g} from {}, {} levels checked", budget,
                      *o.prove_with, proof->checks);
  } else {
    level = choose_level(o, r, why);
  }
  ExtractedLevel e = extract_level(r.pm, level, o.input_order ? VertexOrder::Input : VertexOrder::Stream);
  std::optional<AttributeFitReport> fit;
  if (o.fit_attributes) {
    // The finest level is the input (in input order where the stream keeps it): the level's normals and
    // colours fitted to it, as simplify fits its output's.
    const Mesh finest = extract_level(r.pm, r.pm.max_level(), VertexOrder::Input).mesh;
    fit = fit_attributes_to_input(finest, e.mesh);
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  write_output(e.mesh, o.output, o.format, WriteOptions{}, inputs);
  const double bound = r.pm.level_error[static_cast<std::size_t>(level)];
  const bool measured = !r.pm.measured.empty();
  const double measured_error = level_error(r.pm, level, LevelErrorKind::Measured);
  if (o.json) {
    nlohmann::json j{{"file", o.input}, {"output", o.output}, {"level", level}, {"faces", e.mesh.num_faces()},
                     {"vertices", e.mesh.num_vertices()}, {"error_bound", bound}, {"bytes_read", r.bytes_read},
                     {"seconds", seconds}, {"why", why}};
    // (Under a proof the level is usually between measured ones, whose borrowed value would only mislead.)
    if (measured && !proof) j["measured_error"] = measured_error;
    if (proof) j["proved_bound"] = proof->bound, j["checks"] = proof->checks;
    if (fit) j["attribute_fit"] = attribute_fit_json(*fit);
    fmt::print("{}\n", j.dump(2));
  } else if (!global.quiet) {
    fmt::print(stderr, "pm extract: level {} of {}: {} faces, {} vertices, error bound {:.6g}{} ({}); read {} bytes, {:.1f} ms\n",
               level, r.total_splits, thousands(e.mesh.num_faces()), thousands(e.mesh.num_vertices()), bound,
               proof ? fmt::format(", proved {:.6g}", proof->bound)
               : measured ? fmt::format(", measured {:.6g}", measured_error) : "",
               why,
               thousands(static_cast<long long>(r.bytes_read)), 1000 * seconds);
    if (fit) print_attribute_fit(*fit);
    // Budgets met by the bound alone usually pick levels far finer than a viewer needs: say so once.
    if (!measured && (o.pixel_error || o.max_error) && !o.certified && !o.prove_with)
      fmt::print(stderr, "  note: {} holds no measured errors, so the guaranteed bound chose the level (4-50x the measured "
                         "distance on scanned meshes); streams built with `pm build --measure` meet the budget with "
                         "coarser levels\n",
                 o.input);
  }
  return 0;
}

int run_geomorph(const PmCliOptions& o, const GlobalOptions& global) {
  refuse_to_overwrite(o.output, {o.input});  // before reading: fail fast
  if (o.frames > 0 && o.output == "-") throw Error("pm geomorph: --frames writes files OUT_000 ...: give OUT a file name");
  const PmReadResult r = read_pm_input(o.input);
  warn(r, global);
  const ProgressiveMesh& pm = r.pm;
  if (!o.from || !o.to) throw Error("pm geomorph: --from and --to face counts are required");
  if (o.alpha.has_value() == (o.frames > 0)) throw Error("pm geomorph: give either --alpha or --frames");
  const Index from = level_for_faces(pm, *o.from), to = level_for_faces(pm, *o.to);
  if (from > to) throw Error(fmt::format("pm geomorph: --from ({} faces) must be coarser than --to ({} faces)", *o.from, *o.to));
  const Geomorph g = make_geomorph(pm, from, to, o.input_order ? VertexOrder::Input : VertexOrder::Stream);
  if (o.alpha) {
    if (!(*o.alpha >= 0 && *o.alpha <= 1)) throw Error("pm geomorph: --alpha must be in [0, 1]");
    write_output(g.at(*o.alpha), o.output, o.format, WriteOptions{}, {o.input});
  } else {
    // morph.ply -> morph_000.ply ... morph_NNN.ply, alpha from 0 to 1.
    Mesh frame;
    for (int i = 0; i < o.frames; ++i) {
      const double alpha = o.frames == 1 ? 1.0 : double(i) / double(o.frames - 1);
      g.evaluate(alpha, frame);
      write_output(frame, numbered(o.output, static_cast<std::size_t>(i)), o.format, WriteOptions{}, {o.input});
    }
  }
  if (!global.quiet)
    fmt::print(stderr, "pm geomorph: level {} ({} faces) -> level {} ({} faces), {} vertices morphing{}\n", from,
               thousands(pm.num_faces(from)), to, thousands(pm.num_faces(to)), thousands(g.fine.mesh.num_vertices()),
               o.frames ? fmt::format(", {} frames", o.frames) : fmt::format(", alpha {}", *o.alpha));
  return 0;
}

}  // namespace

Command add_pm_command(CLI::App& app, const GlobalOptions& global) {
  auto opt = std::make_shared<PmCliOptions>();
  CLI::App* pm = app.add_subcommand("pm", "Progressive meshes: build a .pm stream, inspect it, extract levels, geomorph");
  pm->require_subcommand(1);
  pm->footer(R"(Examples:
  lodkit pm build bunny.ply -o bunny.pm
  lodkit pm build bunny.ply -o bunny_q.pm --quantize 14
  lodkit pm info bunny.pm
  lodkit pm extract bunny.pm -o bunny_1k.ply --faces 1000
  lodkit pm extract bunny.pm -o near.ply --pixel-error 1 --distance 0.5 --fov 60 --viewport 1080
  lodkit pm extract bunny.pm -o view.ply --pixel-error 1 --eye 0,0.1,0.3   # fine near the eye only
  lodkit pm geomorph bunny.pm --from 1000 --to 4000 --frames 30 -o morph.ply)");

  CLI::App* build = pm->add_subcommand("build", "Build a progressive mesh from a mesh and write it as a .pm stream");
  build->add_option("input", opt->input, "Input mesh, or - for stdin (with --format)")->required();
  build->add_option("-o,--output", opt->output, "Output .pm file, or - for stdout")->required();
  build->add_option("--format", opt->format, "Format of stdin")->check(format_validator());
  build->add_option("--method", opt->method, "Collapse cost: quadric, hoppe or edge-length")
      ->check(CLI::IsMember({"quadric", "hoppe", "edge-length"}))->capture_default_str();
  build->add_option("--base-faces", opt->base_faces, "Stop collapsing at this many faces (default: as far as legal)")
      ->check(kNonNegative);
  add_inverted_faces_option(build, opt->inverted_faces);
  build->add_option("--quantize", opt->quantize, "Position bits (quantised, compact stream); 0 = lossless")
      ->check(in_range(0, 30))->capture_default_str();
  build->add_flag("--draco", opt->draco, "Compress the base mesh with Draco (needs --quantize)");
  build->add_flag("--keep-order", opt->keep_order, "Store the input order in a quantised stream too");
  build->add_flag("--measure", opt->measure,
                  "Measure levels' distances to the input (compare, levels 1.41x apart in faces) for selection");
  build->add_option("--block", opt->block, "Splits per checksummed block")->check(in_range(1, 1 << 24))->capture_default_str();
  build->add_option("--attribute-weights", opt->attribute_weights, "Normal, UV and colour weights (quadric), e.g. 0,1,0")
      ->delimiter(',')->check(kNonNegative);
  build->add_flag("--drop-normals", opt->drop_normals,
                  "Build without the input's normals (flat shading makes every edge a seam); levels then have none");
  add_keep_orientation_flag(build, opt->keep_orientation);
  build->add_flag("--json", opt->json, "Print the result as JSON on stdout");
  build->footer(R"(Lossless streams reproduce the input exactly (positions bit for bit, same triangles in the
same order; without its normals with --drop-normals; faces that disagreed on orientation turned to
agree unless --keep-orientation); --quantize BITS gives a compact stream in stream order.
Examples:
  lodkit pm build bunny.ply -o bunny.pm
  lodkit pm build scan.obj -o scan.pm --quantize 14 --draco --base-faces 500
  lodkit pm build spot.obj -o spot.pm --attribute-weights 0,1,0
  lodkit pm build bunny.ply -o bunny.pm --measure   # pm extract --pixel-error then picks what a viewer needs
  lodkit pm build bunny.ply -o - | lodkit pm extract - -o bunny_1k.ply --faces 1000   # through a pipe
  lodkit pm build suzanne_flat.ply -o suzanne.pm --drop-normals   # flat shading: every edge a seam otherwise)");

  CLI::App* info = pm->add_subcommand("info", "Levels, sizes and error bounds of a .pm file");
  info->add_option("input", opt->input, "A .pm file, or - for stdin")->required();
  info->add_option("--rows", opt->rows, "Levels in the table")->check(in_range(2, 10000));
  info->add_flag("--json", opt->json, "Print as JSON");
  info->footer("Example:\n  lodkit pm info bunny.pm --json");

  CLI::App* extract = pm->add_subcommand("extract", "Write one level of a .pm file as a mesh");
  extract->add_option("input", opt->input, "A .pm file, or - for stdin")->required();
  extract->add_option("-o,--output", opt->output, "Output mesh, or - for stdout (with --format)")->required();
  extract->add_option("--format", opt->format, "Format of stdout")->check(format_validator());
  extract->add_option("--faces", opt->faces, "The finest level with at most this many faces")->check(kNonNegative);
  extract->add_option("--ratio", opt->ratio, "... at most this fraction of the full face count")->check(in_range(0.0, 1.0));
  extract->add_option("--max-error", opt->max_error, "The coarsest level whose error bound is at most this distance")
      ->check(kNonNegative);
  extract->add_option("--pixel-error", opt->pixel_error, "The coarsest level whose bound projects to at most this many pixels")
      ->check(kNonNegative);
  extract->add_option("--distance", opt->distance, "Eye to bounding-sphere centre (with --pixel-error)")->capture_default_str();
  extract->add_option("--fov", opt->fov, "Vertical field of view, degrees")->check(in_range(0.01, 179.99))->capture_default_str();
  extract->add_option("--viewport", opt->viewport, "Viewport height, pixels")->check(kPositive)->capture_default_str();
  extract->add_option("--eye", opt->eye,
                      "Selective refinement: refine each region only as far as --pixel-error asks from this eye, x,y,z "
                      "(reads the whole file)")
      ->delimiter(',')->expected(3)->excludes("--distance");
  extract->add_option("--eye-path", opt->eye_path,
                      "Selective refinement for each eye of this file, one per line (x,y,z, or x,y,z,lx,ly,lz with the "
                      "point looked at), written to OUT_000 ...; one mesh is kept from view to view")
      ->excludes("--distance");
  extract->add_option("--morph-frames", opt->morph_frames,
                      "With --eye-path: blend each view's change in over this many frames (geomorphs); the views are "
                      "frames 0, K, 2K, ...")
      ->check(in_range(1, 10000))->capture_default_str();
  extract->add_option("--look-at", opt->look_at, "With --eye: the point looked at, x,y,z (default: the bounding box centre)")
      ->delimiter(',')->expected(3);
  extract->add_option("--aspect", opt->aspect, "With --eye: viewport width over height")->check(kPositive)->capture_default_str();
  extract->add_flag("--no-cull", opt->no_cull, "With --eye: refine what lies outside the view too");
  extract->add_flag("--cull-backfaces", opt->cull_backfaces,
                    "With --eye: leave regions facing away from the eye coarse (closed meshes: hidden behind the front)");
  extract->add_flag("--allow-folds", opt->allow_folds,
                    "With --eye: leave faces that fold (face against the input, where splits of different levels "
                    "meet) as they are, instead of refining further until none does");
  extract->add_flag("--input-order", opt->input_order, "Vertices and faces in input order (reads the whole file)");
  extract->add_flag("--certified", opt->certified, "Select by the collapses' own guaranteed bound (4-50x looser) even when the stream has measured errors");
  extract->add_option("--prove-with", opt->prove_with,
                      "The mesh the stream was built from: with --max-error or --pixel-error, the level is then the "
                      "coarsest found whose distance to it is proved within the budget, checking levels between the "
                      "stored ones (reads the whole file)")
      ->excludes("--certified");
  extract->add_flag("--fit-attributes", opt->fit_attributes,
                    "Fit the level's normals, UVs and colours to the finest level's, as simplify does (reads the whole "
                    "file); without it they are the stream's own, each collapse's kept values");
  extract->add_flag("--json", opt->json, "Print the result as JSON on stdout");
  extract->footer(R"(pixels = error * viewport / (2 * d * tan(fov / 2)), d = distance - bounding radius.
The error is the level's measured distance to the input when the stream was built with --measure
(unless --certified), else its guaranteed bound, which is 4-50 times larger on the bunny.
With --eye, each region of the mesh is refined on its own (selective refinement): d is the distance
from the eye to the region, whose error is its measured deviation (its guaranteed bound with
--certified); regions outside the view cone stay coarse unless --no-cull, and so do regions facing
away with --cull-backfaces. Where splits of different levels meet, a face can fold (face against its
own face in the input, or the input faces nearest it, as no uniform level's does): the mesh is refined
further there until none does, unless --allow-folds. --eye-path does so for each line of a file (a camera path), keeping one
mesh from view to view: each view applies and undoes only the splits that change. With
--morph-frames K the change from one view to the next blends in over K frames (Hoppe 1997's
geomorphs, refining and coarsening at once): K - 1 frames morph from the view before to the next,
whose own mesh is the K-th, so views are frames 0, K, 2K, ... and nothing pops between frames.
Only the blocks the chosen level needs are read (all of them with --input-order, --prove-with or
--fit-attributes).
Examples:
  lodkit pm extract bunny.pm -o bunny_1k.ply --faces 1000
  lodkit pm extract bunny.pm -o half.obj --ratio 0.5 --input-order
  lodkit pm extract human.pm -o human_2k.ply --faces 2000 --fit-attributes   # shading as simplify's
  lodkit pm extract bunny.pm -o far.ply --pixel-error 0.5 --distance 2 --fov 45 --viewport 1440
  lodkit pm extract bunny.pm -o seen.ply --pixel-error 1 --distance 2 --prove-with bunny.ply
  lodkit pm extract terrain.pm -o view.ply --pixel-error 1 --eye -0.6,-0.6,0.1 --look-at 0.5,0.5,0
  lodkit pm extract bunny.pm -o view.ply --pixel-error 1 --eye-path orbit.csv   # view_000.ply ...
  lodkit pm extract bunny.pm -o f.ply --pixel-error 1 --eye-path orbit.csv --morph-frames 8   # views f_000, f_008, ...)");

  CLI::App* morph = pm->add_subcommand("geomorph", "Blend between two levels (Hoppe's geomorphs)");
  morph->add_option("input", opt->input, "A .pm file, or - for stdin")->required();
  morph->add_option("--from", opt->from, "Coarse level: at most this many faces")->required()->check(kNonNegative);
  morph->add_option("--to", opt->to, "Fine level: at most this many faces")->required()->check(kNonNegative);
  morph->add_option("--alpha", opt->alpha, "Blend weight: 0 looks like --from, 1 is --to");
  morph->add_option("--frames", opt->frames, "Write this many frames OUT_000 ... with alpha from 0 to 1")->check(in_range(1, 100000));
  morph->add_option("-o,--output", opt->output, "Output mesh (or frame name pattern)")->required();
  morph->add_option("--format", opt->format, "Format of stdout")->check(format_validator());
  morph->add_flag("--input-order", opt->input_order, "Vertices and faces in input order");
  morph->footer(R"(Between two uniform levels. Between selectively refined views along a camera path:
pm extract --eye-path FILE --morph-frames K.
Examples:
  lodkit pm geomorph bunny.pm --from 1000 --to 4000 --alpha 0.5 -o half.ply
  lodkit pm geomorph bunny.pm --from 1000 --to 4000 --frames 30 -o morph.ply   # morph_000.ply ... morph_029.ply)");

  return {pm, [opt, &global, build, info, extract] {
            if (build->parsed()) return run_build(*opt, global);
            if (info->parsed()) return run_info(*opt, global);
            if (extract->parsed()) return run_extract(*opt, global);
            return run_geomorph(*opt, global);
          }};
}

}  // namespace lodkit::cli
