#pragma once
// One entry point for every simplification method the benchmarks compare: lodkit's (quadric, hoppe,
// edge-length, schroeder, pm) and the peers' (meshopt, meshopt-sloppy, openmesh, cgal).
#include <string>
#include <vector>

#include "peers/peers.h"

namespace lodkit::bench {

/// Every method name, lodkit's first.
const std::vector<std::string>& all_methods();

/// Simplifies `mesh` to `target` faces with `method`; the time is the simplification call only
/// (for `pm`: building the progressive mesh plus extracting the level). lodkit's edge-collapse methods
/// also take the suffixes "-inverted-allow|avoid|refuse" (SimplifyOptions::inverted_faces; not among
/// all_methods()), and "-no-inverted" for "-inverted-refuse".
/// Throws on an unknown name.
PeerRun run_method(const std::string& method, const Mesh& mesh, Index target);

/// "a,b,c" -> {"a", "b", "c"} (command-line lists).
std::vector<std::string> split_list(const std::string& text);

}  // namespace lodkit::bench
