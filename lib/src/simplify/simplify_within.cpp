// simplify_within(): simplify() to the coarsest level found whose Hausdorff distance to the input is
// proved within a limit: the collapses recorded as a progressive mesh, its levels searched by
// prove_level_within().
#include <lodkit/error.h>
#include <lodkit/progressive.h>
#include <lodkit/simplify.h>

#include <chrono>
#include <cmath>
#include <fmt/format.h>

#include "simplify/target.h"

namespace lodkit {

SimplifyResult simplify_within(const Mesh& mesh, double max_distance, const SimplifyOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  if (!std::isfinite(max_distance) || max_distance < 0)
    throw Error(fmt::format("simplify: the Hausdorff limit must be finite and not negative, got {}", max_distance));
  validate(mesh, "simplify");
  // The progressive mesh records collapses by vertex, so it cannot drop the input's normals as simplify()
  // does: it is built from a copy without them, and the output gets fresh ones.
  Mesh positions_only;
  const bool drop_normals = options.recompute_normals && mesh.has_normals();
  if (drop_normals) {
    positions_only = mesh;
    positions_only.attributes.normals.resize(0, 3);
  }
  const Mesh& source = drop_normals ? positions_only : mesh;

  ProgressiveOptions po;
  po.simplify = options;
  po.simplify.recompute_normals = false;
  const Index target = detail::requested_faces(mesh, options);  // 0: as far as legal collapses go
  po.base_faces = target;
  const ProgressiveMesh pm = build_progressive_mesh(source, po);

  const ProvedLevel proved = prove_level_within(pm, source, max_distance);
  const Index hi = proved.level;
  const SimplifyResult::HausdorffLimit& within = proved.proof;

  SimplifyResult r;
  ExtractedLevel level = extract_level(pm, hi, VertexOrder::Input);
  r.mesh = std::move(level.mesh);
  if (options.recompute_normals) r.mesh.attributes.normals = compute_vertex_normals(r.mesh);
  r.vertex_origin = std::move(level.vertex_origin);
  r.faces_in = mesh.num_faces();
  r.vertices_in = mesh.num_vertices();
  r.faces_out = r.mesh.num_faces();
  r.vertices_out = r.mesh.num_vertices();
  r.target_faces = target;
  r.collapses = pm.max_level() - hi;
  if (within.coarser_faces) {
    r.reason = StopReason::HausdorffLimit;
    r.reason_text = fmt::format(
        "stopped at {} faces, the coarsest level found within the Hausdorff limit of {:.6g} (proved at most {:.6g}); "
        "a coarser level, {} faces, has a point {:.6g} from the other surface",
        r.faces_out, max_distance, within.bound, *within.coarser_faces, within.coarser_attained);
  } else {
    r.reason = r.faces_out <= target ? StopReason::TargetReached : StopReason::NoLegalCollapse;
    const char* where = r.reason == StopReason::TargetReached
                            ? "reached the target:"
                            : "the collapses stopped (none legal, or the error limit) at";
    r.reason_text = fmt::format("{} {} faces, within the Hausdorff limit of {:.6g} (proved at most {:.6g})", where,
                                r.faces_out, max_distance, within.bound);
  }
  r.within = within;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

}  // namespace lodkit
