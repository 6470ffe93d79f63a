#pragma once
// lodkit::Mesh <-> draco::Mesh. The only place Draco types meet lodkit's.
#include <lodkit/mesh.h>

#include <draco/mesh/mesh.h>
#include <memory>

namespace lodkit::detail {

struct DracoAttributes {
  bool normals = true, uvs = true, colours = true;
};

/// One Draco point per lodkit vertex (identity mapping); colours become normalised uint8 RGBA.
std::unique_ptr<draco::Mesh> to_draco(const Mesh& mesh, const DracoAttributes& which = {});

/// Points become vertices; POSITION, NORMAL, TEX_COORD and COLOR attributes are kept.
Mesh from_draco(const draco::Mesh& mesh);

}  // namespace lodkit::detail
