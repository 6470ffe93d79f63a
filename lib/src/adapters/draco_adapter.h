#pragma once
// lodkit::Mesh <-> draco::Mesh. The only place Draco types meet lodkit's.
#include <lodkit/mesh.h>

#include <draco/mesh/mesh.h>
#include <memory>
#include <string>

namespace lodkit::detail {

struct DracoAttributes {
  bool normals = true, uvs = true, colours = true;
};

/// Which float attributes an encoder quantises (colours are 8-bit already).
struct DracoQuantised {
  bool positions = true, normals = true, uvs = true;
};

/// Why Draco cannot store `mesh`'s attributes (those in `which`), or empty when it can. Draco keeps
/// 32-bit floats, and quantising an attribute takes the extent of its values in float: a larger
/// extent overflows to infinity and crashes its encoder.
std::string draco_range_problem(const Mesh& mesh, const DracoAttributes& which, const DracoQuantised& quantised);

/// One Draco point per lodkit vertex (identity mapping); colours become normalised uint8 RGBA.
std::unique_ptr<draco::Mesh> to_draco(const Mesh& mesh, const DracoAttributes& which = {});

/// Points become vertices; POSITION, NORMAL, TEX_COORD and COLOR attributes are kept.
Mesh from_draco(const draco::Mesh& mesh);

}  // namespace lodkit::detail
