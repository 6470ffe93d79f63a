// lodkit info: what a mesh file holds and whether algorithms can trust it.
#include <lodkit/inspect.h>

#include <cstdio>
#include <fmt/format.h>
#include <memory>

#include "common.h"

namespace lodkit::cli {
namespace {

struct InfoOptions {
  std::string input;
  std::optional<std::string> format;
  bool json = false;
};

void print_report(const std::string& input, const MeshReport& r) {
  auto line = [](const char* key, const std::string& value) { fmt::print("{:<12} {}\n", key, value); };
  line("file", input);
  line("vertices", fmt::format("{} ({} distinct positions in use, {} unreferenced, {} duplicate positions)",
                               thousands(r.vertices), thousands(r.welded_vertices),
                               thousands(r.unreferenced_vertices), thousands(r.duplicate_positions)));
  line("faces", thousands(r.faces));
  line("edges", thousands(r.edges));
  if (!r.bounds.isEmpty()) {
    const auto& lo = r.bounds.min();
    const auto& hi = r.bounds.max();
    line("bounds", fmt::format("[{:.6g} {:.6g} {:.6g}] .. [{:.6g} {:.6g} {:.6g}], diagonal {:.6g}", lo.x(),
                               lo.y(), lo.z(), hi.x(), hi.y(), hi.z(), r.diagonal));
  }
  std::string attrs;
  const std::string uvs =
      r.uv_charts ? fmt::format("uvs ({} chart{})", thousands(*r.uv_charts), *r.uv_charts == 1 ? "" : "s") : "uvs";
  for (auto [has, name] : {std::pair{r.has_normals, std::string("normals")}, {r.has_uvs, uvs},
                           {r.has_colours, std::string("colours")}, {r.has_face_colours, std::string("face colours")}})
    if (has) attrs += (attrs.empty() ? "" : ", ") + name;
  line("attributes", attrs.empty() ? "none" : attrs);
  std::string topo = r.closed ? "closed" : "open";
  topo += r.manifold ? ", manifold" : ", NOT manifold";
  if (r.manifold) topo += r.oriented ? ", oriented" : r.orientable == false ? ", NOT orientable" : ", NOT consistently oriented";
  topo += fmt::format(", {} component{}", r.components, r.components == 1 ? "" : "s");
  if (r.genus) topo += fmt::format(", genus {}", *r.genus);
  topo += fmt::format(", Euler characteristic {}", r.euler_characteristic);
  line("topology", topo);
  line("boundary", fmt::format("{} edges in {} loop{}", thousands(r.boundary_edges), r.boundary_loops,
                               r.boundary_loops == 1 ? "" : "s"));
  line("defects", fmt::format("{} non-manifold edges, {} non-manifold vertices, {} inconsistently "
                              "oriented edges, {} degenerate faces, {} duplicate faces",
                              r.non_manifold_edges, r.non_manifold_vertices,
                              r.inconsistently_oriented_edges, r.degenerate_faces, r.duplicate_faces));
  if (r.orientable == false)
    line("hint", "a one-sided surface (a Moebius band, a Klein bottle): no turning of faces makes every edge agree");
  else if (r.inconsistently_oriented_edges > 0)
    line("hint", "lodkit convert IN OUT --orient turns faces to agree with their neighbours (simplify and pm "
                 "build do so on their own copy)");
  line("area", fmt::format("{:.9g}", r.area));
  if (r.volume) {
    line("volume", fmt::format("{:.9g}{}", *r.volume, *r.volume < 0 ? " (negative: faces point inward)" : ""));
  } else {
    line("volume", "n/a (not a closed, oriented mesh)");
  }
}

}  // namespace

Command add_info_command(CLI::App& app, const GlobalOptions&) {
  auto opt = std::make_shared<InfoOptions>();
  CLI::App* sub = app.add_subcommand("info", "Report counts, bounds, topology and defects of a mesh");
  sub->add_option("input", opt->input, "Mesh file (.obj .ply .off .stl .drc), or - for stdin")->required();
  sub->add_option("--format", opt->format, "Format of the input when it is stdin or misnamed")
      ->check(format_validator());
  sub->add_flag("--json", opt->json, "Print one JSON object instead of the table");
  sub->footer(R"(Examples:
  lodkit info bunny.ply
  lodkit info torus.obj --json
  cat mesh.off | lodkit info - --format off)");
  return {sub, [opt] {
            const Mesh mesh = read_input(opt->input, opt->format);
            const MeshReport report = inspect(mesh);
            if (opt->json) {
              nlohmann::json j = to_json(report);
              j["file"] = opt->input;
              fmt::print("{}\n", j.dump(2));
            } else {
              print_report(opt->input, report);
            }
            return 0;
          }};
}

}  // namespace lodkit::cli
