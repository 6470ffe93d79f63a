// measure_levels(): the distance from levels of a progressive mesh to its input, by compare(), at
// levels spaced geometrically in faces, so that selection can go by what a viewer would see.
#include <lodkit/error.h>
#include <lodkit/metrics.h>
#include <lodkit/progressive.h>

#include <algorithm>
#include <cmath>
#include <fmt/format.h>

namespace lodkit {

void measure_levels(ProgressiveMesh& pm, const Mesh& input, const MeasureLevelsOptions& options) {
  if (!(options.face_factor > 1)) throw Error(fmt::format("measure levels: face factor must exceed 1, got {}", options.face_factor));
  if (options.samples < 0) throw Error(fmt::format("measure levels: sample count must not be negative, got {}", options.samples));
  const Index finest = pm.max_level();
  if (input.num_faces() != pm.source_faces())
    throw Error(fmt::format("measure levels: the input has {} faces, the progressive mesh's finest level {}",
                            input.num_faces(), pm.source_faces()));
  // The input is sampled, and its tree built, once for every level. A level is sampled as densely as
  // compare() would by default, 10 points per face and at least 10,000, but never more than the input: a coarse level far from
  // a dense input is the slowest kind of query, and 500,000 samples on a handful of faces add nothing.
  const long long input_samples =
      options.samples > 0 ? options.samples : std::max<long long>(10000, input.num_faces() / 2);
  const CompareReference reference(input, input_samples);

  // Level 0, then each level with factor times the faces of the last one measured; the finest level
  // is the input's surface (only unused vertices and degenerate faces differ): zero.
  std::vector<LevelMeasurement> measured;
  PMCursor cursor(pm);
  Index level = 0;
  while (level < finest) {
    if (pm.num_faces(level) > 0) {  // a level without faces has no distance (its bound stands)
      cursor.go_to(level);
      const Comparison c = reference.compare(cursor.extract(VertexOrder::Stream).mesh,
                                             std::min(input_samples, default_face_samples(pm.num_faces(level))));
      // An upper bound, so that a level chosen by it keeps its budget: compare()'s certified bound, or
      // the level's own where that is lower.
      measured.push_back({level, std::min(c.hausdorff_bound, pm.level_error[level]), c.rms});
    }
    const double next_faces = std::ceil(double(pm.num_faces(level)) * options.face_factor);
    const Index next = level_for_faces(pm, static_cast<Index>(std::min(next_faces, 2e9)));
    level = std::max(level + 1, next);
  }
  measured.push_back({finest, 0.0, 0.0});
  // A finer level can lie a hair farther than a coarser one: keep the values monotone.
  for (std::size_t i = measured.size() - 1; i-- > 0;)
    measured[i].hausdorff = std::max(measured[i].hausdorff, measured[i + 1].hausdorff);
  pm.measured = std::move(measured);
}

}  // namespace lodkit
