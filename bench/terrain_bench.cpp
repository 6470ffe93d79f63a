// Terrain at scale: time and peak memory of `write_terrain_ply` (streamed) and `generate_terrain`
// (in memory) for several level counts, each in a fresh child process so that the peak resident set
// is the job's own; beside them, the time to write a file of the same size with one fwrite loop (the
// floor any generator that writes the file has to pay).
//
//   lodkit_bench_terrain [--levels 8,10,11] [--base pyramid|grid] [--dir /tmp] [--runs 3]
#include <lodkit/terrain.h>

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "child_process.h"

namespace {

struct Measure {
  double seconds = 0;
  double peak_mib = 0;
};

/// Runs `job` in a child; wall time from the parent (fork and exit included),
/// peak RSS from wait4.
Measure in_child(const std::function<void()>& job) {
  const auto start = std::chrono::steady_clock::now();
  const lodkit::bench::ChildRun run = lodkit::bench::run_in_child([&] {
    job();
    return std::vector<double>{};
  }, 0);
  Measure m;
  m.seconds = run.ok() ? std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() : -1;
  m.peak_mib = run.peak_mib;
  return m;
}

Measure median(int runs, const std::function<void()>& job) {
  std::vector<Measure> all;
  for (int r = 0; r < runs; ++r) all.push_back(in_child(job));
  std::sort(all.begin(), all.end(), [](const Measure& a, const Measure& b) { return a.seconds < b.seconds; });
  return all[all.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<int> levels{8, 10, 11};
  std::string base_name = "pyramid", dir = "/tmp";
  int runs = 3;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string arg = argv[i], value = argv[i + 1];
    if (arg == "--levels") {
      levels.clear();
      for (std::size_t p = 0; p < value.size();) {
        const std::size_t q = value.find(',', p);
        levels.push_back(std::stoi(value.substr(p, q - p)));
        p = q == std::string::npos ? value.size() : q + 1;
      }
    } else if (arg == "--base") base_name = value;
    else if (arg == "--dir") dir = value;
    else if (arg == "--runs") runs = std::stoi(value);
    else {
      fmt::print(stderr, "unknown option {}\n", arg);
      return 2;
    }
  }
  const lodkit::Mesh base =
      lodkit::make_terrain_base(base_name == "grid" ? lodkit::TerrainBase::Grid : lodkit::TerrainBase::Pyramid);
  const std::string path = dir + "/lodkit_bench_terrain.ply";
  fmt::print("An idle child process peaks at {:.1f} MiB (shared libraries); base: {}.\n\n",
             in_child([] {}).peak_mib, base_name);
  fmt::print("| levels | faces | file (MB) | streamed PLY (s) | peak (MiB) | bytes/face at peak | "
             "in memory (s) | peak (MiB) | bytes/face | fwrite of the same bytes (s) |\n");
  fmt::print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const int l : levels) {
    lodkit::TerrainOptions o;
    o.levels = l;
    o.colour = true;
    const lodkit::TerrainSize size = lodkit::terrain_size(base, l);
    const Measure streamed = median(runs, [&] { lodkit::write_terrain_ply(base, o, path); });
    const auto bytes = static_cast<std::size_t>(std::filesystem::file_size(path));
    const Measure memory = median(runs, [&] { (void)lodkit::generate_terrain(base, o); });
    const Measure floor = median(runs, [&] {
      std::vector<char> block(1 << 20, 'x');
      std::FILE* f = std::fopen(path.c_str(), "wb");
      for (std::size_t done = 0; done < bytes; done += block.size())
        std::fwrite(block.data(), 1, std::min(block.size(), bytes - done), f);
      std::fclose(f);
    });
    const double faces = static_cast<double>(size.faces);
    fmt::print("| {} | {:L} | {:.0f} | {:.3f} | {:.0f} | {:.1f} | {:.3f} | {:.0f} | {:.1f} | {:.3f} |\n", l,
               size.faces, bytes / 1e6, streamed.seconds, streamed.peak_mib, streamed.peak_mib * 1048576 / faces,
               memory.seconds, memory.peak_mib, memory.peak_mib * 1048576 / faces, floor.seconds);
    std::filesystem::remove(path);
  }
}
