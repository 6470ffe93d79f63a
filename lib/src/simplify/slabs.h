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

/// `count` slabs of equal face counts across the longest side of the bounding box, each face in the
/// slab of its centroid.
Slabs cut_into_slabs(const EngineState& s, Index count);

}  // namespace lodkit::detail
