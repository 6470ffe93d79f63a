#include <lodkit/error.h>
#include <lodkit/io.h>

#include <algorithm>
#include <cctype>
#include <fmt/format.h>

#include "io/file_buffer.h"
#include "io/formats.h"

namespace lodkit {

std::string_view format_name(MeshFormat format) {
  switch (format) {
    case MeshFormat::Obj: return "obj";
    case MeshFormat::Ply: return "ply";
    case MeshFormat::Off: return "off";
    case MeshFormat::Stl: return "stl";
    case MeshFormat::Draco: return "drc";
  }
  return "?";
}

std::optional<MeshFormat> parse_format(std::string_view name) {
  std::string s(name);
  if (!s.empty() && s[0] == '.') s.erase(0, 1);
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  if (s == "obj") return MeshFormat::Obj;
  if (s == "ply") return MeshFormat::Ply;
  if (s == "off") return MeshFormat::Off;
  if (s == "stl") return MeshFormat::Stl;
  if (s == "drc" || s == "draco") return MeshFormat::Draco;
  return std::nullopt;
}

std::optional<MeshFormat> format_of(const std::filesystem::path& path) {
  return parse_format(path.extension().string());
}

namespace {

MeshFormat require_format(const std::filesystem::path& path, std::optional<MeshFormat> given) {
  if (given) return *given;
  if (auto f = format_of(path)) return *f;
  const std::string ext = path.extension().string();
  if (ext == ".pm")
    throw Error(fmt::format("{}: a progressive-mesh stream, not a mesh: extract a level from it (lodkit pm extract, "
                            "read_pm() and extract_level())", path.string()));
  throw Error(fmt::format("{}: unknown mesh format '{}' (expected .obj, .ply, .off, .stl or .drc)",
                          path.string(), ext.empty() ? "(no extension)" : ext));
}

}  // namespace

Mesh read_mesh_from_memory(std::string_view bytes, MeshFormat format, const std::string& name,
                           const ReadOptions& options) {
  if (bytes.empty()) throw Error(fmt::format("{}: file is empty", name));
  if (options.polygon_sizes) options.polygon_sizes->clear();
  Mesh mesh;
  switch (format) {
    case MeshFormat::Obj: mesh = detail::read_obj(bytes, name, options.polygon_sizes); break;
    case MeshFormat::Ply: mesh = detail::read_ply(bytes, name, options.polygon_sizes); break;
    case MeshFormat::Off: mesh = detail::read_off(bytes, name, options.polygon_sizes); break;
    case MeshFormat::Stl: mesh = detail::read_stl(bytes, name); break;
    case MeshFormat::Draco: mesh = detail::read_drc(bytes, name); break;
  }
  validate(mesh, name);
  if (options.polygon_sizes && (format == MeshFormat::Stl || format == MeshFormat::Draco))
    options.polygon_sizes->assign(static_cast<std::size_t>(mesh.num_faces()), 3);
  if (options.weld) weld_identical_vertices(mesh);
  return mesh;
}

Mesh read_mesh(const std::filesystem::path& path, const ReadOptions& options) {
  // The file first: a missing file or a directory says so, whatever its name's extension.
  const detail::FileBuffer file(path);
  const MeshFormat format = require_format(path, options.format);
  return read_mesh_from_memory(file.bytes(), format, path.string(), options);
}

namespace {

void write_format(const Mesh& mesh, MeshFormat format, detail::Output& out,
                  const WriteOptions& options) {
  switch (format) {
    case MeshFormat::Obj: detail::write_obj(mesh, out, options); break;
    case MeshFormat::Ply: detail::write_ply(mesh, out, options); break;
    case MeshFormat::Off: detail::write_off(mesh, out, options); break;
    case MeshFormat::Stl: detail::write_stl(mesh, out, options); break;
    case MeshFormat::Draco: detail::write_drc(mesh, out, options); break;
  }
}

}  // namespace

void write_mesh(const Mesh& mesh, const std::filesystem::path& path, const WriteOptions& options) {
  detail::refuse_directory(path);
  const MeshFormat format = require_format(path, options.format);
  validate(mesh, path.string());
  detail::write_file_atomically(path, [&](detail::Output& out) {
    try {
      write_format(mesh, format, out, options);
    } catch (const Error& e) {
      throw Error(fmt::format("{}: {}", path.string(), e.what()));
    }
  });
}

std::string write_mesh_to_memory(const Mesh& mesh, MeshFormat format, const WriteOptions& options) {
  validate(mesh, "mesh");
  detail::Output out;
  write_format(mesh, format, out, options);
  return std::move(out.str());
}

namespace detail {

bool colours_are_8bit(const Colours& colours) {
  for (Eigen::Index i = 0; i < colours.size(); ++i) {
    const float c = colours.data()[i];
    if (!(c >= 0.0f && c <= 1.0f) || from_8bit(to_8bit(c)) != c) return false;
  }
  return true;
}

}  // namespace detail
}  // namespace lodkit
