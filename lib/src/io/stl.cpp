// STL, ASCII and binary. STL stores every triangle's corners separately, so positions are welded
// (bit-identical coordinates become one vertex) on read. A file is binary when its size is exactly
// 84 + 50 * (the triangle count in its header); a file starting with "solid" is otherwise ASCII.
#include <lodkit/version.h>

#include <cstring>
#include <unordered_map>
#include <vector>

#include "core/hash.h"
#include "io/formats.h"
#include "io/text_cursor.h"

namespace lodkit::detail {
namespace {

class Welder {
 public:
  explicit Welder(std::size_t expected) { index_.reserve(expected); }
  Index add(double x, double y, double z) {
    auto [it, inserted] = index_.try_emplace(position_key(x, y, z), static_cast<Index>(xyz_.size() / 3));
    if (inserted) xyz_.insert(xyz_.end(), {x, y, z});
    return it->second;
  }
  Positions positions() const {
    return Eigen::Map<const Positions>(xyz_.data(), static_cast<Index>(xyz_.size() / 3), 3);
  }

 private:
  std::unordered_map<PositionKey, Index, PositionKeyHash> index_;
  std::vector<double> xyz_;
};

Mesh read_binary_stl(std::string_view bytes, std::uint32_t count, const std::string& name) {
  Welder welder(count);
  std::vector<Index> tris(3 * static_cast<std::size_t>(count));
  const char* p = bytes.data() + 84;
  for (std::uint32_t f = 0; f < count; ++f, p += 50) {
    float v[9];
    std::memcpy(v, p + 12, sizeof v);  // skip the stored normal; it is recomputed when needed
    for (int k = 0; k < 3; ++k) {
      for (int i = 0; i < 3; ++i)
        if (!std::isfinite(v[3 * k + i]))
          throw Error(fmt::format("{}: triangle {} has a non-finite coordinate ({})", name, f, v[3 * k + i]));
      tris[3 * f + k] = welder.add(v[3 * k], v[3 * k + 1], v[3 * k + 2]);
    }
  }
  Mesh mesh;
  mesh.positions = welder.positions();
  mesh.triangles = Eigen::Map<const Triangles>(tris.data(), count, 3);
  return mesh;
}

Mesh read_ascii_stl(std::string_view bytes, const std::string& name) {
  TextCursor c(bytes, name);
  Welder welder(bytes.size() / 200);
  std::vector<Index> tris;
  c.word();  // "solid"
  c.next_line();
  bool ended = false;
  while (true) {
    c.skip_whitespace();
    if (c.done()) break;
    const char* at = c.pos();
    const std::string_view key = c.word();
    if (key == "facet") {
      // facet normal nx ny nz / outer loop / vertex x3 / endloop / endfacet
      c.next_line();
      c.skip_whitespace();
      if (c.word() != "outer") c.fail(at, "expected 'outer loop' after 'facet'");
      c.next_line();
      for (int k = 0; k < 3; ++k) {
        c.skip_whitespace();
        const char* vat = c.pos();
        if (c.word() != "vertex") c.fail(vat, "expected 'vertex' (facets must be triangles)");
        // STL is single precision in both encodings: round like the binary reader does.
        const double x = static_cast<float>(c.finite_double("vertex coordinate"));
        const double y = static_cast<float>(c.finite_double("vertex coordinate"));
        const double z = static_cast<float>(c.finite_double("vertex coordinate"));
        tris.push_back(welder.add(x, y, z));
        c.next_line();
      }
      c.skip_whitespace();
      if (c.word() != "endloop") c.fail(at, "expected 'endloop' (facets must be triangles)");
      c.next_line();
      c.skip_whitespace();
      if (c.word() != "endfacet") c.fail(at, "expected 'endfacet'");
    } else if (key == "endsolid") {
      ended = true;
    } else if (key == "solid") {
      // several solids in one file: keep reading
    } else {
      c.fail(at, fmt::format("unexpected '{}' in ASCII STL", key));
    }
    c.next_line();
  }
  if (!ended) throw Error(fmt::format("{}: ASCII STL has no 'endsolid' (truncated?)", name));
  Mesh mesh;
  mesh.positions = welder.positions();
  mesh.triangles = Eigen::Map<const Triangles>(tris.data(), static_cast<Index>(tris.size() / 3), 3);
  return mesh;
}

}  // namespace

Mesh read_stl(std::string_view bytes, const std::string& name) {
  if (bytes.size() >= 84) {
    std::uint32_t count;
    std::memcpy(&count, bytes.data() + 80, 4);
    if (bytes.size() == 84 + 50 * static_cast<std::uint64_t>(count))
      return read_binary_stl(bytes, count, name);
  }
  std::string_view start = bytes.substr(0, std::min<std::size_t>(bytes.size(), 512));
  while (!start.empty() && std::isspace(static_cast<unsigned char>(start.front()))) start.remove_prefix(1);
  if (start.starts_with("solid") && bytes.find("facet") != std::string_view::npos)
    return read_ascii_stl(bytes, name);
  if (start.starts_with("solid") && bytes.find("endsolid") != std::string_view::npos)
    return read_ascii_stl(bytes, name);  // an empty solid
  if (bytes.size() < 84)
    throw Error(fmt::format("{}: too short for a binary STL ({} bytes, the header alone is 84)", name,
                            bytes.size()));
  std::uint32_t count;
  std::memcpy(&count, bytes.data() + 80, 4);
  throw Error(fmt::format("{}: binary STL header says {} triangles ({} bytes) but the file has {} bytes "
                          "(truncated or corrupt)",
                          name, count, 84 + 50 * static_cast<std::uint64_t>(count), bytes.size()));
}

void write_stl(const Mesh& mesh, Output& out, const WriteOptions& options) {
  auto normal_of = [&](Index f) {
    const auto t = mesh.triangles.row(f);
    const Eigen::Vector3d a = mesh.positions.row(t[0]), b = mesh.positions.row(t[1]),
                          c = mesh.positions.row(t[2]);
    const Eigen::Vector3d n = (b - a).cross(c - a);
    const double len = n.norm();
    return len > 0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
  };
  if (!options.stl_binary) {
    out.put("solid lodkit\n");
    for (Index f = 0; f < mesh.num_faces(); ++f) {
      const Eigen::Vector3d n = normal_of(f);
      out.put(fmt::format("facet normal {} {} {}\n outer loop\n", n.x(), n.y(), n.z()));
      for (int k = 0; k < 3; ++k) {
        const auto p = mesh.positions.row(mesh.triangles(f, k));
        // STL is float32: write the float value so ASCII and binary files agree.
        out.put(fmt::format("  vertex {} {} {}\n", float(p[0]), float(p[1]), float(p[2])));
      }
      out.put(" endloop\nendfacet\n");
    }
    out.put("endsolid lodkit\n");
    return;
  }
  char header[80] = {};
  std::snprintf(header, sizeof header, "binary STL written by lodkit %s", LODKIT_VERSION_STRING);
  out.put_bytes(header, 80);
  const auto count = static_cast<std::uint32_t>(mesh.num_faces());
  out.put_bytes(&count, 4);
  for (Index f = 0; f < mesh.num_faces(); ++f) {
    float record[12];
    const Eigen::Vector3d n = normal_of(f);
    for (int i = 0; i < 3; ++i) record[i] = static_cast<float>(n[i]);
    for (int k = 0; k < 3; ++k)
      for (int i = 0; i < 3; ++i)
        record[3 + 3 * k + i] = static_cast<float>(mesh.positions(mesh.triangles(f, k), i));
    out.put_bytes(record, sizeof record);
    const std::uint16_t attribute_bytes = 0;
    out.put_bytes(&attribute_bytes, 2);
  }
}

}  // namespace lodkit::detail
