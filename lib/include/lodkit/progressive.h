#pragma once
// Progressive meshes (Hoppe, "Progressive meshes", SIGGRAPH 1996): a coarse base mesh M0 and an
// ordered list of vertex splits, each undoing one edge collapse of simplify(), so that applying the
// first i splits gives level M_i and applying all of them gives the input M_n again.
//
// Numbering ("stream order"): points (positions), wedges (mesh vertices: a point with one set of
// attributes) and faces are numbered in the order they appear. Level i holds exactly the first
// points, wedges and faces, so a level is a prefix and moving between levels touches only the splits
// crossed. Split i creates point `base_points + i`, its wedges and its one or two faces; it moves the
// corners of some faces of the split point over to the new point's wedges.
//
// Error bound: every collapse maps the input simplicially onto the coarser mesh, so the Hausdorff
// distance between M_i and M_n is at most the largest distance from an input vertex to its
// representative's position in M_i. Each point keeps a bounding ball of the input vertices it stands
// for, and `level_error[i]` is a running maximum of |position - centre| + radius: conservative, and
// non-increasing as levels get finer. It is guaranteed but loose: a point's ball grows with every
// collapse, sideways along the surface as much as away from it, so the bound is 4-50 times (on the bunny)
// the distance `compare` measures. Screen-space selection from it models far more than a scene needs;
// measure_levels() adds measured distances at levels spaced by a factor of sqrt(2) in faces, and
// selection can go by those (LevelErrorKind::Measured).
#include <lodkit/mesh.h>
#include <lodkit/simplify.h>

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <vector>

namespace lodkit {

/// The Hausdorff distance and RMS distance between one level and the finest, measured by compare().
struct LevelMeasurement {
  Index level = 0;
  double hausdorff = 0.0;  ///< an upper bound: compare()'s certified one, or the level's own if lower
  double rms = 0.0;
};

/// One vertex split: point `point` (s) splits into s and the new point t = base_points + index.
struct VertexSplit {
  Index point = 0;
  Index first_wedge = 0, num_wedges = 0;    ///< t's new wedges, numbered contiguously
  Index first_face = 0, num_faces = 0;      ///< the new faces (2, or 1 on a boundary)
  Index first_change = 0, num_changes = 0;  ///< into ProgressiveMesh::corner_changes
  Index first_attribute_change = 0, num_attribute_changes = 0;  ///< into attribute_changes
  Eigen::Vector3d position{0, 0, 0};         ///< s after the split (finer level)
  Eigen::Vector3d coarse_position{0, 0, 0};  ///< s before the split (coarser level)
  Eigen::Vector3d new_position{0, 0, 0};     ///< t
};

/// A face corner that moves from one of s's wedges to one of t's when the split is applied.
struct CornerChange {
  Index corner;  ///< 3 * face + k
  Index coarse_wedge, fine_wedge;
};

/// A wedge whose attribute values differ between the two sides of a split (attribute-aware costs).
struct AttributeChange {
  Index wedge;
  Index first_value;  ///< into attribute_values: `attribute_dims` coarse values, then as many fine ones
};

struct ProgressiveMesh {
  Index base_points = 0, base_wedges = 0, base_faces = 0;
  std::vector<VertexSplit> splits;

  /// Per point: its position in M0 (base points only; later points start at their split's new_position).
  std::vector<Eigen::Vector3d> base_positions;
  /// Per wedge (all levels): its point, and the wedge of the split point it split from (-1 in M0).
  std::vector<Index> wedge_point, wedge_parent;
  /// Per face (all levels): its corners' wedges when it first appears (M0 for base faces).
  std::vector<std::array<Index, 3>> face_corners;
  std::vector<CornerChange> corner_changes;

  /// Attributes, in the layout normals (3), UVs (2), colours (4) for those the mesh has. Per wedge,
  /// its values when it first appears; changes in attribute_changes.
  bool has_normals = false, has_uvs = false, has_colours = false, has_face_colours = false;
  int attribute_dims = 0;
  std::vector<double> wedge_attributes;
  std::vector<AttributeChange> attribute_changes;
  std::vector<double> attribute_values;
  Colours face_colours;  ///< per face, then per extra face, when has_face_colours

  /// Conservative Hausdorff bound between level i and the finest level, for i = 0 .. splits.size().
  std::vector<double> level_error;
  /// Measured distances at some levels, by increasing level, or empty (see measure_levels()).
  std::vector<LevelMeasurement> measured;
  /// The finest level's bounding box (for screen-space selection).
  Eigen::AlignedBox3d bounds;

  /// Input numbering, when known (built in memory, or a stream that keeps the order): the input vertex
  /// of each wedge and the input face of each face. Empty otherwise.
  std::vector<Index> wedge_input, face_input;
  /// What the input had beyond the stream's faces and wedges, restored only at the finest level so that
  /// it equals the input exactly: its vertex and face counts, vertices no face uses or that duplicate
  /// another exactly (positions and attributes per `extra_vertex_input`), faces too degenerate to
  /// take part (three input vertices each) and corners that referenced a duplicate.
  Index input_vertices = 0, input_faces = 0;
  std::vector<Index> extra_vertex_input;
  Mesh extra_vertices;
  std::vector<Index> extra_face_input;
  Triangles extra_faces;
  std::vector<std::array<Index, 3>> corner_exceptions;  ///< (input face, corner, input vertex)

  Index num_levels() const { return static_cast<Index>(splits.size()) + 1; }
  Index max_level() const { return static_cast<Index>(splits.size()); }
  Index num_points(Index level) const { return base_points + level; }
  Index num_wedges(Index level) const {
    return level == 0 ? base_wedges : splits[level - 1].first_wedge + splits[level - 1].num_wedges;
  }
  Index num_faces(Index level) const {
    return level == 0 ? base_faces : splits[level - 1].first_face + splits[level - 1].num_faces;
  }
  bool knows_input_order() const { return !wedge_input.empty(); }
  /// Faces of the mesh this was built from: the finest level's and those kept aside as degenerate.
  Index source_faces() const { return num_faces(max_level()) + static_cast<Index>(extra_faces.rows()); }
};

struct ProgressiveOptions {
  /// The simplification whose collapses the splits undo (any method; its targets are ignored).
  SimplifyOptions simplify{};
  /// Stop collapsing at this many faces; by default go as far as legal collapses go.
  std::optional<Index> base_faces{};
  /// Also measure the levels' distances to the input (measure_levels()): slower, but selection by error
  /// or view can then pick the level a viewer actually needs.
  bool measure_levels = false;
};

/// Builds the progressive mesh of `mesh`. \throw Error for an invalid mesh or options.
ProgressiveMesh build_progressive_mesh(const Mesh& mesh, const ProgressiveOptions& options = {});

struct MeasureLevelsOptions {
  /// Levels whose face counts grow by this factor from the base are measured (and the finest level).
  double face_factor = 1.4142135623730951;
  /// Face samples on the input; 0: half its face count, at least 10,000. Each level gets 10 per face,
  /// at least 10,000, never more than the input (compare() then refines around the worst samples, so
  /// the Hausdorff distance converges).
  long long samples = 0;
};

/// Measures the Hausdorff and RMS distances between `input` (the mesh `pm` was built from) and levels
/// of `pm`, and stores them in pm.measured. Each Hausdorff distance is an upper bound (compare()'s
/// hausdorff_bound, or pm.level_error where lower), raised to at least those of the
/// finer measured levels, so the values do not increase with the level. \throw Error if `input` does
/// not have the finest level's face count.
void measure_levels(ProgressiveMesh& pm, const Mesh& input, const MeasureLevelsOptions& options = {});

/// Checks the internal consistency of a progressive mesh (index ranges, counts). \throw Error.
void validate(const ProgressiveMesh& pm, const std::string& context = "progressive mesh");

enum class VertexOrder {
  Input,   ///< vertices and faces in input order (like simplify()), when the order is known
  Stream,  ///< in order of appearance
};

/// A mesh extracted from a progressive mesh, with where its vertices come from.
struct ExtractedLevel {
  Mesh mesh;
  Index level = 0;
  std::vector<Index> vertex_wedge;   ///< for each vertex, its wedge (stream order)
  std::vector<Index> vertex_origin;  ///< for each vertex, its input vertex (its wedge when unknown)
};

/// Walks between levels. Holds the current level's positions, attributes and corners; refine() and
/// coarsen() cost time proportional to the split's size, so moving k levels costs O(k).
class PMCursor {
 public:
  /// Starts at level 0 (the base mesh). `pm` must outlive the cursor.
  explicit PMCursor(const ProgressiveMesh& pm);

  Index level() const { return level_; }
  Index num_faces() const { return pm_->num_faces(level_); }
  Index num_wedges() const { return pm_->num_wedges(level_); }
  double error_bound() const { return pm_->level_error[static_cast<std::size_t>(level_)]; }

  /// Applies the next split; false at the finest level.
  bool refine();
  /// Undoes the last split; false at the base.
  bool coarsen();
  /// Moves to `level` (clamped to 0 .. max_level) by refining or coarsening.
  void go_to(Index level);

  /// The current level as a mesh. At the finest level, in input order, it equals the input exactly.
  ExtractedLevel extract(VertexOrder order = VertexOrder::Input) const;

  /// The wedge that stands for `wedge` at `level` (itself when it exists there).
  Index ancestor(Index wedge, Index level) const;
  const Eigen::Vector3d& point_position(Index point) const { return positions_[static_cast<std::size_t>(point)]; }
  const double* wedge_attributes(Index wedge) const {
    return attributes_.data() + static_cast<std::size_t>(pm_->attribute_dims) * static_cast<std::size_t>(wedge);
  }
  Index corner_wedge(Index face, int k) const { return corners_[3 * static_cast<std::size_t>(face) + k]; }

 private:
  /// Writes split `split`'s changes in their fine (refine) or coarse (coarsen) state.
  void apply(Index split, bool fine);

  const ProgressiveMesh* pm_;
  Index level_ = 0;
  std::vector<Eigen::Vector3d> positions_;  // per point, all levels (later points undefined until split)
  std::vector<double> attributes_;          // per wedge
  std::vector<Index> corners_;              // per face corner
};

/// Level i of `pm` (a convenience over PMCursor).
ExtractedLevel extract_level(const ProgressiveMesh& pm, Index level, VertexOrder order = VertexOrder::Input);

/// A geomorph between a coarse level and a fine level: the fine level's connectivity, with every vertex
/// starting at its ancestor's position and attributes in the coarse level.
struct Geomorph {
  Index coarse_level = 0, fine_level = 0;
  ExtractedLevel fine;              ///< the fine level (the end, alpha = 1)
  Positions start_positions;        ///< per fine vertex: its ancestor's position in the coarse level
  Normals start_normals;
  TexCoords start_uvs;
  Colours start_colours;

  /// The mesh at `alpha` in [0, 1]: exactly the coarse level's shape at 0 and the fine level at 1.
  /// \throw Error for an alpha outside [0, 1] (it would extrapolate past both levels).
  Mesh at(double alpha) const;
  /// As at(), reusing `out`'s storage (connectivity is copied only when the face count differs).
  void evaluate(double alpha, Mesh& out) const;
};

/// \throw Error unless 0 <= coarse_level <= fine_level <= max_level.
Geomorph make_geomorph(const ProgressiveMesh& pm, Index coarse_level, Index fine_level,
                       VertexOrder order = VertexOrder::Input);

/// What a viewer sees: how many pixels of error are acceptable for a model at `distance` from the eye
/// (to the centre of its bounding sphere), with vertical field of view `fov_degrees` over a viewport
/// `viewport_pixels` high.
struct ScreenSpaceBudget {
  double pixel_error = 1.0;
  double distance = 10.0;
  double fov_degrees = 60.0;
  double viewport_pixels = 1080.0;
};

/// The pixels an object-space error projects to: error * H / (2 d tan(fov / 2)), d the distance from
/// the eye to the nearest point of the bounding sphere (`radius` around the centre at `distance`).
/// Infinite when the eye is inside the sphere.
double projected_pixels(double error, double radius, const ScreenSpaceBudget& view);
/// The inverse: the largest object-space error that projects to at most view.pixel_error pixels (0 when
/// the eye is inside the sphere). With simplify_within(), the coarsest mesh proved to look within the
/// budget: `lodkit simplify --pixel-error`.
double object_error_for_pixels(double radius, const ScreenSpaceBudget& view);

/// Which error selection goes by: the guaranteed bound, or the measured distance.
enum class LevelErrorKind { Bound, Measured };

/// The error of `level`. Measured: the Hausdorff distance measured at the nearest measured level at or
/// below it (coarser; errors shrink with the level), never more than the bound; the bound itself when
/// `pm` carries no measurements.
double level_error(const ProgressiveMesh& pm, Index level, LevelErrorKind kind = LevelErrorKind::Bound);

/// The finest level with at most `faces` faces (level 0 if even the base has more).
Index level_for_faces(const ProgressiveMesh& pm, Index faces);
/// The coarsest level whose error is at most `max_error` (the finest level if none is).
Index level_for_error(const ProgressiveMesh& pm, double max_error, LevelErrorKind kind = LevelErrorKind::Bound);
/// The coarsest level whose error projects to at most view.pixel_error pixels.
Index level_for_view(const ProgressiveMesh& pm, const ScreenSpaceBudget& view, LevelErrorKind kind = LevelErrorKind::Bound);
/// A level proved within a Hausdorff limit, and the proof.
struct ProvedLevel {
  Index level = 0;
  SimplifyResult::HausdorffLimit proof;
};

/// The coarsest level found whose Hausdorff distance to `input` (the mesh `pm` was built from) is proved
/// at most `max_distance` by branch and bound (HausdorffChecker, lodkit/metrics.h), finer-grained than
/// level_for_error(): it starts from the level that selection proves within (the guaranteed bound, or a
/// measured level), gallops up from the base doubling the faces, and bisects between the last level
/// that failed and the first that passed to 1/256 of the faces. The distance need not grow at every
/// level, so a coarser level might pass too; the chosen level's bound is proved. simplify_within() and
/// `lodkit pm extract --prove-with` use it.
/// \throw Error if `input` does not have the finest level's face count, or for a bad limit.
ProvedLevel prove_level_within(const ProgressiveMesh& pm, const Mesh& input, double max_distance);

/// The bounding sphere radius used by level_for_view (half the bounding box diagonal).
double bounding_radius(const ProgressiveMesh& pm);

/// A viewer for selective refinement: where the eye is, where it looks, and the error it tolerates.
struct Viewpoint {
  Eigen::Vector3d eye{0, 0, 10};
  Eigen::Vector3d look_at{0, 0, 0};
  double fov_degrees = 60.0;        ///< vertical field of view
  double viewport_pixels = 1080.0;  ///< viewport height
  double aspect = 16.0 / 9.0;       ///< viewport width over height
  double pixel_error = 1.0;
  bool cull = true;  ///< leave what lies outside the view cone (around the frustum) coarse
  /// Leave regions facing away from the eye coarse (for closed meshes: hidden behind the front).
  bool cull_backfaces = false;
  /// Refine further where a face folds: faces against their own input face (see SelectiveRefiner).
  bool unfold = true;
};

/// A selectively refined mesh and what it guarantees.
struct SelectiveLevel {
  ExtractedLevel extracted;  ///< stream order; `level` is the number of splits applied
  Index splits_applied = 0;
  /// Hausdorff bound between this mesh and the finest level: the largest of its points' bounds.
  double error_bound = 0.0;
  /// The largest of its points' measured deviations (SelectiveRefiner::region_deviation()).
  double deviation = 0.0;
  /// By a view: the largest number of pixels a bound of a region in view projects to (at most the
  /// budget unless the finest level is reached there), and how many regions were left coarse outside it.
  double max_pixels = 0.0;
  Index regions_outside = 0;
  Index regions_facing_away = 0;  ///< left coarse because they face away (Viewpoint::cull_backfaces)
  /// By SelectiveMesh: the splits applied and undone to get here from its previous state.
  Index splits_refined = 0, splits_coarsened = 0;
  /// By a view that unfolds: the splits applied beyond the view's own to unfold faces (in splits_applied).
  Index splits_unfolding = 0;
};

/// Selective refinement (Hoppe 1996, section 5): a mesh that applies only the splits a viewer needs,
/// fine near the eye and coarse far from it or out of view. Split j is applied only after every split
/// that created or changed a face around its point by then (its dependencies), so the point's
/// neighbourhood is exactly what the uniform level j had and the split leaves a valid mesh: any
/// dependency-closed set of splits, applied in order, gives a manifold mesh with the input's topology.
/// Each split's region is a ball around the input vertices its point stands for. Its error is either
/// the bound |position - centre| + radius, as for level_error (guaranteed, but loose sideways: about an
/// edge's length even where the surface is flat), or its measured deviation: the distance between the
/// point's faces before and after each split below it, at their corners, edge midpoints and centroids
/// (among more than 64 faces, the farthest its vertices move), added up the hierarchy (a distance to
/// a surface is within that to a finer one plus theirs apart), never more than the bound. The
/// deviation is what a viewer sees; it is measured, not proved. A stream read in part (a prefix, or a
/// damaged stream's valid part) adds its last level's error from the input to both.
///
/// Folds. A split's neighbours may be coarser or finer than in its uniform level, so a face of a
/// selective mesh can fold: face against its own face in the input, or against every input face
/// nearest its centroid (count_flipped_faces()'s rule), which no face of a uniform level does when the
/// simplifier avoided both (its defaults). A view (Viewpoint::unfold, the default) then applies, round
/// by round, the next split of each corner of every face that folds, and their dependencies, until
/// none does: every split moves a point towards the input, whose faces do not fold, so it ends. The
/// result depends on the view's set alone, however the mesh got there.
class SelectiveRefiner {
 public:
  /// Finds every split's dependencies and region (time and memory linear in the stream). `pm` must
  /// outlive the refiner.
  explicit SelectiveRefiner(const ProgressiveMesh& pm);

  /// The splits split `split` needs applied first (all earlier).
  std::span<const Index> dependencies(Index split) const;
  /// The ball of the input vertices split `split`'s point stands for just before it, and that point's
  /// error bound there.
  const Eigen::Vector3d& region_centre(Index split) const { return centre_[static_cast<std::size_t>(split)]; }
  double region_radius(Index split) const { return radius_[static_cast<std::size_t>(split)]; }
  double region_error(Index split) const { return error_[static_cast<std::size_t>(split)]; }
  double region_deviation(Index split) const { return deviation_[static_cast<std::size_t>(split)]; }

  /// Applies the splits `wanted` marks (one entry per split) and every split they depend on, in order.
  /// \throw Error unless `wanted` has one entry per split.
  SelectiveLevel refine(std::vector<char> wanted) const;
  /// Applies the splits whose region is in view with an error (the bound, or the measured deviation)
  /// projecting to more than view.pixel_error pixels (error * H / (2 d tan(fov / 2)), d the distance
  /// from the eye to the region's ball), and their dependencies. \throw Error for a bad view.
  SelectiveLevel refine_for_view(const Viewpoint& view, LevelErrorKind kind = LevelErrorKind::Bound) const;
  /// The view's own splits (one entry per split), without the mesh: those of regions_needing_refinement()
  /// and their dependencies, found down the hierarchy of splits only where a region can need it (what
  /// lies below a split is held in one ball with its largest error). refine_for_view() applies these,
  /// and those that unfold its faces unless the view says not to.
  std::vector<char> splits_for_view(const Viewpoint& view, LevelErrorKind kind = LevelErrorKind::Bound) const;
  /// Per split, whether its own region needs refining for this view: in the view cone, not facing away,
  /// with an error projecting past the budget. Every region is tested (time linear in the stream).
  std::vector<char> regions_needing_refinement(const Viewpoint& view, LevelErrorKind kind = LevelErrorKind::Bound) const;

 private:
  friend class SelectiveMesh;
  struct ViewTest;     // a view's tests of a region (selective.cpp)
  struct InputFacing;  // the input's faces and their tree, for telling faces facing against it (selective.cpp)
  void check_size(const std::vector<char>& wanted) const;  // one entry per split
  void close(std::vector<char>& wanted) const;             // adds every dependency
  /// Per point that exists, its first split not applied: the regions left coarse.
  std::vector<Index> frontier(const std::vector<char>& applied) const;
  /// The splits just below split j in the hierarchy: the next split of its point and the first of the
  /// point it makes (-1 where there is none).
  std::array<Index, 2> below(Index split) const;
  SelectiveLevel apply_closed(std::vector<char> applied, const ViewTest* view) const;  // from the base
  /// The uniform levels in which a point stands where it does now, first and last: from just after its
  /// last split applied (or the one that made it) to its next split (the splits of a point applied
  /// are the first of its splits). Per point, for the closed set `applied`; and as split `split` is
  /// applied or undone.
  using LevelSpan = std::array<Index, 2>;
  /// The split that makes point `point`, or -1 for the base's.
  Index made_by(Index point) const { return point >= pm_->base_points ? point - pm_->base_points : -1; }
  std::vector<LevelSpan> level_spans(const std::vector<char>& applied) const;
  LevelSpan span_after(Index split, bool applied) const;
  /// Whether face `face` of the state folds (see the class comment); `spans` as level_spans() gives.
  bool folds(Index face, const std::vector<Eigen::Vector3d>& positions, const std::vector<Index>& corners,
             const std::vector<char>& applied, const std::vector<LevelSpan>& spans) const;
  /// Applies to the state of the closed set `applied` the splits that unfold its faces, where every
  /// face that can fold is among `check` (the faces of the points of the splits that changed since the
  /// state had none) or, with `check` null, anywhere. Keeps `spans` up to date. Returns them, ascending.
  std::vector<Index> unfold(std::vector<Eigen::Vector3d>& positions, std::vector<double>& attributes, std::vector<Index>& corners,
                            std::vector<char>& applied, std::vector<LevelSpan>& spans, const std::vector<Index>* check) const;
  /// Appends the faces that ever have a corner at split `split`'s two points.
  void append_faces_of(Index split, std::vector<Index>& faces) const;
  /// The faces the closed set `applied` shows, by number: the base's, then those each split opens.
  std::vector<Index> shown_faces(const std::vector<char>& applied) const;
  /// The mesh of the closed set `applied` from the state's arrays, in stream order.
  ExtractedLevel mesh_of(const std::vector<Eigen::Vector3d>& positions, const std::vector<double>& attributes,
                         const std::vector<Index>& corners, const std::vector<char>& applied) const;
  /// The wedge that stands for `wedge` in the closed set `applied`: itself, or its parent's, while the
  /// split that made it is not applied.
  Index ancestor(Index wedge, const std::vector<char>& applied) const;
  /// The mesh the state holds with the closed set `applied`, its errors, and what `view` (if any) sees.
  SelectiveLevel level_of(const std::vector<Eigen::Vector3d>& positions, const std::vector<double>& attributes,
                          const std::vector<Index>& corners, const std::vector<char>& applied, const ViewTest* view) const;
  /// What a view sees of the regions left coarse: pixels in view, regions out of it or facing away.
  void report_view(const ViewTest& test, const std::vector<Index>& coarse, SelectiveLevel& out) const;

  const ProgressiveMesh* pm_;
  std::vector<Index> dependency_start_, dependencies_;  // CSR: split j's are [start[j], start[j + 1])
  std::vector<Index> next_at_point_;      // per split: the next split of its point, or -1
  std::vector<Index> previous_at_point_;  // per split: the split of its point before, or -1
  std::vector<Index> first_at_point_;     // per point: its first split, or -1
  std::vector<Index> wedge_split_;     // per wedge: the split that makes it, or -1 (the base's)
  std::vector<Index> face_split_;      // per face: the split that opens it, or -1 (the base's)
  std::vector<Index> point_wedge_start_, point_wedges_;  // CSR: each point's wedges
  std::vector<Index> point_face_start_, point_faces_;    // CSR: the faces ever with a corner at each point
  std::shared_ptr<const InputFacing> input_;            // the finest level, for faces that fold
  std::vector<Eigen::Vector3d> centre_;
  std::vector<double> radius_, error_, deviation_;
  double beyond_bound_ = 0, beyond_deviation_ = 0;  // the last level's bound and measured error (0 when it is the input)
  // Per split, the cone of the normals of the faces its region can show: axis and half-angle.
  std::vector<Eigen::Vector3d> cone_axis_;
  std::vector<double> cone_half_angle_;
  // Per split, what lies at or below it: a ball around its region's centre holding every region there,
  // and the largest bound and deviation.
  std::vector<double> reach_radius_, reach_bound_, reach_deviation_;
};

/// A change of a SelectiveMesh's state as a geomorph (Hoppe 1997, view-dependent refinement), so that
/// a viewer sees it blend in over a few frames instead of popping: both states' splits' connectivity,
/// every vertex moving from its ancestor's place and attributes in the state before (at alpha 0 the
/// mesh looks exactly like that state: the faces only the new splits make have no area) to those in
/// the new state (alpha 1 looks exactly like it: the faces only the splits undone make have none).
/// Both refining and coarsening blend, in one morph.
struct SelectiveMorph {
  /// `geomorph.fine` holds the joint connectivity at the new state's shape; its coarse_level and
  /// fine_level are the splits applied before and after (either may be the larger).
  Geomorph geomorph;
  /// The new state, as go_to() and adapt() report it: the mesh to show once the morph is over.
  SelectiveLevel reached;
};

/// What a step of a SelectiveMesh changed, for a renderer that keeps the mesh in buffers of its own with
/// a slot per wedge and per face of the whole stream (pm.wedge_point.size() and pm.face_corners.size()):
/// upload these slots again from wedge_position(), wedge_values(), face_shown() and face_corner(). A step
/// then costs what changes and a pass over the per-split flags, not the mesh shown.
struct SelectiveChanges {
  std::vector<Index> wedges;  ///< wedges that appeared, or whose point moved or values changed (ascending)
  std::vector<Index> faces;   ///< faces that appeared or went, or whose corners changed (ascending)
  Index splits_refined = 0, splits_coarsened = 0;
  Index splits_unfolding = 0;  ///< as SelectiveLevel::splits_unfolding
};

/// A selectively refined mesh kept from view to view (Hoppe 1997): moving to another set of splits
/// undoes those no longer wanted, the last first, and applies the new ones in order, so a viewer who
/// moves a little pays for the splits that change rather than for every split. Undoing is exact: a
/// split left in a closed set without it depends on none of it. Each state is the mesh
/// SelectiveRefiner::refine() gives for the same set, bit for bit, whatever the states before it.
class SelectiveMesh {
 public:
  /// The base mesh. `refiner` (and its progressive mesh) must outlive this.
  explicit SelectiveMesh(const SelectiveRefiner& refiner);

  /// Moves to the splits `wanted` marks and their dependencies (refine()'s set).
  /// \throw Error unless `wanted` has one entry per split.
  SelectiveLevel go_to(std::vector<char> wanted);
  /// Moves to the splits the view needs (refine_for_view()'s set and report).
  SelectiveLevel adapt(const Viewpoint& view, LevelErrorKind kind = LevelErrorKind::Bound);
  /// As go_to() and adapt(), with the change as a geomorph from the state before to the new one.
  SelectiveMorph morph_to(std::vector<char> wanted);
  SelectiveMorph morph_to_view(const Viewpoint& view, LevelErrorKind kind = LevelErrorKind::Bound);
  /// As go_to() and adapt(), without making the mesh: what changed, slot by slot.
  SelectiveChanges step_to(std::vector<char> wanted);
  SelectiveChanges step_to_view(const Viewpoint& view, LevelErrorKind kind = LevelErrorKind::Bound);
  /// Per split, whether it is applied now.
  const std::vector<char>& applied() const { return applied_; }
  /// The state slot by slot, for any wedge or face of the stream (a slot not shown holds stale values).
  bool face_shown(Index face) const;
  Index face_corner(Index face, int k) const { return corners_[3 * static_cast<std::size_t>(face) + static_cast<std::size_t>(k)]; }
  const Eigen::Vector3d& wedge_position(Index wedge) const;
  std::span<const double> wedge_values(Index wedge) const;  ///< attribute_dims values

 private:
  struct Change {
    std::vector<Index> undo, redo;  // the splits applied now and not wanted, and the reverse, in order
  };
  std::vector<char> closed(std::vector<char> wanted) const;  // checked, with every dependency
  Change change_to(const std::vector<char>& wanted) const;
  /// Moves to the closed set `wanted` and, when `unfold`, on to the splits that unfold it (counted in
  /// `unfolding`): what changed from the state before, net.
  Change reach(const std::vector<char>& wanted, bool unfold, Index& unfolding);
  void undo(const std::vector<Index>& splits);  // the last first
  void redo(const std::vector<Index>& splits);  // in order
  SelectiveLevel move_to(const std::vector<char>& wanted, const SelectiveRefiner::ViewTest* view);  // wanted is closed
  SelectiveMorph morph(const std::vector<char>& wanted, const SelectiveRefiner::ViewTest* view);    // wanted is closed
  SelectiveChanges step(const std::vector<char>& wanted, bool unfold);                              // wanted is closed

  const SelectiveRefiner* refiner_;
  std::vector<Eigen::Vector3d> positions_;
  std::vector<double> attributes_;
  std::vector<Index> corners_;
  std::vector<char> applied_;
  std::vector<SelectiveRefiner::LevelSpan> spans_;  // per point (SelectiveRefiner::level_spans())
  bool fold_free_ = false;  // whether the state was unfolded: only faces a change touches can fold
};

}  // namespace lodkit
