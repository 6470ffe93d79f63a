// Stanford PLY: ASCII, binary little endian and binary big endian. Vertex x y z, normals nx ny nz,
// texture coordinates (u v, s t, texture_u texture_v, texture_s texture_t), colours red green blue
// alpha of any numeric type; face index lists of any integer type (polygons fan-triangulated), face
// colours; "tristrips" elements (-1 restarts) are decoded. Other elements and properties are skipped.
#include <lodkit/version.h>

#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <optional>
#include <vector>

#include "core/huge_pages.h"
#include "io/formats.h"
#include "io/text_cursor.h"

namespace lodkit::detail {
namespace {

enum class PlyType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };
enum class Encoding { Ascii, BinaryLittleEndian, BinaryBigEndian };

std::optional<PlyType> parse_type(std::string_view s) {
  if (s == "char" || s == "int8") return PlyType::Int8;
  if (s == "uchar" || s == "uint8") return PlyType::UInt8;
  if (s == "short" || s == "int16") return PlyType::Int16;
  if (s == "ushort" || s == "uint16") return PlyType::UInt16;
  if (s == "int" || s == "int32") return PlyType::Int32;
  if (s == "uint" || s == "uint32") return PlyType::UInt32;
  if (s == "float" || s == "float32") return PlyType::Float32;
  if (s == "double" || s == "float64") return PlyType::Float64;
  return std::nullopt;
}

std::size_t size_of(PlyType t) {
  switch (t) {
    case PlyType::Int8: case PlyType::UInt8: return 1;
    case PlyType::Int16: case PlyType::UInt16: return 2;
    case PlyType::Int32: case PlyType::UInt32: case PlyType::Float32: return 4;
    case PlyType::Float64: return 8;
  }
  return 0;
}

bool is_integer(PlyType t) { return t != PlyType::Float32 && t != PlyType::Float64; }

// Colour channels: integers are scaled by their type's maximum, floats are taken as they are.
double colour_scale(PlyType t) {
  switch (t) {
    case PlyType::UInt8: return 1.0 / 255.0;
    case PlyType::UInt16: return 1.0 / 65535.0;
    case PlyType::Int8: return 1.0 / 127.0;
    case PlyType::Int16: return 1.0 / 32767.0;
    default: return 1.0;
  }
}

// What lodkit does with a property.
enum class Role {
  Skip, X, Y, Z, NX, NY, NZ, U, V, Red, Green, Blue, Alpha, FaceIndices, StripIndices
};

struct Property {
  std::string name;
  PlyType type = PlyType::Float32;
  bool is_list = false;
  PlyType count_type = PlyType::UInt8;
  Role role = Role::Skip;
};

struct Element {
  std::string name;
  long long count = 0;
  std::vector<Property> properties;
};

struct Header {
  Encoding encoding = Encoding::Ascii;
  std::vector<Element> elements;
  std::size_t body_offset = 0;
};

Role vertex_role(std::string_view n) {
  if (n == "x") return Role::X;
  if (n == "y") return Role::Y;
  if (n == "z") return Role::Z;
  if (n == "nx") return Role::NX;
  if (n == "ny") return Role::NY;
  if (n == "nz") return Role::NZ;
  if (n == "u" || n == "s" || n == "texture_u" || n == "texture_s") return Role::U;
  if (n == "v" || n == "t" || n == "texture_v" || n == "texture_t") return Role::V;
  if (n == "red" || n == "r" || n == "diffuse_red") return Role::Red;
  if (n == "green" || n == "g" || n == "diffuse_green") return Role::Green;
  if (n == "blue" || n == "b" || n == "diffuse_blue") return Role::Blue;
  if (n == "alpha" || n == "a") return Role::Alpha;
  return Role::Skip;
}

Header parse_header(std::string_view bytes, const std::string& name) {
  // The header is ASCII lines up to and including "end_header\n" (or "\r\n").
  if (bytes.substr(0, 3) != "ply")
    throw Error(fmt::format("{}: not a PLY file (it does not start with 'ply')", name));
  const std::size_t end = bytes.find("end_header");
  if (end == std::string_view::npos)
    throw Error(fmt::format("{}: PLY header has no 'end_header' (truncated?)", name));
  Header h;
  std::size_t body = end + std::strlen("end_header");
  if (body < bytes.size() && bytes[body] == '\r') ++body;
  if (body < bytes.size() && bytes[body] == '\n') ++body;
  h.body_offset = body;

  TextCursor c(bytes.substr(0, end), name);
  bool have_format = false;
  c.next_line();  // "ply"
  while (true) {
    c.skip_whitespace();
    if (c.done()) break;
    const char* line = c.pos();
    const std::string_view key = c.word();
    if (key == "format") {
      const std::string_view f = c.word();
      if (f == "ascii") h.encoding = Encoding::Ascii;
      else if (f == "binary_little_endian") h.encoding = Encoding::BinaryLittleEndian;
      else if (f == "binary_big_endian") h.encoding = Encoding::BinaryBigEndian;
      else c.fail(line, fmt::format("unknown PLY format '{}'", f));
      have_format = true;
    } else if (key == "element") {
      Element e;
      e.name = std::string(c.word());
      e.count = c.integer("element count");
      if (e.count < 0) c.fail(line, fmt::format("negative element count {}", e.count));
      h.elements.push_back(std::move(e));
    } else if (key == "property") {
      if (h.elements.empty()) c.fail(line, "property before any element");
      Element& e = h.elements.back();
      Property p;
      std::string_view t = c.word();
      if (t == "list") {
        p.is_list = true;
        const auto ct = parse_type(c.word());
        const auto it = parse_type(c.word());
        if (!ct || !it || !is_integer(*ct)) c.fail(line, "bad list property types");
        p.count_type = *ct;
        p.type = *it;
      } else {
        const auto st = parse_type(t);
        if (!st) c.fail(line, fmt::format("unknown property type '{}'", t));
        p.type = *st;
      }
      p.name = std::string(c.word());
      if (p.name.empty()) c.fail(line, "property has no name");
      if (e.name == "vertex" && !p.is_list) p.role = vertex_role(p.name);
      if (e.name == "face") {
        if (p.is_list && (p.name == "vertex_indices" || p.name == "vertex_index"))
          p.role = Role::FaceIndices;  // float indices too, if whole numbers (index() checks)
        else if (!p.is_list) {
          const Role r = vertex_role(p.name);
          if (r == Role::Red || r == Role::Green || r == Role::Blue || r == Role::Alpha) p.role = r;
        }
      }
      if (e.name == "tristrips" && p.is_list && p.name == "vertex_indices")
        p.role = Role::StripIndices;
      e.properties.push_back(std::move(p));
    } else if (key == "comment" || key == "obj_info") {
      // nothing to keep
    } else {
      c.fail(line, fmt::format("unknown PLY header keyword '{}'", key));
    }
    c.next_line();
  }
  if (!have_format) throw Error(fmt::format("{}: PLY header has no 'format' line", name));
  return h;
}

// Reads values from the body, in one of the three encodings.
class BodyReader {
 public:
  BodyReader(std::string_view body, Encoding enc, const std::string& name)
      : enc_(enc), p_(body.data()), end_(body.data() + body.size()), text_(body, name), name_(name) {}

  void set_context(const Element& e, long long row) {
    element_ = &e;
    row_ = row;
  }

  double scalar(PlyType t) {
    if (enc_ == Encoding::Ascii) {
      double v;
      text_.skip_whitespace();
      if (text_.done()) truncated();
      if (!text_.try_double(v)) text_.fail(fmt::format("bad value '{}' in {} {}", text_.word(),
                                                       element_->name, row_));
      return v;
    }
    const std::size_t n = size_of(t);
    if (static_cast<std::size_t>(end_ - p_) < n) truncated();
    unsigned char b[8];
    std::memcpy(b, p_, n);
    p_ += n;
    if (enc_ == Encoding::BinaryBigEndian) std::reverse(b, b + n);
    switch (t) {
      case PlyType::Int8: return static_cast<std::int8_t>(b[0]);
      case PlyType::UInt8: return b[0];
      case PlyType::Int16: { std::int16_t v; std::memcpy(&v, b, 2); return v; }
      case PlyType::UInt16: { std::uint16_t v; std::memcpy(&v, b, 2); return v; }
      case PlyType::Int32: { std::int32_t v; std::memcpy(&v, b, 4); return v; }
      case PlyType::UInt32: { std::uint32_t v; std::memcpy(&v, b, 4); return v; }
      case PlyType::Float32: { float v; std::memcpy(&v, b, 4); return v; }
      case PlyType::Float64: { double v; std::memcpy(&v, b, 8); return v; }
    }
    return 0;
  }

  long long list_count(PlyType t) {
    const double c = scalar(t);
    if (!(c >= 0) || c != std::floor(c) || c > 1e9)
      fail(fmt::format("bad list length {}", c));
    return static_cast<long long>(c);
  }

  /// A vertex index, which a file may store in any type: a float one must hold a whole number
  /// (casting anything else, or one past long long's range, would be undefined).
  long long index(PlyType t) {
    const double v = scalar(t);
    if (!(std::abs(v) <= 9.0e15) || v != std::floor(v)) fail(fmt::format("bad vertex index {}", v));
    return static_cast<long long>(v);
  }

  /// Called after the last element: anything left over means the header lied.
  void expect_end() {
    if (enc_ == Encoding::Ascii) {
      text_.skip_whitespace();
      if (!text_.done()) text_.fail("data after the last element (header counts too small?)");
    } else if (p_ != end_) {
      throw Error(fmt::format("{}: {} bytes after the last element (header counts too small?)",
                              name_, end_ - p_));
    }
  }

  [[noreturn]] void fail(const std::string& what) const {
    throw Error(fmt::format("{}: {} {}: {}", name_, element_->name, row_, what));
  }

 private:
  [[noreturn]] void truncated() const {
    throw Error(fmt::format("{}: file ends in {} {} of {} (truncated, or the header count is wrong)",
                            name_, element_->name, row_, element_->count));
  }
  Encoding enc_;
  const char* p_;
  const char* end_;
  TextCursor text_;
  const std::string& name_;
  const Element* element_ = nullptr;
  long long row_ = 0;
};

// The header's counts against the bytes after it, before anything is allocated for them: each row of
// an element takes at least its scalars' sizes (a list at least its count) in binary, and at least a
// character and a separator a property in ASCII. A corrupt count of millions is then a clear error
// rather than an allocation that runs out of memory; smaller ones are read until the file ends, which
// says where.
void check_counts_fit(const Header& h, std::size_t body_bytes, const std::string& name) {
  constexpr long long kSmall = 1 << 20;  // rows allocated without a look at the file's size
  double least = 0;  // bytes the rows so far need at the least (a double: counts may be huge)
  for (const Element& e : h.elements) {
    double row = 0;
    for (const Property& p : e.properties)
      row += h.encoding == Encoding::Ascii ? 2.0 : static_cast<double>(size_of(p.is_list ? p.count_type : p.type));
    least += row * static_cast<double>(e.count);
    if (e.count > kSmall && least - 1 > static_cast<double>(body_bytes))  // (the last line may lack its newline)
      throw Error(fmt::format("{}: the header says {} {} elements, which take at least {:.0f} bytes, but the file has "
                              "{} after its header (truncated, or the header count is wrong)",
                              name, e.count, e.name, least, body_bytes));
  }
}

}  // namespace

Mesh read_ply(std::string_view bytes, const std::string& name, std::vector<int>* polygon_sizes) {
  const Header h = parse_header(bytes, name);
  check_counts_fit(h, bytes.size() - h.body_offset, name);
  BodyReader in(bytes.substr(h.body_offset), h.encoding, name);

  Mesh mesh;
  std::vector<Index> tris;
  std::vector<float> face_rgba;
  std::vector<long long> polygon;
  bool have_vertices = false, have_xyz = false;
  long long vertex_count = 0;
  for (const Element& e : h.elements) {
    const bool is_vertex = e.name == "vertex";
    if (is_vertex) {
      if (have_vertices) throw Error(fmt::format("{}: two 'vertex' elements", name));
      have_vertices = true;
      vertex_count = e.count;
      if (e.count > std::numeric_limits<Index>::max())
        throw Error(fmt::format("{}: {} vertices is more than lodkit supports", name, e.count));
      bool has[16] = {};
      for (const Property& p : e.properties) has[static_cast<int>(p.role)] = true;
      have_xyz = has[int(Role::X)] && has[int(Role::Y)] && has[int(Role::Z)];
      if (!have_xyz) throw Error(fmt::format("{}: vertex element lacks x, y or z", name));
      mesh.positions.resize(e.count, 3);
      advise_huge_pages(mesh.positions.data(), sizeof(double) * 3 * static_cast<std::size_t>(e.count));
      if (has[int(Role::NX)] && has[int(Role::NY)] && has[int(Role::NZ)])
        mesh.attributes.normals.resize(e.count, 3);
      if (has[int(Role::U)] && has[int(Role::V)]) mesh.attributes.uvs.resize(e.count, 2);
      if (has[int(Role::Red)] && has[int(Role::Green)] && has[int(Role::Blue)])
        mesh.attributes.colours = Colours::Ones(e.count, 4);
    }
    const bool is_face = e.name == "face";
    bool face_colour = false, face_indices = false;
    if (is_face)
      for (const Property& p : e.properties) {
        face_colour |= p.role == Role::Red;
        face_indices |= p.role == Role::FaceIndices;
      }
    // Faces without indices would be read as none at all; and without any property their count,
    // which no file size bounds, would be trusted for the reserve below.
    if (is_face && e.count > 0 && !face_indices)
      throw Error(fmt::format("{}: the face element has no vertex_indices list", name));
    if (is_face && face_colour) face_rgba.reserve(static_cast<std::size_t>(4 * e.count));
    if (is_face) reserve_huge(tris, static_cast<std::size_t>(3 * e.count));

    // Rows without properties hold nothing, and no file size bounds their count: not looped over.
    if (e.properties.empty()) continue;
    Attributes& a = mesh.attributes;
    for (long long row = 0; row < e.count; ++row) {
      in.set_context(e, row);
      std::array<float, 4> rgba{1, 1, 1, 1};
      std::size_t first_tri = tris.size();
      for (const Property& p : e.properties) {
        if (p.is_list) {
          const long long n = in.list_count(p.count_type);
          if (p.role == Role::Skip) {
            for (long long k = 0; k < n; ++k) in.scalar(p.type);
            continue;
          }
          polygon.clear();  // grown as indices are read: a corrupt count is not allocated for
          for (long long k = 0; k < n; ++k) polygon.push_back(in.index(p.type));
          if (p.role == Role::FaceIndices) {
            if (n < 3)
              in.fail(fmt::format("face has {} vertex indices (at least 3 needed)", n));
            for (long long idx : polygon)
              if (idx < 0 || idx >= vertex_count)
                in.fail(fmt::format("vertex index {} out of range (the file has {} vertices)", idx,
                                    vertex_count));
            if (polygon_sizes) polygon_sizes->push_back(static_cast<int>(polygon.size()));
            triangulate_fan(polygon, polygon.size(), [&](long long i, long long j, long long k) {
              tris.insert(tris.end(), {Index(i), Index(j), Index(k)});
            });
          } else {  // triangle strip with -1 restarts; every other triangle is flipped back
            std::size_t start = 0;
            for (std::size_t k = 0; k <= polygon.size(); ++k) {
              if (k < polygon.size() && polygon[k] >= 0) {
                if (polygon[k] >= vertex_count)
                  in.fail(fmt::format("strip index {} out of range", polygon[k]));
                continue;
              }
              for (std::size_t i = start; i + 2 < k; ++i) {
                Index t0 = Index(polygon[i]), t1 = Index(polygon[i + 1]), t2 = Index(polygon[i + 2]);
                if ((i - start) % 2) std::swap(t0, t1);
                if (t0 != t1 && t1 != t2 && t0 != t2) {
                  tris.insert(tris.end(), {t0, t1, t2});
                  if (polygon_sizes) polygon_sizes->push_back(3);
                }
              }
              start = k + 1;
            }
          }
          continue;
        }
        const double v = in.scalar(p.type);
        if (is_vertex) {
          switch (p.role) {
            case Role::X: mesh.positions(row, 0) = v; break;
            case Role::Y: mesh.positions(row, 1) = v; break;
            case Role::Z: mesh.positions(row, 2) = v; break;
            case Role::NX: if (a.normals.rows()) a.normals(row, 0) = v; break;
            case Role::NY: if (a.normals.rows()) a.normals(row, 1) = v; break;
            case Role::NZ: if (a.normals.rows()) a.normals(row, 2) = v; break;
            case Role::U: if (a.uvs.rows()) a.uvs(row, 0) = v; break;
            case Role::V: if (a.uvs.rows()) a.uvs(row, 1) = v; break;
            case Role::Red: case Role::Green: case Role::Blue: case Role::Alpha:
              if (a.colours.rows())
                a.colours(row, int(p.role) - int(Role::Red)) =
                    static_cast<float>(v * colour_scale(p.type));
              break;
            default: break;
          }
        } else if (is_face && p.role >= Role::Red && p.role <= Role::Alpha) {
          rgba[int(p.role) - int(Role::Red)] = static_cast<float>(v * colour_scale(p.type));
        }
      }
      if (face_colour)
        for (std::size_t t = first_tri; t < tris.size(); t += 3)
          face_rgba.insert(face_rgba.end(), rgba.begin(), rgba.end());
    }
  }
  in.expect_end();
  if (!have_vertices) throw Error(fmt::format("{}: PLY file has no vertex element", name));

  const auto nf = static_cast<Index>(tris.size() / 3);
  mesh.triangles.resize(nf, 3);
  advise_huge_pages(mesh.triangles.data(), sizeof(Index) * tris.size());
  mesh.triangles = Eigen::Map<const Triangles>(tris.data(), nf, 3);
  if (!face_rgba.empty()) mesh.attributes.face_colours = Eigen::Map<const Colours>(face_rgba.data(), nf, 4);
  return mesh;
}

namespace {

template <typename T>
void put_binary(Output& out, T value, bool big_endian) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, &value, sizeof(T));
  if (big_endian) std::reverse(b, b + sizeof(T));
  out.put_bytes(b, sizeof(T));
}

}  // namespace

void write_ply(const Mesh& mesh, Output& out, const WriteOptions& options) {
  const Attributes& a = mesh.attributes;
  const bool normals = options.normals && mesh.has_normals();
  const bool uvs = options.uvs && mesh.has_uvs();
  const bool colours = options.colours && mesh.has_colours();
  const bool face_colours = options.colours && mesh.has_face_colours();
  // Choose the narrowest field type that stores every value exactly.
  const bool pos_float = exactly_float(mesh.positions);
  const bool nrm_float = !normals || exactly_float(a.normals);
  const bool uv_float = !uvs || exactly_float(a.uvs);
  const bool col_8bit = !colours || colours_are_8bit(a.colours);
  const bool fcol_8bit = !face_colours || colours_are_8bit(a.face_colours);
  const PlyEncoding enc = options.ply_encoding;
  const bool ascii = enc == PlyEncoding::Ascii;
  const bool big = enc == PlyEncoding::BinaryBigEndian;

  out.put("ply\nformat ");
  out.put(ascii ? "ascii" : big ? "binary_big_endian" : "binary_little_endian");
  out.put(" 1.0\ncomment lodkit " LODKIT_VERSION_STRING "\nelement vertex ");
  out.put_number(mesh.num_vertices());
  out.put('\n');
  auto props = [&](const char* type, std::initializer_list<const char*> names) {
    for (const char* n : names) out.put(fmt::format("property {} {}\n", type, n));
  };
  props(pos_float ? "float" : "double", {"x", "y", "z"});
  if (normals) props(nrm_float ? "float" : "double", {"nx", "ny", "nz"});
  if (uvs) props(uv_float ? "float" : "double", {"s", "t"});
  if (colours) props(col_8bit ? "uchar" : "float", {"red", "green", "blue", "alpha"});
  out.put("element face ");
  out.put_number(mesh.num_faces());
  out.put("\nproperty list uchar int vertex_indices\n");
  if (face_colours) props(fcol_8bit ? "uchar" : "float", {"red", "green", "blue", "alpha"});
  out.put("end_header\n");

  // ASCII rows separate values by single spaces; `first` marks the start of a row.
  bool first = true;
  auto separator = [&] {
    if (!first) out.put(' ');
    first = false;
  };
  auto real = [&](double v, bool as_float) {
    if (ascii) {
      separator();
      out.put_number(v);
    } else if (as_float) {
      put_binary(out, static_cast<float>(v), big);
    } else {
      put_binary(out, v, big);
    }
  };
  auto colour = [&](float c, bool as_8bit) {
    if (ascii) {
      separator();
      if (as_8bit) out.put_number(int(to_8bit(c)));
      else out.put_number(c);
    } else if (as_8bit) {
      put_binary(out, to_8bit(c), big);
    } else {
      put_binary(out, c, big);
    }
  };
  auto end_row = [&] {
    if (ascii) out.put('\n');
    first = true;
  };
  for (Index v = 0; v < mesh.num_vertices(); ++v) {
    for (int k = 0; k < 3; ++k) real(mesh.positions(v, k), pos_float);
    if (normals) for (int k = 0; k < 3; ++k) real(a.normals(v, k), nrm_float);
    if (uvs) for (int k = 0; k < 2; ++k) real(a.uvs(v, k), uv_float);
    if (colours) for (int k = 0; k < 4; ++k) colour(a.colours(v, k), col_8bit);
    end_row();
  }
  for (Index f = 0; f < mesh.num_faces(); ++f) {
    if (ascii) {
      out.put('3');
      for (int k = 0; k < 3; ++k) out.put(' '), out.put_number(mesh.triangles(f, k));
      first = false;
    } else {
      put_binary(out, static_cast<unsigned char>(3), big);
      for (int k = 0; k < 3; ++k) put_binary(out, static_cast<std::int32_t>(mesh.triangles(f, k)), big);
    }
    if (face_colours) for (int k = 0; k < 4; ++k) colour(a.face_colours(f, k), fcol_8bit);
    end_row();
  }
}

}  // namespace lodkit::detail
