// lodkit terrain: fractal terrain by consistent midpoint displacement over a grid, a pyramid or any
// triangle mesh. PLY files are written while they are generated (any size); other formats and stdout
// go through a mesh in memory.
#include <lodkit/error.h>
#include <lodkit/terrain.h>

#include <chrono>
#include <fmt/format.h>
#include <memory>

#include "common.h"

namespace lodkit::cli {
namespace {

struct TerrainCommandOptions {
  std::string output, base = "pyramid", sigma = "10%", edge_direction = "auto";
  std::optional<std::string> format, base_format;
  TerrainOptions terrain;
};

Mesh load_base(const TerrainCommandOptions& o) {
  if (o.base == "grid") return make_terrain_base(TerrainBase::Grid);
  if (o.base == "pyramid") return make_terrain_base(TerrainBase::Pyramid);
  const Mesh base = read_input(o.base, o.base_format, {}, "--base-format");
  // A file that reads as a mesh may still be no terrain base (a face whose corners weld into one
  // point): check it here, where the error can name the file.
  try {
    (void)terrain_size(base, o.terrain.levels);
  } catch (const Error& e) {
    throw Error(fmt::format("{}: {}", o.base == "-" ? "stdin" : o.base, e.what()));
  }
  return base;
}

bool streams_ply(const TerrainCommandOptions& o) {
  if (o.output == "-") return false;
  const auto format = o.format ? parse_format(*o.format) : format_of(o.output);
  return format == MeshFormat::Ply;
}

}  // namespace

Command add_terrain_command(CLI::App& app, const GlobalOptions& global) {
  auto opt = std::make_shared<TerrainCommandOptions>();
  CLI::App* sub = app.add_subcommand("terrain", "Fractal terrain by consistent midpoint displacement");
  sub->add_option("-o,--output", opt->output, "Output mesh, or - for stdout (with --format)")->required();
  sub->add_option("--format", opt->format, "Output format when writing stdout")->check(format_validator());
  sub->add_option("--base", opt->base,
                  "grid (a two-triangle square), pyramid (four sides of a square pyramid) or a "
                  "triangle mesh file, or - for stdin with --base-format")
      ->capture_default_str();
  sub->add_option("--base-format", opt->base_format, "Format of the base when read from stdin")
      ->check(format_validator());
  sub->add_option("-l,--levels", opt->terrain.levels, "1-to-4 subdivisions: faces = base faces x 4^levels")
      ->capture_default_str()->check(in_range(0, 15));
  sub->add_option("-H,--roughness", opt->terrain.roughness,
                  "Hurst exponent H in (0, 1]: sigma_l = sigma * 2^(-l H); higher is smoother")
      ->capture_default_str();
  sub->add_option("--sigma", opt->sigma,
                  "Displacement scale sigma_0: absolute (0.05) or a percentage of the base's diagonal (10%)")
      ->capture_default_str();
  sub->add_option("--seed", opt->terrain.seed, "Random seed: same seed, same terrain")->capture_default_str();
  sub->add_flag("--colour,--color", opt->terrain.colour,
                "Flat per-face colours: height palette, inherited by keyed coin flips");
  sub->add_option("--palette-level", opt->terrain.palette_level,
                  "Points of this level or coarser are coloured by height")
      ->capture_default_str();
  sub->add_option("--edge-direction", opt->edge_direction,
                  "Displacement of points on original edges: auto (up for open bases, mean face "
                  "normal for closed ones), up (+z), normals")
      ->capture_default_str()->check(CLI::IsMember({"auto", "up", "normals"}));
  sub->add_option("-j,--threads", opt->terrain.threads, "Worker threads (0: all); never changes the result")
      ->capture_default_str();
  sub->footer(R"(Examples:
  lodkit terrain -o mountain.ply --levels 8 --colour
  lodkit terrain -o plain.ply --base grid --levels 10 --roughness 0.5 --sigma 5% --seed 7
  lodkit generate icosphere -o ball.ply --subdivisions 1
  lodkit terrain -o planet.ply --base ball.ply --levels 7 --sigma 3% --colour
Refining further with the same seed keeps every coarser point: 10 levels contain the 8-level
terrain's points bit for bit. PLY output is streamed (float32 positions, per-face uchar colours).)");
  return {sub, [opt, &global] {
            const auto start = std::chrono::steady_clock::now();
            TerrainCommandOptions& o = *opt;
            const LengthArgument sigma = parse_length(o.sigma, "terrain: --sigma");  // "5%": of the base's diagonal
            o.terrain.sigma = sigma.value;
            o.terrain.sigma_is_relative = sigma.relative;
            o.terrain.edge_direction = o.edge_direction == "up"        ? EdgeDirection::Up
                                       : o.edge_direction == "normals" ? EdgeDirection::FaceNormals
                                                                       : EdgeDirection::Auto;
            if (o.base != "grid" && o.base != "pyramid") refuse_to_overwrite(o.output, {o.base});
            const Mesh base = load_base(o);
            std::int64_t vertices = 0, faces = 0;
            if (streams_ply(o)) {
              const TerrainWriteStats stats = write_terrain_ply(base, o.terrain, o.output);
              vertices = stats.vertices, faces = stats.faces;
            } else {
              const Terrain t = generate_terrain(base, o.terrain);
              write_output(t.mesh, o.output, o.format, WriteOptions{});
              vertices = t.mesh.num_vertices(), faces = t.mesh.num_faces();
            }
            const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            if (!global.quiet)
              fmt::print(stderr, "terrain: {} x {} levels -> {}: {} vertices, {} faces, {:.3f} s\n", o.base,
                         o.terrain.levels, o.output, thousands(vertices), thousands(faces), seconds);
            return 0;
          }};
}

}  // namespace lodkit::cli
