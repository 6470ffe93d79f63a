// simplify_within(): simplify() to the coarsest level found whose Hausdorff distance to the input is
// proved within a limit: the collapses recorded as a progressive mesh, its levels searched by
// prove_level_within(), then coarser levels refit and checked again.
#include <lodkit/error.h>
#include <lodkit/metrics.h>
#include <lodkit/progressive.h>
#include <lodkit/simplify.h>

#include <chrono>
#include <cmath>
#include <fmt/format.h>
#include <optional>

#include "core/topology.h"
#include "simplify/attribute_fit.h"
#include "simplify/refit_input.h"
#include "simplify/target.h"

namespace lodkit {

namespace {

struct RefitLevel {
  ExtractedLevel level;
  RefitReport report;
  HausdorffCheck check;
};

struct RefitSearch {
  Index level = 0;                   ///< of `best`
  std::optional<RefitLevel> best;    ///< the coarsest refit level that passed; none if `proved` refit did not
  std::optional<RefitLevel> failed;  ///< the refit level that failed nearest it, if one was checked
  int checks = 0;
};

// The refit (as simplify() runs it) brings a level nearer the input, so a coarser level than the one
// proved may pass once refit: the bunny at 0.2 % passes with 4,043 faces refit, against 6,167 without.
// Down from `proved`, halving the faces, refit levels are checked until one fails; then the search
// bisects between it and the last that passed, to 1/16 of the faces (about six refits: the bunny at
// 1 % takes 2.8 s instead of 0.53 s). Each face may turn from its orientation before the refit as far
// as the collapses let it turn from its input face. (Searching with 5 passes and refitting the level
// found with 10 ended coarser or finer by chance, 3,656 and 458 faces against 4,043 and 339 at 0.2 %
// and 1 %, in about as much time.)
RefitSearch search_refit_levels(const ProgressiveMesh& pm, const Mesh& input, double max_distance, Index proved,
                                const RefitOptions& options) {
  RefitSearch search;
  const detail::RefitInput prepared(input, options.avoid_inverted);
  const HausdorffChecker checker(input);
  auto refit_level = [&](Index l) {
    RefitLevel t{extract_level(pm, l, VertexOrder::Input), {}, {}};
    t.report = detail::refit_to_input(prepared, t.level.mesh, options);
    t.check = checker.check(t.level.mesh, max_distance);
    ++search.checks;
    return t;
  };
  // `proved` passes unrefit; refit, it is checked last, only if no coarser level passes refit (it is
  // the answer then, or it fails too and the unrefit level stands). That saves one refit of about seven
  // in 14 of 16 runs on eight shared meshes, and costs five where the refit fails every level (fandisk
  // at 0.2 %, 298 faces either way: 0.2 s more); outputs the same.
  Index hi = proved, lo = proved;
  auto take = [&](Index l, RefitLevel&& t) {
    if (t.check.within) search.best = std::move(t), hi = l;
    else search.failed = std::move(t), lo = l;
  };
  while (!search.failed) {  // down by halves
    const Index next = level_for_faces(pm, std::max<Index>(2, pm.num_faces(hi) / 2));
    if (next >= hi) break;
    take(next, refit_level(next));
  }
  while (search.failed && hi - lo > 1 && pm.num_faces(hi) - pm.num_faces(lo) > std::max<Index>(2, pm.num_faces(hi) / 16)) {
    const Index mid = lo + (hi - lo) / 2;
    take(mid, refit_level(mid));
  }
  if (hi == proved) {
    RefitLevel top = refit_level(proved);
    if (!top.check.within) {  // the unrefit level stands
      search.failed.reset();
      return search;
    }
    search.best = std::move(top);
  }
  search.level = hi;
  return search;
}

}  // namespace

SimplifyResult simplify_within(const Mesh& mesh, double max_distance, const SimplifyOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  if (!std::isfinite(max_distance) || max_distance < 0)
    throw Error(fmt::format("simplify: the Hausdorff limit must be finite and not negative, got {}", max_distance));
  validate(mesh, "simplify");
  detail::check_options(options);  // (before the build: a ratio past 1 would set the base's faces)
  // What the levels are built from and measured against: a copy when the input changes first. The
  // progressive mesh records collapses by vertex, so it cannot drop the input's normals as simplify()
  // does: it is built from a copy without them, and the output gets fresh ones. Faces that disagree on
  // orientation are turned, as simplify() turns them (orient_faces).
  const bool drop_normals = options.recompute_normals && mesh.has_normals();
  Mesh positions_only, turned;
  if (drop_normals) {
    positions_only = mesh;
    positions_only.attributes.normals.resize(0, 3);
  }
  Index turned_faces = 0;
  const Mesh& source = detail::oriented(drop_normals ? positions_only : mesh, options.orient_faces, turned, turned_faces);

  ProgressiveOptions po;
  po.simplify = options;
  po.simplify.recompute_normals = false;
  po.simplify.orient_faces = false;  // turned above
  const Index target = detail::requested_faces(mesh, options);  // 0: as far as legal collapses go
  po.base_faces = target;
  const ProgressiveMesh pm = build_progressive_mesh(source, po);

  const ProvedLevel proved = prove_level_within(pm, source, max_distance);
  Index hi = proved.level;
  SimplifyResult::HausdorffLimit within = proved.proof;

  std::optional<ExtractedLevel> level;  // the refit level found, else the proved one (extracted below)
  std::optional<RefitReport> refit;
  if (const RefitOptions refit_options = detail::refit_options(mesh, options, detail::starting_total_turn_deg(options));
      detail::refits(refit_options) && pm.max_level() > 0) {
    RefitSearch search = search_refit_levels(pm, source, max_distance, hi, refit_options);
    within.checks += search.checks;
    if (search.best) {
      hi = search.level;
      level.emplace(std::move(search.best->level));
      refit = search.best->report;
      within.bound = search.best->check.bound;
      within.coarser_faces.reset();
      if (search.failed) {
        within.coarser_faces = search.failed->level.mesh.num_faces();
        within.coarser_attained = search.failed->check.attained;
        within.coarser_at = search.failed->check.attained_at;
      }
    }
  }

  if (!level) level.emplace(extract_level(pm, hi, VertexOrder::Input));

  SimplifyResult r;
  r.refit = refit;
  r.mesh = std::move(level->mesh);
  if (options.recompute_normals) r.mesh.attributes.normals = compute_vertex_normals(r.mesh);
  // (Values only: the proof above holds.)
  if (hi < pm.max_level()) r.attribute_fit = detail::fit_simplified_attributes(source, nullptr, r.mesh, options);
  r.vertex_origin = std::move(level->vertex_origin);
  r.reoriented_faces = turned_faces;
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
