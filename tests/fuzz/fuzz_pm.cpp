// libFuzzer target: a .pm stream's bytes. Reading must return what survives or throw lodkit::Error;
// the levels it returns must extract, geomorph and refine selectively (for a view culling back
// faces, and for every other split) without a crash or a sanitizer report, each vertex index in range;
// the view's splits found down the hierarchy must be those of testing every region, a kept mesh
// moved from one set to the other must give the same meshes, and so must a geomorph between them
// (views unfolded, sets not).
#include <lodkit/error.h>
#include <lodkit/pm_io.h>
#include <lodkit/progressive.h>

#include <cstdint>
#include <string_view>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace lodkit;
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  try {
    const PmReadResult r = read_pm_from_memory(bytes, "fuzz input");
    const ProgressiveMesh& pm = r.pm;
    const Index n = static_cast<Index>(pm.splits.size());
    if (pm.base_faces + 2 * static_cast<long long>(n) > 20000) return 0;  // keep each run short
    (void)extract_level(pm, 0);
    (void)extract_level(pm, n / 2);
    (void)extract_level(pm, n);
    if (n > 0) (void)make_geomorph(pm, 0, n);
    const SelectiveRefiner refiner(pm);
    Viewpoint view;
    view.look_at = pm.bounds.isEmpty() ? Eigen::Vector3d::Zero() : Eigen::Vector3d(pm.bounds.center());
    view.eye = view.look_at + Eigen::Vector3d(0.3, 0.2, 1.0) * (1.0 + bounding_radius(pm));
    if (!view.eye.allFinite() || !((view.look_at - view.eye).norm() > 0)) return 0;
    view.cull_backfaces = true;
    std::vector<char> every_other(static_cast<std::size_t>(n), 0);
    for (std::size_t j = 0; j < every_other.size(); j += 2) every_other[j] = 1;
    const SelectiveLevel seen = refiner.refine_for_view(view, LevelErrorKind::Measured), half = refiner.refine(every_other);
    auto check_indices = [](const Mesh& m) {
      for (Index f = 0; f < m.num_faces(); ++f)
        for (int k = 0; k < 3; ++k)
          if (m.triangles(f, k) < 0 || m.triangles(f, k) >= m.num_vertices()) __builtin_trap();
    };
    check_indices(seen.extracted.mesh);
    check_indices(half.extracted.mesh);
    // The hierarchy finds what testing every region finds; a kept mesh moves between sets exactly.
    std::vector<char> every = refiner.regions_needing_refinement(view, LevelErrorKind::Measured);
    for (std::size_t j = every.size(); j-- > 0;)
      if (every[j])
        for (Index d : refiner.dependencies(static_cast<Index>(j))) every[static_cast<std::size_t>(d)] = 1;
    if (every != refiner.splits_for_view(view, LevelErrorKind::Measured)) __builtin_trap();
    SelectiveMesh kept(refiner);
    if (kept.go_to(every_other).extracted.mesh.triangles != half.extracted.mesh.triangles) __builtin_trap();
    const SelectiveLevel moved = kept.adapt(view, LevelErrorKind::Measured);
    if (moved.extracted.mesh.triangles != seen.extracted.mesh.triangles ||
        moved.extracted.mesh.positions != seen.extracted.mesh.positions)
      __builtin_trap();
    // A geomorph back to the other set: it reaches that set's mesh, and its faces index its vertices.
    const SelectiveMorph back = kept.morph_to(every_other);
    if (back.reached.extracted.mesh.triangles != half.extracted.mesh.triangles ||
        back.reached.extracted.mesh.positions != half.extracted.mesh.positions)
      __builtin_trap();
    const Mesh& joint = back.geomorph.fine.mesh;
    if (back.geomorph.start_positions.rows() != joint.num_vertices()) __builtin_trap();
    check_indices(joint);
    (void)back.geomorph.at(0.5);
    // And a geomorph to the view again, unfolded from a state that was not.
    const SelectiveMorph again = kept.morph_to_view(view, LevelErrorKind::Measured);
    if (again.reached.extracted.mesh.triangles != seen.extracted.mesh.triangles ||
        again.reached.extracted.mesh.positions != seen.extracted.mesh.positions)
      __builtin_trap();
  } catch (const Error&) {
  }
  return 0;
}
