// libFuzzer target: a .pm stream's bytes. Reading must return what survives or throw lodkit::Error;
// the levels it returns must extract, geomorph and refine selectively (for a view culling back
// faces, and for every other split) without a crash or a sanitizer report, each vertex index in range.
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
    for (const SelectiveLevel& s : {refiner.refine_for_view(view, LevelErrorKind::Measured), refiner.refine(every_other)}) {
      const Mesh& m = s.extracted.mesh;
      for (Index f = 0; f < m.num_faces(); ++f)
        for (int k = 0; k < 3; ++k)
          if (m.triangles(f, k) < 0 || m.triangles(f, k) >= m.num_vertices()) __builtin_trap();
    }
  } catch (const Error&) {
  }
  return 0;
}
