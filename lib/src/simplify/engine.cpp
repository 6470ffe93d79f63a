#include <lodkit/error.h>
#include <lodkit/simplify.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <fmt/format.h>
#include <numbers>
#include <numeric>
#include <optional>
#include <set>
#include <tuple>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_group.h>

#include "core/geometry.h"
#include "core/topology.h"
#include "metrics/aabb_tree.h"
#include "simplify/engine.h"
#include "simplify/queue.h"
#include "simplify/slabs.h"

namespace lodkit {
namespace detail {

namespace {

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
// x1.035 or x1.044 Hausdorff (docs/benchmarks.md, session 30).
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
Index input_face(const std::vector<Index>& face_id, Index entry) { return face_id.empty() ? entry : face_id[entry]; }

// Cheapest first; ties broken by index so runs are deterministic.
struct CheaperFirst {
  bool operator()(const HeapEntry& a, const HeapEntry& b) const {
    if (a.cost != b.cost) return a.cost < b.cost;
    if (a.u != b.u) return a.u < b.u;
    return a.v < b.v;
  }
};

// One priority queue and the scratch of the loop that drains it. A run has one lane; on large meshes,
// several first simplify the insides of slabs of the mesh side by side (Engine::run_lanes).
/// A face a collapse would move, whose kept certificate against the input did not settle it: where it
/// would go (Engine::geometry()).
struct UnsettledFace {
  Index face;
  Eigen::Vector3d centroid, normal;
};

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
  Engine(const Mesh& mesh, const SimplifyOptions& options) : o_(options) {
    s_.input = &mesh;
    // The input's tree has no part in the setup: it is built alongside.
    tbb::task_group input_tree_task;
    inverted_mode_ = o_.inverted_faces.value_or(default_inverted_faces(o_.method));
    check_inverted_ = inverted_mode_ != InvertedFaces::Allow && o_.preserve_topology;
    if (check_inverted_)
      input_tree_task.run([&] {
        input_tree_ = std::make_unique<AabbTree>(mesh);
        input_tree_->prepare_facing();
        nearest_input_.resize(static_cast<std::size_t>(mesh.num_faces()));
        tbb::parallel_for(Index{0}, mesh.num_faces(), [&](Index f) { nearest_input_[f] = {input_tree_->certificate(f), f}; });
        against_in_input_.assign(static_cast<std::size_t>(mesh.num_faces()), kUnknown);
      });
    setup(mesh);
    setup_attributes(mesh);
    switch (o_.method) {
      case SimplifyMethod::Quadric: cost_ = make_quadric_cost(o_); break;
      case SimplifyMethod::EdgeLength: cost_ = make_edge_length_cost(o_); break;
      case SimplifyMethod::Hoppe: cost_ = make_hoppe_cost(o_, s_); break;
    }
    cos_max_turn_ = std::cos(o_.max_normal_change_deg * std::numbers::pi / 180.0);
    set_total_turn(starting_total_turn_deg());
    max_valence_ = o_.max_valence.value_or(default_max_valence(o_.method));
    if (cost_->costly()) scored_.resize(s_.position.size());
    input_tree_task.wait();
  }

  SimplifyResult run(Index target);

 private:
  void setup(const Mesh& mesh);
  void setup_attributes(const Mesh& mesh);
  /// face_id: the face of each entry the edges name (empty: the same).
  void add_crease_planes(const std::vector<Index>& face_id);
  void find_sharp_edges(const std::vector<Index>& face_id);
  /// Per face side, the face across it if that one has the higher index, else -1: each interior edge
  /// of two faces once, from its lower face (classify_edges found both faces already; a search per
  /// edge was a fifth of the setup). With `consistent_only`, only faces that agree on orientation.
  std::vector<Index> faces_across(const std::vector<Index>& face_id, bool consistent_only) const;
  // Checks are split by cost: the cheap ones (flags, shared faces, seam wedges) decide where the
  // surviving vertex may go and run whenever a candidate is scored; the link condition and the
  // geometric checks run once, when a candidate reaches the top of the queue.
  /// The faces on edge uv, into probe.shared (in u's face order, which the wedge map follows).
  void find_shared_faces(Index u, Index v, Probe& probe) const;
  /// Expects probe.shared filled for this edge by find_shared_faces(). The link condition is checked
  /// when `link` is given (its scratch rings are used); without it, safe to call from several threads.
  Rejection structure(Index u, Index v, Freedom& freedom, Lane* link, Probe& probe);
  Rejection map_wedges(Index u, Index v, Probe& probe) const;
  Index wedge_at(Index f, Index p) const;
  /// With `inverted_ok`, faces facing against the input are let be (a waited entry; see kInvertedWait).
  Rejection geometry(Lane& lane, Index u, Index v, const Eigen::Vector3d& p, bool inverted_ok = false);
  /// The top entry e, refused under InvertedFaces::Avoid for faces facing against the input: the first
  /// time, queued again to wait (true); when it comes back unchanged, let be (false, and `verdict` says
  /// whether the other checks pass).
  bool wait_inverted(Lane& lane, const HeapEntry& e, const Candidate& c, Rejection& verdict);
  /// Collapse u -> v to p, refused only for faces facing against the input, let be after all: the
  /// other checks' verdict, and where the run did so when it did.
  Rejection let_inverted_be(Lane& lane, Index u, Index v, const Eigen::Vector3d& p);
  /// Whether face f, with centroid `centroid` (absolute, not relative to the origin) and normal n,
  /// faces against the input face nearest its centroid (as count_flipped_faces() sees it), where in the
  /// input it did not. The search starts at the input face found nearest f last time (at first f
  /// itself: face f is input face f). For faces whose kept certificate did not settle it (geometry()
  /// tests that first).
  /// (Double-sided input, two faces back to back, has faces that face against their twin from the
  /// start; holding them would hold their whole neighbourhood.)
  bool faces_against_input(Index f, const Eigen::Vector3d& centroid, const Eigen::Vector3d& n) const {
    // Lanes query side by side, but each on faces of its own region (a face with a corner inside a slab
    // lies in that slab), so no entry is written by two at once.
    NearestInput& last = nearest_input_[f];
    Index hint = last.face;
    const bool now = input_tree_->facing_against(centroid, n, hint);
    if (hint != last.face) last = {input_tree_->certificate(hint), hint};
    if (!now) return false;
    // Whether input face f already faced against its nearest input face: found once per face.
    std::atomic_ref<std::int8_t> known(against_in_input_[f]);
    if (const std::int8_t k = known.load(std::memory_order_relaxed); k != kUnknown) return k == 0;
    const Mesh& in = *s_.input;
    const Eigen::Vector3d input_centroid =
        (in.positions.row(in.triangles(f, 0)) + in.positions.row(in.triangles(f, 1)) + in.positions.row(in.triangles(f, 2)))
            .transpose() / 3.0;
    Index self = f;
    const bool already = input_tree_->facing_against(input_centroid, s_.face_normal0[f].cast<double>(), self);
    known.store(already ? 1 : 0, std::memory_order_relaxed);
    return !already;
  }
  /// The checks and the cost of u -> v, into lane.probe (the path that collapses). With `scored`, c
  /// already holds the cost of u -> v in the current state (recall()) and is not computed again.
  Rejection evaluate(Lane& lane, Index u, Index v, Candidate& c, bool full, bool scored = false);
  /// Costly costs only: keeps the candidate behind queue entry e (from the main thread), so that it
  /// need not be scored again when e reaches the top unchanged.
  void remember(const HeapEntry& e, const Candidate& c);
  /// The candidate remember() kept for e, if e's tags still match it.
  bool recall(const HeapEntry& e, Candidate& c) const;
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
  void collapse(Lane& lane, Index u, Index v, const Candidate& c);
  /// Pops and collapses until `done` says stop or the queue runs dry: the loop of every lane.
  template <typename Done>
  void drain(Lane& lane, Done done, std::optional<std::pair<Index, Index>>& deferred);
  /// The lanes' part of the run (see the comment there), from the first rating of every edge; returns
  /// false (and leaves `first` alone) when the mesh is too small for lanes.
  bool run_lanes(std::vector<HeapEntry>& first);
  /// One pass of lanes over `slabs` until `stop_at` faces are left; takes the entries queued so far and
  /// returns those left, the rims' edges rated.
  std::vector<HeapEntry> lane_pass(Slabs slabs, Index stop_at, std::vector<HeapEntry>& queued);
  /// Every edge of the mesh as it is now, each once.
  std::vector<std::pair<Index, Index>> remaining_edges();
  /// The queue entries of these edges, rated side by side, in list order.
  std::vector<HeapEntry> rate_all(const std::vector<std::pair<Index, Index>>& edges);
  /// Calls the progress callback, about once a percent, with `alive` faces left.
  void report_progress(Index alive);
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
  void neighbours(Index p, std::vector<Index>& out);
  /// Wedge w's attributes as the output has them (optimised values unscaled, normals unit length,
  /// colours clamped to float), in the layout of attribute_values_per_vertex().
  void output_attributes(Index w, double* out) const;
  /// The cheapest legal collapse of a boundary edge (it removes one face), if any.
  std::optional<std::pair<Index, Index>> cheapest_boundary_collapse(Lane& lane);
  /// Why the remaining edges cannot collapse: the sentence, and the edges counted by reason.
  std::string stop_report(Index target, BlockedEdges& blocked);

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
  double starting_total_turn_deg() const {
    return std::max(o_.max_total_normal_change_deg.value_or(default_max_total_normal_change(o_.method)),
                    o_.max_normal_change_deg);
  }
  void set_total_turn(double deg) {
    total_turn_deg_ = deg;
    cos_max_total_turn_ = std::cos(deg * std::numbers::pi / 180.0);
  }
  bool relax_total_turn();
  Index max_valence_ = 0;  // faces at a vertex, at most (0 = no limit; see SimplifyOptions::max_valence)
  std::vector<EdgeUse> edges_;  // every edge of the input, from setup() until run() has queued them
  std::vector<Index> canonical_;  // per input vertex: the first vertex identical to it
  std::vector<Index> region_;  // per point: its slab while lanes run, -1 on a slab's rim; then empty
  tbb::enumerable_thread_specific<std::array<Probe, 2>> probes_;
  // Result bookkeeping.
  double max_error_ = 0;
  Index collapses_ = 0, locked_ = 0, dropped_ = 0;
  Index target_ = 0;  // the run's face target
  Index faces_before_ = 0, next_report_ = 0;  // for the progress callback
  int lanes_used_ = 1;
  std::vector<CollapseRecord> records_;
  std::vector<double> attribute_scale_;     // per attribute dimension: weight x diagonal
  std::array<bool, 3> attribute_layout_{};  // normals, uvs, colours in the attribute vector
};

void Engine::setup(const Mesh& mesh) {
  const Index nv = mesh.num_vertices();
  s_.origin = local_origin(bounding_box(mesh));
  // Points: one per distinct position.
  const Eigen::VectorX<Index> cls = position_classes(mesh);
  s_.point_of.assign(static_cast<std::size_t>(nv), -1);
  std::vector<Index> point_of_class(static_cast<std::size_t>(nv), -1);
  Index points = 0;
  for (Index v = 0; v < nv; ++v) {
    Index& p = point_of_class[cls[v]];
    if (p < 0) {
      p = points++;
      s_.position.push_back(mesh.positions.row(v).transpose() - s_.origin);
    }
    s_.point_of[v] = p;
  }
  s_.quadric.assign(static_cast<std::size_t>(points), {});
  s_.flags.assign(static_cast<std::size_t>(points), 0);
  s_.point_faces.assign(static_cast<std::size_t>(points), {});
  version_.assign(static_cast<std::size_t>(points), 0);
  dirty_.assign(static_cast<std::size_t>(points), 0);

  // Faces on canonical wedges (identical vertices merged, so an unwelded soup is not all seams); a
  // face whose corners are not three distinct points cannot take part and is dropped.
  canonical_ = identical_vertex_classes(mesh);
  const std::vector<Index>& canonical = canonical_;
  const auto faces = static_cast<std::size_t>(mesh.num_faces());
  s_.face.reserve(faces), s_.face_point.reserve(faces), s_.face_normal0.reserve(faces), s_.face_dead.reserve(faces);
  {
    // Each point's face list sized once (growing half a million lists one face at a time showed in
    // the profile); a collapse appends at most a few more.
    std::vector<std::uint32_t> degree(static_cast<std::size_t>(points), 0);
    for (Index f = 0; f < mesh.num_faces(); ++f)
      for (int k = 0; k < 3; ++k) ++degree[s_.point_of[canonical[mesh.triangles(f, k)]]];
    for (Index p = 0; p < points; ++p) s_.point_faces[p].reserve(degree[p]);
  }
  for (Index f = 0; f < mesh.num_faces(); ++f) {
    const std::array<Index, 3> w{canonical[mesh.triangles(f, 0)], canonical[mesh.triangles(f, 1)],
                                 canonical[mesh.triangles(f, 2)]};
    const std::array<Index, 3> p{s_.point_of[w[0]], s_.point_of[w[1]], s_.point_of[w[2]]};
    s_.face.push_back(w);
    s_.face_point.push_back(p);
    const Eigen::Vector3d n0 = (mesh.positions.row(w[1]) - mesh.positions.row(w[0]))
                                   .cross(mesh.positions.row(w[2]) - mesh.positions.row(w[0]))
                                   .transpose();
    s_.face_normal0.push_back(n0.norm() > 0 ? Eigen::Vector3f(n0.normalized().cast<float>()) : Eigen::Vector3f::Zero());
    if (p[0] == p[1] || p[1] == p[2] || p[0] == p[2]) {
      s_.face_dead.push_back(1);
      ++dropped_;
      continue;
    }
    s_.face_dead.push_back(0);
    for (Index q : p) s_.point_faces[q].push_back(f);
  }
  s_.alive_faces = mesh.num_faces() - dropped_;
  // The faces that take part, for the edge and fan classification: face_point itself unless some were
  // dropped (a copy of it cost 17 MiB on a 1M-face mesh), with the face of each entry.
  std::vector<std::array<Index, 3>> live_copy;
  std::vector<Index> face_id;  // empty: every face takes part
  if (dropped_ > 0) {
    live_copy.reserve(static_cast<std::size_t>(s_.alive_faces));
    face_id.reserve(static_cast<std::size_t>(s_.alive_faces));
    for (Index f = 0; f < mesh.num_faces(); ++f)
      if (!s_.face_dead[f]) live_copy.push_back(s_.face_point[f]), face_id.push_back(f);
  }
  const std::vector<std::array<Index, 3>>& point_faces = dropped_ > 0 ? live_copy : s_.face_point;

  // Boundaries and non-manifold parts.
  edges_ = classify_edges(point_faces);
  std::vector<char> border_side(3 * faces, 0);  // per face side: on the boundary
  for (const EdgeUse& e : edges_) {
    if (e.faces == 1) {
      s_.flags[e.lo] |= kBorder, s_.flags[e.hi] |= kBorder;
      const Index f = input_face(face_id, e.face[0]);
      const int k = s_.side(f, e.lo, e.hi);
      border_side[3 * std::size_t(f) + k] = 1;
      s_.input_boundary.push_back({s_.corner_point(f, k), s_.corner_point(f, (k + 1) % 3)});
    }
    if (e.faces > 2 || !e.consistent) s_.flags[e.lo] |= kLocked, s_.flags[e.hi] |= kLocked;
  }
  std::sort(s_.input_boundary.begin(), s_.input_boundary.end());
  const std::vector<char> fans = non_manifold_fans(points, point_faces);
  for (Index p = 0; p < points; ++p) {
    if (fans[p]) s_.flags[p] |= kLocked;
    if (o_.lock_boundary && (s_.flags[p] & kBorder)) s_.flags[p] |= kLocked;
    locked_ += (s_.flags[p] & kLocked) != 0;
  }
  // Seams: a point whose faces use more than one wedge.
  for (Index p = 0; p < points; ++p) {
    Index first = -1;
    for (Index f : s_.point_faces[p])
      for (int k = 0; k < 3; ++k)
        if (s_.corner_point(f, k) == p) {
          if (first < 0) first = s_.face[f][k];
          else if (s_.face[f][k] != first) s_.flags[p] |= kSeam;
        }
  }

  // Quadrics: area-weighted face planes, and boundary constraint planes through each border edge,
  // perpendicular to its face, weighted by the squared edge length; then the crease planes.
  for (Index f = 0; f < mesh.num_faces(); ++f) {
    if (s_.face_dead[f]) continue;
    const Index a = s_.corner_point(f, 0), b = s_.corner_point(f, 1), c = s_.corner_point(f, 2);
    const Eigen::Vector3d n2 = (s_.position[b] - s_.position[a]).cross(s_.position[c] - s_.position[a]);
    const double len = n2.norm();
    if (!(len > 0)) continue;
    const Eigen::Vector3d n = n2 / len;
    const Quadric q = Quadric::plane(n, -n.dot(s_.position[a]), 0.5 * len);
    s_.quadric[a] += q, s_.quadric[b] += q, s_.quadric[c] += q;
    for (int k = 0; k < 3; ++k) {
      if (!border_side[3 * std::size_t(f) + k]) continue;
      const Index p0 = s_.corner_point(f, k), p1 = s_.corner_point(f, (k + 1) % 3);
      const Eigen::Vector3d edge = s_.position[p1] - s_.position[p0];
      const Eigen::Vector3d m = edge.cross(n).normalized();
      if (!m.allFinite()) continue;
      const Quadric bq = Quadric::plane(m, -m.dot(s_.position[p0]), o_.boundary_weight * edge.squaredNorm());
      s_.quadric[p0] += bq, s_.quadric[p1] += bq;
    }
  }
  add_crease_planes(face_id);
  find_sharp_edges(face_id);
}

std::vector<Index> Engine::faces_across(const std::vector<Index>& face_id, bool consistent_only) const {
  std::vector<Index> across(3 * s_.face.size(), -1);
  for (const EdgeUse& e : edges_) {
    if (e.faces != 2 || (consistent_only && !e.consistent)) continue;
    const Index f0 = input_face(face_id, e.face[0]), f1 = input_face(face_id, e.face[1]);
    const Index f = std::min(f0, f1);
    across[3 * std::size_t(f) + s_.side(f, e.lo, e.hi)] = std::max(f0, f1);
  }
  return across;
}

// Crease planes: the boundary constraint generalised to folded edges. Face planes alone leave a
// thin fin's rim, or a spike's tip, free to slide inwards at almost no cost (the planes of both
// sides contain that direction), which is where plain quadrics lose Hausdorff distance. Each interior
// edge adds the plane through it whose normal bisects its faces' normals, weighted by
// crease_weight * |edge|^2 * (1 - n1.n2) / 2: nothing on flat ground, the full weight on a fin whose
// sides fold back onto each other (n2 = -n1, where the plane is a boundary plane).
void Engine::add_crease_planes(const std::vector<Index>& face_id) {
  // Quadric only: hoppe starts from the quadric's position but measures its own energy, and it kept
  // less Hausdorff with them (horse 10 %: 0.28 % against 0.14 %).
  if (o_.method != SimplifyMethod::Quadric || !(o_.crease_weight > 0)) return;
  // Each interior edge of two consistently oriented faces, from the face of lower index, in face order.
  const Index faces = static_cast<Index>(s_.face.size());
  const std::vector<Index> across = faces_across(face_id, true);
  for (Index f = 0; f < faces; ++f) {
    for (int k = 0; k < 3; ++k) {
      const Index other = across[3 * std::size_t(f) + k];
      if (other < 0) continue;
      const Index p0 = s_.corner_point(f, k), p1 = s_.corner_point(f, (k + 1) % 3);
      const Eigen::Vector3d n1 = s_.face_normal0[f].cast<double>(), n2 = s_.face_normal0[other].cast<double>();
      const double fold = 0.5 * (1.0 - n1.dot(n2));
      const Eigen::Vector3d m = (n1 + n2).normalized();
      if (!(fold > 1e-6) || !m.allFinite()) continue;
      const Eigen::Vector3d& a = s_.position[p0];
      const double weight = o_.crease_weight * fold * (s_.position[p1] - a).squaredNorm();
      const Quadric q = Quadric::plane(m, -m.dot(a), weight);
      s_.quadric[p0] += q, s_.quadric[p1] += q;
    }
  }
}

// Hoppe samples points along these (HoppeCost::sample_creases()): E_dist sees an edge only through the
// points near it.
void Engine::find_sharp_edges(const std::vector<Index>& face_id) {
  if (o_.method != SimplifyMethod::Hoppe || o_.hoppe_crease_angle_deg >= 180) return;
  const float cos_sharp = static_cast<float>(std::cos(o_.hoppe_crease_angle_deg * std::numbers::pi / 180.0));
  const std::vector<Index> across = faces_across(face_id, false);
  for (std::size_t i = 0; i < across.size(); ++i) {
    if (across[i] < 0) continue;
    const Eigen::Vector3f &n0 = s_.face_normal0[i / 3], &n1 = s_.face_normal0[across[i]];
    if (n0.squaredNorm() < 0.5f || n1.squaredNorm() < 0.5f || n0.dot(n1) >= cos_sharp) continue;  // degenerate or smooth
    s_.sharp_edges.push_back({static_cast<Index>(i / 3), static_cast<int>(i % 3)});
  }
}

void Engine::setup_attributes(const Mesh& mesh) {
  const AttributeWeights& w = o_.attribute_weights;
  const Attributes& a = mesh.attributes;
  const bool normals = w.normals > 0 && mesh.has_normals(), uvs = w.uvs > 0 && mesh.has_uvs(),
             colours = w.colours > 0 && mesh.has_colours();
  const int k = 3 * normals + 2 * uvs + 4 * colours;
  if (k == 0) return;
  const Eigen::AlignedBox3d box = bounding_box(mesh);
  const double diagonal = box.isEmpty() ? 1.0 : std::max(box.diagonal().norm(), 1e-300);
  attribute_scale_.clear();
  for (int i = 0; i < 3 * normals; ++i) attribute_scale_.push_back(w.normals * diagonal);
  for (int i = 0; i < 2 * uvs; ++i) attribute_scale_.push_back(w.uvs * diagonal);
  for (int i = 0; i < 4 * colours; ++i) attribute_scale_.push_back(w.colours * diagonal);
  attribute_layout_ = {normals, uvs, colours};
  const Index nv = mesh.num_vertices();
  s_.wedge_value.assign(static_cast<std::size_t>(k) * nv, 0.0);
  for (Index v = 0; v < nv; ++v) {
    double* out = &s_.wedge_value[static_cast<std::size_t>(k) * v];
    int j = 0;
    if (normals) for (int i = 0; i < 3; ++i, ++j) out[j] = a.normals(v, i) * attribute_scale_[j];
    if (uvs) for (int i = 0; i < 2; ++i, ++j) out[j] = a.uvs(v, i) * attribute_scale_[j];
    if (colours) for (int i = 0; i < 4; ++i, ++j) out[j] = a.colours(v, i) * attribute_scale_[j];
  }
  s_.attribute_quadrics.reset(k, static_cast<std::size_t>(nv));
  for (Index f = 0; f < mesh.num_faces(); ++f) {
    if (s_.face_dead[f]) continue;
    Eigen::Vector3d p[3];
    const double* values[3];
    for (int c = 0; c < 3; ++c) {
      p[c] = s_.position[s_.corner_point(f, c)];
      values[c] = &s_.wedge_value[static_cast<std::size_t>(k) * s_.face[f][c]];
    }
    const double area = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).norm();
    for (int c = 0; c < 3; ++c) s_.attribute_quadrics.add_face(static_cast<std::size_t>(s_.face[f][c]), p, values, area);
  }
}

void Engine::output_attributes(Index w, double* out) const {
  const Attributes& a = s_.input->attributes;
  const std::size_t k = static_cast<std::size_t>(s_.attribute_quadrics.dims());
  const double* value = k ? &s_.wedge_value[k * static_cast<std::size_t>(w)] : nullptr;
  int i = 0, j = 0;  // i: output layout, j: optimised values
  if (s_.input->has_normals()) {
    if (attribute_layout_[0]) {
      Eigen::Vector3d n;
      for (int d = 0; d < 3; ++d, ++j) n[d] = value[j] / attribute_scale_[j];
      if (n.norm() > 0) n.normalize();
      else n = a.normals.row(w).transpose();
      for (int d = 0; d < 3; ++d) out[i++] = n[d];
    } else {
      for (int d = 0; d < 3; ++d) out[i++] = a.normals(w, d);
    }
  }
  if (s_.input->has_uvs())
    for (int d = 0; d < 2; ++d, j += attribute_layout_[1])
      out[i++] = attribute_layout_[1] ? value[j] / attribute_scale_[j] : a.uvs(w, d);
  if (s_.input->has_colours())
    for (int d = 0; d < 4; ++d, j += attribute_layout_[2])
      out[i++] = attribute_layout_[2] ? double(static_cast<float>(std::clamp(value[j] / attribute_scale_[j], 0.0, 1.0)))
                                      : double(a.colours(w, d));
}

void Engine::neighbours(Index p, std::vector<Index>& out) { s_.ring(p, out); }

Index Engine::wedge_at(Index f, Index p) const {
  for (int k = 0; k < 3; ++k)
    if (s_.corner_point(f, k) == p) return s_.face[f][k];
  return -1;
}

// Wedges: each wedge of u maps to v's wedge in the same vanishing face (probe.shared). Every wedge u still
// uses must be mapped, and two wedges may not merge: seams neither tear nor fuse.
Rejection Engine::map_wedges(Index u, Index v, Probe& probe) const {
  probe.wedge_map_size = 0;
  if (!s_.has(u, kSeam) && !s_.has(v, kSeam)) {
    // One wedge each, so u's goes to v's. (A point that is no seam never becomes one: a seam point
    // can merge only into a point with as many wedges.)
    probe.wedge_map[probe.wedge_map_size++] = {wedge_at(probe.shared[0], u), wedge_at(probe.shared[0], v)};
    return Rejection::None;
  }
  for (Index f : probe.shared) {
    const Index wu = wedge_at(f, u), wv = wedge_at(f, v);
    bool known = false;
    for (int i = 0; i < probe.wedge_map_size; ++i) {
      if (probe.wedge_map[i].first == wu) {
        if (probe.wedge_map[i].second != wv) return Rejection::Seam;
        known = true;
      } else if (probe.wedge_map[i].second == wv) {
        return Rejection::Seam;
      }
    }
    if (!known) probe.wedge_map[probe.wedge_map_size++] = {wu, wv};
  }
  for (Index f : s_.faces_of(u)) {
    const Index wu = wedge_at(f, u);
    bool mapped = false;
    for (int i = 0; i < probe.wedge_map_size; ++i) mapped |= probe.wedge_map[i].first == wu;
    if (!mapped) return Rejection::Seam;
  }
  return Rejection::None;
}

void Engine::find_shared_faces(Index u, Index v, Probe& probe) const {
  probe.shared.clear();
  for (Index f : s_.faces_of(u))
    for (int k = 0; k < 3; ++k)
      if (s_.corner_point(f, k) == v) probe.shared.push_back(f);
}

Rejection Engine::structure(Index u, Index v, Freedom& freedom, Lane* link, Probe& probe) {
  if (s_.has(u, kRemoved) || s_.has(v, kRemoved)) return Rejection::Topology;
  if (s_.has(u, kLocked)) return Rejection::Locked;
  const std::vector<Index>& fu = s_.faces_of(u);
  if (probe.shared.empty() || probe.shared.size() > 2) return Rejection::Topology;
  const bool border_edge = probe.shared.size() == 1;
  if (s_.has(u, kBorder) && !border_edge) return Rejection::Boundary;  // u would leave its boundary

  if (const Rejection r = map_wedges(u, v, probe); r != Rejection::None) return r;
  if (max_valence_ > 0) {
    // The merged vertex has the faces of both but the vanishing ones; a collapse that leaves no vertex
    // with more faces than before is always allowed.
    const std::size_t nu = fu.size(), nv = s_.faces_of(v).size(), merged = nu + nv - 2 * probe.shared.size();
    if (merged > std::size_t(max_valence_) && merged > std::max(nu, nv)) return Rejection::Valence;
  }

  if (o_.preserve_topology && link) {
    // Link condition: the only common neighbours of u and v are the apexes of the vanishing faces.
    std::vector<Index>&ring_u = link->ring_u, &ring_v = link->ring_v, &common = link->ring_tmp;
    neighbours(u, ring_u);
    neighbours(v, ring_v);
    common.clear();
    std::set_intersection(ring_u.begin(), ring_u.end(), ring_v.begin(), ring_v.end(), std::back_inserter(common));
    if (common.size() != probe.shared.size()) return Rejection::Topology;
    // v keeps enough neighbours (a tetrahedron cannot lose a vertex).
    const std::size_t degree = ring_u.size() + ring_v.size() - common.size() - 2;
    if (degree < (s_.has(v, kBorder) ? 2u : 3u)) return Rejection::Topology;
    if (border_edge) {
      // A boundary loop of three edges (u v w) would collapse to nothing.
      Index w = -1;
      for (int k = 0; k < 3; ++k)
        if (s_.corner_point(probe.shared[0], k) != u && s_.corner_point(probe.shared[0], k) != v) w = s_.corner_point(probe.shared[0], k);
      int uw = 0, vw = 0;
      for (Index f : fu)
        for (int k = 0; k < 3; ++k) uw += s_.corner_point(f, k) == w;
      for (Index f : s_.faces_of(v))
        for (int k = 0; k < 3; ++k) vw += s_.corner_point(f, k) == w;
      if (uw == 1 && vw == 1) return Rejection::Topology;
    }
  }

  const bool u_constrained = s_.has(u, kBorder) || s_.has(u, kSeam);
  const bool v_constrained = s_.has(v, kBorder) || s_.has(v, kSeam) || s_.has(v, kLocked);
  if (u_constrained && !v_constrained) return s_.has(u, kBorder) ? Rejection::Boundary : Rejection::Seam;
  const bool fixed = s_.has(v, kLocked) || (s_.has(v, kBorder) && !s_.has(u, kBorder)) ||
                     (s_.has(v, kSeam) && !s_.has(u, kSeam));
  freedom = fixed ? Freedom::AtKept : Freedom::Free;
  return Rejection::None;
}

Rejection Engine::geometry(Lane& lane, Index u, Index v, const Eigen::Vector3d& p, bool inverted_ok) {
  if (!o_.preserve_topology) return Rejection::None;
  constexpr double kQualityScale = 6.928203230275509;  // 4 sqrt(3): equilateral = 1
  const bool against_input = check_inverted_ && !inverted_ok;
  // The local checks on every changed face first, with each face's certificate against the input; the
  // nearest-input-face searches, where a certificate does not settle it, only once every local check
  // passed, so that a candidate they reject never pays for one.
  std::vector<UnsettledFace>& unsettled = lane.unsettled;
  unsettled.clear();
  auto check = [&](Index moved, Index other) {
    for (Index f : s_.faces_of(moved)) {
      Eigen::Vector3d before[3], after[3];
      bool has_other = false;
      for (int k = 0; k < 3; ++k) {
        const Index q = s_.corner_point(f, k);
        has_other |= q == other;
        before[k] = after[k] = s_.position[q];
        if (q == moved) after[k] = p;
      }
      if (has_other) continue;  // vanishes
      const Eigen::Vector3d n0 = (before[1] - before[0]).cross(before[2] - before[0]);
      const Eigen::Vector3d n1 = (after[1] - after[0]).cross(after[2] - after[0]);
      const double l0 = n0.norm(), l1 = n1.norm();
      if (!(l1 > 0)) return Rejection::Sliver;
      // Against the face's last shape, and against its input shape (by a limit of its own): small turns
      // must not add up to a flip over many collapses.
      if (l0 > 0 && n1.dot(n0) < cos_max_turn_ * l0 * l1) return Rejection::Flip;
      if (n1.dot(s_.face_normal0[f].cast<double>()) < cos_max_total_turn_ * l1) return Rejection::Flip;
      auto quality = [&](const Eigen::Vector3d* t, double twice_area) {
        const double sum = (t[1] - t[0]).squaredNorm() + (t[2] - t[1]).squaredNorm() + (t[0] - t[2]).squaredNorm();
        return sum > 0 ? kQualityScale * 0.5 * twice_area / sum : 0.0;
      };
      const double q1 = quality(after, l1);
      if (q1 < o_.min_triangle_quality && q1 < quality(before, l0)) return Rejection::Sliver;
      if (against_input) {
        const Eigen::Vector3d centroid = (after[0] + after[1] + after[2]) / 3.0 + s_.origin;
        if (!nearest_input_[f].certificate.settles(centroid, n1)) unsettled.push_back({f, centroid, n1});
      }
    }
    return Rejection::None;
  };
  if (const Rejection r = check(u, v); r != Rejection::None) return r;
  if (p != s_.position[v])
    if (const Rejection r = check(v, u); r != Rejection::None) return r;
  for (const UnsettledFace& u : unsettled)
    if (faces_against_input(u.face, u.centroid, u.normal)) return Rejection::Inverted;
  return Rejection::None;
}

Rejection Engine::evaluate(Lane& lane, Index u, Index v, Candidate& c, bool full, bool scored) {
  if (!inside(lane.region, u, v)) return Rejection::Locked;
  find_shared_faces(u, v, lane.probe);
  Freedom freedom;
  if (const Rejection r = structure(u, v, freedom, full ? &lane : nullptr, lane.probe); r != Rejection::None) return r;
  if (!scored && !cost_->score(s_, lane.probe, u, v, freedom, c)) return Rejection::Cost;
  if (o_.max_error && c.error > *o_.max_error) return Rejection::ErrorLimit;
  return full ? geometry(lane, u, v, c.position) : Rejection::None;
}

void Engine::remember(const HeapEntry& e, const Candidate& c) {
  if (scored_.empty()) return;
  // Drop what this edge had and every entry a collapse since voided or outdated (never recalled).
  auto& list = scored_[e.u];
  std::erase_if(list, [&](const Scored& s) {
    return s.v == e.v || s.version != version_[e.u] + version_[s.v] || s.epoch != dirty_[e.u] + dirty_[s.v];
  });
  list.push_back({e.v, e.version, e.epoch, c});
}

bool Engine::recall(const HeapEntry& e, Candidate& c) const {
  if (scored_.empty()) return false;
  for (const Scored& s : scored_[e.u])
    if (s.v == e.v && s.version == e.version && s.epoch == e.epoch) {
      c = s.c;
      return true;
    }
  return false;
}

std::optional<HeapEntry> Engine::rate_edge(Index a, Index b, Index region, std::array<Probe, 2>& probes,
                                           Candidate* chosen) {
  // Cheap checks per direction, then the cost. When neither end is constrained both directions merge
  // into the same vertex at the same place (unless placement is at an endpoint): score one.
  if (!inside(region, a, b)) return std::nullopt;
  Freedom fa, fb;
  auto& [pa, pb] = probes;
  find_shared_faces(a, b, pa);
  pb.shared = pa.shared;  // the same faces for both directions
  const bool ok_a = structure(a, b, fa, nullptr, pa) == Rejection::None;
  const bool ok_b = structure(b, a, fb, nullptr, pb) == Rejection::None;
  if (!ok_a && !ok_b) return std::nullopt;
  auto score = [&](Index u, Index v, Freedom f, const Probe& probe, Candidate& c) {
    return cost_->score(s_, probe, u, v, f, c) && !(o_.max_error && c.error > *o_.max_error);
  };
  Candidate ca, cb;
  const bool symmetric = ok_a && ok_b && fa == Freedom::Free && fb == Freedom::Free &&
                         o_.placement != Placement::Endpoint && !s_.has(a, kBorder) && !s_.has(b, kBorder) &&
                         !s_.has(a, kSeam) && !s_.has(b, kSeam);
  const bool scored_a = ok_a && score(a, b, fa, pa, ca);
  const bool scored_b = !symmetric && ok_b && score(b, a, fb, pb, cb);
  if (!scored_a && !scored_b) return std::nullopt;
  const bool use_a = scored_a && (!scored_b || ca.cost <= cb.cost);
  if (chosen) *chosen = use_a ? ca : cb;
  return entry(use_a ? ca.cost : cb.cost, use_a ? a : b, use_a ? b : a);
}

void Engine::push_edges(Lane& lane, const std::vector<std::pair<Index, Index>>& edges) {
  // Worth a task only where scoring is costly (hoppe: tens of microseconds per candidate) or the list
  // is long (every edge at the start).
  const std::size_t n = edges.size();
  const bool costly = cost_->costly();
  // Inside a lane, the lanes are what runs side by side: a task per edge there would only add waits.
  if (lane.region >= 0 || n < (costly ? 4u : 4096u)) {
    auto& probes = probes_.local();
    Candidate c;
    for (const auto& [a, b] : edges)
      if (const auto e = rate_edge(a, b, lane.region, probes, &c)) lane.queue.push(*e), remember(*e, c);
    return;
  }
  lane.rated_candidates.resize(scored_.empty() ? 0 : n);
  rate_edges(edges, lane.region, lane.rated, scored_.empty() ? nullptr : lane.rated_candidates.data());
  for (std::size_t i = 0; i < n; ++i)
    if (const HeapEntry& e = lane.rated[i]; !unrated(e)) {
      lane.queue.push(e);
      if (!scored_.empty()) remember(e, lane.rated_candidates[i]);
    }
}

void Engine::rate_edges(const std::vector<std::pair<Index, Index>>& edges, Index region, std::vector<HeapEntry>& out,
                        Candidate* candidates) {
  out.resize(edges.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, edges.size(), cost_->costly() ? 1 : 1024),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      auto& probes = probes_.local();
                      for (std::size_t i = r.begin(); i < r.end(); ++i) {
                        const auto e = rate_edge(edges[i].first, edges[i].second, region, probes,
                                                 candidates ? &candidates[i] : nullptr);
                        out[i] = e ? *e : HeapEntry{0, -1, -1, 0, 0};
                      }
                    });
}

void Engine::collapse(Lane& lane, Index u, Index v, const Candidate& c) {
  const Probe& probe = lane.probe;
  CollapseRecord* rec = nullptr;
  if (o_.record_collapses) {
    records_.push_back({u, v, s_.position[v] + s_.origin, c.position + s_.origin, c.error, {}, {}, {}, {}, {}});
    rec = &records_.back();
    for (int i = 0; i < probe.wedge_map_size; ++i) rec->wedge_map.push_back({probe.wedge_map[i].first, probe.wedge_map[i].second});
  }
  for (Index f : probe.shared) {
    s_.face_dead[f] = 1;
    if (rec) rec->removed_faces.push_back(f);
  }
  const Index gone = static_cast<Index>(probe.shared.size());
  if (lane.region < 0) s_.alive_faces -= gone;
  else lane.removed_faces += gone;  // lanes run side by side: their counts are summed between rounds
  // Keep every point's face list free of dead faces: only u, v and the apexes held them. (Matching
  // the one or two faces, not looking each face up in face_dead: those lookups missed the cache.)
  const Index gone0 = probe.shared[0], gone1 = probe.shared.size() > 1 ? probe.shared[1] : gone0;
  // A slab's rim point is shared with another lane: its list is left alone until the lanes are done.
  auto prune = [&](Index p) {
    if (!region_.empty() && region_[p] < 0) return;
    auto& list = s_.point_faces[p];
    list.erase(std::remove_if(list.begin(), list.end(), [&](Index f) { return f == gone0 || f == gone1; }), list.end());
  };
  for (Index f : probe.shared)
    for (int k = 0; k < 3; ++k) {
      const Index q = s_.corner_point(f, k);
      if (q != u) prune(q);
    }
  prune(u);
  for (Index f : s_.faces_of(u)) {
    for (int k = 0; k < 3; ++k) {
      if (s_.corner_point(f, k) != u) continue;
      const Index old = s_.face[f][k];
      for (int i = 0; i < probe.wedge_map_size; ++i)
        if (probe.wedge_map[i].first == old) s_.face[f][k] = probe.wedge_map[i].second;
      s_.face_point[f][k] = v;
      if (rec) rec->changed_corners.push_back({f, k, old});
    }
    s_.point_faces[v].push_back(f);
  }
  if (s_.attribute_quadrics.enabled()) {
    // The kept wedges take the attribute values that minimise the merged attribute error.
    const std::size_t k = static_cast<std::size_t>(s_.attribute_quadrics.dims());
    const std::size_t layout = static_cast<std::size_t>(attribute_values_per_vertex(*s_.input));
    for (int i = 0; i < probe.wedge_map_size; ++i) {
      const auto [wu, wv] = probe.wedge_map[i];
      s_.attribute_quadrics.best_at(std::size_t(wu), std::size_t(wv), c.position, &s_.wedge_value[k * wv]);
      s_.attribute_quadrics.merge(std::size_t(wv), std::size_t(wu));
      if (rec) {
        rec->attribute_vertices.push_back(wv);
        rec->attributes_after.resize(rec->attributes_after.size() + layout);
        output_attributes(wv, &rec->attributes_after[rec->attributes_after.size() - layout]);
      }
    }
  }
  lane.stale_estimate += s_.point_faces[u].size() + s_.point_faces[v].size();
  s_.point_faces[u].clear();
  if (!scored_.empty()) std::vector<Scored>().swap(scored_[u]);  // u is gone
  s_.position[v] = c.position;
  s_.quadric[v] += s_.quadric[u];
  s_.flags[u] |= kRemoved;
  ++version_[u];
  ++version_[v];
  lane.max_error = std::max(lane.max_error, c.error);
  ++lane.collapses;
  cost_->collapsed(s_, u, v, probe.shared);

  std::vector<Index>& ring = lane.ring;
  neighbours(v, ring);
  // Edges at v are re-scored now; with a wide update, edges at v's neighbours are marked and
  // re-scored when they reach the top of the queue. (Queueing v's edges at their last cost instead,
  // scored only when that reaches the top, made hoppe 35 % faster on the bunny but cost accuracy:
  // Hausdorff 0.249 -> 0.321 %, RMS 0.0210 -> 0.0216 % at 10 %, and a flipped face in the tests. A
  // collapse can lower its neighbours' costs, so their last cost is no lower bound.)
  // (Atomic: a slab's rim point may be in two lanes' rings at once.)
  if (cost_->wide_update())
    for (Index w : ring) std::atomic_ref<std::uint32_t>(dirty_[w]).fetch_add(1, std::memory_order_relaxed);
  lane.ring_edges.clear();
  for (Index w : ring) {
    lane.ring_edges.push_back({v, w});
    prefetch_for_rating(w);
  }
  push_edges(lane, lane.ring_edges);
}

std::optional<std::pair<Index, Index>> Engine::cheapest_boundary_collapse(Lane& lane) {
  std::optional<std::pair<Index, Index>> best;
  double best_cost = 0;
  std::vector<Index> ring;
  Candidate c;
  for (Index u = 0; u < static_cast<Index>(s_.position.size()); ++u) {
    if (!s_.has(u, kBorder) || s_.has(u, kRemoved)) continue;
    neighbours(u, ring);
    for (Index v : ring)  // both directions: v is on the boundary too and visits u in turn
      if (s_.has(v, kBorder) && evaluate(lane, u, v, c, true) == Rejection::None && lane.probe.shared.size() == 1 &&
          (!best || c.cost < best_cost))
        best = {u, v}, best_cost = c.cost;
  }
  return best;
}

std::string Engine::stop_report(Index target, BlockedEdges& blocked) {
  // Classify every remaining edge by why it cannot collapse.
  std::size_t counts[static_cast<int>(Rejection::kCount)] = {};
  const std::vector<std::pair<Index, Index>> edges = remaining_edges();
  const Index remaining = static_cast<Index>(edges.size());
  for (const auto& [p, q] : edges) {
    Candidate c;
    const Rejection a = evaluate(main_, p, q, c, true), b = evaluate(main_, q, p, c, true);
    // Report the more specific of the two directions' reasons.
    counts[static_cast<int>(std::max(a, b))]++;
  }
  auto count = [&](Rejection r) { return static_cast<Index>(counts[static_cast<int>(r)]); };
  blocked.remaining = remaining;
  blocked.locked = count(Rejection::Locked), blocked.topology = count(Rejection::Topology);
  blocked.boundary = count(Rejection::Boundary), blocked.seams = count(Rejection::Seam);
  blocked.valence = count(Rejection::Valence);
  blocked.flips = count(Rejection::Flip), blocked.inverted = count(Rejection::Inverted);
  blocked.slivers = count(Rejection::Sliver);
  blocked.error_limit = count(Rejection::ErrorLimit), blocked.cost = count(Rejection::Cost);
  const char* names[] = {"", "locked (non-manifold or locked boundary) vertices", "topology (link condition)",
                         "boundary rules", "attribute seams", "the valence limit", "face flips",
                         "faces that would face against the input (inverted_faces)", "slivers",
                         "the error limit", "the cost"};
  std::string why;
  for (int r = 1; r < static_cast<int>(Rejection::kCount); ++r)
    if (counts[r]) why += fmt::format("{}{} blocked by {}", why.empty() ? "" : ", ", counts[r], names[r]);
  return fmt::format("stopped at {} faces, above the target of {}: none of the {} remaining edges can collapse "
                     "({}); {} vertices are locked",
                     s_.alive_faces, target, remaining, why.empty() ? "no edges left" : why, locked_);
}

template <typename Done>
void Engine::drain(Lane& lane, Done done, std::optional<std::pair<Index, Index>>& deferred) {
  auto& queue = lane.queue;
  Candidate c;
  while (!queue.empty() && !done()) {
    if (4 * lane.stale_estimate > queue.size()) {
      // The pop order stays the same: only entries the loop below would skip are dropped.
      queue.filter([&](const HeapEntry& e) { return !stale(e); });
      lane.stale_estimate = 0;
      continue;
    }
    const HeapEntry e = queue.pop();
    if (!queue.empty()) prefetch_point(queue.top().u), prefetch_point(queue.top().v);
    if (stale(e)) continue;
    if (outdated(e)) {
      // Its neighbourhood changed: score it again, with the other such entries at the top of the
      // queue (up to the first up-to-date one), side by side.
      lane.rescore.assign(1, {e.u, e.v});
      while (!queue.empty() && lane.rescore.size() < kRescoreBatch) {
        const HeapEntry& t = queue.top();
        if (stale(t)) {
          queue.pop();
          continue;
        }
        if (!outdated(t)) break;
        lane.rescore.push_back({t.u, t.v});
        queue.pop();
      }
      push_edges(lane, lane.rescore);
      continue;
    }
    const bool scored = recall(e, c);
    Rejection verdict = evaluate(lane, e.u, e.v, c, true, scored);
    if (verdict == Rejection::Inverted && inverted_mode_ == InvertedFaces::Avoid && wait_inverted(lane, e, c, verdict))
      continue;
    // The next pop's data arrives in three steps, each while a collapse is checked or done: checking
    // one waited on memory for a third of its time (igea, lanes: 1.40 -> 1.02 G cycles).
    if (!queue.empty()) prefetch_faces(queue.top().u), prefetch_faces(queue.top().v);
    if (verdict != Rejection::None) {
      // The best direction is illegal now; the other one may still be worth queueing.
      Candidate r;
      if (evaluate(lane, e.v, e.u, r, true) == Rejection::None) {
        const HeapEntry other = entry(r.cost, e.v, e.u);
        queue.push(other);
        remember(other, r);
      }
      continue;
    }
    if (lane.region < 0 && s_.alive_faces - static_cast<Index>(lane.probe.shared.size()) < target_) {
      deferred = {e.u, e.v};
      break;
    }
    lane.paid = std::max<double>(lane.paid, e.cost);
    collapse(lane, e.u, e.v, c);
    if (!queue.empty()) prefetch_corners(queue.top().u), prefetch_corners(queue.top().v);
    if (lane.region < 0) report_progress(s_.alive_faces);
  }
}

// On a large mesh, lanes do most of the work side by side first. The mesh is cut into slabs of equal
// face counts across the longest side of its bounding box; each lane collapses only edges with both
// ends inside its slab (the slab's rim, points with faces in two slabs, stays put, so no two lanes
// ever touch the same point, face or list). They go in rounds: each collapses all it has that costs
// less than a common threshold, which then rises by a quarter, so the slabs coarsen at the pace one
// queue would set and no slab runs ahead. A round's work depends on the threshold only, never on which
// lane finished first: the result is the same for any number of threads. Two passes: the second on
// slabs cut halfway between the first's cuts, so the first's rims lie inside them. Each stops where what
// follows can still restore its rims (lane_pass_stop), and one queue does at least the last 5 %.
bool Engine::run_lanes(std::vector<HeapEntry>& first) {
  const Index target = target_;
  const Index alive = s_.alive_faces;
  const Index per_lane = o_.lane_faces.value_or(default_lane_faces(o_.method));
  const Index count = per_lane > 0 ? std::min<Index>(kMaxLanes, alive / per_lane) : 0;
  if (count < 2 || o_.record_collapses) return false;

  // (A third pass, on the first cuts again, was 1 % faster over 26 hoppe runs but lost accuracy: laurana
  // at 1 %, Hausdorff x2.65.)
  const Index last_queue = target + (alive - target) / 20;
  const Index least_pass = (alive - target) / 50;  // a pass worth its cuts and re-rating
  std::vector<HeapEntry> entries;
  bool ran = false;
  for (const bool shifted : {false, true}) {
    Slabs slabs = cut_into_slabs(s_, count, shifted);
    const Index stop = std::max(last_queue, lane_pass_stop(s_.alive_faces, target, slabs.rim_faces));
    if (stop > s_.alive_faces - least_pass) break;
    entries = lane_pass(std::move(slabs), stop, ran ? entries : first);
    ran = true;
  }
  if (!ran) return false;
  main_.queue.load(std::move(entries));
  lanes_used_ = static_cast<int>(count);
  return true;
}

std::vector<HeapEntry> Engine::lane_pass(Slabs slabs, Index stop_at, std::vector<HeapEntry>& queued) {
  const Index alive = s_.alive_faces;
  region_ = std::move(slabs.region);
  // Costly costs keep their last candidates per point; one kept across passes may name a point now in
  // another lane, whose tags that lane moves meanwhile. Dropped: those entries are scored again.
  for (auto& list : scored_) list.clear();
  std::vector<Lane> lanes(slabs.faces.size());
  for (std::size_t i = 0; i < lanes.size(); ++i) {
    lanes[i].region = static_cast<Index>(i);
    // Never below its share of the target (rounded up), so the lanes together stop above it.
    lanes[i].floor = static_cast<Index>((std::int64_t(target_) * slabs.faces[i] + alive - 1) / alive);
  }
  {
    // Entries with an end on a rim are dropped: the rims' edges are rated afresh after the pass. (No
    // entry is stale: nothing collapsed since they were rated or filtered.)
    auto lane_of = [&](const HeapEntry& e) { return region_[e.u] >= 0 && region_[e.u] == region_[e.v] ? region_[e.u] : -1; };
    std::vector<std::size_t> sizes(lanes.size(), 0);
    for (const HeapEntry& e : queued)
      if (const Index i = lane_of(e); i >= 0) ++sizes[i];
    std::vector<std::vector<HeapEntry>> split(lanes.size());
    for (std::size_t i = 0; i < lanes.size(); ++i) split[i].reserve(sizes[i]);  // exact: no spare half
    for (const HeapEntry& e : queued)
      if (const Index i = lane_of(e); i >= 0) split[i].push_back(e);
    queued = {};
    tbb::parallel_for(std::size_t(0), lanes.size(), [&](std::size_t i) { lanes[i].queue.load(std::move(split[i])); });
  }
  auto lane_alive = [&](const Lane& lane) { return slabs.faces[lane.region] - lane.removed_faces; };
  double threshold = INFINITY;
  for (const Lane& lane : lanes)
    if (!lane.queue.empty()) threshold = std::min<double>(threshold, lane.queue.top().cost);
  Index total = alive;
  while (std::isfinite(threshold)) {
    tbb::parallel_for(std::size_t(0), lanes.size(), [&](std::size_t i) {
      Lane& lane = lanes[i];
      if (lane.done) return;
      std::optional<std::pair<Index, Index>> unused;
      auto at_floor = [&] { return lane_alive(lane) < lane.floor + 2; };  // a collapse removes up to two
      drain(lane, [&] { return at_floor() || lane.queue.top().cost > threshold; }, unused);
      lane.done = lane.queue.empty() || at_floor();
    });
    total = alive;
    for (const Lane& lane : lanes) total -= lane.removed_faces;
    report_progress(total);
    if (total <= stop_at) break;
    double next = INFINITY;
    for (const Lane& lane : lanes)
      if (!lane.done) next = std::min<double>(next, lane.queue.top().cost);
    // (A cost may be negative, as hoppe's can: then the threshold moves up towards zero.)
    threshold = std::max(threshold < 0 ? threshold * 0.75 : threshold * 1.25, next);
  }
  s_.alive_faces = total;
  for (Lane& lane : lanes) {
    collapses_ += lane.collapses, max_error_ = std::max(max_error_, lane.max_error);
    // Entries waiting go on to the next queue, which lets them be when they come back, as does what was paid.
    main_.waited.merge(lane.waited);
    main_.paid = std::max(main_.paid, lane.paid);
    if (lane.let_inverted && !inverted_allowed_at_) inverted_allowed_at_ = alive;
  }

  // What the lanes left (still valid: scored as one queue would have), and the rims' edges, which no
  // lane queued, rated now. The rims' face lists kept the faces their lanes removed: pruned first.
  std::vector<std::pair<Index, Index>> edges;
  std::vector<Index>& ring = main_.ring;
  for (Index p = 0; p < static_cast<Index>(region_.size()); ++p) {
    if (region_[p] != -1) continue;
    auto& list = s_.point_faces[p];
    list.erase(std::remove_if(list.begin(), list.end(), [&](Index f) { return s_.face_dead[f] != 0; }), list.end());
    neighbours(p, ring);
    for (Index q : ring)
      if (region_[q] != -1 || q > p) edges.push_back({p, q});
  }
  region_ = {};
  std::vector<HeapEntry> entries = rate_all(edges);
  std::size_t total_entries = entries.size();
  for (const Lane& lane : lanes) total_entries += lane.queue.size();
  entries.reserve(total_entries);
  for (Lane& lane : lanes) {
    const std::vector<HeapEntry> left = lane.queue.take();
    std::copy_if(left.begin(), left.end(), std::back_inserter(entries), [&](const HeapEntry& e) { return !stale(e); });
  }
  return entries;
}

// The default limit on a face's turn from its input shape (60 degrees for hoppe and edge-length) stops CAD
// parts short of coarse targets: a face there comes to stand for a region across a 90-degree edge. Rather
// than stop, the run goes on with 90 degrees, the most that never lets a face face against its input self.
// A limit the caller set is kept. Runs that reach their target without it are unchanged.
bool Engine::relax_total_turn() {
  constexpr double kFlipBoundary = 90.0;
  if (o_.max_total_normal_change_deg || total_turn_deg_ >= kFlipBoundary || !o_.preserve_topology) return false;
  set_total_turn(kFlipBoundary);
  relaxed_at_ = s_.alive_faces;
  return true;
}

bool Engine::wait_inverted(Lane& lane, const HeapEntry& e, const Candidate& c, Rejection& verdict) {
  if (lane.waited.insert({e.u, e.v, e.version}).second) {
    HeapEntry later = e;
    later.cost = static_cast<float>(kInvertedWait * std::max(lane.paid, c.cost));
    lane.queue.push(later);
    remember(later, c);
    return true;
  }
  verdict = let_inverted_be(lane, e.u, e.v, c.position);
  return false;
}

Rejection Engine::let_inverted_be(Lane& lane, Index u, Index v, const Eigen::Vector3d& p) {
  const Rejection verdict = geometry(lane, u, v, p, true);
  if (verdict != Rejection::None) return verdict;
  lane.let_inverted = true;
  // Lanes run side by side with no common count: theirs is where their pass began (see lane_pass()).
  if (lane.region < 0 && !inverted_allowed_at_) inverted_allowed_at_ = s_.alive_faces;
  return verdict;
}

std::vector<std::pair<Index, Index>> Engine::remaining_edges() {
  std::vector<std::pair<Index, Index>> edges;
  std::vector<Index>& ring = main_.ring;
  for (Index p = 0; p < static_cast<Index>(s_.position.size()); ++p) {
    if (s_.has(p, kRemoved)) continue;
    neighbours(p, ring);
    for (Index q : ring)
      if (q > p) edges.push_back({p, q});
  }
  return edges;
}

std::vector<HeapEntry> Engine::rate_all(const std::vector<std::pair<Index, Index>>& edges) {
  // Straight into the entries, those of illegal edges then dropped: an array of optional entries
  // beside them was 39 MiB more at the peak on a 1M-face mesh. (Their candidates are not kept: most
  // are re-scored before they reach the top, and keeping them all raised hoppe's peak on the horse by
  // 15 MiB, to 71.)
  std::vector<HeapEntry> entries;
  rate_edges(edges, -1, entries, nullptr);
  std::erase_if(entries, unrated);
  return entries;
}

void Engine::report_progress(Index alive) {
  if (!o_.progress || faces_before_ - alive < next_report_) return;
  const Index to_remove = std::max<Index>(1, faces_before_ - target_);
  o_.progress(std::min(1.0, double(faces_before_ - alive) / to_remove));
  next_report_ += std::max<Index>(1, to_remove / 100);
}

SimplifyResult Engine::run(Index target) {
  SimplifyResult result;
  result.faces_in = s_.input->num_faces();
  result.vertices_in = s_.input->num_vertices();
  result.target_faces = target;
  faces_before_ = s_.alive_faces;
  target_ = target;

  // Every edge once, scored in both directions; on a large mesh the lanes do most of the work first.
  {
    std::vector<std::pair<Index, Index>> edges;
    edges.reserve(edges_.size());
    for (const EdgeUse& e : edges_)
      if (e.faces <= 2) edges.push_back({e.lo, e.hi});
    edges_ = {};
    std::vector<HeapEntry> first = rate_all(edges);
    if (!run_lanes(first)) main_.queue.load(std::move(first));
  }
  // The best legal collapse, kept back when it would remove two faces and one is left to remove.
  std::optional<std::pair<Index, Index>> deferred;
  drain(main_, [&] { return s_.alive_faces <= target; }, deferred);
  // The queue ran dry above the target. An edge refused when it was last rated is rated again only when
  // a collapse keeps one of its ends, so one that a collapse beside it made legal (a face there no
  // longer turns too far) was never queued again, and the run stopped short of a legal collapse. Rate
  // every edge left once more, and go on while that finds collapses.
  // When that finds none, a default limit on the turn from the input shape may still give way (the turn is
  // checked at the top of the queue, not in rating: an empty rating leaves nothing for it to free).
  // (InvertedFaces::Avoid needs no such step: its entries wait in the queue, they are not refused.)
  while (!deferred && s_.alive_faces > target) {
    std::vector<HeapEntry> entries = rate_all(remaining_edges());
    if (entries.empty()) break;
    const Index before = main_.collapses;
    main_.queue.load(std::move(entries));
    drain(main_, [&] { return s_.alive_faces <= target; }, deferred);
    if (main_.collapses == before && !relax_total_turn()) break;
  }
  Candidate c;
  if (s_.alive_faces > target && deferred) {
    // Only a boundary edge removes exactly one face. Look for the cheapest directly: draining the
    // queue for it took as long as the whole run on a closed 1M-face mesh. If there is none, take the
    // best two-face collapse and land one below the target.
    if (const auto one = cheapest_boundary_collapse(main_)) deferred = one;
    Rejection verdict = evaluate(main_, deferred->first, deferred->second, c, true);
    // A waited entry was let be when it was found.
    if (verdict == Rejection::Inverted && inverted_mode_ == InvertedFaces::Avoid)
      verdict = let_inverted_be(main_, deferred->first, deferred->second, c.position);
    if (verdict == Rejection::None) collapse(main_, deferred->first, deferred->second, c);
  }
  collapses_ += main_.collapses;
  max_error_ = std::max(max_error_, main_.max_error);

  if (s_.alive_faces <= target) {
    result.reason = StopReason::TargetReached;
    result.reason_text = fmt::format("reached the target: {} faces (target {})", s_.alive_faces, target);
  } else {
    result.reason_text = stop_report(target, result.blocked);
    result.reason = result.blocked.error_limit > 0 ? StopReason::ErrorLimit : StopReason::NoLegalCollapse;
  }
  if (relaxed_at_) {
    result.turn_limit_relaxed_at = *relaxed_at_;
    result.reason_text += fmt::format("; faces were let turn up to {:g} degrees from their input shape from {} faces on, "
                                      "where the default limit of {:g} held every collapse back",
                                      total_turn_deg_, *relaxed_at_, starting_total_turn_deg());
  }
  if (inverted_allowed_at_) {
    result.inverted_allowed_at = *inverted_allowed_at_;
    result.reason_text += fmt::format("; faces were let face against the input from {} faces on, where the "
                                      "collapses that avoided them cost {:g} times as much",
                                      *inverted_allowed_at_, kInvertedWait);
  }

  // Output: surviving faces in input order; surviving wedges in input order with their point's position.
  const Mesh& in = *s_.input;
  std::vector<Index> new_index(static_cast<std::size_t>(in.num_vertices()), -1);
  Index nf = 0;
  for (std::size_t f = 0; f < s_.face.size(); ++f)
    if (!s_.face_dead[f]) {
      ++nf;
      for (Index w : s_.face[f]) new_index[w] = 0;
    }
  Index nv = 0;
  for (Index w = 0; w < in.num_vertices(); ++w)
    if (new_index[w] == 0) new_index[w] = nv++, result.vertex_origin.push_back(w);
  Mesh& out = result.mesh;
  out.positions.resize(nv, 3);
  out.triangles.resize(nf, 3);
  result.face_origin.reserve(static_cast<std::size_t>(nf));
  const Attributes& a = in.attributes;
  if (in.has_normals()) out.attributes.normals.resize(nv, 3);
  if (in.has_uvs()) out.attributes.uvs.resize(nv, 2);
  if (in.has_colours()) out.attributes.colours.resize(nv, 4);
  if (in.has_face_colours()) out.attributes.face_colours.resize(nf, 4);
  for (Index i = 0; i < nv; ++i) {
    const Index w = result.vertex_origin[i];
    out.positions.row(i) = (s_.position[s_.point_of[w]] + s_.origin).transpose();
    if (in.has_normals()) out.attributes.normals.row(i) = a.normals.row(w);
    if (in.has_uvs()) out.attributes.uvs.row(i) = a.uvs.row(w);
    if (in.has_colours()) out.attributes.colours.row(i) = a.colours.row(w);
  }
  if (s_.attribute_quadrics.enabled()) {
    // Attributes the cost optimised come from the wedges' current values.
    std::vector<double> value(static_cast<std::size_t>(attribute_values_per_vertex(in)));
    for (Index i = 0; i < nv; ++i) {
      output_attributes(result.vertex_origin[i], value.data());
      int j = 0;
      if (in.has_normals()) for (int d = 0; d < 3; ++d) out.attributes.normals(i, d) = value[j++];
      if (in.has_uvs()) for (int d = 0; d < 2; ++d) out.attributes.uvs(i, d) = value[j++];
      if (in.has_colours()) for (int d = 0; d < 4; ++d) out.attributes.colours(i, d) = static_cast<float>(value[j++]);
    }
  }
  Index row = 0;
  for (std::size_t f = 0; f < s_.face.size(); ++f) {
    if (s_.face_dead[f]) continue;
    for (int k = 0; k < 3; ++k) out.triangles(row, k) = new_index[s_.face[f][k]];
    if (in.has_face_colours()) out.attributes.face_colours.row(row) = a.face_colours.row(static_cast<Index>(f));
    result.face_origin.push_back(static_cast<Index>(f));
    ++row;
  }
  result.faces_out = nf;
  result.vertices_out = nv;
  result.collapses = collapses_;
  result.error = max_error_;
  result.locked_vertices = locked_;
  result.lanes = lanes_used_;
  result.dropped_degenerate_faces = dropped_;
  result.records = std::move(records_);
  if (o_.record_collapses) {
    result.vertex_point = s_.point_of;
    result.vertex_canonical = std::move(canonical_);
  }
  if (o_.progress) o_.progress(1.0);
  return result;
}

}  // namespace
}  // namespace detail

SimplifyResult simplify(const Mesh& mesh, const SimplifyOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  validate(mesh, "simplify");
  if (options.target_ratio && !(*options.target_ratio >= 0 && *options.target_ratio <= 1))
    throw Error(fmt::format("simplify: ratio must be between 0 and 1, got {}", *options.target_ratio));
  if (options.target_faces && *options.target_faces < 0)
    throw Error(fmt::format("simplify: face target must not be negative, got {}", *options.target_faces));
  if (options.max_error && !(*options.max_error >= 0))
    throw Error(fmt::format("simplify: max error must not be negative, got {}", *options.max_error));
  if (!(options.max_normal_change_deg > 0 && options.max_normal_change_deg <= 180))
    throw Error("simplify: max normal change must be in (0, 180] degrees");
  if (options.max_total_normal_change_deg &&
      !(*options.max_total_normal_change_deg > 0 && *options.max_total_normal_change_deg <= 180))
    throw Error(fmt::format("simplify: max total normal change must be in (0, 180] degrees, got {}",
                            *options.max_total_normal_change_deg));
  if (options.lane_faces && *options.lane_faces < 0)
    throw Error(fmt::format("simplify: faces per lane must not be negative, got {}", *options.lane_faces));
  if (options.max_valence && *options.max_valence < 0)
    throw Error(fmt::format("simplify: the valence limit must not be negative, got {}", *options.max_valence));
  if (!(options.hoppe_points_per_face >= 0 && options.hoppe_points_per_face <= 1000))
    throw Error(fmt::format("simplify: hoppe's random points per face must be between 0 and 1000, got {}",
                            options.hoppe_points_per_face));
  if (!(options.hoppe_points_on_every_face >= 0 && options.hoppe_points_on_every_face <= 1000))
    throw Error(fmt::format("simplify: hoppe's random points on every face must be between 0 and 1000, got {}",
                            options.hoppe_points_on_every_face));
  if (options.hoppe_min_points < 0)
    throw Error(fmt::format("simplify: hoppe's minimum sample points must not be negative, got {}", options.hoppe_min_points));
  if (!(options.hoppe_crease_angle_deg >= 0 && options.hoppe_crease_angle_deg <= 180))
    throw Error(fmt::format("simplify: hoppe's crease angle must be between 0 and 180 degrees, got {}",
                            options.hoppe_crease_angle_deg));
  Index target = 0;
  if (!options.target_faces && !options.target_ratio && !options.max_error) target = mesh.num_faces() / 2;
  if (options.target_faces) target = std::max(target, *options.target_faces);
  if (options.target_ratio)
    target = std::max(target, static_cast<Index>(std::llround(*options.target_ratio * mesh.num_faces())));
  if (options.recompute_normals && options.record_collapses)
    throw Error("simplify: recompute_normals cannot be combined with record_collapses");
  SimplifyResult r;
  if (options.recompute_normals && mesh.has_normals()) {
    // A copy without normals: the engine welds vertices that differed only by them.
    Mesh positions_only = mesh;
    positions_only.attributes.normals.resize(0, 3);
    r = detail::Engine(positions_only, options).run(target);
  } else {
    r = detail::Engine(mesh, options).run(target);
  }
  if (options.recompute_normals) r.mesh.attributes.normals = compute_vertex_normals(r.mesh);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

int attribute_values_per_vertex(const Mesh& mesh) {
  return 3 * mesh.has_normals() + 2 * mesh.has_uvs() + 4 * mesh.has_colours();
}

Index default_lane_faces(SimplifyMethod method) { return method == SimplifyMethod::Hoppe ? 8000 : 125000; }

Index default_max_valence(SimplifyMethod method) { return method == SimplifyMethod::Hoppe ? 24 : 0; }

InvertedFaces default_inverted_faces(SimplifyMethod method) {
  return method == SimplifyMethod::Quadric ? InvertedFaces::Avoid : InvertedFaces::Allow;
}

double default_max_total_normal_change(SimplifyMethod method) { return method == SimplifyMethod::Quadric ? 90.0 : 60.0; }

std::string to_string(SimplifyMethod method) {
  switch (method) {
    case SimplifyMethod::Quadric: return "quadric";
    case SimplifyMethod::Hoppe: return "hoppe";
    case SimplifyMethod::EdgeLength: return "edge-length";
  }
  return "?";
}

std::optional<SimplifyMethod> parse_method(const std::string& name) {
  if (name == "quadric") return SimplifyMethod::Quadric;
  if (name == "hoppe") return SimplifyMethod::Hoppe;
  if (name == "edge-length") return SimplifyMethod::EdgeLength;
  return std::nullopt;
}

std::string to_string(InvertedFaces mode) {
  switch (mode) {
    case InvertedFaces::Allow: return "allow";
    case InvertedFaces::Avoid: return "avoid";
    case InvertedFaces::Refuse: return "refuse";
  }
  return "?";
}

std::optional<InvertedFaces> parse_inverted_faces(const std::string& name) {
  for (const InvertedFaces mode : {InvertedFaces::Allow, InvertedFaces::Avoid, InvertedFaces::Refuse})
    if (name == to_string(mode)) return mode;
  return std::nullopt;
}

}  // namespace lodkit
