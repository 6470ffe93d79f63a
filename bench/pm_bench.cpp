// Progressive meshes: build time, cursor speed, stream size against Draco single-rate, and error per
// level. Usage: lodkit_bench_pm MESH... (peak memory: run under /usr/bin/time -v, see docs/benchmarks.md)
#include <lodkit/io.h>
#include <lodkit/metrics.h>
#include <lodkit/pm_io.h>
#include <lodkit/progressive.h>

#include <chrono>
#include <fmt/format.h>

#include "mesh_list_main.h"
#include "seconds_since.h"

using namespace lodkit;


constexpr const char* kUsage =
    "usage: lodkit_bench_pm MESH...\n"
    "Builds each mesh's progressive mesh and prints CSV on stdout: build time, refine/coarsen splits per\n"
    "second, lossless and 14-bit stream bytes against Draco's 14-bit single-rate file, prefix read time,\n"
    "and Hausdorff/RMS/bound of the levels at 10 % and 1 % of the faces.\n"
    "Example: build/bench/lodkit_bench_pm ../shared/models/scans/stanford_bunny_zipper.ply\n";

int run(int argc, char** argv);

int main(int argc, char** argv) { return mesh_list_main(argc, argv, "lodkit_bench_pm", kUsage, run); }

int run(int argc, char** argv) {
  fmt::print("mesh,faces,vertices,build_s,write_s,splits,refine_splits_per_s,coarsen_splits_per_s,lossless_bytes,"
             "q14_bytes,q14_bits_per_vertex,draco14_bytes,ratio_to_draco,read_prefix_ms,level_faces,hausdorff_pct,rms_pct,bound_pct\n");
  for (int i = 1; i < argc; ++i) {
    const std::string path = argv[i];
    const Mesh mesh = read_mesh(path);
    auto t = std::chrono::steady_clock::now();
    const ProgressiveMesh pm = build_progressive_mesh(mesh);
    const double build = seconds_since(t);
    PMCursor cursor(pm);
    // Several sweeps so the timer sees enough work.
    const int sweeps = 5;
    double refine = 0, coarsen = 0;
    for (int s = 0; s < sweeps; ++s) {
      t = std::chrono::steady_clock::now();
      cursor.go_to(pm.max_level());
      refine += seconds_since(t);
      t = std::chrono::steady_clock::now();
      cursor.go_to(0);
      coarsen += seconds_since(t);
    }
    const double splits = double(pm.max_level()) * sweeps;
    t = std::chrono::steady_clock::now();
    const std::string lossless = write_pm_to_memory(pm);
    const double write = seconds_since(t);
    PmWriteOptions q;
    q.position_bits = 14;
    const std::string quantised = write_pm_to_memory(pm, q);
    WriteOptions d;
    d.format = MeshFormat::Draco;
    d.draco.position_bits = 14;
    const std::string draco = write_mesh_to_memory(mesh, MeshFormat::Draco, d);
    const double diag = bounding_box(mesh).diagonal().norm();
    for (double fraction : {0.1, 0.01}) {
      const Index faces = static_cast<Index>(fraction * mesh.num_faces());
      t = std::chrono::steady_clock::now();
      PmReadOptions ro;
      ro.max_faces = faces;
      const PmReadResult prefix = read_pm_from_memory(quantised, path, ro);
      const ExtractedLevel e = extract_level(prefix.pm, prefix.pm.max_level(), VertexOrder::Stream);
      const double read_ms = 1000 * seconds_since(t);
      const Index level = level_for_faces(pm, faces);
      const Comparison c = compare(mesh, extract_level(pm, level).mesh);
      fmt::print("{},{},{},{:.3f},{:.3f},{},{:.3g},{:.3g},{},{},{:.1f},{},{:.2f},{:.2f},{},{:.4f},{:.4f},{:.4f}\n", path,
                 mesh.num_faces(), mesh.num_vertices(), build, write, pm.max_level(), splits / refine, splits / coarsen,
                 lossless.size(), quantised.size(), 8.0 * double(quantised.size()) / mesh.num_vertices(), draco.size(),
                 double(quantised.size()) / double(draco.size()), read_ms, pm.num_faces(level), 100 * c.hausdorff / diag,
                 100 * c.rms / diag, 100 * pm.level_error[level] / diag);
      (void)e;
    }
  }
  return 0;
}
