// CSG benchmark: lodkit's corefinement booleans against CGAL's Nef_polyhedron_3 on the same inputs.
// Each run is a child process with a time limit (Nef can take minutes); every case runs `--runs`
// times per method and reports the median time (a 2-core VM's timings wander by 10-20 %).
// Prints a Markdown table.
//
//   lodkit_bench_csg [--limit SECONDS] [--runs N]
#include <lodkit/csg.h>
#include <lodkit/inspect.h>
#include <lodkit/io.h>
#include <lodkit/primitives.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fmt/format.h>
#include <functional>
#include <string>
#include <unistd.h>

#include "child_process.h"
#include "peers/peers.h"

using namespace lodkit;

namespace {

struct Timed {
  bool ok = false, timed_out = false;
  double seconds = 0, peak_mib = 0;
  long faces = 0;
  double volume = 0;
};

Timed run_in_child(const std::function<Mesh()>& work, int limit_seconds) {
  const bench::ChildRun run = bench::run_in_child(
      [&] {
        const auto t0 = std::chrono::steady_clock::now();
        const Mesh m = work();
        return std::vector<double>{std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(),
                                   double(m.num_faces()), inspect(m).volume.value_or(0.0)};
      },
      3, limit_seconds);
  Timed t;
  t.ok = run.ok();
  t.timed_out = run.end == bench::ChildRun::End::TimedOut;
  t.peak_mib = run.peak_mib;
  if (t.ok) t.seconds = run.reply[0], t.faces = static_cast<long>(run.reply[1]), t.volume = run.reply[2];
  return t;
}

Mesh moved(Mesh m, double x, double y, double z) {
  m.positions.rowwise() += Eigen::RowVector3d(x, y, z);
  return m;
}

// A UV sphere with 2 * segments * (rings - 1) triangles.
Mesh sphere_with(int segments) { return make_uv_sphere({.radius = 1.0, .segments = segments, .rings = segments / 2 + 1}); }

// 50 primitives: a plate minus a 7 x 7 grid of cylinders.
std::vector<Mesh> plate_with_49_holes() {
  std::vector<Mesh> parts{make_box({.size = {8, 8, 0.5}})};
  for (int i = 0; i < 7; ++i)
    for (int j = 0; j < 7; ++j)
      parts.push_back(moved(make_cylinder({.radius = 0.3, .height = 1, .segments = 32}), -3 + i, -3 + j, 0));
  return parts;
}

}  // namespace

int main(int argc, char** argv) {
  int limit = 600, runs = 3;
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]) == "--limit" && i + 1 < argc) limit = std::stoi(argv[++i]);
    if (std::string(argv[i]) == "--runs" && i + 1 < argc) runs = std::max(1, std::stoi(argv[++i]));
  }
  // The median run by time (the largest peak memory of all runs).
  auto median_of = [&](const std::function<Mesh()>& work) {
    std::vector<Timed> all;
    for (int r = 0; r < runs; ++r) {
      all.push_back(run_in_child(work, limit));
      if (!all.back().ok) return all.back();  // failed or timed out: no point repeating
    }
    std::sort(all.begin(), all.end(), [](const Timed& a, const Timed& b) { return a.seconds < b.seconds; });
    Timed m = all[all.size() / 2];
    for (const Timed& t : all) m.peak_mib = std::max(m.peak_mib, t.peak_mib);
    return m;
  };
  fmt::print("| case | method | time s | peak MiB | faces | volume | Nef / lodkit |\n|---|---|---:|---:|---:|---:|---:|\n");
  auto row = [&](const std::string& name, const std::vector<Mesh>& operands, BooleanOp op, const CsgNode* as_tree = nullptr) {
    const Timed lk = median_of([&] {
      if (as_tree) return evaluate(*as_tree, {.tolerance = circle_chordal_error(0.3, 32)}).mesh;
      // The same operands as a tree: lodkit's evaluator (checks once, reduces pairwise).
      CsgNode tree;
      tree.kind = CsgNode::Kind::Operation;
      tree.op = op;
      for (std::size_t i = 0; i < operands.size(); ++i) {
        CsgNode leaf;
        leaf.kind = CsgNode::Kind::MeshFile;
        leaf.mesh = fmt::format("/tmp/lodkit-bench-csg-{}-{}.ply", getpid(), i);
        write_mesh(operands[i], leaf.mesh);
        tree.children.push_back(leaf);
      }
      Mesh m = evaluate(tree).mesh;
      for (const CsgNode& leaf : tree.children) std::filesystem::remove(leaf.mesh);
      return m;
    });
    const Timed nef = median_of([&] { return bench::nef_fold(operands, op); });
    auto cell = [&](const Timed& t) {
      return t.ok ? fmt::format("{:.3f} | {:.0f} | {} | {:.6f}", t.seconds, t.peak_mib, t.faces, t.volume)
                  : (t.timed_out ? fmt::format("> {} (stopped) | | |", limit) : std::string("failed | | |"));
    };
    fmt::print("| {} | lodkit (corefinement) | {} | |\n", name, cell(lk));
    const std::string ratio = lk.ok && nef.ok ? fmt::format("{:.1f}x", nef.seconds / lk.seconds)
                              : lk.ok && nef.timed_out ? fmt::format("> {:.0f}x", limit / lk.seconds) : "";
    fmt::print("| | CGAL Nef_polyhedron_3 | {} | {} |\n", cell(nef), ratio);
    std::fflush(stdout);
  };
  for (int segments : {100, 316}) {  // 9,900 and 99,856 triangles
    const Mesh a = sphere_with(segments);
    const Mesh b = moved(sphere_with(segments), 0.7, 0.3, 0.2);
    row(fmt::format("union of two {}-triangle spheres", a.num_faces()), {a, b}, BooleanOp::Union);
  }
  // The same plate as a CSG tree of 50 primitives (the cylinders tessellated to the same 32 segments).
  CsgNode plate;
  plate.kind = CsgNode::Kind::Operation;
  plate.op = BooleanOp::Difference;
  CsgNode box;
  box.primitive = "box";
  box.size = {8, 8, 0.5};
  plate.children.push_back(box);
  for (int i = 0; i < 7; ++i)
    for (int j = 0; j < 7; ++j) {
      CsgNode c;
      c.primitive = "cylinder";
      c.parameters = {{"radius", 0.3}, {"height", 1.0}};
      c.transform.topRightCorner<3, 1>() = Eigen::Vector3d(-3 + i, -3 + j, 0);
      plate.children.push_back(c);
    }
  row("plate minus 49 cylinders: 50-primitive tree", plate_with_49_holes(), BooleanOp::Difference, &plate);
  row("plate minus 49 cylinders: 50 mesh files", plate_with_49_holes(), BooleanOp::Difference);
  return 0;
}
