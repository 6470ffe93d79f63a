#pragma once
// compare(): how far two surfaces are from each other, measured by dense deterministic sampling.
//
// Each direction samples the first surface at its vertices, along its edges and inside its faces
// (a stratified R2 low-discrepancy pattern, allotted by area) and finds each sample's closest point
// on the other surface with an AABB tree. Mean and RMS are area-weighted over the face samples. The
// largest distance is certified by branch and bound: the samples give a lower bound; over each
// triangle the distance is at most its corners' farthest from any one face of the other surface (the
// distance to a triangle is convex), or, where the other surface's faces cover it seen from its plane,
// their largest height over it; triangles whose bound exceeds the lower bound are split until it does
// not, by `hausdorff_tolerance`. The reported maximum is attained at a point (`max_at`); `max_bound`
// proves none lies farther (src/metrics/max_distance_bound.cpp).
// Parallel with TBB; every sample's result is stored by index and reduced in order, so the answer is
// identical for any thread count.
#include <lodkit/mesh.h>

#include <memory>
#include <optional>

namespace lodkit {

/// compare()'s default face samples for a mesh of `faces` faces: 10 per face, at least 10,000 and at
/// most 150 M (beyond 15 M faces, fewer than 10 a face: memory).
long long default_face_samples(Index faces);

struct CompareOptions {
  /// Face samples per direction; default default_face_samples() of the larger mesh. At most 150 M
  /// (about 100 bytes each while measured).
  std::optional<long long> samples{};
  /// Certify the maximum to this fraction: max_bound <= max * (1 + hausdorff_tolerance).
  double hausdorff_tolerance = 1e-3;
  /// At most this many triangle splits per direction; max_bound then says how far it got.
  long long max_splits = 1'000'000;
};

struct DirectedDistance {
  double max = 0.0;        ///< one-sided Hausdorff distance: attained at a point of the first surface
  double max_bound = 0.0;  ///< certified: no point of the first surface is farther from the second
  Eigen::Vector3d max_at = Eigen::Vector3d::Zero();       ///< where `max` is attained, on the first surface
  Eigen::Vector3d max_nearest = Eigen::Vector3d::Zero();  ///< the point of the second surface nearest it
  long long max_queries = 0;  ///< closest-point queries the certificate took, beyond the samples
  double mean = 0.0;  ///< area-weighted mean distance
  double rms = 0.0;   ///< area-weighted root mean square distance
  double normal_deviation_mean_deg = 0.0;  ///< angle between the two surfaces' face normals
  double normal_deviation_max_deg = 0.0;
  /// When both meshes have vertex colours: the colour each surface interpolates at a sample and at its
  /// closest point, compared (Euclidean over red, green, blue and alpha; 0..1 per channel), area-weighted
  /// over the face samples like `rms`, and the largest over all samples.
  std::optional<double> colour_rms{}, colour_max{};
  /// When both meshes have vertex normals: the angle between the shading normals each surface
  /// interpolates at a sample and at its closest point (degrees; 90 where an interpolated normal
  /// vanishes), area-weighted over the face samples like `rms`, and the largest over all samples.
  std::optional<double> shading_rms_deg{}, shading_max_deg{};
  /// When both meshes have UVs: the distance between the texture coordinates each surface interpolates
  /// at a sample and at its closest point (UV units), area-weighted like `rms`, and the largest. Compared
  /// within a chart only (faces joined where their UVs are continuous): across a UV seam the atlas jumps,
  /// so a sample whose closest point lies in a chart other than its own's counterpart (the chart most of
  /// its chart's area lands on, or that lands most on it) is left out; `uv_compared` is the fraction of
  /// the area compared.
  std::optional<double> uv_rms{}, uv_max{};
  double uv_compared = 0.0;
  long long samples = 0;
};

struct Comparison {
  DirectedDistance a_to_b;  ///< samples on A, distances to B
  DirectedDistance b_to_a;
  double hausdorff = 0.0;   ///< max of the two one-sided distances
  double hausdorff_bound = 0.0;  ///< max of the two certified bounds: the true value is in [hausdorff, this]
  double mean = 0.0;        ///< average of the two means
  double rms = 0.0;         ///< sqrt of the average of the two mean squares
  double diagonal = 0.0;    ///< bounding-box diagonal of A: the reference for percentages
  /// Both directions' colour_rms combined as `rms` is (when both meshes have vertex colours).
  std::optional<double> colour_rms{};
  /// Both directions' shading_rms_deg combined as `rms` is (when both meshes have vertex normals).
  std::optional<double> shading_rms_deg{};
  /// Both directions' uv_rms combined as `rms` is (when both meshes have UVs).
  std::optional<double> uv_rms{};
  /// The direction whose maximum is the Hausdorff distance (A -> B on a tie): its max_at is where to look.
  const DirectedDistance& farther() const { return a_to_b.max >= b_to_a.max ? a_to_b : b_to_a; }
  double percent(double value) const { return diagonal > 0 ? 100.0 * value / diagonal : 0.0; }
};

/// \throw Error if either mesh has no faces.
Comparison compare(const Mesh& a, const Mesh& b, const CompareOptions& options = {});

/// One mesh compared with many (the levels of a progressive mesh, a sweep of simplifications): its
/// samples and its tree are made once. `compare(other)` gives, bit for bit, what
/// compare(reference, other, options) gives with options.samples = face_samples; `other` can also be
/// sampled more sparsely (a coarse mesh needs fewer samples than its dense reference). Keeps a
/// reference to `reference`, which must outlive it.
class CompareReference {
 public:
  /// \throw Error if `reference` has no faces or face_samples is not positive.
  CompareReference(const Mesh& reference, long long face_samples, const CompareOptions& options = {});
  ~CompareReference();
  CompareReference(const CompareReference&) = delete;
  CompareReference& operator=(const CompareReference&) = delete;
  /// `other_face_samples`: face samples on `other` (default: face_samples).
  /// \throw Error if `other` has no faces or other_face_samples is not positive.
  Comparison compare(const Mesh& other, std::optional<long long> other_face_samples = {}) const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

/// What HausdorffChecker::check() decided.
struct HausdorffCheck {
  /// Proved: every point of each surface lies within the distance asked of the other.
  bool within = false;
  /// The largest distance found at an actual point: above the distance asked when not within (unless
  /// the search ran out of splits, undecided, which counts as not within).
  double attained = 0.0;
  Eigen::Vector3d attained_at = Eigen::Vector3d::Zero();  ///< that point, on either surface
  /// When within: no point of either surface is farther than this from the other (at most the distance asked).
  double bound = 0.0;
  long long queries = 0;  ///< closest-point queries made
};

/// Whether the Hausdorff distance between `reference` and other meshes is at most a given distance,
/// decided by compare()'s branch and bound without its sampling: each surface's vertices are measured,
/// then its triangles are split only until every piece is proved within the distance, and the search
/// stops at the first point found farther. So it answers in a fraction of compare()'s time, and the
/// answer "within" is a proof. The reference's tree is built once. Keeps a reference to `reference`,
/// which must outlive it.
class HausdorffChecker {
 public:
  /// `max_splits` per direction: where the search runs out, the answer is "not within" (undecided).
  /// \throw Error if `reference` has no faces.
  explicit HausdorffChecker(const Mesh& reference, long long max_splits = 1'000'000);
  ~HausdorffChecker();
  HausdorffChecker(const HausdorffChecker&) = delete;
  HausdorffChecker& operator=(const HausdorffChecker&) = delete;
  /// \throw Error if `other` has no faces or `distance` is negative or not finite.
  HausdorffCheck check(const Mesh& other, double distance) const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

/// Faces of `mesh` whose normal points against the normal of the face of `reference` nearest to
/// their centroid: the "flipped faces" of simplification benchmarks. Where several faces are nearest
/// (two coinciding, facing opposite ways, or two meeting at the edge nearest the centroid), a face
/// counts only if it faces against all of them.
Index count_flipped_faces(const Mesh& reference, const Mesh& mesh);

}  // namespace lodkit
