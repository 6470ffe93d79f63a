// From an input mesh to the engine's state: points and wedges, boundary, seam and lock flags, face
// lists, quadrics with boundary and crease planes, attribute quadrics; and the input's tree beside it.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <tbb/parallel_for.h>
#include <tbb/task_group.h>

#include "core/geometry.h"
#include "core/huge_pages.h"
#include "core/topology.h"
#include "simplify/collapse_engine.h"

namespace lodkit::detail {

Engine::Engine(const Mesh& mesh, const SimplifyOptions& options) : o_(options) {
  s_.input = &mesh;
  // The input's tree has no part in the setup: it is built alongside.
  tbb::task_group input_tree_task;
  inverted_mode_ = o_.inverted_faces.value_or(default_inverted_faces(o_.method));
  check_inverted_ = inverted_mode_ != InvertedFaces::Allow && o_.preserve_topology;
  if (check_inverted_)
    input_tree_task.run([&] {
      // facing_against() only, which mostly settles without a search: quick to build, and lean.
      input_tree_ = std::make_unique<AabbTree>(mesh, AabbTree::Options{.copy_corners = false, .surface_area_splits = false});
      input_tree_->prepare_facing();
      resize_huge(nearest_input_, static_cast<std::size_t>(mesh.num_faces()));
      tbb::parallel_for(Index{0}, mesh.num_faces(), [&](Index f) { nearest_input_[f] = {input_tree_->certificate(f), f}; });
      assign_huge(against_in_input_, static_cast<std::size_t>(mesh.num_faces()), std::int8_t{kUnknown});
    });
  setup(mesh);
  setup_attributes(mesh);
  switch (o_.method) {
    case SimplifyMethod::Quadric: cost_ = make_quadric_cost(o_); break;
    case SimplifyMethod::EdgeLength: cost_ = make_edge_length_cost(o_); break;
    case SimplifyMethod::Hoppe: cost_ = make_hoppe_cost(o_, s_); break;
  }
  cos_max_turn_ = std::cos(o_.max_normal_change_deg * std::numbers::pi / 180.0);
  set_total_turn(starting_total_turn_deg());
  max_valence_ = o_.max_valence.value_or(default_max_valence(o_.method));
  if (cost_->costly()) scored_.resize(s_.position.size());
  input_tree_task.wait();
}


void Engine::setup(const Mesh& mesh) {
  const Index nv = mesh.num_vertices();
  s_.origin = local_origin(bounding_box(mesh));
  // Points: one per distinct position.
  const Eigen::VectorX<Index> cls = position_classes(mesh);
  assign_huge(s_.point_of, static_cast<std::size_t>(nv), Index{-1});
  auto point_of_class = huge_vector<Index>(static_cast<std::size_t>(nv), -1);
  reserve_huge(s_.position, static_cast<std::size_t>(nv));
  Index points = 0;
  for (Index v = 0; v < nv; ++v) {
    Index& p = point_of_class[cls[v]];
    if (p < 0) {
      p = points++;
      s_.position.push_back(mesh.positions.row(v).transpose() - s_.origin);
    }
    s_.point_of[v] = p;
  }
  assign_huge(s_.quadric, static_cast<std::size_t>(points), Quadric{});
  assign_huge(s_.flags, static_cast<std::size_t>(points), std::uint8_t{0});
  resize_huge(s_.point_faces, static_cast<std::size_t>(points));
  assign_huge(version_, static_cast<std::size_t>(points), std::uint32_t{0});
  assign_huge(dirty_, static_cast<std::size_t>(points), std::uint32_t{0});
  // Every point collapses once at most: the records in one block, not doubled as they grow.
  if (o_.record_collapses) reserve_huge(records_, static_cast<std::size_t>(points));

  // Faces on canonical wedges (identical vertices merged, so an unwelded soup is not all seams); a
  // face whose corners are not three distinct points cannot take part and is dropped.
  canonical_ = identical_vertex_classes(mesh);
  const std::vector<Index>& canonical = canonical_;
  const auto faces = static_cast<std::size_t>(mesh.num_faces());
  reserve_huge(s_.face, faces), reserve_huge(s_.face_point, faces), reserve_huge(s_.face_normal0, faces);
  reserve_huge(s_.face_dead, faces);
  {
    // Each point's face list sized once (growing half a million lists one face at a time showed in
    // the profile); a collapse appends at most a few more.
    std::vector<std::uint32_t> degree(static_cast<std::size_t>(points), 0);
    for (Index f = 0; f < mesh.num_faces(); ++f)
      for (int k = 0; k < 3; ++k) ++degree[s_.point_of[canonical[mesh.triangles(f, k)]]];
    for (Index p = 0; p < points; ++p) s_.point_faces[p].reserve(degree[p]);
  }
  for (Index f = 0; f < mesh.num_faces(); ++f) {
    const std::array<Index, 3> w{canonical[mesh.triangles(f, 0)], canonical[mesh.triangles(f, 1)],
                                 canonical[mesh.triangles(f, 2)]};
    const std::array<Index, 3> p{s_.point_of[w[0]], s_.point_of[w[1]], s_.point_of[w[2]]};
    s_.face.push_back(w);
    s_.face_point.push_back(p);
    const Eigen::Vector3d n0 = (mesh.positions.row(w[1]) - mesh.positions.row(w[0]))
                                   .cross(mesh.positions.row(w[2]) - mesh.positions.row(w[0]))
                                   .transpose();
    s_.face_normal0.push_back(n0.norm() > 0 ? Eigen::Vector3f(n0.normalized().cast<float>()) : Eigen::Vector3f::Zero());
    if (p[0] == p[1] || p[1] == p[2] || p[0] == p[2]) {
      s_.face_dead.push_back(1);
      ++dropped_;
      continue;
    }
    s_.face_dead.push_back(0);
    for (Index q : p) s_.point_faces[q].push_back(f);
  }
  s_.alive_faces = mesh.num_faces() - dropped_;
  // The faces that take part, for the edge and fan classification: face_point itself unless some were
  // dropped (a copy of it cost 17 MiB on a 1M-face mesh), with the face of each entry.
  std::vector<std::array<Index, 3>> live_copy;
  std::vector<Index> face_id;  // empty: every face takes part
  if (dropped_ > 0) {
    live_copy.reserve(static_cast<std::size_t>(s_.alive_faces));
    face_id.reserve(static_cast<std::size_t>(s_.alive_faces));
    for (Index f = 0; f < mesh.num_faces(); ++f)
      if (!s_.face_dead[f]) live_copy.push_back(s_.face_point[f]), face_id.push_back(f);
  }
  const std::vector<std::array<Index, 3>>& point_faces = dropped_ > 0 ? live_copy : s_.face_point;

  // Boundaries and non-manifold parts.
  edges_ = classify_edges(point_faces);
  auto border_side = huge_vector<char>(3 * faces);  // per face side: on the boundary
  for (const EdgeUse& e : edges_) {
    if (e.faces == 1) {
      s_.flags[e.lo] |= kBorder, s_.flags[e.hi] |= kBorder;
      const Index f = input_face(face_id, e.face[0]);
      const int k = s_.side(f, e.lo, e.hi);
      border_side[3 * std::size_t(f) + k] = 1;
      s_.input_boundary.push_back({s_.corner_point(f, k), s_.corner_point(f, (k + 1) % 3)});
    }
    if (e.faces > 2 || !e.consistent) s_.flags[e.lo] |= kLocked, s_.flags[e.hi] |= kLocked;
    faces_disagree_ |= e.faces == 2 && !e.consistent;
  }
  std::sort(s_.input_boundary.begin(), s_.input_boundary.end());
  const std::vector<char> fans = non_manifold_fans(points, point_faces);
  for (Index p = 0; p < points; ++p) {
    if (fans[p]) s_.flags[p] |= kLocked;
    if (o_.lock_boundary && (s_.flags[p] & kBorder)) s_.flags[p] |= kLocked;
    locked_ += (s_.flags[p] & kLocked) != 0;
  }
  // Seams: a point whose faces use more than one wedge.
  for (Index p = 0; p < points; ++p) {
    Index first = -1;
    for (Index f : s_.point_faces[p])
      for (int k = 0; k < 3; ++k)
        if (s_.corner_point(f, k) == p) {
          if (first < 0) first = s_.face[f][k];
          else if (s_.face[f][k] != first) s_.flags[p] |= kSeam;
        }
  }

  // Quadrics: area-weighted face planes, and boundary constraint planes through each border edge,
  // perpendicular to its face, weighted by the squared edge length; then the crease planes.
  for (Index f = 0; f < mesh.num_faces(); ++f) {
    if (s_.face_dead[f]) continue;
    const Index a = s_.corner_point(f, 0), b = s_.corner_point(f, 1), c = s_.corner_point(f, 2);
    const Eigen::Vector3d n2 = (s_.position[b] - s_.position[a]).cross(s_.position[c] - s_.position[a]);
    const double len = n2.norm();
    if (!(len > 0)) continue;
    const Eigen::Vector3d n = n2 / len;
    const Quadric q = Quadric::plane(n, -n.dot(s_.position[a]), 0.5 * len);
    s_.quadric[a] += q, s_.quadric[b] += q, s_.quadric[c] += q;
    for (int k = 0; k < 3; ++k) {
      if (!border_side[3 * std::size_t(f) + k]) continue;
      const Index p0 = s_.corner_point(f, k), p1 = s_.corner_point(f, (k + 1) % 3);
      const Eigen::Vector3d edge = s_.position[p1] - s_.position[p0];
      const Eigen::Vector3d m = edge.cross(n).normalized();
      if (!m.allFinite()) continue;
      const Quadric bq = Quadric::plane(m, -m.dot(s_.position[p0]), o_.boundary_weight * edge.squaredNorm());
      s_.quadric[p0] += bq, s_.quadric[p1] += bq;
    }
  }
  add_crease_planes(face_id);
  find_sharp_edges(face_id);
}

std::vector<Index> Engine::faces_across(const std::vector<Index>& face_id, bool consistent_only) const {
  auto across = huge_vector<Index>(3 * s_.face.size(), -1);
  for (const EdgeUse& e : edges_) {
    if (e.faces != 2 || (consistent_only && !e.consistent)) continue;
    const Index f0 = input_face(face_id, e.face[0]), f1 = input_face(face_id, e.face[1]);
    const Index f = std::min(f0, f1);
    across[3 * std::size_t(f) + s_.side(f, e.lo, e.hi)] = std::max(f0, f1);
  }
  return across;
}

// Crease planes: the boundary constraint generalised to folded edges. Face planes alone leave a
// thin fin's rim, or a spike's tip, free to slide inwards at almost no cost (the planes of both
// sides contain that direction), which is where plain quadrics lose Hausdorff distance. Each interior
// edge adds the plane through it whose normal bisects its faces' normals, weighted by
// crease_weight * |edge|^2 * (1 - n1.n2) / 2: nothing on flat ground, the full weight on a fin whose
// sides fold back onto each other (n2 = -n1, where the plane is a boundary plane).
void Engine::add_crease_planes(const std::vector<Index>& face_id) {
  // Quadric only: hoppe starts from the quadric's position but measures its own energy, and it kept
  // less Hausdorff with them (horse 10 %: 0.28 % against 0.14 %).
  if (o_.method != SimplifyMethod::Quadric || !(o_.crease_weight > 0)) return;
  // Each interior edge of two consistently oriented faces, from the face of lower index, in face order.
  const Index faces = static_cast<Index>(s_.face.size());
  const std::vector<Index> across = faces_across(face_id, true);
  for (Index f = 0; f < faces; ++f) {
    for (int k = 0; k < 3; ++k) {
      const Index other = across[3 * std::size_t(f) + k];
      if (other < 0) continue;
      const Index p0 = s_.corner_point(f, k), p1 = s_.corner_point(f, (k + 1) % 3);
      const Eigen::Vector3d n1 = s_.face_normal0[f].cast<double>(), n2 = s_.face_normal0[other].cast<double>();
      const double fold = 0.5 * (1.0 - n1.dot(n2));
      const Eigen::Vector3d m = (n1 + n2).normalized();
      if (!(fold > 1e-6) || !m.allFinite()) continue;
      const Eigen::Vector3d& a = s_.position[p0];
      const double weight = o_.crease_weight * fold * (s_.position[p1] - a).squaredNorm();
      const Quadric q = Quadric::plane(m, -m.dot(a), weight);
      s_.quadric[p0] += q, s_.quadric[p1] += q;
    }
  }
}

// Hoppe samples points along these (HoppeCost::sample_creases()): E_dist sees an edge only through the
// points near it.
void Engine::find_sharp_edges(const std::vector<Index>& face_id) {
  if (o_.method != SimplifyMethod::Hoppe || o_.hoppe_crease_angle_deg >= 180) return;
  const float cos_sharp = static_cast<float>(std::cos(o_.hoppe_crease_angle_deg * std::numbers::pi / 180.0));
  const std::vector<Index> across = faces_across(face_id, false);
  for (std::size_t i = 0; i < across.size(); ++i) {
    if (across[i] < 0) continue;
    const Eigen::Vector3f &n0 = s_.face_normal0[i / 3], &n1 = s_.face_normal0[across[i]];
    if (n0.squaredNorm() < 0.5f || n1.squaredNorm() < 0.5f || n0.dot(n1) >= cos_sharp) continue;  // degenerate or smooth
    s_.sharp_edges.push_back({static_cast<Index>(i / 3), static_cast<int>(i % 3)});
  }
}

void Engine::setup_attributes(const Mesh& mesh) {
  const AttributeWeights& w = o_.attribute_weights;
  const Attributes& a = mesh.attributes;
  const bool normals = w.normals > 0 && mesh.has_normals(), uvs = w.uvs > 0 && mesh.has_uvs(),
             colours = w.colours > 0 && mesh.has_colours();
  const int k = 3 * normals + 2 * uvs + 4 * colours;
  if (k == 0) return;
  const Eigen::AlignedBox3d box = bounding_box(mesh);
  const double diagonal = box.isEmpty() ? 1.0 : std::max(box.diagonal().norm(), 1e-300);
  attribute_scale_.clear();
  for (int i = 0; i < 3 * normals; ++i) attribute_scale_.push_back(w.normals * diagonal);
  for (int i = 0; i < 2 * uvs; ++i) attribute_scale_.push_back(w.uvs * diagonal);
  for (int i = 0; i < 4 * colours; ++i) attribute_scale_.push_back(w.colours * diagonal);
  attribute_layout_ = {normals, uvs, colours};
  const Index nv = mesh.num_vertices();
  s_.wedge_value.assign(static_cast<std::size_t>(k) * nv, 0.0);
  for (Index v = 0; v < nv; ++v) {
    double* out = &s_.wedge_value[static_cast<std::size_t>(k) * v];
    int j = 0;
    if (normals) for (int i = 0; i < 3; ++i, ++j) out[j] = a.normals(v, i) * attribute_scale_[j];
    if (uvs) for (int i = 0; i < 2; ++i, ++j) out[j] = a.uvs(v, i) * attribute_scale_[j];
    if (colours) for (int i = 0; i < 4; ++i, ++j) out[j] = a.colours(v, i) * attribute_scale_[j];
  }
  s_.attribute_quadrics.reset(k, static_cast<std::size_t>(nv));
  for (Index f = 0; f < mesh.num_faces(); ++f) {
    if (s_.face_dead[f]) continue;
    Eigen::Vector3d p[3];
    const double* values[3];
    for (int c = 0; c < 3; ++c) {
      p[c] = s_.position[s_.corner_point(f, c)];
      values[c] = &s_.wedge_value[static_cast<std::size_t>(k) * s_.face[f][c]];
    }
    const double area = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).norm();
    for (int c = 0; c < 3; ++c) s_.attribute_quadrics.add_face(static_cast<std::size_t>(s_.face[f][c]), p, values, area);
  }
}

void Engine::output_attributes(Index w, double* out) const {
  const Attributes& a = s_.input->attributes;
  const std::size_t k = static_cast<std::size_t>(s_.attribute_quadrics.dims());
  const double* value = k ? &s_.wedge_value[k * static_cast<std::size_t>(w)] : nullptr;
  int i = 0, j = 0;  // i: output layout, j: optimised values
  if (s_.input->has_normals()) {
    if (attribute_layout_[0]) {
      Eigen::Vector3d n;
      for (int d = 0; d < 3; ++d, ++j) n[d] = value[j] / attribute_scale_[j];
      if (n.norm() > 0) n.normalize();
      else n = a.normals.row(w).transpose();
      for (int d = 0; d < 3; ++d) out[i++] = n[d];
    } else {
      for (int d = 0; d < 3; ++d) out[i++] = a.normals(w, d);
    }
  }
  if (s_.input->has_uvs())
    for (int d = 0; d < 2; ++d, j += attribute_layout_[1])
      out[i++] = attribute_layout_[1] ? value[j] / attribute_scale_[j] : a.uvs(w, d);
  if (s_.input->has_colours())
    for (int d = 0; d < 4; ++d, j += attribute_layout_[2])
      out[i++] = attribute_layout_[2] ? double(static_cast<float>(std::clamp(value[j] / attribute_scale_[j], 0.0, 1.0)))
                                      : double(a.colours(w, d));
}

}  // namespace lodkit::detail
