#pragma once
// Helpers shared by the tests: scratch directories and tiny hand-built meshes.
#include <lodkit/mesh.h>

#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <cstddef>
#include <filesystem>
#include <string>
#include <utility>

namespace lodkit::test {

/// A fresh empty directory under the system temp dir, removed when the object dies.
class ScratchDir {
 public:
  explicit ScratchDir(const std::string& tag);
  ~ScratchDir();
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }
  /// Number of entries in the directory (to check that nothing was left behind).
  std::size_t entries() const;

 private:
  std::filesystem::path path_;
};

/// f() on `threads` threads: an arena of that many slots, with TBB allowed as many workers, so that
/// four threads are four even on a two-core machine (the default arena has one slot per core). For the
/// tests that a result does not depend on the thread count.
template <typename F>
auto on_threads(int threads, F&& f) {
  const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
  tbb::task_arena arena(threads);
  return arena.execute(std::forward<F>(f));
}

void write_text(const std::filesystem::path& path, const std::string& text);
std::string read_bytes(const std::filesystem::path& path);

/// Regular tetrahedron-like solid, outward oriented (volume 1/6 for the unit corner tetrahedron).
Mesh tetrahedron();
/// One triangle.
Mesh single_triangle();

/// The first way two meshes differ (counts, positions, triangles, each attribute), or "" when they are
/// identical bit for bit: EXPECT_EQ(test::difference(a, b), "").
std::string difference(const Mesh& a, const Mesh& b);

/// A UV sphere of 24 x 12 segments with UVs (a seam at u = 0 / 1) and smooth vertex normals.
Mesh seamed_uv_sphere();

/// An icosphere with deterministic radial noise of +-amplitude (relative): a bumpy closed surface.
Mesh bumpy_sphere(int subdivisions, double amplitude, unsigned seed = 7);
/// The mesh flat-shaded: three vertices of its own per face, each with the face's unit normal.
Mesh flat_shaded(const Mesh& mesh);
/// A lens 1/100 as thick as it is wide (a flattened icosphere, 20,480 faces): a coarse face there lies
/// nearer the far side than its own, where the plain flip checks let some face the wrong way.
Mesh thin_lens();

/// The u = 0 / u = 1 seam of an equirectangular UV sphere (make_uv_sphere with uvs), checked: its
/// vertices with u = 0, and how many of them have no twin, or more than one, at their point with
/// u = 1 and the same v. The seam meets where every one has exactly one.
struct SeamTwins {
  Index seam = 0, without_twin = 0, with_more_twins = 0;
};
SeamTwins u_seam_twins(const Mesh& m);
/// The widest range of u over one face's corners, among faces whose corners all have |v - 0.5| <= band:
/// a face straddling the u = 0 / u = 1 seam spans most of the texture. (Near a UV sphere's poles faces
/// fan over many longitudes, which a band below 0.5 leaves out.)
double widest_u_span(const Mesh& m, double band = 0.5);

}  // namespace lodkit::test
