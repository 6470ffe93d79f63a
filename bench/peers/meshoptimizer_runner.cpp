#include <chrono>
#include <meshoptimizer.h>
#include <vector>

#include "peers/peers.h"

namespace lodkit::bench {

PeerRun run_meshoptimizer(const Mesh& mesh, Index target_faces, bool sloppy) {
  std::vector<float> xyz(static_cast<std::size_t>(3 * mesh.num_vertices()));
  for (Index v = 0; v < mesh.num_vertices(); ++v)
    for (int k = 0; k < 3; ++k) xyz[3 * v + k] = static_cast<float>(mesh.positions(v, k));
  std::vector<unsigned> indices(static_cast<std::size_t>(3 * mesh.num_faces()));
  for (Index f = 0; f < mesh.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) indices[3 * f + k] = static_cast<unsigned>(mesh.triangles(f, k));
  std::vector<unsigned> out(indices.size());
  const auto t0 = std::chrono::steady_clock::now();
  const std::size_t target = 3 * static_cast<std::size_t>(target_faces);
  const std::size_t n = sloppy ? meshopt_simplifySloppy(out.data(), indices.data(), indices.size(), xyz.data(),
                                                        xyz.size() / 3, 12, target, 1e30f, nullptr)
                               : meshopt_simplify(out.data(), indices.data(), indices.size(), xyz.data(),
                                                  xyz.size() / 3, 12, target, 1e30f, 0, nullptr);
  PeerRun run;
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  // Keep only the vertices the result uses.
  std::vector<Index> remap(xyz.size() / 3, -1);
  Index nv = 0;
  for (std::size_t i = 0; i < n; ++i)
    if (remap[out[i]] < 0) remap[out[i]] = nv++;
  run.mesh.positions.resize(nv, 3);
  run.vertex_origin.resize(static_cast<std::size_t>(nv));
  for (std::size_t v = 0; v < remap.size(); ++v)
    if (remap[v] >= 0) {
      run.mesh.positions.row(remap[v]) = mesh.positions.row(static_cast<Index>(v));
      run.vertex_origin[static_cast<std::size_t>(remap[v])] = static_cast<Index>(v);
    }
  run.mesh.triangles.resize(static_cast<Index>(n / 3), 3);
  for (std::size_t i = 0; i < n; ++i) run.mesh.triangles(static_cast<Index>(i / 3), static_cast<int>(i % 3)) = remap[out[i]];
  return run;
}

}  // namespace lodkit::bench
