#include "metrics/max_distance_bound.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <tbb/parallel_for.h>
#include <vector>

#include "core/geometry.h"
#include "core/topology.h"
#include "metrics/aabb_tree.h"

namespace lodkit::detail {

std::vector<std::array<Index, 3>> face_neighbours(const Mesh& to) {
  const Eigen::VectorX<Index> cls = position_classes(to);
  std::vector<std::array<Index, 3>> faces(static_cast<std::size_t>(to.num_faces()));
  for (Index f = 0; f < to.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) faces[f][k] = cls[to.triangles(f, k)];
  std::vector<std::array<Index, 3>> across(faces.size(), {-1, -1, -1});
  for (const EdgeUse& e : classify_edges(faces)) {
    if (e.faces != 2) continue;
    for (int side = 0; side < 2; ++side) {
      const auto& f = faces[e.face[side]];
      for (int k = 0; k < 3; ++k)
        if (std::minmax(f[k], f[(k + 1) % 3]) == std::pair<const Index&, const Index&>(e.lo, e.hi))
          across[e.face[side]][k] = e.face[1 - side];
    }
  }
  return across;
}

namespace {

// A triangle of `from` (a face or a part of one) and what its bound rests on.
struct Piece {
  std::array<Eigen::Vector3d, 3> corner;
  std::array<Index, 3> corner_face;  // the face of `to` nearest each corner
  Index inherited = -1;              // the face its parent's bound came from
  Index centroid_face = -1;          // the face of `to` nearest its centroid; -1 until asked
  Index best = -1;                   // the face its bound comes from
  double bound = 0;
};

bool lower_bound_first(const Piece& a, const Piece& b) { return a.bound < b.bound; }

// A triangle clipped by three half-planes has at most six corners; rounding could add a few.
constexpr int kClipCapacity = 9;

// 2D points of a piece's plane, each with its height above the plane.
struct Lifted {
  Eigen::Vector2d at;
  double height;
};

// 2 x the signed area of (a, b, c): positive when counter-clockwise.
double orient(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  return (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
}

class Bounder {
 public:
  Bounder(const Mesh& to, const AabbTree& tree, std::span<const std::array<Index, 3>> across)
      : to_(to), tree_(tree), across_(across) {}

  double distance(Index f, const Eigen::Vector3d& p) const {
    const Eigen::Vector3d q = closest_point_on_triangle(p, to_.positions.row(to_.triangles(f, 0)),
                                                        to_.positions.row(to_.triangles(f, 1)),
                                                        to_.positions.row(to_.triangles(f, 2)));
    return (q - p).norm();
  }

  // The least, over the candidate faces, of the farthest corner from the face (cheap, and exact where
  // one face is nearest the whole piece); where that does not settle it (above `enough`), the patch
  // bound too.
  void rate(Piece& s, double enough) const {
    std::array<Index, 5> candidates{s.corner_face[0], s.corner_face[1], s.corner_face[2], s.inherited, s.centroid_face};
    s.bound = std::numeric_limits<double>::infinity();
    for (int i = 0; i < 5; ++i) {
      const Index f = candidates[i];
      if (f < 0 || std::find(candidates.begin(), candidates.begin() + i, f) != candidates.begin() + i) continue;
      double farthest = 0;
      for (int k = 0; k < 3 && farthest < s.bound; ++k) farthest = std::max(farthest, distance(f, s.corner[k]));
      if (farthest < s.bound) s.bound = farthest, s.best = f;
    }
    if (s.bound > enough) s.bound = std::min(s.bound, patch_bound(s, s.bound));
  }

  // Seen from the piece's plane, the faces of `to` around it, where they all face one way (the plane's
  // or all the other: `to` may be oriented either way round) and cover the piece with no edge of theirs
  // open: then every point p of the piece has a point of `to`
  // straight above or below it, at a height that is affine over each face, so the largest height over
  // the overlap of each face with the piece (at the overlap's corners) bounds the distance from p. It
  // holds however many faces the piece spans, where the single-face bound needs the piece split down to
  // the size of the gap. Infinity where it does not apply; gives up above `give_up`.
  double patch_bound(const Piece& s, double give_up) const {
    constexpr double inf = std::numeric_limits<double>::infinity();
    // A piece of a coarse level can span thousands of the input's faces: at 256 it was split twice
    // before its pieces' patches fitted, each failed try wasted (igea_loop1's 692-face level against
    // the input: 3,744 splits and 0.49 s; at 4096, 172 splits and 0.20 s).
    constexpr std::size_t kMaxFaces = 4096;
    constexpr double kMinFacing = 0.05;  // faces steeper than this to the plane project too thin to trust
    const Eigen::Vector3d o = s.corner[0];
    const Eigen::Vector3d normal = (s.corner[1] - o).cross(s.corner[2] - o);
    const double twice_area = normal.norm();
    if (!(twice_area > 0)) return inf;
    const Eigen::Vector3d n = normal / twice_area, e1 = (s.corner[1] - o).normalized(), e2 = n.cross(e1);
    auto lift = [&](const Eigen::Vector3d& p) { return Lifted{{(p - o).dot(e1), (p - o).dot(e2)}, (p - o).dot(n)}; };
    const std::array<Eigen::Vector2d, 3> t{lift(s.corner[0]).at, lift(s.corner[1]).at, lift(s.corner[2]).at};
    // Slack for rounding in the inside tests, relative to the piece's size.
    const double slack = 1e-12 * (t[1].squaredNorm() + t[2].squaredNorm());

    // Which faces were visited: stamped with this call's number, not looked up in a list (a piece
    // spanning a few hundred faces made that list's lookups quadratic: most of a Hausdorff check).
    Marks& marks = scratch_marks();
    const std::uint32_t stamp = marks.next(static_cast<std::size_t>(to_.num_faces()));
    auto visited = [&](Index f) { return marks.stamp[static_cast<std::size_t>(f)] == stamp; };
    std::size_t visits = 0;
    std::vector<Index>& queue = scratch_queue();
    queue.clear();
    for (Index f : {s.centroid_face, s.corner_face[0], s.corner_face[1], s.corner_face[2]})
      if (f >= 0 && std::find(queue.begin(), queue.end(), f) == queue.end()) queue.push_back(f);
    double bound = 0, covered_area = 0;
    double side = 0;  // +1 or -1: the way the first face overlapping the piece faces, which all must
    bool any = false;
    for (std::size_t head = 0; head < queue.size(); ++head) {
      const Index f = queue[head];
      if (visited(f)) continue;
      std::array<Lifted, 3> c;
      for (int k = 0; k < 3; ++k) c[k] = lift(to_.positions.row(to_.triangles(f, k)));
      const double face_area2 = orient(c[0].at, c[1].at, c[2].at);
      // The seeds may lie off the piece; the faces reached from it must overlap it.
      const bool seed = !any;
      std::array<Lifted, kClipCapacity> poly{}, next{};
      const int count = clip(c, t, poly, next);
      if (count < 0) return inf;
      if (count == 0) {
        if (seed) continue;  // a seed beside the piece: try the next
        return inf;          // cannot happen for a face reached across an edge that meets the piece
      }
      const Eigen::Vector3d face_normal = (to_.positions.row(to_.triangles(f, 1)) - to_.positions.row(to_.triangles(f, 0)))
                                              .cross(to_.positions.row(to_.triangles(f, 2)) - to_.positions.row(to_.triangles(f, 0)));
      if (seed) side = face_area2 > 0 ? 1.0 : -1.0;
      if (!(side * face_area2 > 0) || side * face_normal.dot(n) < kMinFacing * face_normal.norm()) return inf;
      if (seed) {
        // Restart the search from this face alone: the other seeds count only if reached.
        queue.assign(1, f);
        head = 0;
        any = true;
      }
      marks.stamp[static_cast<std::size_t>(f)] = stamp;
      if (++visits > kMaxFaces) return inf;
      for (int i = 0; i < count; ++i) bound = std::max(bound, std::abs(poly[i].height));
      if (bound > give_up) return inf;
      for (int i = 1; i + 1 < count; ++i) covered_area += orient(poly[0].at, poly[i].at, poly[i + 1].at);
      for (int k = 0; k < 3; ++k) {
        if (!segment_meets(c[k].at, c[(k + 1) % 3].at, t, slack)) continue;
        const Index g = across_[f][k];
        if (g < 0) return inf;  // an open or non-manifold edge over the piece: it may not be covered
        if (!visited(g)) queue.push_back(g);
      }
    }
    return any && side * covered_area > 0 ? bound : inf;
  }

  // The distance from p to `to`, and its nearest face.
  std::pair<double, Index> measure(const Eigen::Vector3d& p, Index hint) {
    ++queries;
    const AabbTree::Hit hit = tree_.closest(p, hint);
    return {std::sqrt(hit.squared_distance), hit.face};
  }

  long long queries = 0;

 private:
  // Triangle c (counter-clockwise) clipped to triangle t: the overlap's corners, with heights (-1 if
  // rounding made more than the capacity).
  static int clip(const std::array<Lifted, 3>& c, const std::array<Eigen::Vector2d, 3>& t, std::array<Lifted, kClipCapacity>& poly,
                  std::array<Lifted, kClipCapacity>& next) {
    int count = 3;
    for (int k = 0; k < 3; ++k) poly[k] = c[k];
    for (int k = 0; k < 3 && count > 0; ++k) {
      const Eigen::Vector2d& a = t[k];
      const Eigen::Vector2d& b = t[(k + 1) % 3];
      int out = 0;
      for (int i = 0; i < count; ++i) {
        const Lifted& p = poly[i];
        const Lifted& q = poly[(i + 1) % count];
        const double sp = orient(a, b, p.at), sq = orient(a, b, q.at);
        if (out + 2 > kClipCapacity) return -1;  // only rounding could make so many
        if (sp >= 0) next[out++] = p;
        if ((sp >= 0) != (sq >= 0)) {
          const double w = sp / (sp - sq);
          next[out++] = {p.at + w * (q.at - p.at), p.height + w * (q.height - p.height)};
        }
      }
      count = out;
      std::swap(poly, next);
    }
    return count;
  }

  // Whether segment a b meets triangle t (counter-clockwise), touching included.
  static bool segment_meets(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const std::array<Eigen::Vector2d, 3>& t,
                            double slack) {
    double lo = 0, hi = 1;
    for (int k = 0; k < 3; ++k) {
      const double sa = orient(t[k], t[(k + 1) % 3], a) + slack, sb = orient(t[k], t[(k + 1) % 3], b) + slack;
      if (sa < 0 && sb < 0) return false;
      if (sa < 0) lo = std::max(lo, sa / (sa - sb));
      else if (sb < 0) hi = std::min(hi, sa / (sa - sb));
    }
    return lo <= hi;
  }

  // Per thread: a stamp per face of `to`, and the last stamp handed out. A stamp is never reused
  // while the array lives (on wrap-around it is cleared), so no clearing between calls.
  struct Marks {
    std::vector<std::uint32_t> stamp;
    std::uint32_t last = 0;
    std::uint32_t next(std::size_t faces) {
      if (stamp.size() < faces) stamp.resize(faces, 0);
      if (++last == 0) std::fill(stamp.begin(), stamp.end(), 0), last = 1;
      return last;
    }
  };
  static Marks& scratch_marks() {
    thread_local Marks m;
    return m;
  }
  static std::vector<Index>& scratch_queue() {
    thread_local std::vector<Index> v;
    return v;
  }

  const Mesh& to_;
  const AabbTree& tree_;
  std::span<const std::array<Index, 3>> across_;
};

}  // namespace

MaxDistanceBound bound_max_distance(const Mesh& from, const Mesh& to, const AabbTree& tree,
                                    std::span<const std::array<Index, 3>> to_neighbours,
                                    std::span<const Index> corner_face,
                                    double attained, const Eigen::Vector3d& attained_at,
                                    const MaxDistanceOptions& options) {
  Bounder bounder(to, tree, to_neighbours);
  double lower = attained;
  Eigen::Vector3d lower_at = attained_at;
  auto attain = [&](double d, const Eigen::Vector3d& p) {
    if (d > lower) lower = d, lower_at = p;
  };
  // Rounding leaves bounds a hair above what they bound: below this, a gap is not worth closing.
  const auto box = bounding_box(from);
  const double slack = 1e-9 * (box.isEmpty() ? 1.0 : box.diagonal().norm());
  auto threshold = [&] {
    return options.at_most ? *options.at_most : lower + std::max(options.tolerance * lower, slack);
  };
  // Deciding: a point farther than at_most answers it.
  auto decided_against = [&] { return options.at_most && lower > *options.at_most; };
  auto settled = [&](double bound) { return bound <= threshold(); };

  if (decided_against()) {
    MaxDistanceBound result;
    result.attained = lower;
    result.bound = std::numeric_limits<double>::infinity();  // none was sought
    result.attained_at = lower_at;
    return result;
  }
  // Every face's bound from its corners' nearest faces, side by side; only those above what is
  // attained go on.
  auto face_piece = [&](Index f) {
    Piece s;
    for (int k = 0; k < 3; ++k) {
      s.corner[k] = from.positions.row(from.triangles(f, k));
      s.corner_face[k] = corner_face[from.triangles(f, k)];
    }
    bounder.rate(s, threshold());
    return s;
  };
  std::vector<double> face_bound(static_cast<std::size_t>(from.num_faces()));
  tbb::parallel_for(tbb::blocked_range<Index>(0, from.num_faces(), 4096), [&](const tbb::blocked_range<Index>& r) {
    for (Index f = r.begin(); f != r.end(); ++f) face_bound[f] = face_piece(f).bound;
  });
  double pruned = 0;  // the largest bound set aside
  std::vector<Piece> heap;
  for (Index f = 0; f < from.num_faces(); ++f) {
    if (settled(face_bound[f])) pruned = std::max(pruned, face_bound[f]);
    else heap.push_back(face_piece(f));
  }
  std::make_heap(heap.begin(), heap.end(), lower_bound_first);

  auto offer = [&](Piece&& s) {
    if (settled(s.bound)) {
      pruned = std::max(pruned, s.bound);
    } else {
      heap.push_back(std::move(s));
      std::push_heap(heap.begin(), heap.end(), lower_bound_first);
    }
  };
  MaxDistanceBound result;
  while (!heap.empty() && !settled(heap.front().bound)) {
    if (result.splits >= options.max_splits || decided_against()) break;
    std::pop_heap(heap.begin(), heap.end(), lower_bound_first);
    Piece s = std::move(heap.back());
    heap.pop_back();
    if (s.centroid_face < 0) {
      // The face nearest the centroid first: where one face of `to` is nearest all of the piece (the
      // same surface, or a parallel one), it makes the bound exact without a split.
      const Eigen::Vector3d centroid = (s.corner[0] + s.corner[1] + s.corner[2]) / 3.0;
      const auto [d, f] = bounder.measure(centroid, s.corner_face[0]);
      attain(d, centroid);
      s.centroid_face = f;
      bounder.rate(s, threshold());
      offer(std::move(s));
      continue;
    }
    ++result.splits;
    // A piece of a degenerate face is a segment: quartered, each quarter still spans half of it, and
    // where the corners' nearest faces of `to` differ (a segment across an edge of `to`) the pieces
    // at that point multiply fourfold a level (a 23-face mesh took a million splits against itself).
    // Halved at its longest edge instead, two pieces a level meet there.
    std::array<double, 3> edge;  // squared length of edge k, from corner k to the next
    for (int k = 0; k < 3; ++k) edge[k] = (s.corner[(k + 1) % 3] - s.corner[k]).squaredNorm();
    const int a = static_cast<int>(std::max_element(edge.begin(), edge.end()) - edge.begin());
    if ((s.corner[1] - s.corner[0]).cross(s.corner[2] - s.corner[0]).norm() <= 1e-9 * edge[a]) {
      const int b = (a + 1) % 3, c = (a + 2) % 3;
      const Eigen::Vector3d m = 0.5 * (s.corner[a] + s.corner[b]);
      const auto [d, f] = bounder.measure(m, s.corner_face[a]);
      attain(d, m);
      for (const int end : {a, b}) {
        Piece child;
        child.corner = {s.corner[end], m, s.corner[c]};
        child.corner_face = {s.corner_face[end], f, s.corner_face[c]};
        child.inherited = s.best;
        bounder.rate(child, threshold());
        offer(std::move(child));
      }
      continue;
    }
    std::array<Eigen::Vector3d, 3> mid;
    std::array<Index, 3> mid_face;
    for (int k = 0; k < 3; ++k) {
      mid[k] = 0.5 * (s.corner[k] + s.corner[(k + 1) % 3]);
      const auto [d, f] = bounder.measure(mid[k], s.corner_face[k]);
      attain(d, mid[k]);
      mid_face[k] = f;
    }
    // Three corner triangles and the middle one, which shares its parent's centroid.
    for (int k = 0; k < 4; ++k) {
      Piece child;
      if (k < 3) {
        const int prev = (k + 2) % 3;
        child.corner = {s.corner[k], mid[k], mid[prev]};
        child.corner_face = {s.corner_face[k], mid_face[k], mid_face[prev]};
      } else {
        child.corner = mid;
        child.corner_face = mid_face;
        child.centroid_face = s.centroid_face;
      }
      child.inherited = s.best;
      bounder.rate(child, threshold());
      offer(std::move(child));
    }
  }
  result.attained = lower;
  result.attained_at = lower_at;
  result.bound = std::max({lower, pruned, heap.empty() ? 0.0 : heap.front().bound});
  result.queries = bounder.queries;
  return result;
}

}  // namespace lodkit::detail
