// Building the AabbTree: its nodes (surface-area or median splits, the top split side by side and the
// parts below it built side by side) and the quads its searches walk.
#include <fmt/format.h>
#include <lodkit/error.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <array>
#include <limits>

#include "core/huge_pages.h"
#include "metrics/aabb_tree.h"

namespace lodkit::detail {

namespace {
constexpr int kParallelFaces = 1 << 14;  // subtrees larger than this are built side by side
constexpr int kLeafSize = AabbTree::kLeafSize;
// Whether entries carry their face's box (surface-area splits) or the centroid alone (median splits).
template <typename Entry>
constexpr bool kBoxed = requires(Entry e) { e.lo; };

// Nodes of a subtree over n faces and over n + 1 with median splits, which depends on n alone. (Halves
// differ by one at most, so two counts per level carry the recursion.)
std::pair<int, int> subtree_nodes_pair(int n) {
  if (n + 1 <= kLeafSize) return {1, 1};
  if (n == kLeafSize) return {1, 3};
  const auto [a, b] = subtree_nodes_pair(n / 2);
  return n % 2 == 0 ? std::pair{1 + 2 * a, 1 + a + b} : std::pair{1 + a + b, 1 + 2 * b};
}
int subtree_nodes(int n) { return subtree_nodes_pair(n).first; }

// Where to split slots [begin, end) of `entries`, reordering them: along the axis of the centroids'
// longest extent, at the median; or, for boxed entries, at the boundary of kBins equal bins that
// minimises the surface area heuristic (each side's box area times its faces). On CAD meshes, where
// long thin faces lie among small ones, the latter halves the nodes a query visits; on scans it saves
// about a tenth (the log's session 39). At the median where the bins cannot split the faces.
constexpr int kBins = 16;

double box_area(const Eigen::AlignedBox3f& box) {
  if (box.isEmpty()) return 0.0;
  const Eigen::Vector3d d = box.diagonal().cast<double>();
  return d.x() * d.y() + d.y() * d.z() + d.z() * d.x();
}

// A centroid's bin of kBins along `axis`, from `low` at `scale` bins a unit.
int bin_of(const Eigen::Vector3f& centre, int axis, float low, float scale) {
  // Clamped before the cast: across a float's whole range the product is infinite or NaN, and
  // converting that to int is undefined.
  const float at = (centre[axis] - low) * scale;
  if (!(at > 0)) return 0;
  return at >= kBins - 1 ? kBins - 1 : static_cast<int>(at);
}

// The bin below which the surface area heuristic splits, or -1 where no bin boundary splits the faces.
template <typename Entry>
int surface_area_bin(const std::vector<Entry>& entries, int begin, int end, int axis, float low, float scale) {
  std::array<Eigen::AlignedBox3f, kBins> boxes;
  std::array<int, kBins> counts{};
  for (int i = begin; i < end; ++i) {
    const int k = bin_of(entries[i].centre, axis, low, scale);
    boxes[k].extend(entries[i].lo), boxes[k].extend(entries[i].hi);
    ++counts[k];
  }
  std::array<double, kBins> below_cost{};  // below_cost[k]: the bins under k as one side (0 faces: -1)
  Eigen::AlignedBox3f side;
  int faces = 0;
  for (int k = 1; k < kBins; ++k) {
    side.extend(boxes[k - 1]), faces += counts[k - 1];
    below_cost[k] = faces > 0 ? box_area(side) * faces : -1;
  }
  side.setEmpty(), faces = 0;
  double best = std::numeric_limits<double>::infinity();
  int best_bin = -1;
  for (int k = kBins - 1; k > 0; --k) {
    side.extend(boxes[k]), faces += counts[k];
    if (faces == 0 || below_cost[k] < 0) continue;
    if (const double cost = below_cost[k] + box_area(side) * faces; cost < best) best = cost, best_bin = k;
  }
  return best_bin;
}

template <typename Entry>
int split(std::vector<Entry>& entries, int begin, int end, int depth) {
  Eigen::AlignedBox3f centre_box;
  for (int i = begin; i < end; ++i) centre_box.extend(entries[i].centre);
  int axis;
  const float extent = centre_box.diagonal().maxCoeff(&axis);
  if constexpr (kBoxed<Entry>) {
    if (extent > 0 && depth < AabbTree::kSurfaceAreaDepth) {
      const float low = centre_box.min()[axis], scale = kBins / extent;
      if (const int bin = surface_area_bin(entries, begin, end, axis, low, scale); bin >= 0)
        return static_cast<int>(std::partition(entries.begin() + begin, entries.begin() + end,
                                               [&](const Entry& e) { return bin_of(e.centre, axis, low, scale) < bin; }) -
                                entries.begin());
    }
  }
  const int mid = (begin + end) / 2;
  std::nth_element(entries.begin() + begin, entries.begin() + mid, entries.begin() + end,
                   [&](const Entry& a, const Entry& b) { return a.centre[axis] < b.centre[axis]; });
  return mid;
}
}  // namespace

AabbTree::AabbTree(const Mesh& mesh, const Options& options) : mesh_(mesh) {
  const Index n = mesh.num_faces();
  if (n > kMostFaces) throw Error(fmt::format("{} faces: the closest-point search takes at most {}", n, kMostFaces));
  resize_huge(order_, static_cast<std::size_t>(n));
  auto centroid = [&](Index f) {
    return Eigen::Vector3d((mesh.positions.row(mesh.triangles(f, 0)) + mesh.positions.row(mesh.triangles(f, 1)) +
                            mesh.positions.row(mesh.triangles(f, 2))).transpose() / 3.0);
  };
  nodes_.emplace_back();
  if (options.surface_area_splits) {
    auto boxed = huge_vector<Boxed>(static_cast<std::size_t>(n));
    tbb::parallel_for(Index{0}, n, [&](Index f) {
      const Eigen::Vector3d a = mesh.positions.row(mesh.triangles(f, 0)), b = mesh.positions.row(mesh.triangles(f, 1)),
                            c = mesh.positions.row(mesh.triangles(f, 2));
      boxed[f].centre = centroid(f).cast<float>(), boxed[f].face = f;
      boxed[f].lo = a.cwiseMin(b).cwiseMin(c).cast<float>(), boxed[f].hi = a.cwiseMax(b).cwiseMax(c).cast<float>();
    });
    build_tree(boxed);
  } else {
    auto centred = huge_vector<Centred>(static_cast<std::size_t>(n));
    tbb::parallel_for(Index{0}, n, [&](Index f) { centred[f] = {centroid(f).cast<float>(), f}; });
    build_tree(centred);
  }
  if (n > 0 && nodes_[0].count == 0) {
    reserve_huge(quads_, nodes_.size() / 3 + 1);
    build_quad(0);
  }
  if (options.copy_corners) resize_huge(corners_, static_cast<std::size_t>(n));
  read_positions();
}

void AabbTree::read_positions() {
  if (!nodes_.empty() && !order_.empty())
    extent_ = std::max(nodes_[0].box.min().cwiseAbs().maxCoeff(), nodes_[0].box.max().cwiseAbs().maxCoeff());
  tbb::parallel_for(std::size_t{0}, corners_.size(), [&](std::size_t i) {
    for (int k = 0; k < 3; ++k) corners_[i][k] = mesh_.positions.row(mesh_.triangles(order_[i], k)).transpose();
  });
}

void AabbTree::extend_by_face(Eigen::AlignedBox3d& box, Index f) const {
  for (int k = 0; k < 3; ++k) box.extend(mesh_.positions.row(mesh_.triangles(f, k)).transpose());
}

// The tree's top (nodes over more than kParallelFaces faces), split side by side, and the parts below
// it, built side by side: straight into nodes_ where a part's size is known in advance (median splits),
// else into a list of its own first, then moved in.
struct AabbTree::Part {
  int begin, end;
  std::unique_ptr<Part> child[2];  // a node of the top: its halves
  int pair = -1;                   // a node of the top: its children's index in nodes_
  int depth = 0;                   // its root's level
  int root = -1, next = -1;        // a part: its root's index in nodes_, and where its other nodes start
  std::size_t size = 0;            // a part: its nodes
  std::vector<Node> nodes;         // a part built on its own: its nodes, root first
};

template <typename Entry>
void AabbTree::build_tree(std::vector<Entry>& entries) {
  constexpr bool sized = !kBoxed<Entry>;  // median parts' node counts are known in advance
  const int n = static_cast<int>(entries.size());
  if (n == 0) return;
  const std::unique_ptr<Part> top = split_top(0, n, 0, entries);
  std::vector<Part*> parts;
  auto collect = [&](auto& self, Part& part) -> void {
    if (!part.child[0]) return parts.push_back(&part);
    self(self, *part.child[0]), self(self, *part.child[1]);
  };
  collect(collect, *top);
  tbb::parallel_for(std::size_t{0}, parts.size(), [&](std::size_t i) {
    Part& part = *parts[i];
    if (sized) {
      part.size = static_cast<std::size_t>(subtree_nodes(part.end - part.begin));
      return;
    }
    part.nodes.resize(static_cast<std::size_t>(2 * (part.end - part.begin)));  // never more
    int next = 1;
    build(part.nodes, 0, next, part.begin, part.end, part.depth, entries);
    part.nodes.resize(static_cast<std::size_t>(next));
    part.nodes.shrink_to_fit();
    part.size = part.nodes.size();
  });
  // Each node of the top has its children's pair, and each part its root there and its other nodes after.
  int total = 1;
  auto place = [&](auto& self, Part& part, int at) -> void {
    if (!part.child[0]) {
      part.root = at, part.next = total, total += static_cast<int>(part.size) - 1;
      return;
    }
    part.pair = total;
    total += 2;
    self(self, *part.child[0], part.pair), self(self, *part.child[1], part.pair + 1);
  };
  place(place, *top, 0);
  assign_huge(nodes_, static_cast<std::size_t>(total), Node{});
  tbb::parallel_for(std::size_t{0}, parts.size(), [&](std::size_t i) {
    Part& part = *parts[i];
    if (sized) {
      int next = part.next;
      build(nodes_, part.root, next, part.begin, part.end, part.depth, entries);
      return;
    }
    // Node j > 0 of the part's list lands at shift + j, its root at part.root.
    const int shift = part.next - 1;
    for (std::size_t j = 0; j < part.nodes.size(); ++j) {
      Node& moved = nodes_[j == 0 ? part.root : shift + static_cast<int>(j)];
      moved = part.nodes[j];
      if (moved.count == 0) moved.first += shift;
    }
    std::vector<Node>().swap(part.nodes);
  });
  auto join = [&](auto& self, Part& part, int at) -> void {  // the top's nodes, once all below are in
    if (!part.child[0]) return;
    self(self, *part.child[0], part.pair), self(self, *part.child[1], part.pair + 1);
    nodes_[at].first = part.pair, nodes_[at].count = 0;
    nodes_[at].box = nodes_[part.pair].box.merged(nodes_[part.pair + 1].box);
  };
  join(join, *top, 0);
  tbb::parallel_for(0, n, [&](int i) { order_[i] = entries[i].face; });
  std::vector<Entry>().swap(entries);  // before the quads are made: not both at the peak
}

template <typename Entry>
std::unique_ptr<AabbTree::Part> AabbTree::split_top(int begin, int end, int depth, std::vector<Entry>& entries) const {
  auto part = std::make_unique<Part>();
  part->begin = begin, part->end = end, part->depth = depth;
  if (end - begin <= kParallelFaces) return part;
  const int mid = split(entries, begin, end, depth);
  tbb::parallel_invoke([&] { part->child[0] = split_top(begin, mid, depth + 1, entries); },
                       [&] { part->child[1] = split_top(mid, end, depth + 1, entries); });
  return part;
}

template <typename Entry>
void AabbTree::build(std::vector<Node>& nodes, int at, int& next, int begin, int end, int depth,
                     std::vector<Entry>& entries) const {
  if (end - begin <= kLeafSize) {
    Node& leaf = nodes[at];
    for (int i = begin; i < end; ++i) extend_by_face(leaf.box, entries[i].face);
    leaf.first = begin;
    leaf.count = end - begin;
    return;
  }
  const int mid = split(entries, begin, end, depth);
  // The children are a pair, each subtree's other nodes after both: children come after their parent.
  const int left = next;
  next += 2;
  build(nodes, left, next, begin, mid, depth + 1, entries);
  build(nodes, left + 1, next, mid, end, depth + 1, entries);
  nodes[at].first = left;
  nodes[at].count = 0;
  nodes[at].box = nodes[left].box.merged(nodes[left + 1].box);
}

int AabbTree::build_quad(int node) {
  const int index = static_cast<int>(quads_.size());
  quads_.emplace_back();
  Quad quad;
  for (int axis = 0; axis < 3; ++axis)
    for (int lane = 0; lane < 4; ++lane)
      quad.lo[axis][lane] = std::numeric_limits<float>::infinity(), quad.hi[axis][lane] = -std::numeric_limits<float>::infinity();
  std::fill_n(quad.node, 4, -1);
  std::fill_n(quad.next, 4, -1);
  auto set_lane = [&](int lane, int i) {
    set_lane_box(quad, lane, i);
    quad.node[lane] = i;
    if (nodes_[i].count > 0) quad.next[lane] = leaf_code(nodes_[i]);
  };
  for (int side = 0; side < 2; ++side) {
    const int child = nodes_[node].first + side;
    if (nodes_[child].count > 0) {
      set_lane(2 * side, child);
      continue;
    }
    for (int k = 0; k < 2; ++k) set_lane(2 * side + k, nodes_[child].first + k);
  }
  for (int lane = 0; lane < 4; ++lane)
    if (quad.node[lane] >= 0 && nodes_[quad.node[lane]].count == 0) quad.next[lane] = build_quad(quad.node[lane]);
  quads_[index] = quad;
  return index;
}

void AabbTree::set_lane_box(Quad& quad, int lane, int node) const {
  const Eigen::AlignedBox3d& box = nodes_[node].box;
  for (int axis = 0; axis < 3; ++axis) {
    float lo = static_cast<float>(box.min()[axis]), hi = static_cast<float>(box.max()[axis]);
    if (lo > box.min()[axis]) lo = std::nextafter(lo, -std::numeric_limits<float>::infinity());
    if (hi < box.max()[axis]) hi = std::nextafter(hi, std::numeric_limits<float>::infinity());
    quad.lo[axis][lane] = lo, quad.hi[axis][lane] = hi;
  }
}

void AabbTree::refit() {
  if (!normals_.empty()) throw Error("AabbTree::refit(): the tree is readied for facing checks, which it would not refit");
  if (nodes_.empty() || order_.empty()) return;
  refit_node(0);
  for (Quad& quad : quads_)
    for (int lane = 0; lane < 4; ++lane)
      if (quad.node[lane] >= 0) set_lane_box(quad, lane, quad.node[lane]);
  read_positions();
}

void AabbTree::refit_node(int node) {
  Node& n = nodes_[node];
  if (n.count > 0) {
    n.box.setEmpty();
    for (int i = n.first; i < n.first + n.count; ++i) extend_by_face(n.box, order_[i]);
    return;
  }
  refit_node(n.first);
  refit_node(n.first + 1);
  n.box = nodes_[n.first].box.merged(nodes_[n.first + 1].box);
}

}  // namespace lodkit::detail
