#include "core/uv_charts.h"

#include "core/geometry.h"

namespace lodkit::detail {

std::vector<Index> uv_charts(const Mesh& mesh) {
  const Index nf = mesh.num_faces();
  const Eigen::VectorX<Index> point = position_classes(mesh);
  UnionFind charts(static_cast<std::size_t>(nf));
  unite_across_edges(
      nf, [&](Index f, int k) { return point[mesh.triangles(f, k)]; }, [](Index) { return false; },
      [&](Index f, int k, Index g, int j) {
        return mesh.attributes.uvs.row(mesh.triangles(f, k)) == mesh.attributes.uvs.row(mesh.triangles(g, j));
      },
      charts);
  std::vector<Index> chart(static_cast<std::size_t>(nf));
  std::unordered_map<int, Index> number;
  for (Index f = 0; f < nf; ++f) chart[f] = number.try_emplace(charts.find(int(f)), Index(number.size())).first->second;
  return chart;
}

void ChartPartners::settle() {
  best_from_.clear(), best_to_.clear();
  for (const auto& [pair, area] : votes_) {
    auto& f = best_from_[pair.first];
    if (area > f.first) f = {area, pair.second};
    auto& t = best_to_[pair.second];
    if (area > t.first) t = {area, pair.first};
  }
}

bool ChartPartners::partners(Index from_chart, Index to_chart) const {
  const auto f = best_from_.find(from_chart);
  if (f != best_from_.end() && f->second.second == to_chart) return true;
  const auto t = best_to_.find(to_chart);
  return t != best_to_.end() && t->second.second == from_chart;
}

double longest_uv_side2(const Mesh& m, Index f) {
  double longest = 0;
  for (int k = 0; k < 3; ++k)
    longest = std::max(longest, (m.attributes.uvs.row(m.triangles(f, k)) - m.attributes.uvs.row(m.triangles(f, (k + 1) % 3)))
                                    .cast<double>()
                                    .squaredNorm());
  return longest;
}

bool near_uv_triangle(const Mesh& m, Index f, const Eigen::Vector2d& uv, double reach2) {
  Eigen::Vector3d c[3];
  for (int k = 0; k < 3; ++k) c[k] << m.attributes.uvs.row(m.triangles(f, k)).transpose().cast<double>(), 0.0;
  const Eigen::Vector3d x(uv.x(), uv.y(), 0.0);
  return (closest_point_on_triangle(x, c[0], c[1], c[2]) - x).squaredNorm() <= reach2;
}

}  // namespace lodkit::detail
