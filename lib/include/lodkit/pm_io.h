#pragma once
// The .pm stream (docs/formats/pm.md): a header, the base mesh M0, then blocks of vertex splits, each
// block with its byte length and CRC-32, so a reader can stop after any block (progressive
// transmission) and a damaged stream still yields its valid prefix.
//
// Splits are coded against what the decoder already has: the split point as an index, the corners
// that move to the new point as one bit per face of the split point, the new faces' third vertex as
// an index into the split point's ring, positions as quantised residuals from a prediction, and all
// of it entropy-coded with Draco's rANS symbol coder. Lossless mode stores positions and attributes
// as doubles and reproduces the in-memory progressive mesh bit for bit.
#include <lodkit/progressive.h>

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

namespace lodkit {

struct PmWriteOptions {
  /// Quantisation of positions on a grid over the bounding box's longest side; 0 is lossless.
  int position_bits = 0;
  /// Quantised mode only: bits per normal component, per UV component and per colour channel.
  int normal_bits = 10;
  int uv_bits = 12;
  int colour_bits = 8;
  /// Quantised mode only: the base mesh through Draco (sequential connectivity, same quantisation).
  bool draco_base = false;
  int draco_compression_level = 7;
  /// Store the input's vertex and face order (and what only the finest level has) so that reading the
  /// whole stream reproduces the input exactly. Default: on when lossless, off when quantised.
  std::optional<bool> keep_order{};
  /// Splits per block: the granularity at which a reader can stop and a damaged stream is cut.
  Index splits_per_block = 1024;
};

/// Where the bytes of a stream went.
struct PmStreamStats {
  std::size_t total_bytes = 0, header_bytes = 0, base_bytes = 0, measured_bytes = 0, split_bytes = 0, order_bytes = 0,
              extra_bytes = 0;
  Index split_blocks = 0;
};

/// Writes `pm` atomically (temporary file, then rename). \throw Error "<path>: <problem>".
PmStreamStats write_pm(const ProgressiveMesh& pm, const std::filesystem::path& path, const PmWriteOptions& options = {});
/// The bytes write_pm() would write.
std::string write_pm_to_memory(const ProgressiveMesh& pm, const PmWriteOptions& options = {},
                               PmStreamStats* stats = nullptr);

struct PmReadOptions {
  /// Stop reading once the next split would exceed this many faces (progressive transmission).
  std::optional<Index> max_faces{};
  /// The same as a fraction of the finest level's faces (as the header announces them), rounded to
  /// the nearest count; with max_faces too, the smaller budget holds.
  std::optional<double> max_ratio{};
  /// Stop at the coarsest level whose error is at most this: the level level_for_error() picks from
  /// the whole stream (with `select_by`), read without the finer splits.
  std::optional<double> max_error{};
  /// Stop at the coarsest level whose error projects within this view's pixel budget: the level
  /// level_for_view() picks from the whole stream.
  std::optional<ScreenSpaceBudget> view{};
  /// What max_error and view are held to: the bound, or the measured distance when the stream has it.
  LevelErrorKind select_by = LevelErrorKind::Bound;
  // With several budgets, the read stops at the coarsest of the levels they pick.
};

struct PmReadResult {
  ProgressiveMesh pm;
  /// Every split of the stream was read (false when stopped by a budget or by damage).
  bool complete = false;
  /// Non-empty when the stream was damaged: what was wrong and which levels survive.
  std::string warning;
  std::size_t bytes_read = 0;
  Index total_splits = 0;   ///< splits the header announces
  Index total_faces = 0;    ///< faces of the finest level, as the header announces them
  int position_bits = 0;    ///< 0: lossless
  PmStreamStats stats;      ///< of the part that was read
};

/// Reads a stream, or only the prefix that the budgets in `options` need. A truncated or corrupted
/// split block ends the read with a warning and the levels before it. \throw Error "<path>: <problem>"
/// when not even the header and base mesh are intact, or a budget is invalid.
PmReadResult read_pm(const std::filesystem::path& path, const PmReadOptions& options = {});
PmReadResult read_pm_from_memory(std::string_view bytes, const std::string& name, const PmReadOptions& options = {});

}  // namespace lodkit
