// Selective refinement against uniform levels: for viewers at several distances, the faces each way
// needs for the same pixel budget, the time per view, and the distance compare() measures against the
// deviation the selective mesh reports. Usage: lodkit_bench_selective MESH...
#include <lodkit/io.h>
#include <lodkit/metrics.h>
#include <lodkit/progressive.h>

#include <chrono>
#include <fmt/format.h>

#include "mesh_list_main.h"
#include "seconds_since.h"

using namespace lodkit;

namespace {

constexpr const char* kUsage =
    "usage: lodkit_bench_selective MESH...\n"
    "Builds each mesh's progressive mesh (with measured levels) and prints CSV on stdout: for an eye at\n"
    "1.2, 2, 4 and 8 bounding radii from the centre (looking at it, 60 deg, 1080 px) and budgets of 1 and\n"
    "4 px, the faces of the selective mesh by measured deviation and by the bound, of the uniform level\n"
    "by measured error and by the bound, the milliseconds per selective view, and the Hausdorff distance\n"
    "compare() measures between the selective mesh and the input beside the deviation it reports.\n"
    "Example: build/bench/lodkit_bench_selective ../shared/models/scans/stanford_bunny_zipper.ply\n";

int run(int argc, char** argv) {
  fmt::print("mesh,faces,build_s,refiner_s,eye_radii,pixels,selective_faces,selective_bound_faces,uniform_faces,"
             "uniform_bound_faces,view_ms,hausdorff,deviation,error_bound\n");
  for (int i = 1; i < argc; ++i) {
    const std::string path = argv[i];
    const Mesh mesh = read_mesh(path);
    auto t = std::chrono::steady_clock::now();
    ProgressiveOptions options;
    options.measure_levels = true;
    const ProgressiveMesh pm = build_progressive_mesh(mesh, options);
    const double build = seconds_since(t);
    t = std::chrono::steady_clock::now();
    const SelectiveRefiner refiner(pm);
    const double setup = seconds_since(t);
    const Mesh finest = extract_level(pm, pm.max_level(), VertexOrder::Stream).mesh;
    const Eigen::Vector3d centre = pm.bounds.center();
    const double radius = bounding_radius(pm);
    for (double radii : {1.2, 2.0, 4.0, 8.0}) {
      for (double pixels : {1.0, 4.0}) {
        Viewpoint view;
        view.look_at = centre;
        view.eye = centre + Eigen::Vector3d(0.3, 0.2, 1.0).normalized() * radii * radius;
        view.pixel_error = pixels;
        t = std::chrono::steady_clock::now();
        const SelectiveLevel s = refiner.refine_for_view(view, LevelErrorKind::Measured);
        const double view_ms = 1000 * seconds_since(t);
        const SelectiveLevel b = refiner.refine_for_view(view, LevelErrorKind::Bound);
        const ScreenSpaceBudget uniform{pixels, radii * radius, view.fov_degrees, view.viewport_pixels};
        const Index measured_level = level_for_view(pm, uniform, LevelErrorKind::Measured);
        const Index bound_level = level_for_view(pm, uniform, LevelErrorKind::Bound);
        const Comparison c = compare(finest, s.extracted.mesh);
        fmt::print("{},{},{:.3f},{:.3f},{},{},{},{},{},{},{:.2f},{:.6g},{:.6g},{:.6g}\n", path, mesh.num_faces(), build,
                   setup, radii, pixels, s.extracted.mesh.num_faces(), b.extracted.mesh.num_faces(),
                   pm.num_faces(measured_level), pm.num_faces(bound_level), view_ms, c.hausdorff, s.deviation,
                   s.error_bound);
      }
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return mesh_list_main(argc, argv, "lodkit_bench_selective", kUsage, run); }
