#pragma once
// The stability suite: meshes built to make simplifiers fail (sharp features, thin parts, holes,
// non-manifold edges, unwelded soups, slivers, noise, huge offsets, tiny scales, UV seams). Shared by
// the tests (lodkit's default method must stay valid on every one) and by
// bench/stability_bench.cpp (where every method, lodkit's and the peers', is charted on them).
#include <lodkit/mesh.h>

#include <string>
#include <vector>

namespace lodkit::test {

struct StabilityCase {
  std::string name;
  Mesh mesh;
};

std::vector<StabilityCase> stability_suite();

}  // namespace lodkit::test
