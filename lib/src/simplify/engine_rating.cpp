// Candidates into queue entries: each edge rated in its cheaper legal direction, side by side when
// there are many, and the costly costs' candidates kept for when their entry reaches the top.
#include <algorithm>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/huge_pages.h"
#include "simplify/collapse_engine.h"

namespace lodkit::detail {

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

void Engine::forget_candidates() {
  for (auto& list : scored_) list.clear();
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
    return cost_->score(s_, probe, u, v, f, c) && !(o_.max_error && c.error > *o_.max_error) &&
           s_.representable(c.position);
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
  resize_huge(out, edges.size());
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

}  // namespace lodkit::detail
