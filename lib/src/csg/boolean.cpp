// The one translation unit that compiles CGAL's corefinement (it is the slowest code in the project).
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/repair_degeneracies.h>
#include <CGAL/Polygon_mesh_processing/shape_predicates.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <lodkit/csg.h>
#include <lodkit/error.h>
#include <lodkit/primitives.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <fmt/format.h>
#include <iterator>
#include <numeric>

namespace lodkit {
namespace {

namespace PMP = CGAL::Polygon_mesh_processing;

// Builds the Surface_mesh. Faces whose orientation disagrees with their neighbours' cannot be
// added as they are; then the mesh goes through CGAL's polygon-soup orientation, with a warning.
template <typename Kernel>
CGAL::Surface_mesh<typename Kernel::Point_3> to_surface_mesh(const Mesh& m, const std::string& name,
                                                             std::vector<std::string>& warnings) {
  using SM = CGAL::Surface_mesh<typename Kernel::Point_3>;
  SM sm;
  std::vector<typename SM::Vertex_index> v;
  v.reserve(static_cast<std::size_t>(m.num_vertices()));
  for (Index i = 0; i < m.num_vertices(); ++i) v.push_back(sm.add_vertex({m.positions(i, 0), m.positions(i, 1), m.positions(i, 2)}));
  bool all = true;
  for (Index f = 0; f < m.num_faces() && all; ++f)
    all = sm.add_face(v[m.triangles(f, 0)], v[m.triangles(f, 1)], v[m.triangles(f, 2)]) != SM::null_face();
  if (all) return sm;
  std::vector<typename Kernel::Point_3> points;
  std::vector<std::array<std::size_t, 3>> polygons;
  for (Index i = 0; i < m.num_vertices(); ++i) points.emplace_back(m.positions(i, 0), m.positions(i, 1), m.positions(i, 2));
  for (Index f = 0; f < m.num_faces(); ++f)
    polygons.push_back({std::size_t(m.triangles(f, 0)), std::size_t(m.triangles(f, 1)), std::size_t(m.triangles(f, 2))});
  const bool clean = PMP::orient_polygon_soup(points, polygons);
  SM oriented;
  PMP::polygon_soup_to_polygon_mesh(points, polygons, oriented);
  warnings.push_back(fmt::format("{}: faces were inconsistently oriented; made consistent{}", name,
                                 clean ? "" : " (some non-manifold vertices were split)"));
  return oriented;
}

double rounded(double x) { return x; }

// A lazy exact number's own to_double() returns the middle of whatever interval it holds, which
// depends on what was computed before (and on which thread): the same point could round two ways.
// Rounding the exact value gives one answer, so the halves of split_solid() meet vertex for vertex.
template <typename ET>
double rounded(const CGAL::Lazy_exact_nt<ET>& x) {
  const auto& interval = x.approx();
  if (interval.inf() == interval.sup()) return interval.inf();
  const ET& e = CGAL::exact(x);
  const auto [below, above] = CGAL::to_interval(e);  // the doubles on either side
  if (below == above) return below;
  return e - ET(below) <= ET(above) - e ? below : above;  // the nearest
}

// The mesh in a canonical order: vertices sorted by position, faces by their vertex indices (each
// starting at its lowest). CGAL's creation order follows its box-intersection order, which breaks
// ties by memory address, so without this a parallel evaluation could list the same mesh differently
// from run to run.
template <typename SM>
Mesh from_surface_mesh(const SM& sm) {
  std::vector<std::array<double, 3>> points;
  std::vector<typename SM::Vertex_index> handles;
  for (auto v : sm.vertices()) {
    const auto& p = sm.point(v);
    points.push_back({rounded(p.x()), rounded(p.y()), rounded(p.z())});
    handles.push_back(v);
  }
  std::vector<Index> order(points.size());
  std::iota(order.begin(), order.end(), Index{0});
  std::sort(order.begin(), order.end(), [&](Index a, Index b) { return points[a] < points[b]; });
  Mesh m;
  m.positions.resize(static_cast<Index>(points.size()), 3);
  std::vector<Index> id(sm.num_vertices(), -1);
  for (Index n = 0; n < static_cast<Index>(order.size()); ++n) {
    const auto& p = points[order[n]];
    m.positions.row(n) << p[0], p[1], p[2];
    id[handles[order[n]].idx()] = n;
  }
  std::vector<std::array<Index, 3>> faces;
  for (auto face : sm.faces()) {
    std::array<Index, 3> t{};
    int k = 0;
    for (auto v : CGAL::vertices_around_face(sm.halfedge(face), sm))
      if (k < 3) t[k++] = id[v.idx()];
    std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());  // same orientation
    faces.push_back(t);
  }
  std::sort(faces.begin(), faces.end());
  m.triangles.resize(static_cast<Index>(faces.size()), 3);
  for (Index f = 0; f < static_cast<Index>(faces.size()); ++f) m.triangles.row(f) << faces[f][0], faces[f][1], faces[f][2];
  return m;
}

// Welded copy: corefinement needs shared vertices, and files often repeat positions at seams.
Mesh welded(const Mesh& m) {
  Mesh w;
  w.positions = m.positions;
  w.triangles = m.triangles;
  const auto cls = position_classes(w);
  for (Index f = 0; f < w.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) w.triangles(f, k) = cls[w.triangles(f, k)];
  remove_unreferenced_vertices(w);
  return w;
}

// Checks an operand; turns it outward if it is inside out.
template <typename SM>
void check_operand(SM& sm, const Mesh& source, const std::string& name, std::vector<std::string>& warnings) {
  if (source.num_faces() == 0) throw Error(fmt::format("{}: has no faces", name));
  if (sm.number_of_faces() != static_cast<std::size_t>(source.num_faces()))
    throw Error(fmt::format("{}: is not a 2-manifold ({} of {} faces could not be connected)", name,
                            source.num_faces() - static_cast<Index>(sm.number_of_faces()), source.num_faces()));
  if (!CGAL::is_valid_polygon_mesh(sm)) throw Error(fmt::format("{}: is not a valid 2-manifold mesh", name));
  if (!CGAL::is_closed(sm)) throw Error(fmt::format("{}: is not closed (it has boundary edges)", name));
  std::vector<std::pair<typename SM::Face_index, typename SM::Face_index>> pairs;
  PMP::self_intersections<CGAL::Parallel_if_available_tag>(sm, std::back_inserter(pairs));
  if (!pairs.empty()) throw Error(fmt::format("{}: intersects itself ({} face pairs)", name, pairs.size()));
  if (!PMP::does_bound_a_volume(sm)) throw Error(fmt::format("{}: does not bound a volume (inconsistent orientation or nested shells)", name));
  if (!PMP::is_outward_oriented(sm)) {
    PMP::reverse_face_orientations(sm);
    warnings.push_back(fmt::format("{}: was inside out; reoriented outward", name));
  }
}

template <typename SM>
bool clean_and_check(SM& sm);

template <typename Kernel>
bool run(const Mesh& a, const Mesh& b, BooleanOp op, const std::string& na, const std::string& nb,
         Mesh& out, std::vector<std::string>& warnings, bool check = true) {
  using SM = CGAL::Surface_mesh<typename Kernel::Point_3>;
  SM ma = to_surface_mesh<Kernel>(a, na, warnings), mb = to_surface_mesh<Kernel>(b, nb, warnings), result;
  if (check) {
    check_operand(ma, a, na, warnings);
    check_operand(mb, b, nb, warnings);
  }
  bool ok = false;
  switch (op) {
    case BooleanOp::Union: ok = PMP::corefine_and_compute_union(ma, mb, result); break;
    case BooleanOp::Difference: ok = PMP::corefine_and_compute_difference(ma, mb, result); break;
    case BooleanOp::Intersection: ok = PMP::corefine_and_compute_intersection(ma, mb, result); break;
  }
  if (!ok) return false;
  if (result.number_of_faces() > 0 && !clean_and_check(result)) return false;
  out = from_surface_mesh(result);
  return true;
}

// Removes flat triangles (rounded intersection points can fall exactly on a line) and checks that
// what is left is closed and free of self-intersections.
template <typename SM>
bool clean_and_check(SM& sm) {
  bool flat = false;
  for (auto f : sm.faces()) flat = flat || PMP::is_degenerate_triangle_face(f, sm);
  if (flat) {
    if (!PMP::remove_degenerate_faces(sm)) return false;
    sm.collect_garbage();
  }
  return sm.number_of_faces() > 0 && CGAL::is_closed(sm) && !PMP::does_self_intersect<CGAL::Parallel_if_available_tag>(sm);
}

// Exact results rounded to doubles: nearby points may merge or cross. A needle whose two close
// corners round to one point is gone (as if its short edge had been collapsed); flat triangles are
// repaired; then the mesh must be closed and free of self-intersections, or it is refused.
bool rounded_result_is_valid(Mesh& m) {
  if (m.num_faces() == 0) return true;
  Mesh w = welded(m);
  Index kept = 0;
  for (Index f = 0; f < w.num_faces(); ++f) {
    const auto t = w.triangles.row(f);
    if (t(0) != t(1) && t(1) != t(2) && t(2) != t(0)) w.triangles.row(kept++) = t;
  }
  w.triangles.conservativeResize(kept, 3);
  std::vector<std::string> repaired;  // non-empty: some faces could not be connected as they are
  auto sm = to_surface_mesh<CGAL::Exact_predicates_inexact_constructions_kernel>(w, "result", repaired);
  if (!repaired.empty() || !clean_and_check(sm)) return false;
  m = from_surface_mesh(sm);
  return true;
}

}  // namespace

void check_solid(const Mesh& mesh, const std::string& name) {
  validate(mesh, name);
  std::vector<std::string> warnings;
  const Mesh w = welded(mesh);
  auto sm = to_surface_mesh<CGAL::Exact_predicates_inexact_constructions_kernel>(w, name, warnings);
  check_operand(sm, w, name, warnings);
}

bool are_separate_solids(const Mesh& mesh) {
  using SM = CGAL::Surface_mesh<CGAL::Exact_predicates_inexact_constructions_kernel::Point_3>;
  std::vector<std::string> warnings;
  const Mesh w = welded(mesh);
  SM sm = to_surface_mesh<CGAL::Exact_predicates_inexact_constructions_kernel>(w, "parts", warnings);
  return warnings.empty() && sm.number_of_faces() == static_cast<std::size_t>(w.num_faces()) && CGAL::is_closed(sm) &&
         !PMP::does_self_intersect<CGAL::Parallel_if_available_tag>(sm) && PMP::does_bound_a_volume(sm) && PMP::is_outward_oriented(sm);
}

std::pair<Mesh, Mesh> split_solid(const Mesh& solid, int axis, double at) {
  if (axis < 0 || axis > 2) throw Error(fmt::format("split_solid: axis must be 0, 1 or 2, got {}", axis));
  const Eigen::AlignedBox3d box = bounding_box(solid);
  if (box.isEmpty() || !(at > box.min()[axis] && at < box.max()[axis])) {
    // The plane misses the solid: all of it lies on one side.
    if (!box.isEmpty() && at <= box.min()[axis]) return {Mesh{}, solid};
    return {solid, Mesh{}};
  }
  // Vertices a rounding error away from the plane (a sphere's meridian at x = 6e-17, say) go onto it:
  // cut next to them, the halves would get needle triangles that rounding folds over.
  Mesh snapped = welded(solid);
  const double snap = 1e-12 * box.diagonal().norm();
  for (Index i = 0; i < snapped.num_vertices(); ++i)
    if (std::abs(snapped.positions(i, axis) - at) <= snap) snapped.positions(i, axis) = at;
  // Each half is the solid's intersection with a triangular prism whose end face lies in the plane
  // and holds the solid's whole cross-section in one triangle: no edge of the clipper crosses the
  // solid, so the cut adds no vertices but where the solid's own edges meet the plane. Exact
  // constructions make those points round to the same doubles in both halves (and to exactly `at`
  // across the plane), so the halves meet face to face without slivers.
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  const double margin = 1.0 + box.diagonal().maxCoeff();
  const double u0 = box.min()[u] - margin, v0 = box.min()[v] - margin;
  const double du = 2 * (box.sizes()[u] + 2 * margin), dv = 2 * (box.sizes()[v] + 2 * margin);  // legs twice the box
  auto half = [&](bool below) {
    const double far = below ? box.min()[axis] - margin : box.max()[axis] + margin;
    Mesh clipper;
    clipper.positions.resize(6, 3);
    for (int end = 0; end < 2; ++end)
      for (int corner = 0; corner < 3; ++corner) {
        Eigen::Vector3d p;
        p[axis] = end == 0 ? at : far;
        p[u] = u0 + (corner == 1 ? du : 0.0);
        p[v] = v0 + (corner == 2 ? dv : 0.0);
        clipper.positions.row(3 * end + corner) = p.transpose();
      }
    clipper.triangles.resize(8, 3);
    clipper.triangles << 0, 2, 1, 3, 4, 5, 0, 1, 4, 0, 4, 3, 1, 2, 5, 1, 5, 4, 2, 0, 3, 2, 3, 5;
    if (signed_volume(clipper) < 0) clipper.triangles.col(1).swap(clipper.triangles.col(2));
    Mesh out;
    std::vector<std::string> ignored;
    if (!run<CGAL::Exact_predicates_exact_constructions_kernel>(snapped, clipper, BooleanOp::Intersection, "solid",
                                                                "half-space", out, ignored, false) ||
        !rounded_result_is_valid(out))
      throw Error(fmt::format("split_solid: the halves of the solid at {} = {} are not valid solids",
                              "xyz"[axis], at));
    return out;
  };
  return {half(true), half(false)};
}

std::string to_string(BooleanOp op) {
  switch (op) {
    case BooleanOp::Union: return "union";
    case BooleanOp::Difference: return "difference";
    case BooleanOp::Intersection: return "intersection";
  }
  return "?";
}

BooleanResult boolean(const Mesh& a_in, const Mesh& b_in, BooleanOp op, const BooleanOptions& options,
                      const std::string& name_a, const std::string& name_b) {
  const auto start = std::chrono::steady_clock::now();
  validate(a_in, name_a);
  validate(b_in, name_b);
  const Mesh a = welded(a_in), b = welded(b_in);
  BooleanResult r;
  bool ok = false;
  const bool check = options.check_operands;
  const Eigen::AlignedBox3d box_a = bounding_box(a), box_b = bounding_box(b);
  if (!box_a.isEmpty() && !box_b.isEmpty() && !box_a.intersects(box_b)) {
    // Boxes apart (not even touching): nothing to corefine. The union is both shells, the
    // intersection empty, the difference A.
    if (check) check_solid(a, name_a), check_solid(b, name_b);
    r.mesh = op == BooleanOp::Union ? concatenated(a, b) : op == BooleanOp::Intersection ? Mesh{} : a;
    ok = true;
  }
  if (!ok && !options.exact)
    ok = run<CGAL::Exact_predicates_inexact_constructions_kernel>(a, b, op, name_a, name_b, r.mesh, r.warnings, check);
  if (!ok) {
    r.warnings.clear();
    r.used_exact = true;
    ok = run<CGAL::Exact_predicates_exact_constructions_kernel>(a, b, op, name_a, name_b, r.mesh, r.warnings, check);
    if (ok && !rounded_result_is_valid(r.mesh))
      throw Error(fmt::format("{} of {} and {}: the exact result is valid, but rounding it to double precision makes "
                              "it touch itself; try a slightly different tolerance or placement",
                              to_string(op), name_a, name_b));
    if (!ok) {
      // Solids that only touch along an edge or at a vertex: their union is not a 2-manifold there.
      // If their interiors do not overlap, the result is still exact as sets: the union is both
      // shells side by side, the intersection is empty and the difference is A.
      Mesh overlap;
      std::vector<std::string> ignored;
      const bool touching = op != BooleanOp::Intersection &&
                            run<CGAL::Exact_predicates_exact_constructions_kernel>(a, b, BooleanOp::Intersection, name_a, name_b,
                                                                                   overlap, ignored) &&
                            overlap.num_faces() == 0;
      if (!touching)
        throw Error(fmt::format("{} of {} and {}: the result would not be a closed 2-manifold (the operands touch along "
                                "edges or at vertices where their interiors also overlap); CGAL refuses it even with exact "
                                "constructions",
                                to_string(op), name_a, name_b));
      r.warnings.push_back(fmt::format("{} and {} only touch (along an edge or at a vertex): the {} keeps {} as separate shells",
                                       name_a, name_b, to_string(op), op == BooleanOp::Union ? "both" : "the first"));
      r.mesh = op == BooleanOp::Union ? concatenated(a, b) : a;
    }
  }
  r.volume = signed_volume(r.mesh);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

}  // namespace lodkit
