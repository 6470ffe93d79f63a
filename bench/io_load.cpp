// Load-time benchmark: lodkit's readers against OpenMesh's reader and tinyobjloader on the same
// files. Each measured load runs in a fresh child process, so peak memory (max RSS) is the reader's
// own and no run warms another's heap. Prints a Markdown table (median of --runs loads).
//
//   lodkit_bench_io MESH [--runs N] [--workdir DIR]
//
// MESH is converted once to OBJ and binary little-endian PLY in DIR; every reader then loads those.
#include <lodkit/io.h>
#include <lodkit/primitives.h>

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fmt/format.h>
#include <functional>
#include <string>
#include <tiny_obj_loader.h>
#include <vector>

#include "child_process.h"

namespace fs = std::filesystem;

namespace {

struct Sample {
  double seconds;
  double peak_mib;
};

// Runs `load` in a child process; returns its wall time (measured in the child) and peak RSS.
Sample run_in_child(const std::function<long()>& load) {
  const lodkit::bench::ChildRun run = lodkit::bench::run_in_child(
      [&] {
        const auto t0 = std::chrono::steady_clock::now();
        const long faces = load();
        const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        if (faces <= 0) std::_Exit(3);
        return std::vector<double>{s};
      },
      1);
  if (!run.ok()) {
    std::fprintf(stderr, "a reader failed\n");
    std::exit(1);
  }
  return {run.reply[0], run.peak_mib};
}

Sample median(const std::function<long()>& load, int runs) {
  std::vector<Sample> s;
  for (int i = 0; i < runs; ++i) s.push_back(run_in_child(load));
  std::sort(s.begin(), s.end(), [](const Sample& a, const Sample& b) { return a.seconds < b.seconds; });
  return s[s.size() / 2];
}

long load_lodkit(const fs::path& p) { return lodkit::read_mesh(p).num_faces(); }

long load_openmesh(const fs::path& p) {
  OpenMesh::TriMesh_ArrayKernelT<> mesh;
  OpenMesh::IO::Options options;
  if (!OpenMesh::IO::read_mesh(mesh, p.string(), options)) return -1;
  return static_cast<long>(mesh.n_faces());
}

long load_tinyobj(const fs::path& p) {
  tinyobj::ObjReader reader;
  tinyobj::ObjReaderConfig config;
  config.triangulate = true;
  if (!reader.ParseFromFile(p.string(), config)) return -1;
  long faces = 0;
  for (const auto& shape : reader.GetShapes()) faces += static_cast<long>(shape.mesh.num_face_vertices.size());
  return faces;
}

}  // namespace

int main(int argc, char** argv) {
  std::string input;
  int runs = 5;
  fs::path workdir = fs::temp_directory_path() / "lodkit-bench-io";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--runs" && i + 1 < argc) runs = std::stoi(argv[++i]);
    else if (a == "--workdir" && i + 1 < argc) workdir = argv[++i];
    else input = a;
  }
  fs::create_directories(workdir);
  lodkit::Mesh mesh;
  std::string label;
  if (input.empty()) {
    mesh = lodkit::make_icosphere({.subdivisions = 8});  // 1,310,720 triangles
    label = "icosphere, 8 subdivisions";
  } else {
    mesh = lodkit::read_mesh(input);
    label = fs::path(input).filename().string();
  }
  // Plain positions + triangles, so every reader does the same work.
  mesh.attributes = {};
  const fs::path obj = workdir / "bench.obj", ply = workdir / "bench.ply";
  lodkit::write_mesh(mesh, obj);
  lodkit::write_mesh(mesh, ply);

  fmt::print("Mesh: {} ({} vertices, {} triangles); OBJ {:.1f} MB, binary PLY {:.1f} MB; median of {} runs\n\n",
             label, mesh.num_vertices(), mesh.num_faces(), fs::file_size(obj) / 1e6, fs::file_size(ply) / 1e6, runs);
  fmt::print("| file | reader | load time (s) | peak RSS (MiB) | triangles/s (M) | vs lodkit |\n");
  fmt::print("|---|---|---:|---:|---:|---:|\n");
  auto row = [&](const char* file, const char* reader, const Sample& s, double base) {
    fmt::print("| {} | {} | {:.3f} | {:.0f} | {:.1f} | {:.1f}x |\n", file, reader, s.seconds, s.peak_mib,
               mesh.num_faces() / s.seconds / 1e6, s.seconds / base);
  };
  const Sample lk_obj = median([&] { return load_lodkit(obj); }, runs);
  row("OBJ", "lodkit", lk_obj, lk_obj.seconds);
  row("OBJ", "tinyobjloader 2.0rc10", median([&] { return load_tinyobj(obj); }, runs), lk_obj.seconds);
  row("OBJ", "OpenMesh 9.0", median([&] { return load_openmesh(obj); }, runs), lk_obj.seconds);
  const Sample lk_ply = median([&] { return load_lodkit(ply); }, runs);
  row("PLY (binary LE)", "lodkit", lk_ply, lk_ply.seconds);
  row("PLY (binary LE)", "OpenMesh 9.0", median([&] { return load_openmesh(ply); }, runs), lk_ply.seconds);
  return 0;
}
