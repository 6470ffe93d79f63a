// Subdivision through OpenSubdiv: lodkit's mesh becomes a Far::TopologyDescriptor (vertices welded by
// position, UVs as a face-varying channel indexed by lodkit's own seam-split vertices), the refiner
// refines uniformly, and Far::PrimvarRefiner carries positions, colours and UVs level by level.
#include <lodkit/error.h>
#include <lodkit/metrics.h>
#include <lodkit/subdivide.h>

#include <fmt/format.h>
#include <opensubdiv/far/primvarRefiner.h>
#include <opensubdiv/far/topologyDescriptor.h>
#include <opensubdiv/far/topologyRefinerFactory.h>

#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <unordered_map>

namespace lodkit {
namespace {

namespace Far = OpenSubdiv::Far;
namespace Sdc = OpenSubdiv::Sdc;

/// A primvar as Far::PrimvarRefinerReal wants it: Clear() and AddWithWeight(). Weights are double
/// (PrimvarRefinerReal<double>): float weights would cost 1e-8 of relative precision per level.
template <int N, typename T>
struct Primvar {
  T v[N];
  void Clear(void* = nullptr) {
    for (T& x : v) x = 0;
  }
  void AddWithWeight(const Primvar& src, double weight) {
    for (int k = 0; k < N; ++k) v[k] += static_cast<T>(weight) * src.v[k];
  }
};
using Point = Primvar<3, double>;
using Uv = Primvar<2, double>;
using Rgba = Primvar<4, float>;

/// Faces as OpenSubdiv takes them: corner counts and corner vertex indices (lodkit vertices).
struct Faces {
  std::vector<int> sizes;
  std::vector<Index> corners;
};

/// Undoes the readers' fan triangulation: polygon k with s corners became s - 2 consecutive
/// triangles (c0, c1, c2), (c0, c2, c3), ...
Faces faces_of(const Mesh& mesh, std::span<const int> polygon_sizes, bool triangles_only) {
  Faces faces;
  if (polygon_sizes.empty() || triangles_only) {
    faces.sizes.assign(static_cast<std::size_t>(mesh.num_faces()), 3);
    faces.corners.assign(mesh.triangles.data(), mesh.triangles.data() + 3 * mesh.num_faces());
    return faces;
  }
  Index t = 0;
  for (const int s : polygon_sizes) {
    if (s < 3 || t + (s - 2) > mesh.num_faces())
      throw Error("subdivide: the polygon sizes do not match the mesh's triangles");
    const auto first = mesh.triangles.row(t);
    faces.sizes.push_back(s);
    faces.corners.insert(faces.corners.end(), {first[0], first[1], first[2]});
    for (int k = 1; k < s - 2; ++k) {
      const auto next = mesh.triangles.row(t + k);
      if (next[0] != first[0] || next[1] != faces.corners.back())
        throw Error("subdivide: the polygon sizes do not match the mesh's triangles");
      faces.corners.push_back(next[2]);
    }
    t += s - 2;
  }
  if (t != mesh.num_faces()) throw Error("subdivide: the polygon sizes do not match the mesh's triangles");
  return faces;
}

Sdc::SchemeType scheme_type(SubdivisionScheme s) {
  switch (s) {
    case SubdivisionScheme::Loop: return Sdc::SCHEME_LOOP;
    case SubdivisionScheme::CatmullClark: return Sdc::SCHEME_CATMARK;
    case SubdivisionScheme::Bilinear: return Sdc::SCHEME_BILINEAR;
  }
  return Sdc::SCHEME_LOOP;
}

Sdc::Options sdc_options(const SubdivideOptions& o) {
  Sdc::Options sdc;
  switch (o.boundary) {
    case BoundaryRule::None: sdc.SetVtxBoundaryInterpolation(Sdc::Options::VTX_BOUNDARY_NONE); break;
    case BoundaryRule::EdgeOnly: sdc.SetVtxBoundaryInterpolation(Sdc::Options::VTX_BOUNDARY_EDGE_ONLY); break;
    case BoundaryRule::EdgeAndCorner:
      sdc.SetVtxBoundaryInterpolation(Sdc::Options::VTX_BOUNDARY_EDGE_AND_CORNER);
      break;
  }
  constexpr Sdc::Options::FVarLinearInterpolation kUv[] = {
      Sdc::Options::FVAR_LINEAR_NONE,          Sdc::Options::FVAR_LINEAR_CORNERS_ONLY,
      Sdc::Options::FVAR_LINEAR_CORNERS_PLUS1, Sdc::Options::FVAR_LINEAR_CORNERS_PLUS2,
      Sdc::Options::FVAR_LINEAR_BOUNDARIES,    Sdc::Options::FVAR_LINEAR_ALL};
  sdc.SetFVarLinearInterpolation(kUv[static_cast<int>(o.uv_rule)]);
  return sdc;
}

/// Splits a quad (a, b, c, d) along its shorter diagonal; fans larger polygons.
template <typename Emit>
void triangulate(const std::vector<Index>& corners, const std::vector<Point>& points,
                 const std::vector<Index>& point_of, Emit&& emit) {
  if (corners.size() == 4) {
    auto at = [&](int k) {
      const Point& p = points[static_cast<std::size_t>(point_of[static_cast<std::size_t>(corners[k])])];
      return Eigen::Vector3d(p.v[0], p.v[1], p.v[2]);
    };
    if ((at(0) - at(2)).squaredNorm() <= (at(1) - at(3)).squaredNorm()) {
      emit(corners[0], corners[1], corners[2]), emit(corners[0], corners[2], corners[3]);
    } else {
      emit(corners[0], corners[1], corners[3]), emit(corners[1], corners[2], corners[3]);
    }
    return;
  }
  for (std::size_t k = 1; k + 1 < corners.size(); ++k) emit(corners[0], corners[k], corners[k + 1]);
}

Mesh subdivide_levels(const Mesh& mesh, const Faces& faces, const SubdivideOptions& o, int levels) {
  // Topology on positions: seam copies of a vertex are one OpenSubdiv vertex.
  const Eigen::VectorX<Index> cls = position_classes(mesh);
  std::vector<Index> point_of_vertex(static_cast<std::size_t>(mesh.num_vertices()));
  std::vector<Index> first_vertex_of_point;
  for (Index v = 0; v < mesh.num_vertices(); ++v) {
    if (cls[v] == v) {
      point_of_vertex[v] = static_cast<Index>(first_vertex_of_point.size());
      first_vertex_of_point.push_back(v);
    } else {
      point_of_vertex[v] = point_of_vertex[cls[v]];
    }
  }
  std::vector<Far::Index> topo_corners(faces.corners.size());
  for (std::size_t k = 0; k < faces.corners.size(); ++k) topo_corners[k] = point_of_vertex[faces.corners[k]];
  std::vector<Far::Index> uv_corners(faces.corners.begin(), faces.corners.end());

  Far::TopologyDescriptor desc;
  desc.numVertices = static_cast<int>(first_vertex_of_point.size());
  desc.numFaces = static_cast<int>(faces.sizes.size());
  desc.numVertsPerFace = faces.sizes.data();
  desc.vertIndicesPerFace = topo_corners.data();
  Far::TopologyDescriptor::FVarChannel uv_channel;
  const bool uvs = mesh.has_uvs();
  if (uvs) {
    uv_channel.numValues = mesh.num_vertices();
    uv_channel.valueIndices = uv_corners.data();
    desc.numFVarChannels = 1;
    desc.fvarChannels = &uv_channel;
  }
  using Factory = Far::TopologyRefinerFactory<Far::TopologyDescriptor>;
  std::unique_ptr<Far::TopologyRefiner> refiner(
      Factory::Create(desc, Factory::Options(scheme_type(o.scheme), sdc_options(o))));
  if (!refiner) throw Error("subdivide: OpenSubdiv rejected the mesh's topology");
  if (levels > 0) {
    Far::TopologyRefiner::UniformOptions uniform(levels);
    uniform.fullTopologyInLastLevel = true;  // Limit() needs the last level's full topology
    refiner->RefineUniform(uniform);
  }

  // Primvars at level 0, then refined level by level.
  std::vector<Point> points(first_vertex_of_point.size());
  std::vector<Rgba> colours(mesh.has_colours() ? points.size() : 0);
  for (std::size_t p = 0; p < points.size(); ++p) {
    const Index v = first_vertex_of_point[p];
    for (int k = 0; k < 3; ++k) points[p].v[k] = mesh.positions(v, k);
    if (!colours.empty())
      for (int k = 0; k < 4; ++k) colours[p].v[k] = mesh.attributes.colours(v, k);
  }
  std::vector<Uv> uv_values(uvs ? static_cast<std::size_t>(mesh.num_vertices()) : 0);
  for (std::size_t v = 0; v < uv_values.size(); ++v)
    for (int k = 0; k < 2; ++k) uv_values[v].v[k] = mesh.attributes.uvs(static_cast<Index>(v), k);

  const Far::PrimvarRefinerReal<double> primvars(*refiner);
  for (int level = 1; level <= levels; ++level) {
    const Far::TopologyLevel& child = refiner->GetLevel(level);
    std::vector<Point> next_points(static_cast<std::size_t>(child.GetNumVertices()));
    primvars.Interpolate(level, points, next_points);
    points = std::move(next_points);
    if (!colours.empty()) {
      std::vector<Rgba> next(static_cast<std::size_t>(child.GetNumVertices()));
      primvars.Interpolate(level, colours, next);
      colours = std::move(next);
    }
    if (uvs) {
      std::vector<Uv> next(static_cast<std::size_t>(child.GetNumFVarValues(0)));
      primvars.InterpolateFaceVarying(level, uv_values, next, 0);
      uv_values = std::move(next);
    }
  }
  if (o.limit) {
    std::vector<Point> limit_points(points.size());
    primvars.Limit(points, limit_points);
    points = std::move(limit_points);
    if (!colours.empty()) {
      std::vector<Rgba> limit(colours.size());
      primvars.Limit(colours, limit);
      colours = std::move(limit);
    }
    if (uvs) {
      std::vector<Uv> limit(uv_values.size());
      primvars.LimitFaceVarying(uv_values, limit, 0);
      uv_values = std::move(limit);
    }
  }

  // Output vertices: one per (point, UV value) pair in use, in first-use order.
  const Far::TopologyLevel& last = refiner->GetLevel(levels);
  std::vector<Index> point_of_out;
  std::vector<Index> uv_of_out;
  std::unordered_map<std::uint64_t, Index> out_of_pair;
  std::vector<Index> out_of_point(uvs ? 0 : points.size(), -1);
  auto output_vertex = [&](Index point, Index uv) {
    if (!uvs) {
      Index& slot = out_of_point[static_cast<std::size_t>(point)];
      if (slot < 0) slot = static_cast<Index>(point_of_out.size()), point_of_out.push_back(point);
      return slot;
    }
    const std::uint64_t key = (static_cast<std::uint64_t>(point) << 32) | static_cast<std::uint32_t>(uv);
    const auto [it, inserted] = out_of_pair.emplace(key, static_cast<Index>(point_of_out.size()));
    if (inserted) point_of_out.push_back(point), uv_of_out.push_back(uv);
    return it->second;
  };
  std::vector<Index> face_out, triangles;
  for (int f = 0; f < last.GetNumFaces(); ++f) {
    const auto fv = last.GetFaceVertices(f);
    face_out.clear();
    for (int k = 0; k < fv.size(); ++k)
      face_out.push_back(output_vertex(fv[k], uvs ? last.GetFaceFVarValues(f, 0)[k] : 0));
    triangulate(face_out, points, point_of_out, [&](Index a, Index b, Index c) {
      triangles.insert(triangles.end(), {a, b, c});
    });
  }

  Mesh out;
  const auto nv = static_cast<Index>(point_of_out.size());
  out.positions.resize(nv, 3);
  if (uvs) out.attributes.uvs.resize(nv, 2);
  if (!colours.empty()) out.attributes.colours.resize(nv, 4);
  for (Index v = 0; v < nv; ++v) {
    const auto p = static_cast<std::size_t>(point_of_out[static_cast<std::size_t>(v)]);
    out.positions.row(v) << points[p].v[0], points[p].v[1], points[p].v[2];
    if (uvs) {
      const Uv& uv = uv_values[static_cast<std::size_t>(uv_of_out[static_cast<std::size_t>(v)])];
      out.attributes.uvs.row(v) << uv.v[0], uv.v[1];
    }
    if (!colours.empty()) out.attributes.colours.row(v) << colours[p].v[0], colours[p].v[1], colours[p].v[2], colours[p].v[3];
  }
  out.triangles = Eigen::Map<const Triangles>(triangles.data(), static_cast<Index>(triangles.size() / 3), 3);
  if (mesh.has_normals()) out.attributes.normals = compute_vertex_normals(out);
  return out;
}

// Triangles `levels` levels make: Loop splits each triangle into 4; Catmull-Clark and bilinear turn
// an n-gon into n quads, then each quad into 4, and every quad is written as 2 triangles.
double output_triangles(const Mesh& mesh, const Faces& faces, SubdivisionScheme scheme, int levels) {
  if (levels == 0) return static_cast<double>(mesh.num_faces());
  const double growth = std::pow(4.0, levels - 1);
  if (scheme == SubdivisionScheme::Loop) return 4.0 * growth * static_cast<double>(mesh.num_faces());
  double corners = 0;
  for (const int size : faces.sizes) corners += size;
  return 2.0 * growth * corners;
}

// `advice`: what to do instead.
void check_output_size(const Mesh& mesh, const Faces& faces, const SubdivideOptions& o, int levels,
                       const std::string& advice) {
  const double triangles = output_triangles(mesh, faces, o.scheme, levels);
  if (triangles > static_cast<double>(o.max_faces))
    throw Error(fmt::format("subdivide: {} level{} would make {:.0f} triangles, more than the limit of {} (max "
                            "faces; refining takes about 260 bytes a face); {}",
                            levels, levels == 1 ? "" : "s", triangles, o.max_faces, advice));
}

}  // namespace

SubdivideResult subdivide(const Mesh& mesh, const SubdivideOptions& options, std::span<const int> polygon_sizes) {
  validate(mesh, "subdivide input");
  if (mesh.num_faces() == 0) throw Error("subdivide: the mesh has no faces");
  if (options.max_levels < 0 || options.max_levels > 10)
    throw Error(fmt::format("subdivide: max levels must be 0..10, not {}", options.max_levels));
  if (options.max_faces < 1 || options.max_faces > std::numeric_limits<Index>::max())
    throw Error(fmt::format("subdivide: max faces must be 1..{}, not {}", std::numeric_limits<Index>::max(),
                            options.max_faces));
  const Faces faces = faces_of(mesh, polygon_sizes, options.scheme == SubdivisionScheme::Loop);
  SubdivideResult result;
  if (!options.tolerance) {
    if (options.levels < 0 || options.levels > 10)
      throw Error(fmt::format("subdivide: levels must be 0..10, not {}", options.levels));
    check_output_size(mesh, faces, options, options.levels, "use fewer levels or raise the limit");
    result.levels = options.levels;
    result.mesh = subdivide_levels(mesh, faces, options, options.levels);
    return result;
  }
  if (!(*options.tolerance > 0.0) || !std::isfinite(*options.tolerance))
    throw Error(fmt::format("subdivide: tolerance must be positive, not {}", *options.tolerance));
  const double tolerance =
      options.tolerance_is_relative ? *options.tolerance * bounding_box(mesh).diagonal().norm() : *options.tolerance;
  // Model no more than the scene needs: stop at the first level the next one barely changes.
  Mesh current = subdivide_levels(mesh, faces, options, 0);
  for (int level = 0; level < options.max_levels; ++level) {
    if (level > 0)  // before the level that would be too large
      check_output_size(mesh, faces, options, level + 1,
                        fmt::format("level {} -> {} still moves the surface by {:.4g} > tolerance {:.4g}; raise the "
                                    "tolerance or the limit", level - 1, level, result.level_change.back(), tolerance));
    else
      check_output_size(mesh, faces, options, 1, "raise the limit");
    Mesh next = subdivide_levels(mesh, faces, options, level + 1);
    const double change = compare(current, next).hausdorff;
    result.level_change.push_back(change);
    if (change <= tolerance) {
      result.levels = level;
      result.mesh = std::move(current);
      return result;
    }
    current = std::move(next);
  }
  throw Error(fmt::format("subdivide: {} levels still change the surface by {:.4g} > tolerance {:.4g}; "
                          "raise --max-levels or the tolerance",
                          options.max_levels, result.level_change.back(), tolerance));
}

}  // namespace lodkit
