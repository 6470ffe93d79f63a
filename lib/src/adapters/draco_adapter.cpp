#include "adapters/draco_adapter.h"

#include <lodkit/error.h>

#include <cmath>
#include <fmt/format.h>

#include <draco/attributes/geometry_attribute.h>
#include <draco/attributes/point_attribute.h>

#include "io/formats.h"

namespace lodkit::detail {
namespace {

template <typename T, typename Row>
int add_attribute(draco::Mesh& dm, draco::GeometryAttribute::Type type, draco::DataType data_type,
                  int components, bool normalized, Index n, Row&& row_of) {
  draco::GeometryAttribute ga;
  ga.Init(type, nullptr, static_cast<std::uint8_t>(components), data_type, normalized,
          static_cast<std::int64_t>(sizeof(T) * components), 0);
  const int id = dm.AddAttribute(ga, /*identity_mapping=*/true, static_cast<std::uint32_t>(n));
  draco::PointAttribute* att = dm.attribute(id);
  T value[4];
  for (Index v = 0; v < n; ++v) {
    row_of(v, value);
    att->SetAttributeValue(draco::AttributeValueIndex(static_cast<std::uint32_t>(v)), value);
  }
  return id;
}

// The first problem with the columns of `values` (named by `axes`) as Draco floats; see
// draco_range_problem.
template <typename Matrix>
std::string float_range_problem(const Matrix& values, const char* what, const char* axes, bool quantised) {
  for (Index c = 0; c < values.cols(); ++c) {
    float lo = INFINITY, hi = -INFINITY;
    for (Index v = 0; v < values.rows(); ++v) {
      const float x = static_cast<float>(values(v, c));
      if (!std::isfinite(x))
        return fmt::format("vertex {}'s {} {} ({}) is beyond the 32-bit floats Draco stores", v, axes[c], what,
                           static_cast<double>(values(v, c)));
      lo = std::min(lo, x), hi = std::max(hi, x);
    }
    if (quantised && values.rows() > 0 && !std::isfinite(hi - lo))
      return fmt::format("its {} span {} .. {} in {}, an extent beyond the 32-bit floats Draco quantises with; "
                         "write them with 0 quantisation bits",
                         what, lo, hi, axes[c]);
  }
  return {};
}

}  // namespace

std::string draco_range_problem(const Mesh& mesh, const DracoAttributes& which, const DracoQuantised& quantised) {
  const Attributes& a = mesh.attributes;
  std::string why = float_range_problem(mesh.positions, "positions", "xyz", quantised.positions);
  if (why.empty() && which.normals && mesh.has_normals()) why = float_range_problem(a.normals, "normals", "xyz", quantised.normals);
  if (why.empty() && which.uvs && mesh.has_uvs()) why = float_range_problem(a.uvs, "UVs", "uv", quantised.uvs);
  return why;
}

std::unique_ptr<draco::Mesh> to_draco(const Mesh& mesh, const DracoAttributes& which) {
  auto dm = std::make_unique<draco::Mesh>();
  const Index n = mesh.num_vertices();
  const Attributes& a = mesh.attributes;
  dm->set_num_points(static_cast<std::uint32_t>(n));
  add_attribute<float>(*dm, draco::GeometryAttribute::POSITION, draco::DT_FLOAT32, 3, false, n,
                       [&](Index v, float* out) {
                         for (int k = 0; k < 3; ++k) out[k] = static_cast<float>(mesh.positions(v, k));
                       });
  if (which.normals && mesh.has_normals())
    add_attribute<float>(*dm, draco::GeometryAttribute::NORMAL, draco::DT_FLOAT32, 3, false, n,
                         [&](Index v, float* out) {
                           for (int k = 0; k < 3; ++k) out[k] = static_cast<float>(a.normals(v, k));
                         });
  if (which.uvs && mesh.has_uvs())
    add_attribute<float>(*dm, draco::GeometryAttribute::TEX_COORD, draco::DT_FLOAT32, 2, false, n,
                         [&](Index v, float* out) {
                           for (int k = 0; k < 2; ++k) out[k] = static_cast<float>(a.uvs(v, k));
                         });
  if (which.colours && mesh.has_colours())
    add_attribute<std::uint8_t>(*dm, draco::GeometryAttribute::COLOR, draco::DT_UINT8, 4, true, n,
                                [&](Index v, std::uint8_t* out) {
                                  for (int k = 0; k < 4; ++k) out[k] = to_8bit(a.colours(v, k));
                                });
  dm->SetNumFaces(static_cast<std::size_t>(mesh.num_faces()));
  for (Index f = 0; f < mesh.num_faces(); ++f) {
    draco::Mesh::Face face;
    for (int k = 0; k < 3; ++k) face[k] = draco::PointIndex(static_cast<std::uint32_t>(mesh.triangles(f, k)));
    dm->SetFace(draco::FaceIndex(static_cast<std::uint32_t>(f)), face);
  }
  return dm;
}

Mesh from_draco(const draco::Mesh& dm) {
  Mesh mesh;
  const auto n = static_cast<Index>(dm.num_points());
  const draco::PointAttribute* pos = dm.GetNamedAttribute(draco::GeometryAttribute::POSITION);
  if (!pos) throw Error("Draco mesh has no POSITION attribute");
  auto read = [&](const draco::PointAttribute* att, auto& matrix, int components) {
    using Scalar = typename std::remove_reference_t<decltype(matrix)>::Scalar;
    matrix.resize(n, components);
    double value[4] = {0, 0, 0, 1};
    std::uint8_t bytes[4] = {0, 0, 0, 255};
    const bool as_bytes = att->data_type() == draco::DT_UINT8;
    for (Index v = 0; v < n; ++v) {
      const auto avi = att->mapped_index(draco::PointIndex(static_cast<std::uint32_t>(v)));
      if (as_bytes) {
        att->ConvertValue<std::uint8_t>(avi, static_cast<std::int8_t>(std::min<int>(att->num_components(), components)), bytes);
        for (int k = 0; k < components; ++k) matrix(v, k) = static_cast<Scalar>(from_8bit(bytes[k]));
      } else {
        att->ConvertValue<double>(avi, static_cast<std::int8_t>(std::min<int>(att->num_components(), components)), value);
        for (int k = 0; k < components; ++k) matrix(v, k) = static_cast<Scalar>(value[k]);
      }
    }
  };
  read(pos, mesh.positions, 3);
  if (const auto* att = dm.GetNamedAttribute(draco::GeometryAttribute::NORMAL))
    read(att, mesh.attributes.normals, 3);
  if (const auto* att = dm.GetNamedAttribute(draco::GeometryAttribute::TEX_COORD))
    read(att, mesh.attributes.uvs, 2);
  if (const auto* att = dm.GetNamedAttribute(draco::GeometryAttribute::COLOR)) {
    read(att, mesh.attributes.colours, 4);
    if (att->num_components() == 3) mesh.attributes.colours.col(3).setOnes();
  }
  const auto nf = static_cast<Index>(dm.num_faces());
  mesh.triangles.resize(nf, 3);
  for (Index f = 0; f < nf; ++f) {
    const auto& face = dm.face(draco::FaceIndex(static_cast<std::uint32_t>(f)));
    for (int k = 0; k < 3; ++k) mesh.triangles(f, k) = static_cast<Index>(face[k].value());
  }
  return mesh;
}

}  // namespace lodkit::detail
