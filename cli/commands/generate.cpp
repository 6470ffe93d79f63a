// lodkit generate: primitive meshes, sized by parameters, tessellated by counts or a chordal tolerance.
#include <lodkit/error.h>
#include <lodkit/primitives.h>

#include <chrono>
#include <fmt/format.h>
#include <memory>

#include "common.h"

namespace lodkit::cli {
namespace {

struct GenerateOptions {
  std::string shape, output;
  std::optional<std::string> format;
  std::optional<double> radius, height, tolerance, major_radius, minor_radius, base;
  std::vector<double> size;
  std::optional<int> segments, rings, subdivisions, stacks, divisions, major_segments, minor_segments;
  bool uvs = false, normals = false;
};

const std::vector<std::string> kShapes{"box", "sphere", "icosphere", "cylinder", "cone",
                                       "torus", "grid", "pyramid"};

Mesh generate(const GenerateOptions& o) {
  const std::string& s = o.shape;
  auto set = [](auto& field, const auto& value) {
    if (value) field = *value;
  };
  if (o.uvs && s != "sphere" && s != "torus" && s != "grid")
    throw Error(fmt::format("generate: --uvs is available for sphere, torus and grid, not {}", s));
  if (s == "box") {
    BoxOptions b;
    if (o.size.size() == 1) b.size.setConstant(o.size[0]);
    else if (o.size.size() == 3) b.size = {o.size[0], o.size[1], o.size[2]};
    else if (!o.size.empty()) throw Error("generate: box --size takes 1 or 3 values");
    set(b.divisions, o.divisions);
    return make_box(b);
  }
  if (s == "sphere") {
    UvSphereOptions b;
    set(b.radius, o.radius), set(b.segments, o.segments), set(b.rings, o.rings);
    b.tolerance = o.tolerance;
    b.uvs = o.uvs;
    return make_uv_sphere(b);
  }
  if (s == "icosphere") {
    IcosphereOptions b;
    set(b.radius, o.radius), set(b.subdivisions, o.subdivisions);
    b.tolerance = o.tolerance;
    return make_icosphere(b);
  }
  if (s == "cylinder") {
    CylinderOptions b;
    set(b.radius, o.radius), set(b.height, o.height), set(b.segments, o.segments), set(b.stacks, o.stacks);
    b.tolerance = o.tolerance;
    return make_cylinder(b);
  }
  if (s == "cone") {
    ConeOptions b;
    set(b.radius, o.radius), set(b.height, o.height), set(b.segments, o.segments);
    b.tolerance = o.tolerance;
    return make_cone(b);
  }
  if (s == "torus") {
    TorusOptions b;
    set(b.major_radius, o.major_radius), set(b.minor_radius, o.minor_radius);
    set(b.major_segments, o.major_segments), set(b.minor_segments, o.minor_segments);
    b.tolerance = o.tolerance;
    b.uvs = o.uvs;
    return make_torus(b);
  }
  if (s == "grid") {
    GridOptions b;
    if (o.size.size() == 1) b.size.setConstant(o.size[0]);
    else if (o.size.size() == 2) b.size = {o.size[0], o.size[1]};
    else if (!o.size.empty()) throw Error("generate: grid --size takes 1 or 2 values");
    if (o.divisions) b.divisions_x = b.divisions_y = *o.divisions;
    b.uvs = o.uvs;
    return make_grid(b);
  }
  PyramidOptions b;  // "pyramid" (CLI11 has checked the name)
  set(b.base, o.base), set(b.height, o.height);
  return make_square_pyramid(b);
}

}  // namespace

Command add_generate_command(CLI::App& app, const GlobalOptions& global) {
  auto opt = std::make_shared<GenerateOptions>();
  CLI::App* sub = app.add_subcommand("generate", "Generate a primitive mesh");
  sub->add_option("shape", opt->shape, "box, sphere, icosphere, cylinder, cone, torus, grid or pyramid")
      ->required()->check(CLI::IsMember(kShapes));
  sub->add_option("-o,--output", opt->output, "Output mesh, or - for stdout (with --format)")->required();
  sub->add_option("--format", opt->format, "Output format when writing stdout")->check(format_validator());
  sub->add_option("--tolerance", opt->tolerance,
                  "Chordal tolerance: the coarsest tessellation within this distance of the true "
                  "surface (sphere, icosphere, cylinder, cone, torus; overrides segment counts)");
  sub->add_option("--radius", opt->radius, "Radius (sphere, icosphere, cylinder, cone; default 1)");
  sub->add_option("--height", opt->height, "Height (cylinder, cone: 2; pyramid: 1)");
  sub->add_option("--segments", opt->segments, "Segments around the axis (sphere, cylinder, cone)");
  sub->add_option("--rings", opt->rings, "Rings pole to pole (sphere; default 16)");
  sub->add_option("--stacks", opt->stacks, "Rings along the axis (cylinder; default 1)");
  sub->add_option("--subdivisions", opt->subdivisions, "Subdivision levels (icosphere; default 3)");
  sub->add_option("--size", opt->size, "Edge lengths: box X [Y Z], grid X [Y] (default 1)")->expected(1, 3);
  sub->add_option("--divisions", opt->divisions, "Quads per side (box: 1, grid: 10)");
  sub->add_option("--major-radius", opt->major_radius, "Torus: axis to tube centre (default 1)");
  sub->add_option("--minor-radius", opt->minor_radius, "Torus: tube radius (default 0.25)");
  sub->add_option("--major-segments", opt->major_segments, "Torus: segments around the axis (48)");
  sub->add_option("--minor-segments", opt->minor_segments, "Torus: segments around the tube (16)");
  sub->add_option("--base", opt->base, "Pyramid: side of the square base (default 1)");
  sub->add_flag("--uvs", opt->uvs, "Add texture coordinates with seams (sphere, torus, grid)");
  sub->add_flag("--normals", opt->normals, "Add area-weighted vertex normals");
  sub->footer(R"(Examples:
  lodkit generate torus -o torus.ply
  lodkit generate sphere -o sphere.obj --radius 2 --tolerance 0.001 --uvs
  lodkit generate box -o box.off --size 2 1 1 --divisions 8
  lodkit generate grid -o plane.ply --size 10 --divisions 100)");
  return {sub, [opt, &global] {
            const auto start = std::chrono::steady_clock::now();
            Mesh mesh = generate(*opt);
            if (opt->normals) mesh.attributes.normals = compute_vertex_normals(mesh);
            write_output(mesh, opt->output, opt->format, WriteOptions{});
            const double seconds =
                std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            if (!global.quiet)
              fmt::print(stderr, "generate: {} -> {}: {} vertices, {} faces, {:.3f} s\n", opt->shape,
                         opt->output, thousands(mesh.num_vertices()), thousands(mesh.num_faces()), seconds);
            return 0;
          }};
}

}  // namespace lodkit::cli
