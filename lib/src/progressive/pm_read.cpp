// The .pm reader: chunk by chunk from a file or a buffer, stopping at the face budget, at the end, or
// at the first damaged block (keeping every level before it).
#include <lodkit/error.h>
#include <lodkit/pm_io.h>

#include <algorithm>
#include <cstdio>
#include <draco/compression/decode.h>
#include <fmt/format.h>
#include <memory>

#include "adapters/draco_adapter.h"
#include "io/output.h"
#include "progressive/pm_stream.h"

namespace lodkit {
namespace detail::pm {

namespace {

constexpr std::size_t kMaxSymbols = std::size_t(1) << 31;

/// Appends the state's new values to `pm` as the split the record describes (called before applying);
/// false, appending nothing, when a position lies beyond the range of a float (as for any mesh).
bool append_split(ProgressiveMesh& pm, const StreamState& st, const SplitRecord& r, double error) {
  const std::size_t dims = static_cast<std::size_t>(st.dims);
  VertexSplit v;
  v.point = r.point;
  v.first_wedge = st.num_wedges();
  v.num_wedges = r.num_wedges;
  v.first_face = st.num_faces();
  v.num_faces = r.num_faces;
  v.coarse_position = st.position[static_cast<std::size_t>(r.point)];
  if (st.quantised) {
    for (int d = 0; d < 3; ++d)
      v.position[d] = st.position_quantiser.value(r.qfine[d]), v.new_position[d] = st.position_quantiser.value(r.qnew[d]);
  } else {
    v.position = r.fine_position;
    v.new_position = r.new_position;
  }
  if (!within_coordinate_range(v.position) || !within_coordinate_range(v.new_position)) return false;
  const Index t = st.num_points();
  for (Index i = 0; i < r.num_wedges; ++i) {
    pm.wedge_point.push_back(t);
    pm.wedge_parent.push_back(parent_wedge(r, st, v.first_wedge + i));
  }
  if (st.quantised) {
    for (std::size_t i = 0; i < r.qnew_attributes.size(); ++i)
      pm.wedge_attributes.push_back(st.attribute_quantiser[i % dims].value(r.qnew_attributes[i]));
  } else {
    pm.wedge_attributes.insert(pm.wedge_attributes.end(), r.new_attributes.begin(), r.new_attributes.end());
  }
  for (Index i = 0; i < r.num_faces; ++i) pm.face_corners.push_back(r.faces[static_cast<std::size_t>(i)]);
  v.first_change = static_cast<Index>(pm.corner_changes.size());
  for (const auto& [f, k, w] : r.changes) pm.corner_changes.push_back({3 * f + k, st.corners[static_cast<std::size_t>(f)][k], w});
  v.num_changes = static_cast<Index>(r.changes.size());
  v.first_attribute_change = static_cast<Index>(pm.attribute_changes.size());
  for (std::size_t i = 0; i < r.attribute_wedges.size(); ++i) {
    const std::size_t w = static_cast<std::size_t>(r.attribute_wedges[i]);
    pm.attribute_changes.push_back({r.attribute_wedges[i], static_cast<Index>(pm.attribute_values.size())});
    pm.attribute_values.insert(pm.attribute_values.end(), &st.attribute[dims * w], &st.attribute[dims * w] + dims);
    for (std::size_t d = 0; d < dims; ++d)
      pm.attribute_values.push_back(st.quantised ? st.attribute_quantiser[d].value(r.qattribute_values[dims * i + d])
                                                 : r.attribute_values[dims * i + d]);
  }
  v.num_attribute_changes = static_cast<Index>(r.attribute_wedges.size());
  if (pm.has_face_colours) {
    const Index rows = static_cast<Index>(pm.face_corners.size());
    pm.face_colours.conservativeResize(rows, 4);
    for (Index i = 0; i < r.num_faces; ++i) pm.face_colours.row(rows - r.num_faces + i) = r.face_colours[static_cast<std::size_t>(i)].transpose();
  }
  pm.splits.push_back(v);
  pm.level_error.push_back(error);
  return true;
}

/// Drops every split after `level` (appending is all a block does to `pm`).
void truncate(ProgressiveMesh& pm, Index level) {
  const std::size_t dims = static_cast<std::size_t>(pm.attribute_dims);
  pm.splits.resize(static_cast<std::size_t>(level));
  const auto wedges = static_cast<std::size_t>(pm.num_wedges(level)), faces = static_cast<std::size_t>(pm.num_faces(level));
  pm.wedge_point.resize(wedges);
  pm.wedge_parent.resize(wedges);
  pm.wedge_attributes.resize(dims * wedges);
  pm.face_corners.resize(faces);
  if (pm.has_face_colours) pm.face_colours.conservativeResize(static_cast<Index>(faces), 4);
  const VertexSplit* last = level > 0 ? &pm.splits.back() : nullptr;
  pm.corner_changes.resize(last ? static_cast<std::size_t>(last->first_change + last->num_changes) : 0);
  pm.attribute_changes.resize(last ? static_cast<std::size_t>(last->first_attribute_change + last->num_attribute_changes) : 0);
  pm.attribute_values.resize(pm.attribute_changes.empty() ? 0 : static_cast<std::size_t>(pm.attribute_changes.back().first_value) + 2 * dims);
  pm.level_error.resize(static_cast<std::size_t>(level) + 1);
}

/// Sequential reads over the streams of a block, each failing softly.
struct Cursor {
  const std::vector<std::uint32_t>* v;
  std::size_t at = 0;
  bool next(std::uint32_t& out) {
    if (at >= v->size()) return false;
    out = (*v)[at++];
    return true;
  }
};

}  // namespace

bool decode_base(std::string_view payload, const Header& h, StreamState& st, ProgressiveMesh* pm, std::string& why) {
  auto fail = [&](const char* what) {
    why = what;
    return false;
  };
  ByteReader r(payload.data(), payload.size());
  const int dims = h.attribute_dims();
  st = {};
  st.dims = dims;
  st.quantised = h.flags & kQuantised;
  st.position_quantiser = h.position_quantiser();
  if (st.quantised) {
    for (int d = 0; d < dims; ++d) {
      Quantiser q;
      if (!r.get(q.offset) || !r.get(q.step) || !std::isfinite(q.offset) || !(q.step > 0) || !std::isfinite(q.step))
        return fail("bad attribute quantisation");
      st.attribute_quantiser.push_back(q);
    }
  }
  std::uint8_t kind = 0;
  if (!r.get(kind) || kind > kDracoMeshBase || (kind == kRawBase) == st.quantised || (kind == kDracoMeshBase) != !!(h.flags & kDracoBase))
    return fail("unknown base mesh encoding");
  std::vector<std::uint32_t> per_point;
  if (!r.get_symbols(per_point, h.base_points) || per_point.size() != h.base_points) return fail("bad wedge counts");
  std::uint64_t total = 0;
  for (std::uint32_t n : per_point) total += n;
  if (total != h.base_wedges) return fail("wedge counts do not add up");
  for (std::uint32_t n : per_point) st.add_point(static_cast<Index>(n));

  const std::size_t nw = h.base_wedges, nf = h.base_faces, np = h.base_points;
  std::vector<std::uint32_t> faces, colour_codes;
  std::vector<float> colours;
  if (kind == kRawBase) {
    st.position.resize(np);
    for (auto& p : st.position)
      for (int d = 0; d < 3; ++d)
        if (!r.get(p[d]) || !std::isfinite(p[d])) return fail("bad base positions");
    st.attribute.resize(nw * static_cast<std::size_t>(dims));
    for (double& a : st.attribute)
      if (!r.get(a) || !std::isfinite(a)) return fail("bad base attributes");
    if (!r.get_symbols(faces, 3 * nf)) return fail("bad base faces");
    if (h.flags & kFaceColours) {
      colours.resize(4 * nf);
      for (float& c : colours)
        if (!r.get(c)) return fail("bad base face colours");
    }
  } else if (kind == kQuantisedBase) {
    std::vector<std::uint32_t> pos, attr;
    if (!r.get_symbols(pos, 3 * np) || pos.size() != 3 * np) return fail("bad base positions");
    if (!r.get_symbols(attr, nw * static_cast<std::size_t>(dims)) || attr.size() != nw * static_cast<std::size_t>(dims))
      return fail("bad base attributes");
    if (!r.get_symbols(faces, 3 * nf) || !r.get_symbols(colour_codes, 4 * nf)) return fail("bad base faces");
    std::array<std::int64_t, 3> last{0, 0, 0};
    for (std::size_t p = 0; p < np; ++p) {
      for (int d = 0; d < 3; ++d) last[d] += unzigzag(pos[3 * p + d]);
      st.qposition.push_back(last);
    }
    std::vector<std::int64_t> last_attr(static_cast<std::size_t>(dims), 0);
    for (std::size_t i = 0; i < attr.size(); ++i) {
      last_attr[i % dims] += unzigzag(attr[i]);
      st.qattribute.push_back(last_attr[i % dims]);
    }
  } else {
    std::uint64_t bytes = 0;
    std::string_view data;
    if (!r.get_varint(bytes) || !r.get_bytes(static_cast<std::size_t>(bytes), data)) return fail("bad Draco base");
    draco::DecoderBuffer buffer;
    buffer.Init(data.data(), data.size());
    draco::Decoder decoder;
    auto decoded = decoder.DecodeMeshFromBuffer(&buffer);
    if (!decoded.ok() || !decoded.value()) return fail("the Draco base does not decode");
    const Mesh m = from_draco(*decoded.value());
    if (static_cast<std::size_t>(m.num_vertices()) != nw || static_cast<std::size_t>(m.num_faces()) != nf)
      return fail("the Draco base has the wrong counts");
    for (Index f = 0; f < m.num_faces(); ++f)
      for (int k = 0; k < 3; ++k) faces.push_back(static_cast<std::uint32_t>(m.triangles(f, k)));
    for (std::size_t p = 0; p < np; ++p) {
      std::array<std::int64_t, 3> q{};
      for (int d = 0; d < 3; ++d) q[d] = st.position_quantiser.q(m.positions(st.point_first_wedge[p], d));
      st.qposition.push_back(q);
    }
    if ((h.flags & kNormals) && !m.has_normals()) return fail("the Draco base lacks normals");
    if ((h.flags & kUvs) && !m.has_uvs()) return fail("the Draco base lacks UVs");
    if ((h.flags & kColours) && !m.has_colours()) return fail("the Draco base lacks colours");
    for (Index w = 0; w < m.num_vertices(); ++w) {
      int i = 0;
      auto put = [&](double v) {
        st.qattribute.push_back(st.attribute_quantiser[static_cast<std::size_t>(i)].q(v));
        ++i;
      };
      if (h.flags & kNormals) for (int d = 0; d < 3; ++d) put(m.attributes.normals(w, d));
      if (h.flags & kUvs) for (int d = 0; d < 2; ++d) put(m.attributes.uvs(w, d));
      if (h.flags & kColours) for (int d = 0; d < 4; ++d) put(m.attributes.colours(w, d));
    }
    if (!r.get_symbols(colour_codes, 4 * nf)) return fail("bad base face colours");
  }
  if (st.quantised) {
    for (const auto& q : st.qposition) {
      Eigen::Vector3d p;
      for (int d = 0; d < 3; ++d) p[d] = st.position_quantiser.value(q[d]);
      st.position.push_back(p);
    }
    for (std::size_t i = 0; i < st.qattribute.size(); ++i)
      st.attribute.push_back(st.attribute_quantiser[i % static_cast<std::size_t>(dims)].value(st.qattribute[i]));
    if (h.flags & kFaceColours) {
      if (colour_codes.size() != 4 * nf) return fail("bad base face colours");
      for (std::uint32_t c : colour_codes) colours.push_back(face_colour_value(c, h.colour_bits));
    }
  }
  // As for any mesh (validate()): squares of coordinates past a float's range overflow distances.
  for (const Eigen::Vector3d& p : st.position)
    if (!within_coordinate_range(p)) return fail("a base position beyond the range of a float");
  if (faces.size() != 3 * nf) return fail("bad base faces");
  for (std::size_t f = 0; f < nf; ++f) {
    std::array<Index, 3> c{};
    for (int k = 0; k < 3; ++k) {
      if (faces[3 * f + k] >= nw) return fail("a base face uses a vertex out of range");
      c[k] = static_cast<Index>(faces[3 * f + k]);
    }
    const Index a = st.wedge_point[c[0]], b = st.wedge_point[c[1]], d = st.wedge_point[c[2]];
    if (a == b || b == d || a == d) return fail("a base face repeats a point");
    st.add_face(c);
  }
  std::uint16_t code = 0;
  if (!r.get(code) || !r.at_end()) return fail("bad base error bound");
  st.error_code = code;
  if (pm) {
    pm->has_normals = h.flags & kNormals;
    pm->has_uvs = h.flags & kUvs;
    pm->has_colours = h.flags & kColours;
    pm->has_face_colours = h.flags & kFaceColours;
    pm->attribute_dims = dims;
    pm->bounds = Eigen::AlignedBox3d(Eigen::Vector3d(h.box_min[0], h.box_min[1], h.box_min[2]),
                                     Eigen::Vector3d(h.box_max[0], h.box_max[1], h.box_max[2]));
    pm->base_points = static_cast<Index>(np);
    pm->base_wedges = static_cast<Index>(nw);
    pm->base_faces = static_cast<Index>(nf);
    pm->base_positions = st.position;
    pm->wedge_point = st.wedge_point;
    pm->wedge_parent.assign(nw, -1);
    pm->wedge_attributes = st.attribute;
    pm->face_corners = st.corners;
    if (pm->has_face_colours) {
      pm->face_colours.resize(static_cast<Index>(nf), 4);
      for (std::size_t i = 0; i < colours.size(); ++i) pm->face_colours(static_cast<Index>(i / 4), static_cast<Index>(i % 4)) = colours[i];
    }
    pm->level_error = {error_value(code, h.reference())};
  }
  return true;
}

namespace {

/// The measured levels block: count, then per level its distance from the previous level (varint)
/// and two doubles, Hausdorff and RMS. False unless levels increase within the stream and values are
/// finite and not negative.
bool decode_measured(std::string_view payload, const Header& h, std::vector<LevelMeasurement>& out) {
  ByteReader r(payload.data(), payload.size());
  std::uint64_t count = 0, level = 0;
  if (!r.get_varint(count) || count > h.splits + 1) return false;
  for (std::uint64_t i = 0; i < count; ++i) {
    std::uint64_t step = 0;
    LevelMeasurement m;
    if (!r.get_varint(step) || !r.get(m.hausdorff) || !r.get(m.rms)) return false;
    level += step;
    if ((i > 0 && step == 0) || level > h.splits || !(m.hausdorff >= 0 && m.rms >= 0) || !std::isfinite(m.hausdorff) ||
        !std::isfinite(m.rms))
      return false;
    m.level = static_cast<Index>(level);
    out.push_back(m);
  }
  return r.at_end();
}

/// Where a prefix read stops: before the split that would exceed the face budget, or at the first
/// level that is good enough for the error or view budget (levels' bounds do not increase).
struct StopRule {
  std::optional<Index> max_faces;
  std::optional<double> max_error;
  std::optional<ScreenSpaceBudget> view;
  LevelErrorKind kind = LevelErrorKind::Bound;

  bool too_many(Index faces) const { return max_faces && faces > *max_faces; }
  /// The same tests as level_for_error() and level_for_view(), so the prefix ends at their level.
  bool good_enough(const ProgressiveMesh& pm) const {
    if (!max_error && !view) return false;
    const double error = level_error(pm, pm.max_level(), kind);
    return (max_error && error <= *max_error) ||
           (view && projected_pixels(error, bounding_radius(pm), *view) <= view->pixel_error);
  }
};

StopRule stop_rule(const PmReadOptions& options, const Header& h, const std::string& name) {
  StopRule rule;
  rule.max_faces = options.max_faces;
  if (options.max_ratio) {
    if (!(*options.max_ratio >= 0 && *options.max_ratio <= 1))
      throw Error(fmt::format("{}: face ratio must be between 0 and 1, got {}", name, *options.max_ratio));
    const auto by_ratio = static_cast<Index>(std::llround(*options.max_ratio * double(h.faces)));
    rule.max_faces = std::min(rule.max_faces.value_or(by_ratio), by_ratio);
  }
  if (options.max_error && !(*options.max_error >= 0))
    throw Error(fmt::format("{}: error budget must not be negative, got {}", name, *options.max_error));
  rule.max_error = options.max_error;
  rule.kind = options.select_by;
  if (options.view) {
    if (!(options.view->pixel_error >= 0))
      throw Error(fmt::format("{}: pixel error must not be negative, got {}", name, options.view->pixel_error));
    rule.view = options.view;
    try {
      projected_pixels(0.0, 0.0, *rule.view);  // checks the field of view and viewport before reading
    } catch (const Error& e) {
      throw Error(fmt::format("{}: {}", name, e.what()));
    }
  }
  return rule;
}

/// Decodes one block of splits into `pm`, applying each to the state; sets `stopped` and returns
/// where `rule` says the read should end. False, with `why`, if the block is malformed.
bool decode_block(std::string_view payload, const Header& h, StreamState& st, ProgressiveMesh& pm, double slack,
                  const StopRule& rule, bool& stopped, std::string& why) {
  ByteReader r(payload.data(), payload.size());
  std::uint32_t count = 0;
  std::uint8_t predictor = 0;
  if (!r.get(count) || !r.get(predictor) || count == 0 || count > h.splits_per_block || predictor > 1) {
    why = "bad block header";
    return false;
  }
  std::array<std::vector<std::uint32_t>, kStreamCount> streams;
  for (auto& s : streams)
    if (!r.get_symbols(s, kMaxSymbols)) {
      why = "bad symbol stream";
      return false;
    }
  std::uint64_t raw_size = 0;
  std::string_view raw_bytes;
  if (!r.get_varint(raw_size) || !r.get_bytes(static_cast<std::size_t>(raw_size), raw_bytes) || !r.at_end()) {
    why = "bad raw values";
    return false;
  }
  ByteReader raw(raw_bytes.data(), raw_bytes.size());
  std::array<Cursor, kStreamCount> in;
  for (int i = 0; i < kStreamCount; ++i) in[i].v = &streams[i];
  const std::size_t dims = static_cast<std::size_t>(st.dims);
  std::vector<Index> ring;
  std::uint16_t& code = st.error_code;
  auto bad = [&](const char* what) {
    why = what;
    return false;
  };
  for (std::uint32_t n = 0; n < count; ++n) {
    if (rule.good_enough(pm)) {
      stopped = true;
      return true;
    }
    if (pm.splits.size() >= h.splits) return bad("more splits than the header announces");
    SplitRecord rec;
    std::uint32_t v = 0;
    const Index t = st.num_points();
    if (!in[kPoint].next(v) || v >= static_cast<std::uint32_t>(t)) return bad("split point out of range");
    rec.point = static_cast<Index>(v);
    const Index s = rec.point;
    if (!in[kWedgeCount].next(v) || v == 0 || v > (1u << 20)) return bad("bad wedge count");
    rec.num_wedges = static_cast<Index>(v);
    if (!in[kFaceCount].next(v) || v < 1 || v > 2) return bad("bad face count");
    rec.num_faces = static_cast<Index>(v);
    st.neighbours(s, ring);
    const Index first_new = st.num_wedges();
    for (Index i = 0; i < rec.num_faces; ++i) {
      std::uint32_t shape = 0, wt = 0, ws = 0, wx = 0, third = 0;
      if (!in[kShape].next(shape) || shape > 5 || !in[kWedgeIndex].next(wt) || !in[kWedgeIndex].next(ws) ||
          !in[kWedgeIndex].next(wx) || !in[kThird].next(third))
        return bad("bad new face");
      Index x = -1;
      if (third < ring.size()) {
        x = ring[third];
      } else {
        if (third != ring.size() || !in[kEscape].next(v) || v >= static_cast<std::uint32_t>(t)) return bad("bad third point");
        x = static_cast<Index>(v);
      }
      if (x == s || wt >= static_cast<std::uint32_t>(rec.num_wedges) ||
          ws >= static_cast<std::uint32_t>(st.point_num_wedges[s]) || wx >= static_cast<std::uint32_t>(st.point_num_wedges[x]))
        return bad("bad new face wedges");
      const int pt = static_cast<int>(shape / 2), ps = (shape & 1) ? (pt + 1) % 3 : (pt + 2) % 3, px = 3 - pt - ps;
      auto& c = rec.faces[static_cast<std::size_t>(i)];
      c[pt] = first_new + static_cast<Index>(wt);
      c[ps] = st.point_first_wedge[s] + static_cast<Index>(ws);
      c[px] = st.point_first_wedge[x] + static_cast<Index>(wx);
    }
    const std::vector<char> predicted =
        h.version >= 2 ? predicted_moves(st, rec) : std::vector<char>(st.point_faces[static_cast<std::size_t>(s)].size(), 0);
    std::size_t face_index = 0;
    for (Index f : st.point_faces[static_cast<std::size_t>(s)]) {
      if (!in[kChangeBit].next(v) || v > 1) return bad("bad corner bits");
      if (!(v ^ static_cast<std::uint32_t>(predicted[face_index++] != 0))) continue;
      const int k = st.corner_of(f, s);
      std::uint32_t which = 0;
      if (k < 0 || !in[kChangeWedge].next(which)) return bad("bad moved corner");
      Index fine = -1;
      if (which == 0) fine = paired_fine_wedge(rec, st, st.corners[static_cast<std::size_t>(f)][k]);
      else if (which <= static_cast<std::uint32_t>(rec.num_wedges)) fine = first_new + static_cast<Index>(which - 1);
      if (fine < 0) return bad("a moved corner has no wedge to go to");
      rec.changes.push_back({f, k, fine});
    }
    if (st.quantised) {
      const auto& coarse = st.qposition[static_cast<std::size_t>(s)];
      PredictionRings rings;
      if (predictor == 1) rings = prediction_rings(st, rec);
      const auto predicted_new = predictor == 1 ? ring_centroid(st, rings.new_point, coarse) : coarse;
      std::array<std::uint32_t, 3> a{}, b{};
      for (int d = 0; d < 3; ++d) {
        if (!in[kResidualNew].next(a[d]) || !in[kResidualSplit].next(b[d])) return bad("missing position residual");
        rec.qnew[d] = predicted_new[d] + unzigzag(a[d]);
      }
      const auto predicted_split = predictor == 1 ? ring_centroid(st, rings.split_point, rec.qnew) : coarse;
      for (int d = 0; d < 3; ++d) rec.qfine[d] = predicted_split[d] + unzigzag(b[d]);
    } else {
      for (int d = 0; d < 3; ++d)
        if (!raw.get(rec.fine_position[d]) || !std::isfinite(rec.fine_position[d])) return bad("bad position");
      for (int d = 0; d < 3; ++d)
        if (!raw.get(rec.new_position[d]) || !std::isfinite(rec.new_position[d])) return bad("bad position");
    }
    // One wedge's attribute values: quantised codes against wedge `base`'s, or raw doubles.
    auto read_values = [&](Index base, Stream stream, std::vector<std::int64_t>& codes, std::vector<double>& values) {
      for (std::size_t d = 0; d < dims; ++d) {
        if (st.quantised) {
          if (!in[stream].next(v)) return false;
          codes.push_back(st.qattribute[dims * static_cast<std::size_t>(base) + d] + unzigzag(v));
        } else {
          double a = 0;
          if (!raw.get(a) || !std::isfinite(a)) return false;
          values.push_back(a);
        }
      }
      return true;
    };
    for (Index i = 0; i < rec.num_wedges; ++i)
      if (!read_values(parent_wedge(rec, st, first_new + i), kAttribute, rec.qnew_attributes, rec.new_attributes))
        return bad("bad attribute");
    std::uint32_t changes = 0;
    if (!in[kAttributeChangeCount].next(changes) || changes > static_cast<std::uint32_t>(st.point_num_wedges[s])) return bad("bad attribute changes");
    for (std::uint32_t i = 0; i < changes; ++i) {
      if (!in[kAttributeChangeWedge].next(v) || v >= static_cast<std::uint32_t>(st.point_num_wedges[s])) return bad("bad attribute change");
      const Index w = st.point_first_wedge[s] + static_cast<Index>(v);
      rec.attribute_wedges.push_back(w);
      if (!read_values(w, kAttributeChange, rec.qattribute_values, rec.attribute_values)) return bad("bad attribute change");
    }
    if (pm.has_face_colours)
      for (Index i = 0; i < rec.num_faces; ++i)
        for (int c = 0; c < 4; ++c) {
          if (st.quantised) {
            if (!in[kFaceColour].next(v)) return bad("missing face colour");
            rec.face_colours[static_cast<std::size_t>(i)][c] = face_colour_value(v, h.colour_bits);
          } else if (!raw.get(rec.face_colours[static_cast<std::size_t>(i)][c])) {
            return bad("missing face colour");
          }
        }
    if (!in[kErrorDelta].next(v)) return bad("missing error bound");
    const std::int64_t next = std::int64_t(code) - unzigzag(v);
    if (next < 0 || next > 65535) return bad("bad error bound");
    code = static_cast<std::uint16_t>(next);
    if (rule.too_many(st.num_faces() + rec.num_faces)) {
      stopped = true;
      return true;
    }
    if (!append_split(pm, st, rec, error_value(code, h.reference()) + (st.quantised ? slack : 0.0)))
      return bad("a position beyond the range of a float");
    apply_split(st, rec);
  }
  for (int i = 0; i < kStreamCount; ++i)
    if (in[i].at != streams[i].size()) return bad("leftover values in a block");
  if (!raw.at_end()) return bad("leftover raw values in a block");
  return true;
}

/// Bytes from a file (read as needed, so a prefix read touches only the prefix) or from memory.
class Source {
 public:
  explicit Source(std::string_view bytes) : bytes_(bytes) {}
  explicit Source(std::FILE* file) : file_(file) {
    if (std::fseek(file, 0, SEEK_END) == 0) size_ = static_cast<std::size_t>(std::max(0L, std::ftell(file)));
    std::rewind(file);
  }
  /// Reads exactly n bytes into out; false (and as much as there was) at the end.
  bool read(std::size_t n, std::string& out) {
    const std::size_t available = (file_ ? size_ : bytes_.size()) - consumed_;
    n = std::min(n, available + 1);  // never allocate for bytes that cannot be there
    out.resize(n);
    std::size_t got = 0;
    if (file_) {
      got = std::fread(out.data(), 1, n, file_);
    } else {
      got = std::min(n, bytes_.size() - at_);
      std::copy_n(bytes_.data() + at_, got, out.data());
      at_ += got;
    }
    consumed_ += got;
    out.resize(got);
    return got == n;
  }
  std::size_t consumed() const { return consumed_; }

 private:
  std::string_view bytes_;
  std::size_t at_ = 0;
  std::FILE* file_ = nullptr;
  std::size_t size_ = 0;
  std::size_t consumed_ = 0;
};

PmReadResult read_stream(Source& src, const std::string& name, const PmReadOptions& options) {
  PmReadResult result;
  std::string head;
  if (!src.read(kHeaderSize, head)) {
    if (head.empty()) throw Error(fmt::format("{}: empty file, not a progressive mesh", name));
    throw Error(fmt::format("{}: truncated header ({} of {} bytes)", name, head.size(), kHeaderSize));
  }
  Header h;
  std::string why;
  if (!decode_header(head.data(), h, why)) throw Error(fmt::format("{}: {}", name, why));
  result.total_splits = static_cast<Index>(h.splits);
  result.total_faces = static_cast<Index>(h.faces);
  const StopRule rule = stop_rule(options, h, name);
  result.position_bits = h.position_bits;
  result.stats.header_bytes = kHeaderSize;
  ProgressiveMesh& pm = result.pm;
  StreamState st;
  const double slack = (h.flags & kQuantised) ? 0.5 * std::sqrt(3.0) * h.position_quantiser().step : 0.0;

  // One chunk: type, length, payload, CRC. Returns false with `why` when it is missing or damaged.
  std::string chunk_head, payload, tail;
  auto read_chunk = [&](std::uint8_t& type) {
    if (!src.read(5, chunk_head)) {
      why = chunk_head.empty() ? "the stream ends early" : "truncated block header";
      return false;
    }
    type = static_cast<std::uint8_t>(chunk_head[0]);
    std::uint32_t length = 0;
    std::memcpy(&length, chunk_head.data() + 1, 4);
    if (length > (1u << 31)) {
      why = "implausible block length";
      return false;
    }
    if (!src.read(length, payload) || !src.read(4, tail)) {
      why = "truncated block";
      return false;
    }
    std::uint32_t crc = 0;
    std::memcpy(&crc, tail.data(), 4);
    if (crc != crc32(payload.data(), payload.size(), crc32(chunk_head.data(), 5))) {
      why = "checksum mismatch (damaged block)";
      return false;
    }
    return true;
  };

  std::uint8_t type = 0;
  if (!read_chunk(type) || type != kBase) throw Error(fmt::format("{}: no intact base mesh: {}", name, type != kBase && why.empty() ? "unexpected block" : why));
  if (!decode_base(payload, h, st, &pm, why)) throw Error(fmt::format("{}: bad base mesh: {}", name, why));
  if (st.quantised) pm.level_error[0] += slack;
  result.stats.base_bytes = src.consumed() - kHeaderSize;

  // Only while splits remain: the blocks after them (input order, extras) belong to a whole read.
  bool stopped = h.splits > 0 && rule.too_many(pm.num_faces(0));
  bool order_seen = false;
  while (!stopped) {
    if (pm.splits.size() < h.splits && rule.good_enough(pm)) break;  // before the next block
    const std::size_t before = src.consumed();
    if (!read_chunk(type)) {
      result.warning = fmt::format("{}: {} after {} of {} splits; using levels 0..{}", name, why, pm.splits.size(), h.splits,
                                   pm.splits.size());
      break;
    }
    if (type == kMeasured) {
      std::vector<LevelMeasurement> measured;
      if (!pm.splits.empty() || !pm.measured.empty() || !decode_measured(payload, h, measured)) {
        result.warning = fmt::format("{}: bad measured-levels block; selection goes by the bounds", name);
        continue;  // the splits after it are intact (their blocks have their own checksums)
      }
      for (LevelMeasurement& m : measured) m.hausdorff += slack;  // as for the bounds
      pm.measured = std::move(measured);
      result.stats.measured_bytes = src.consumed() - before;
    } else if (type == kSplits) {
      if (pm.splits.size() >= h.splits || order_seen) {
        result.warning = fmt::format("{}: unexpected split block; using levels 0..{}", name, pm.splits.size());
        break;
      }
      // A block that turns out malformed is cut off whole (the state is not used again).
      const Index level = pm.max_level();
      if (!decode_block(payload, h, st, pm, slack, rule, stopped, why)) {
        truncate(pm, level);
        result.warning = fmt::format("{}: damaged split block ({}) after {} of {} splits; using levels 0..{}", name, why,
                                     pm.splits.size(), h.splits, pm.splits.size());
        break;
      }
      result.stats.split_bytes += src.consumed() - before;
      ++result.stats.split_blocks;
    } else if (type == kOrderChunk) {
      if (pm.splits.size() != h.splits) {
        result.warning = fmt::format("{}: order block before all splits", name);
        break;
      }
      ByteReader r(payload.data(), payload.size());
      std::uint64_t nv = 0, nf = 0;
      std::vector<std::uint32_t> wi, fi;
      if (!r.get_varint(nv) || !r.get_varint(nf) || !r.get_symbols(wi, h.wedges) || !r.get_symbols(fi, h.faces) ||
          wi.size() != h.wedges || fi.size() != h.faces || !r.at_end() || nv > (1u << 31) || nf > (1u << 31)) {
        result.warning = fmt::format("{}: damaged order block; levels come in stream order", name);
        break;
      }
      pm.input_vertices = static_cast<Index>(nv);
      pm.input_faces = static_cast<Index>(nf);
      pm.wedge_input.assign(wi.begin(), wi.end());
      pm.face_input.assign(fi.begin(), fi.end());
      order_seen = true;
      result.stats.order_bytes = src.consumed() - before;
    } else if (type == kExtras) {
      ByteReader r(payload.data(), payload.size());
      std::vector<std::uint32_t> vi, fi, tri, exceptions;
      bool ok = order_seen && r.get_symbols(vi, kMaxSymbols);
      const Index n = static_cast<Index>(vi.size());
      Mesh& x = pm.extra_vertices;
      x = {};
      x.positions.resize(n, 3);
      if (pm.has_normals) x.attributes.normals.resize(n, 3);
      if (pm.has_uvs) x.attributes.uvs.resize(n, 2);
      if (pm.has_colours) x.attributes.colours.resize(n, 4);
      for (Index i = 0; ok && i < n; ++i) {
        for (int d = 0; d < 3; ++d) ok = ok && r.get(x.positions(i, d));
        if (pm.has_normals) for (int d = 0; d < 3; ++d) ok = ok && r.get(x.attributes.normals(i, d));
        if (pm.has_uvs) for (int d = 0; d < 2; ++d) ok = ok && r.get(x.attributes.uvs(i, d));
        if (pm.has_colours) for (int d = 0; d < 4; ++d) ok = ok && r.get(x.attributes.colours(i, d));
      }
      ok = ok && r.get_symbols(fi, kMaxSymbols) && r.get_symbols(tri, kMaxSymbols) && tri.size() == 3 * fi.size();
      const Index nf = pm.num_faces(pm.max_level());
      if (ok && pm.has_face_colours) {
        pm.face_colours.conservativeResize(nf + static_cast<Index>(fi.size()), 4);
        for (Index f = 0; ok && f < static_cast<Index>(fi.size()); ++f)
          for (int c = 0; c < 4; ++c) ok = ok && r.get(pm.face_colours(nf + f, c));
      }
      ok = ok && r.get_symbols(exceptions, kMaxSymbols) && exceptions.size() % 3 == 0 && r.at_end();
      const auto in_range = [](const std::vector<std::uint32_t>& v, Index limit) {
        return std::all_of(v.begin(), v.end(), [&](std::uint32_t i) { return i < static_cast<std::uint32_t>(limit); });
      };
      ok = ok && in_range(vi, pm.input_vertices) && in_range(fi, pm.input_faces) && in_range(tri, pm.input_vertices);
      for (std::size_t i = 0; ok && i < exceptions.size(); i += 3)
        ok = exceptions[i] < static_cast<std::uint32_t>(pm.input_faces) && exceptions[i + 1] < 3 &&
             exceptions[i + 2] < static_cast<std::uint32_t>(pm.input_vertices);
      ok = ok && pm.wedge_input.size() + vi.size() == static_cast<std::size_t>(pm.input_vertices) &&
           pm.face_input.size() + fi.size() == static_cast<std::size_t>(pm.input_faces);
      if (!ok) {
        pm.wedge_input.clear(), pm.face_input.clear();
        result.warning = fmt::format("{}: damaged extras block; levels come in stream order", name);
        break;
      }
      pm.extra_vertex_input.assign(vi.begin(), vi.end());
      pm.extra_face_input.assign(fi.begin(), fi.end());
      pm.extra_faces.resize(static_cast<Index>(fi.size()), 3);
      for (std::size_t i = 0; i < tri.size(); ++i) pm.extra_faces(static_cast<Index>(i / 3), static_cast<Index>(i % 3)) = static_cast<Index>(tri[i]);
      for (std::size_t i = 0; i < exceptions.size(); i += 3)
        pm.corner_exceptions.push_back({static_cast<Index>(exceptions[i]), static_cast<Index>(exceptions[i + 1]), static_cast<Index>(exceptions[i + 2])});
      result.stats.extra_bytes = src.consumed() - before;
    } else if (type == kEnd) {
      break;
    } else {
      result.warning = fmt::format("{}: unknown block type {}; using levels 0..{}", name, int(type), pm.splits.size());
      break;
    }
  }
  result.complete = pm.splits.size() == h.splits;
  if (order_seen && (!result.complete || pm.extra_vertex_input.size() + pm.wedge_input.size() != static_cast<std::size_t>(pm.input_vertices))) {
    pm.wedge_input.clear(), pm.face_input.clear();  // half an order is no order
  }
  // A prefix holds the measurements of its own levels.
  std::erase_if(pm.measured, [&](const LevelMeasurement& m) { return m.level > pm.max_level(); });
  result.bytes_read = src.consumed();
  result.stats.total_bytes = result.bytes_read;
  validate(pm, name);
  return result;
}

}  // namespace
}  // namespace detail::pm

PmReadResult read_pm_from_memory(std::string_view bytes, const std::string& name, const PmReadOptions& options) {
  detail::pm::Source src(bytes);
  return detail::pm::read_stream(src, name, options);
}

PmReadResult read_pm(const std::filesystem::path& path, const PmReadOptions& options) {
  detail::refuse_directory(path);
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!file) throw Error(fmt::format("{}: cannot open: {}", path.string(), std::strerror(errno)));
  detail::pm::Source src(file.get());
  return detail::pm::read_stream(src, path.string(), options);
}

}  // namespace lodkit
