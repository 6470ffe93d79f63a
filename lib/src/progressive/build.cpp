// build_progressive_mesh(): replays the engine's collapse records forward to learn what every face,
// wedge and point looked like just before each collapse, then numbers everything in refinement order.
#include <lodkit/error.h>
#include <lodkit/progressive.h>

#include <algorithm>
#include <fmt/format.h>

#include "core/geometry.h"
#include "core/huge_pages.h"
#include "core/topology.h"

namespace lodkit {
namespace {

/// The wedge of the kept point that wedge w of the removed point merged into (-1 if w was unused).
Index merged_into(const CollapseRecord& rec, Index w) {
  for (const auto& [wu, wv] : rec.wedge_map)
    if (wu == w) return wv;
  return -1;
}

void copy_attributes(const Mesh& mesh, Index v, double* out) {
  const Attributes& a = mesh.attributes;
  int i = 0;
  if (mesh.has_normals()) for (int d = 0; d < 3; ++d) out[i++] = a.normals(v, d);
  if (mesh.has_uvs()) for (int d = 0; d < 2; ++d) out[i++] = a.uvs(v, d);
  if (mesh.has_colours()) for (int d = 0; d < 4; ++d) out[i++] = a.colours(v, d);
}

}  // namespace

ProgressiveMesh build_progressive_mesh(const Mesh& input, const ProgressiveOptions& options) {
  validate(input, "progressive mesh");
  // An input whose faces disagree on orientation is built with them turned (SimplifyOptions::orient_faces;
  // simplify() leaves that to its caller when it records, as the records name the corners replayed here).
  Mesh turned;
  Index turned_faces = 0;
  const Mesh& mesh = detail::oriented(input, options.simplify.orient_faces, turned, turned_faces);
  if (options.base_faces && *options.base_faces < 0)
    throw Error(fmt::format("progressive mesh: base face count must not be negative, got {}", *options.base_faces));
  SimplifyOptions so = options.simplify;
  so.target_ratio.reset();
  so.target_faces = options.base_faces.value_or(0);
  so.record_collapses = true;
  SimplifyResult r = simplify(mesh, so);

  const Index nv = mesh.num_vertices(), nf = mesh.num_faces();
  const std::size_t dims = static_cast<std::size_t>(attribute_values_per_vertex(mesh));
  const std::vector<Index>& point_of = r.vertex_point;
  const std::vector<Index>& canonical = r.vertex_canonical;
  const Index num_engine_points =
      point_of.empty() ? 0 : *std::max_element(point_of.begin(), point_of.end()) + 1;

  // Faces the engine uses (three distinct points) and the wedges they reference.
  std::vector<std::array<Index, 3>> corners(static_cast<std::size_t>(nf));
  std::vector<char> face_used(static_cast<std::size_t>(nf), 0), wedge_used(static_cast<std::size_t>(nv), 0);
  for (Index f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) corners[f][k] = canonical[mesh.triangles(f, k)];
    const Index a = point_of[corners[f][0]], b = point_of[corners[f][1]], c = point_of[corners[f][2]];
    if (a == b || b == c || a == c) continue;
    face_used[f] = 1;
    for (Index w : corners[f]) wedge_used[w] = 1;
  }
  // Each point's wedges: the referenced canonical vertices at its position, in input order.
  std::vector<std::vector<Index>> point_wedges(static_cast<std::size_t>(num_engine_points));
  for (Index w = 0; w < nv; ++w)
    if (wedge_used[w]) point_wedges[point_of[w]].push_back(w);

  // Forward replay: positions, attribute values and corners just before each collapse.
  std::vector<Eigen::Vector3d> position(static_cast<std::size_t>(num_engine_points));
  std::vector<detail::Ball> ball(static_cast<std::size_t>(num_engine_points));
  for (Index w = 0; w < nv; ++w) position[point_of[w]] = mesh.positions.row(w).transpose();
  for (Index p = 0; p < num_engine_points; ++p) ball[p] = {position[p], 0.0};
  std::vector<double> value(dims * static_cast<std::size_t>(nv));
  for (Index w = 0; w < nv; ++w) copy_attributes(mesh, w, value.data() + dims * w);

  const std::size_t nc = r.records.size();
  std::vector<std::array<Index, 3>> creation_corners(static_cast<std::size_t>(nf));
  std::vector<Eigen::Vector3d> removed_position(nc);
  std::vector<std::vector<double>> removed_values(nc);  // the removed point's wedges' values
  std::vector<double> bound_after(nc);
  std::vector<std::vector<double>> attributes_before(nc);  // of the vertices whose values the collapse changes
  double bound = 0;
  for (std::size_t c = 0; c < nc; ++c) {
    const CollapseRecord& rec = r.records[c];
    for (Index f : rec.removed_faces) creation_corners[f] = corners[f];
    removed_position[c] = position[rec.removed];
    for (Index w : point_wedges[rec.removed])
      removed_values[c].insert(removed_values[c].end(), value.data() + dims * w, value.data() + dims * (w + 1));
    for (const auto& [f, k, old] : rec.changed_corners) {
      const Index to = merged_into(rec, old);
      if (to < 0) throw Error("progressive mesh: internal error: a collapse record misses a wedge");
      corners[f][k] = to;
    }
    for (std::size_t i = 0; i < rec.attribute_vertices.size(); ++i) {
      double* v = value.data() + dims * rec.attribute_vertices[i];
      attributes_before[c].insert(attributes_before[c].end(), v, v + dims);  // input values stay bit-exact
      std::copy_n(rec.attributes_after.data() + dims * i, dims, v);
    }
    position[rec.kept] = rec.kept_after;
    ball[rec.kept] = detail::enclosing_ball(ball[rec.kept], ball[rec.removed]);
    bound = std::max(bound, (rec.kept_after - ball[rec.kept].centre).norm() + ball[rec.kept].radius);
    bound_after[c] = bound;
  }

  ProgressiveMesh pm;
  pm.has_normals = mesh.has_normals();
  pm.has_uvs = mesh.has_uvs();
  pm.has_colours = mesh.has_colours();
  pm.has_face_colours = mesh.has_face_colours();
  pm.attribute_dims = static_cast<int>(dims);
  pm.bounds = bounding_box(mesh);
  pm.input_vertices = nv;
  pm.input_faces = nf;

  // Numbering. Points: the base's (in input order of their first wedge), then one per split.
  std::vector<char> removed(static_cast<std::size_t>(num_engine_points), 0);
  for (const CollapseRecord& rec : r.records) removed[rec.removed] = 1;
  std::vector<Index> point_id(static_cast<std::size_t>(num_engine_points), -1);
  std::vector<Index> point_order;
  for (Index w = 0; w < nv; ++w) {
    const Index p = point_of[w];
    if (wedge_used[w] && !removed[p] && point_id[p] < 0) point_id[p] = static_cast<Index>(point_order.size()), point_order.push_back(p);
  }
  pm.base_points = static_cast<Index>(point_order.size());
  for (std::size_t j = 0; j < nc; ++j) {
    const Index p = r.records[nc - 1 - j].removed;
    point_id[p] = pm.base_points + static_cast<Index>(j);
    point_order.push_back(p);
  }
  // Wedges: all of a point's wedges appear with it.
  std::vector<Index> wedge_id(static_cast<std::size_t>(nv), -1);
  for (Index p : point_order) {
    for (Index w : point_wedges[p]) {
      wedge_id[w] = static_cast<Index>(pm.wedge_input.size());
      pm.wedge_input.push_back(w);
      pm.wedge_point.push_back(point_id[p]);
    }
  }
  // Base wedges are those of base points; the rest follow the split order.
  pm.base_wedges = 0;
  for (Index p = 0; p < pm.base_points; ++p) pm.base_wedges += static_cast<Index>(point_wedges[point_order[p]].size());
  // Faces: the base's in input order, then each split's in the order the collapse removed them.
  std::vector<Index> face_id(static_cast<std::size_t>(nf), -1);
  std::vector<char> face_removed(static_cast<std::size_t>(nf), 0);
  for (const CollapseRecord& rec : r.records)
    for (Index f : rec.removed_faces) face_removed[f] = 1;
  for (Index f = 0; f < nf; ++f)
    if (face_used[f] && !face_removed[f]) face_id[f] = static_cast<Index>(pm.face_input.size()), pm.face_input.push_back(f);
  pm.base_faces = static_cast<Index>(pm.face_input.size());

  auto wid = [&](Index w) {
    const Index id = wedge_id[w];
    if (id < 0) throw Error("progressive mesh: internal error: a face uses an unnumbered wedge");
    return id;
  };
  pm.wedge_parent.assign(pm.wedge_input.size(), -1);
  pm.wedge_attributes.assign(dims * pm.wedge_input.size(), 0.0);
  pm.base_positions.resize(static_cast<std::size_t>(pm.base_points));
  for (Index i = 0; i < pm.base_points; ++i) pm.base_positions[i] = position[point_order[i]];
  for (Index i = 0; i < pm.base_wedges; ++i)
    std::copy_n(value.data() + dims * pm.wedge_input[i], dims, pm.wedge_attributes.data() + dims * i);

  detail::resize_huge(pm.splits, nc);
  Index next_wedge = pm.base_wedges;
  for (std::size_t j = 0; j < nc; ++j) {
    const std::size_t c = nc - 1 - j;
    const CollapseRecord& rec = r.records[c];
    VertexSplit& s = pm.splits[j];
    s.point = point_id[rec.kept];
    s.position = rec.kept_before;
    s.coarse_position = rec.kept_after;
    s.new_position = removed_position[c];
    s.first_wedge = next_wedge;
    s.num_wedges = static_cast<Index>(point_wedges[rec.removed].size());
    for (Index i = 0; i < s.num_wedges; ++i) {
      const Index w = point_wedges[rec.removed][i];
      std::copy_n(removed_values[c].data() + dims * i, dims, pm.wedge_attributes.data() + dims * (next_wedge + i));
      // The parent: the kept wedge this one merged into (or, if it was unused then, the kept point's
      // first wedge; the .pm reader derives the same).
      const Index merged = merged_into(rec, w);
      pm.wedge_parent[next_wedge + i] = wid(merged >= 0 ? merged : point_wedges[rec.kept].front());
    }
    next_wedge += s.num_wedges;
    s.first_face = static_cast<Index>(pm.face_input.size());
    s.num_faces = static_cast<Index>(rec.removed_faces.size());
    for (Index f : rec.removed_faces) face_id[f] = static_cast<Index>(pm.face_input.size()), pm.face_input.push_back(f);
  }
  // Corner changes and attribute changes need every face numbered first.
  for (std::size_t j = 0; j < nc; ++j) {
    const CollapseRecord& rec = r.records[nc - 1 - j];
    const std::vector<double>& before = attributes_before[nc - 1 - j];
    VertexSplit& s = pm.splits[j];
    s.first_change = static_cast<Index>(pm.corner_changes.size());
    for (const auto& [f, k, old] : rec.changed_corners)
      pm.corner_changes.push_back({3 * face_id[f] + k, wid(merged_into(rec, old)), wid(old)});
    s.num_changes = static_cast<Index>(pm.corner_changes.size()) - s.first_change;
    s.first_attribute_change = static_cast<Index>(pm.attribute_changes.size());
    for (std::size_t i = 0; i < rec.attribute_vertices.size(); ++i) {
      pm.attribute_changes.push_back({wid(rec.attribute_vertices[i]), static_cast<Index>(pm.attribute_values.size())});
      pm.attribute_values.insert(pm.attribute_values.end(), rec.attributes_after.data() + dims * i,
                                 rec.attributes_after.data() + dims * (i + 1));
      pm.attribute_values.insert(pm.attribute_values.end(), before.data() + dims * i, before.data() + dims * (i + 1));
    }
    s.num_attribute_changes = static_cast<Index>(pm.attribute_changes.size()) - s.first_attribute_change;
  }
  pm.face_corners.resize(pm.face_input.size());
  for (std::size_t i = 0; i < pm.face_input.size(); ++i) {
    const Index f = pm.face_input[i];
    const std::array<Index, 3>& src = static_cast<Index>(i) < pm.base_faces ? corners[f] : creation_corners[f];
    for (int k = 0; k < 3; ++k) pm.face_corners[i][k] = wid(src[k]);
  }

  // Error bounds: level i is reached after nc - i collapses.
  pm.level_error.resize(nc + 1);
  for (std::size_t i = 0; i <= nc; ++i) pm.level_error[i] = i == nc ? 0.0 : bound_after[nc - 1 - i];

  // What only the finest level restores: vertices outside the wedges, degenerate faces, duplicates.
  for (Index v = 0; v < nv; ++v)
    if (wedge_id[v] < 0) pm.extra_vertex_input.push_back(v);
  pm.extra_vertices.positions.resize(static_cast<Index>(pm.extra_vertex_input.size()), 3);
  if (pm.has_normals) pm.extra_vertices.attributes.normals.resize(pm.extra_vertices.positions.rows(), 3);
  if (pm.has_uvs) pm.extra_vertices.attributes.uvs.resize(pm.extra_vertices.positions.rows(), 2);
  if (pm.has_colours) pm.extra_vertices.attributes.colours.resize(pm.extra_vertices.positions.rows(), 4);
  for (std::size_t i = 0; i < pm.extra_vertex_input.size(); ++i) {
    const Index v = pm.extra_vertex_input[i], row = static_cast<Index>(i);
    pm.extra_vertices.positions.row(row) = mesh.positions.row(v);
    if (pm.has_normals) pm.extra_vertices.attributes.normals.row(row) = mesh.attributes.normals.row(v);
    if (pm.has_uvs) pm.extra_vertices.attributes.uvs.row(row) = mesh.attributes.uvs.row(v);
    if (pm.has_colours) pm.extra_vertices.attributes.colours.row(row) = mesh.attributes.colours.row(v);
  }
  for (Index f = 0; f < nf; ++f)
    if (!face_used[f]) pm.extra_face_input.push_back(f);
  pm.extra_faces.resize(static_cast<Index>(pm.extra_face_input.size()), 3);
  for (std::size_t i = 0; i < pm.extra_face_input.size(); ++i)
    pm.extra_faces.row(static_cast<Index>(i)) = mesh.triangles.row(pm.extra_face_input[i]);
  for (Index f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k)
      if (face_used[f] && mesh.triangles(f, k) != canonical[mesh.triangles(f, k)])
        pm.corner_exceptions.push_back({f, k, mesh.triangles(f, k)});
  if (pm.has_face_colours) {
    // Per face, then per extra (degenerate) face.
    const std::size_t n = pm.face_input.size();
    pm.face_colours.resize(static_cast<Index>(n + pm.extra_face_input.size()), 4);
    for (std::size_t i = 0; i < n; ++i) pm.face_colours.row(static_cast<Index>(i)) = mesh.attributes.face_colours.row(pm.face_input[i]);
    for (std::size_t i = 0; i < pm.extra_face_input.size(); ++i)
      pm.face_colours.row(static_cast<Index>(n + i)) = mesh.attributes.face_colours.row(pm.extra_face_input[i]);
  }
  if (options.measure_levels) measure_levels(pm, mesh);
  return pm;
}

}  // namespace lodkit
