// Geomorphs (Hoppe 1996, section 4.2): the fine level's connectivity with each vertex interpolating
// from its ancestor in the coarse level to itself, so switching levels does not pop.
#include <lodkit/error.h>
#include <lodkit/progressive.h>

#include <fmt/format.h>

namespace lodkit {

Geomorph make_geomorph(const ProgressiveMesh& pm, Index coarse_level, Index fine_level, VertexOrder order) {
  if (!(0 <= coarse_level && coarse_level <= fine_level && fine_level <= pm.max_level()))
    throw Error(fmt::format("geomorph: levels must satisfy 0 <= from <= to <= {}, got from {} to {}", pm.max_level(),
                            coarse_level, fine_level));
  Geomorph g;
  g.coarse_level = coarse_level;
  g.fine_level = fine_level;
  PMCursor cursor(pm);
  cursor.go_to(fine_level);
  g.fine = cursor.extract(order);
  cursor.go_to(coarse_level);

  const Mesh& fine = g.fine.mesh;
  const Index n = fine.num_vertices();
  g.start_positions.resize(n, 3);
  if (pm.has_normals) g.start_normals.resize(n, 3);
  if (pm.has_uvs) g.start_uvs.resize(n, 2);
  if (pm.has_colours) g.start_colours.resize(n, 4);
  for (Index v = 0; v < n; ++v) {
    const Index wedge = g.fine.vertex_wedge[static_cast<std::size_t>(v)];
    if (wedge < 0) {  // a vertex only the finest input level has: it does not move
      g.start_positions.row(v) = fine.positions.row(v);
      if (pm.has_normals) g.start_normals.row(v) = fine.attributes.normals.row(v);
      if (pm.has_uvs) g.start_uvs.row(v) = fine.attributes.uvs.row(v);
      if (pm.has_colours) g.start_colours.row(v) = fine.attributes.colours.row(v);
      continue;
    }
    const Index a = cursor.ancestor(wedge, coarse_level);
    g.start_positions.row(v) = cursor.point_position(pm.wedge_point[static_cast<std::size_t>(a)]).transpose();
    const double* value = cursor.wedge_attributes(a);
    int i = 0;
    if (pm.has_normals) for (int d = 0; d < 3; ++d) g.start_normals(v, d) = value[i++];
    if (pm.has_uvs) for (int d = 0; d < 2; ++d) g.start_uvs(v, d) = value[i++];
    if (pm.has_colours) for (int d = 0; d < 4; ++d) g.start_colours(v, d) = static_cast<float>(value[i++]);
  }
  return g;
}

void Geomorph::evaluate(double alpha, Mesh& out) const {
  if (!(alpha >= 0 && alpha <= 1)) throw Error(fmt::format("geomorph: alpha must be in [0, 1], got {}", alpha));
  const Mesh& end = fine.mesh;
  if (out.num_faces() != end.num_faces() || out.num_vertices() != end.num_vertices()) out = end;
  // (1 - a) s + a e is exactly s at a = 0 and exactly e at a = 1.
  const double a = alpha, b = 1.0 - alpha;
  out.positions = b * start_positions + a * end.positions;
  if (end.has_normals()) {
    out.attributes.normals = b * start_normals + a * end.attributes.normals;
    if (alpha > 0 && alpha < 1) out.attributes.normals.rowwise().normalize();
  }
  if (end.has_uvs()) out.attributes.uvs = b * start_uvs + a * end.attributes.uvs;
  if (end.has_colours())
    out.attributes.colours = static_cast<float>(b) * start_colours + static_cast<float>(a) * end.attributes.colours;
}

Mesh Geomorph::at(double alpha) const {
  Mesh out;
  evaluate(alpha, out);
  return out;
}

}  // namespace lodkit
