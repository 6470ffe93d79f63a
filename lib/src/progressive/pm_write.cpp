// The .pm writer. Every split is coded against the decoder state (StreamState) that the reader will
// have at that point, and then applied to it with the reader's own apply_split().
#include <lodkit/error.h>
#include <lodkit/pm_io.h>

#include <algorithm>
#include <draco/compression/encode.h>
#include <fmt/format.h>

#include "adapters/draco_adapter.h"
#include "io/output.h"
#include "progressive/pm_stream.h"

namespace lodkit {
namespace {

using namespace detail::pm;

void put_chunk(std::string& out, Chunk type, const std::string& payload) {
  std::string head(1, static_cast<char>(type));
  const auto n = static_cast<std::uint32_t>(payload.size());
  head.append(reinterpret_cast<const char*>(&n), 4);
  std::uint32_t crc = crc32(head.data(), head.size());
  crc = crc32(payload.data(), payload.size(), crc);
  out += head;
  out += payload;
  out.append(reinterpret_cast<const char*>(&crc), 4);
}

/// Per-dimension attribute grids: normals over [-1, 1], UVs over their range, colours over [0, 1].
std::vector<Quantiser> attribute_quantisers(const ProgressiveMesh& pm, const PmWriteOptions& o) {
  std::vector<Quantiser> q;
  auto cells = [](int bits) { return std::exp2(bits) - 1; };
  if (pm.has_normals)
    for (int d = 0; d < 3; ++d) q.push_back({-1.0, 2.0 / cells(o.normal_bits)});
  if (pm.has_uvs) {
    const int base = 3 * pm.has_normals;
    for (int d = 0; d < 2; ++d) {
      double lo = 0, hi = 0;
      bool first = true;
      auto see = [&](double v) {
        lo = first ? v : std::min(lo, v), hi = first ? v : std::max(hi, v);
        first = false;
      };
      const std::size_t dims = static_cast<std::size_t>(pm.attribute_dims);
      for (std::size_t i = base + d; i < pm.wedge_attributes.size(); i += dims) see(pm.wedge_attributes[i]);
      for (std::size_t i = base + d; i < pm.attribute_values.size(); i += dims) see(pm.attribute_values[i]);
      q.push_back({lo, hi > lo ? (hi - lo) / cells(o.uv_bits) : 1.0});
    }
  }
  if (pm.has_colours)
    for (int d = 0; d < 4; ++d) q.push_back({0.0, 1.0 / cells(o.colour_bits)});
  return q;
}

std::string encode_base(const ProgressiveMesh& pm, const Header& h, const std::vector<Quantiser>& aq, int kind,
                        const PmWriteOptions& o) {
  const std::size_t dims = static_cast<std::size_t>(pm.attribute_dims);
  const Quantiser pq = h.position_quantiser();
  ByteWriter b;
  for (const Quantiser& q : aq) b.put(q.offset), b.put(q.step);
  b.put(static_cast<std::uint8_t>(kind));
  std::vector<std::uint32_t> wedges_per_point(static_cast<std::size_t>(pm.base_points), 0);
  for (Index w = 0; w < pm.base_wedges; ++w) ++wedges_per_point[static_cast<std::size_t>(pm.wedge_point[w])];
  b.put_symbols(wedges_per_point);
  std::vector<std::uint32_t> faces;
  for (Index f = 0; f < pm.base_faces; ++f)
    for (Index w : pm.face_corners[f]) faces.push_back(static_cast<std::uint32_t>(w));
  std::vector<std::uint32_t> colour_codes;
  if (pm.has_face_colours && kind != 0)
    for (Index f = 0; f < pm.base_faces; ++f)
      for (int c = 0; c < 4; ++c) colour_codes.push_back(face_colour_code(pm.face_colours(f, c), o.colour_bits));

  if (kind == kRawBase) {
    for (const Eigen::Vector3d& p : pm.base_positions) b.put(p.x()), b.put(p.y()), b.put(p.z());
    for (std::size_t i = 0; i < dims * static_cast<std::size_t>(pm.base_wedges); ++i) b.put(pm.wedge_attributes[i]);
    b.put_symbols(faces);
    if (pm.has_face_colours)
      for (Index f = 0; f < pm.base_faces; ++f)
        for (int c = 0; c < 4; ++c) b.put(pm.face_colours(f, c));
  } else if (kind == kQuantisedBase) {
    std::vector<std::uint32_t> pos, attr;
    std::array<std::int64_t, 3> last{0, 0, 0};
    for (const Eigen::Vector3d& p : pm.base_positions)
      for (int d = 0; d < 3; ++d) {
        const std::int64_t q = pq.q(p[d]);
        pos.push_back(zigzag(q - last[d]));
        last[d] = q;
      }
    std::vector<std::int64_t> last_attr(dims, 0);
    for (Index w = 0; w < pm.base_wedges; ++w)
      for (std::size_t d = 0; d < dims; ++d) {
        const std::int64_t q = aq[d].q(pm.wedge_attributes[dims * w + d]);
        attr.push_back(zigzag(q - last_attr[d]));
        last_attr[d] = q;
      }
    b.put_symbols(pos);
    b.put_symbols(attr);
    b.put_symbols(faces);
    b.put_symbols(colour_codes);
  } else {  // Draco, sequential connectivity so that wedge and face numbers survive
    Mesh base;
    base.positions.resize(pm.base_wedges, 3);
    base.triangles.resize(pm.base_faces, 3);
    if (pm.has_normals) base.attributes.normals.resize(pm.base_wedges, 3);
    if (pm.has_uvs) base.attributes.uvs.resize(pm.base_wedges, 2);
    if (pm.has_colours) base.attributes.colours.resize(pm.base_wedges, 4);
    for (Index w = 0; w < pm.base_wedges; ++w) {
      base.positions.row(w) = pm.base_positions[static_cast<std::size_t>(pm.wedge_point[w])].transpose();
      std::size_t i = dims * w;
      if (pm.has_normals) for (int d = 0; d < 3; ++d) base.attributes.normals(w, d) = pm.wedge_attributes[i++];
      if (pm.has_uvs) for (int d = 0; d < 2; ++d) base.attributes.uvs(w, d) = pm.wedge_attributes[i++];
      if (pm.has_colours) for (int d = 0; d < 4; ++d) base.attributes.colours(w, d) = static_cast<float>(pm.wedge_attributes[i++]);
    }
    for (Index f = 0; f < pm.base_faces; ++f)
      for (int k = 0; k < 3; ++k) base.triangles(f, k) = pm.face_corners[f][k];
    if (!detail::draco_range_problem(base, {}, {}).empty()) return {};  // (positions, normals and UVs quantised)
    const auto dm = detail::to_draco(base);
    draco::Encoder encoder;
    encoder.SetEncodingMethod(draco::MESH_SEQUENTIAL_ENCODING);
    const int speed = 10 - std::clamp(o.draco_compression_level, 0, 10);
    encoder.SetSpeedOptions(speed, speed);
    encoder.SetAttributeQuantization(draco::GeometryAttribute::POSITION, o.position_bits);
    if (pm.has_normals) encoder.SetAttributeQuantization(draco::GeometryAttribute::NORMAL, o.normal_bits);
    if (pm.has_uvs) encoder.SetAttributeQuantization(draco::GeometryAttribute::TEX_COORD, o.uv_bits);
    draco::EncoderBuffer buffer;
    if (!encoder.EncodeMeshToBuffer(*dm, &buffer).ok()) return {};
    b.put_varint(buffer.size());
    b.put_bytes({buffer.data(), buffer.size()});
    b.put_symbols(colour_codes);
  }
  b.put(error_code(pm.level_error[0], h.reference()));
  return std::move(b.str());
}

/// Codes split j against the state; returns its record (the values the decoder will reconstruct).
SplitRecord code_split(const ProgressiveMesh& pm, std::size_t j, const StreamState& st, const PmWriteOptions& o,
                       std::array<std::vector<std::uint32_t>, kStreamCount>& out, ByteWriter& raw,
                       std::vector<std::uint32_t>& residual_alt, std::uint16_t& last_code, double reference,
                       bool rotate_new_faces) {
  const VertexSplit& vs = pm.splits[j];
  const std::size_t dims = static_cast<std::size_t>(pm.attribute_dims);
  const Index s = vs.point, t = st.num_points();
  SplitRecord r;
  r.point = s;
  r.num_wedges = vs.num_wedges;
  r.num_faces = vs.num_faces;
  out[kPoint].push_back(static_cast<std::uint32_t>(s));
  out[kWedgeCount].push_back(static_cast<std::uint32_t>(vs.num_wedges));
  out[kFaceCount].push_back(static_cast<std::uint32_t>(vs.num_faces));
  if (vs.num_faces < 1 || vs.num_faces > 2) throw Error(fmt::format("split {} has {} new faces; the stream holds 1 or 2", j, vs.num_faces));

  std::vector<Index> ring;
  st.neighbours(s, ring);
  auto point_of = [&](Index w) { return pm.wedge_point[static_cast<std::size_t>(w)]; };
  auto first_wedge = [&](Index p) { return p == t ? vs.first_wedge : st.point_first_wedge[static_cast<std::size_t>(p)]; };
  for (Index i = 0; i < vs.num_faces; ++i) {
    std::array<Index, 3> c = pm.face_corners[static_cast<std::size_t>(vs.first_face + i)];
    int pt = -1, ps = -1, px = -1;
    for (int k = 0; k < 3; ++k) {
      const Index p = point_of(c[k]);
      if (p == t) pt = k;
      else if (p == s) ps = k;
      else px = k;
    }
    if (rotate_new_faces && pt > 0) {
      // Without the input order a face's first corner is free: start at the new point (fewer bits).
      std::rotate(c.begin(), c.begin() + pt, c.end());
      ps = (ps - pt + 3) % 3, px = (px - pt + 3) % 3, pt = 0;
    }
    r.faces[i] = c;
    if (pt < 0 || ps < 0 || px < 0) throw Error(fmt::format("split {}: a new face does not join the two points and a third", j));
    out[kShape].push_back(static_cast<std::uint32_t>(2 * pt + (ps == (pt + 1) % 3)));
    const Index third = point_of(c[px]);
    out[kWedgeIndex].push_back(static_cast<std::uint32_t>(c[pt] - first_wedge(t)));
    out[kWedgeIndex].push_back(static_cast<std::uint32_t>(c[ps] - first_wedge(s)));
    out[kWedgeIndex].push_back(static_cast<std::uint32_t>(c[px] - first_wedge(third)));
    const auto at = std::lower_bound(ring.begin(), ring.end(), third);
    if (at != ring.end() && *at == third) {
      out[kThird].push_back(static_cast<std::uint32_t>(at - ring.begin()));
    } else {
      out[kThird].push_back(static_cast<std::uint32_t>(ring.size()));
      out[kEscape].push_back(static_cast<std::uint32_t>(third));
    }
  }
  // Moved corners: one bit per face of s, in face order.
  const CornerChange* changes = pm.corner_changes.data() + vs.first_change;
  const std::vector<char> predicted = predicted_moves(st, r);
  std::size_t face_index = 0;
  for (Index f : st.point_faces[static_cast<std::size_t>(s)]) {
    const CornerChange* c = std::find_if(changes, changes + vs.num_changes, [&](const CornerChange& x) { return x.corner / 3 == f; });
    out[kChangeBit].push_back((c != changes + vs.num_changes) != (predicted[face_index++] != 0));
    if (c == changes + vs.num_changes) continue;
    r.changes.push_back({f, st.corner_of(f, s), c->fine_wedge});
    const Index paired = paired_fine_wedge(r, st, c->coarse_wedge);
    out[kChangeWedge].push_back(paired == c->fine_wedge ? 0u : static_cast<std::uint32_t>(1 + c->fine_wedge - vs.first_wedge));
  }
  if (static_cast<Index>(r.changes.size()) != vs.num_changes)
    throw Error(fmt::format("split {}: a moved corner is not on a face of the split point", j));

  // Positions.
  if (st.quantised) {
    const Quantiser& q = st.position_quantiser;
    const auto& coarse = st.qposition[static_cast<std::size_t>(s)];
    for (int d = 0; d < 3; ++d) r.qnew[d] = q.q(vs.new_position[d]), r.qfine[d] = q.q(vs.position[d]);
    const PredictionRings rings = prediction_rings(st, r);
    const auto predicted_new = ring_centroid(st, rings.new_point, coarse);
    const auto predicted_split = ring_centroid(st, rings.split_point, r.qnew);
    for (int d = 0; d < 3; ++d) {
      out[kResidualNew].push_back(zigzag(r.qnew[d] - coarse[d]));
      out[kResidualSplit].push_back(zigzag(r.qfine[d] - coarse[d]));
      residual_alt.push_back(zigzag(r.qnew[d] - predicted_new[d]));
      residual_alt.push_back(zigzag(r.qfine[d] - predicted_split[d]));
    }
  } else {
    r.fine_position = vs.position;
    r.new_position = vs.new_position;
    for (int d = 0; d < 3; ++d) raw.put(vs.position[d]);
    for (int d = 0; d < 3; ++d) raw.put(vs.new_position[d]);
  }
  // The new wedges' attributes, against the wedge each splits from.
  for (Index i = 0; i < vs.num_wedges; ++i) {
    const Index w = vs.first_wedge + i;
    const Index parent = parent_wedge(r, st, w);
    for (std::size_t d = 0; d < dims; ++d) {
      const double v = pm.wedge_attributes[dims * static_cast<std::size_t>(w) + d];
      if (st.quantised) {
        const std::int64_t qv = st.attribute_quantiser[d].q(v);
        r.qnew_attributes.push_back(qv);
        out[kAttribute].push_back(zigzag(qv - st.qattribute[dims * static_cast<std::size_t>(parent) + d]));
      } else {
        r.new_attributes.push_back(v);
        raw.put(v);
      }
    }
  }
  out[kAttributeChangeCount].push_back(static_cast<std::uint32_t>(vs.num_attribute_changes));
  for (Index i = 0; i < vs.num_attribute_changes; ++i) {
    const AttributeChange& a = pm.attribute_changes[static_cast<std::size_t>(vs.first_attribute_change + i)];
    if (pm.wedge_point[static_cast<std::size_t>(a.wedge)] != s) throw Error(fmt::format("split {}: an attribute change off the split point", j));
    r.attribute_wedges.push_back(a.wedge);
    out[kAttributeChangeWedge].push_back(static_cast<std::uint32_t>(a.wedge - st.point_first_wedge[static_cast<std::size_t>(s)]));
    for (std::size_t d = 0; d < dims; ++d) {
      const double v = pm.attribute_values[static_cast<std::size_t>(a.first_value) + dims + d];
      if (st.quantised) {
        const std::int64_t qv = st.attribute_quantiser[d].q(v);
        r.qattribute_values.push_back(qv);
        out[kAttributeChange].push_back(zigzag(qv - st.qattribute[dims * static_cast<std::size_t>(a.wedge) + d]));
      } else {
        r.attribute_values.push_back(v);
        raw.put(v);
      }
    }
  }
  if (pm.has_face_colours)
    for (Index i = 0; i < vs.num_faces; ++i)
      for (int c = 0; c < 4; ++c) {
        const float v = pm.face_colours(vs.first_face + i, c);
        if (st.quantised) {
          const std::uint32_t code = face_colour_code(v, o.colour_bits);
          out[kFaceColour].push_back(code);
          r.face_colours[i][c] = face_colour_value(code, o.colour_bits);
        } else {
          r.face_colours[i][c] = v;
          raw.put(v);
        }
      }
  r.error = error_code(pm.level_error[j + 1], reference);
  out[kErrorDelta].push_back(zigzag(std::int64_t(last_code) - std::int64_t(r.error)));
  last_code = r.error;
  return r;
}

}  // namespace

std::string write_pm_to_memory(const ProgressiveMesh& pm, const PmWriteOptions& o, PmStreamStats* stats_out) {
  validate(pm, "write_pm");
  if (o.position_bits < 0 || o.position_bits > 30) throw Error(fmt::format("write_pm: position bits must be 0 (lossless) to 30, got {}", o.position_bits));
  for (int bits : {o.normal_bits, o.uv_bits, o.colour_bits})
    if (bits < 1 || bits > 30) throw Error(fmt::format("write_pm: attribute bits must be 1 to 30, got {}", bits));
  if (o.splits_per_block < 1) throw Error("write_pm: splits per block must be at least 1");
  if (o.draco_base && o.position_bits == 0) throw Error("write_pm: a Draco base needs quantised positions (--quantize BITS)");
  if (o.draco_compression_level < 0 || o.draco_compression_level > 10)
    throw Error(fmt::format("write_pm: the Draco compression level must be 0 to 10, got {}", o.draco_compression_level));

  Header h;
  const bool quantised = o.position_bits > 0;
  const bool order = o.keep_order.value_or(!quantised) && pm.knows_input_order();
  h.flags = static_cast<std::uint16_t>((quantised ? kQuantised : 0) | (pm.has_normals ? kNormals : 0) |
                                       (pm.has_uvs ? kUvs : 0) | (pm.has_colours ? kColours : 0) |
                                       (pm.has_face_colours ? kFaceColours : 0) | (order ? kOrder : 0));
  h.position_bits = static_cast<std::uint8_t>(o.position_bits);
  h.normal_bits = static_cast<std::uint8_t>(o.normal_bits);
  h.uv_bits = static_cast<std::uint8_t>(o.uv_bits);
  h.colour_bits = static_cast<std::uint8_t>(o.colour_bits);
  h.points = static_cast<std::uint32_t>(pm.num_points(pm.max_level()));
  h.wedges = static_cast<std::uint32_t>(pm.num_wedges(pm.max_level()));
  h.faces = static_cast<std::uint32_t>(pm.num_faces(pm.max_level()));
  h.base_points = static_cast<std::uint32_t>(pm.base_points);
  h.base_wedges = static_cast<std::uint32_t>(pm.base_wedges);
  h.base_faces = static_cast<std::uint32_t>(pm.base_faces);
  h.splits = static_cast<std::uint32_t>(pm.splits.size());
  h.splits_per_block = static_cast<std::uint32_t>(o.splits_per_block);
  if (!pm.bounds.isEmpty())
    for (int d = 0; d < 3; ++d) h.box_min[d] = pm.bounds.min()[d], h.box_max[d] = pm.bounds.max()[d];
  const std::vector<Quantiser> aq = quantised ? attribute_quantisers(pm, o) : std::vector<Quantiser>{};

  // The base, and the decoder state after it (the writer decodes its own base, so both agree).
  StreamState st;
  std::string why;
  int kind = !quantised ? kRawBase : o.draco_base ? kDracoMeshBase : kQuantisedBase;
  std::string base = encode_base(pm, h, aq, kind, o);
  if (kind == kDracoMeshBase) {
    h.flags |= kDracoBase;
    bool same = !base.empty() && decode_base(base, h, st, nullptr, why);
    for (Index f = 0; same && f < pm.base_faces; ++f) same = st.corners[static_cast<std::size_t>(f)] == pm.face_corners[f];
    if (!same) {  // Draco refused the base or renumbered something: fall back to the plain quantised base
      h.flags &= static_cast<std::uint16_t>(~kDracoBase);
      kind = kQuantisedBase;
      base = encode_base(pm, h, aq, kind, o);
      st = {};
    }
  }
  if (st.point_first_wedge.empty() && !decode_base(base, h, st, nullptr, why))
    throw Error("write_pm: internal error: the base does not decode: " + why);

  PmStreamStats stats;
  std::string out = encode_header(h);
  stats.header_bytes = out.size();
  put_chunk(out, kBase, base);
  stats.base_bytes = out.size() - stats.header_bytes;
  if (!pm.measured.empty()) {
    // Before the splits, so that a reader choosing a level by measured error knows where to stop.
    ByteWriter m;
    m.put_varint(pm.measured.size());
    Index previous = 0;
    for (const LevelMeasurement& level : pm.measured) {
      m.put_varint(static_cast<std::uint64_t>(level.level - previous));
      m.put(level.hausdorff);
      m.put(level.rms);
      previous = level.level;
    }
    const std::size_t before = out.size();
    put_chunk(out, kMeasured, m.str());
    stats.measured_bytes = out.size() - before;
  }

  std::uint16_t last_code = error_code(pm.level_error[0], h.reference());
  for (std::size_t first = 0; first < pm.splits.size(); first += static_cast<std::size_t>(o.splits_per_block)) {
    const std::size_t count = std::min(pm.splits.size() - first, static_cast<std::size_t>(o.splits_per_block));
    std::array<std::vector<std::uint32_t>, kStreamCount> streams;
    std::vector<std::uint32_t> alternative;  // residuals against the ring centroids, new and split interleaved
    ByteWriter raw;
    for (std::size_t j = first; j < first + count; ++j) {
      const SplitRecord r = code_split(pm, j, st, o, streams, raw, alternative, last_code, h.reference(), !order);
      apply_split(st, r);
    }
    // Pick the predictor that suits this block: the split point's coarse position for both points
    // (cheap, good for tiny splits), or each point's ring centroid after the split.
    auto cost = [](const std::vector<std::uint32_t>& v) {
      double c = 0;
      for (std::uint32_t x : v) c += std::log2(1.0 + x);
      return c;
    };
    std::uint8_t predictor = 0;
    if (quantised && cost(alternative) < cost(streams[kResidualNew]) + cost(streams[kResidualSplit])) {
      predictor = 1;
      streams[kResidualNew].clear(), streams[kResidualSplit].clear();
      for (std::size_t i = 0; i < alternative.size(); i += 6)
        for (int d = 0; d < 3; ++d) streams[kResidualNew].push_back(alternative[i + 2 * d]), streams[kResidualSplit].push_back(alternative[i + 2 * d + 1]);
    }
    ByteWriter b;
    b.put(static_cast<std::uint32_t>(count));
    b.put(predictor);
    for (const auto& s : streams) b.put_symbols(s);
    b.put_varint(raw.str().size());
    b.put_bytes(raw.str());
    const std::size_t before = out.size();
    put_chunk(out, kSplits, b.str());
    stats.split_bytes += out.size() - before;
    ++stats.split_blocks;
  }
  if (order) {
    ByteWriter b;
    b.put_varint(static_cast<std::uint64_t>(pm.input_vertices));
    b.put_varint(static_cast<std::uint64_t>(pm.input_faces));
    b.put_symbols({pm.wedge_input.begin(), pm.wedge_input.end()});
    b.put_symbols({pm.face_input.begin(), pm.face_input.end()});
    std::size_t before = out.size();
    put_chunk(out, kOrderChunk, b.str());
    stats.order_bytes = out.size() - before;

    ByteWriter x;
    x.put_symbols({pm.extra_vertex_input.begin(), pm.extra_vertex_input.end()});
    for (std::size_t i = 0; i < pm.extra_vertex_input.size(); ++i) {
      const Index row = static_cast<Index>(i);
      for (int d = 0; d < 3; ++d) x.put(pm.extra_vertices.positions(row, d));
      if (pm.has_normals) for (int d = 0; d < 3; ++d) x.put(pm.extra_vertices.attributes.normals(row, d));
      if (pm.has_uvs) for (int d = 0; d < 2; ++d) x.put(pm.extra_vertices.attributes.uvs(row, d));
      if (pm.has_colours) for (int d = 0; d < 4; ++d) x.put(pm.extra_vertices.attributes.colours(row, d));
    }
    x.put_symbols({pm.extra_face_input.begin(), pm.extra_face_input.end()});
    std::vector<std::uint32_t> tri;
    for (Index f = 0; f < pm.extra_faces.rows(); ++f)
      for (int k = 0; k < 3; ++k) tri.push_back(static_cast<std::uint32_t>(pm.extra_faces(f, k)));
    x.put_symbols(tri);
    if (pm.has_face_colours)
      for (Index f = 0; f < pm.extra_faces.rows(); ++f)
        for (int c = 0; c < 4; ++c) x.put(pm.face_colours(pm.num_faces(pm.max_level()) + f, c));
    std::vector<std::uint32_t> exceptions;
    for (const auto& e : pm.corner_exceptions)
      for (Index v : e) exceptions.push_back(static_cast<std::uint32_t>(v));
    x.put_symbols(exceptions);
    before = out.size();
    put_chunk(out, kExtras, x.str());
    stats.extra_bytes = out.size() - before;
  }
  put_chunk(out, kEnd, {});
  stats.total_bytes = out.size();
  if (stats_out) *stats_out = stats;
  return out;
}

PmStreamStats write_pm(const ProgressiveMesh& pm, const std::filesystem::path& path, const PmWriteOptions& options) {
  PmStreamStats stats;
  const std::string bytes = write_pm_to_memory(pm, options, &stats);
  detail::write_file_atomically(path, [&](detail::Output& out) { out.put_bytes(bytes.data(), bytes.size()); });
  return stats;
}

}  // namespace lodkit
