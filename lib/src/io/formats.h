#pragma once
// One reader and one writer per file format. Readers get the whole file and its name (for
// messages) and return a validated mesh; writers append to an Output.
#include <lodkit/error.h>
#include <lodkit/io.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <string_view>
#include <vector>

#include "io/output.h"

namespace lodkit::detail {

Mesh read_obj(std::string_view bytes, const std::string& name, std::vector<int>* polygon_sizes = nullptr);
Mesh read_ply(std::string_view bytes, const std::string& name, std::vector<int>* polygon_sizes = nullptr);
Mesh read_off(std::string_view bytes, const std::string& name, std::vector<int>* polygon_sizes = nullptr);
Mesh read_stl(std::string_view bytes, const std::string& name);
Mesh read_drc(std::string_view bytes, const std::string& name);

void write_obj(const Mesh& mesh, Output& out, const WriteOptions& options);
void write_ply(const Mesh& mesh, Output& out, const WriteOptions& options);
void write_off(const Mesh& mesh, Output& out, const WriteOptions& options);
void write_stl(const Mesh& mesh, Output& out, const WriteOptions& options);
void write_drc(const Mesh& mesh, Output& out, const WriteOptions& options);

/// Appends the triangles of a convex polygon (fan from its first corner).
template <typename Corners, typename Emit>
void triangulate_fan(const Corners& corners, std::size_t count, Emit&& emit) {
  for (std::size_t k = 1; k + 1 < count; ++k) emit(corners[0], corners[k], corners[k + 1]);
}

/// True when every value of the matrix is exactly representable as a float (so a float field in
/// the file reads back to the same double).
template <typename Matrix>
bool exactly_float(const Matrix& m) {
  for (Eigen::Index i = 0; i < m.size(); ++i) {
    const double v = m.data()[i];
    if (static_cast<double>(static_cast<float>(v)) != v) return false;
  }
  return true;
}

/// True when every colour channel is k / 255 for an integer k (so 8-bit storage is exact).
bool colours_are_8bit(const Colours& colours);
inline unsigned char to_8bit(float c) {
  return static_cast<unsigned char>(std::lround(std::clamp(c, 0.0f, 1.0f) * 255.0f));
}
inline float from_8bit(unsigned v) { return static_cast<float>(v) / 255.0f; }

}  // namespace lodkit::detail
