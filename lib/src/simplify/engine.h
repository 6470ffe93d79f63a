#pragma once
// The collapse engine's state and the interface its costs plug into (not public API).
//
//        w0                     Collapse u -> v: u disappears, v survives (possibly moved to p).
//       /  \                    The faces on edge uv (one on a boundary) vanish; every other face
//      /    \                   of u gets v in u's place. A vertex of the input is a "wedge"; wedges
//     u ---- v                  with one position are one "point", and the engine works on points,
//      \    /                   rewriting wedges so that attribute seams stay intact.
//       \  /
//        w1
#include <lodkit/simplify.h>

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "simplify/attribute_quadric.h"
#include "simplify/quadric.h"

namespace lodkit::detail {

enum PointFlag : std::uint8_t {
  kBorder = 1,   ///< on an open boundary
  kSeam = 2,     ///< its faces use more than one wedge (attribute discontinuity)
  kLocked = 4,   ///< never removed, never moved (non-manifold, or a locked boundary)
  kRemoved = 8,
};

struct EngineState {
  const Mesh* input = nullptr;
  std::vector<Index> point_of;                  ///< wedge -> point
  /// Positions are kept relative to this point, near the mesh when it lies far from the origin: a
  /// quadric's terms grow with the squared distance from the origin, and at 10^6 their rounding
  /// swamped the errors they rank. Subtracting it is exact (local_origin()).
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector3d> position;        ///< per point, relative to origin
  std::vector<Quadric> quadric;                 ///< per point: planes of its faces (and boundary)
  std::vector<std::uint8_t> flags;              ///< per point: PointFlag bits
  std::vector<std::vector<Index>> point_faces;  ///< per point: incident faces (dead ones pruned lazily)
  std::vector<std::array<Index, 3>> face;       ///< wedges of each face
  std::vector<std::array<Index, 3>> face_point; ///< points of each face (point_of[face]: one load, not two)
  std::vector<std::uint8_t> face_dead;
  std::vector<Eigen::Vector3f> face_normal0;    ///< each face's unit normal in the input
  /// The input's boundary edges (one face each), as that face runs them, sorted.
  std::vector<std::pair<Index, Index>> input_boundary;
  /// Hoppe: the input's interior edges whose faces turn by more than hoppe_crease_angle_deg, each as
  /// (its face of lower index, that face's side), in face order.
  std::vector<std::pair<Index, int>> sharp_edges;
  Index alive_faces = 0;

  /// Per-wedge attribute quadrics and values (scaled), when attribute weights are on.
  AttributeQuadrics attribute_quadrics;
  std::vector<double> wedge_value;  ///< k values per wedge

  /// Whether a position relative to origin lies within the coordinates validate() takes. An optimum
  /// can lie outside the input's box (by up to twice the edge's length), and near a float's range that
  /// is an output nothing could write or read back.
  bool representable(const Eigen::Vector3d& local) const {
    return within_coordinate_range(local + origin);
  }
  Index corner_point(Index f, int k) const { return face_point[f][k]; }
  bool has(Index p, PointFlag flag) const { return flags[p] & flag; }
  /// The side k of face f that joins points a and b (from corner k to k + 1, either way), or -1.
  int side(Index f, Index a, Index b) const {
    for (int k = 0; k < 3; ++k) {
      const Index p0 = corner_point(f, k), p1 = corner_point(f, (k + 1) % 3);
      if ((p0 == a && p1 == b) || (p0 == b && p1 == a)) return k;
    }
    return -1;
  }
  /// Alive faces of point p (a collapse prunes the dead ones from the lists it touches).
  const std::vector<Index>& faces_of(Index p) const { return point_faces[p]; }
  /// The points around p (each once with `repeats` false, else once per face that has it), sorted.
  void ring(Index p, std::vector<Index>& out, bool repeats = false) const {
    out.clear();
    for (Index f : faces_of(p))
      for (int k = 0; k < 3; ++k)
        if (corner_point(f, k) != p) out.push_back(corner_point(f, k));
    std::sort(out.begin(), out.end());
    if (!repeats) out.erase(std::unique(out.begin(), out.end()), out.end());
  }
};

/// What the structural checks of one candidate u -> v found. Each direction and each thread has its
/// own, so candidates can be checked and scored side by side.
struct Probe {
  std::vector<Index> shared;             ///< the faces on edge uv (they vanish), in u's face order
  std::pair<Index, Index> wedge_map[2];  ///< each wedge of u -> the wedge of v it merges into
  int wedge_map_size = 0;
};

/// Where the surviving vertex may go.
enum class Freedom { Free, AtKept };

struct Candidate {
  Eigen::Vector3d position;
  double cost = 0;   ///< priority (lower first)
  double error = 0;  ///< distance-like estimate reported to the user
};

class CostModel {
 public:
  virtual ~CostModel() = default;
  /// Scores collapse u -> v, whose checks filled `probe`. Fills `out`; returns false if the cost
  /// refuses the collapse. Called from several threads at once for different candidates.
  virtual bool score(const EngineState& s, const Probe& probe, Index u, Index v, Freedom freedom, Candidate& out) = 0;
  /// Called after u -> v was performed (faces and position; attribute values next); probe.shared are the
  /// faces that vanished, probe.wedge_map the wedges that merged.
  virtual void collapsed(EngineState&, Index /*u*/, Index /*v*/, const Probe& /*probe*/) {}
  /// True if collapsed() sets the merged wedges' attribute values itself (EngineState::wedge_value of the
  /// probe's wedge map), where the engine would take the attribute quadrics' best ones.
  virtual bool places_attributes() const { return false; }
  /// True if a collapse changes the costs of edges around v's neighbours too (not just v's edges):
  /// those are then re-scored lazily, when they reach the top of the queue.
  virtual bool wide_update() const { return false; }
  /// Once the collapses are done: moves the surviving points, connectivity fixed, to lower the cost's own
  /// measure over the whole mesh; `pass` counts from 0 (hoppe: Mesh optimization's position step,
  /// hoppe_fit.cpp), and returns the measure before the move; nothing for a cost that has no such step.
  /// The engine then sends back the moves that break its limits and asks fit_measure().
  virtual std::optional<double> fit(EngineState&, int /*pass*/) { return std::nullopt; }
  /// The measure fit() lowers, at the current positions.
  virtual double fit_measure(const EngineState&) { return 0; }
  /// True if one score costs enough (tens of microseconds) to share even a handful across threads.
  virtual bool costly() const { return false; }
  /// True while the cost scores by the quadric error in place of its own (hoppe, until
  /// SimplifyOptions::hoppe_energy_from); own_scores() ends that. Everything else, such as keeping the
  /// points on their faces, goes on as ever.
  virtual bool scores_by_quadric() const { return false; }
  virtual void own_scores() {}
};

std::unique_ptr<CostModel> make_quadric_cost(const SimplifyOptions& options);
std::unique_ptr<CostModel> make_edge_length_cost(const SimplifyOptions& options);
std::unique_ptr<CostModel> make_hoppe_cost(const SimplifyOptions& options, const EngineState& state);

/// The quadric error of placing the merged u, v at p, as a distance: sqrt(Q(p) / area).
inline double quadric_distance(const Quadric& q, const Eigen::Vector3d& p) {
  return q.weight > 0 ? std::sqrt(q.evaluate(p) / q.weight) : 0.0;
}

}  // namespace lodkit::detail
