// The naive priority |v1 - v2| / |n1 . n2| (short edges between vertices whose normals agree go
// first), with the vertex placed at an endpoint or the midpoint. It ignores how far the surface moves,
// which is why it fails at high reductions; lodkit keeps it to show that.
#include "simplify/engine.h"

namespace lodkit::detail {
namespace {

Eigen::Vector3d vertex_normal(const EngineState& s, Index p) {
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  for (Index f : s.faces_of(p)) {
    const Eigen::Vector3d a = s.position[s.corner_point(f, 0)], b = s.position[s.corner_point(f, 1)],
                          c = s.position[s.corner_point(f, 2)];
    n += (b - a).cross(c - a);
  }
  const double len = n.norm();
  return len > 0 ? Eigen::Vector3d(n / len) : n;
}

class EdgeLengthCost final : public CostModel {
 public:
  explicit EdgeLengthCost(Placement placement) : placement_(placement) {}

  bool score(const EngineState& s, const Probe&, Index u, Index v, Freedom freedom, Candidate& out) override {
    const Eigen::Vector3d& pu = s.position[u];
    const Eigen::Vector3d& pv = s.position[v];
    const double agreement = std::abs(vertex_normal(s, u).dot(vertex_normal(s, v)));
    out.cost = (pu - pv).norm() / std::max(agreement, 1e-3);
    // "Optimal" has no meaning for this cost: it places at the midpoint, as the method is described.
    out.position = freedom == Freedom::Free && placement_ != Placement::Endpoint ? Eigen::Vector3d(0.5 * (pu + pv)) : pv;
    out.error = quadric_distance(s.quadric[u] + s.quadric[v], out.position);
    return true;
  }

 private:
  Placement placement_;
};

}  // namespace

std::unique_ptr<CostModel> make_edge_length_cost(const SimplifyOptions& options) {
  return std::make_unique<EdgeLengthCost>(options.placement);
}

}  // namespace lodkit::detail
