// Whether a collapse is legal: its structure (flags, link condition, seams, valence), then its geometry
// (turns, slivers, faces facing against the input).
#include <algorithm>
#include <atomic>
#include <iterator>

#include "core/geometry.h"
#include "simplify/collapse_engine.h"

namespace lodkit::detail {

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
      Eigen::Vector3d n1;
      if (const Rejection r = face_move(f, before, after, n1); r != Rejection::None) return r;
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
  for (const UnsettledFace& moved : unsettled)
    if (faces_against_input(moved.face, moved.centroid, moved.normal)) return Rejection::Inverted;
  return Rejection::None;
}

bool Engine::faces_against_input(Index f, const Eigen::Vector3d& centroid, const Eigen::Vector3d& n) const {
  // Lanes query side by side, but each on faces of its own region (a face with a corner inside a slab
  // lies in that slab), so no entry is written by two at once.
  NearestInput& last = nearest_input_[f];
  Index hint = last.face;
  const bool now = input_tree_->facing_against(centroid, n, hint, &last.certificate);
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


Rejection Engine::evaluate(Lane& lane, Index u, Index v, Candidate& c, bool full, bool scored) {
  if (!inside(lane.region, u, v)) return Rejection::Locked;
  find_shared_faces(u, v, lane.probe);
  Freedom freedom;
  if (const Rejection r = structure(u, v, freedom, full ? &lane : nullptr, lane.probe); r != Rejection::None) return r;
  if (!scored && !cost_->score(s_, lane.probe, u, v, freedom, c)) return Rejection::Cost;
  if (o_.max_error && c.error > *o_.max_error) return Rejection::ErrorLimit;
  return full ? geometry(lane, u, v, c.position) : Rejection::None;
}

}  // namespace lodkit::detail
