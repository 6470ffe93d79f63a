#pragma once
// Hoppe's points sampled on the input, shared by his energy (hoppe_cost.cpp keeps them, hoppe_scorer.cpp
// scores a collapse against them) and the fit after the collapses (hoppe_fit.cpp) (not public API).
#include <algorithm>
#include <cstdint>
#include <mutex>
#include <optional>
#include <unordered_map>
#include <utility>
#include <vector>

#include "simplify/engine.h"

namespace lodkit::detail {

/// A point sampled on the input's surface, kept with the current face it belongs to (inline, not by
/// index: a candidate reads every point of a dozen faces, and scattered points cost a cache miss each).
struct Sample {
  Eigen::Vector3d x;
  double dist2 = 0;  ///< squared distance to its face
};

/// Per face of the engine (dead ones empty): the points that belong to it.
using FaceSamples = std::vector<std::vector<Sample>>;

/// With E_scalar (attribute weights): per face, for each of its points in FaceSamples' order, the input's
/// k attribute values at the point (scaled as EngineState::wedge_value) and then the squared distance
/// from those to the current mesh's values at the point's projection (0 where that lies across an
/// attribute seam), and the point's chart: k + 2 numbers per point. (Apart from Sample, so that runs
/// without attributes read no more per point.)
using FaceValues = std::vector<std::vector<double>>;

/// Normals, UVs and colours: the most attribute values a wedge has.
constexpr std::size_t kMostAttributeDims = 3 + 2 + 4;

/// The points sampled on the input's boundary, each belonging to one boundary edge of the current mesh.
/// Lanes (slabs simplified side by side) look up and change the edges at their own points only, but
/// in one map: its lookups and changes take the lock. (A list found stays where it is: the map's
/// nodes never move, and no other lane touches it.)
struct BoundaryCurves {
  std::vector<Eigen::Vector3d> point;
  std::vector<double> dist2;  ///< per point: squared distance to its edge
  std::unordered_map<std::uint64_t, std::vector<Index>> edge_points;  ///< by edge_key()
  mutable std::mutex lock;

  static std::uint64_t edge_key(Index a, Index b) {
    return std::uint64_t(std::uint32_t(std::min(a, b))) << 32 | std::uint32_t(std::max(a, b));
  }
  static std::pair<Index, Index> edge_of(std::uint64_t key) { return {Index(key >> 32), Index(key & 0xffffffffu)}; }
  const std::vector<Index>* points_of(Index a, Index b) const {
    const std::lock_guard hold(lock);
    const auto it = edge_points.find(edge_key(a, b));
    return it == edge_points.end() ? nullptr : &it->second;
  }
};

/// The paper's spring schedule: springs matter while there are few points per face (they keep vertices
/// from drifting where the data cannot hold them) and fade as points accumulate.
inline double spring_constant(double points_per_face) {
  if (points_per_face < 4) return 1e-2;
  if (points_per_face < 8) return 1e-4;
  return 1e-8;
}

/// Moves every point of the current mesh that is not locked to where E = E_dist + E_spring (+ the
/// boundary points' squared distances to their edges) is least with each sample's barycentric weights
/// on its face held fixed: one sparse solve (see hoppe_fit.cpp). With `reassign`, each sample first
/// goes to the nearest of the faces at its face's corners. Returns E before the move (after the
/// reassignment); nothing when there is nothing to move or the solve fails.
std::optional<double> fit_points(EngineState& s, FaceSamples& samples, const BoundaryCurves& curves, bool reassign);

/// E at the current positions, each sample measured on its own face.
double points_energy(const EngineState& s, const FaceSamples& samples, const BoundaryCurves& curves);

}  // namespace lodkit::detail
