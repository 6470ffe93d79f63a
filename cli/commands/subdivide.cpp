// lodkit subdivide: Loop, Catmull-Clark or bilinear subdivision through OpenSubdiv, a fixed number of
// levels or the fewest levels within a tolerance of the next.
#include <lodkit/error.h>
#include <lodkit/subdivide.h>

#include <chrono>
#include <fmt/format.h>
#include <memory>

#include "common.h"

namespace lodkit::cli {
namespace {

struct SubdivideCommandOptions {
  std::string input, output, scheme = "loop", boundary = "edge", uv_rule = "corners";
  std::optional<std::string> format, input_format, tolerance;
  SubdivideOptions subdivide;
};

}  // namespace

Command add_subdivide_command(CLI::App& app, const GlobalOptions& global) {
  auto opt = std::make_shared<SubdivideCommandOptions>();
  CLI::App* sub = app.add_subcommand("subdivide", "Subdivision surfaces (Loop, Catmull-Clark, bilinear) through OpenSubdiv");
  sub->add_option("input", opt->input, "Input mesh, or - for stdin (with --input-format)")->required();
  sub->add_option("-o,--output", opt->output, "Output mesh, or - for stdout (with --format)")->required();
  sub->add_option("--input-format", opt->input_format, "Input format when reading stdin")->check(format_validator());
  sub->add_option("--format", opt->format, "Output format when writing stdout")->check(format_validator());
  sub->add_option("-s,--scheme", opt->scheme,
                  "loop (triangles), catmull-clark or bilinear (polygons: quads in OBJ/OFF/PLY are kept)")
      ->capture_default_str()->check(CLI::IsMember({"loop", "catmull-clark", "bilinear"}));
  sub->add_option("-l,--levels", opt->subdivide.levels, "Refinement levels (faces grow 4x per level)")
      ->capture_default_str()->check(in_range(0, 10));
  sub->add_option("-t,--tolerance", opt->tolerance,
                  "Instead of --levels: the fewest levels whose surface is within this Hausdorff "
                  "distance of the next level's; absolute (0.001) or % of the diagonal (0.1%)");
  sub->add_option("--max-levels", opt->subdivide.max_levels, "Cap for --tolerance")->capture_default_str()
      ->check(in_range(0, 10));
  sub->add_option("--boundary", opt->boundary,
                  "Boundary rule: none (boundary faces shrink away), edge (smooth boundary curves), "
                  "edge-and-corner (keep valence-2 corners sharp)")
      ->capture_default_str()->check(CLI::IsMember({"none", "edge", "edge-and-corner"}));
  sub->add_option("--uv", opt->uv_rule,
                  "Where UVs (face-varying) stay linear: smooth, corners, corners1, corners2, "
                  "boundaries, all")
      ->capture_default_str()
      ->check(CLI::IsMember({"smooth", "corners", "corners1", "corners2", "boundaries", "all"}));
  sub->add_flag("--limit", opt->subdivide.limit, "Move the final points onto the limit surface");
  sub->add_option("--max-faces", opt->subdivide.max_faces,
                  "Refuse, before any work, levels that would make more triangles than this (refining "
                  "takes about 260 bytes a face)")
      ->capture_default_str()->check(CLI::Range(std::int64_t{1}, std::int64_t{2147483647}));
  sub->footer(R"(Examples:
  lodkit generate icosphere -o ico.ply --subdivisions 0
  lodkit subdivide ico.ply -o smooth.ply --scheme loop --levels 3 --limit
  lodkit subdivide cube.obj -o cc.obj --scheme catmull-clark --levels 4 --boundary edge-and-corner
  lodkit subdivide part.obj -o part_smooth.ply --scheme catmull-clark --tolerance 0.1%
Catmull-Clark output quads are split along their shorter diagonal (lodkit meshes are triangles).)");
  return {sub, [opt, &global] {
            const auto start = std::chrono::steady_clock::now();
            SubdivideCommandOptions& o = *opt;
            SubdivideOptions& s = o.subdivide;
            s.scheme = o.scheme == "loop"            ? SubdivisionScheme::Loop
                       : o.scheme == "catmull-clark" ? SubdivisionScheme::CatmullClark
                                                     : SubdivisionScheme::Bilinear;
            s.boundary = o.boundary == "none"   ? BoundaryRule::None
                         : o.boundary == "edge" ? BoundaryRule::EdgeOnly
                                                : BoundaryRule::EdgeAndCorner;
            const std::vector<std::string> uv_names{"smooth", "corners", "corners1", "corners2", "boundaries", "all"};
            s.uv_rule = static_cast<UvRule>(std::find(uv_names.begin(), uv_names.end(), o.uv_rule) - uv_names.begin());
            if (o.tolerance) {
              const LengthArgument tolerance = parse_length(*o.tolerance, "subdivide: --tolerance");
              s.tolerance = tolerance.value;
              s.tolerance_is_relative = tolerance.relative;
            }
            refuse_to_overwrite(o.output, {o.input});
            std::vector<int> polygon_sizes;
            ReadOptions read;
            read.polygon_sizes = &polygon_sizes;
            const Mesh mesh = read_input(o.input, o.input_format, read, "--input-format");
            const SubdivideResult result = subdivide(mesh, s, polygon_sizes);
            write_output(result.mesh, o.output, o.format, WriteOptions{}, {o.input});
            const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            if (!global.quiet) {
              fmt::print(stderr, "subdivide: {} -> {}: {} x {} level{}, {} -> {} faces, {:.3f} s\n", o.input, o.output,
                         o.scheme, result.levels, result.levels == 1 ? "" : "s", thousands(mesh.num_faces()),
                         thousands(result.mesh.num_faces()), seconds);
              for (std::size_t k = 0; k < result.level_change.size(); ++k)
                fmt::print(stderr, "  level {} -> {}: surface moves {:.6g}\n", k, k + 1, result.level_change[k]);
            }
            return 0;
          }};
}

}  // namespace lodkit::cli
