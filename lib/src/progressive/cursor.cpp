// PMCursor: the current level's mutable state. A split writes only what it changes (the split point's
// position, the corners that move to the new point, changed attribute values); new points, wedges and
// faces already hold their values from construction, because a level is a prefix of every array.
#include <lodkit/error.h>
#include <lodkit/progressive.h>

#include <algorithm>
#include <fmt/format.h>
#include <numeric>

#include "progressive/split_state.h"

namespace lodkit {

PMCursor::PMCursor(const ProgressiveMesh& pm) : pm_(&pm) {
  detail::SplitState base = detail::base_state(pm);
  positions_ = std::move(base.positions);
  attributes_ = std::move(base.attributes);
  corners_ = std::move(base.corners);
}

void PMCursor::apply(Index split, bool fine) { detail::apply_split(*pm_, split, fine, positions_, attributes_, corners_); }

bool PMCursor::refine() {
  if (level_ >= pm_->max_level()) return false;
  apply(level_++, true);
  return true;
}

bool PMCursor::coarsen() {
  if (level_ <= 0) return false;
  apply(--level_, false);
  return true;
}

void PMCursor::go_to(Index level) {
  level = std::clamp<Index>(level, 0, pm_->max_level());
  while (level_ < level) refine();
  while (level_ > level) coarsen();
}

Index PMCursor::ancestor(Index wedge, Index level) const {
  const Index limit = pm_->num_wedges(std::clamp<Index>(level, 0, pm_->max_level()));
  while (wedge >= limit && wedge >= 0) wedge = pm_->wedge_parent[static_cast<std::size_t>(wedge)];
  return wedge;
}

ExtractedLevel PMCursor::extract(VertexOrder order) const {
  const ProgressiveMesh& pm = *pm_;
  const bool input_order = order == VertexOrder::Input && pm.knows_input_order();
  const bool whole_input = input_order && level_ == pm.max_level();
  const Index nw = num_wedges(), nf = num_faces();

  // Which wedges and faces, in which order.
  std::vector<Index> faces(static_cast<std::size_t>(nf)), wedges;
  std::iota(faces.begin(), faces.end(), 0);
  std::vector<char> used(static_cast<std::size_t>(nw), whole_input ? 1 : 0);
  if (!whole_input)
    for (Index c = 0; c < 3 * nf; ++c) used[static_cast<std::size_t>(corners_[static_cast<std::size_t>(c)])] = 1;
  for (Index w = 0; w < nw; ++w)
    if (used[static_cast<std::size_t>(w)]) wedges.push_back(w);
  if (input_order) {
    auto by = [](const std::vector<Index>& key) {
      return [&key](Index a, Index b) { return key[static_cast<std::size_t>(a)] < key[static_cast<std::size_t>(b)]; };
    };
    std::sort(faces.begin(), faces.end(), by(pm.face_input));
    std::sort(wedges.begin(), wedges.end(), by(pm.wedge_input));
  }

  ExtractedLevel out;
  out.level = level_;
  Mesh& m = out.mesh;
  const Index extra_v = whole_input ? static_cast<Index>(pm.extra_vertex_input.size()) : 0;
  const Index extra_f = whole_input ? static_cast<Index>(pm.extra_face_input.size()) : 0;
  const Index nv_out = static_cast<Index>(wedges.size()) + extra_v, nf_out = nf + extra_f;
  detail::size_level_mesh(pm, nv_out, nf_out, m);
  out.vertex_wedge.assign(static_cast<std::size_t>(nv_out), -1);
  out.vertex_origin.assign(static_cast<std::size_t>(nv_out), -1);

  // Row of each wedge (and, for the whole input, of each input vertex).
  std::vector<Index> row_of(static_cast<std::size_t>(nw), -1);
  auto put_vertex = [&](Index row, Index w) {
    row_of[static_cast<std::size_t>(w)] = row;
    out.vertex_wedge[static_cast<std::size_t>(row)] = w;
    out.vertex_origin[static_cast<std::size_t>(row)] = pm.knows_input_order() ? pm.wedge_input[static_cast<std::size_t>(w)] : w;
    detail::put_wedge(pm, positions_, attributes_, w, m, row);
  };
  if (whole_input) {
    // Input numbering exactly: wedges and extra vertices go to their input rows.
    for (Index w : wedges) put_vertex(pm.wedge_input[static_cast<std::size_t>(w)], w);
    for (Index i = 0; i < extra_v; ++i) {
      const Index row = pm.extra_vertex_input[static_cast<std::size_t>(i)];
      out.vertex_origin[static_cast<std::size_t>(row)] = row;
      m.positions.row(row) = pm.extra_vertices.positions.row(i);
      if (pm.has_normals) m.attributes.normals.row(row) = pm.extra_vertices.attributes.normals.row(i);
      if (pm.has_uvs) m.attributes.uvs.row(row) = pm.extra_vertices.attributes.uvs.row(i);
      if (pm.has_colours) m.attributes.colours.row(row) = pm.extra_vertices.attributes.colours.row(i);
    }
  } else {
    for (std::size_t i = 0; i < wedges.size(); ++i) put_vertex(static_cast<Index>(i), wedges[i]);
  }
  for (Index i = 0; i < nf; ++i) {
    const Index f = faces[static_cast<std::size_t>(i)];
    const Index row = whole_input ? pm.face_input[static_cast<std::size_t>(f)] : i;
    for (int k = 0; k < 3; ++k) m.triangles(row, k) = row_of[static_cast<std::size_t>(corner_wedge(f, k))];
    if (pm.has_face_colours) m.attributes.face_colours.row(row) = pm.face_colours.row(f);
  }
  if (whole_input) {
    for (Index i = 0; i < extra_f; ++i) {
      const Index row = pm.extra_face_input[static_cast<std::size_t>(i)];
      m.triangles.row(row) = pm.extra_faces.row(i);
      if (pm.has_face_colours) m.attributes.face_colours.row(row) = pm.face_colours.row(nf + i);
    }
    for (const auto& [f, k, v] : pm.corner_exceptions) m.triangles(f, k) = v;
  }
  return out;
}

ExtractedLevel extract_level(const ProgressiveMesh& pm, Index level, VertexOrder order) {
  if (level < 0 || level > pm.max_level())
    throw Error(fmt::format("progressive mesh: level {} is outside 0..{}", level, pm.max_level()));
  PMCursor cursor(pm);
  cursor.go_to(level);
  return cursor.extract(order);
}

}  // namespace lodkit
