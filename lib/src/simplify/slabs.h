#pragma once
// Cutting a mesh into slabs that can be simplified side by side (the engine's lanes).
#include <vector>

#include "simplify/engine.h"

namespace lodkit::detail {

struct Slabs {
  /// Per point: the slab all its faces lie in, or -1 on a rim (faces in two slabs). A point on no
  /// alive face keeps -2.
  std::vector<Index> region;
  std::vector<Index> faces;  ///< alive faces per slab
  Index rim_faces = 0;       ///< alive faces with a corner on a rim
};

/// Slabs of equal face counts across the longest side of the bounding box, each face in the slab of
/// its centroid: `count` of them, or with `shifted`, cut halfway between those cuts instead (count + 1
/// slabs, the two end ones half as thick), so the first cut's rims lie inside the second's slabs.
Slabs cut_into_slabs(const EngineState& s, Index count, bool shifted = false);

/// Where a pass of lanes that starts at `alive` faces, with `rim_faces` of them on its slabs' rims, may
/// stop on the way to `target`. A rim stays put through its pass, at the density the pass started
/// with, while the rest coarsens: it ends with about rim_faces * (1 - stop / alive) faces too many.
/// Whatever follows must have at least three times that to remove; with less, the rims' detail has to
/// go all at once, wherever it is (a 20,480-face torus at 1 % in 8 slabs: RMS +80 %). The least such stop.
Index lane_pass_stop(Index alive, Index target, Index rim_faces);

}  // namespace lodkit::detail
