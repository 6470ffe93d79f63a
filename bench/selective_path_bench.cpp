// A viewer moving along a path: the time per view of selective refinement from the base
// (SelectiveRefiner::refine_for_view) against a mesh kept from view to view (SelectiveMesh::adapt) and
// one that makes each step a geomorph (SelectiveMesh::morph_to_view) or only names the slots that change
// (SelectiveMesh::step_to_view), how many splits each step changes, and how far the surface jumps
// between frames with and without the geomorphs.
// Usage: lodkit_bench_selective_path MESH...
#include <lodkit/io.h>
#include <lodkit/metrics.h>
#include <lodkit/progressive.h>

#include <chrono>
#include <cmath>
#include <functional>
#include <fmt/format.h>
#include <numbers>

#include "mesh_list_main.h"
#include "seconds_since.h"

using namespace lodkit;

namespace {

constexpr const char* kUsage =
    "usage: lodkit_bench_selective_path MESH...\n"
    "Builds each mesh's progressive mesh (with measured levels) and prints CSV on stdout: per path (an\n"
    "orbit at 1.5 bounding radii, 0.5 deg per view; a dolly from 4 to 1.2 radii, 0.5 % of the distance\n"
    "per view; 240 views each, looking at the centre, 60 deg, 1080 px, 1 px by measured deviation), the\n"
    "mean milliseconds per view from the base, kept, kept as a geomorph from the view before (the\n"
    "morph's mesh and the view's), and kept naming the slots that change (no mesh made), with the mean\n"
    "wedge and face slots named per view, the mean splits applied and undone per view when kept, the mean\n"
    "splits applied, faces, and vertices of the morph. Every 24th step, the surface's jump (Hausdorff\n"
    "distance, % of the diagonal) from the view before: at once, and the largest of 4 frames' with the\n"
    "morph. Each kept and morphed view is checked against the fresh one. Then the mean splits applied per\n"
    "view to unfold faces that fold, and at those 10 views the faces facing against the input (compare's\n"
    "count), as shown and without unfolding (Viewpoint::unfold off).\n"
    "Example: build/bench/lodkit_bench_selective_path ../shared/models/scans/stanford_bunny_zipper.ply\n";

int run(int argc, char** argv) {
  fmt::print("mesh,faces,splits,path,views,fresh_ms,kept_ms,morph_ms,step_ms,slots_per_view,changed_per_view,splits_applied,"
             "view_faces,morph_vertices,jump_pct,morph_frame_jump_pct,unfolding_per_view,against,against_allowing_folds\n");
  constexpr int kViews = 240, kJumpEvery = 24, kFrames = 4;
  for (int i = 1; i < argc; ++i) {
    const std::string path = argv[i];
    const Mesh mesh = read_mesh(path);
    ProgressiveOptions options;
    options.measure_levels = true;
    const ProgressiveMesh pm = build_progressive_mesh(mesh, options);
    const SelectiveRefiner refiner(pm);
    const Eigen::Vector3d centre = pm.bounds.center();
    const double radius = bounding_radius(pm);
    const Eigen::Vector3d side = Eigen::Vector3d(0.3, 0.2, 1.0).normalized();
    auto orbit = [&](int v) -> Eigen::Vector3d {
      const double a = 0.5 * v * std::numbers::pi / 180;
      return centre + 1.5 * radius * Eigen::Vector3d(std::sin(a) * side.z() + std::cos(a) * side.x(), side.y(),
                                                     std::cos(a) * side.z() - std::sin(a) * side.x());
    };
    auto dolly = [&](int v) -> Eigen::Vector3d { return centre + std::max(1.2, 4.0 * std::pow(0.995, v)) * radius * side; };
    for (const auto& [name, eye_at] : {std::pair<const char*, std::function<Eigen::Vector3d(int)>>{"orbit", orbit}, {"dolly", dolly}}) {
      SelectiveMesh kept(refiner), morphing(refiner), stepping(refiner);
      double fresh_ms = 0, kept_ms = 0, morph_ms = 0, step_ms = 0, slots = 0, changed = 0, applied = 0, faces = 0, morph_vertices = 0;
      double jump = 0, frame_jump = 0, unfolding = 0;
      Index against = 0, against_folded = 0;
      Mesh before;
      for (int v = 0; v < kViews; ++v) {
        Viewpoint view;
        view.eye = eye_at(v);
        view.look_at = centre;
        auto t = std::chrono::steady_clock::now();
        const SelectiveLevel a = refiner.refine_for_view(view, LevelErrorKind::Measured);
        fresh_ms += 1000 * seconds_since(t);
        t = std::chrono::steady_clock::now();
        const SelectiveLevel b = kept.adapt(view, LevelErrorKind::Measured);
        kept_ms += 1000 * seconds_since(t);
        t = std::chrono::steady_clock::now();
        const SelectiveMorph m = morphing.morph_to_view(view, LevelErrorKind::Measured);
        morph_ms += 1000 * seconds_since(t);
        t = std::chrono::steady_clock::now();
        const SelectiveChanges c = stepping.step_to_view(view, LevelErrorKind::Measured);
        step_ms += 1000 * seconds_since(t);
        if (stepping.applied() != kept.applied()) throw std::runtime_error(fmt::format("{}: view {} of the {} differs stepped", path, v, name));
        if (v > 0) slots += double(c.wedges.size() + c.faces.size());
        for (const SelectiveLevel* other : {&b, &m.reached})
          if (a.extracted.mesh.triangles != other->extracted.mesh.triangles || a.extracted.mesh.positions != other->extracted.mesh.positions)
            throw std::runtime_error(fmt::format("{}: view {} of the {} differs kept", path, v, name));
        morph_vertices += double(m.geomorph.fine.mesh.num_vertices());
        if (v > 0 && v % kJumpEvery == 0) {
          // The frames a viewer sees: the view before, the morph's inner frames, this view.
          jump = std::max(jump, compare(before, b.extracted.mesh).hausdorff);
          // Faces facing against the input, unfolded and not.
          against += count_flipped_faces(mesh, b.extracted.mesh);
          Viewpoint as_is = view;
          as_is.unfold = false;
          against_folded += count_flipped_faces(mesh, refiner.refine_for_view(as_is, LevelErrorKind::Measured).extracted.mesh);
          Mesh last = before;
          for (int k = 1; k <= kFrames; ++k) {
            Mesh next = k < kFrames ? m.geomorph.at(double(k) / kFrames) : b.extracted.mesh;
            frame_jump = std::max(frame_jump, compare(last, next).hausdorff);
            last = std::move(next);
          }
        }
        before = b.extracted.mesh;
        if (v > 0) changed += double(b.splits_refined + b.splits_coarsened);  // the first view starts from the base
        applied += double(b.splits_applied);
        unfolding += double(b.splits_unfolding);
        faces += double(b.extracted.mesh.num_faces());
      }
      const double diagonal = pm.bounds.diagonal().norm();
      fmt::print("{},{},{},{},{},{:.3f},{:.3f},{:.3f},{:.3f},{:.0f},{:.1f},{:.0f},{:.0f},{:.0f},{:.5f},{:.5f},{:.2f},{},{}\n", path,
                 mesh.num_faces(), pm.splits.size(), name, kViews, fresh_ms / kViews, kept_ms / kViews, morph_ms / kViews,
                 step_ms / kViews, slots / (kViews - 1), changed / (kViews - 1),
                 applied / kViews, faces / kViews, morph_vertices / kViews, 100 * jump / diagonal, 100 * frame_jump / diagonal,
                 unfolding / kViews, against, against_folded);
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return mesh_list_main(argc, argv, "lodkit_bench_selective_path", kUsage, run); }
