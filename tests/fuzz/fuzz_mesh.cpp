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

// Finite positions and attributes, one attribute row per vertex, indices in range and (unless the
// mesh is the input given back) no face repeating a vertex.
void check_output(const Mesh& m, const char* what, bool may_repeat_input_faces = false) {
  const Index n = m.num_vertices();
  bool ok = m.positions.allFinite();
  for (Index f = 0; ok && f < m.num_faces(); ++f) {
    const auto t = m.triangles.row(f);
    for (int k = 0; k < 3; ++k) ok &= t[k] >= 0 && t[k] < n;
    ok &= may_repeat_input_faces || (t[0] != t[1] && t[1] != t[2] && t[0] != t[2]);
  }
  const Attributes& a = m.attributes;
  ok &= (a.normals.rows() == 0 || a.normals.rows() == n) && (a.uvs.rows() == 0 || a.uvs.rows() == n) &&
        (a.colours.rows() == 0 || a.colours.rows() == n) && a.normals.allFinite() && a.uvs.allFinite();
  if (!ok) {
    std::fprintf(stderr, "lodkit fuzz: invalid output from %s\n", what);
    std::abort();
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
