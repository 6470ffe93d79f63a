// Public terrain API: the base shapes, sizes, and the two sinks over TerrainEngine: a Mesh in memory,
// and a PLY file written in order while patches are generated in parallel.
#include <lodkit/error.h>
#include <lodkit/terrain.h>

#include <fmt/format.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <bit>
#include <cstring>

#include "io/output.h"
#include "terrain/engine.h"

namespace lodkit {
namespace {

using detail::TerrainEngine;
using detail::TerrainPoint;

struct Workspace {
  std::vector<TerrainPoint> lattice, scratch;
  std::vector<std::int64_t> indices;
};

template <typename Body>
void run_with_threads(int threads, Body&& body) {
  if (threads < 0) throw Error(fmt::format("terrain: threads must be non-negative, not {}", threads));
  tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
  arena.execute(body);
}

/// Runs fill(first, last, bytes) on blocks of [0, count) in parallel, a batch at a time, and appends
/// the blocks' bytes to `out` in order: parallel generation, sequential file, bounded memory.
template <typename Fill>
void write_blocks_in_order(detail::Output& out, std::int64_t count, std::int64_t block, Fill&& fill) {
  const std::int64_t blocks = (count + block - 1) / block;
  const std::int64_t batch = 4 * std::max(1, tbb::this_task_arena::max_concurrency());
  std::vector<std::string> buffers(static_cast<std::size_t>(batch));
  for (std::int64_t first = 0; first < blocks; first += batch) {
    const std::int64_t last = std::min(blocks, first + batch);
    tbb::parallel_for(first, last, [&](std::int64_t b) {
      std::string& bytes = buffers[static_cast<std::size_t>(b - first)];
      bytes.clear();
      fill(b * block, std::min(count, (b + 1) * block), bytes);
    });
    for (std::int64_t b = first; b < last; ++b) out.put_bytes(buffers[static_cast<std::size_t>(b - first)].data(),
                                                              buffers[static_cast<std::size_t>(b - first)].size());
  }
}

template <typename T>
void append_le(std::string& bytes, T value) {
  static_assert(std::endian::native == std::endian::little, "PLY writer assumes a little-endian host");
  char raw[sizeof(T)];
  std::memcpy(raw, &value, sizeof(T));
  bytes.append(raw, sizeof(T));
}

void append_point(std::string& bytes, const TerrainPoint& p) {
  for (int k = 0; k < 3; ++k) append_le(bytes, static_cast<float>(p.position[k]));
}

}  // namespace

Mesh make_terrain_base(TerrainBase base) {
  Mesh mesh;
  if (base == TerrainBase::Grid) {
    mesh.positions.resize(4, 3);
    mesh.positions << -0.5, -0.5, 0, 0.5, -0.5, 0, 0.5, 0.5, 0, -0.5, 0.5, 0;
    mesh.triangles.resize(2, 3);
    mesh.triangles << 0, 1, 2, 0, 2, 3;
  } else {
    mesh.positions.resize(5, 3);
    mesh.positions << -0.5, -0.5, 0, 0.5, -0.5, 0, 0.5, 0.5, 0, -0.5, 0.5, 0, 0, 0, 0.5;
    mesh.triangles.resize(4, 3);
    mesh.triangles << 0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4;
  }
  return mesh;
}

double terrain_sigma(const Mesh& base, const TerrainOptions& options, int level) {
  const double diagonal = bounding_box(base).diagonal().norm();
  const double sigma0 = options.sigma_is_relative ? options.sigma * diagonal : options.sigma;
  return sigma0 * std::exp2(-level * options.roughness);
}

TerrainSize terrain_size(const Mesh& base, int levels) {
  if (levels < 0 || levels > 15) throw Error(fmt::format("terrain: levels must be 0..15, not {}", levels));
  return detail::prepared_terrain_size(detail::prepare_terrain_base(base), levels);
}

Terrain generate_terrain(const Mesh& base, const TerrainOptions& options) {
  const TerrainEngine engine(base, options);
  Terrain t;
  const auto nv = static_cast<Index>(engine.num_vertices());
  const auto nf = static_cast<Index>(engine.num_faces());
  t.mesh.positions.resize(nv, 3);
  t.mesh.triangles.resize(nf, 3);
  if (engine.coloured()) t.mesh.attributes.face_colours.resize(nf, 4);
  t.keys.resize(static_cast<std::size_t>(nv));
  t.vertex_level.resize(static_cast<std::size_t>(nv));
  auto store = [&](std::int64_t v, const TerrainPoint& p) {
    t.mesh.positions.row(static_cast<Index>(v)) = p.position.transpose();
    t.keys[static_cast<std::size_t>(v)] = p.key;
    t.vertex_level[static_cast<std::size_t>(v)] = p.level;
  };
  const int n = engine.side();
  const auto& palette = detail::terrain_palette();
  run_with_threads(options.threads, [&] {
    for (Index v = 0; v < engine.num_coarse_vertices(); ++v) store(v, engine.coarse_point(v));
    tbb::enumerable_thread_specific<Workspace> workspaces;
    tbb::parallel_for(Index{0}, engine.num_coarse_edges(), [&](Index e) {
      std::vector<TerrainPoint>& points = workspaces.local().scratch;
      engine.refine_edge(e, points);
      for (int i = 1; i < n; ++i)
        store(engine.first_edge_point() + static_cast<std::int64_t>(e) * (n - 1) + i - 1, points[static_cast<std::size_t>(i)]);
    });
    tbb::parallel_for(Index{0}, engine.num_coarse_faces(), [&](Index f) {
      Workspace& w = workspaces.local();
      engine.refine_face(f, w.lattice, w.scratch);
      engine.lattice_vertex_indices(f, w.indices);
      for (int j = 1; j < n; ++j)
        for (int i = 1; i + j < n; ++i) store(w.indices[engine.lattice_index(i, j)], w.lattice[engine.lattice_index(i, j)]);
      Index face = f * n * n;
      engine.for_each_lattice_triangle([&](int i0, int j0, int i1, int j1, int i2, int j2) {
        const std::size_t a = engine.lattice_index(i0, j0), b = engine.lattice_index(i1, j1),
                          c = engine.lattice_index(i2, j2);
        t.mesh.triangles.row(face) << static_cast<Index>(w.indices[a]), static_cast<Index>(w.indices[b]),
            static_cast<Index>(w.indices[c]);
        if (engine.coloured()) {
          const detail::Rgb rgb = palette[TerrainEngine::face_colour(w.lattice[a], w.lattice[b], w.lattice[c])];
          t.mesh.attributes.face_colours.row(face) << rgb.r / 255.0f, rgb.g / 255.0f, rgb.b / 255.0f, 1.0f;
        }
        ++face;
      });
    });
  });
  return t;
}

TerrainWriteStats write_terrain_ply(const Mesh& base, const TerrainOptions& options,
                                    const std::filesystem::path& path) {
  const TerrainEngine engine(base, options);
  const int n = engine.side();
  const std::int64_t per_face = static_cast<std::int64_t>(n) * n;
  const auto& palette = detail::terrain_palette();
  // One palette index per output face, filled while the face's patch is generated for its points.
  std::vector<std::uint8_t> face_colour(engine.coloured() ? static_cast<std::size_t>(engine.num_faces()) : 0);
  TerrainWriteStats stats;
  stats.vertices = engine.num_vertices();
  stats.faces = engine.num_faces();

  detail::write_file_atomically(path, [&](detail::Output& out) {
    std::string header = fmt::format(
        "ply\nformat binary_little_endian 1.0\n"
        "comment lodkit terrain levels {} roughness {} sigma {}{} seed {}\n"
        "element vertex {}\nproperty float x\nproperty float y\nproperty float z\n"
        "element face {}\nproperty list uchar int vertex_indices\n",
        options.levels, options.roughness, options.sigma, options.sigma_is_relative ? " (of the base diagonal)" : "",
        options.seed, stats.vertices, stats.faces);
    if (engine.coloured()) header += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    header += "end_header\n";
    out.put(header);
    run_with_threads(options.threads, [&] {
      tbb::enumerable_thread_specific<Workspace> workspaces;
      std::string coarse;
      for (Index v = 0; v < engine.num_coarse_vertices(); ++v) append_point(coarse, engine.coarse_point(v));
      out.put_bytes(coarse.data(), coarse.size());
      write_blocks_in_order(out, engine.num_coarse_edges(), std::max(1, 65536 / n), [&](std::int64_t first, std::int64_t last, std::string& bytes) {
        std::vector<TerrainPoint>& points = workspaces.local().scratch;
        for (std::int64_t e = first; e < last; ++e) {
          engine.refine_edge(static_cast<Index>(e), points);
          for (int i = 1; i < n; ++i) append_point(bytes, points[static_cast<std::size_t>(i)]);
        }
      });
      write_blocks_in_order(out, engine.num_coarse_faces(), std::max<std::int64_t>(1, 65536 / per_face),
                            [&](std::int64_t first, std::int64_t last, std::string& bytes) {
        Workspace& w = workspaces.local();
        for (std::int64_t f = first; f < last; ++f) {
          engine.refine_face(static_cast<Index>(f), w.lattice, w.scratch);
          for (int j = 1; j < n; ++j)
            for (int i = 1; i + j < n; ++i) append_point(bytes, w.lattice[engine.lattice_index(i, j)]);
          if (!engine.coloured()) continue;
          std::int64_t face = f * per_face;
          engine.for_each_lattice_triangle([&](int i0, int j0, int i1, int j1, int i2, int j2) {
            face_colour[static_cast<std::size_t>(face++)] = TerrainEngine::face_colour(
                w.lattice[engine.lattice_index(i0, j0)], w.lattice[engine.lattice_index(i1, j1)],
                w.lattice[engine.lattice_index(i2, j2)]);
          });
        }
      });
      const std::size_t face_bytes = 13 + (engine.coloured() ? 3 : 0);
      write_blocks_in_order(out, engine.num_coarse_faces(), std::max<std::int64_t>(1, 65536 / per_face),
                            [&](std::int64_t first, std::int64_t last, std::string& bytes) {
        std::vector<std::int64_t>& indices = workspaces.local().indices;
        bytes.resize(static_cast<std::size_t>((last - first) * per_face) * face_bytes);
        char* cursor = bytes.data();
        auto put_index = [&](std::int64_t v) {
          const auto i = static_cast<std::int32_t>(v);
          std::memcpy(cursor, &i, 4);
          cursor += 4;
        };
        for (std::int64_t f = first; f < last; ++f) {
          engine.lattice_vertex_indices(static_cast<Index>(f), indices);
          std::int64_t face = f * per_face;
          engine.for_each_lattice_triangle([&](int i0, int j0, int i1, int j1, int i2, int j2) {
            *cursor++ = 3;
            put_index(indices[engine.lattice_index(i0, j0)]);
            put_index(indices[engine.lattice_index(i1, j1)]);
            put_index(indices[engine.lattice_index(i2, j2)]);
            if (engine.coloured()) {
              const detail::Rgb rgb = palette[face_colour[static_cast<std::size_t>(face++)]];
              *cursor++ = static_cast<char>(rgb.r);
              *cursor++ = static_cast<char>(rgb.g);
              *cursor++ = static_cast<char>(rgb.b);
            }
          });
        }
      });
    });
    stats.bytes = static_cast<std::int64_t>(header.size()) + stats.vertices * 12 +
                  stats.faces * (13 + (engine.coloured() ? 3 : 0));
  });
  return stats;
}

}  // namespace lodkit
