#pragma once
// What the pm subcommands share (pm.cpp; pm_selective.cpp for extract --eye and --eye-path): their
// options, reading a stream by path or "-", and naming numbered outputs.
#include <lodkit/pm_io.h>
#include <lodkit/progressive.h>

#include <optional>
#include <string>
#include <vector>

#include "common.h"

namespace lodkit::cli::pm {

struct PmCliOptions {
  // build
  std::string input, output, method = "quadric";
  std::optional<std::string> format;
  std::optional<Index> base_faces;
  int quantize = 0;
  bool draco = false, keep_order = false, json = false, measure = false, drop_normals = false, keep_orientation = false;
  Index block = 1024;
  std::vector<double> attribute_weights;
  std::optional<std::string> inverted_faces;  // allow|avoid|refuse; unset: by method, as simplify
  // extract / geomorph
  std::optional<Index> faces, from, to;
  std::optional<double> ratio, pixel_error, alpha, max_error;
  double distance = 10.0, fov = 60.0, viewport = 1080.0;
  int frames = 0;
  bool input_order = false, certified = false, fit_attributes = false;
  std::optional<std::string> prove_with;  // extract: the mesh the stream was built from
  std::vector<double> eye, look_at;        // extract: selective refinement for this viewer
  std::optional<std::string> eye_path;     // extract: ... for each viewer of this file
  int morph_frames = 1;                    // extract --eye-path: frames per step, the last the view itself
  double aspect = 16.0 / 9.0;
  bool no_cull = false, cull_backfaces = false, allow_folds = false;
  std::optional<Index> rows;
};

/// A stream from a file, or from stdin when `path` is "-".
PmReadResult read_pm_input(const std::string& path, const PmReadOptions& options = {});

/// The reader's warning on stderr (a damaged or cut stream read up to its last good block), unless quiet.
void warn(const PmReadResult& r, const GlobalOptions& global);

/// By the measured distance (the bound where the stream has none), unless the bound is asked for.
LevelErrorKind selection_kind(const PmCliOptions& o);

/// --eye and --look-at: CLI11 takes exactly three numbers.
inline Eigen::Vector3d point_option(const std::vector<double>& xyz) { return {xyz[0], xyz[1], xyz[2]}; }

/// out.ply -> out_000.ply, out_001.ply, ...: the frames of a geomorph or the views of a path.
std::string numbered(const std::string& output, std::size_t i);

/// pm extract --eye / --eye-path: the splits each viewer needs, fine near the eye and coarse far away or
/// out of view (pm_selective.cpp). `inputs`: the files no output may overwrite.
int run_selective(const PmCliOptions& o, const GlobalOptions& global, const std::vector<std::string>& inputs);

}  // namespace lodkit::cli::pm
