// Simplification benchmark: lodkit's methods beside meshoptimizer, OpenMesh's Decimater and CGAL's
// edge_collapse, on the same input and targets. Every run happens in a fresh child process (time of
// the simplification call, and the process's peak RSS); every result is then measured by lodkit's
// compare (symmetric Hausdorff, RMS, as % of the input's bounding-box diagonal) and inspected
// (non-manifold edges, faces flipped against the nearest input face); where the input has vertex
// normals, colours or UVs, their errors too (the peers' outputs carry those of the input vertices they
// keep). With --repeat N every run is made N times and the median time and peak memory reported, as
// the anchors were measured: one run varies by about 5 % with what ran before it.
//
//   lodkit_bench_simplify [--targets 0.1,0.01] [--methods quadric,hoppe,...] [--csv FILE]
//                         [--hoppe-max-faces N] [--repeat N] MESH...
#include <lodkit/inspect.h>
#include <lodkit/io.h>
#include <lodkit/metrics.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <fmt/format.h>

#include <fstream>
#include <string>
#include <unistd.h>
#include <vector>

#include "child_process.h"
#include "methods.h"

namespace fs = std::filesystem;
using namespace lodkit;

namespace {

struct Outcome {
  bool ok = false;
  double seconds = 0;
  double peak_mib = 0;
  Mesh mesh;
};

Outcome run_in_child(const std::string& method, const fs::path& input, Index target, const fs::path& output) {
  const bench::ChildRun run = bench::run_in_child(
      [&] {
        const Mesh mesh = read_mesh(input);
        const bench::PeerRun r = bench::run_method(method, mesh, target);
        write_mesh(r.mesh, output);
        return std::vector<double>{r.seconds};
      },
      1);
  Outcome o;
  o.ok = run.ok();
  o.peak_mib = run.peak_mib;
  if (o.ok) o.seconds = run.reply[0], o.mesh = read_mesh(output);
  return o;
}

// The middle value (the lower of the two middle ones for an even count).
double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  return values[(values.size() - 1) / 2];
}

// The run made `repeat` times: the median time and peak memory, the last output. A method is
// deterministic, so every run's output has the same faces; a run that differs fails the row.
Outcome run_repeated(const std::string& method, const fs::path& input, Index target, const fs::path& output, int repeat) {
  std::vector<double> seconds, peaks;
  Outcome last;
  for (int i = 0; i < repeat; ++i) {
    Outcome o = run_in_child(method, input, target, output);
    if (!o.ok) return {};
    if (i > 0 && o.mesh.num_faces() != last.mesh.num_faces()) {
      std::fprintf(stderr, "lodkit_bench_simplify: %s gave %d faces, then %d: not deterministic\n", method.c_str(),
                   int(last.mesh.num_faces()), int(o.mesh.num_faces()));
      return {};
    }
    seconds.push_back(o.seconds), peaks.push_back(o.peak_mib);
    last = std::move(o);
  }
  last.seconds = median(seconds), last.peak_mib = median(peaks);
  return last;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> methods = bench::all_methods();
  std::vector<double> targets{0.1, 0.01};
  std::vector<std::string> inputs;
  std::string csv_path;
  Index hoppe_max_faces = 150'000;
  int repeat = 1;
  const char* usage =
      "usage: lodkit_bench_simplify [--targets 0.1,0.01] [--methods quadric,hoppe,...] [--csv FILE]\n"
      "                             [--hoppe-max-faces N] [--repeat N] MESH...\n";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      std::fputs(usage, stdout);
      return 0;
    }
    if (a == "--methods" && i + 1 < argc) methods = bench::split_list(argv[++i]);
    else if (a == "--targets" && i + 1 < argc) {
      targets.clear();
      for (const auto& t : bench::split_list(argv[++i])) targets.push_back(std::stod(t));
    } else if (a == "--csv" && i + 1 < argc) csv_path = argv[++i];
    else if (a == "--hoppe-max-faces" && i + 1 < argc) hoppe_max_faces = std::stoi(argv[++i]);
    else if (a == "--repeat" && i + 1 < argc) {
      repeat = std::atoi(argv[++i]);
      if (repeat < 1) {
        std::fprintf(stderr, "lodkit_bench_simplify: --repeat takes a count of 1 or more\n%s", usage);
        return 2;
      }
    }
    else if (a.starts_with("-")) {
      std::fprintf(stderr, "lodkit_bench_simplify: unknown option or missing value: %s\n%s", a.c_str(), usage);
      return 2;
    } else inputs.push_back(a);
  }
  if (inputs.empty()) {
    std::fputs(usage, stderr);
    return 2;
  }
  const fs::path work = fs::temp_directory_path() / fmt::format("lodkit-bench-simplify-{}", getpid());
  fs::create_directories(work);
  std::ofstream csv;
  if (!csv_path.empty()) {
    csv.open(csv_path);
    csv << "mesh,faces_in,target,method,faces_out,seconds,peak_mib,hausdorff_pct,rms_pct,normal_dev_deg,non_manifold_edges,flipped,components,euler,hausdorff_bound_pct,shading_rms_deg,colour_rms,uv_rms\n";
  }
  fmt::print("| mesh → target | method | time s | peak MiB | faces | Hausdorff % | RMS % | non-manifold edges | flipped | shading ° | colour | UV |\n");
  fmt::print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const std::string& path : inputs) {
    // Prepared once: unreferenced vertices dropped (peers differ in how they treat them).
    Mesh mesh = read_mesh(path);
    remove_unreferenced_vertices(mesh);
    const fs::path prepared = work / "input.ply";
    write_mesh(mesh, prepared);
    const std::string name = fs::path(path).filename().string();
    // compare(mesh, output) as its defaults sample (10 per input face: outputs have fewer faces), with
    // the input sampled once.
    const CompareReference reference(mesh, default_face_samples(mesh.num_faces()));
    for (double ratio : targets) {
      const auto target = static_cast<Index>(std::llround(ratio * mesh.num_faces()));
      bool first = true;
      for (const std::string& method : methods) {
        if (method == "hoppe" && mesh.num_faces() > hoppe_max_faces) continue;
        const Outcome o = run_repeated(method, prepared, target, work / "output.ply", repeat);
        const std::string label = first ? fmt::format("{} {} → {}", name, mesh.num_faces(), target) : "";
        first = false;
        if (!o.ok || o.mesh.num_faces() == 0) {
          fmt::print("| {} | {} | failed | | | | | | | | | |\n", label, method);
          continue;
        }
        const Comparison c = o.mesh.num_faces() <= mesh.num_faces() ? reference.compare(o.mesh) : compare(mesh, o.mesh);
        const MeshReport r = inspect(o.mesh);
        const Index flipped = count_flipped_faces(mesh, o.mesh);
        const double normal_dev = 0.5 * (c.a_to_b.normal_deviation_mean_deg + c.b_to_a.normal_deviation_mean_deg);
        // Attribute errors where both meshes have them (compare's), else blank: a method that drops
        // normals or colours has none to measure.
        auto optional = [](const std::optional<double>& x, const char* format) {
          return x ? fmt::format(fmt::runtime(format), *x) : std::string();
        };
        const std::string shading = optional(c.shading_rms_deg, "{:.2f}"), colour = optional(c.colour_rms, "{:.4f}"),
                          uv = optional(c.uv_rms, "{:.4f}");
        fmt::print("| {} | {} | {:.3f} | {:.0f} | {} | {:.4f} | {:.5f} | {} | {} | {} | {} | {} |\n", label, method, o.seconds,
                   o.peak_mib, o.mesh.num_faces(), c.percent(c.hausdorff), c.percent(c.rms), r.non_manifold_edges, flipped,
                   shading, colour, uv);
        std::fflush(stdout);
        if (csv.is_open())
          csv << fmt::format("{},{},{},{},{},{:.6f},{:.1f},{:.6f},{:.7f},{:.4f},{},{},{},{},{:.6f},{},{},{}\n", name, mesh.num_faces(),
                             target, method, o.mesh.num_faces(), o.seconds, o.peak_mib, c.percent(c.hausdorff),
                             c.percent(c.rms), normal_dev, r.non_manifold_edges, flipped, r.components,
                             r.euler_characteristic, c.percent(c.hausdorff_bound), optional(c.shading_rms_deg, "{:.4f}"),
                             optional(c.colour_rms, "{:.6f}"), optional(c.uv_rms, "{:.6f}"));
      }
    }
  }
  fs::remove_all(work);
  return 0;
}
