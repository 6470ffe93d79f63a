// The AabbTree's searches (closest points, faces facing a way, the facing checks' certificates); its
// construction is in aabb_tree_build.cpp.
#include "metrics/aabb_tree.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <type_traits>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#include <tbb/parallel_for.h>

#include "core/geometry.h"
#include "core/huge_pages.h"

namespace lodkit::detail {

namespace {
// facing_against() skips the search where every face near p turns less than kTurn from a cone that
// itself lies within a right angle, less kTurn, of the normal asked about: the nearest face, whichever
// it is, then faces the same way. A larger kTurn finds faces that turn farther off, but asks more of
// the normal; clearances are searched out to kReach times a leaf's size.
constexpr double kTurn = std::numbers::pi / 4;
constexpr double kReach = 6;
constexpr double kAngleSlack = 1e-7;   // radians: acos and the sums of angles round
constexpr double kCosineSlack = 1e-9;  // and cosines
constexpr double kSideSlack = 1e-6;    // the sines of the side tests, whose axes are floats
constexpr double kTieSlack = 1e-12;    // of the coordinates' magnitude: faces this much nearer tie

double angle_between(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {  // unit vectors
  return std::acos(std::clamp(a.dot(b), -1.0, 1.0));
}

double box_squared_distance(const Eigen::AlignedBox3d& box, const Eigen::Vector3d& p) {
  return (p - p.cwiseMax(box.min()).cwiseMin(box.max())).squaredNorm();
}

// Whether face f at squared distance d comes before `best` in the searches' order: by distance, then
// by index.
bool comes_before(double d, Index f, const AabbTree::Hit& best) {
  return d < best.squared_distance || (d == best.squared_distance && f < best.face);
}

// How descend() enters nodes: enter(node, flag) returns kPass to pass over the node, or the flag its
// subtree carries (kPlain or kFlagged; a search may flag a subtree, the flag passing to all below).
constexpr int kPass = -1, kPlain = 0, kFlagged = 1;
// The closest-point search enters every node.
struct EnterAll {
  int operator()(int, bool) const { return kPlain; }
};
// The cone searches pass over the nodes skip(node) rules out.
template <typename Skip>
auto entering_unless(Skip skip) {
  return [skip](int i, bool) { return skip(i) ? kPass : kPlain; };
}

// The nodes a search through the quads has yet to visit, each with its box's squared distance from the
// point (found when its parent was opened), its Quad::next and its flag.
// (A search pushes at most three more than it pops at each quad, one for every two levels.)
struct QuadStack {
  static constexpr int kSize = 128;
  static_assert(3 * (AabbTree::kMostDepth / 2 + 1) + 1 <= kSize);
  int node[kSize], next[kSize];
  double distance[kSize];
  bool flag[kSize];
  int top = 0;
  void push(int i, int n, double d, bool f) { node[top] = i, next[top] = n, distance[top] = d, flag[top] = f, ++top; }
};

// A quad's four squared box distances from p, as lower bounds of the exact ones, in floats: p rounds to
// floats by up to 2^-24 |p| an axis (taken off each axis's distance, with the largest coordinate
// standing for |p|), and the differences, squares and sums by 2^-24 each (a factor 1 - 2^-20 covers
// them); the boxes were rounded outwards. Where coordinates or squared distances could leave a
// float's range (beyond kFloatReach), in doubles.
struct QuadDistances {
  static constexpr double kFloatReach = 1e15;
  QuadDistances(const Eigen::Vector3d& p, double tree_extent) : point(p) {
    const double extent = p.cwiseAbs().maxCoeff();
    in_floats = std::max(extent, tree_extent) <= kFloatReach;
    for (int axis = 0; axis < 3; ++axis) at[axis] = static_cast<float>(p[axis]);
    slack = static_cast<float>(extent * 0x1p-23) + std::numeric_limits<float>::min();
  }
  Eigen::Vector3d point;
  bool in_floats;
  float at[3], slack;
  static constexpr float kShrink = 1.0f - 0x1p-20f;

  void operator()(const float (&lo)[3][4], const float (&hi)[3][4], double out[4]) const {
    if (!in_floats) {
      for (int lane = 0; lane < 4; ++lane) {
        double sum = 0;
        for (int axis = 0; axis < 3; ++axis) {
          const double off = std::max(std::max(double(lo[axis][lane]) - point[axis], point[axis] - double(hi[axis][lane])), 0.0);
          sum += off * off;
        }
        out[lane] = sum;
      }
      return;
    }
    float d[4];
#if defined(__SSE2__)
    const __m128 zero = _mm_setzero_ps(), margin = _mm_set1_ps(slack);
    __m128 sum = zero;
    for (int axis = 0; axis < 3; ++axis) {
      const __m128 p = _mm_set1_ps(at[axis]);
      __m128 off = _mm_max_ps(_mm_max_ps(_mm_sub_ps(_mm_load_ps(lo[axis]), p), _mm_sub_ps(p, _mm_load_ps(hi[axis]))), zero);
      off = _mm_max_ps(_mm_sub_ps(off, margin), zero);
      sum = _mm_add_ps(sum, _mm_mul_ps(off, off));
    }
    _mm_storeu_ps(d, _mm_mul_ps(sum, _mm_set1_ps(kShrink)));
#else
    for (int lane = 0; lane < 4; ++lane) {
      float sum = 0;
      for (int axis = 0; axis < 3; ++axis) {
        const float off = std::max(std::max(lo[axis][lane] - at[axis], at[axis] - hi[axis][lane]), 0.0f);
        const float less = std::max(off - slack, 0.0f);
        sum += less * less;
      }
      d[lane] = sum * kShrink;
    }
#endif
    for (int lane = 0; lane < 4; ++lane) out[lane] = d[lane];
  }
};
}  // namespace

template <typename Enter, typename Visit>
void AabbTree::descend(const Eigen::Vector3d& p, const double& bound, Enter enter, Visit visit) const {
  if (order_.empty()) return;
  const QuadDistances distances(p, extent_);
  QuadStack stack;
  const Node& root = nodes_[0];
  stack.push(0, quads_.empty() ? leaf_code(root) : 0, box_squared_distance(root.box, p), false);
  while (stack.top > 0) {
    --stack.top;
    if (stack.distance[stack.top] > bound) continue;
    const int i = stack.node[stack.top];
    const int entered = enter(i, stack.flag[stack.top]);
    if (entered == kPass) continue;
    const bool flag = entered == kFlagged;
    if (const int next = stack.next[stack.top]; next < 0) {
      const int first = (-1 - next) >> 2, count = ((-1 - next) & 3) + 1;  // leaf_code() undone
      for (int slot = first; slot < first + count; ++slot)
        if (visit(slot, flag)) return;
      continue;
    }
    const Quad& quad = quads_[stack.next[stack.top]];
    double d[4];
    distances(quad.lo, quad.hi, d);
    // The middle level is entered too: lanes under a child passed over go, and the others take its flag.
    bool lane_flag[2] = {flag, flag};
    if constexpr (!std::is_same_v<Enter, EnterAll>) {
      const Node& node = nodes_[i];
      for (int side = 0; side < 2; ++side) {
        const int child = node.first + side;
        if (nodes_[child].count > 0) continue;  // a leaf in its lane, entered when popped
        const int middle = enter(child, flag);
        if (middle == kPass) d[2 * side] = d[2 * side + 1] = std::numeric_limits<double>::infinity();
        lane_flag[side] = middle == kFlagged;
      }
    }
    // Nearer first on top: pushed farthest first.
    // (An empty lane's box lies at infinity, which a search without a bound yet, bound = infinity,
    // would not rule out: it is passed over by its node.)
    int lanes[4], n = 0;
    for (int lane = 0; lane < 4; ++lane) {
      if (quad.node[lane] < 0 || !(d[lane] <= bound)) continue;
      int at = n++;
      for (; at > 0 && d[lanes[at - 1]] < d[lane]; --at) lanes[at] = lanes[at - 1];
      lanes[at] = lane;
    }
    for (int k = 0; k < n; ++k)
      stack.push(quad.node[lanes[k]], quad.next[lanes[k]], d[lanes[k]], lane_flag[lanes[k] / 2]);
  }
}

Eigen::Vector3d AabbTree::closest_on_face(const Eigen::Vector3d& p, Index f) const {
  return closest_point_on_triangle(p, mesh_.positions.row(mesh_.triangles(f, 0)), mesh_.positions.row(mesh_.triangles(f, 1)),
                                   mesh_.positions.row(mesh_.triangles(f, 2)));
}

AabbTree::Hit AabbTree::closest(const Eigen::Vector3d& p, Index hint) const {
  Hit best{p, std::numeric_limits<double>::infinity(), -1};
  auto consider = [&](Index f, const Eigen::Vector3d& q) {
    if (const double d = (q - p).squaredNorm(); comes_before(d, f, best)) best = {q, d, f};
  };
  if (hint >= 0) consider(hint, closest_on_face(p, hint));
  if (nodes_.empty() || order_.empty()) return best;
  descend(p, best.squared_distance, EnterAll{}, [&](int slot, bool) {
    const Index f = order_[slot];
    if (corners_.empty()) {
      consider(f, closest_on_face(p, f));
      return false;
    }
    // The face's own box first: most faces of a leaf lie farther than the best found so far.
    const auto& t = corners_[slot];
    const Eigen::Vector3d lo = t[0].cwiseMin(t[1]).cwiseMin(t[2]), hi = t[0].cwiseMax(t[1]).cwiseMax(t[2]);
    if ((p - p.cwiseMax(lo).cwiseMin(hi)).squaredNorm() <= best.squared_distance)
      consider(f, closest_point_on_triangle(p, t[0], t[1], t[2]));
    return false;
  });
  return best;
}

void AabbTree::prepare_facing() {
  const Index n = mesh_.num_faces();
  assign_huge(normals_, static_cast<std::size_t>(n), Eigen::Vector3d(Eigen::Vector3d::Zero()));
  tbb::parallel_for(Index{0}, n, [&](Index f) {
    const Eigen::Vector3d a = mesh_.positions.row(mesh_.triangles(f, 0)), b = mesh_.positions.row(mesh_.triangles(f, 1)),
                          c = mesh_.positions.row(mesh_.triangles(f, 2));
    const Eigen::Vector3d normal = (b - a).cross(c - a);
    if (const double length = normal.norm(); length > 0) normals_[f] = normal / length;
  });
  assign_huge(cones_, nodes_.size(), Cone{Eigen::Vector3d::Zero(), -1});
  certificates_.clear();
  assign_huge(leaf_of_, static_cast<std::size_t>(n), std::int32_t{-1});
  if (order_.empty()) return;
  const int nodes = static_cast<int>(nodes_.size());
  auto set_trig = [](Cone& cone) {
    cone.cos_half = std::cos(cone.half_angle);
    cone.sin_half = std::sin(cone.half_angle);
  };
  tbb::parallel_for(0, nodes, [&](int i) {
    const Node& node = nodes_[i];
    if (node.count == 0) return;
    Cone& cone = cones_[i];
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int s = node.first; s < node.first + node.count; ++s) sum += normals_[order_[s]];
    // The widest angle from the axis is the arc cosine of the least dot product (one acos, not one a face).
    double least_dot = 2;
    for (int s = node.first; s < node.first + node.count; ++s) {
      const Eigen::Vector3d& normal = normals_[order_[s]];
      if (normal == Eigen::Vector3d::Zero()) continue;
      if (sum.norm() < 1e-6) {  // faces back to back: any direction
        cone = {normal, std::numbers::pi};
        break;
      }
      if (cone.half_angle < 0) cone = {sum.normalized(), 0.0};
      least_dot = std::min(least_dot, cone.axis.dot(normal));
    }
    if (least_dot <= 1) cone.half_angle = std::acos(std::clamp(least_dot, -1.0, 1.0)) + kAngleSlack;
    set_trig(cone);
  });
  // Children come after their parent: bottom up is back to front.
  for (int i = nodes - 1; i >= 0; --i) {
    const Node& node = nodes_[i];
    if (node.count > 0) continue;
    Cone& cone = cones_[i];
    const Cone &a = cones_[node.first], &b = cones_[node.first + 1];
    if (a.half_angle < 0 || b.half_angle < 0) {
      cone = a.half_angle < 0 ? b : a;
      continue;
    }
    const Eigen::Vector3d sum = a.axis + b.axis;
    cone.axis = sum.norm() > 1e-6 ? Eigen::Vector3d(sum.normalized()) : a.axis;
    cone.half_angle = std::min(std::numbers::pi, std::max(angle_between(cone.axis, a.axis) + a.half_angle,
                                                          angle_between(cone.axis, b.axis) + b.half_angle) + kAngleSlack);
    set_trig(cone);
  }
  std::vector<int> leaves;
  for (int i = 0; i < nodes; ++i)
    if (nodes_[i].count > 0) leaves.push_back(i);
  resize_huge(certificates_, leaves.size());
  tbb::parallel_for(std::size_t{0}, leaves.size(), [&](std::size_t i) {
    const Node& node = nodes_[leaves[i]];
    certificates_[i] = leaf_certificate(leaves[i]);
    for (int s = node.first; s < node.first + node.count; ++s) leaf_of_[order_[s]] = static_cast<std::int32_t>(i);
  });
  // The side tests, from the cones, rounded outwards.
  assign_huge(sides_, nodes_.size(), SideTest{});
  tbb::parallel_for(0, nodes, [&](int i) {
    const Cone& cone = cones_[i];
    SideTest& side = sides_[i];
    if (cone.half_angle < 0) side.sine = -2;  // no face with area: each faces neither way
    if (cone.half_angle < 0 || cone.half_angle >= std::numbers::pi / 2) return;
    side.axis = cone.axis.cast<float>();
    side.sine = std::nextafter(static_cast<float>(cone.sin_half + kSideSlack), 2.0f);
  });
  std::vector<Cone>().swap(cones_);  // only finding the certificates needs them (25 MB on 1M faces)
}

// The face closest(p) finds is the first by (distance, index). Its side is found in up to two searches:
// 1. The nearest face B, passing over nodes whose faces all face the same way as `normal` (most of what
//    lies near p, by their cones: a face turns at most the half angle h from the axis a, so less than a
//    right angle from n when a . n > sin h). If B faces the same way, so does the nearest face: were
//    the nearest face N against, no node holding N could be passed over for its side, nor for its
//    distance, which is at most B's, and the search would have found N. B is the next hint.
// 2. If B faces against, it is nearer than every face this search tested, so only a face in a node it
//    passed over can come first; all of those face the same way. They are searched, stopping at the
//    first found before B.
bool AabbTree::nearest_faces_against(const Eigen::Vector3d& p, const Eigen::Vector3d& normal,
                                     const Eigen::Vector3d& unit, Index& hint) const {
  Hit best{p, std::numeric_limits<double>::infinity(), -1};
  auto distance = [&](Index f) { return (closest_on_face(p, f) - p).squaredNorm(); };
  auto test_face = [&](Index f) {
    if (const double d = distance(f); comes_before(d, f, best)) best.squared_distance = d, best.face = f;
  };
  if (hint >= 0) test_face(hint);
  const auto same_side = [&](int i) { return sides_[i].all_same(unit); };
  descend(p, best.squared_distance, entering_unless(same_side), [&](int slot, bool) {
    test_face(order_[slot]);
    return false;
  });
  if (best.face < 0) return false;
  hint = best.face;
  if (!(normals_[best.face].dot(normal) < 0)) return false;
  // The flag: inside a node the first search passed over (leaves outside were searched already).
  bool before_b = false;
  descend(
      p, best.squared_distance, [&](int i, bool inside) { return inside || same_side(i) ? kFlagged : kPlain; },
      [&](int slot, bool inside) {
        if (!inside) return false;
        const Index f = order_[slot];
        if (comes_before(distance(f), f, best)) before_b = true, hint = f;
        return before_b;
      });
  return !before_b;
}

AabbTree::Hit AabbTree::closest_facing(const Eigen::Vector3d& p, const Eigen::Vector3d& normal) const {
  Hit best{p, std::numeric_limits<double>::infinity(), -1};
  const double length = normal.norm();
  if (normals_.empty() || order_.empty() || !(length > 0)) return best;
  const Eigen::Vector3d against = -normal / length;
  // (Nodes whose faces all face the other way are passed over.)
  const auto facing_away = [&](int i) { return sides_[i].all_same(against); };
  descend(p, best.squared_distance, entering_unless(facing_away), [&](int slot, bool) {
    const Index f = order_[slot];
    if (!(normals_[f].dot(normal) > 0)) return false;
    const Eigen::Vector3d q = closest_on_face(p, f);
    if (const double d = (q - p).squaredNorm(); comes_before(d, f, best)) best = {q, d, f};
    return false;
  });
  return best;
}

AabbTree::Certificate AabbTree::leaf_certificate(int leaf) const {
  const Node& node = nodes_[leaf];
  const Cone& cone = cones_[leaf];
  // A normal n may skip when angle(axis, n) < pi/2 - turn, that is axis . n > sin(turn) |n|. The
  // stored axis is the cone's rounded to floats, off by up to about 1e-7 in any dot product with a
  // unit vector: the margin on the sine covers that (a margin on the angle would not, where the
  // sine is flat).
  const double turn = cone.half_angle + kTurn;
  Certificate out;
  if (cone.half_angle < 0 || turn >= std::numbers::pi / 2) return out;  // no skipping here
  out.axis = cone.axis.cast<float>();
  out.min_dot = std::nextafter(static_cast<float>(std::sin(turn) + 1e-6), 2.0f);
  // The anchor: the centroid of the leaf's first face with area, in floats, so a little off the face;
  // the clearance is measured from it, less that little.
  for (int s = node.first; s < node.first + node.count; ++s) {
    const Index f = order_[s];
    if (normals_[f] == Eigen::Vector3d::Zero()) continue;
    const Eigen::Vector3d a = mesh_.positions.row(mesh_.triangles(f, 0)), b = mesh_.positions.row(mesh_.triangles(f, 1)),
                          c = mesh_.positions.row(mesh_.triangles(f, 2));
    out.anchor = ((a + b + c) / 3.0).cast<float>();
    const Eigen::Vector3d anchor = out.anchor.cast<double>();
    const double off_surface = (closest_point_on_triangle(anchor, a, b, c) - anchor).norm();
    const double reach = kReach * 0.5 * node.box.diagonal().norm();
    const double clearance = distance_to_turned(anchor, cone.axis, cone.half_angle + kTurn, reach) - off_surface;
    out.clearance = static_cast<float>(clearance);
    if (out.clearance > clearance) out.clearance = std::nextafter(out.clearance, -1.0f);
    break;
  }
  return out;
}

double AabbTree::distance_to_turned(const Eigen::Vector3d& p, const Eigen::Vector3d& axis, double angle,
                                    double limit) const {
  // In cosines, with a margin: a face near the limit counts as turned, and a node is passed over only
  // when none of its faces can be.
  const double cos_angle = std::cos(angle), sin_angle = std::sin(angle);
  double best = limit * limit;
  auto none_turned = [&](int i) {
    const Cone& cone = cones_[i];
    if (cone.half_angle < 0) return true;  // no face with area
    // angle(axis, cone axis) + half angle <= angle, as cos(angle - half angle) <= axis . cone axis
    return cone.half_angle <= angle &&
           axis.dot(cone.axis) >= cos_angle * cone.cos_half + sin_angle * cone.sin_half + kCosineSlack;
  };
  descend(p, best, entering_unless(none_turned), [&](int slot, bool) {
    const Index f = order_[slot];
    if (normals_[f] == Eigen::Vector3d::Zero() || axis.dot(normals_[f]) >= cos_angle + kCosineSlack) return false;
    best = std::min(best, (closest_on_face(p, f) - p).squaredNorm());
    return false;
  });
  return std::sqrt(best);
}

bool AabbTree::facing_against(const Eigen::Vector3d& p, const Eigen::Vector3d& normal, Index& hint,
                              const Certificate* hint_certificate) const {
  const double length = normal.norm();
  if (!(length > 0)) return false;
  // Let a be the hint leaf's anchor, e its distance off the surface, g the face nearest p. Then
  // |p - g| <= |p - a| + e, and g comes within 2 |p - a| + e of a: inside the clearance, g turns less
  // than cone + kTurn from the axis, so less than a right angle from `normal`.
  if (hint >= 0) {
    const Certificate& c = hint_certificate ? *hint_certificate : certificate(hint);
    if (c.settles(p, normal)) return false;
    // The hint face's own distance is a bound on the nearest face's: where p lies nearer the surface
    // than the anchor, it reaches further (a large face's centroid far from its leaf's anchor).
    if (c.turns_little(normal)) {
      if (c.settles_within(p, normal, (closest_on_face(p, hint) - p).norm())) return false;
    }
  }
  // Without a hint, the nearest face itself: nearest_faces_against() may return a face far from p
  // (the nearest outside the nodes it passed over), and as the next hint that would never settle.
  if (hint >= 0 && !sides_.empty()) return nearest_faces_against(p, normal, normal / length, hint);
  const Hit hit = closest(p, hint);
  hint = hit.face;
  return hit.face >= 0 && face_normal(hit.face).dot(normal) < 0;
}

bool AabbTree::facing_against_all_nearest(const Eigen::Vector3d& p, const Eigen::Vector3d& normal, Index& hint) const {
  // Ties are rare: the second search runs only where the first found the nearest face against.
  return facing_against(p, normal, hint) && !faces_way_within(p, normal, closest(p, hint).squared_distance);
}

Eigen::Vector3d AabbTree::face_normal(Index f) const {
  if (!normals_.empty()) return normals_[f];
  const Eigen::Vector3d a = mesh_.positions.row(mesh_.triangles(f, 0)), b = mesh_.positions.row(mesh_.triangles(f, 1)),
                        c = mesh_.positions.row(mesh_.triangles(f, 2));
  return (b - a).cross(c - a);
}

bool AabbTree::faces_way_within(const Eigen::Vector3d& p, const Eigen::Vector3d& normal, double squared_distance) const {
  // Equal distances computed from different corners differ by a few roundings of the coordinates.
  const double slack = kTieSlack * std::max(extent_, p.cwiseAbs().maxCoeff());
  const double reach = std::sqrt(squared_distance) + slack, bound = reach * reach;
  bool found = false;
  const auto visit = [&](int slot, bool) {
    const Index f = order_[slot];
    found = face_normal(f).dot(normal) > 0 && (closest_on_face(p, f) - p).squaredNorm() <= bound;
    return found;
  };
  if (sides_.empty()) {
    descend(p, bound, EnterAll{}, visit);
  } else {
    const Eigen::Vector3d against = -normal.normalized();
    descend(p, bound, entering_unless([&](int i) { return sides_[i].all_same(against); }), visit);
  }
  return found;
}

}  // namespace lodkit::detail
