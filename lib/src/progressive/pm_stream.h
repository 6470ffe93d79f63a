#pragma once
// What the .pm writer and reader share: the layout constants, little-endian byte buffers, Draco's
// entropy-coded symbol arrays, the quantisers, and the decoder state both sides keep in step (the
// writer codes every split against exactly what the reader will have when it decodes it).
#include <lodkit/progressive.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

namespace lodkit::detail::pm {

static_assert(std::endian::native == std::endian::little, "the .pm codec assumes a little-endian host");

inline constexpr char kMagic[8] = {'L', 'K', 'P', 'M', '\r', '\n', '\x1a', '\n'};
inline constexpr std::uint16_t kVersion = 3;  // 2: moved-corner bits against the fan prediction; 3: measured levels
inline constexpr std::uint16_t kOldestVersion = 1;
inline constexpr std::size_t kHeaderSize = 100;  // including its CRC

enum Flag : std::uint16_t {
  kQuantised = 1,
  kDracoBase = 2,
  kNormals = 4,
  kUvs = 8,
  kColours = 16,
  kFaceColours = 32,
  kOrder = 64,
};

/// How the base mesh is stored.
enum BaseKind : std::uint8_t { kRawBase = 0, kQuantisedBase = 1, kDracoMeshBase = 2 };

enum Chunk : std::uint8_t {
  kBase = 'B',
  kMeasured = 'M',  // version 3 on, optional, between the base and the first split block
  kSplits = 'S',
  kOrderChunk = 'O',
  kExtras = 'X',
  kEnd = 'E',
};

std::uint32_t crc32(const void* data, std::size_t n, std::uint32_t crc = 0);

/// Appends little-endian values and entropy-coded symbol arrays.
class ByteWriter {
 public:
  template <typename T>
  void put(T value) {
    data_.append(reinterpret_cast<const char*>(&value), sizeof value);
  }
  void put_bytes(std::string_view bytes) { data_.append(bytes); }
  void put_varint(std::uint64_t v) {
    while (v >= 0x80) data_.push_back(static_cast<char>((v & 0x7f) | 0x80)), v >>= 7;
    data_.push_back(static_cast<char>(v));
  }
  /// Count, then the symbols through Draco's rANS coder (adaptive to their distribution).
  void put_symbols(const std::vector<std::uint32_t>& symbols);
  std::string& str() { return data_; }

 private:
  std::string data_;
};

/// Reads what ByteWriter wrote; every read reports failure instead of running past the end.
class ByteReader {
 public:
  ByteReader(const char* data, std::size_t size) : p_(data), end_(data + size) {}
  template <typename T>
  bool get(T& value) {
    if (static_cast<std::size_t>(end_ - p_) < sizeof value) return false;
    std::memcpy(&value, p_, sizeof value);
    p_ += sizeof value;
    return true;
  }
  bool get_bytes(std::size_t n, std::string_view& out) {
    if (static_cast<std::size_t>(end_ - p_) < n) return false;
    out = {p_, n};
    p_ += n;
    return true;
  }
  bool get_varint(std::uint64_t& v) {
    v = 0;
    for (int shift = 0; shift < 64; shift += 7) {
      if (p_ == end_) return false;
      const auto byte = static_cast<std::uint8_t>(*p_++);
      v |= std::uint64_t(byte & 0x7f) << shift;
      if (!(byte & 0x80)) return true;
    }
    return false;
  }
  /// At most `max_count` symbols (a corrupt count must not allocate the moon).
  bool get_symbols(std::vector<std::uint32_t>& out, std::size_t max_count);
  bool at_end() const { return p_ == end_; }

 private:
  const char* p_;
  const char* end_;
};

inline std::uint32_t zigzag(std::int64_t v) { return static_cast<std::uint32_t>((v << 1) ^ (v >> 63)); }
inline std::int64_t unzigzag(std::uint32_t u) { return static_cast<std::int64_t>(u >> 1) ^ -static_cast<std::int64_t>(u & 1); }

/// A uniform grid: value = offset + q * step.
struct Quantiser {
  double offset = 0, step = 1;
  std::int64_t q(double x) const { return std::llround((x - offset) / step); }
  double value(std::int64_t q) const { return offset + static_cast<double>(q) * step; }
};

/// Face colours in quantised mode: channel codes on 2^bits - 1 steps over [0, 1].
inline std::uint32_t face_colour_code(float v, int bits) {
  return static_cast<std::uint32_t>(std::llround(std::clamp(v, 0.f, 1.f) * (std::exp2(bits) - 1)));
}
inline float face_colour_value(std::uint32_t code, int bits) { return static_cast<float>(code / (std::exp2(bits) - 1)); }

/// Error bounds as 16-bit codes on a log scale (2^(1/16) apart, relative to `reference`), rounded up so
/// that the decoded bound is never below the true one. Code 0 is zero.
std::uint16_t error_code(double bound, double reference);
double error_value(std::uint16_t code, double reference);

/// The header's fields.
struct Header {
  std::uint16_t version = kVersion;
  std::uint16_t flags = 0;
  std::uint8_t position_bits = 0, normal_bits = 0, uv_bits = 0, colour_bits = 0;
  std::uint32_t points = 0, wedges = 0, faces = 0, base_points = 0, base_wedges = 0, base_faces = 0, splits = 0;
  std::uint32_t splits_per_block = 0;
  double box_min[3] = {0, 0, 0}, box_max[3] = {0, 0, 0};

  int attribute_dims() const { return 3 * !!(flags & kNormals) + 2 * !!(flags & kUvs) + 4 * !!(flags & kColours); }
  double reference() const {  // the scale of error codes: the box diagonal
    const double d = std::sqrt((box_max[0] - box_min[0]) * (box_max[0] - box_min[0]) +
                               (box_max[1] - box_min[1]) * (box_max[1] - box_min[1]) +
                               (box_max[2] - box_min[2]) * (box_max[2] - box_min[2]));
    return d > 0 ? d : 1.0;
  }
  Quantiser position_quantiser() const;
};

std::string encode_header(const Header& h);
/// False if the bytes are not a header this reader understands; `why` says what is wrong.
bool decode_header(const char* bytes, Header& h, std::string& why);

/// The state both coder sides keep: which faces each point has, the current corners and (quantised
/// mode) the current grid positions and attribute codes.
struct StreamState {
  std::vector<Index> point_first_wedge, point_num_wedges;
  std::vector<std::vector<Index>> point_faces;  // sorted by face number
  std::vector<std::array<Index, 3>> corners;
  std::vector<Index> wedge_point;
  // Current values: positions per point and attributes per wedge (x dims). In quantised mode the
  // grid codes are the truth and the doubles their decoded values.
  int dims = 0;
  bool quantised = false;
  std::vector<Eigen::Vector3d> position;
  std::vector<double> attribute;
  std::vector<std::array<std::int64_t, 3>> qposition;
  std::vector<std::int64_t> qattribute;
  Quantiser position_quantiser;
  std::vector<Quantiser> attribute_quantiser;  // per dimension
  std::uint16_t error_code = 0;                // of the current level's bound

  Index num_points() const { return static_cast<Index>(point_first_wedge.size()); }
  Index num_wedges() const { return static_cast<Index>(wedge_point.size()); }
  Index num_faces() const { return static_cast<Index>(corners.size()); }
  void add_point(Index num_wedges);
  void add_face(const std::array<Index, 3>& c);
  /// The other points of p's faces, sorted.
  void neighbours(Index p, std::vector<Index>& out) const;
  int corner_of(Index face, Index point) const {
    for (int k = 0; k < 3; ++k)
      if (wedge_point[static_cast<std::size_t>(corners[static_cast<std::size_t>(face)][k])] == point) return k;
    return -1;
  }
  /// Moves corner (face, k) from point `from` to wedge w of point `to`.
  void move_corner(Index face, int k, Index w, Index from, Index to);
};

/// Entropy-coded symbol arrays of a split block, one per kind of value.
enum Stream {
  kPoint,                 // the split point
  kWedgeCount,            // the new point's wedges
  kFaceCount,             // new faces (1 or 2)
  kShape,                 // per new face: where the new and split points sit among its corners (0..5)
  kWedgeIndex,            // per new face: new, split and third corner's wedge within its point
  kThird,                 // per new face: the third point as an index into the split point's ring
  kEscape,                // values that did not fit the predictions (raw)
  kChangeBit,             // per face of the split point: does its corner move, XOR the fan prediction
  kChangeWedge,           // per moved corner: 0 = the wedge paired in the new faces, else 1 + index
  kResidualNew,           // quantised: new point minus the split point's coarse position
  kResidualSplit,         // quantised: split point's fine position minus its prediction
  kAttribute,             // quantised: new wedges' attributes minus their parent's
  kAttributeChangeCount,  // per split: wedges of the split point whose attributes change
  kAttributeChangeWedge,  // their index within the split point's wedges
  kAttributeChange,       // quantised: fine minus coarse attribute codes
  kFaceColour,            // quantised: new faces' colour codes
  kErrorDelta,            // how much finer the level's error code is than the last
  kStreamCount
};

/// One split as the coder sees it: what the decoder learns before applying it.
struct SplitRecord {
  Index point = 0, num_wedges = 0, num_faces = 0;
  std::array<std::array<Index, 3>, 2> faces{};  // corners' wedges of the new faces
  std::vector<std::array<Index, 3>> changes;    // (face, corner, fine wedge) in face order
  Eigen::Vector3d fine_position{0, 0, 0}, new_position{0, 0, 0};
  std::array<std::int64_t, 3> qfine{}, qnew{};
  std::vector<double> new_attributes;                // num_wedges x dims
  std::vector<std::int64_t> qnew_attributes;
  std::vector<Index> attribute_wedges;               // changed wedges of the split point
  std::vector<double> attribute_values;              // their fine values (x dims)
  std::vector<std::int64_t> qattribute_values;
  std::array<Eigen::Vector4f, 2> face_colours{};
  std::uint16_t error = 0;                           // code of the level this split produces
};

/// Both are asked before the split is applied, when the new point's wedges are those numbered from
/// st.num_wedges() on. The new point's wedge paired with the split point's wedge `coarse` in a new
/// face (-1 if none): where a moved corner that used `coarse` goes.
Index paired_fine_wedge(const SplitRecord& r, const StreamState& st, Index coarse);
/// The split point's wedge a new wedge splits from: its partner in a new face, else the first one.
Index parent_wedge(const SplitRecord& r, const StreamState& st, Index fine);

/// Quantised positions are predicted from the split's connectivity (asked before it is applied): each
/// of the two points at the centroid of its ring after the split (the umbrella rule), where the new
/// point's ring counts the split point at its coarse position and the split point's ring counts the
/// new point at r.qnew. The rings (sorted, no repeats) come from the connectivity alone, so a decoder
/// finds them once, predicts the new point, decodes r.qnew, then predicts the split point.
struct PredictionRings {
  std::vector<Index> new_point, split_point;
};
PredictionRings prediction_rings(const StreamState& st, const SplitRecord& r);
/// Which faces of the split point (in its face order) the new faces say will move to the new point:
/// the fan between the two new faces' third points, counter-clockwise, or from the one new face to
/// the border. All zero where the fan is not simple. Asked before the split is applied, once the new
/// faces are known; the stream's moved-corner bits are the true bits XOR these (version 2 on).
std::vector<char> predicted_moves(const StreamState& st, const SplitRecord& r);
/// The rounded centroid of the ring's quantised positions and `partner`.
std::array<std::int64_t, 3> ring_centroid(const StreamState& st, const std::vector<Index>& ring,
                                          const std::array<std::int64_t, 3>& partner);

/// Applies a split to the state (both coder sides call this).
void apply_split(StreamState& st, const SplitRecord& r);

/// Decodes a base chunk's payload into the state (and into `pm`, when given). False, with `why`, if
/// the payload is malformed.
bool decode_base(std::string_view payload, const Header& h, StreamState& st, ProgressiveMesh* pm, std::string& why);

}  // namespace lodkit::detail::pm
