#include "terrain/engine.h"

#include <lodkit/error.h>

#include <fmt/format.h>
#include <opensubdiv/far/topologyDescriptor.h>
#include <opensubdiv/far/topologyRefinerFactory.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include "core/topology.h"
#include "terrain/keyed_random.h"

namespace lodkit::detail {
namespace {

namespace Far = OpenSubdiv::Far;
namespace Sdc = OpenSubdiv::Sdc;

/// Patches of 4^kPatchLevels triangles: big enough that the per-patch overhead vanishes, small
/// enough to stay in cache; the coarse levels above them are OpenSubdiv's.
constexpr int kPatchLevels = 6;

}  // namespace

const std::array<Rgb, 6>& terrain_palette() {
  static const std::array<Rgb, 6> palette{{{38, 84, 156},     // water
                                           {214, 197, 140},   // sand
                                           {96, 152, 64},     // grass
                                           {46, 96, 48},      // forest
                                           {124, 110, 98},    // rock
                                           {244, 246, 250}}}; // snow
  return palette;
}

Mesh prepare_terrain_base(const Mesh& base) {
  validate(base, "terrain base");
  if (base.num_faces() == 0) throw Error("terrain base: has no faces");
  Mesh welded;  // positions and faces only, so welding identical vertices welds by position
  welded.positions = base.positions;
  welded.triangles = base.triangles;
  weld_identical_vertices(welded);
  for (Index f = 0; f < welded.num_faces(); ++f) {
    const auto t = welded.triangles.row(f);
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2])
      throw Error(fmt::format("terrain base: face {} repeats a vertex", f));
  }
  remove_unreferenced_vertices(welded);
  return welded;
}

TerrainSize prepared_terrain_size(const Mesh& base, int levels) {
  std::vector<std::array<Index, 3>> faces(static_cast<std::size_t>(base.num_faces()));
  for (Index f = 0; f < base.num_faces(); ++f)
    faces[f] = {base.triangles(f, 0), base.triangles(f, 1), base.triangles(f, 2)};
  const auto edges = static_cast<std::int64_t>(classify_edges(faces).size());
  const std::int64_t n = std::int64_t{1} << levels;
  TerrainSize size;
  size.faces = base.num_faces() * n * n;
  size.vertices = base.num_vertices() + edges * (n - 1) + base.num_faces() * (n - 1) * (n - 2) / 2;
  return size;
}

TerrainEngine::TerrainEngine(const Mesh& raw_base, const TerrainOptions& options) : options_(options) {
  if (options.levels < 0 || options.levels > 15)
    throw Error(fmt::format("terrain: levels must be 0..15, not {}", options.levels));
  if (!(options.roughness > 0.0 && options.roughness <= 1.0))
    throw Error(fmt::format("terrain: roughness (H) must be in (0, 1], not {}", options.roughness));
  if (!(options.sigma >= 0.0) || !std::isfinite(options.sigma))
    throw Error(fmt::format("terrain: sigma must be finite and non-negative, not {}", options.sigma));
  if (options.palette_level < 0) throw Error("terrain: palette level must be non-negative");
  if (!(options.up.norm() > 0.0) || !options.up.allFinite()) throw Error("terrain: up must be a non-zero vector");
  const Mesh base = prepare_terrain_base(raw_base);
  levels_ = options.levels;
  colour_ = options.colour;

  const TerrainSize size = prepared_terrain_size(base, levels_);
  if (size.vertices > std::numeric_limits<Index>::max() || size.faces > std::numeric_limits<Index>::max())
    throw Error(fmt::format("terrain: {} levels of a {}-face base make {} faces, above the 2^31 - 1 limit",
                            levels_, base.num_faces(), size.faces));
  num_vertices_ = size.vertices;
  num_faces_ = size.faces;

  sigma_.assign(static_cast<std::size_t>(levels_) + 1, 0.0);
  for (int l = 1; l <= levels_; ++l) sigma_[static_cast<std::size_t>(l)] = terrain_sigma(base, options, l);

  // Patches below the coarse level; the palette needs every point it colours in the coarse level.
  const int palette_levels = colour_ ? std::min(options.palette_level, levels_) : 0;
  coarse_level_ = std::max(std::max(levels_ - kPatchLevels, 0), palette_levels);
  n_ = 1 << (levels_ - coarse_level_);
  build_coarse_levels(base);
}

TerrainPoint TerrainEngine::midpoint(const TerrainPoint& a, const TerrainPoint& b, int direction,
                                     int level) const {
  TerrainPoint m;
  m.key = midpoint_key(a.key, b.key);
  m.level = static_cast<std::uint8_t>(level);
  const double d = sigma_[static_cast<std::size_t>(level)] * keyed_gaussian(m.key, options_.seed);
  // The same expression everywhere a midpoint is made, so shared points are bit-identical
  // (this file is compiled without floating-point contraction).
  m.position = 0.5 * (a.position + b.position) + d * directions_[static_cast<std::size_t>(direction)];
  // Order-independent choice between the end points' colours.
  const TerrainPoint& low = a.key < b.key ? a : b;
  const TerrainPoint& high = a.key < b.key ? b : a;
  m.colour = keyed_coin(m.key, options_.seed) ? low.colour : high.colour;
  return m;
}

void TerrainEngine::build_coarse_levels(const Mesh& base) {
  const Index nv = base.num_vertices(), nf = base.num_faces();
  std::vector<int> verts_per_face(static_cast<std::size_t>(nf), 3);
  std::vector<Far::Index> indices(base.triangles.data(), base.triangles.data() + 3 * nf);
  Far::TopologyDescriptor desc;
  desc.numVertices = nv;
  desc.numFaces = nf;
  desc.numVertsPerFace = verts_per_face.data();
  desc.vertIndicesPerFace = indices.data();
  using Factory = Far::TopologyRefinerFactory<Far::TopologyDescriptor>;
  std::unique_ptr<Far::TopologyRefiner> refiner(
      Factory::Create(desc, Factory::Options(Sdc::SCHEME_LOOP, Sdc::Options())));
  if (!refiner) throw Error("terrain base: OpenSubdiv rejected its topology");
  if (coarse_level_ > 0) {
    Far::TopologyRefiner::UniformOptions uniform(coarse_level_);
    uniform.fullTopologyInLastLevel = true;
    refiner->RefineUniform(uniform);
  }

  // Level 0: keys, face normals, original edge directions.
  const Far::TopologyLevel& top = refiner->GetLevel(0);
  std::vector<TerrainPoint> points(static_cast<std::size_t>(nv));
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (Index v = 0; v < nv; ++v) {
    points[v].position = base.positions.row(v).transpose();
    points[v].key = base_vertex_key(static_cast<std::uint64_t>(v));
    centroid += points[v].position;
  }
  centroid /= nv;
  closed_base_ = true;
  for (Index e = 0; e < top.GetNumEdges(); ++e)
    if (top.GetEdgeFaces(e).size() != 2) closed_base_ = false;
  EdgeDirection rule = options_.edge_direction;
  if (rule == EdgeDirection::Auto) rule = closed_base_ ? EdgeDirection::FaceNormals : EdgeDirection::Up;

  directions_.clear();
  for (Index f = 0; f < nf; ++f) {
    const auto fv = top.GetFaceVertices(f);
    const Eigen::Vector3d n = (points[fv[1]].position - points[fv[0]].position)
                                  .cross(points[fv[2]].position - points[fv[0]].position);
    directions_.push_back(n.norm() > 0.0 ? Eigen::Vector3d(n.normalized()) : Eigen::Vector3d::Zero());
  }
  const Eigen::Vector3d up = options_.up.normalized();
  for (Index e = 0; e < top.GetNumEdges(); ++e) {
    Eigen::Vector3d d = up;
    if (rule == EdgeDirection::FaceNormals) {
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (const Far::Index f : top.GetEdgeFaces(e)) sum += directions_[static_cast<std::size_t>(f)];
      d = sum.norm() > 1e-12 ? Eigen::Vector3d(sum.normalized()) : Eigen::Vector3d::Zero();
    }
    directions_.push_back(d);
  }
  std::vector<int> edge_dir(static_cast<std::size_t>(top.GetNumEdges()));
  for (Index e = 0; e < top.GetNumEdges(); ++e) edge_dir[e] = nf + e;
  std::vector<int> face_dir(static_cast<std::size_t>(nf));
  for (Index f = 0; f < nf; ++f) face_dir[f] = f;

  // With colour, the points of the palette level (every point of level <= it) take palette colours by
  // height as soon as that level exists; deeper midpoints inherit theirs in midpoint(). The coarse
  // level is at least the palette level, so this happens here.
  const int palette_level = std::min(options_.palette_level, levels_);
  auto colour_by_height = [&](std::vector<TerrainPoint>& level_points) {
    auto height = [&](const Eigen::Vector3d& p) {
      return closed_base_ ? (p - centroid).norm() : (p - centroid).dot(up);
    };
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const TerrainPoint& p : level_points) {
      lo = std::min(lo, height(p.position));
      hi = std::max(hi, height(p.position));
    }
    // Thresholds between water | sand | grass | forest | rock | snow, as fractions of the range.
    constexpr std::array<double, 5> kThresholds{0.22, 0.27, 0.50, 0.68, 0.84};
    for (TerrainPoint& p : level_points) {
      const double t = hi > lo ? (height(p.position) - lo) / (hi - lo) : 0.5;
      std::uint8_t c = 0;
      while (c < kThresholds.size() && t > kThresholds[c]) ++c;
      p.colour = c;
    }
  };
  if (colour_ && palette_level == 0) colour_by_height(points);

  // Levels 1..k through the refiner's parent-child relations.
  for (int l = 0; l < coarse_level_; ++l) {
    const Far::TopologyLevel& parent = refiner->GetLevel(l);
    const Far::TopologyLevel& child = refiner->GetLevel(l + 1);
    std::vector<TerrainPoint> next(static_cast<std::size_t>(child.GetNumVertices()));
    for (Index v = 0; v < parent.GetNumVertices(); ++v) {
      const Index c = parent.GetVertexChildVertex(v);
      next[c] = points[v];
    }
    for (Index e = 0; e < parent.GetNumEdges(); ++e) {
      const auto ev = parent.GetEdgeVertices(e);
      const Index c = parent.GetEdgeChildVertex(e);
      next[c] = midpoint(points[ev[0]], points[ev[1]], edge_dir[e], l + 1);
    }
    std::vector<int> next_edge_dir(static_cast<std::size_t>(child.GetNumEdges()), -1);
    std::vector<int> next_face_dir(static_cast<std::size_t>(child.GetNumFaces()), -1);
    for (Index e = 0; e < parent.GetNumEdges(); ++e)
      for (const Far::Index ce : parent.GetEdgeChildEdges(e)) next_edge_dir[ce] = edge_dir[e];
    for (Index f = 0; f < parent.GetNumFaces(); ++f) {
      for (const Far::Index ce : parent.GetFaceChildEdges(f)) next_edge_dir[ce] = face_dir[f];
      for (const Far::Index cf : parent.GetFaceChildFaces(f)) next_face_dir[cf] = face_dir[f];
    }
    points = std::move(next);
    edge_dir = std::move(next_edge_dir);
    face_dir = std::move(next_face_dir);
    if (colour_ && l + 1 == palette_level) colour_by_height(points);
  }

  const Far::TopologyLevel& last = refiner->GetLevel(coarse_level_);
  edges_.resize(static_cast<std::size_t>(last.GetNumEdges()));
  for (Index e = 0; e < last.GetNumEdges(); ++e) {
    const auto ev = last.GetEdgeVertices(e);
    edges_[e] = {{ev[0], ev[1]}, edge_dir[e]};
  }
  faces_.resize(static_cast<std::size_t>(last.GetNumFaces()));
  for (Index f = 0; f < last.GetNumFaces(); ++f) {
    const auto fv = last.GetFaceVertices(f);
    const auto fe = last.GetFaceEdges(f);
    faces_[f] = {{fv[0], fv[1], fv[2]}, {fe[0], fe[1], fe[2]}, face_dir[f]};
  }
  points_ = std::move(points);
}

void TerrainEngine::refine_edge(Index e, std::vector<TerrainPoint>& out) const {
  const Edge& edge = edges_[static_cast<std::size_t>(e)];
  out.resize(static_cast<std::size_t>(n_) + 1);
  out[0] = points_[static_cast<std::size_t>(edge.v[0])];
  out[static_cast<std::size_t>(n_)] = points_[static_cast<std::size_t>(edge.v[1])];
  int level = coarse_level_;
  for (int s = n_ / 2; s >= 1; s /= 2) {
    ++level;
    for (int i = s; i < n_; i += 2 * s)
      out[static_cast<std::size_t>(i)] =
          midpoint(out[static_cast<std::size_t>(i - s)], out[static_cast<std::size_t>(i + s)], edge.direction, level);
  }
}

void TerrainEngine::refine_face(Index f, std::vector<TerrainPoint>& lattice,
                                std::vector<TerrainPoint>& scratch) const {
  const Face& face = faces_[static_cast<std::size_t>(f)];
  lattice.resize(lattice_size());
  // The three sides, copied from the edges so both faces of an edge hold identical points.
  for (int k = 0; k < 3; ++k) {
    refine_edge(face.e[k], scratch);
    const bool forward = edges_[static_cast<std::size_t>(face.e[k])].v[0] == face.v[k];
    for (int t = 0; t <= n_; ++t) {
      const auto [i, j] = side_point(k, t);
      lattice[lattice_index(i, j)] = scratch[static_cast<std::size_t>(forward ? t : n_ - t)];
    }
  }
  int level = coarse_level_;
  for (int s = n_ / 2; s >= 1; s /= 2) {
    ++level;
    for (int j = s; j < n_; j += s)
      for (int i = s; i + j < n_; i += s) {
        const bool odd_i = (i / s) % 2 == 1, odd_j = (j / s) % 2 == 1;
        if (!odd_i && !odd_j) continue;  // an older point
        std::size_t a, b;
        if (odd_i && !odd_j) a = lattice_index(i - s, j), b = lattice_index(i + s, j);
        else if (!odd_i) a = lattice_index(i, j - s), b = lattice_index(i, j + s);
        else a = lattice_index(i - s, j + s), b = lattice_index(i + s, j - s);
        lattice[lattice_index(i, j)] = midpoint(lattice[a], lattice[b], face.direction, level);
      }
  }
}

void TerrainEngine::lattice_vertex_indices(Index f, std::vector<std::int64_t>& out) const {
  const Face& face = faces_[static_cast<std::size_t>(f)];
  out.resize(lattice_size());
  for (int k = 0; k < 3; ++k) {
    const Edge& edge = edges_[static_cast<std::size_t>(face.e[k])];
    const bool forward = edge.v[0] == face.v[k];
    const std::int64_t first = first_edge_point() + static_cast<std::int64_t>(face.e[k]) * (n_ - 1);
    for (int t = 0; t <= n_; ++t) {
      const auto [i, j] = side_point(k, t);
      std::int64_t g;
      if (t == 0) g = face.v[k];
      else if (t == n_) g = face.v[(k + 1) % 3];
      else g = first + (forward ? t : n_ - t) - 1;
      out[lattice_index(i, j)] = g;
    }
  }
  std::int64_t next = first_face_point() + static_cast<std::int64_t>(f) * points_inside_face();
  for (int j = 1; j < n_; ++j)
    for (int i = 1; i + j < n_; ++i) out[lattice_index(i, j)] = next++;
}

std::uint8_t TerrainEngine::face_colour(const TerrainPoint& a, const TerrainPoint& b, const TerrainPoint& c) {
  if (a.colour == b.colour || a.colour == c.colour) return a.colour;
  if (b.colour == c.colour) return b.colour;
  const TerrainPoint* least = &a;
  if (b.key < least->key) least = &b;
  if (c.key < least->key) least = &c;
  return least->colour;
}

}  // namespace lodkit::detail
