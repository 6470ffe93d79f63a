#include <lodkit/decimate.h>
#include <lodkit/error.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fmt/format.h>
#include <numbers>
#include <optional>
#include <span>
#include <vector>

#include "core/topology.h"
#include "metrics/aabb_tree.h"

namespace lodkit {
namespace {

constexpr int kClasses = 5;

// Which classes may be removed, and against what (the paper's table).
enum class Criterion { Keep, Plane, Line };
constexpr Criterion kRule[kClasses] = {
    /* Simple       */ Criterion::Plane,  // distance to the average plane of the star
    /* Complex      */ Criterion::Keep,   // non-manifold or otherwise not a single fan
    /* Boundary     */ Criterion::Line,   // distance to the line through its two boundary neighbours
    /* InteriorEdge */ Criterion::Line,   // distance to the line through its two feature neighbours
    /* Corner       */ Criterion::Keep,   // one or more than two feature edges, or a sharp boundary
};

struct Star {
  VertexClass cls = VertexClass::Complex;
  std::vector<Index> loop;      // neighbours in counter-clockwise order
  bool closed = false;          // interior vertex (cycle) or boundary vertex (open chain)
  std::vector<int> features;    // positions in `loop` of feature-edge neighbours (interior only)
  std::vector<Index> faces;
  std::vector<Index> fan;       // with UVs, faces in loop order: fan[i] is (v, loop[i], loop[i + 1])
  Eigen::Vector3d normal = Eigen::Vector3d::Zero(), centre = Eigen::Vector3d::Zero();
};

using Tri = std::array<Index, 3>;

class Decimator {
 public:
  // `uvs`: the input's UVs, to keep its seams and give each corner its side's UVs; null: positions only.
  Decimator(const Mesh& mesh, const DecimateOptions& o, const TexCoords* uvs)
      : o_(o), uvs_(uvs), position_class_(position_classes(mesh)) {
    const Eigen::VectorX<Index>& cls = position_class_;
    std::vector<Index> point_of_class(static_cast<std::size_t>(mesh.num_vertices()), -1);
    std::vector<Index> point_of(static_cast<std::size_t>(mesh.num_vertices()));
    for (Index v = 0; v < mesh.num_vertices(); ++v) {
      Index& p = point_of_class[cls[v]];
      if (p < 0)
        p = static_cast<Index>(position_.size()), position_.push_back(mesh.positions.row(v).transpose()), first_vertex_.push_back(v);
      point_of[v] = p;
    }
    point_faces_.resize(position_.size());
    for (Index f = 0; f < mesh.num_faces(); ++f) {
      const Tri t{point_of[mesh.triangles(f, 0)], point_of[mesh.triangles(f, 1)], point_of[mesh.triangles(f, 2)]};
      if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
      add_face(t, {mesh.triangles(f, 0), mesh.triangles(f, 1), mesh.triangles(f, 2)});
    }
    error_.assign(position_.size(), 0.0);
    removed_.assign(position_.size(), 0);
    // Input normals per point: vertices never move, so a new triangle can be checked against the
    // surface it replaces even after many removals around it.
    normal0_.assign(position_.size(), Eigen::Vector3d::Zero());
    for (const Tri& t : face_) {
      const Eigen::Vector3d n = (position_[t[1]] - position_[t[0]]).cross(position_[t[2]] - position_[t[0]]);
      for (Index p : t) normal0_[p] += n;
    }
    for (auto& n : normal0_)
      if (n.norm() > 0) n.normalize();
    cos_feature_ = std::cos(o.feature_angle_deg * std::numbers::pi / 180.0);
    if (o.inverted_faces != InvertedFaces::Allow) {
      inverted_.assign(position_.size(), 0);
      // A face of the input at each point: where a new face's corner is, a start for the search whose
      // certificate mostly settles the answer at once.
      input_face_.assign(position_.size(), -1);
      for (Index f = 0; f < mesh.num_faces(); ++f)
        for (int k = 0; k < 3; ++k)
          if (Index& at = input_face_[point_of[mesh.triangles(f, k)]]; at < 0) at = f;
    }
  }

  /// The input's tree, readied by prepare_facing(), to refuse removals that leave a face facing against
  /// it; null: no such check.
  void set_input_tree(const detail::AabbTree* tree) { input_tree_ = tree; }

  Index alive_faces() const { return alive_faces_; }
  Index points() const { return static_cast<Index>(position_.size()); }
  bool removed(Index v) const { return removed_[v] != 0; }

  // Builds the star of v and classifies it.
  void star(Index v, Star& s) {
    s = Star{};
    std::vector<std::pair<Index, Index>> next;  // a -> b for each face (v, a, b)
    double area = 0;
    for (Index f : point_faces_[v]) {
      if (!alive_[f]) continue;
      const Tri& t = face_[f];
      const int k = t[0] == v ? 0 : t[1] == v ? 1 : 2;
      next.push_back({t[(k + 1) % 3], t[(k + 2) % 3]});
      s.faces.push_back(f);
      const Eigen::Vector3d a = position_[t[0]], b = position_[t[1]], c = position_[t[2]];
      const Eigen::Vector3d n2 = (b - a).cross(c - a);  // twice the area, along the normal
      s.normal += n2;
      s.centre += 0.5 * n2.norm() * (a + b + c) / 3.0;
      area += 0.5 * n2.norm();
    }
    if (next.empty()) return;
    if (!(area > 0) || !(s.normal.norm() > 0)) return;
    s.centre /= area;
    s.normal.normalize();
    // Each neighbour may start at most one face and end at most one face.
    auto find_next = [&](Index a) -> Index {
      Index found = -1;
      for (const auto& [x, y] : next)
        if (x == a) {
          if (found >= 0) return -2;
          found = y;
        }
      return found;
    };
    Index start = next[0].first;
    int starts = 0;
    for (const auto& [x, y] : next) {
      bool has_prev = false;
      int as_first = 0;
      for (const auto& [x2, y2] : next) has_prev |= y2 == x, as_first += x2 == x;
      if (as_first > 1) return;  // non-manifold
      if (!has_prev) start = x, ++starts;
    }
    if (starts > 1) return;  // several fans: a bow tie
    s.closed = starts == 0;
    Index a = start;
    for (std::size_t guard = 0; guard <= next.size(); ++guard) {
      s.loop.push_back(a);
      const Index b = find_next(a);
      if (b == -2) return;
      if (b < 0 || b == start) break;
      a = b;
    }
    if (s.loop.size() != (s.closed ? next.size() : next.size() + 1)) return;  // not a single fan
    if (uvs_) {  // (the fan serves the seams alone)
      for (const Index point : s.loop)
        for (std::size_t k = 0; k < next.size(); ++k)
          if (next[k].first == point) s.fan.push_back(s.faces[k]);
    }
    // Feature edges: the edge (v, loop[i]) between faces (v, loop[i-1], loop[i]) and (v, loop[i], loop[i+1]).
    const std::size_t n = s.loop.size();
    auto face_normal = [&](Index p, Index q) {
      const Eigen::Vector3d nn = (position_[p] - position_[v]).cross(position_[q] - position_[v]);
      return Eigen::Vector3d(nn.norm() > 0 ? Eigen::Vector3d(nn.normalized()) : nn);
    };
    for (std::size_t i = 0; i < n; ++i) {
      if (!s.closed && (i == 0 || i + 1 == n)) continue;  // boundary edges
      const Index prev = s.loop[(i + n - 1) % n], w = s.loop[i], nxt = s.loop[(i + 1) % n];
      if (face_normal(prev, w).dot(face_normal(w, nxt)) < cos_feature_ || seam(s, v, i))
        s.features.push_back(static_cast<int>(i));
    }
    if (!s.closed) s.cls = s.features.empty() ? VertexClass::Boundary : VertexClass::Corner;
    else if (s.features.empty()) s.cls = VertexClass::Simple;
    else if (s.features.size() == 2) s.cls = VertexClass::InteriorEdge;
    else s.cls = VertexClass::Corner;
  }

  // Distance of v from what it must stay close to; negative when its class is kept.
  double removal_error(Index v, const Star& s) const {
    const Eigen::Vector3d& p = position_[v];
    switch (kRule[static_cast<int>(s.cls)]) {
      case Criterion::Keep: return -1;
      case Criterion::Plane: return std::abs(s.normal.dot(p - s.centre));
      case Criterion::Line: {
        const Index a = s.closed ? s.loop[s.features[0]] : s.loop.front();
        const Index b = s.closed ? s.loop[s.features[1]] : s.loop.back();
        const Eigen::Vector3d d = position_[b] - position_[a];
        if (!(d.norm() > 0)) return -1;
        return (p - position_[a]).cross(d).norm() / d.norm();
      }
    }
    return -1;
  }

  // Tries to remove v: triangulate its hole and apply. Returns false if no acceptable triangulation.
  // `may_invert`: let a new face face against the input (InvertedFaces::Avoid, once the pass's
  // threshold is well past this removal's error); `inverted`, on return, whether one does.
  bool remove(Index v, const Star& s, double error, bool may_invert, bool& inverted) {
    inverted = false;
    new_faces_.clear();
    new_wedges_.clear();
    if (!inverted_.empty()) inverted_[v] = 0;
    if (s.closed && s.cls == VertexClass::InteriorEdge) {
      // The feature line must survive: split along it first.
      const int i = s.features[0], j = s.features[1];
      std::vector<Index> a(s.loop.begin() + i, s.loop.begin() + j + 1), b(s.loop.begin() + j, s.loop.end());
      b.insert(b.end(), s.loop.begin(), s.loop.begin() + i + 1);
      if (a.size() < 3 || b.size() < 3) return false;  // the feature neighbours are adjacent: nothing to split
      if (edge_exists(s.loop[i], s.loop[j]) || !split(a, s.normal)) return false;
      const std::size_t first_of_b = new_faces_.size();
      if (!split(b, s.normal)) return false;
      if (uvs_) {
        // Each side of the line takes its corners' UVs from the faces on its side (a seam may be the line).
        std::vector<Index> side_b(s.fan.begin() + j, s.fan.end());
        side_b.insert(side_b.end(), s.fan.begin(), s.fan.begin() + i);
        add_wedges(0, first_of_b, std::span(s.fan).subspan(i, j - i));
        add_wedges(first_of_b, new_faces_.size(), side_b);
      }
    } else {
      if (!s.closed && edge_exists(s.loop.front(), s.loop.back())) return false;  // would close a pinch
      if (s.loop.size() < 3 || !split(s.loop, s.normal)) return false;
      if (uvs_) add_wedges(0, new_faces_.size(), s.fan);  // no seam runs through v: one side
    }
    // Every new triangle faces the same way as the star and is not already in the mesh.
    constexpr double kLimit = -0.17;  // cos(100 deg): a corner may not face away from its input normal
    for (const Tri& t : new_faces_) {
      const Eigen::Vector3d n = (position_[t[1]] - position_[t[0]]).cross(position_[t[2]] - position_[t[0]]);
      if (!(n.dot(s.normal) > 0)) return false;
      const double len = n.norm();
      for (Index p : t)
        if (n.dot(normal0_[p]) < kLimit * len) return false;
      if (face_exists(t)) return false;
    }
    if (static_cast<Index>(new_faces_.size()) != static_cast<Index>(s.faces.size()) - 2 + (s.closed ? 0 : 1))
      return false;
    if (input_tree_) {
      inverted = faces_against_input();
      inverted_[v] = inverted && !may_invert;
      if (inverted_[v]) return false;
    }
    for (Index f : s.faces) alive_[f] = 0, --alive_faces_;
    for (std::size_t k = 0; k < new_faces_.size(); ++k) add_face(new_faces_[k], uvs_ ? new_wedges_[k] : Tri{});
    removed_[v] = 1;
    point_faces_[v].clear();
    for (Index w : s.loop) {
      auto& list = point_faces_[w];
      list.erase(std::remove_if(list.begin(), list.end(), [&](Index f) { return !alive_[f]; }), list.end());
      if (o_.accumulate_error) error_[w] += error;
    }
    return true;
  }

  double accumulated(Index v) const { return error_[v]; }
  /// Whether v's last removal was refused for a face facing against the input.
  bool refused_as_inverted(Index v) const { return !inverted_.empty() && inverted_[v]; }
  /// For each input vertex, the first vertex with its position (position_classes()).
  const Eigen::VectorX<Index>& position_class() const { return position_class_; }

  /// The mesh left; `vertex_of`: for each of its vertices, the first input vertex at that position, or
  /// with UVs, the input vertex (wedge) whose UVs it carries: a vertex for each UV at a point.
  Mesh output(std::vector<Index>& vertex_of) const {
    if (uvs_) return output_with_uvs(vertex_of);
    Mesh m;
    std::vector<Index> id(position_.size(), -1);
    Index nv = 0, nf = 0;
    for (std::size_t f = 0; f < face_.size(); ++f)
      if (alive_[f]) {
        ++nf;
        for (Index p : face_[f])
          if (id[p] < 0) id[p] = nv++;
      }
    m.positions.resize(nv, 3);
    vertex_of.assign(static_cast<std::size_t>(nv), -1);
    for (std::size_t p = 0; p < position_.size(); ++p)
      if (id[p] >= 0) m.positions.row(id[p]) = position_[p].transpose(), vertex_of[id[p]] = first_vertex_[p];
    m.triangles.resize(nf, 3);
    Index row = 0;
    for (std::size_t f = 0; f < face_.size(); ++f)
      if (alive_[f]) {
        for (int k = 0; k < 3; ++k) m.triangles(row, k) = id[face_[f][k]];
        ++row;
      }
    return m;
  }

 private:
  // Whether a new face faces against the input face nearest its centroid, and no input face as near
  // faces its way (count_flipped_faces()).
  bool faces_against_input() const {
    for (const Tri& t : new_faces_) {
      Index hint = input_face_[t[0]];
      const Eigen::Vector3d centroid = (position_[t[0]] + position_[t[1]] + position_[t[2]]) / 3.0;
      const Eigen::Vector3d n = (position_[t[1]] - position_[t[0]]).cross(position_[t[2]] - position_[t[0]]);
      if (input_tree_->facing_against_all_nearest(centroid, n, hint)) return true;
    }
    return false;
  }

  Mesh output_with_uvs(std::vector<Index>& vertex_of) const {
    Mesh m;
    // Per point, its output vertices so far and their UVs: a point lies on few seams.
    std::vector<std::vector<std::pair<Eigen::Vector2d, Index>>> at_point(position_.size());
    vertex_of.clear();
    Index nf = 0;
    for (std::size_t f = 0; f < face_.size(); ++f) nf += alive_[f];
    m.triangles.resize(nf, 3);
    Index row = 0;
    for (std::size_t f = 0; f < face_.size(); ++f) {
      if (!alive_[f]) continue;
      for (int k = 0; k < 3; ++k) {
        const Index w = wedge_[f][k];
        const Eigen::Vector2d uv = uvs_->row(w).transpose();
        auto& here = at_point[face_[f][k]];
        auto it = std::find_if(here.begin(), here.end(), [&](const auto& e) { return e.first == uv; });
        if (it == here.end()) {
          here.push_back({uv, static_cast<Index>(vertex_of.size())});
          vertex_of.push_back(w);
          it = here.end() - 1;
        }
        m.triangles(row, k) = it->second;
      }
      ++row;
    }
    m.positions.resize(static_cast<Index>(vertex_of.size()), 3);
    for (std::size_t p = 0; p < position_.size(); ++p)
      for (const auto& [uv, id] : at_point[p]) m.positions.row(id) = position_[p].transpose();
    return m;
  }

  // The input vertex at point p in face f (its wedge: which of the input's vertices there, and so
  // which UVs).
  Index wedge_at(Index f, Index p) const {
    const Tri& t = face_[f];
    return wedge_[f][t[0] == p ? 0 : t[1] == p ? 1 : 2];
  }

  // Whether the edge (v, loop[i]) of an interior fan is a UV seam: the UVs at either end differ
  // between its two faces.
  bool seam(const Star& s, Index v, std::size_t i) const {
    if (!uvs_) return false;
    const std::size_t n = s.loop.size();
    const Index before = s.fan[(i + n - 1) % n], after = s.fan[i], w = s.loop[i];
    return uvs_->row(wedge_at(before, v)) != uvs_->row(wedge_at(after, v)) ||
           uvs_->row(wedge_at(before, w)) != uvs_->row(wedge_at(after, w));
  }

  // The wedges of new faces [begin, end), each corner's from a face of `side` (old faces around the
  // hole, UVs continuous across them) at the same point.
  void add_wedges(std::size_t begin, std::size_t end, std::span<const Index> side) {
    for (std::size_t k = begin; k < end; ++k) {
      Tri w{};
      for (int c = 0; c < 3; ++c) {
        const Index p = new_faces_[k][c];
        w[c] = -1;
        for (const Index f : side)
          if (face_[f][0] == p || face_[f][1] == p || face_[f][2] == p) {
            w[c] = wedge_at(f, p);
            break;
          }
      }
      new_wedges_.push_back(w);
    }
  }

  void add_face(const Tri& t, const Tri& wedges) {
    const auto f = static_cast<Index>(face_.size());
    face_.push_back(t);
    if (uvs_) wedge_.push_back(wedges);
    alive_.push_back(1);
    ++alive_faces_;
    for (Index p : t) point_faces_[p].push_back(f);
  }

  bool edge_exists(Index a, Index b) const {
    for (Index f : point_faces_[a])
      if (alive_[f] && (face_[f][0] == b || face_[f][1] == b || face_[f][2] == b)) return true;
    return false;
  }

  bool face_exists(const Tri& t) const {
    for (Index f : point_faces_[t[0]]) {
      if (!alive_[f]) continue;
      int shared = 0;
      for (Index p : face_[f]) shared += p == t[1] || p == t[2];
      if (shared == 2) return true;
    }
    return false;
  }

  // Recursive loop splitting: the best split line (by min distance of loop vertices to the split
  // plane / line length) whose plane, holding the line and the average normal, has every other loop
  // vertex strictly on its own side.
  bool split(const std::vector<Index>& loop, const Eigen::Vector3d& normal) {
    const std::size_t n = loop.size();
    if (n == 3) {
      new_faces_.push_back({loop[0], loop[1], loop[2]});
      return true;
    }
    double best_score = -1;
    std::size_t best_i = 0, best_j = 0;
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = i + 2; j < n; ++j) {
        if (i == 0 && j == n - 1) continue;  // adjacent around the loop
        const Eigen::Vector3d& a = position_[loop[i]];
        const Eigen::Vector3d line = position_[loop[j]] - a;
        const double length = line.norm();
        const Eigen::Vector3d m = line.cross(normal);
        if (!(length > 0) || !(m.norm() > 0)) continue;
        const Eigen::Vector3d plane = m.normalized();
        double min_distance = INFINITY;
        bool valid = true;
        for (std::size_t k = 0; k < n && valid; ++k) {
          if (k == i || k == j) continue;
          const double d = plane.dot(position_[loop[k]] - a);
          // For a counter-clockwise loop, the vertices between i and j lie right of the line i -> j.
          const bool between = k > i && k < j;
          if (between ? !(d > 0) : !(d < 0)) valid = false;
          min_distance = std::min(min_distance, std::abs(d));
        }
        if (!valid) continue;
        const double score = min_distance / length;
        if (score > best_score && !edge_exists(loop[i], loop[j])) best_score = score, best_i = i, best_j = j;
      }
    if (best_score < o_.aspect_ratio) return false;
    std::vector<Index> first(loop.begin() + best_i, loop.begin() + best_j + 1);
    std::vector<Index> second(loop.begin() + best_j, loop.end());
    second.insert(second.end(), loop.begin(), loop.begin() + best_i + 1);
    return split(first, normal) && split(second, normal);
  }

  const DecimateOptions& o_;
  const TexCoords* uvs_;
  std::vector<Eigen::Vector3d> position_;
  std::vector<Index> first_vertex_;  // per point: the first input vertex there
  Eigen::VectorX<Index> position_class_;
  std::vector<Tri> face_;
  std::vector<Tri> wedge_;  // with UVs: per face, the input vertex at each corner
  std::vector<char> alive_;
  std::vector<std::vector<Index>> point_faces_;
  std::vector<double> error_;
  std::vector<char> removed_;
  std::vector<Eigen::Vector3d> normal0_;
  std::vector<Tri> new_faces_;
  std::vector<Tri> new_wedges_;
  const detail::AabbTree* input_tree_ = nullptr;  // the input, for the side of its nearest face (inverted_faces)
  std::vector<char> inverted_;                  // per point: its last removal refused for that
  std::vector<Index> input_face_;               // per point: an input face there (the searches' hint)
  Index alive_faces_ = 0;
  double cos_feature_ = 0;
};

// Each output vertex is an input vertex (`vertex_of`): the first at its point, or with UVs, one there
// for each side of a seam. It takes that vertex's UVs and colour, and its normal where the input has
// one normal per position (where it has several, at hard edges, the welding cannot keep them, and no
// normals are written). Then all three are fitted to the input's (fit_attributes_to_input()).
// `cls`: the input's position classes (position_classes()).
std::optional<AttributeFitReport> carry_attributes(const Mesh& input, const Eigen::VectorX<Index>& cls,
                                                   const std::vector<Index>& vertex_of, bool uvs, Mesh& out) {
  bool normals = input.has_normals();
  for (Index v = 0; v < input.num_vertices() && normals; ++v)
    normals = (input.attributes.normals.row(v) - input.attributes.normals.row(cls[v])).norm() <= 1e-9;
  const bool colours = input.has_colours();
  if (!normals && !colours && !uvs) return std::nullopt;
  const Index n = out.num_vertices();
  if (normals) out.attributes.normals.resize(n, 3);
  if (colours) out.attributes.colours.resize(n, 4);
  if (uvs) out.attributes.uvs.resize(n, 2);
  for (Index i = 0; i < n; ++i) {
    if (normals) out.attributes.normals.row(i) = input.attributes.normals.row(vertex_of[i]);
    if (colours) out.attributes.colours.row(i) = input.attributes.colours.row(vertex_of[i]);
    if (uvs) out.attributes.uvs.row(i) = input.attributes.uvs.row(vertex_of[i]);
  }
  return fit_attributes_to_input(input, out);
}

}  // namespace

std::array<Index, 5> count_vertex_classes(const Mesh& mesh, double feature_angle_deg) {
  validate(mesh, "decimate");
  DecimateOptions o;
  o.feature_angle_deg = feature_angle_deg;
  o.inverted_faces = InvertedFaces::Allow;  // classification only: nothing is removed
  Decimator d(mesh, o, nullptr);
  std::array<Index, 5> counts{};
  Star s;
  for (Index v = 0; v < d.points(); ++v) {
    d.star(v, s);
    ++counts[static_cast<int>(s.cls)];
  }
  return counts;
}

DecimateResult decimate(const Mesh& mesh, const DecimateOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  validate(mesh, "decimate");
  if (options.target_ratio && !(*options.target_ratio >= 0 && *options.target_ratio <= 1))
    throw Error(fmt::format("decimate: ratio must be between 0 and 1, got {}", *options.target_ratio));
  if (options.max_error && !(*options.max_error >= 0))
    throw Error(fmt::format("decimate: max error must not be negative, got {}", *options.max_error));
  if (!(options.feature_angle_deg > 0 && options.feature_angle_deg <= 180))
    throw Error("decimate: feature angle must be in (0, 180] degrees");
  if (!(options.aspect_ratio >= 0)) throw Error("decimate: aspect ratio must not be negative");

  DecimateResult r;
  r.faces_in = mesh.num_faces();
  r.vertices_in = mesh.num_vertices();
  Index target = 0;
  if (options.target_faces) target = std::max(target, *options.target_faces);
  if (options.target_ratio) target = std::max(target, static_cast<Index>(std::llround(*options.target_ratio * mesh.num_faces())));
  const auto box = bounding_box(mesh);
  const double diagonal = box.isEmpty() ? 0.0 : box.diagonal().norm();
  const bool has_target = options.target_faces || options.target_ratio;
  const double max_error = options.max_error.value_or(has_target ? diagonal : 0.005 * diagonal);

  // Thresholds that grow to max_error: exact removals first, then steps of sqrt(2), so that within
  // a pass (which visits vertices in order, not best first) errors stay close to the threshold.
  std::vector<double> thresholds{0.0};
  for (int k = 32; k >= 0; --k) thresholds.push_back(max_error * std::pow(2.0, -0.5 * k));

  Mesh turned;
  const Mesh& source = detail::oriented(mesh, options.orient_faces, turned, r.reoriented_faces);
  // With UVs, their seams are feature lines, so that no new face straddles one.
  const bool uvs = options.fit_attributes && source.has_uvs();
  Decimator d(source, options, uvs ? &source.attributes.uvs : nullptr);
  // (Built beside the decimator's own setup on the other core, this saved nothing: the searches cost.)
  std::optional<detail::AabbTree> tree;
  if (options.inverted_faces != InvertedFaces::Allow) {
    tree.emplace(source, detail::AabbTree::Options{.copy_corners = false});  // (few closest() calls: lean)
    tree->prepare_facing();
    d.set_input_tree(&*tree);
  }
  Star s;
  // A removal that leaves a face facing against the input waits (Avoid) until the threshold is twice its
  // error, as an edge collapse waits until the others cost four times as much (squared distances).
  constexpr double kInvertedWait = 2.0;
  const auto may_invert = [&](double error, double threshold) {
    return options.inverted_faces == InvertedFaces::Avoid && kInvertedWait * error < threshold;
  };
  const auto apply = [&](Index v, double error, double bound, double threshold) {
    bool inverted = false;
    if (!d.remove(v, s, error, may_invert(bound, threshold), inverted)) return;
    ++r.removed;
    r.error = std::max(r.error, bound);
    if (inverted && !r.inverted_allowed_at) r.inverted_allowed_at = d.alive_faces() + (s.closed ? 2 : 1);
  };
  // v's removal error and the bound it is held to (with --accumulate-error, plus what its neighbours'
  // removals passed on), with its star in s; none where v is gone or cannot be removed.
  const auto removal = [&](Index v) -> std::optional<std::pair<double, double>> {
    if (d.removed(v)) return std::nullopt;
    d.star(v, s);
    const double e = d.removal_error(v, s);
    if (e < 0) return std::nullopt;
    return std::pair{e, e + (options.accumulate_error ? d.accumulated(v) : 0.0)};
  };
  for (double t : thresholds) {
    for (Index v = 0; v < d.points() && d.alive_faces() > target; ++v) {
      const auto found = removal(v);
      if (!found || found->second > t) continue;
      const Index removes = s.closed ? 2 : 1;
      if (d.alive_faces() - removes < target && removes > 1) continue;  // would overshoot by one
      apply(v, found->first, found->second, t);
    }
    if (d.alive_faces() <= target) break;
  }
  if (has_target && d.alive_faces() == target + 1) {
    // Only two-face removals are left (a closed mesh has an even face count): land one below.
    for (Index v = 0; v < d.points() && d.alive_faces() > target; ++v)
      if (const auto found = removal(v); found && found->second <= max_error) apply(v, found->first, found->second, max_error);
  }

  std::vector<Index> vertex_of;
  r.mesh = d.output(vertex_of);
  if (options.fit_attributes) r.attribute_fit = carry_attributes(source, d.position_class(), vertex_of, uvs, r.mesh);
  r.faces_out = r.mesh.num_faces();
  r.vertices_out = r.mesh.num_vertices();
  r.target_reached = has_target ? r.faces_out <= target : true;
  // What is left, and why it stayed.
  for (Index v = 0; v < d.points(); ++v) {
    if (d.removed(v)) continue;
    d.star(v, s);
    if (s.faces.empty()) continue;
    ++r.remaining_by_class[static_cast<int>(s.cls)];
    const double e = d.removal_error(v, s);
    if (e < 0) continue;
    if (e + (options.accumulate_error ? d.accumulated(v) : 0.0) > max_error) ++r.remaining_above_threshold;
    else ++r.remaining_no_triangulation, r.remaining_inverted += d.refused_as_inverted(v);
  }
  const auto& c = r.remaining_by_class;
  const std::string classes = fmt::format("{} simple, {} complex, {} boundary, {} interior-edge, {} corner", c[0], c[1],
                                          c[2], c[3], c[4]);
  if (has_target && r.target_reached) {
    r.reason_text = fmt::format("reached the target: {} faces (target {})", r.faces_out, target);
  } else {
    // Points, not vertices: with UVs a point on a seam is a vertex for each side.
    const Index points_left = c[0] + c[1] + c[2] + c[3] + c[4];
    r.reason_text = fmt::format(
        "stopped at {} faces{}: of the {} vertices left ({}), {} are corners or complex (kept by rule{}), {} are "
        "farther than {:.6g} from their plane or line, {} found no split meeting the aspect ratio {}{}",
        r.faces_out, has_target ? fmt::format(" above the target of {}", target) : "", points_left, classes,
        c[1] + c[4], uvs ? "; UV seams are feature lines" : "", r.remaining_above_threshold, max_error,
        r.remaining_no_triangulation, options.aspect_ratio,
        r.remaining_inverted > 0
            ? fmt::format(" ({} of them last left a face facing against the input)", r.remaining_inverted)
            : "");
  }
  if (r.inverted_allowed_at)
    r.reason_text += fmt::format("; faces were let face against the input from {} faces on, where the removal's "
                                 "error was half the pass's threshold", *r.inverted_allowed_at);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

}  // namespace lodkit
