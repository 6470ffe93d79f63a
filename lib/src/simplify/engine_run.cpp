// The run: the queue's loop, the lanes that go first on large meshes, what happens when the queue runs
// dry, the stop report and the output mesh.
#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "core/huge_pages.h"
#include "simplify/collapse_engine.h"

namespace lodkit::detail {

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
  forget_candidates();
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
    for (std::size_t i = 0; i < lanes.size(); ++i) reserve_huge(split[i], sizes[i]);  // exact: no spare half
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
  reserve_huge(entries, total_entries);
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
  if (o_.max_total_normal_change_deg || total_turn_deg_ >= kRelaxedTotalTurnDeg || !o_.preserve_topology) return false;
  set_total_turn(kRelaxedTotalTurnDeg);
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
  const char* names[] = {"", "locked (non-manifold, disagreeing on orientation, or a locked boundary) vertices", "topology (link condition)",
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

Index Engine::quadric_until(Index target) const {
  if (!cost_->scores_by_quadric() || target <= 0) return 0;
  const double until = std::ceil(o_.hoppe_energy_from * double(target));  // above target: the factor is above 1
  return until < double(s_.alive_faces) ? static_cast<Index>(until) : 0;
}

void Engine::queue_edges(const std::vector<std::pair<Index, Index>>& edges, Index target) {
  target_ = target;
  std::vector<HeapEntry> first = rate_all(edges);
  if (!run_lanes(first)) main_.queue.load(std::move(first));
}

void Engine::report_progress(Index alive) {
  if (!o_.progress || faces_before_ - alive < next_report_) return;
  const Index to_remove = std::max<Index>(1, faces_before_ - final_target_);
  o_.progress(std::min(1.0, double(faces_before_ - alive) / to_remove));
  next_report_ += std::max<Index>(1, to_remove / 100);
}

SimplifyResult Engine::run(Index target) {
  SimplifyResult result;
  result.faces_in = s_.input->num_faces();
  result.vertices_in = s_.input->num_vertices();
  result.target_faces = target;
  faces_before_ = s_.alive_faces;
  final_target_ = target;

  // Every edge once, scored in both directions; on a large mesh the lanes do most of the work first.
  std::vector<std::pair<Index, Index>> edges;
  reserve_huge(edges, edges_.size());
  for (const EdgeUse& e : edges_)
    if (e.faces <= 2) edges.push_back({e.lo, e.hi});
  edges_ = {};
  // The best legal collapse, kept back when it would remove two faces and one is left to remove.
  std::optional<std::pair<Index, Index>> deferred;
  if (const Index until = quadric_until(target); until > 0) {
    // hoppe ranks by the quadric error down to `until` faces (SimplifyOptions::hoppe_energy_from); then
    // what is queued goes, and every edge left is rated afresh by the energy.
    queue_edges(edges, until);
    drain(main_, [&] { return s_.alive_faces <= until; }, deferred);
    deferred.reset();
    main_.queue.take();
    forget_candidates();
    main_.stale_estimate = 0;
    main_.waited.clear();
    main_.paid = 0;  // (in the quadric's units)
    energy_from_ = s_.alive_faces;
    edges = remaining_edges();
  }
  cost_->own_scores();
  queue_edges(edges, target);
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
  result.hoppe_energy_from_faces = energy_from_;
  if (inverted_allowed_at_) {
    result.inverted_allowed_at = *inverted_allowed_at_;
    result.reason_text += fmt::format("; faces were let face against the input from {} faces on, where the "
                                      "collapses that avoided them cost {:g} times as much",
                                      *inverted_allowed_at_, kInvertedWait);
  }

  fit_points(result);

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

}  // namespace lodkit::detail
