#include "common.h"

#include <lodkit/error.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <filesystem>
#include <fmt/format.h>
#include <iostream>
#include <iterator>

namespace lodkit::cli {

namespace fs = std::filesystem;

namespace {

MeshFormat stream_format(const std::optional<std::string>& format, const char* stream, const char* format_option) {
  if (!format && !format_option) throw Error(fmt::format("{}: this command reads files only, not stdin", stream));
  if (!format)
    throw Error(fmt::format("{}: give the format with {} (obj, ply, off, stl, drc)", stream, format_option));
  if (auto f = parse_format(*format)) return *f;
  throw Error(fmt::format("{}: unknown format '{}'", stream, *format));
}

}  // namespace

std::string read_stdin() {
  return std::string{std::istreambuf_iterator<char>(std::cin), std::istreambuf_iterator<char>()};
}

void write_stdout(const std::string& bytes) {
  std::fwrite(bytes.data(), 1, bytes.size(), stdout);
  std::fflush(stdout);
}

Mesh read_input(const std::string& path, const std::optional<std::string>& format, const ReadOptions& options,
                const char* format_option) {
  if (path == "-") {
    const MeshFormat f = stream_format(format, "<stdin>", format_option);  // (before waiting for stdin)
    return read_mesh_from_memory(read_stdin(), f, "<stdin>", options);
  }
  ReadOptions with_format = options;
  if (format) with_format.format = stream_format(format, path.c_str(), format_option);
  return read_mesh(path, with_format);
}

void refuse_to_overwrite(const std::string& path, const std::vector<std::string>& inputs) {
  std::error_code ec;
  if (path == "-" || !fs::exists(path, ec)) return;
  for (const std::string& input : inputs)
    if (!input.empty() && input != "-" && fs::equivalent(path, input, ec))
      throw Error(fmt::format("{}: refusing to overwrite the input file{}; choose another output path", path,
                              input == path ? "" : fmt::format(" {}", input)));
}

void refuse_json_beside_stdout(bool json, const std::string& output) {
  if (json && output == "-")
    throw Error("<stdout>: --json prints there, and so does the output (-): give the output a file name");
}

void write_output(const Mesh& mesh, const std::string& path, const std::optional<std::string>& format,
                  const WriteOptions& options, const std::vector<std::string>& inputs, const char* format_option) {
  if (path == "-") {
    write_stdout(write_mesh_to_memory(mesh, stream_format(format, "<stdout>", format_option), options));
    return;
  }
  refuse_to_overwrite(path, inputs);
  WriteOptions with_format = options;
  if (format) with_format.format = stream_format(format, path.c_str(), format_option);
  write_mesh(mesh, path, with_format);
}

LengthArgument parse_length(const std::string& text, const std::string& option) {
  LengthArgument length;
  std::string number = text;
  length.relative = !number.empty() && number.back() == '%';
  if (length.relative) number.pop_back();
  std::size_t used = 0;
  try {
    length.value = std::stod(number, &used);
  } catch (const std::logic_error&) {
    used = 0;
  }
  if (used == 0 || used != number.size() || !(length.value >= 0) || !std::isfinite(length.value))
    throw Error(fmt::format("{} '{}' is not a non-negative number or a percentage", option, text));
  if (length.relative) length.value /= 100.0;
  return length;
}

namespace {

// Why `text` is not a finite number, or "" (and the number in `value`).
std::string not_a_number(const std::string& text, double& value) {
  if (!CLI::detail::lexical_cast(text, value) || std::isnan(value)) return text + " is not a number";
  if (!std::isfinite(value)) return text + " is not a finite number";
  return {};
}

CLI::Validator number_check(bool above_zero) {
  return CLI::Validator(
      [above_zero](std::string& text) -> std::string {
        double value = 0;
        if (std::string why = not_a_number(text, value); !why.empty()) return why;
        if (above_zero && !(value > 0)) return text + " is not above 0";
        if (!above_zero && !(value >= 0)) return text + " is negative";
        return {};
      },
      above_zero ? "POSITIVE" : "NONNEGATIVE");
}

}  // namespace

CLI::Validator in_range(double low, double high) {
  return CLI::Validator(
      [low, high](std::string& text) -> std::string {
        double value = 0;
        if (std::string why = not_a_number(text, value); !why.empty()) return why;
        if (!(value >= low && value <= high)) return fmt::format("{} is not between {} and {}", text, low, high);
        return {};
      },
      fmt::format("[{} - {}]", low, high));
}

const CLI::Validator kNonNegative = number_check(false);
const CLI::Validator kPositive = number_check(true);

std::string thousands(long long n) {
  std::string digits = std::to_string(n < 0 ? -n : n), out;
  for (std::size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out.push_back(',');
    out.push_back(digits[i]);
  }
  return n < 0 ? "-" + out : out;
}

nlohmann::json to_json(const MeshReport& r) {
  using nlohmann::json;
  json j;
  j["vertices"] = r.vertices;
  j["faces"] = r.faces;
  j["welded_vertices"] = r.welded_vertices;
  j["duplicate_positions"] = r.duplicate_positions;
  j["unreferenced_vertices"] = r.unreferenced_vertices;
  j["edges"] = r.edges;
  if (r.bounds.isEmpty()) {
    j["bounds"] = nullptr;
  } else {
    j["bounds"] = {{"min", {r.bounds.min().x(), r.bounds.min().y(), r.bounds.min().z()}},
                   {"max", {r.bounds.max().x(), r.bounds.max().y(), r.bounds.max().z()}}};
  }
  j["diagonal"] = r.diagonal;
  j["components"] = r.components;
  j["boundary_edges"] = r.boundary_edges;
  j["boundary_loops"] = r.boundary_loops;
  j["non_manifold_edges"] = r.non_manifold_edges;
  j["non_manifold_vertices"] = r.non_manifold_vertices;
  j["inconsistently_oriented_edges"] = r.inconsistently_oriented_edges;
  j["degenerate_faces"] = r.degenerate_faces;
  j["duplicate_faces"] = r.duplicate_faces;
  j["manifold"] = r.manifold;
  j["oriented"] = r.oriented;
  if (r.orientable) j["orientable"] = *r.orientable;
  j["closed"] = r.closed;
  j["euler_characteristic"] = r.euler_characteristic;
  j["genus"] = r.genus ? json(*r.genus) : json(nullptr);
  j["area"] = r.area;
  j["volume"] = r.volume ? json(*r.volume) : json(nullptr);
  j["attributes"] = {{"normals", r.has_normals}, {"uvs", r.has_uvs}, {"colours", r.has_colours},
                     {"face_colours", r.has_face_colours}};
  if (r.uv_charts) j["uv_charts"] = *r.uv_charts;
  return j;
}

CLI::Validator format_validator() {
  return CLI::Validator(
      [](std::string& s) -> std::string {
        return parse_format(s) ? std::string() : "unknown format '" + s + "' (obj, ply, off, stl, drc)";
      },
      "FORMAT");
}

CLI::Option* add_inverted_faces_option(CLI::App* app, std::optional<std::string>& mode) {
  return app
      ->add_option("--inverted-faces", mode,
                   "Collapses that leave a face facing against the nearest input face: allow (no check), avoid (such a "
                   "collapse waits until the others cost four times as much), refuse (never; may stop short of the "
                   "target, and says so). Default: avoid for quadric, refuse for schroeder (whose avoid lets such a removal be once "
                   "a pass's threshold is twice its error), allow for hoppe and edge-length. simplify's refit "
                   "after the collapses makes no such face unless allow is given")
      ->check(CLI::IsMember({"allow", "avoid", "refuse"}));
}

CLI::Option* add_keep_orientation_flag(CLI::App* app, bool& keep) {
  return app->add_flag("--keep-orientation", keep,
                       "Leave faces that disagree with their neighbours' orientation as they are (the ends of their "
                       "shared edges then stay locked); by default they are turned to agree first");
}

void print_reoriented(Index faces) {
  if (faces > 0)
    fmt::print(stderr, "  turned {} faces of the input to agree with their neighbours' orientation first "
               "(--keep-orientation leaves them)\n", thousands(faces));
}

nlohmann::json attribute_fit_json(const AttributeFitReport& fit) {
  return {{"normals", fit.normals}, {"colours", fit.colours}, {"uvs", fit.uvs}, {"samples", fit.samples}, {"seconds", fit.seconds}};
}

void print_attribute_fit(const AttributeFitReport& fit) {
  std::vector<std::string> what;
  if (fit.normals) what.push_back("normals");
  if (fit.uvs) what.push_back("UVs");
  if (fit.colours) what.push_back("colours");
  if (what.empty()) {
    fmt::print(stderr, "  attribute fit: nothing to fit (no normals, UVs or colours, or constant over the input)\n");
    return;
  }
  std::string list = what[0];
  for (std::size_t i = 1; i < what.size(); ++i) list += (i + 1 == what.size() ? " and " : ", ") + what[i];
  fmt::print(stderr, "  {} fitted to the input's ({} points, {:.3f} s)\n", list, thousands(fit.samples), fit.seconds);
}

}  // namespace lodkit::cli
