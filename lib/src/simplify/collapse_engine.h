#pragma once
// The edge-collapse engine behind simplify(): its queue entries, lanes and class (not public API). Its
// work is split by job: engine_setup.cpp (from a mesh to the engine's state), engine_checks.cpp (whether
// a collapse is legal), engine_rating.cpp (candidates into queue entries), engine_collapse.cpp
// (performing one) and engine_run.cpp (the queue's loop, the lanes, the stop report and the output).
#include <lodkit/simplify.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <numbers>
#include <optional>
#include <set>
#include <string>
#include <tuple>
#include <utility>
#include <vector>
#include <tbb/enumerable_thread_specific.h>

#include "core/geometry.h"
#include "core/topology.h"
#include "metrics/aabb_tree.h"
#include "simplify/engine.h"
#include "simplify/queue.h"
#include "simplify/target.h"
#include "simplify/slabs.h"

namespace lodkit::detail {

// Why a candidate collapse was refused. The final report counts these over the edges left.
enum class Rejection { None, Locked, Topology, Boundary, Seam, Valence, Flip, Inverted, Sliver, ErrorLimit, Cost, kCount };

// At most this many lanes (slabs simplified side by side; see Engine::run_lanes).
constexpr Index kMaxLanes = 8;

// InvertedFaces::Avoid: a collapse that would leave a face facing against the input waits in the queue
// until the collapses cost this many times the most the lane had paid for one when it was found (for
// quadric's squared distances, twice the distance); if it comes back unchanged, it is let be. Refused
// until nothing else was left, such collapses cost accuracy where they were the cheap way on: ogre at 1 %
// (crossing components) reached 2.99 % Hausdorff instead of 0.92 %, the counter at 1 % 2.44 % instead of
// 1.13 %. Waiting 4 times keeps allow's errors over the 46 bench runs (geometric means x1.000, x1.007)
// and leaves no such face on 34 of them (22 with allow); waiting 16 or 64 times, 35 or 36 of them at
// x1.035 or x1.044 Hausdorff (docs/benchmarks-log.md, session 30).
constexpr double kInvertedWait = 4.0;

// How many entries whose neighbourhood changed are re-scored at once (wide updates).
constexpr std::size_t kRescoreBatch = 16;

// 20 bytes: the queue holds millions of these and its speed is its cache footprint. Counters only
// grow, so a sum changes whenever either of its terms does.
struct HeapEntry {
  float cost;
  Index u, v;
  std::uint32_t version;  // version_[u] + version_[v] when scored: void once either endpoint changed
  std::uint32_t epoch;    // dirty_[u] + dirty_[v] when scored: re-score if it moved
};

// The face an entry of setup()'s face list is, given the faces of its entries (empty: the same).
inline Index input_face(const std::vector<Index>& face_id, Index entry) { return face_id.empty() ? entry : face_id[entry]; }

// Cheapest first; ties broken by index so runs are deterministic.
struct CheaperFirst {
  bool operator()(const HeapEntry& a, const HeapEntry& b) const {
    if (a.cost != b.cost) return a.cost < b.cost;
    if (a.u != b.u) return a.u < b.u;
    return a.v < b.v;
  }
};

/// A face a collapse would move, whose kept certificate against the input did not settle it: where it
/// would go (Engine::geometry()).
struct UnsettledFace {
  Index face;
  Eigen::Vector3d centroid, normal;
};

// One priority queue and the scratch of the loop that drains it. A run has one lane; on large meshes,
// several first simplify the insides of slabs of the mesh side by side (Engine::run_lanes).
struct Lane {
  BatchQueue<HeapEntry, CheaperFirst> queue;
  // Entries a collapse made stale, roughly (the edges at its two ends). Nine in ten pops used to be
  // stale entries, each a full sift through a heap of millions; once they are a quarter of it, one
  // linear pass drops them all instead.
  std::size_t stale_estimate = 0;
  Index region = -1;  ///< the slab whose inner points it may collapse; -1: every point
  Index removed_faces = 0, collapses = 0, floor = 0;
  double max_error = 0;
  bool done = false;
  // Scratch, reused across calls.
  Probe probe;
  std::vector<Index> ring, ring_u, ring_v, ring_tmp;
  std::vector<HeapEntry> rated;              ///< see Engine::rate_edges()
  std::vector<Candidate> rated_candidates;  ///< with rated, when scores are remembered
  std::vector<std::pair<Index, Index>> ring_edges, rescore;
  std::vector<UnsettledFace> unsettled;  ///< see Engine::geometry()
  /// InvertedFaces::Avoid: entries (u, v, version) queued again to wait (see kInvertedWait); when one
  /// comes back unchanged, it is let be.
  std::set<std::tuple<Index, Index, std::uint32_t>> waited;
  double paid = 0;            ///< the highest cost this lane has collapsed (at least 0)
  bool let_inverted = false;  ///< a waited entry was collapsed
};

class Engine {
 public:
  Engine(const Mesh& mesh, const SimplifyOptions& options);

  SimplifyResult run(Index target);
  /// Whether two faces of the input run an edge they share the same way (its ends are then locked).
  bool faces_disagree() const { return faces_disagree_; }

 private:
  // engine_setup.cpp: from the input to the engine's state.
  void setup(const Mesh& mesh);
  void setup_attributes(const Mesh& mesh);
  /// face_id: the face of each entry the edges name (empty: the same).
  void add_crease_planes(const std::vector<Index>& face_id);
  void find_sharp_edges(const std::vector<Index>& face_id);
  /// Per face side, the face across it if that one has the higher index, else -1: each interior edge
  /// of two faces once, from its lower face (classify_edges found both faces already; a search per
  /// edge was a fifth of the setup). With `consistent_only`, only faces that agree on orientation.
  std::vector<Index> faces_across(const std::vector<Index>& face_id, bool consistent_only) const;
  /// Wedge w's attributes as the output has them (optimised values unscaled, normals unit length,
  /// colours clamped to float), in the layout of attribute_values_per_vertex().
  void output_attributes(Index w, double* out) const;

  // engine_checks.cpp: whether a collapse is legal. Checks are split by cost: the cheap ones (flags,
  // shared faces, seam wedges) decide where the surviving vertex may go and run whenever a candidate is
  // scored; the link condition and the geometric checks run once, when a candidate reaches the top of
  // the queue.
  /// The faces on edge uv, into probe.shared (in u's face order, which the wedge map follows).
  void find_shared_faces(Index u, Index v, Probe& probe) const;
  /// Expects probe.shared filled for this edge by find_shared_faces(). The link condition is checked
  /// when `link` is given (its scratch rings are used); without it, safe to call from several threads.
  Rejection structure(Index u, Index v, Freedom& freedom, Lane* link, Probe& probe);
  Rejection map_wedges(Index u, Index v, Probe& probe) const;
  Index wedge_at(Index f, Index p) const;
  /// With `inverted_ok`, faces facing against the input are let be (a waited entry; see kInvertedWait).
  Rejection geometry(Lane& lane, Index u, Index v, const Eigen::Vector3d& p, bool inverted_ok = false);
  /// The limits on face f moving from corners `was` to `now`, for a collapse (geometry()) and for the
  /// fit after the collapses (engine_fit.cpp): not degenerate; turned no further than one step may,
  /// nor than its limit from its input shape (small turns must not add up to a flip); not thinned
  /// below the quality floor where it was better. `n1`: now's normal (not unit). Inline: geometry()
  /// runs it on every face of every candidate.
  Rejection face_move(Index f, const Eigen::Vector3d* was, const Eigen::Vector3d* now, Eigen::Vector3d& n1) const {
    const Eigen::Vector3d n0 = (was[1] - was[0]).cross(was[2] - was[0]);
    n1 = (now[1] - now[0]).cross(now[2] - now[0]);
    const double l0 = n0.norm(), l1 = n1.norm();
    if (!(l1 > 0)) return Rejection::Sliver;
    if (l0 > 0 && n1.dot(n0) < cos_max_turn_ * l0 * l1) return Rejection::Flip;
    if (n1.dot(s_.face_normal0[f].cast<double>()) < cos_max_total_turn_ * l1) return Rejection::Flip;
    const double q1 = triangle_quality(now[0], now[1], now[2], l1);
    if (q1 < o_.min_triangle_quality && q1 < triangle_quality(was[0], was[1], was[2], l0)) return Rejection::Sliver;
    return Rejection::None;
  }
  /// Whether face f, with centroid `centroid` (absolute, not relative to the origin) and normal n,
  /// faces against the input face nearest its centroid (as count_flipped_faces() sees it), where in the
  /// input it did not. The search starts at the input face found nearest f last time (at first f
  /// itself: face f is input face f). For faces whose kept certificate did not settle it (geometry()
  /// tests that first).
  /// (Double-sided input, two faces back to back, has faces that face against their twin from the
  /// start; holding them would hold their whole neighbourhood.)
  bool faces_against_input(Index f, const Eigen::Vector3d& centroid, const Eigen::Vector3d& n) const;
  /// The checks and the cost of u -> v, into lane.probe (the path that collapses). With `scored`, c
  /// already holds the cost of u -> v in the current state (recall()) and is not computed again.
  Rejection evaluate(Lane& lane, Index u, Index v, Candidate& c, bool full, bool scored = false);

  // engine_rating.cpp: candidates into queue entries, and the entries' tags.
  /// Costly costs only: keeps the candidate behind queue entry e (from the main thread), so that it
  /// need not be scored again when e reaches the top unchanged.
  void remember(const HeapEntry& e, const Candidate& c);
  /// The candidate remember() kept for e, if e's tags still match it.
  bool recall(const HeapEntry& e, Candidate& c) const;
  /// Drops every candidate remember() kept: at a change of queue (a lane pass, the quadric stage's end),
  /// where an entry's tags no longer tell whether its candidate still holds.
  void forget_candidates();
  /// The queue entry of edge ab, in its cheaper legal direction, if either is (thread-safe); that
  /// direction's candidate into `chosen` when given.
  std::optional<HeapEntry> rate_edge(Index a, Index b, Index region, std::array<Probe, 2>& probes,
                                     Candidate* chosen = nullptr);
  /// Rates the edges (side by side when they are many, or costly) and queues them in list order, so
  /// the queue is the same whatever the number of threads.
  void push_edges(Lane& lane, const std::vector<std::pair<Index, Index>>& edges);
  /// Rates the edges side by side into `out`, in list order, an illegal edge's entry marked by
  /// unrated() (and their candidates into `candidates` when given, as long as `edges`).
  void rate_edges(const std::vector<std::pair<Index, Index>>& edges, Index region, std::vector<HeapEntry>& out,
                  Candidate* candidates);
  static bool unrated(const HeapEntry& e) { return e.u < 0; }
  /// Both ends inside the slab (region -1: anywhere, and always once the lanes are done).
  bool inside(Index region, Index u, Index v) const {
    return region < 0 || (region_[u] == region && region_[v] == region);
  }
  HeapEntry entry(double cost, Index u, Index v) const {
    return {static_cast<float>(cost), u, v, version_[u] + version_[v], dirty_[u] + dirty_[v]};
  }
  /// An endpoint changed since e was scored: e is void.
  bool stale(const HeapEntry& e) const { return e.version != version_[e.u] + version_[e.v]; }
  /// An endpoint's neighbourhood changed since e was scored (wide updates): score it again.
  bool outdated(const HeapEntry& e) const { return e.epoch != dirty_[e.u] + dirty_[e.v]; }
  /// The queue entries of these edges, rated side by side, in list order.
  std::vector<HeapEntry> rate_all(const std::vector<std::pair<Index, Index>>& edges);
  /// Every edge of the mesh as it is now, each once.
  std::vector<std::pair<Index, Index>> remaining_edges();
  void neighbours(Index p, std::vector<Index>& out) const { s_.ring(p, out); }

  // engine_collapse.cpp: performing one.
  void collapse(Lane& lane, Index u, Index v, const Candidate& c);

  // engine_run.cpp: the queue's loop, the lanes, the stop.
  /// Pops and collapses until `done` says stop or the queue runs dry: the loop of every lane.
  template <typename Done>
  void drain(Lane& lane, Done done, std::optional<std::pair<Index, Index>>& deferred);
  /// The lanes' part of the run (see the comment there), from the first rating of every edge; returns
  /// false (and leaves `first` alone) when the mesh is too small for lanes.
  bool run_lanes(std::vector<HeapEntry>& first);
  /// One pass of lanes over `slabs` until `stop_at` faces are left; takes the entries queued so far and
  /// returns those left, the rims' edges rated.
  std::vector<HeapEntry> lane_pass(Slabs slabs, Index stop_at, std::vector<HeapEntry>& queued);
  /// The top entry e, refused under InvertedFaces::Avoid for faces facing against the input: the first
  /// time, queued again to wait (true); when it comes back unchanged, let be (false, and `verdict` says
  /// whether the other checks pass).
  bool wait_inverted(Lane& lane, const HeapEntry& e, const Candidate& c, Rejection& verdict);
  /// Collapse u -> v to p, refused only for faces facing against the input, let be after all: the
  /// other checks' verdict, and where the run did so when it did.
  Rejection let_inverted_be(Lane& lane, Index u, Index v, const Eigen::Vector3d& p);
  /// hoppe: the faces down to which the quadric error ranks the collapses (SimplifyOptions::hoppe_energy_from),
  /// or 0 where the cost's own scores rank them all.
  Index quadric_until(Index target) const;
  /// The edges rated and queued, for a stage down to `target` faces: into the lanes when the mesh is large.
  void queue_edges(const std::vector<std::pair<Index, Index>>& edges, Index target);
  /// Calls the progress callback, about once a percent, with `alive` faces left.
  void report_progress(Index alive);
  /// The cheapest legal collapse of a boundary edge (it removes one face), if any.
  std::optional<std::pair<Index, Index>> cheapest_boundary_collapse(Lane& lane);
  /// Why the remaining edges cannot collapse: the sentence, and the edges counted by reason.
  std::string stop_report(Index target, BlockedEdges& blocked);

  // Prefetching, for the queue's loop and the collapse.
  /// Point p's data asked for before it is needed: the loop is bound by cache misses on points
  /// scattered over a large mesh, and asking for several at once overlaps them. For rating an edge at
  /// p: its quadric, position and face list's header (not the list: rating does not read it, and
  /// asking for it stalled on a cache miss per ring point, 2-3 % of a quadric run on igea 1M).
  void prefetch_for_rating(Index p) const {
    __builtin_prefetch(&s_.quadric[p]);
    __builtin_prefetch(reinterpret_cast<const char*>(&s_.quadric[p]) + 64);
    __builtin_prefetch(&s_.position[p]);
    __builtin_prefetch(&s_.point_faces[p]);
  }
  /// That, and p's face list, for checking a collapse at p.
  void prefetch_point(Index p) const {
    prefetch_for_rating(p);
    __builtin_prefetch(s_.point_faces[p].data());
  }
  // The next two levels of what checking a collapse at p reads: its faces once p's face list is in
  // cache, then their corners' positions once the faces are.
  void prefetch_faces(Index p) const {
    for (Index f : s_.faces_of(p)) __builtin_prefetch(&s_.face_point[f]), __builtin_prefetch(&s_.face_normal0[f]);
  }
  void prefetch_corners(Index p) const {
    for (Index f : s_.faces_of(p))
      for (int k = 0; k < 3; ++k) __builtin_prefetch(&s_.position[s_.corner_point(f, k)]);
  }

  SimplifyOptions o_;
  EngineState s_;
  InvertedFaces inverted_mode_;
  bool check_inverted_;                   // faces facing against the input are checked (Avoid or Refuse)
  std::unique_ptr<AabbTree> input_tree_;  // the input, for the face nearest a new face (unless Allow)
  // Per face (unless Allow), the input face last found nearest, and a copy of its certificate: read
  // from the tree through the face, it was a miss to memory on almost every check.
  struct NearestInput {
    AabbTree::Certificate certificate;
    Index face;
  };
  mutable std::vector<NearestInput> nearest_input_;
  static constexpr std::int8_t kUnknown = -1;
  mutable std::vector<std::int8_t> against_in_input_;  // per face: 1 if its input self faced against the input
  /// Faces left when InvertedFaces::Avoid first let a face face against the input (wait_inverted()).
  std::optional<Index> inverted_allowed_at_;
  std::unique_ptr<CostModel> cost_;
  Lane main_;  // the whole run's, or the last part's after the lanes
  std::vector<std::uint32_t> version_;
  std::vector<std::uint32_t> dirty_;  // bumped when a point's neighbourhood energy changed (wide updates)
  // Costly costs only (hoppe): per point u, the last candidate scored for each of its edges u -> v.
  // Scoring the top entry again before collapsing it took a tenth of a hoppe run, on the one thread
  // that cannot share it; its tags say whether it still holds.
  struct Scored {
    Index v;
    std::uint32_t version, epoch;  // the entry's tags
    Candidate c;
  };
  std::vector<std::vector<Scored>> scored_;
  double cos_max_turn_ = 0, cos_max_total_turn_ = 0;
  double total_turn_deg_ = 0;
  /// Faces left when the default limit on a face's turn from its input shape was relaxed (relax_total_turn()).
  std::optional<Index> relaxed_at_;
  double starting_total_turn_deg() const { return detail::starting_total_turn_deg(o_); }
  void set_total_turn(double deg) {
    total_turn_deg_ = deg;
    cos_max_total_turn_ = std::cos(deg * std::numbers::pi / 180.0);
  }
  bool relax_total_turn();
  /// The cost's fit after the collapses (CostModel::fit), held to the collapses' limits (engine_fit.cpp).
  void fit_points(SimplifyResult& result);
  Index send_back_breaking_moves(const std::vector<Index>& faces, const std::vector<Eigen::Vector3d>& before);
  bool move_breaks_limits(Index f, const std::vector<Eigen::Vector3d>& before) const;
  Index max_valence_ = 0;  // faces at a vertex, at most (0 = no limit; see SimplifyOptions::max_valence)
  std::vector<EdgeUse> edges_;  // every edge of the input, from setup() until run() has queued them
  std::vector<Index> canonical_;  // per input vertex: the first vertex identical to it
  std::vector<Index> region_;  // per point: its slab while lanes run, -1 on a slab's rim; then empty
  tbb::enumerable_thread_specific<std::array<Probe, 2>> probes_;
  // Result bookkeeping.
  double max_error_ = 0;
  Index collapses_ = 0, locked_ = 0, dropped_ = 0;
  bool faces_disagree_ = false;
  Index target_ = 0;        // the face target of the run's current stage
  Index final_target_ = 0;  // the run's
  std::optional<Index> energy_from_;  // faces left when hoppe's energy took over from the quadric error
  Index faces_before_ = 0, next_report_ = 0;  // for the progress callback
  int lanes_used_ = 1;
  std::vector<CollapseRecord> records_;
  std::vector<double> attribute_scale_;     // per attribute dimension: weight x diagonal
  std::array<bool, 3> attribute_layout_{};  // normals, uvs, colours in the attribute vector
};

}  // namespace lodkit::detail
