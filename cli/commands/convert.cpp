// lodkit convert: one mesh format to another, optionally welded, turned to agree on orientation or Draco-quantised.
#include <lodkit/error.h>
#include <lodkit/mesh.h>

#include <chrono>
#include <fmt/format.h>
#include <memory>

#include "common.h"

namespace lodkit::cli {
namespace {

struct ConvertOptions {
  std::string input, output, output_flag;
  std::optional<std::string> from, to;
  bool weld = false, drop_unreferenced = false, ascii = false, big_endian = false;
  bool no_normals = false, no_uvs = false, no_colours = false, compute_normals = false, orient = false;
  std::optional<int> quantize;
  int compression_level = 7;
};

int run_convert(const ConvertOptions& o, const GlobalOptions& global) {
  const std::string output = o.output_flag.empty() ? o.output : o.output_flag;
  if (output.empty()) throw Error("convert: no output given (lodkit convert IN OUT)");
  if (!o.output.empty() && !o.output_flag.empty())
    throw Error("convert: give the output once, either as OUT or with -o");
  if (output == "-" && !o.to) throw Error("<stdout>: give the format with --to (obj, ply, off, stl, drc)");  // fail fast
  const auto start = std::chrono::steady_clock::now();
  Mesh mesh = read_input(o.input, o.from, {}, "--from");
  const Index vertices_in = mesh.num_vertices();
  if (o.weld) weld_identical_vertices(mesh);
  if (o.drop_unreferenced) remove_unreferenced_vertices(mesh);
  const Index turned = o.orient ? orient_consistently(mesh) : 0;
  if (o.compute_normals) mesh.attributes.normals = compute_vertex_normals(mesh);

  WriteOptions w;
  if (o.ascii) {
    w.ply_encoding = PlyEncoding::Ascii;
    w.stl_binary = false;
  } else if (o.big_endian) {
    w.ply_encoding = PlyEncoding::BinaryBigEndian;
  }
  w.normals = !o.no_normals;
  w.uvs = !o.no_uvs;
  w.colours = !o.no_colours;
  if (o.quantize) w.draco.position_bits = *o.quantize;
  w.draco.compression_level = o.compression_level;
  write_output(mesh, output, o.to, w, {o.input}, "--to");
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!global.quiet)
    fmt::print(stderr, "convert: {} -> {}: {} vertices ({} in), {} faces, {:.3f} s\n", o.input, output,
               thousands(mesh.num_vertices()), thousands(vertices_in), thousands(mesh.num_faces()),
               seconds);
  if (o.orient && !global.quiet)
    fmt::print(stderr, "convert: turned {} faces to agree with their neighbours' orientation\n", thousands(turned));
  return 0;
}

}  // namespace

Command add_convert_command(CLI::App& app, const GlobalOptions& global) {
  auto opt = std::make_shared<ConvertOptions>();
  CLI::App* sub = app.add_subcommand("convert", "Convert a mesh between OBJ, PLY, OFF, STL and Draco");
  sub->add_option("input", opt->input, "Input mesh, or - for stdin (with --from)")->required();
  sub->add_option("output", opt->output, "Output mesh, or - for stdout (with --to)");
  sub->add_option("-o,--output", opt->output_flag, "Output mesh (alternative to the positional OUT)");
  sub->add_option("--from", opt->from, "Input format when reading stdin or a misnamed file")
      ->check(format_validator());
  sub->add_option("--to", opt->to, "Output format when writing stdout")->check(format_validator());
  sub->add_flag("--weld", opt->weld, "Merge vertices with identical positions and attributes");
  sub->add_flag("--drop-unreferenced", opt->drop_unreferenced, "Remove vertices no face uses");
  sub->add_flag("--orient", opt->orient,
                "Turn faces that disagree with their neighbours' orientation (closed parts end up facing outwards)");
  sub->add_flag("--compute-normals", opt->compute_normals, "Replace normals by area-weighted vertex normals");
  sub->add_flag("--ascii", opt->ascii, "Write ASCII PLY or STL instead of binary");
  sub->add_flag("--big-endian", opt->big_endian, "Write binary big-endian PLY");
  sub->add_flag("--no-normals", opt->no_normals, "Do not write normals");
  sub->add_flag("--no-uvs", opt->no_uvs, "Do not write texture coordinates");
  sub->add_flag("--no-colours", opt->no_colours, "Do not write colours");
  sub->add_option("--quantize", opt->quantize, "Draco position quantisation bits (0 = none; default 14)")
      ->check(in_range(0, 30));
  sub->add_option("--compression-level", opt->compression_level, "Draco compression level 0-10")
      ->check(in_range(0, 10))->capture_default_str();
  sub->footer(R"(Examples:
  lodkit convert bunny.obj bunny.ply
  lodkit convert scan.stl scan.ply --weld --drop-unreferenced
  lodkit convert shuffled.obj fixed.ply --orient
  lodkit convert bunny.ply bunny.drc --quantize 14
  lodkit convert model.obj - --to off | other-tool)");
  return {sub, [opt, &global] { return run_convert(*opt, global); }};
}

}  // namespace lodkit::cli
