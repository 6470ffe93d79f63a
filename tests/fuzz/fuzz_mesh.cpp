// libFuzzer target: a mesh file's bytes, read as LODKIT_FUZZ_FORMAT (one binary per format).
//
// The reader must either return a mesh or throw lodkit::Error; anything else (a crash, a sanitizer
// report, another exception, a hang, gigabytes allocated for a corrupt count) is a finding. With
// LODKIT_FUZZ_DEEP set in the environment, each mesh that reads (up to 3,000 faces) also goes through
// every simplification method, a progressive mesh and its stream, and compare, and their outputs are
// checked for what any output must be. See docs/fuzzing.md.
#include <lodkit/decimate.h>
#include <lodkit/error.h>
#include <lodkit/inspect.h>
#include <lodkit/io.h>
#include <lodkit/metrics.h>
#include <lodkit/pm_io.h>
#include <lodkit/progressive.h>
#include <lodkit/simplify.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string_view>

namespace {

using namespace lodkit;

// What validate() asks of every mesh (finite values within a float's range, indices in range, one
// attribute row per vertex or face) and, unless the mesh is the input given back, no face repeating
// a vertex.
void check_output(const Mesh& m, const char* what, bool may_repeat_input_faces = false) {
  try {
    validate(m, what);
  } catch (const Error& e) {
    std::fprintf(stderr, "lodkit fuzz: invalid output: %s\n", e.what());
    std::abort();
  }
  for (Index f = 0; f < m.num_faces() && !may_repeat_input_faces; ++f) {
    const auto t = m.triangles.row(f);
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
      std::fprintf(stderr, "lodkit fuzz: invalid output from %s: face %d repeats a vertex\n", what, f);
      std::abort();
    }
  }
}

void simplify_every_way(const Mesh& mesh) {
  for (SimplifyMethod method : {SimplifyMethod::Quadric, SimplifyMethod::Hoppe, SimplifyMethod::EdgeLength}) {
    try {
      SimplifyOptions options;
      options.method = method;
      options.target_ratio = 0.3;
      options.hoppe_min_points = 200;  // a few points a face, not 100,000
      options.record_collapses = true;
      check_output(simplify(mesh, options).mesh, "simplify");
    } catch (const Error&) {
    }
  }
  try {
    DecimateOptions options;
    options.target_ratio = 0.3;
    check_output(decimate(mesh, options).mesh, "decimate");
  } catch (const Error&) {
  }
  try {
    ProgressiveOptions options;
    options.simplify.hoppe_min_points = 200;
    const ProgressiveMesh pm = build_progressive_mesh(mesh, options);
    const PmReadResult back = read_pm_from_memory(write_pm_to_memory(pm), "round trip");
    const Index finest = static_cast<Index>(pm.splits.size());
    check_output(extract_level(back.pm, finest / 2).mesh, "pm level", finest / 2 == finest);
    const Mesh written = extract_level(pm, finest).mesh, read = extract_level(back.pm, finest).mesh;
    check_output(read, "pm finest level", true);  // the input again, degenerate faces and all
    if (written.positions != read.positions || written.triangles != read.triangles) {
      std::fprintf(stderr, "lodkit fuzz: a lossless .pm stream read back differently\n");
      std::abort();
    }
  } catch (const Error&) {
  }
  try {
    CompareOptions options;
    options.samples = 2000;
    // Coplanar faces overlapping with open edges (the same mesh twice, ties everywhere) take the
    // certificate to its split limit, seconds under the sanitizers: a known limit, not a finding.
    options.max_splits = 20000;
    (void)compare(mesh, mesh, options);
  } catch (const Error&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  Mesh mesh;
  try {
    mesh = read_mesh_from_memory(bytes, MeshFormat::LODKIT_FUZZ_FORMAT, "fuzz input");
  } catch (const Error&) {
    return 0;
  }
  (void)inspect(mesh);
  static const bool deep = std::getenv("LODKIT_FUZZ_DEEP") != nullptr;
  if (deep && mesh.num_faces() <= 3000 && mesh.num_vertices() <= 3000) simplify_every_way(mesh);
  return 0;
}
