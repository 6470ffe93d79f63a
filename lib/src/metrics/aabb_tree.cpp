#include "metrics/aabb_tree.h"

#include <algorithm>
#include <limits>

#include "core/geometry.h"

namespace lodkit::detail {

namespace {
constexpr int kLeafSize = 4;

double box_squared_distance(const Eigen::AlignedBox3d& box, const Eigen::Vector3d& p) {
  return (p - p.cwiseMax(box.min()).cwiseMin(box.max())).squaredNorm();
}
}  // namespace

AabbTree::AabbTree(const Mesh& mesh) : mesh_(mesh) {
  const Index n = mesh.num_faces();
  order_.resize(static_cast<std::size_t>(n));
  std::vector<Eigen::Vector3d> centroids(static_cast<std::size_t>(n));
  for (Index f = 0; f < n; ++f) {
    order_[f] = f;
    centroids[f] = (mesh.positions.row(mesh.triangles(f, 0)) + mesh.positions.row(mesh.triangles(f, 1)) +
                    mesh.positions.row(mesh.triangles(f, 2))).transpose() / 3.0;
  }
  nodes_.reserve(static_cast<std::size_t>(2 * n / kLeafSize + 2));
  nodes_.push_back({});
  if (n > 0) build(0, 0, static_cast<int>(n), centroids);
}

void AabbTree::build(int node, int begin, int end, const std::vector<Eigen::Vector3d>& centroids) {
  Eigen::AlignedBox3d box, centre_box;
  for (int i = begin; i < end; ++i) {
    const Index f = order_[i];
    for (int k = 0; k < 3; ++k) box.extend(mesh_.positions.row(mesh_.triangles(f, k)).transpose());
    centre_box.extend(centroids[f]);
  }
  nodes_[node].box = box;
  if (end - begin <= kLeafSize) {
    nodes_[node].first = begin;
    nodes_[node].count = end - begin;
    return;
  }
  int axis;
  centre_box.diagonal().maxCoeff(&axis);
  const int mid = (begin + end) / 2;
  std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
                   [&](Index a, Index b) { return centroids[a][axis] < centroids[b][axis]; });
  const int left = static_cast<int>(nodes_.size());
  nodes_.push_back({});
  nodes_.push_back({});
  nodes_[node].first = left;
  nodes_[node].count = 0;
  build(left, begin, mid, centroids);
  build(left + 1, mid, end, centroids);
}

AabbTree::Hit AabbTree::closest(const Eigen::Vector3d& p, Index hint) const {
  Hit best{p, std::numeric_limits<double>::infinity(), -1};
  auto test_face = [&](Index f) {
    const Eigen::Vector3d q = closest_point_on_triangle(p, mesh_.positions.row(mesh_.triangles(f, 0)),
                                                        mesh_.positions.row(mesh_.triangles(f, 1)),
                                                        mesh_.positions.row(mesh_.triangles(f, 2)));
    const double d = (q - p).squaredNorm();
    if (d < best.squared_distance || (d == best.squared_distance && f < best.face)) best = {q, d, f};
  };
  if (hint >= 0) test_face(hint);
  if (nodes_.empty() || order_.empty()) return best;
  int stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[stack[--top]];
    if (box_squared_distance(node.box, p) > best.squared_distance) continue;
    if (node.count > 0) {
      for (int i = node.first; i < node.first + node.count; ++i) test_face(order_[i]);
      continue;
    }
    // Visit the nearer child first (pushed last).
    const int a = node.first, b = node.first + 1;
    const double da = box_squared_distance(nodes_[a].box, p), db = box_squared_distance(nodes_[b].box, p);
    if (da < db) {
      stack[top++] = b;
      stack[top++] = a;
    } else {
      stack[top++] = a;
      stack[top++] = b;
    }
  }
  return best;
}

}  // namespace lodkit::detail
