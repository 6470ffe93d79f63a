// Draco (.drc) through the Draco library: edgebreaker connectivity coding with per-attribute
// quantisation (DracoOptions). Draco stores float32 values and may renumber vertices.
#include <draco/compression/decode.h>
#include <draco/compression/encode.h>

#include "adapters/draco_adapter.h"
#include "io/formats.h"

namespace lodkit::detail {

Mesh read_drc(std::string_view bytes, const std::string& name) {
  draco::DecoderBuffer buffer;
  buffer.Init(bytes.data(), bytes.size());
  const auto type = draco::Decoder::GetEncodedGeometryType(&buffer);
  if (!type.ok())
    throw Error(fmt::format("{}: not a Draco file ({})", name, type.status().error_msg_string()));
  if (type.value() != draco::TRIANGULAR_MESH)
    throw Error(fmt::format("{}: Draco file holds a point cloud, not a triangle mesh", name));
  draco::Decoder decoder;
  auto decoded = decoder.DecodeMeshFromBuffer(&buffer);
  if (!decoded.ok())
    throw Error(fmt::format("{}: Draco decoding failed: {} (truncated or corrupt?)", name,
                            decoded.status().error_msg_string()));
  try {
    return from_draco(*decoded.value());
  } catch (const Error& e) {
    throw Error(fmt::format("{}: {}", name, e.what()));
  }
}

void write_drc(const Mesh& mesh, Output& out, const WriteOptions& options) {
  const DracoOptions& d = options.draco;
  auto check_bits = [](int bits, const char* what) {
    if (bits < 0 || bits > 30)
      throw Error(fmt::format("Draco {} quantisation must be 0 (off) to 30 bits, not {}", what, bits));
  };
  check_bits(d.position_bits, "position");
  check_bits(d.normal_bits, "normal");
  check_bits(d.uv_bits, "UV");
  if (d.compression_level < 0 || d.compression_level > 10)
    throw Error(fmt::format("Draco compression level must be 0 to 10, not {}", d.compression_level));
  if (mesh.num_faces() == 0) throw Error("Draco cannot store a mesh without faces");

  const DracoAttributes which{options.normals, options.uvs, options.colours};
  if (const std::string why = draco_range_problem(mesh, which, {d.position_bits > 0, d.normal_bits > 0, d.uv_bits > 0});
      !why.empty())
    throw Error("Draco cannot store this mesh: " + why);
  const auto dm = to_draco(mesh, which);
  draco::Encoder encoder;
  const int speed = 10 - d.compression_level;
  encoder.SetSpeedOptions(speed, speed);
  if (d.position_bits > 0) encoder.SetAttributeQuantization(draco::GeometryAttribute::POSITION, d.position_bits);
  if (d.normal_bits > 0) encoder.SetAttributeQuantization(draco::GeometryAttribute::NORMAL, d.normal_bits);
  if (d.uv_bits > 0) encoder.SetAttributeQuantization(draco::GeometryAttribute::TEX_COORD, d.uv_bits);
  draco::EncoderBuffer buffer;
  const draco::Status status = encoder.EncodeMeshToBuffer(*dm, &buffer);
  if (!status.ok()) throw Error(fmt::format("Draco encoding failed: {}", status.error_msg_string()));
  out.put_bytes(buffer.data(), buffer.size());
}

}  // namespace lodkit::detail
