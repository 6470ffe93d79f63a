#include <lodkit/error.h>
#include <lodkit/mesh.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <numeric>
#include <vector>

#include "core/hash.h"
#include "core/huge_pages.h"

namespace lodkit {
namespace {

template <typename Matrix>
void check_rows(const Matrix& m, Index expected, const char* what, const char* per,
                const std::string& context) {
  if (m.rows() != 0 && m.rows() != expected)
    throw Error(fmt::format("{}: {} has {} rows but the mesh has {} {}", context, what, m.rows(),
                            expected, per));
}

template <typename Matrix>
void check_finite(const Matrix& m, const char* what, const std::string& context) {
  for (Eigen::Index r = 0; r < m.rows(); ++r)
    for (Eigen::Index c = 0; c < m.cols(); ++c)
      if (!std::isfinite(static_cast<double>(m(r, c))))
        throw Error(fmt::format("{}: {} {} is not finite ({})", context, what, r,
                                static_cast<double>(m(r, c))));
}

}  // namespace

void validate(const Mesh& mesh, const std::string& context) {
  const Index n = mesh.num_vertices();
  check_finite(mesh.positions, "vertex", context);
  for (Index v = 0; v < n; ++v) {
    const Eigen::Vector3d p = mesh.positions.row(v).transpose();
    if (!within_coordinate_range(p))
      throw Error(fmt::format("{}: vertex {} has a coordinate of {}, beyond the range of a float (±{:.8g}) "
                              "that lodkit computes in; scale the mesh down",
                              context, v, p.cwiseAbs().maxCoeff(), std::numeric_limits<float>::max()));
  }
  for (Index f = 0; f < mesh.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      const Index v = mesh.triangles(f, k);
      if (v < 0 || v >= n)
        throw Error(fmt::format("{}: face {} refers to vertex {} but there are {} vertices", context,
                                f, v, n));
    }
  const Attributes& a = mesh.attributes;
  check_rows(a.normals, n, "the normal array", "vertices", context);
  check_rows(a.uvs, n, "the UV array", "vertices", context);
  check_rows(a.colours, n, "the colour array", "vertices", context);
  check_rows(a.face_colours, mesh.num_faces(), "the face colour array", "faces", context);
  check_finite(a.normals, "normal", context);
  check_finite(a.uvs, "UV", context);
  check_finite(a.colours, "colour", context);
  check_finite(a.face_colours, "face colour", context);
}

Eigen::AlignedBox3d bounding_box(const Mesh& mesh) {
  Eigen::AlignedBox3d box;
  for (Index v = 0; v < mesh.num_vertices(); ++v) box.extend(mesh.positions.row(v).transpose());
  return box;
}

Eigen::VectorX<Index> position_classes(const Mesh& mesh) {
  const Index n = mesh.num_vertices();
  Eigen::VectorX<Index> cls(n);
  detail::advise_huge_pages(cls.data(), sizeof(Index) * static_cast<std::size_t>(n));
  // Open addressing, linear probing, each slot the first vertex of its class: one flat array, where a
  // node-based map allocated per vertex (a sixth of a 1M-face simplification's setup).
  std::size_t capacity = 16;
  while (capacity < 2 * static_cast<std::size_t>(n)) capacity *= 2;
  auto slot = detail::huge_vector<Index>(capacity, -1);
  auto key_of = [&](Index v) {
    const auto p = mesh.positions.row(v);
    return detail::position_key(p[0], p[1], p[2]);
  };
  for (Index v = 0; v < n; ++v) {
    const detail::PositionKey key = key_of(v);
    std::size_t i = detail::PositionKeyHash{}(key) & (capacity - 1);
    while (slot[i] >= 0 && !(key_of(slot[i]) == key)) i = (i + 1) & (capacity - 1);
    if (slot[i] < 0) slot[i] = v;
    cls[v] = slot[i];
  }
  return cls;
}

namespace {

// Applies a vertex remap (old -> new, -1 = dropped) to every per-vertex array and the triangles.
void remap_vertices(Mesh& mesh, const std::vector<Index>& new_of_old, Index new_count) {
  auto compact = [&](auto& matrix) {
    if (matrix.rows() == 0) return;
    std::remove_reference_t<decltype(matrix)> out(new_count, matrix.cols());
    for (Index v = 0; v < static_cast<Index>(new_of_old.size()); ++v)
      if (new_of_old[v] >= 0) out.row(new_of_old[v]) = matrix.row(v);
    matrix = std::move(out);
  };
  compact(mesh.positions);
  compact(mesh.attributes.normals);
  compact(mesh.attributes.uvs);
  compact(mesh.attributes.colours);
  for (Index f = 0; f < mesh.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) mesh.triangles(f, k) = new_of_old[mesh.triangles(f, k)];
}

}  // namespace

std::vector<Index> identical_vertex_classes(const Mesh& mesh) {
  const Index n = mesh.num_vertices();
  const Attributes& a = mesh.attributes;
  // A vertex record: position then every attribute present, one flat array of ordered keys (a vector
  // per vertex cost an allocation each). Keys compare like the values, with -0 equal to +0 and every
  // NaN equal to every other, so the sort sees a strict order whatever the input holds.
  auto key = [](double x) {
    const std::uint64_t b = x != x ? 0x7ff8000000000000ULL : detail::bits_of(x);
    return b >> 63 ? ~b : b | (1ULL << 63);
  };
  const auto width = [](const auto& m) { return m.rows() ? static_cast<std::size_t>(m.cols()) : 0u; };
  const std::size_t k = 3 + width(a.normals) + width(a.uvs) + width(a.colours);
  auto records = detail::huge_vector<std::uint64_t>(k * static_cast<std::size_t>(n));
  for (Index v = 0; v < n; ++v) {
    std::uint64_t* r = &records[k * static_cast<std::size_t>(v)];
    for (int d = 0; d < 3; ++d) *r++ = key(mesh.positions(v, d));
    for (std::size_t d = 0; d < width(a.normals); ++d) *r++ = key(a.normals(v, d));
    for (std::size_t d = 0; d < width(a.uvs); ++d) *r++ = key(a.uvs(v, d));
    for (std::size_t d = 0; d < width(a.colours); ++d) *r++ = key(a.colours(v, d));
  }
  auto row = [&](Index v) { return records.begin() + static_cast<std::ptrdiff_t>(k * static_cast<std::size_t>(v)); };
  auto same = [&](Index i, Index j) { return std::equal(row(i), row(i) + k, row(j)); };
  // Open addressing, linear probing, each slot the first (lowest) vertex of its class: a sort of all
  // records was the largest step of a 1M-face simplification's setup.
  std::size_t capacity = 16;
  while (capacity < 2 * static_cast<std::size_t>(n)) capacity *= 2;
  auto slot = detail::huge_vector<Index>(capacity, -1);
  auto representative = detail::huge_vector<Index>(static_cast<std::size_t>(n));
  for (Index v = 0; v < n; ++v) {
    std::uint64_t h = 0;
    for (auto r = row(v); r != row(v) + k; ++r) h = detail::mix64(h ^ *r);
    std::size_t i = h & (capacity - 1);
    while (slot[i] >= 0 && !same(slot[i], v)) i = (i + 1) & (capacity - 1);
    if (slot[i] < 0) slot[i] = v;
    representative[v] = slot[i];
  }
  return representative;
}

Index weld_identical_vertices(Mesh& mesh) {
  const Index n = mesh.num_vertices();
  const std::vector<Index> representative = identical_vertex_classes(mesh);
  std::vector<Index> new_of_old(static_cast<std::size_t>(n), -1);
  Index next = 0;
  for (Index v = 0; v < n; ++v)
    if (representative[v] == v) new_of_old[v] = next++;
  for (Index v = 0; v < n; ++v) new_of_old[v] = new_of_old[representative[v]];
  const Index removed = n - next;
  if (removed > 0) {
    // remap_vertices copies rows by new index; duplicates write the same row twice, harmlessly.
    remap_vertices(mesh, new_of_old, next);
  }
  return removed;
}

Index remove_unreferenced_vertices(Mesh& mesh) {
  const Index n = mesh.num_vertices();
  std::vector<char> used(static_cast<std::size_t>(n), 0);
  for (Index f = 0; f < mesh.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) used[mesh.triangles(f, k)] = 1;
  std::vector<Index> new_of_old(static_cast<std::size_t>(n), -1);
  Index next = 0;
  for (Index v = 0; v < n; ++v)
    if (used[v]) new_of_old[v] = next++;
  if (next != n) remap_vertices(mesh, new_of_old, next);
  return n - next;
}

double signed_volume(const Mesh& mesh) {
  const Eigen::AlignedBox3d box = bounding_box(mesh);
  const Eigen::Vector3d o = box.isEmpty() ? Eigen::Vector3d(Eigen::Vector3d::Zero()) : Eigen::Vector3d(box.center());
  double six_volume = 0.0;
  for (Index f = 0; f < mesh.num_faces(); ++f) {
    const Eigen::Vector3d a = mesh.positions.row(mesh.triangles(f, 0)).transpose() - o,
                          b = mesh.positions.row(mesh.triangles(f, 1)).transpose() - o,
                          c = mesh.positions.row(mesh.triangles(f, 2)).transpose() - o;
    six_volume += a.dot(b.cross(c));
  }
  return six_volume / 6.0;
}

namespace {

Mesh concatenate(std::span<const Mesh* const> parts) {
  Index nv = 0, nf = 0;
  for (const Mesh* p : parts) nv += p->num_vertices(), nf += p->num_faces();
  Mesh m;
  m.positions.resize(nv, 3);
  m.triangles.resize(nf, 3);
  Index v = 0, f = 0;
  for (const Mesh* p : parts) {
    m.positions.middleRows(v, p->num_vertices()) = p->positions;
    m.triangles.middleRows(f, p->num_faces()) = p->triangles.array() + v;
    v += p->num_vertices(), f += p->num_faces();
  }
  return m;
}

}  // namespace

Mesh concatenated(const Mesh& a, const Mesh& b) {
  const Mesh* parts[] = {&a, &b};
  return concatenate(parts);
}

Mesh concatenated(std::span<const Mesh> parts) {
  std::vector<const Mesh*> pointers;
  for (const Mesh& p : parts) pointers.push_back(&p);
  return concatenate(pointers);
}

Normals compute_vertex_normals(const Mesh& mesh) {
  Normals normals = Normals::Zero(mesh.num_vertices(), 3);
  for (Index f = 0; f < mesh.num_faces(); ++f) {
    const auto t = mesh.triangles.row(f);
    const Eigen::Vector3d a = mesh.positions.row(t[0]), b = mesh.positions.row(t[1]),
                          c = mesh.positions.row(t[2]);
    const Eigen::Vector3d area_normal = (b - a).cross(c - a);  // length = 2 * area
    for (int k = 0; k < 3; ++k) normals.row(t[k]) += area_normal.transpose();
  }
  for (Index v = 0; v < mesh.num_vertices(); ++v) {
    const double len = normals.row(v).norm();
    if (len > 0) normals.row(v) /= len;
  }
  return normals;
}

}  // namespace lodkit
