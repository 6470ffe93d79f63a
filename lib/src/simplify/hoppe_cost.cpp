// Placeholder until the energy model lands: Hoppe's method is scored like the quadric.
#include "simplify/engine.h"

namespace lodkit::detail {
std::unique_ptr<CostModel> make_hoppe_cost(const SimplifyOptions& options, const EngineState&) {
  return make_quadric_cost(options);
}
}  // namespace lodkit::detail
