#include "progressive/pm_stream.h"

#include <algorithm>
#include <draco/compression/config/compression_shared.h>
#include <draco/compression/entropy/symbol_decoding.h>
#include <draco/compression/entropy/symbol_encoding.h>
#include <draco/core/decoder_buffer.h>
#include <draco/core/encoder_buffer.h>
#include <zlib.h>

namespace lodkit::detail::pm {

std::uint32_t crc32(const void* data, std::size_t n, std::uint32_t crc) {
  const auto* p = static_cast<const Bytef*>(data);
  uLong c = crc;
  while (n > 0) {  // zlib takes uInt lengths
    const uInt chunk = static_cast<uInt>(std::min<std::size_t>(n, 1u << 30));
    c = ::crc32(c, p, chunk);
    p += chunk;
    n -= chunk;
  }
  return static_cast<std::uint32_t>(c);
}

void ByteWriter::put_symbols(const std::vector<std::uint32_t>& symbols) {
  put_varint(symbols.size());
  if (symbols.empty()) return;
  draco::EncoderBuffer buffer;
  if (!draco::EncodeSymbols(symbols.data(), static_cast<int>(symbols.size()), 1, nullptr, &buffer))
    throw std::runtime_error("entropy coder failed");
  put_varint(buffer.size());
  data_.append(buffer.data(), buffer.size());
}

bool ByteReader::get_symbols(std::vector<std::uint32_t>& out, std::size_t max_count) {
  std::uint64_t count = 0, bytes = 0;
  if (!get_varint(count) || count > max_count) return false;
  out.assign(static_cast<std::size_t>(count), 0);
  if (count == 0) return true;
  std::string_view data;
  if (!get_varint(bytes) || !get_bytes(static_cast<std::size_t>(bytes), data)) return false;
  draco::DecoderBuffer buffer;
  // The symbol format of Draco's bitstream 2.2 (the decoder needs a version to pick it).
  buffer.Init(data.data(), data.size(), DRACO_BITSTREAM_VERSION(2, 2));
  return draco::DecodeSymbols(static_cast<std::uint32_t>(count), 1, &buffer, out.data());
}

namespace {
constexpr int kCodeSteps = 16;     // codes per doubling
constexpr int kCodeZero = 2048;    // code offset: codes reach 2^-128 of the reference
}  // namespace

double error_value(std::uint16_t code, double reference) {
  if (code == 0) return 0.0;
  return reference * std::exp2(static_cast<double>(static_cast<int>(code) - 1 - kCodeZero) / kCodeSteps);
}

std::uint16_t error_code(double bound, double reference) {
  if (!(bound > 0)) return 0;
  // (Clamped as a double: the code of a bound far past the reference is not an int.)
  const double scaled = std::ceil(std::log2(bound / reference) * kCodeSteps) + kCodeZero + 1;
  int code = scaled >= 65535 ? 65535 : scaled >= 1 ? static_cast<int>(scaled) : 1;
  while (code < 65535 && error_value(static_cast<std::uint16_t>(code), reference) < bound) ++code;
  return static_cast<std::uint16_t>(code);
}

Quantiser Header::position_quantiser() const {
  double extent = 0;
  for (int i = 0; i < 3; ++i) extent = std::max(extent, box_max[i] - box_min[i]);
  const double cells = std::exp2(position_bits) - 1;
  return {0.0, extent > 0 && cells > 0 ? extent / cells : 1.0};
}

std::string encode_header(const Header& h) {
  ByteWriter w;
  w.put_bytes({kMagic, sizeof kMagic});
  w.put(kVersion);
  w.put(h.flags);
  w.put(h.position_bits), w.put(h.normal_bits), w.put(h.uv_bits), w.put(h.colour_bits);
  for (std::uint32_t v : {h.points, h.wedges, h.faces, h.base_points, h.base_wedges, h.base_faces, h.splits, h.splits_per_block})
    w.put(v);
  for (double v : h.box_min) w.put(v);
  for (double v : h.box_max) w.put(v);
  w.put(crc32(w.str().data(), w.str().size()));
  return w.str();
}

bool decode_header(const char* bytes, Header& h, std::string& why) {
  if (std::memcmp(bytes, kMagic, sizeof kMagic) != 0) {
    why = "not a lodkit progressive mesh (bad magic number; a mesh becomes one through lodkit pm build)";
    return false;
  }
  ByteReader r(bytes + sizeof kMagic, kHeaderSize - sizeof kMagic);
  std::uint16_t version = 0;
  r.get(version);
  if (version < kOldestVersion || version > kVersion) {
    why = "unsupported .pm version " + std::to_string(version) + " (this reader knows " + std::to_string(kOldestVersion) +
          " to " + std::to_string(kVersion) + ")";
    return false;
  }
  h.version = version;
  r.get(h.flags);
  r.get(h.position_bits), r.get(h.normal_bits), r.get(h.uv_bits), r.get(h.colour_bits);
  for (std::uint32_t* v : {&h.points, &h.wedges, &h.faces, &h.base_points, &h.base_wedges, &h.base_faces, &h.splits,
                           &h.splits_per_block})
    r.get(*v);
  for (double& v : h.box_min) r.get(v);
  for (double& v : h.box_max) r.get(v);
  std::uint32_t crc = 0;
  r.get(crc);
  if (crc != crc32(bytes, kHeaderSize - 4)) {
    why = "header checksum mismatch (damaged header)";
    return false;
  }
  const bool quantised = h.flags & kQuantised;
  if (quantised != (h.position_bits > 0) || h.position_bits > 30 || h.normal_bits > 30 || h.uv_bits > 30 ||
      h.colour_bits > 30 || h.splits_per_block == 0 || h.points != h.base_points + h.splits ||
      h.base_wedges > h.wedges || h.base_faces > h.faces || h.base_points > h.base_wedges) {
    why = "inconsistent header fields";
    return false;
  }
  for (int i = 0; i < 3; ++i)
    if (!(std::abs(h.box_min[i]) <= kLargestCoordinate) || !(std::abs(h.box_max[i]) <= kLargestCoordinate)) {
      why = "a bounding box in the header that is not finite or lies beyond the range of a float";
      return false;
    }
  return true;
}

void StreamState::add_point(Index num_wedges) {
  const Index p = num_points();
  point_first_wedge.push_back(this->num_wedges());
  point_num_wedges.push_back(num_wedges);
  point_faces.emplace_back();
  for (Index i = 0; i < num_wedges; ++i) wedge_point.push_back(p);
}

void StreamState::add_face(const std::array<Index, 3>& c) {
  const Index f = num_faces();
  corners.push_back(c);
  for (Index w : c) {
    auto& list = point_faces[static_cast<std::size_t>(wedge_point[static_cast<std::size_t>(w)])];
    if (list.empty() || list.back() != f) list.push_back(f);
  }
}

void StreamState::neighbours(Index p, std::vector<Index>& out) const {
  out.clear();
  for (Index f : point_faces[static_cast<std::size_t>(p)])
    for (Index w : corners[static_cast<std::size_t>(f)]) {
      const Index q = wedge_point[static_cast<std::size_t>(w)];
      if (q != p) out.push_back(q);
    }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
}

void StreamState::move_corner(Index face, int k, Index w, Index from, Index to) {
  corners[static_cast<std::size_t>(face)][k] = w;
  auto& a = point_faces[static_cast<std::size_t>(from)];
  if (corner_of(face, from) < 0) a.erase(std::lower_bound(a.begin(), a.end(), face));
  auto& b = point_faces[static_cast<std::size_t>(to)];
  const auto at = std::lower_bound(b.begin(), b.end(), face);
  if (at == b.end() || *at != face) b.insert(at, face);
}

}  // namespace lodkit::detail::pm

namespace lodkit::detail::pm {

namespace {
/// The point of wedge w before the split is applied (new wedges belong to the new point).
Index point_before(const StreamState& st, Index w, Index t) {
  return w >= st.num_wedges() ? t : st.wedge_point[static_cast<std::size_t>(w)];
}

/// New face i's wedges of the split point and of the new point (-1 where missing).
std::pair<Index, Index> split_and_new_wedge(const SplitRecord& r, const StreamState& st, Index i) {
  const Index t = st.num_points();
  Index ws = -1, wt = -1;
  for (Index w : r.faces[static_cast<std::size_t>(i)]) {
    const Index p = point_before(st, w, t);
    if (p == t) wt = w;
    else if (p == r.point) ws = w;
  }
  return {ws, wt};
}
}  // namespace

Index paired_fine_wedge(const SplitRecord& r, const StreamState& st, Index coarse) {
  for (Index i = 0; i < r.num_faces; ++i) {
    const auto [ws, wt] = split_and_new_wedge(r, st, i);
    if (ws == coarse && wt >= 0) return wt;
  }
  return -1;
}

Index parent_wedge(const SplitRecord& r, const StreamState& st, Index fine) {
  for (Index i = 0; i < r.num_faces; ++i) {
    const auto [ws, wt] = split_and_new_wedge(r, st, i);
    if (wt == fine && ws >= 0) return ws;
  }
  return st.point_first_wedge[static_cast<std::size_t>(r.point)];
}

PredictionRings prediction_rings(const StreamState& st, const SplitRecord& r) {
  const Index s = r.point, t = st.num_points();
  PredictionRings rings;
  auto add_points_of = [&](const std::array<Index, 3>& corners, std::vector<Index>& ring) {
    for (Index w : corners) {
      const Index p = point_before(st, w, t);
      if (p != s && p != t) ring.push_back(p);
    }
  };
  for (Index i = 0; i < r.num_faces; ++i) {
    add_points_of(r.faces[static_cast<std::size_t>(i)], rings.new_point);
    add_points_of(r.faces[static_cast<std::size_t>(i)], rings.split_point);
  }
  std::size_t moved = 0;  // changes are in face order, like s's face list
  for (Index f : st.point_faces[static_cast<std::size_t>(s)]) {
    const bool to_t = moved < r.changes.size() && r.changes[moved][0] == f;
    moved += to_t;
    add_points_of(st.corners[static_cast<std::size_t>(f)], to_t ? rings.new_point : rings.split_point);
  }
  for (std::vector<Index>* ring : {&rings.new_point, &rings.split_point}) {
    std::sort(ring->begin(), ring->end());
    ring->erase(std::unique(ring->begin(), ring->end()), ring->end());
  }
  return rings;
}

std::vector<char> predicted_moves(const StreamState& st, const SplitRecord& r) {
  const Index s = r.point, t = st.num_points();
  const std::vector<Index>& faces = st.point_faces[static_cast<std::size_t>(s)];
  std::vector<char> moved(faces.size(), 0);
  // Where the moving arc starts and ends: a new face (s, x, t) in counter-clockwise order spans x -> t
  // around s, so x starts the arc; (s, t, x) ends it at x.
  Index start = -1, end = -1;
  for (Index i = 0; i < r.num_faces; ++i) {
    const auto& c = r.faces[static_cast<std::size_t>(i)];
    for (int k = 0; k < 3; ++k) {
      if (point_before(st, c[k], t) != s) continue;
      const Index next = point_before(st, c[(k + 1) % 3], t), after = point_before(st, c[(k + 2) % 3], t);
      if (after == t) start = next;
      else if (next == t) end = after;
    }
  }
  // s's faces as (s, a, b) counter-clockwise: a face spans a -> b around s.
  std::vector<std::pair<Index, Index>> spans(faces.size());
  for (std::size_t i = 0; i < faces.size(); ++i) {
    const auto& c = st.corners[static_cast<std::size_t>(faces[i])];
    const int k = st.corner_of(faces[i], s);
    spans[i] = {st.wedge_point[static_cast<std::size_t>(c[(k + 1) % 3])], st.wedge_point[static_cast<std::size_t>(c[(k + 2) % 3])]};
  }
  auto find = [&](Index p, bool from) -> std::ptrdiff_t {
    std::ptrdiff_t hit = -1;
    for (std::size_t i = 0; i < spans.size(); ++i)
      if ((from ? spans[i].first : spans[i].second) == p) {
        if (hit >= 0) return -2;  // not a simple fan: no prediction
        hit = static_cast<std::ptrdiff_t>(i);
      }
    return hit;
  };
  // Walk counter-clockwise from `start` to `end`, or from the one known end to the border.
  const bool forward = start >= 0;
  Index at = forward ? start : end;
  if (at < 0) return moved;
  for (std::size_t steps = 0; steps < faces.size(); ++steps) {
    if (at == (forward ? end : start) && steps > 0) return moved;
    const std::ptrdiff_t i = find(at, forward);
    if (i == -2) return std::vector<char>(faces.size(), 0);
    if (i < 0) break;  // reached the border
    moved[static_cast<std::size_t>(i)] = 1;
    at = forward ? spans[static_cast<std::size_t>(i)].second : spans[static_cast<std::size_t>(i)].first;
  }
  // Only a walk that ends where the other new face says (or at the border, with one new face) is a prediction.
  const bool closed = start >= 0 && end >= 0;
  if (closed && at != end) return std::vector<char>(faces.size(), 0);
  return moved;
}

std::array<std::int64_t, 3> ring_centroid(const StreamState& st, const std::vector<Index>& ring,
                                          const std::array<std::int64_t, 3>& partner) {
  std::array<std::int64_t, 3> out{};
  for (int d = 0; d < 3; ++d) {
    std::int64_t sum = partner[d];
    for (Index p : ring) sum += st.qposition[static_cast<std::size_t>(p)][d];
    out[d] = static_cast<std::int64_t>(std::llround(static_cast<double>(sum) / static_cast<double>(ring.size() + 1)));
  }
  return out;
}

void apply_split(StreamState& st, const SplitRecord& r) {
  const std::size_t dims = static_cast<std::size_t>(st.dims);
  const Index s = r.point, t = st.num_points();
  st.add_point(r.num_wedges);
  if (st.quantised) {
    st.qposition.push_back(r.qnew);
    st.qposition[static_cast<std::size_t>(s)] = r.qfine;
    Eigen::Vector3d fine, fresh;
    for (int d = 0; d < 3; ++d)
      fine[d] = st.position_quantiser.value(r.qfine[d]), fresh[d] = st.position_quantiser.value(r.qnew[d]);
    st.position.push_back(fresh);
    st.position[static_cast<std::size_t>(s)] = fine;
    st.qattribute.insert(st.qattribute.end(), r.qnew_attributes.begin(), r.qnew_attributes.end());
    for (std::size_t i = 0; i < r.qnew_attributes.size(); ++i)
      st.attribute.push_back(st.attribute_quantiser[i % dims].value(r.qnew_attributes[i]));
    for (std::size_t i = 0; i < r.attribute_wedges.size(); ++i)
      for (std::size_t d = 0; d < dims; ++d) {
        const std::size_t at = dims * static_cast<std::size_t>(r.attribute_wedges[i]) + d;
        st.qattribute[at] = r.qattribute_values[dims * i + d];
        st.attribute[at] = st.attribute_quantiser[d].value(st.qattribute[at]);
      }
  } else {
    st.position.push_back(r.new_position);
    st.position[static_cast<std::size_t>(s)] = r.fine_position;
    st.attribute.insert(st.attribute.end(), r.new_attributes.begin(), r.new_attributes.end());
    for (std::size_t i = 0; i < r.attribute_wedges.size(); ++i)
      std::copy_n(&r.attribute_values[dims * i], dims, &st.attribute[dims * static_cast<std::size_t>(r.attribute_wedges[i])]);
  }
  for (const auto& [f, k, w] : r.changes) st.move_corner(f, k, w, s, t);
  for (Index i = 0; i < r.num_faces; ++i) st.add_face(r.faces[static_cast<std::size_t>(i)]);
}

}  // namespace lodkit::detail::pm
