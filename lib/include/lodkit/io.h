#pragma once
// Mesh files, chosen by extension: OBJ, PLY (ASCII, binary little/big endian), OFF, STL (ASCII,
// binary) and Draco (.drc).
//
// Reading never trusts the file: a missing, empty or truncated file, wrong header counts, NaN/inf
// coordinates, out-of-range indices or faces with fewer than 3 vertices raise lodkit::Error with a
// message of the form "<file>: <what is wrong>". Writing goes to a temporary file beside the target
// that is renamed over it only on success, so a failed write leaves nothing behind.
#include <lodkit/mesh.h>

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace lodkit {

enum class MeshFormat { Obj, Ply, Off, Stl, Draco };

/// "obj", "ply", "off", "stl", "drc".
std::string_view format_name(MeshFormat format);
/// The format of a name such as "ply" or ".PLY"; nullopt if unknown.
std::optional<MeshFormat> parse_format(std::string_view name);
/// The format implied by a path's extension; nullopt if unknown.
std::optional<MeshFormat> format_of(const std::filesystem::path& path);

struct ReadOptions {
  /// Read as this format whatever the extension says.
  std::optional<MeshFormat> format;
  /// Merge vertices with identical positions and attributes after reading. STL is always welded by
  /// position (it stores each triangle's corners separately).
  bool weld = false;
  /// When set, receives the corner count of every polygon in file order; polygon k became
  /// count - 2 consecutive fan triangles (corner 0 with each pair of neighbours). STL and Draco
  /// report 3 for every face. Subdivision uses it to recover quads.
  std::vector<int>* polygon_sizes = nullptr;
};

/// Reads a mesh; the format comes from `options.format` or else the extension.
/// \throw Error "<path>: <problem>" for any unreadable, malformed or unknown-format file.
Mesh read_mesh(const std::filesystem::path& path, const ReadOptions& options = {});

/// Reads a mesh from bytes already in memory (stdin, a network buffer). `name` is used in messages.
Mesh read_mesh_from_memory(std::string_view bytes, MeshFormat format, const std::string& name,
                           const ReadOptions& options = {});

enum class PlyEncoding { BinaryLittleEndian, BinaryBigEndian, Ascii };

struct DracoOptions {
  /// Quantisation bits per attribute; 0 stores full float32 values (lossless up to float).
  int position_bits = 14;
  int normal_bits = 10;
  int uv_bits = 12;
  /// Colours are stored as normalised 8-bit RGBA (exact for 8-bit colours).
  /// Draco's speed/ratio trade-off, 0 (fastest) to 10 (smallest).
  int compression_level = 7;
};

struct WriteOptions {
  /// Write in this format whatever the extension says.
  std::optional<MeshFormat> format;
  PlyEncoding ply_encoding = PlyEncoding::BinaryLittleEndian;
  bool stl_binary = true;
  DracoOptions draco;
  /// Write the attributes the mesh has (where the format can carry them).
  bool normals = true;
  bool uvs = true;
  bool colours = true;
};

/// Writes a mesh; the format comes from `options.format` or else the extension. Atomic: temporary file, then rename.
/// Positions are written so that reading them back gives the same doubles (shortest round-trip
/// text in OBJ/OFF/ASCII PLY; float in binary PLY when every coordinate is exactly a float, else
/// double). STL and Draco store float32.
/// \throw Error "<path>: <problem>".
void write_mesh(const Mesh& mesh, const std::filesystem::path& path, const WriteOptions& options = {});

/// The bytes `write_mesh` would write, for stdout or a network buffer.
std::string write_mesh_to_memory(const Mesh& mesh, MeshFormat format, const WriteOptions& options = {});

/// Removes the temporary files of the writes in progress (every file lodkit writes, meshes, `.pm`
/// streams and terrains, goes to a hidden temporary file beside its target and is renamed into place
/// when complete). Async-signal-safe: for a program's SIGINT or SIGTERM handler, so that an
/// interrupted run leaves nothing behind; the library installs no handler itself (the CLI does).
void remove_unfinished_outputs() noexcept;

}  // namespace lodkit
