#include "methods.h"

#include <lodkit/decimate.h>
#include <lodkit/error.h>
#include <lodkit/progressive.h>
#include <lodkit/simplify.h>

#include <chrono>
#include <sstream>
#include <string_view>

#include "seconds_since.h"

namespace lodkit::bench {
namespace {

// The input's vertex normals, UVs and colours, each output vertex taking its origin's: what a peer's
// output carries, being input vertices. Nothing when `run.vertex_origin` is empty.
void carry_attributes(const Mesh& input, PeerRun& run) {
  if (run.vertex_origin.empty()) return;
  const Attributes& from = input.attributes;
  Attributes& to = run.mesh.attributes;
  const auto n = static_cast<Index>(run.vertex_origin.size());
  if (input.has_normals()) to.normals.resize(n, 3);
  if (input.has_uvs()) to.uvs.resize(n, 2);
  if (input.has_colours()) to.colours.resize(n, 4);
  for (Index i = 0; i < n; ++i) {
    const Index v = run.vertex_origin[static_cast<std::size_t>(i)];
    if (input.has_normals()) to.normals.row(i) = from.normals.row(v);
    if (input.has_uvs()) to.uvs.row(i) = from.uvs.row(v);
    if (input.has_colours()) to.colours.row(i) = from.colours.row(v);
  }
}

}  // namespace

const std::vector<std::string>& all_methods() {
  static const std::vector<std::string> names{"quadric", "hoppe",          "edge-length", "schroeder", "pm",
                                              "meshopt", "meshopt-sloppy", "openmesh",    "cgal"};
  return names;
}

PeerRun run_method(const std::string& method, const Mesh& mesh, Index target) {
  // The peers see positions only; their outputs carry the attributes of the input vertices they kept.
  auto carried = [&](PeerRun run) {
    carry_attributes(mesh, run);
    return run;
  };
  if (method == "meshopt") return carried(run_meshoptimizer(mesh, target, false));
  if (method == "meshopt-sloppy") return carried(run_meshoptimizer(mesh, target, true));
  if (method == "openmesh") return carried(run_openmesh(mesh, target));
  if (method == "cgal") return carried(run_cgal(mesh, target));
  const auto t0 = std::chrono::steady_clock::now();
  if (method == "pm") {
    // The progressive-mesh path: build the stream (quadric collapses), then extract the level with
    // the target's face count: the cost of one level from scratch; every further level of the same
    // mesh costs only the extraction (see the progressive-mesh section of docs/benchmarks.md).
    const ProgressiveMesh pm = build_progressive_mesh(mesh);
    ExtractedLevel level = extract_level(pm, level_for_faces(pm, target));
    return {std::move(level.mesh), seconds_since(t0)};
  }
  if (method == "schroeder") {
    DecimateResult r = decimate(mesh, {.target_faces = target});
    return {std::move(r.mesh), seconds_since(t0)};
  }
  // "quadric-inverted-avoid": the method with SimplifyOptions::inverted_faces = Avoid (and "-allow",
  // "-refuse"; "-no-inverted" is "-inverted-refuse").
  std::string name = method;
  std::optional<InvertedFaces> inverted;
  if (name.ends_with("-no-inverted")) {
    name.resize(name.size() - std::string_view("-no-inverted").size());
    inverted = InvertedFaces::Refuse;
  } else if (const auto at = name.rfind("-inverted-"); at != std::string::npos) {
    inverted = parse_inverted_faces(name.substr(at + std::string_view("-inverted-").size()));
    if (!inverted) throw Error("unknown method " + method);
    name.resize(at);
  }
  const auto parsed = parse_method(name);
  if (!parsed) throw Error("unknown method " + method);
  SimplifyOptions o;
  o.method = *parsed;
  o.inverted_faces = inverted;
  o.target_faces = target;
  SimplifyResult r = simplify(mesh, o);
  return {std::move(r.mesh), seconds_since(t0)};
}

std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream ss(text);
  for (std::string item; std::getline(ss, item, ',');) out.push_back(item);
  return out;
}

}  // namespace lodkit::bench
