// Wavefront OBJ: v (with the common "v x y z r g b" colour extension), vt, vn and polygonal f
// records with 1-based or negative (relative) indices. Polygons are fan-triangulated. A position
// used with different vt/vn in different corners becomes several vertices (a seam); the first
// combination seen keeps the position's own index, so files without seams keep their vertex order.
#include <lodkit/version.h>

#include <array>
#include <unordered_map>
#include <vector>

#include "core/hash.h"
#include "io/formats.h"
#include "io/text_cursor.h"

namespace lodkit::detail {
namespace {

struct Corner {
  Index p, t, n;  // -1 when absent
};

struct ComboKey {
  Index p, t, n;
  bool operator==(const ComboKey&) const = default;
};
struct ComboHash {
  std::size_t operator()(const ComboKey& k) const {
    return mix64((std::uint64_t(std::uint32_t(k.p)) << 32) ^ std::uint32_t(k.t) ^
                 (std::uint64_t(std::uint32_t(k.n)) << 17));
  }
};

// Parses one "p", "p/t", "p//n" or "p/t/n" corner. Indices are resolved against the counts so far.
Corner parse_corner(TextCursor& c, Index np, Index nt, Index nn) {
  auto resolve = [&](long long raw, Index count, const char* kind, const char* at) -> Index {
    long long r = raw > 0 ? raw - 1 : count + raw;
    if (raw == 0) c.fail(at, fmt::format("{} index 0 is invalid (OBJ indices start at 1)", kind));
    if (r < 0 || r >= count)
      c.fail(at, fmt::format("{} index {} is out of range ({} defined so far)", kind, raw, count));
    return static_cast<Index>(r);
  };
  const char* at = c.pos();
  long long raw;
  if (!c.try_integer(raw)) c.fail(at, fmt::format("bad face corner '{}'", c.word()));
  Corner corner{resolve(raw, np, "vertex", at), -1, -1};
  if (c.peek() != '/') return corner;
  c.next_char();
  if (c.peek() != '/') {
    if (!c.try_integer(raw)) c.fail(at, "bad texture index in face corner");
    corner.t = resolve(raw, nt, "texture coordinate", at);
  }
  if (c.peek() != '/') return corner;
  c.next_char();
  if (!c.try_integer(raw)) c.fail(at, "bad normal index in face corner");
  corner.n = resolve(raw, nn, "normal", at);
  return corner;
}

}  // namespace

Mesh read_obj(std::string_view bytes, const std::string& name, std::vector<int>* polygon_sizes) {
  TextCursor c(bytes, name);
  std::vector<double> positions, uvs, normals;
  std::vector<float> colours;  // per position, filled only once a coloured "v" appears
  std::vector<Corner> corners;
  std::vector<std::array<Index, 3>> triangles;  // indices into `corners`
  std::vector<Corner> polygon;
  bool any_t = false, any_n = false;

  while (true) {
    c.skip_whitespace();
    if (c.done()) break;
    if (c.peek() == '#') {
      c.next_line();
      continue;
    }
    const char* line = c.pos();
    const std::string_view key = c.word();
    if (key == "v") {
      for (int k = 0; k < 3; ++k) positions.push_back(c.finite_double("vertex coordinate"));
      double extra[4];
      int n_extra = 0;
      while (n_extra < 4 && c.try_double(extra[n_extra])) ++n_extra;
      if (n_extra == 3 || n_extra == 4) {  // x y z r g b [a]: a widespread extension
        const std::size_t v = positions.size() / 3 - 1;
        if (colours.empty()) colours.assign(4 * v, 1.0f);
        for (int k = 0; k < 3; ++k) colours.push_back(static_cast<float>(extra[k]));
        colours.push_back(n_extra == 4 ? static_cast<float>(extra[3]) : 1.0f);
      } else if (!colours.empty()) {
        colours.insert(colours.end(), {1.0f, 1.0f, 1.0f, 1.0f});
      }
    } else if (key == "vt") {
      uvs.push_back(c.finite_double("texture coordinate"));
      double v = 0.0;
      if (!c.at_line_end()) v = c.finite_double("texture coordinate");
      uvs.push_back(v);
    } else if (key == "vn") {
      for (int k = 0; k < 3; ++k) normals.push_back(c.finite_double("normal component"));
    } else if (key == "f" || key == "fo") {
      polygon.clear();
      const auto np = static_cast<Index>(positions.size() / 3);
      const auto nt = static_cast<Index>(uvs.size() / 2);
      const auto nn = static_cast<Index>(normals.size() / 3);
      while (!c.at_line_end()) polygon.push_back(parse_corner(c, np, nt, nn));
      if (polygon.size() < 3)
        c.fail(line, fmt::format("face has {} corner{} (at least 3 needed)", polygon.size(),
                                 polygon.size() == 1 ? "" : "s"));
      const auto base = static_cast<Index>(corners.size());
      for (const Corner& k : polygon) {
        any_t |= k.t >= 0;
        any_n |= k.n >= 0;
        corners.push_back(k);
      }
      if (polygon_sizes) polygon_sizes->push_back(static_cast<int>(polygon.size()));
      for (std::size_t k = 1; k + 1 < polygon.size(); ++k)
        triangles.push_back({base, base + static_cast<Index>(k), base + static_cast<Index>(k + 1)});
    }
    // Everything else (o, g, s, usemtl, mtllib, l, p, curves) carries nothing lodkit stores.
    c.next_line();
  }

  if (positions.empty()) throw Error(fmt::format("{}: no vertices found (is this an OBJ file?)", name));

  Mesh mesh;
  const auto np = static_cast<Index>(positions.size() / 3);
  const auto nf = static_cast<Index>(triangles.size());
  mesh.triangles.resize(nf, 3);

  if (!any_t && !any_n) {  // the common case: one vertex per position
    mesh.positions = Eigen::Map<const Positions>(positions.data(), np, 3);
    for (Index f = 0; f < nf; ++f)
      for (int k = 0; k < 3; ++k) mesh.triangles(f, k) = corners[triangles[f][k]].p;
    if (!colours.empty()) mesh.attributes.colours = Eigen::Map<const Colours>(colours.data(), np, 4);
    return mesh;
  }

  // Corners with their own (t, n): the first combination per position keeps slot p, others are
  // appended after the positions.
  std::vector<std::pair<Index, Index>> first(static_cast<std::size_t>(np), {-2, -2});
  std::unordered_map<ComboKey, Index, ComboHash> extra;
  std::vector<Corner> slots;  // slot -> its (p, t, n), for slots >= np
  std::vector<Index> slot_of_corner(corners.size());
  for (std::size_t i = 0; i < corners.size(); ++i) {
    const Corner& k = corners[i];
    auto& f = first[k.p];
    if (f.first == -2) f = {k.t, k.n};
    if (f.first == k.t && f.second == k.n) {
      slot_of_corner[i] = k.p;
      continue;
    }
    auto [it, inserted] = extra.try_emplace({k.p, k.t, k.n}, np + static_cast<Index>(slots.size()));
    if (inserted) slots.push_back(k);
    slot_of_corner[i] = it->second;
  }
  const Index nv = np + static_cast<Index>(slots.size());
  mesh.positions.resize(nv, 3);
  mesh.positions.topRows(np) = Eigen::Map<const Positions>(positions.data(), np, 3);
  if (any_t) mesh.attributes.uvs = TexCoords::Zero(nv, 2);
  if (any_n) mesh.attributes.normals = Normals::Zero(nv, 3);
  if (!colours.empty()) mesh.attributes.colours.resize(nv, 4);
  auto fill = [&](Index slot, Index p, Index t, Index n) {
    mesh.positions.row(slot) = Eigen::Map<const Eigen::RowVector3d>(&positions[3 * p]);
    if (!colours.empty())
      mesh.attributes.colours.row(slot) = Eigen::Map<const Eigen::RowVector4f>(&colours[4 * p]);
    if (t >= 0) mesh.attributes.uvs.row(slot) = Eigen::Map<const Eigen::RowVector2d>(&uvs[2 * t]);
    if (n >= 0)
      mesh.attributes.normals.row(slot) = Eigen::Map<const Eigen::RowVector3d>(&normals[3 * n]);
  };
  for (Index p = 0; p < np; ++p) fill(p, p, first[p].first, first[p].second);
  for (std::size_t s = 0; s < slots.size(); ++s)
    fill(np + static_cast<Index>(s), slots[s].p, slots[s].t, slots[s].n);
  for (Index f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) mesh.triangles(f, k) = slot_of_corner[triangles[f][k]];
  return mesh;
}

void write_obj(const Mesh& mesh, Output& out, const WriteOptions& options) {
  const Attributes& a = mesh.attributes;
  const bool colours = options.colours && mesh.has_colours();
  const bool uvs = options.uvs && mesh.has_uvs();
  const bool normals = options.normals && mesh.has_normals();
  out.put("# lodkit " LODKIT_VERSION_STRING "\n");
  for (Index v = 0; v < mesh.num_vertices(); ++v) {
    out.put('v');
    for (int k = 0; k < 3; ++k) out.put(' '), out.put_number(mesh.positions(v, k));
    if (colours)
      for (int k = 0; k < 3; ++k) out.put(' '), out.put_number(a.colours(v, k));
    out.put('\n');
  }
  if (uvs)
    for (Index v = 0; v < mesh.num_vertices(); ++v) {
      out.put("vt ");
      out.put_number(a.uvs(v, 0));
      out.put(' ');
      out.put_number(a.uvs(v, 1));
      out.put('\n');
    }
  if (normals)
    for (Index v = 0; v < mesh.num_vertices(); ++v) {
      out.put("vn");
      for (int k = 0; k < 3; ++k) out.put(' '), out.put_number(a.normals(v, k));
      out.put('\n');
    }
  for (Index f = 0; f < mesh.num_faces(); ++f) {
    out.put('f');
    for (int k = 0; k < 3; ++k) {
      const Index i = mesh.triangles(f, k) + 1;
      out.put(' ');
      out.put_number(i);
      if (uvs || normals) {
        out.put('/');
        if (uvs) out.put_number(i);
        if (normals) out.put('/'), out.put_number(i);
      }
    }
    out.put('\n');
  }
}

}  // namespace lodkit::detail
