#pragma once
// simplify(): edge-collapse simplification with a choice of cost.
//
// One engine (lib/src/simplify/collapse_engine.h) keeps a priority queue of candidate collapses u -> v
// over vertices welded by position. Each candidate is checked once when scored and again when it is
// taken: the link condition (the result stays a 2-manifold with the same genus, components and
// boundary loops), no face normal turning by more than `max_normal_change_deg`, no new sliver below
// `min_triangle_quality`, boundary vertices move only along the boundary, and attribute seams
// (vertices split by differing normals/UVs/colours) collapse only along the seam, so no seam is ever
// torn or merged. Vertices on non-manifold edges or fans are locked, not rejected, so dirty meshes
// still simplify. After a collapse only the edges around the kept vertex are re-scored.
//
// Costs:
//   Quadric     Garland & Heckbert, "Surface simplification using quadric error metrics" (1997):
//               area-weighted plane quadrics plus boundary constraint planes; optimal placement by a
//               3x3 solve (regularised towards the midpoint where Q is near-singular), with the
//               endpoints and the midpoint as fallbacks.
//   Hoppe       Hoppe, "Progressive meshes" (1996): E = E_dist + E_spring over points sampled on the
//               original surface, each collapse scored by locally optimising the new position.
//   EdgeLength  the naive |v1 - v2| / |n1 . n2| priority with endpoint/midpoint placement; with
//               topology checks off it breaks models apart, as the literature warns.
//
// Every collapse can be recorded so that it can be undone exactly (progressive meshes).
#include <lodkit/mesh.h>

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace lodkit {

enum class SimplifyMethod { Quadric, Hoppe, EdgeLength };

/// What a run does about faces that would face against the input face nearest their centroid (what
/// count_flipped_faces() counts, and benchmarks call flipped). The flip checks hold a face to its own
/// input shape only; a coarse face can still come to lie nearer another part of the input (the far
/// side of a thin part, a crossing component) and face against it.
enum class InvertedFaces {
  Allow,   ///< no check beyond the flip checks
  Avoid,   ///< such a collapse waits in the queue until the others cost four times as much, then is let be
  Refuse,  ///< refuse every such collapse, and stop short of the target if need be
};

/// Weights of attribute errors against geometric error (quadric method). An attribute difference of
/// 1 (a UV unit, a colour channel's range, a unit normal's component) weighs like `weight` times the
/// bounding-box diagonal. 0 leaves that attribute out of the cost (seams are kept either way).
struct AttributeWeights {
  double normals = 0.0;
  double uvs = 0.0;
  double colours = 0.0;
};
enum class Placement { Optimal, Endpoint, Midpoint };

/// Why simplification stopped.
enum class StopReason {
  TargetReached,    ///< the face target (from target_faces or target_ratio)
  ErrorLimit,       ///< every remaining collapse would exceed max_error
  NoLegalCollapse,  ///< every remaining collapse is illegal (locked vertices, topology, flips)
  HausdorffLimit,   ///< simplify_within(): the next coarser level lies farther from the input than the limit
};

/// How refit_to_input() moves a simplification's vertices to fit its input (see there).
struct RefitOptions {
  /// Passes of the first stage, towards the largest distances; each measures every sample once. 0 = none.
  int passes = 10;
  /// Samples weigh (d / d_max)^exponent: high values fit the largest distances (the Hausdorff
  /// distance), 0 the sum of their squares (RMS).
  double exponent = 6.0;
  /// The first step, as a fraction of each vertex's least-squares move (itself no longer than the
  /// distance of the vertex's farthest sample). It grows by 1.25 after a pass that lowered the largest
  /// sampled distance (to at most 1); after one that did not, the vertices go back and it halves.
  double step = 0.3;
  double max_step_turn_deg = 30.0;     ///< how far a face may turn in one step
  /// How far a face may turn from its input face's orientation (given face origins), else from its own
  /// before the refit.
  double max_total_turn_deg = 60.0;
  double min_triangle_quality = 0.02;  ///< as in SimplifyOptions; a face already below it may not get worse
  /// No face may come to face against the input face nearest its centroid; those that do already move
  /// towards the nearest input face that faces their way, between the stages.
  bool avoid_inverted = true;
  bool fix_boundary = false;           ///< boundary vertices stay put (vertices on non-manifold edges always do)
  /// Passes of the second stage, towards the least sum of squared distances (the RMS) with unit
  /// weights, in which no sample may get farther than the larger of its own distance and rms_guard times
  /// the largest sampled distance: the first stage's largest distances stay. 0 = none.
  int rms_passes = 8;
  double rms_guard = 0.9;  ///< in [0, 1]; 1 lets samples up to the largest distance (RMS lower, Hausdorff up a little)
  /// After the refit's first measure, a sample nearer than this fraction of the largest sampled distance
  /// whose nearest point on the face it was last measured against lies inside that face keeps that face
  /// without a search (the distance is then an upper bound; the largest stays exact). 0: every sample
  /// is searched every pass. 0.5 takes 0.6 times as long as 0 over the shared meshes, with the same
  /// errors within 0.3 % (docs/benchmarks-log.md, "Session 40").
  double keep_face_below = 0.5;
};

/// What fit_attributes_to_input() fits.
struct AttributeFitOptions {
  bool normals = true;
  bool colours = true;
  /// UVs within their charts: a point counts only where its closest point on the other mesh lies in
  /// the same piece of the atlas (as compare()'s uv_rms measures them).
  bool uvs = true;
  /// Points sampled on each face of the simplified mesh, on average (larger faces get more); the input
  /// gives one per face besides.
  double samples_per_face = 4.0;
};

/// What fit_attributes_to_input() did.
struct AttributeFitReport {
  bool normals = false, colours = false, uvs = false;  ///< what was fitted (present in both meshes, and asked for)
  long long samples = 0;                  ///< pairs of points, both ways
  double seconds = 0.0;
};

/// What refit_to_input() did.
struct RefitReport {
  /// The largest distance of a sample of either surface from the other, before and after. A sampled
  /// value (lodkit::compare certifies the Hausdorff distance); the refit only keeps steps that lower it.
  double sampled_max_before = 0.0, sampled_max_after = 0.0;
  /// The root mean square of the samples' distances, before and after (a sampled value, as above).
  double sampled_rms_before = 0.0, sampled_rms_after = 0.0;
  int passes = 0;             ///< sampling passes made, in both stages
  int steps = 0;              ///< steps that lowered the sampled maximum (first stage)
  int rms_steps = 0;          ///< steps that lowered the sum of squared distances within the guard (second stage)
  /// Faces facing against the input face nearest their centroid, before and after the rounds between
  /// the stages that move them towards the input's faces that face their way (avoid_inverted only).
  Index inverted_before = 0, inverted_after = 0;
  int turn_steps = 0;         ///< those rounds kept
  Index moved_vertices = 0;   ///< welded points moved
  double seconds = 0.0;
};

struct SimplifyOptions {
  SimplifyMethod method = SimplifyMethod::Quadric;
  Placement placement = Placement::Optimal;
  /// Stop at this many faces (or the nearest count below it that the mesh allows).
  std::optional<Index> target_faces{};
  /// Stop at this fraction of the input's faces (0..1).
  std::optional<double> target_ratio{};
  /// Never perform a collapse whose error estimate (a distance, see SimplifyResult::error) exceeds this.
  std::optional<double> max_error{};

  bool preserve_topology = true;   ///< link condition and flip checks (off only to show failure)
  bool lock_boundary = false;      ///< boundary vertices never move or disappear
  /// First turn the faces of an inconsistently oriented input to agree (orient_consistently(), on a
  /// copy): the ends of an edge whose two faces run it the same way are locked, so such an input barely
  /// simplifies (a blob with its faces turned at random: 4,050 -> 3,900 faces at any target). The
  /// output's faces then agree with one another; refit and face checks measure against the turned copy.
  bool orient_faces = true;
  double boundary_weight = 10.0;   ///< weight of boundary constraint planes (quadric); higher keeps borders
  /// Weight of crease planes (quadric method only): planes through folded edges that keep thin fins, spikes and
  /// sharp ridges from sliding inwards; a fully folded edge weighs like a border edge at 10. 0 = off.
  double crease_weight = 5.0;
  double max_normal_change_deg = 60.0;  ///< how far a face may turn in one collapse
  /// How far a face may turn from its input orientation over all collapses, so that small turns never
  /// add up to a flip; never below max_normal_change_deg. Unset: by method
  /// (default_max_total_normal_change()), and raised to 90 degrees where that limit alone would stop the
  /// run short of its target (SimplifyResult::turn_limit_relaxed_at).
  std::optional<double> max_total_normal_change_deg{};
  double min_triangle_quality = 0.02;   ///< 4 sqrt(3) area / sum of squared edges, for new triangles
  /// Faces facing against the input face nearest their centroid: checked with a closest-face query per
  /// face a collapse changes, skipped where a certificate shows the answer (AabbTree::facing_against()).
  /// Unset: by method (default_inverted_faces()). With preserve_topology only; schroeder does not use it.
  /// The refit after the collapses avoids such faces unless this is Allow (unset counts as Avoid there).
  std::optional<InvertedFaces> inverted_faces{};
  /// Attribute-aware quadrics (Garland & Heckbert 1998) for the attributes given a weight; the merged
  /// wedges then also take the attribute values that minimise the error.
  AttributeWeights attribute_weights{};
  /// Ignore the input's normals and give the output area-weighted vertex normals instead. Vertices that
  /// differ only by their normals then count as one, so a flat-shaded mesh (a normal per face corner,
  /// which makes every edge an attribute seam and stops every collapse) simplifies like a welded one.
  /// A normal weight in attribute_weights then has nothing to weigh. Not with record_collapses (the
  /// records would name vertices of a mesh without normals).
  bool recompute_normals = false;

  /// Hoppe: random points sampled per input face on average (besides the vertices); and the seed. Four
  /// start every neighbourhood past the paper's strongest springs (under 4 points per face), which on
  /// smooth meshes outweigh the distances, grow the stars and slow the run (fertility at 10 %: 18.8 s
  /// with 1, 2.0 s with 4; docs/benchmarks-log.md, "Session 21").
  double hoppe_points_per_face = 4.0;
  /// Hoppe: of those, how many go on every face, however small (E_dist must see each face of a fine
  /// feature); the rest are spread over the surface by area, so that E_dist stands for the integral of
  /// the squared distance over the input, which RMS measures. Points all per face (1000, as before
  /// session 27) weight the energy by tessellation density, and on CAD parts the large faces hardly
  /// count (46 shared runs: RMS x0.94 with 2, Hausdorff x1.00; docs/benchmarks-log.md, "Session 27").
  double hoppe_points_on_every_face = 2.0;
  /// Hoppe: the fewest sample points in all (vertices plus random points); smaller meshes get more random
  /// points per face to reach it. With few points per face the paper's spring schedule keeps the springs
  /// strong, and on CAD meshes of long thin triangles they pull vertices off creases (fandisk's RMS at
  /// 10 %: 0.0158 % with 1 point per face, 0.0028 % with this floor; docs/benchmarks-log.md, "Session 13").
  /// Meshes of about 67k faces and more (the bunny) are not affected. 0 = no floor.
  Index hoppe_min_points = 100000;
  /// Hoppe: input edges whose two faces turn by more than this (degrees) get points along them too,
  /// about one per average edge length (E_dist sees a sharp edge only through the points near it, and
  /// with a few random points per long thin CAD triangle a collapse could bevel it almost for free:
  /// trimesh_counter at 10 %, Hausdorff 0.174 -> 0.059 %; docs/benchmarks-log.md, "Session 26"). 180 = none.
  double hoppe_crease_angle_deg = 60.0;
  /// Hoppe: passes of the fit after the collapses, the position step of "Mesh optimization" (Hoppe et
  /// al. 1993): every vertex moved at once to lower E_dist + E_spring over the whole mesh, connectivity
  /// fixed, by one sparse solve; passes after the first hand each point to its nearest face first. A move
  /// that would turn a face further than a collapse may, thin it or (inverted_faces avoid or refuse)
  /// leave it facing against the input is sent back. On the shared scans, CAD parts and attribute meshes
  /// at 10 % and 1 %: RMS x0.93, Hausdorff x0.98, about 2 % more time (docs/benchmarks-log.md, "Session
  /// 41"). Not with record_collapses (a progressive mesh's levels keep the collapses' positions) nor
  /// without preserve_topology. 0 = none.
  int hoppe_fit_passes = 1;
  /// Hoppe: its energy ranks the collapses once the mesh is within this many times the face target;
  /// until then the quadric error ranks them, while the points ride along on their faces as ever. The
  /// early collapses are small, the two costs agree on them, and scoring them by the energy was half of
  /// the run's time: on the shared scans, CAD parts and attribute meshes at 10 % and 1 %, 2 gives RMS
  /// x0.98, Hausdorff x0.96 in about half the time (docs/benchmarks-log.md, "Session 58"). Up to 1 = the
  /// energy from the first collapse, as in the paper. Not with record_collapses (every level of a
  /// progressive mesh is an output), nor without a face target (max_error alone).
  double hoppe_energy_from = 2.0;
  std::uint64_t seed = 1;

  /// Meshes of at least twice this many faces are first simplified in slabs of about this many faces,
  /// side by side (up to 8, when no collapses are recorded): a slab's rim waits for the end, when one
  /// queue finishes the job. The result does not depend on the thread count. 0 = never; unset: by
  /// method (default_lane_faces()).
  std::optional<Index> lane_faces{};

  /// No collapse may leave a vertex with more faces around it than this, unless it had as many before
  /// (so a vertex with few faces can always go). Without it, `hoppe` grows hubs of 60-100 faces on
  /// flat parts, where only its springs order the collapses, and each score then projects hundreds of
  /// points onto a hundred triangles (a 20,000-face grid to 1 %: 11.7 s; with 24: 1.1 s). 0 = no limit;
  /// unset: by method (default_max_valence()).
  std::optional<Index> max_valence{};

  /// Sampling passes of refit_to_input() after the collapses: every vertex moved at once to fit the
  /// input, towards its largest distances (bunny at 1 %: Hausdorff 0.94 -> 0.59 %, RMS 0.180 -> 0.144 %;
  /// docs/benchmarks-log.md, "Session 35"). Unset: by method and size (default_refit_passes()). Not with
  /// record_collapses (a progressive mesh's levels keep the collapses' positions) nor without
  /// preserve_topology.
  std::optional<int> refit_passes{};
  /// Passes of the refit's second stage, towards the least squared distances with the largest kept
  /// (RefitOptions::rms_passes; on the shared scans, CAD parts and attribute meshes at 10 % and 1 %:
  /// RMS x0.88, Hausdorff x1.00). Unset: kDefaultRefitRmsPasses where the first stage runs
  /// (refit_passes > 0, given or by default), else none; given where the first stage is off
  /// (refit_passes = 0, or by default above 500,000 faces), the second stage runs alone.
  std::optional<int> refit_rms_passes{};
  /// Set the output's vertex normals, colours and UVs, where input and output have them, to the values that
  /// best match the input's, once the positions are final (fit_attributes_to_input(); positions and faces
  /// stay). Not with record_collapses (a progressive mesh's levels keep the collapses' values), nor for
  /// normals with recompute_normals.
  bool fit_attributes = true;

  bool record_collapses = false;
  /// Called with the fraction done (0..1), at most about 100 times.
  std::function<void(double)> progress{};
};

/// What hoppe's fit after the collapses did (SimplifyOptions::hoppe_fit_passes).
struct HoppeFitReport {
  int passes = 0;              ///< passes kept (one that does not lower E is undone and ends the fit)
  double energy_before = 0.0;  ///< E = E_dist + E_spring (+ the boundary points' part), squared input units
  double energy_after = 0.0;
  Index points_sent_back = 0;  ///< moves undone: a face would have turned too far, thinned or faced against the input
  double seconds = 0.0;
};

/// One collapse u -> v, enough to undo it exactly.
struct CollapseRecord {
  Index removed;                    ///< the point (welded vertex) that disappears
  Index kept;                       ///< the point it merges into
  Eigen::Vector3d kept_before;      ///< kept's position before the collapse
  Eigen::Vector3d kept_after;       ///< and after
  double error;                     ///< error estimate of the collapse
  std::vector<Index> removed_faces;                      ///< faces that vanish
  std::vector<std::array<Index, 3>> changed_corners;     ///< (face, corner, old vertex)
  /// Each vertex (wedge) of `removed` and the vertex of `kept` it merged into: one pair per wedge, so
  /// an attribute seam through the edge stays a seam.
  std::vector<std::array<Index, 2>> wedge_map;
  /// With attribute weights, the merged vertices take new attribute values: these vertices, and their
  /// values after the collapse in the layout of the mesh's attributes (normals 3, UVs 2, colours 4, for
  /// those the mesh has), `attribute_values_per_vertex` numbers each. (Their values before are the
  /// input's or an earlier record's.)
  std::vector<Index> attribute_vertices;
  std::vector<double> attributes_after;
};

/// Why the edges left could not collapse when a run stopped short of its target: each edge once,
/// under the more specific of its two directions' reasons. All zero when the target was reached.
struct BlockedEdges {
  Index remaining = 0;    ///< edges left in the output
  Index locked = 0;       ///< an end is locked (non-manifold input, faces that disagree on orientation, or a locked boundary)
  Index topology = 0;     ///< the link condition: the result would not stay 2-manifold, or a part would vanish
  Index boundary = 0;     ///< a boundary point would leave its boundary
  Index seams = 0;        ///< an attribute seam would break
  Index flips = 0;        ///< a face would turn by more than max_normal_change_deg
  Index inverted = 0;     ///< a face would face against the nearest input face (inverted_faces)
  Index slivers = 0;      ///< a new face would be degenerate or a sliver
  Index valence = 0;      ///< a vertex would get more faces than max_valence
  Index error_limit = 0;  ///< the collapse's error exceeds max_error
  Index cost = 0;         ///< the cost has no value there (hoppe: no surface left for the points)
};

struct SimplifyResult {
  Mesh mesh;
  Index faces_in = 0, faces_out = 0, vertices_in = 0, vertices_out = 0;
  Index target_faces = 0;           ///< the face target aimed at (faces_in when none)
  Index collapses = 0;
  /// The largest error estimate of any collapse performed: for Quadric and EdgeLength the RMS distance
  /// from the merged vertex to the planes of the faces it replaced (sqrt of quadric error / area);
  /// for Hoppe the RMS distance of the sampled points to the mesh (the quadric's before the energy took
  /// over: hoppe_energy_from_faces).
  double error = 0.0;
  StopReason reason = StopReason::TargetReached;
  std::string reason_text;          ///< one human sentence: why it stopped where it did
  BlockedEdges blocked;             ///< the same reasons as counts, when it stopped short
  Index locked_vertices = 0;        ///< on non-manifold edges or fans (or the boundary when locked)
  Index dropped_degenerate_faces = 0;
  Index reoriented_faces = 0;       ///< input faces turned to agree with their neighbours first (orient_faces)
  int lanes = 1;                    ///< slabs simplified side by side first (see lane_faces), or 1
  /// Faces left when the run, stuck above its target under the method's default limit on a face's turn
  /// from its input shape, went on with 90 degrees (see max_total_normal_change_deg); unset if it did not.
  std::optional<Index> turn_limit_relaxed_at;
  /// Faces left when InvertedFaces::Avoid first let a face face against the input (the others cost four
  /// times as much); unset if it did not. Where lanes ran, the faces when their pass began.
  std::optional<Index> inverted_allowed_at;
  /// Faces left when hoppe's energy took over from the quadric error (SimplifyOptions::hoppe_energy_from);
  /// unset where the energy ranked every collapse.
  std::optional<Index> hoppe_energy_from_faces;
  double seconds = 0.0;
  std::vector<Index> vertex_origin; ///< for each output vertex, its input vertex
  std::vector<Index> face_origin;   ///< for each output face, the input face it is (moved corners and all)
  std::vector<CollapseRecord> records;
  /// With record_collapses: for each input vertex, the point (vertices welded by position) that the
  /// records' `removed` and `kept` number, and for each input vertex the identical vertex (same
  /// position and attributes) that stands for it in faces and records.
  std::vector<Index> vertex_point, vertex_canonical;
  /// simplify_within(): what proves the output within the limit, and what held the next level back.
  struct HausdorffLimit {
    double max_distance = 0.0;  ///< the limit asked
    double bound = 0.0;         ///< proved: no point of the output or the input lies farther than this from the other
    int checks = 0;             ///< levels checked by branch and bound
    /// The coarser level that failed nearest the output, when one did: its faces (at most 1/256 of the
    /// output's, or 2, fewer), and a point of it or of the input that lies `coarser_attained` from the
    /// other, farther than the limit.
    std::optional<Index> coarser_faces{};
    double coarser_attained = 0.0;
    Eigen::Vector3d coarser_at = Eigen::Vector3d::Zero();
  };
  std::optional<HausdorffLimit> within{};
  /// What the refit after the collapses did, when one ran (SimplifyOptions::refit_passes).
  std::optional<RefitReport> refit{};
  /// What hoppe's fit after the collapses did, when one ran (SimplifyOptions::hoppe_fit_passes).
  std::optional<HoppeFitReport> hoppe_fit{};
  /// What the fit of the normals, colours and UVs did, when one ran (SimplifyOptions::fit_attributes).
  std::optional<AttributeFitReport> attribute_fit{};
};

/// Numbers per vertex in the attribute layout of `mesh` (normals 3, UVs 2, colours 4, for those present).
int attribute_values_per_vertex(const Mesh& mesh);

/// \throw Error for invalid options (ratio outside 0..1, negative targets) or an invalid mesh.
SimplifyResult simplify(const Mesh& mesh, const SimplifyOptions& options = {});

/// The coarsest simplification found whose Hausdorff distance to `mesh` is proved at most `max_distance`
/// (absolute). The collapses are those of simplify() with `options`, recorded as a progressive mesh
/// down to the target (target_faces, target_ratio, max_error; by default as far as legal collapses go);
/// its levels are then checked by branch and bound (HausdorffChecker, lodkit/metrics.h): up from the
/// base, doubling the faces, then bisecting between the last level that failed and the first that
/// passed until they are 1/256 of the faces apart. Where simplify() would refit (refit_passes,
/// default_refit_passes()), refit levels are then checked down from the one found, halving the faces
/// until one fails, then bisecting to 1/16 of the faces, and the output is the coarsest refit level
/// that passed (result.refit says so). The distance need not grow at every collapse, so a coarser level might pass
/// too, but the output's own bound is proved (result.within). Unrefit, the output equals simplify()
/// with refit_passes = 0 (and hoppe_fit_passes = 0, fit_attributes = false) to the same face count, except on meshes large enough for lanes (see
/// lane_faces), whose progressive mesh runs one queue. Slower than simplify(): the bunny (69k faces)
/// takes 4.0-5.9 s with the refit search (0.5-0.8 s without), igea_loop1 (1M, no refit) 6.2-7.6 s. `error` is
/// not estimated here (0).
/// \throw Error for an invalid mesh or options, or a negative or non-finite `max_distance`.
SimplifyResult simplify_within(const Mesh& mesh, double max_distance, const SimplifyOptions& options = {});

/// Moves the vertices of `simplified`, a simplification of `input` (the same surface with fewer faces),
/// to lie closer to `input`; faces, attributes and vertex order stay. Vertices with the same position
/// move together, so seams stay closed. Iteratively reweighted least squares over points sampled on
/// both surfaces (Hoppe et al., "Mesh optimization", 1993, with connectivity fixed and weights towards
/// the largest distances; see the .cpp); each step is kept only if it lowers the largest sampled
/// distance. Faces keep within the turn, quality and orientation limits of `options`. `face_origin`:
/// for each face of `simplified`, the input face it stands for (SimplifyResult::face_origin), or empty.
/// \throw Error for invalid options, or face origins that do not match the faces.
RefitReport refit_to_input(const Mesh& input, Mesh& simplified, const RefitOptions& options = {},
                           std::span<const Index> face_origin = {});

/// Sets the vertex normals, colours and UVs of `simplified`, a simplification of `input`, to the values
/// that best match the input's (those both meshes have, unless constant over the input). Points are
/// sampled on both surfaces, each pairing the value one surface has there with the other's at its
/// closest point, and one sparse least-squares solve fits every vertex's values at once, faces
/// interpolating linearly; vertices split by a seam are fitted apart, so hard edges stay. Normals are
/// renormalised, colours clamped to 0..1. UVs have a solve of their own, over the pairs within a chart
/// (as compare() measures them: across a UV seam the other side belongs to another piece of the
/// atlas), and a vertex on a UV seam keeps its UVs, so that its twins across the seam still meet it.
/// Positions, faces and vertex order stay. The same result for any thread count.
/// \throw Error if options.samples_per_face is not positive.
AttributeFitReport fit_attributes_to_input(const Mesh& input, Mesh& simplified, const AttributeFitOptions& options = {});

/// Refit passes when SimplifyOptions::refit_passes is unset: 10 for quadric and hoppe on inputs of up to
/// 500,000 faces; none above, where a pass costs about as much as the whole simplification (igea_loop1,
/// 1M faces, to 10 %: 2.0 s, with the refit 15 s), and none for edge-length, kept as the naive method it
/// is. On the shared scans, CAD parts and attribute meshes at 10 % and 1 %: quadric Hausdorff x0.66, RMS
/// x0.86, time x5; hoppe, whose refit weighs by (d / d_max)^2 (its energy fits the squared distances
/// already), Hausdorff x0.73, RMS x0.91, faces facing against the input 2,041 -> 946, time x1.2-1.4.
int default_refit_passes(SimplifyMethod method, Index input_faces);

/// The refit's second-stage passes where SimplifyOptions::refit_rms_passes is unset and the first stage runs.
inline constexpr int kDefaultRefitRmsPasses = 8;

/// Faces per slab when SimplifyOptions::lane_faces is unset: 125,000 for quadric and edge-length, whose
/// collapses take microseconds, so that only large meshes pay for the slabs' rims; 8,000 for hoppe,
/// whose collapses take ten times longer, so that the bunny already runs in 8 slabs.
Index default_lane_faces(SimplifyMethod method);

/// The valence limit when SimplifyOptions::max_valence is unset: 24 faces for hoppe (on the shared scans,
/// CAD parts and attribute meshes, 16k-125k faces at 10 % and 1 %: time x0.97, RMS x1.000); none for
/// quadric and edge-length, whose costs keep flat parts even.
Index default_max_valence(SimplifyMethod method);

/// The limit on a face's turn from its input orientation when SimplifyOptions::max_total_normal_change_deg is
/// unset: 90 degrees for quadric (no face ever faces against its input self; on the shared scans, CAD
/// parts and attribute meshes at 10 % and 1 %, against 60: Hausdorff x0.977, RMS x0.952, and CAD parts
/// that stopped short at 60 reach their targets), 60 for hoppe (90 there: Hausdorff x1.017, more
/// flipped faces) and edge-length. Unset, the limit rises to 90 degrees when it alone would stop a run
/// short of its target.
double default_max_total_normal_change(SimplifyMethod method);

/// InvertedFaces when SimplifyOptions::inverted_faces is unset: Avoid for quadric (over the shared meshes
/// at 10 % and 1 %, no such face on 34 of 46 runs instead of 22, at the same Hausdorff and RMS x1.007,
/// in about twice the time of a small mesh and a fifth more on 1M faces), Allow for hoppe (whose speed
/// goal has no room for x1.10) and edge-length (the method that shows failure). See
/// docs/commands/simplify.md, "Faces facing against the input".
InvertedFaces default_inverted_faces(SimplifyMethod method);

std::string to_string(SimplifyMethod method);
std::string to_string(InvertedFaces mode);
std::optional<InvertedFaces> parse_inverted_faces(const std::string& name);
std::optional<SimplifyMethod> parse_method(const std::string& name);

}  // namespace lodkit
