#include "bad_corpus.h"

#include <lodkit/io.h>
#include <lodkit/primitives.h>

#include <cstring>
#include <fstream>

#include "test_util.h"

namespace lodkit::test {

std::vector<BadFile> write_bad_corpus(const std::filesystem::path& dir) {
  std::vector<BadFile> corpus;
  auto add = [&](const std::string& name, const std::string& bytes, const std::string& expected) {
    write_text(dir / name, bytes);
    corpus.push_back({name, expected});
  };
  const std::string cube_obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n";

  // Empty and unknown.
  for (const char* ext : {"obj", "ply", "off", "stl", "drc"})
    add(std::string("empty.") + ext, "", "file is empty");
  add("mesh.xyz", cube_obj, "unknown mesh format");
  add("no_extension", cube_obj, "unknown mesh format");
  add("stream.pm", cube_obj, "a progressive-mesh stream, not a mesh");

  // OBJ.
  add("nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", "line 2");
  add("inf.obj", "v 0 0 0\nv 1 0 0\nv 0 inf 0\nf 1 2 3\n", "finite");
  add("index_out_of_range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "out of range");
  add("negative_out_of_range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n", "out of range");
  add("index_zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "index 0");
  add("two_corners.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", "at least 3");
  add("truncated.obj", "v 0 0 0\nv 1 0 0\nv 0 1", "missing vertex coordinate");
  add("garbage.obj", "v 0 0 zero\nf 1 2 3\n", "not a number");
  add("binary.obj", std::string("\x00\x01\x02\x03\xff", 5), "no vertices");
  // Finite but beyond what squares and areas survive: hoppe's setup turned 3e231 into NaN (fuzzing).
  add("huge_coordinate.obj", "v 0 0 0\nv 1e80 0 0\nv 0 1 0\nf 1 2 3\n", "vertex 1 has a coordinate of 1e+80, beyond the range of a float");
  // The first value that rounds to a float's infinity (3.40282347e38, which rounds to its largest, is in).
  add("float_infinity_coordinate.obj", "v 0 0 0\nv 0 3.4028236e38 0\nv 0 0 1\nf 1 2 3\n",
      "vertex 1 has a coordinate of 3.4028236e+38, beyond the range of a float");
  add("bad_uv_index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/2 3/1\n", "texture coordinate index 2");

  // PLY.
  const std::string ply_head =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
  add("truncated_ascii.ply", ply_head + "0 0 0\n1 0 0\n", "truncated");
  add("nan.ply", ply_head + "0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n", "finite");
  add("index_out_of_range.ply", ply_head + "0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", "out of range");
  add("negative_index.ply", ply_head + "0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n", "out of range");
  add("two_indices.ply", ply_head + "0 0 0\n1 0 0\n0 1 0\n2 0 1\n", "at least 3");
  add("too_many_rows.ply", ply_head + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 2\n", "header counts");
  {
    // Indices stored as floats must be whole numbers: casting 6.2e63 to an integer was undefined
    // behaviour, and 0.5 was silently read as 0 (found by fuzzing the reader).
    std::string float_head = ply_head;
    float_head.replace(float_head.find("uchar int"), 9, "uchar float");
    add("huge_float_index.ply", float_head + "0 0 0\n1 0 0\n0 1 0\n3 0 1 6.2e63\n", "bad vertex index");
    add("fractional_index.ply", float_head + "0 0 0\n1 0 0\n0 1 0\n3 0 0.5 2\n", "bad vertex index 0.5");
  }
  // A face count with no indices to read: faces silently vanished, and a count of 748 million with
  // no property to bound it by the file's size was reserved for (out of memory; found by fuzzing).
  add("faces_without_indices.ply",
      "ply\nformat binary_little_endian 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
      "property float z\nelement face 748173922\nend_header\n",
      "the face element has no vertex_indices list");
  add("no_magic.ply", "format ascii 1.0\nend_header\n", "not a PLY file");
  add("no_end_header.ply", "ply\nformat ascii 1.0\nelement vertex 3\n", "end_header");
  add("bad_format.ply", "ply\nformat binary_middle_endian 1.0\nend_header\n", "unknown PLY format");
  add("no_xyz.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float q\nend_header\n1\n", "lacks x");
  {
    // Binary: header claims 1000 vertices, body holds 2.
    std::string bin =
        "ply\nformat binary_little_endian 1.0\nelement vertex 1000\nproperty float x\nproperty float y\n"
        "property float z\nend_header\n";
    const float v[6] = {0, 0, 0, 1, 1, 1};
    bin.append(reinterpret_cast<const char*>(v), sizeof v);
    add("truncated_binary.ply", bin, "file ends in vertex 2 of 1000");
    std::string bad_list =
        "ply\nformat binary_little_endian 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
        "property float z\nelement face 1\nproperty list int int vertex_indices\nend_header\n";
    const std::int32_t count = -5;
    bad_list.append(reinterpret_cast<const char*>(&count), 4);
    add("negative_list_length.ply", bad_list, "bad list length");
    // A list of 999,999,999 indices holding 3: 8 GB were allocated for it before reading.
    std::string long_list =
        "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nelement face 1\nproperty list uint int vertex_indices\nend_header\n";
    const float corners[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    long_list.append(reinterpret_cast<const char*>(corners), sizeof corners);
    const std::uint32_t length = 999'999'999;
    long_list.append(reinterpret_cast<const char*>(&length), 4);
    const std::int32_t three[3] = {0, 1, 2};
    long_list.append(reinterpret_cast<const char*>(three), sizeof three);
    add("long_list.ply", long_list, "file ends in face 0 of 1");
  }

  // OFF.
  add("truncated.off", "OFF\n4 4 0\n0 0 0\n1 0 0\n", "file ends at vertex 2 of 4");
  add("wrong_face_count.off", "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "file ends at face 1 of 2");
  // Counts of billions in a small file: refused before allocating for them (they ran out of memory,
  // and the message named no file).
  add("billions.off", "OFF\n2000000000 1 0\n0 0 0\n", "the header says 2000000000 vertices");
  add("billions.ply",
      "ply\nformat binary_little_endian 1.0\nelement vertex 2147483647\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n",
      "the header says 2147483647 vertex elements");
  // A polygon's corner count is not trusted for an allocation: 272 quadrillion corners asked for
  // 2 exabytes before the first index was read (found by fuzzing).
  add("huge_polygon.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n272000000000000000 0 1 2\n", "missing vertex index");
  add("nan.off", "OFF\n3 1 0\n0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n", "finite");
  add("index_out_of_range.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", "out of range");
  add("two_vertices.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n", "at least 3");
  add("not_off.off", "PLY\n3 1 0\n", "not an OFF file");

  // STL.
  {
    Mesh tet = tetrahedron();
    WriteOptions w;
    const std::string stl = write_mesh_to_memory(tet, MeshFormat::Stl, w);
    add("truncated_binary.stl", stl.substr(0, stl.size() - 7), "truncated");
    std::string nan_stl = stl;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    std::memcpy(nan_stl.data() + 84 + 12, &nan, 4);  // first vertex x of the first triangle
    add("nan_binary.stl", nan_stl, "non-finite");
    add("short.stl", "abc", "too short");
  }
  add("truncated_ascii.stl", "solid x\nfacet normal 0 0 1\n outer loop\n  vertex 0 0 0\n  vertex 1 0 0\n",
      "line");
  add("quad_ascii.stl",
      "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 1 1 0\nvertex 0 1 0\n"
      "endloop\nendfacet\nendsolid x\n",
      "facets must be triangles");

  // Draco.
  {
    const std::string drc = write_mesh_to_memory(make_icosphere({.subdivisions = 2}), MeshFormat::Draco);
    add("truncated.drc", drc.substr(0, drc.size() / 2), "Draco");
    add("not_draco.drc", "this is not a draco file at all", "not a Draco file");
  }
  return corpus;
}

}  // namespace lodkit::test
