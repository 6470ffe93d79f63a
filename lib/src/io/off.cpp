// Geomview OFF and its variants: [ST][C][N]OFF. A vertex line is x y z [nx ny nz] [r g b [a]] [s t];
// a face line is n i0 ... i(n-1) [r g b [a]]. Colours given as integers are 0-255, as decimals
// 0-1. '#' starts a comment anywhere.
#include <lodkit/version.h>

#include <vector>

#include "io/formats.h"
#include "io/text_cursor.h"

namespace lodkit::detail {
namespace {

void skip_space_and_comments(TextCursor& c) {
  for (;;) {
    c.skip_whitespace();
    if (c.peek() != '#') return;
    c.next_line();
  }
}

// Reads up to four colour channels left on the current line.
bool read_colour(TextCursor& c, float rgba[4], int max_channels = 4) {
  int n = 0;
  while (n < max_channels && !c.at_line_end()) {
    const char* at = c.pos();
    const std::string_view token = c.word();
    const bool decimal = token.find_first_of(".eE") != std::string_view::npos;
    double v;
    TextCursor tc(token, "");
    if (!tc.try_double(v) || !std::isfinite(v)) c.fail(at, fmt::format("bad colour value '{}'", token));
    rgba[n++] = static_cast<float>(decimal ? v : v / 255.0);
  }
  if (n == 0) return false;
  if (n < 3) c.fail("colour needs at least 3 channels");
  if (n == 3) rgba[3] = 1.0f;
  return true;
}

}  // namespace

Mesh read_off(std::string_view bytes, const std::string& name, std::vector<int>* polygon_sizes) {
  TextCursor c(bytes, name);
  skip_space_and_comments(c);
  const char* at = c.pos();
  std::string_view key = c.word();
  bool has_uv = false, has_colour = false, has_normal = false;
  if (key.starts_with("ST")) has_uv = true, key.remove_prefix(2);
  if (key.starts_with("C")) has_colour = true, key.remove_prefix(1);
  if (key.starts_with("N")) has_normal = true, key.remove_prefix(1);
  if (key != "OFF") {
    if (key.ends_with("OFF")) c.fail(at, fmt::format("unsupported OFF variant '{}'", key));
    c.fail(at, "not an OFF file (it does not start with 'OFF')");
  }
  skip_space_and_comments(c);
  const long long nv = c.integer("vertex count");
  const long long nf = c.integer("face count");
  if (!c.at_line_end()) c.integer("edge count");
  if (nv < 0 || nf < 0) c.fail("negative counts in header");
  if (nv > std::numeric_limits<Index>::max()) c.fail("too many vertices");
  // Before allocating for millions of them: a vertex line takes at least 6 bytes ("0 0 0\n"), a face 8
  // ("3 0 1 2\n"). (Smaller counts are read until the file ends, which says where.)
  if (const double least = 6.0 * static_cast<double>(nv) + 8.0 * static_cast<double>(nf);
      nv + nf > (1 << 20) && least - 1 > static_cast<double>(bytes.end() - c.pos()))  // (the last line may lack its newline)
    c.fail(fmt::format("the header says {} vertices and {} faces, which take at least {:.0f} bytes, but {} are left "
                       "(truncated, or the header counts are wrong)", nv, nf, least, bytes.end() - c.pos()));

  Mesh mesh;
  Attributes& a = mesh.attributes;
  mesh.positions.resize(nv, 3);
  if (has_normal) a.normals.resize(nv, 3);
  if (has_colour) a.colours = Colours::Ones(nv, 4);
  if (has_uv) a.uvs.resize(nv, 2);
  for (long long v = 0; v < nv; ++v) {
    skip_space_and_comments(c);
    if (c.done()) c.fail(fmt::format("file ends at vertex {} of {} (truncated, or the header count is wrong)", v, nv));
    for (int k = 0; k < 3; ++k) mesh.positions(v, k) = c.finite_double("vertex coordinate");
    if (has_normal) for (int k = 0; k < 3; ++k) a.normals(v, k) = c.finite_double("normal component");
    if (has_colour) {
      int channels = 4;
      if (has_uv) {  // the last two values on the line are s t
        TextCursor probe = c;
        int tokens = 0;
        while (!probe.at_line_end()) probe.word(), ++tokens;
        channels = std::min(4, tokens - 2);
      }
      float rgba[4];
      if (!read_colour(c, rgba, channels)) c.fail("missing vertex colour");
      for (int k = 0; k < 4; ++k) a.colours(v, k) = rgba[k];
    }
    if (has_uv) for (int k = 0; k < 2; ++k) a.uvs(v, k) = c.finite_double("texture coordinate");
    c.next_line();
  }
  std::vector<Index> tris;
  std::vector<float> face_rgba;
  bool face_colours = false;
  std::vector<long long> polygon;
  tris.reserve(static_cast<std::size_t>(3 * nf));
  for (long long f = 0; f < nf; ++f) {
    skip_space_and_comments(c);
    if (c.done()) c.fail(fmt::format("file ends at face {} of {} (truncated, or the header count is wrong)", f, nf));
    const char* line = c.pos();
    const long long n = c.integer("face vertex count");
    if (n < 3) c.fail(line, fmt::format("face has {} vertices (at least 3 needed)", n));
    polygon.clear();  // grown as indices are read: a corrupt count is not allocated for
    for (long long k = 0; k < n; ++k) {
      const long long index = c.integer("vertex index");
      if (index < 0 || index >= nv)
        c.fail(line, fmt::format("vertex index {} out of range (the file has {} vertices)", index, nv));
      polygon.push_back(index);
    }
    float rgba[4];
    const bool coloured = read_colour(c, rgba);
    if (coloured && !face_colours) {  // the first coloured face: earlier faces default to white
      face_colours = true;
      face_rgba.assign(4 * tris.size() / 3, 1.0f);
    }
    if (polygon_sizes) polygon_sizes->push_back(static_cast<int>(polygon.size()));
    triangulate_fan(polygon, polygon.size(), [&](long long i, long long j, long long k) {
      tris.insert(tris.end(), {Index(i), Index(j), Index(k)});
      if (face_colours) {
        if (coloured) face_rgba.insert(face_rgba.end(), rgba, rgba + 4);
        else face_rgba.insert(face_rgba.end(), {1.0f, 1.0f, 1.0f, 1.0f});
      }
    });
    c.next_line();
  }
  skip_space_and_comments(c);
  if (!c.done()) c.fail("data after the last face (header counts too small?)");
  const auto nt = static_cast<Index>(tris.size() / 3);
  mesh.triangles = Eigen::Map<const Triangles>(tris.data(), nt, 3);
  if (face_colours) a.face_colours = Eigen::Map<const Colours>(face_rgba.data(), nt, 4);
  return mesh;
}

void write_off(const Mesh& mesh, Output& out, const WriteOptions& options) {
  const Attributes& a = mesh.attributes;
  const bool uvs = options.uvs && mesh.has_uvs();
  const bool colours = options.colours && mesh.has_colours();
  const bool normals = options.normals && mesh.has_normals();
  const bool face_colours = options.colours && mesh.has_face_colours();
  const bool col_8bit = !colours || colours_are_8bit(a.colours);
  const bool fcol_8bit = !face_colours || colours_are_8bit(a.face_colours);
  if (uvs) out.put("ST");
  if (colours) out.put('C');
  if (normals) out.put('N');
  out.put("OFF\n# lodkit " LODKIT_VERSION_STRING "\n");
  out.put_number(mesh.num_vertices());
  out.put(' ');
  out.put_number(mesh.num_faces());
  out.put(" 0\n");
  auto colour = [&](float value, bool as_8bit) {
    out.put(' ');
    if (as_8bit) {
      out.put_number(int(to_8bit(value)));
    } else {  // always with a decimal point, so it reads back as 0-1
      const std::string s = fmt::format("{}", value);
      out.put(s);
      if (s.find_first_of(".eE") == std::string::npos) out.put(".0");
    }
  };
  for (Index v = 0; v < mesh.num_vertices(); ++v) {
    out.put_number(mesh.positions(v, 0));
    for (int k = 1; k < 3; ++k) out.put(' '), out.put_number(mesh.positions(v, k));
    if (normals) for (int k = 0; k < 3; ++k) out.put(' '), out.put_number(a.normals(v, k));
    if (colours) for (int k = 0; k < 4; ++k) colour(a.colours(v, k), col_8bit);
    if (uvs) for (int k = 0; k < 2; ++k) out.put(' '), out.put_number(a.uvs(v, k));
    out.put('\n');
  }
  for (Index f = 0; f < mesh.num_faces(); ++f) {
    out.put('3');
    for (int k = 0; k < 3; ++k) out.put(' '), out.put_number(mesh.triangles(f, k));
    if (face_colours) for (int k = 0; k < 4; ++k) colour(a.face_colours(f, k), fcol_8bit);
    out.put('\n');
  }
}

}  // namespace lodkit::detail
