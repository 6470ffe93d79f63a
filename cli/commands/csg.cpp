// lodkit csg: booleans of closed meshes, and CSG trees from JSON.
#include <lodkit/csg.h>
#include <lodkit/error.h>

#include <fmt/format.h>
#include <memory>
#include <string>
#include <vector>

#include "common.h"

namespace lodkit::cli {
namespace {

struct CsgCliOptions {
  std::string a, b, tree, output;
  std::optional<std::string> format;
  double tolerance = 0.01;
  bool exact = false, json = false;
  std::size_t split_at_parts = CsgOptions{}.split_at_parts;
};

void report(const GlobalOptions& global, bool as_json, const std::string& what, const std::string& output, const Mesh& mesh,
            double volume, double seconds, const std::vector<std::string>& warnings, bool used_exact) {
  for (const auto& w : warnings) fmt::print(stderr, "lodkit: warning: {}\n", w);
  if (as_json) {
    nlohmann::json j{{"operation", what}, {"output", output}, {"faces", mesh.num_faces()}, {"vertices", mesh.num_vertices()},
                     {"volume", volume}, {"seconds", seconds}, {"exact", used_exact}, {"warnings", warnings}};
    fmt::print("{}\n", j.dump(2));
  } else if (!global.quiet) {
    fmt::print(stderr, "csg {}: {} faces, volume {:.9g}, {:.3f} s{} -> {}\n", what, thousands(mesh.num_faces()), volume, seconds,
               used_exact ? " (exact constructions)" : "", output);
  }
}

// The tree's file and every mesh file it reads: none may be the output.
std::vector<std::string> files_read(const std::string& tree_file, const CsgNode& root) {
  std::vector<std::string> files{tree_file};
  auto visit = [&](const CsgNode& node, auto&& self) -> void {
    if (node.kind == CsgNode::Kind::MeshFile) files.push_back(node.mesh.string());
    for (const CsgNode& child : node.children) self(child, self);
  };
  visit(root, visit);
  return files;
}

}  // namespace

Command add_csg_command(CLI::App& app, const GlobalOptions& global) {
  auto opt = std::make_shared<CsgCliOptions>();
  CLI::App* sub = app.add_subcommand("csg", "Booleans of closed meshes and CSG trees (through CGAL)");
  sub->require_subcommand(1);
  std::vector<std::pair<CLI::App*, BooleanOp>> ops;
  for (const auto& [name, op] : {std::pair{"union", BooleanOp::Union}, {"difference", BooleanOp::Difference},
                                 {"intersection", BooleanOp::Intersection}}) {
    CLI::App* o = sub->add_subcommand(name, fmt::format("The {} of two closed meshes", name));
    o->add_option("a", opt->a, "First closed mesh")->required();
    o->add_option("b", opt->b, "Second closed mesh")->required();
    o->add_option("-o,--output", opt->output, "Output mesh, or - for stdout (with --format)")->required();
    o->add_option("--format", opt->format, "Format of stdout")->check(format_validator());
    o->add_flag("--exact", opt->exact, "Exact constructions from the start (slower; used anyway when needed)");
    o->add_flag("--json", opt->json, "Print the result as JSON");
    o->footer(fmt::format("Example:\n  lodkit csg {} a.ply b.ply -o out.ply", name));
    ops.push_back({o, op});
  }
  CLI::App* tree = sub->add_subcommand("tree", "Evaluate a CSG tree (JSON) of primitives, meshes and transforms");
  tree->add_option("model", opt->tree, "The tree, e.g. data/csg/housing.json")->required();
  tree->add_option("-o,--output", opt->output, "Output mesh, or - for stdout (with --format)")->required();
  tree->add_option("--format", opt->format, "Format of stdout")->check(format_validator());
  tree->add_option("--tolerance", opt->tolerance, "Chordal tolerance of curved primitives")->check(kPositive)
      ->capture_default_str();
  tree->add_flag("--exact", opt->exact, "Exact constructions from the start");
  tree->add_option("--split-at-parts", opt->split_at_parts,
                   "Cut a difference with at least this many separate cutting parts in two (in parallel, then "
                   "joined; adds a seam of edges); 0 never")
      ->capture_default_str();
  tree->add_flag("--json", opt->json, "Print the result as JSON");
  tree->footer(R"(Nodes: {"op": "union|difference|intersection", "children": [...]},
       {"primitive": "box|sphere|cylinder|cone|torus", "size"/"radius"/"height"/"major_radius"/"minor_radius"},
       {"mesh": "path.ply"}; any node may carry "transform": {"scale", "rotate", "translate"} or {"matrix"}.
Example:
  lodkit csg tree data/csg/housing.json -o housing.ply --tolerance 0.005)");
  sub->footer(R"(Examples:
  lodkit csg union a.ply b.ply -o ab.ply
  lodkit csg tree data/csg/plate_with_holes.json -o plate.ply)");
  return {sub, [opt, ops, tree, &global] {
            for (const auto& [app_op, op] : ops) {
              if (!app_op->parsed()) continue;
              refuse_to_overwrite(opt->output, {opt->a, opt->b});  // before reading: fail fast
              refuse_json_beside_stdout(opt->json, opt->output);
              const Mesh a = read_input(opt->a, std::nullopt, {}, nullptr), b = read_input(opt->b, std::nullopt, {}, nullptr);
              const BooleanResult r = boolean(a, b, op, {.exact = opt->exact}, opt->a, opt->b);
              write_output(r.mesh, opt->output, opt->format, WriteOptions{}, {opt->a, opt->b});
              report(global, opt->json, to_string(op), opt->output, r.mesh, r.volume, r.seconds, r.warnings, r.used_exact);
              return 0;
            }
            if (!tree->parsed()) return 2;
            const CsgNode root = read_csg(opt->tree);
            const std::vector<std::string> inputs = files_read(opt->tree, root);
            refuse_to_overwrite(opt->output, inputs);
            refuse_json_beside_stdout(opt->json, opt->output);
            CsgResult r;
            try {
              r = evaluate(root, {.tolerance = opt->tolerance, .exact = opt->exact, .split_at_parts = opt->split_at_parts});
            } catch (const Error& e) {  // "$.children[1]: ...": which file the JSON path is in
              throw Error(fmt::format("{}: {}", opt->tree, e.what()));
            }
            write_output(r.mesh, opt->output, opt->format, WriteOptions{}, inputs);
            report(global, opt->json, fmt::format("tree ({} primitives, {} operations)", r.primitives, r.operations), opt->output,
                   r.mesh, r.volume, r.seconds, r.warnings, false);
            return 0;
          }};
}

}  // namespace lodkit::cli
