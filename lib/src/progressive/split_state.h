#pragma once
// What a progressive mesh's splits write (point positions, wedge attributes, face corners), shared by
// the cursor, which walks between uniform levels, and selective refinement, which applies any
// dependency-closed set of splits.
#include <lodkit/mesh.h>
#include <lodkit/progressive.h>

#include <algorithm>
#include <cstddef>
#include <vector>

namespace lodkit::detail {

struct SplitState {
  std::vector<Eigen::Vector3d> positions;  // per point, all levels (later points at their split's new_position)
  std::vector<double> attributes;          // per wedge
  std::vector<Index> corners;              // per face corner
};

// The base mesh; every later point, wedge and face already holds the values it appears with.
inline SplitState base_state(const ProgressiveMesh& pm) {
  SplitState s;
  s.positions.resize(static_cast<std::size_t>(pm.num_points(pm.max_level())));
  std::copy(pm.base_positions.begin(), pm.base_positions.end(), s.positions.begin());
  for (std::size_t j = 0; j < pm.splits.size(); ++j) s.positions[pm.base_points + j] = pm.splits[j].new_position;
  s.attributes = pm.wedge_attributes;
  s.corners.resize(3 * pm.face_corners.size());
  for (std::size_t f = 0; f < pm.face_corners.size(); ++f)
    for (int k = 0; k < 3; ++k) s.corners[3 * f + k] = pm.face_corners[f][k];
  return s;
}

// Writes split `split`'s changes in their fine (refine) or coarse (coarsen) state.
inline void apply_split(const ProgressiveMesh& pm, Index split, bool fine, std::vector<Eigen::Vector3d>& positions,
                        std::vector<double>& attributes, std::vector<Index>& corners) {
  const VertexSplit& s = pm.splits[static_cast<std::size_t>(split)];
  const CornerChange* c = pm.corner_changes.data() + s.first_change;
  for (Index i = 0; i < s.num_changes; ++i)
    corners[static_cast<std::size_t>(c[i].corner)] = fine ? c[i].fine_wedge : c[i].coarse_wedge;
  positions[static_cast<std::size_t>(s.point)] = fine ? s.position : s.coarse_position;
  // attribute_values holds the coarse values, then the fine ones.
  const std::size_t dims = static_cast<std::size_t>(pm.attribute_dims);
  for (Index i = 0; i < s.num_attribute_changes; ++i) {
    const AttributeChange& a = pm.attribute_changes[static_cast<std::size_t>(s.first_attribute_change + i)];
    std::copy_n(&pm.attribute_values[static_cast<std::size_t>(a.first_value) + (fine ? dims : 0)], dims,
                &attributes[dims * static_cast<std::size_t>(a.wedge)]);
  }
}

// Sizes `m` for a level of `vertices` and `faces`, with the attributes the stream carries.
inline void size_level_mesh(const ProgressiveMesh& pm, Index vertices, Index faces, Mesh& m) {
  m.positions.resize(vertices, 3);
  m.triangles.resize(faces, 3);
  if (pm.has_normals) m.attributes.normals.resize(vertices, 3);
  if (pm.has_uvs) m.attributes.uvs.resize(vertices, 2);
  if (pm.has_colours) m.attributes.colours.resize(vertices, 4);
  if (pm.has_face_colours) m.attributes.face_colours.resize(faces, 4);
}

// Row `row` of `m` from wedge `w`: its point's position and its attribute values (normals, UVs,
// colours) as `positions` and `attributes` hold them.
inline void put_wedge(const ProgressiveMesh& pm, const std::vector<Eigen::Vector3d>& positions,
                      const std::vector<double>& attributes, Index w, Mesh& m, Index row) {
  m.positions.row(row) = positions[static_cast<std::size_t>(pm.wedge_point[static_cast<std::size_t>(w)])].transpose();
  const double* a = attributes.data() + static_cast<std::size_t>(pm.attribute_dims) * static_cast<std::size_t>(w);
  int i = 0;
  if (pm.has_normals) for (int d = 0; d < 3; ++d) m.attributes.normals(row, d) = a[i++];
  if (pm.has_uvs) for (int d = 0; d < 2; ++d) m.attributes.uvs(row, d) = a[i++];
  if (pm.has_colours) for (int d = 0; d < 4; ++d) m.attributes.colours(row, d) = static_cast<float>(a[i++]);
}

}  // namespace lodkit::detail
