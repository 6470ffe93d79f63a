#pragma once
// What every subcommand shares: reading and writing meshes by path or "-" (stdin/stdout), the
// summary lines on stderr, and the subcommand registry.
#include <lodkit/inspect.h>
#include <lodkit/io.h>
#include <lodkit/simplify.h>

#include <CLI/CLI.hpp>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace lodkit::cli {

/// A registered subcommand: its CLI11 app and the function that runs it (returns the exit code).
struct Command {
  CLI::App* app;
  std::function<int()> run;
};

struct GlobalOptions {
  bool quiet = false;
};

Command add_info_command(CLI::App& app, const GlobalOptions& global);
Command add_convert_command(CLI::App& app, const GlobalOptions& global);
Command add_generate_command(CLI::App& app, const GlobalOptions& global);
Command add_simplify_command(CLI::App& app, const GlobalOptions& global);
Command add_compare_command(CLI::App& app, const GlobalOptions& global);
Command add_csg_command(CLI::App& app, const GlobalOptions& global);
Command add_pm_command(CLI::App& app, const GlobalOptions& global);
Command add_terrain_command(CLI::App& app, const GlobalOptions& global);
Command add_subdivide_command(CLI::App& app, const GlobalOptions& global);

/// All of stdin, and bytes to stdout (flushed).
std::string read_stdin();
void write_stdout(const std::string& bytes);

/// Reads `path`, or stdin when it is "-" (then `format` names the format; when missing, the error
/// names `format_option`, the command's option for it, or says the command reads files only if null).
Mesh read_input(const std::string& path, const std::optional<std::string>& format, const ReadOptions& options = {},
                const char* format_option = "--format");

/// Throws if `path` names the same file as one of `inputs` (under any name); "-" and "" are never files.
void refuse_to_overwrite(const std::string& path, const std::vector<std::string>& inputs);

/// Throws when `--json` would print on stdout beside a mesh or stream written there (`output` is "-").
void refuse_json_beside_stdout(bool json, const std::string& output);

/// Writes to `path` atomically, or to stdout when it is "-" (then `format` names the format).
/// Refuses to write over any of `inputs` (the same file under any name).
void write_output(const Mesh& mesh, const std::string& path, const std::optional<std::string>& format,
                  const WriteOptions& options, const std::vector<std::string>& inputs = {},
                  const char* format_option = "--format");

/// "12,345"
std::string thousands(long long n);

/// Option checks for numbers of 0 or more, above 0, and from `low` to `high`. CLI11's NonNegativeNumber,
/// PositiveNumber and Range say the same, but the first two name their upper bound, the largest double,
/// in 310 digits, and all three call a word that is no number out of range: here "--crease-weight: abc
/// is not a number", "--ratio: 2 is not between 0 and 1".
extern const CLI::Validator kNonNegative;
extern const CLI::Validator kPositive;
CLI::Validator in_range(double low, double high);

/// A non-negative length given on the command line: "0.5" is absolute, "0.5%" a percentage (of a
/// diagonal, say); `value` is then the fraction (0.005).
struct LengthArgument {
  double value = 0.0;
  bool relative = false;
};
/// \throw Error "<option> '<text>' is not a non-negative number or a percentage".
LengthArgument parse_length(const std::string& text, const std::string& option);

nlohmann::json to_json(const MeshReport& report);

/// CLI11 validator for names of mesh formats.
CLI::Validator format_validator();

/// `--inverted-faces allow|avoid|refuse` (SimplifyOptions::inverted_faces; unset: by method), as simplify
/// and pm build take it.
CLI::Option* add_inverted_faces_option(CLI::App* app, std::optional<std::string>& mode);

/// `--keep-orientation` (SimplifyOptions::orient_faces off), as simplify and pm build take it.
CLI::Option* add_keep_orientation_flag(CLI::App* app, bool& keep);
/// The summary's line on faces turned to agree on orientation (nothing when none were).
void print_reoriented(Index faces);

/// The attribute fit's report as JSON, and its summary line ("nothing to fit" when no normals, UVs or
/// colours were: none in the output, or constant over the input).
nlohmann::json attribute_fit_json(const AttributeFitReport& fit);
void print_attribute_fit(const AttributeFitReport& fit);

}  // namespace lodkit::cli
