// The stability suite through every method: where and how each simplifier fails. Each run is a child
// process with a time limit, so a crash or a hang is recorded, not inherited. For every suite mesh,
// method and target (10 %, 1 %, and "min": a one-face target, as far as the method will go) it records
// the outcome and the damage against the input: non-finite coordinates, new non-manifold edges, faces
// flipped against the nearest input face, and changed components, Euler characteristic or boundary
// loops. Prints a Markdown matrix (suite mesh x method, the failures in each cell) and writes a CSV.
//
//   lodkit_bench_stability [--methods quadric,meshopt,...] [--csv FILE] [--limit SECONDS]
#include <lodkit/inspect.h>
#include <lodkit/io.h>
#include <lodkit/metrics.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <fstream>
#include <string>
#include <unistd.h>
#include <vector>

#include "child_process.h"
#include "methods.h"
#include "stability_suite.h"

namespace fs = std::filesystem;
using namespace lodkit;

namespace {

enum class Status { Ok, NonFinite, Error, Crash, Timeout };

const char* to_string(Status s) {
  switch (s) {
    case Status::Ok: return "ok";
    case Status::NonFinite: return "nan";
    case Status::Error: return "error";
    case Status::Crash: return "crash";
    case Status::Timeout: return "timeout";
  }
  return "?";
}

struct Run {
  Status status = Status::Error;
  double seconds = 0;
  Mesh mesh;
};

Run run_in_child(const std::string& method, const Mesh& input, Index target, const fs::path& output, int limit) {
  const bench::ChildRun child = bench::run_in_child(
      [&] {
        const bench::PeerRun r = bench::run_method(method, input, target);
        if (!r.mesh.positions.allFinite()) return std::vector<double>{double(Status::NonFinite), r.seconds};
        write_mesh(r.mesh, output);
        return std::vector<double>{double(Status::Ok), r.seconds};
      },
      2, limit);
  Run run;
  if (child.end == bench::ChildRun::End::Crashed) run.status = Status::Crash;
  if (child.end == bench::ChildRun::End::TimedOut) run.status = Status::Timeout;
  if (!child.ok()) return run;  // Error unless it crashed or hung
  run.status = static_cast<Status>(static_cast<int>(child.reply[0]));
  run.seconds = child.reply[1];
  if (run.status == Status::Ok) run.mesh = read_mesh(output);
  return run;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> methods = bench::all_methods();
  std::string csv_path;
  int limit = 120;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--methods" && i + 1 < argc) methods = bench::split_list(argv[++i]);
    else if (a == "--csv" && i + 1 < argc) csv_path = argv[++i];
    else if (a == "--limit" && i + 1 < argc) limit = std::stoi(argv[++i]);
    else {
      std::fprintf(stderr, "usage: lodkit_bench_stability [--methods quadric,meshopt,...] [--csv FILE] [--limit SECONDS]\n");
      return 2;
    }
  }
  const fs::path work = fs::temp_directory_path() / fmt::format("lodkit-bench-stability-{}", getpid());
  fs::create_directories(work);
  std::ofstream csv;
  if (!csv_path.empty()) {
    csv.open(csv_path);
    csv << "mesh,faces_in,target,method,status,faces_out,seconds,non_manifold_in,non_manifold_out,flipped,"
           "components_in,components_out,euler_in,euler_out,boundary_in,boundary_out\n";
  }
  const std::vector<std::pair<double, std::string>> targets{{0.1, "10%"}, {0.01, "1%"}, {0.0, "min"}};
  std::string rule = "|---|";
  for (std::size_t m = 0; m < methods.size(); ++m) rule += "---|";
  fmt::print("| suite mesh (faces) | {} |\n{}\n", fmt::join(methods, " | "), rule);
  std::fflush(stdout);  // before any fork, or the children inherit the buffer and print it again
  for (const test::StabilityCase& c : test::stability_suite()) {
    const MeshReport before = inspect(c.mesh);
    std::vector<std::string> cells;
    for (const std::string& method : methods) {
      std::vector<std::string> failures;
      for (const auto& [ratio, label] : targets) {
        const Index target = std::max<Index>(1, static_cast<Index>(std::llround(ratio * double(c.mesh.num_faces()))));
        const Run run = run_in_child(method, c.mesh, target, work / "out.ply", limit);
        std::vector<std::string> what;
        MeshReport after;
        Index flipped = 0;
        if (run.status != Status::Ok) {
          what.push_back(to_string(run.status));
        } else if (run.mesh.num_faces() == 0) {
          what.push_back("empty");
        } else {
          after = inspect(run.mesh);
          flipped = count_flipped_faces(c.mesh, run.mesh);
          if (after.non_manifold_edges > before.non_manifold_edges)
            what.push_back(fmt::format("+{} non-manifold edges", after.non_manifold_edges - before.non_manifold_edges));
          if (after.components != before.components)
            what.push_back(fmt::format("components {}→{}", before.components, after.components));
          if (after.euler_characteristic != before.euler_characteristic)
            what.push_back(fmt::format("χ {}→{}", before.euler_characteristic, after.euler_characteristic));
          if (after.boundary_loops != before.boundary_loops)
            what.push_back(fmt::format("boundaries {}→{}", before.boundary_loops, after.boundary_loops));
          // Against the nearest input face: meaningful while the output still follows the input.
          if (flipped > 0 && ratio > 0) what.push_back(fmt::format("{} flipped", flipped));
        }
        if (!what.empty()) failures.push_back(fmt::format("{}: {}", label, fmt::join(what, ", ")));
        if (csv.is_open())
          csv << fmt::format("{},{},{},{},{},{},{:.6f},{},{},{},{},{},{},{},{},{}\n", c.name, c.mesh.num_faces(), target, method,
                             to_string(run.status), run.mesh.num_faces(), run.seconds, before.non_manifold_edges,
                             after.non_manifold_edges, flipped, before.components, after.components,
                             before.euler_characteristic, after.euler_characteristic, before.boundary_loops,
                             after.boundary_loops);
      }
      cells.push_back(failures.empty() ? "ok" : fmt::format("{}", fmt::join(failures, "; ")));
    }
    fmt::print("| {} ({}) | {} |\n", c.name, c.mesh.num_faces(), fmt::join(cells, " | "));
    std::fflush(stdout);
  }
  fs::remove_all(work);
  return 0;
}
