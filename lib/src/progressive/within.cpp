// prove_level_within(): the coarsest level found of a progressive mesh whose Hausdorff distance to its
// input is proved within a limit, by a search over the levels with HausdorffChecker.
#include <lodkit/error.h>
#include <lodkit/metrics.h>
#include <lodkit/progressive.h>

#include <algorithm>
#include <cmath>
#include <fmt/format.h>

namespace lodkit {

ProvedLevel prove_level_within(const ProgressiveMesh& pm, const Mesh& input, double max_distance) {
  if (!std::isfinite(max_distance) || max_distance < 0)
    throw Error(fmt::format("progressive mesh: the Hausdorff limit must be finite and not negative, got {}", max_distance));
  if (input.num_faces() != pm.source_faces())
    throw Error(fmt::format("progressive mesh: the input has {} faces, the progressive mesh's finest level {}",
                            input.num_faces(), pm.source_faces()));
  // The answer lies between `lo`, a level that failed (or the base, unchecked), and `hi`, one proved
  // within: at first the coarsest level the stream's own distances prove within (the guaranteed ball
  // bound, or a measured level's certified distance; see level_for_error()), usually far too fine. A
  // check costs most where it passes on a fine level (every input face proved near the level;
  // bisecting down from there took igea_loop1 at 0.1 % 13.9 s instead of 7.9 s), so the search
  // gallops up from the base, doubling the faces, and bisects between the last level that failed and
  // the first that passed, to 1/256 of the faces.
  ProvedLevel out;
  SimplifyResult::HausdorffLimit& proof = out.proof;
  proof.max_distance = max_distance;
  const LevelErrorKind kind = pm.measured.empty() ? LevelErrorKind::Bound : LevelErrorKind::Measured;
  Index hi = level_for_error(pm, max_distance, kind);  // (the finest level at worst, 0 from the input)
  proof.bound = level_error(pm, hi, kind);
  Index lo = -1;  // no level known to fail yet
  bool galloping = true;
  const HausdorffChecker checker(input);
  PMCursor cursor(pm);
  // Checks `level`; moves hi or lo there.
  auto check = [&](Index level) {
    cursor.go_to(level);
    ++proof.checks;
    const HausdorffCheck c = checker.check(cursor.extract(VertexOrder::Stream).mesh, max_distance);
    if (c.within) {
      hi = level, proof.bound = c.bound;
    } else {
      lo = level, proof.coarser_attained = c.attained, proof.coarser_at = c.attained_at;
    }
  };
  if (hi > 0) check(0);  // the base: a generous limit passes there and needs nothing more
  while (lo >= 0 && hi - lo > 1) {
    const Index faces_lo = pm.num_faces(lo), faces_hi = pm.num_faces(hi);
    if (faces_hi - faces_lo <= std::max<Index>(2, faces_hi / 256)) break;
    Index next = level_for_faces(pm, std::max<Index>(2 * faces_lo, 4));
    if (next >= hi || !galloping) next = lo + (hi - lo) / 2;
    if (next <= lo) next = lo + 1;
    const Index before = hi;
    check(next);
    if (hi != before) galloping = false;  // passed: bisect from here on
  }
  if (lo >= 0) proof.coarser_faces = pm.num_faces(lo);
  out.level = hi;
  return out;
}

}  // namespace lodkit
