// CSG trees: JSON in, a closed mesh out. Everything but the booleans themselves (boolean.cpp).
#include <lodkit/csg.h>
#include <lodkit/error.h>
#include <lodkit/io.h>
#include <lodkit/primitives.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <fmt/format.h>
#include <fstream>
#include <nlohmann/json.hpp>
#include <limits>
#include <numbers>
#include <optional>
#include <mutex>
#include <sstream>
#include <tuple>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include "io/output.h"

namespace lodkit {
namespace {

using nlohmann::json;

struct Context {
  const std::string& name;
  const std::filesystem::path& base;
};

[[noreturn]] void fail(const Context& c, const std::string& path, const std::string& what) {
  throw Error(fmt::format("{}: {}: {}", c.name, path, what));
}

double number(const Context& c, const json& j, const std::string& path) {
  if (!j.is_number()) fail(c, path, "expected a number");
  const double v = j.get<double>();
  if (!std::isfinite(v)) fail(c, path, "must be finite");
  return v;
}

Eigen::Vector3d vec3(const Context& c, const json& j, const std::string& path) {
  if (!j.is_array() || j.size() != 3) fail(c, path, "expected [x, y, z]");
  return {number(c, j[0], path + "[0]"), number(c, j[1], path + "[1]"), number(c, j[2], path + "[2]")};
}

// One transform object: scale, then rotate, then translate (M = T R S), or a whole 4x4 matrix.
Eigen::Matrix4d transform_of(const Context& c, const json& t, const std::string& path) {
  if (!t.is_object()) fail(c, path, "a transform is an object with translate, rotate, scale or matrix");
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  if (t.contains("matrix")) {
    if (t.size() != 1) fail(c, path, "\"matrix\" cannot be combined with other transforms in one object");
    const json& a = t["matrix"];
    if (!a.is_array() || a.size() != 16) fail(c, path + ".matrix", "expected 16 numbers, row by row");
    for (int i = 0; i < 16; ++i) m(i / 4, i % 4) = number(c, a[i], fmt::format("{}.matrix[{}]", path, i));
    if (m.row(3) != Eigen::RowVector4d(0, 0, 0, 1)) fail(c, path + ".matrix", "last row must be 0 0 0 1");
    return m;
  }
  Eigen::Matrix3d scale = Eigen::Matrix3d::Identity(), rotate = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translate = Eigen::Vector3d::Zero();
  for (const auto& [key, value] : t.items()) {
    const std::string p = path + "." + key;
    if (key == "translate") {
      translate = vec3(c, value, p);
    } else if (key == "scale") {
      Eigen::Vector3d s = value.is_number() ? Eigen::Vector3d::Constant(number(c, value, p)) : vec3(c, value, p);
      if ((s.array() == 0).any()) fail(c, p, "scale must not be zero");
      scale = s.asDiagonal();
    } else if (key == "rotate") {
      if (!value.is_object()) fail(c, p, "expected {\"axis\": [x, y, z], \"degrees\": d} or {\"euler\": [x, y, z]}");
      constexpr double deg = std::numbers::pi / 180.0;
      if (value.contains("euler")) {
        const Eigen::Vector3d e = vec3(c, value["euler"], p + ".euler") * deg;  // about x, then y, then z
        rotate = (Eigen::AngleAxisd(e.z(), Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(e.y(), Eigen::Vector3d::UnitY()) *
                  Eigen::AngleAxisd(e.x(), Eigen::Vector3d::UnitX())).toRotationMatrix();
      } else {
        if (!value.contains("axis") || !value.contains("degrees")) fail(c, p, "needs \"axis\" and \"degrees\" (or \"euler\")");
        const Eigen::Vector3d axis = vec3(c, value["axis"], p + ".axis");
        if (!(axis.norm() > 0)) fail(c, p + ".axis", "must not be zero");
        rotate = Eigen::AngleAxisd(number(c, value["degrees"], p + ".degrees") * deg, axis.normalized()).toRotationMatrix();
      }
    } else {
      fail(c, p, "unknown transform (translate, rotate, scale or matrix)");
    }
  }
  m.topLeftCorner<3, 3>() = rotate * scale;
  m.topRightCorner<3, 1>() = translate;
  return m;
}

CsgNode parse_node(const Context& c, const json& j, const std::string& path) {
  if (!j.is_object()) fail(c, path, "a node is an object with \"op\", \"primitive\" or \"mesh\"");
  CsgNode node;
  node.json_path = path;
  const int kinds = int(j.contains("op")) + int(j.contains("primitive")) + int(j.contains("mesh"));
  if (kinds != 1) fail(c, path, "a node needs exactly one of \"op\", \"primitive\" or \"mesh\"");
  if (j.contains("transform")) {
    const json& t = j["transform"];
    if (t.is_array()) {  // applied in order: the first element acts first
      for (std::size_t i = 0; i < t.size(); ++i)
        node.transform = transform_of(c, t[i], fmt::format("{}.transform[{}]", path, i)) * node.transform;
    } else {
      node.transform = transform_of(c, t, path + ".transform");
    }
  }
  for (const auto& [key, value] : j.items()) {
    const std::string p = path + "." + key;
    if (key == "transform") continue;
    if (key == "op") {
      node.kind = CsgNode::Kind::Operation;
      const std::string op = value.is_string() ? value.get<std::string>() : "";
      if (op == "union") node.op = BooleanOp::Union;
      else if (op == "difference") node.op = BooleanOp::Difference;
      else if (op == "intersection") node.op = BooleanOp::Intersection;
      else fail(c, p, "must be \"union\", \"difference\" or \"intersection\"");
    } else if (key == "children") {
      if (!value.is_array() || value.empty()) fail(c, p, "expected a non-empty array of nodes");
      for (std::size_t i = 0; i < value.size(); ++i) node.children.push_back(parse_node(c, value[i], fmt::format("{}[{}]", p, i)));
    } else if (key == "primitive") {
      node.kind = CsgNode::Kind::Primitive;
      node.primitive = value.is_string() ? value.get<std::string>() : "";
      static const char* const known[] = {"box", "sphere", "cylinder", "cone", "torus"};
      if (std::find(std::begin(known), std::end(known), node.primitive) == std::end(known))
        fail(c, p, "must be box, sphere, cylinder, cone or torus");
    } else if (key == "mesh") {
      node.kind = CsgNode::Kind::MeshFile;
      if (!value.is_string()) fail(c, p, "expected a file path");
      node.mesh = c.base / value.get<std::string>();
    } else if (key == "size") {
      if (value.is_number()) node.size = {number(c, value, p)};
      else node.size = {vec3(c, value, p).x(), vec3(c, value, p).y(), vec3(c, value, p).z()};
    } else if (key == "radius" || key == "height" || key == "major_radius" || key == "minor_radius") {
      node.parameters.push_back({key, number(c, value, p)});
    } else {
      fail(c, p, "unknown key");
    }
  }
  if (node.kind == CsgNode::Kind::Operation && node.children.empty()) fail(c, path, "an operation needs \"children\"");
  if (node.kind != CsgNode::Kind::Operation && !node.children.empty()) fail(c, path + ".children", "only operations have children");
  return node;
}

double parameter(const CsgNode& n, const char* key, double fallback) {
  for (const auto& [k, v] : n.parameters)
    if (k == key) return v;
  return fallback;
}

Mesh transformed(Mesh m, const Eigen::Matrix4d& t) {
  if (t.isIdentity()) return m;
  for (Index v = 0; v < m.num_vertices(); ++v)
    m.positions.row(v) = (t.topLeftCorner<3, 3>() * m.positions.row(v).transpose() + t.topRightCorner<3, 1>()).transpose();
  if (t.topLeftCorner<3, 3>().determinant() < 0) m.triangles.col(1).swap(m.triangles.col(2));  // mirrored: keep outward
  return m;
}

// True when no two parts' bounding boxes meet (touching counts as meeting).
bool have_disjoint_boxes(const std::vector<Mesh>& parts) {
  std::vector<Eigen::AlignedBox3d> boxes;
  for (const Mesh& m : parts) boxes.push_back(bounding_box(m));
  for (std::size_t i = 0; i < boxes.size(); ++i)
    for (std::size_t j = i + 1; j < boxes.size(); ++j)
      if (boxes[i].intersects(boxes[j])) return false;
  return true;
}

// A plane `coordinate[axis] == at` through a solid that no part's bounding box crosses.
struct SeparatingPlane {
  int axis = 0;
  double at = 0.0;
};

// Where to cut inside the open interval (lo, hi): in the widest stretch free of the solid's vertex
// coordinates, and not in its middle. A plane through or next to a vertex, or seam points at the
// "round" coordinates users give (holes on a grid), make near-collinear points, and those are what
// rounding a corefinement's exact result can break.
std::optional<double> cut_position(const Mesh& solid, int axis, double lo, double hi) {
  std::vector<double> stops{lo, hi};
  for (Index v = 0; v < solid.num_vertices(); ++v)
    if (const double c = solid.positions(v, axis); lo < c && c < hi) stops.push_back(c);
  std::sort(stops.begin(), stops.end());
  std::size_t widest = 0;
  for (std::size_t i = 1; i + 1 < stops.size(); ++i)
    if (stops[i + 1] - stops[i] > stops[widest + 1] - stops[widest]) widest = i;
  const double at = stops[widest] + (std::numbers::sqrt2 - 1.0) * (stops[widest + 1] - stops[widest]);
  if (!(stops[widest] < at && at < stops[widest + 1])) return std::nullopt;
  return at;
}

// The most even split of `parts` by an axis-aligned plane that cuts `solid` and no part's box
// (along `only_axis` if given, else the solid's longest axis that has one). None when every such
// plane leaves fewer than two parts on a side.
std::optional<SeparatingPlane> separating_plane(const Mesh& solid, const std::vector<Mesh>& parts, std::optional<int> only_axis) {
  const Eigen::AlignedBox3d solid_box = bounding_box(solid);
  std::vector<Eigen::AlignedBox3d> boxes;
  for (const Mesh& m : parts) boxes.push_back(bounding_box(m));
  std::array<int, 3> axes = {0, 1, 2};
  const Eigen::Vector3d extent = solid_box.sizes();
  std::stable_sort(axes.begin(), axes.end(), [&](int a, int b) { return extent[a] > extent[b]; });
  const std::size_t n = boxes.size();
  auto imbalance = [n](std::size_t below) { return below > n - below ? below - (n - below) : (n - below) - below; };
  for (int axis : axes) {
    if (only_axis && axis != *only_axis) continue;
    std::vector<std::size_t> order(n);
    for (std::size_t i = 0; i < n; ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return boxes[a].min()[axis] < boxes[b].min()[axis]; });
    std::size_t best = 0;  // parts below the best gap (0: none yet)
    double best_lo = 0, best_hi = 0;
    double highest = -std::numeric_limits<double>::infinity();  // top of the parts below so far
    for (std::size_t k = 1; k < n; ++k) {
      highest = std::max(highest, boxes[order[k - 1]].max()[axis]);
      const double lo = std::max(highest, solid_box.min()[axis]), hi = std::min(boxes[order[k]].min()[axis], solid_box.max()[axis]);
      if (!(lo < hi) || std::min(k, n - k) < 2) continue;
      if (best == 0 || imbalance(k) < imbalance(best)) best = k, best_lo = lo, best_hi = hi;
    }
    if (best == 0) continue;
    if (const auto at = cut_position(solid, axis, best_lo, best_hi)) return SeparatingPlane{axis, *at};
  }
  return std::nullopt;
}

// Evaluates a tree bottom-up. Siblings are independent, so children and each level of a pairwise
// reduction run in parallel (CGAL's kernels are thread-safe on separate meshes).
struct Evaluator {
  explicit Evaluator(const CsgOptions& o) : options(o) {}

  const CsgOptions& options;
  std::atomic<int> primitives = 0, operations = 0;
  std::mutex warnings_mutex;
  std::vector<std::string> warnings;

  Mesh leaf(const CsgNode& n) {
    ++primitives;
    const double t = options.tolerance;
    try {
      if (n.kind == CsgNode::Kind::MeshFile) {
        // Checked once here; every boolean after this works on solids it made itself.
        Mesh m = read_mesh(n.mesh);
        check_solid(m, n.mesh.string());
        return m;
      }
      if (n.primitive == "box") {
        BoxOptions b;
        if (n.size.size() == 1) b.size.setConstant(n.size[0]);
        else if (n.size.size() == 3) b.size = {n.size[0], n.size[1], n.size[2]};
        return make_box(b);
      }
      if (n.primitive == "sphere") return make_uv_sphere({.radius = parameter(n, "radius", 1.0), .tolerance = t});
      if (n.primitive == "cylinder")
        return make_cylinder({.radius = parameter(n, "radius", 1.0), .height = parameter(n, "height", 2.0), .tolerance = t});
      if (n.primitive == "cone")
        return make_cone({.radius = parameter(n, "radius", 1.0), .height = parameter(n, "height", 2.0), .tolerance = t});
      return make_torus({.major_radius = parameter(n, "major_radius", 1.0), .minor_radius = parameter(n, "minor_radius", 0.25),
                         .tolerance = t});
    } catch (const Error& e) {
      throw Error(fmt::format("{}: {}", n.json_path, e.what()));
    }
  }

  Mesh combine(const Mesh& a, const Mesh& b, BooleanOp op, const std::string& na, const std::string& nb) {
    ++operations;
    BooleanResult r = boolean(a, b, op, {.exact = options.exact, .check_operands = false}, na, nb);
    if (!r.warnings.empty()) {
      const std::lock_guard lock(warnings_mutex);
      for (auto& w : r.warnings) warnings.push_back(std::move(w));
    }
    return std::move(r.mesh);
  }

  // Pairwise (balanced) reduction: each operand takes part in log2(n) operations, not up to n, so a
  // union of many parts never corefines one ever-growing mesh against each small one.
  Mesh reduce(std::vector<Mesh> parts, BooleanOp op, const std::string& where) {
    if (op == BooleanOp::Union && parts.size() > 2) {
      // Many separate parts (holes to drill, say): their union is just all their shells, once one
      // test shows that none touches or contains another. Every part is a valid solid already (a
      // primitive, a checked file or a checked result), so pairwise disjoint bounding boxes settle
      // it without testing a single triangle pair.
      Mesh all = concatenated(parts);
      if (have_disjoint_boxes(parts) || are_separate_solids(all)) return all;
    }
    while (parts.size() > 1) {
      std::vector<Mesh> next((parts.size() + 1) / 2);
      tbb::parallel_for(std::size_t{0}, parts.size() / 2, [&](std::size_t i) {
        next[i] = combine(parts[2 * i], parts[2 * i + 1], op, where, where);
      });
      if (parts.size() % 2) next.back() = std::move(parts.back());
      parts = std::move(next);
    }
    return std::move(parts.front());
  }

  // a - (b1 u b2 u ...). With many parts (holes to drill, say), a plane between two groups of them
  // cuts `a` in two, each group is subtracted from its half in parallel, and the halves are joined
  // along the cut: each corefinement sees only its share of the intersections, and both cores work.
  // Further cuts of a half run parallel to the first: a crossing cut would put vertices on the first
  // cut's edges that the other half lacks. The rule depends only on the input, so the result is the
  // same on any machine.
  Mesh subtract(Mesh a, std::vector<Mesh> parts, const std::string& name_a, const std::string& name_b,
                std::optional<int> axis = std::nullopt) {
    if (a.num_faces() == 0) return a;
    if (options.split_at_parts > 0 && parts.size() >= options.split_at_parts) {
      if (const auto plane = separating_plane(a, parts, axis)) {
        try {
          Mesh below, above;  // not a structured binding: the lambdas below capture them
          std::tie(below, above) = split_solid(a, plane->axis, plane->at);
          std::vector<Mesh> lower, upper;
          for (const Mesh& p : parts) (bounding_box(p).max()[plane->axis] < plane->at ? lower : upper).push_back(p);
          tbb::parallel_invoke([&] { below = subtract(std::move(below), std::move(lower), name_a, name_b, plane->axis); },
                               [&] { above = subtract(std::move(above), std::move(upper), name_a, name_b, plane->axis); });
          if (auto joined = join_solids(below, above, plane->axis, plane->at)) return std::move(*joined);
          return combine(below, above, BooleanOp::Union, name_a, name_a);
        } catch (const Error&) {
          // A half's corefinement can fail to round where the whole one does not (its faces are cut
          // differently): then the whole difference decides.
        }
      }
    }
    const Mesh cut = reduce(std::move(parts), BooleanOp::Union, name_b);
    return combine(a, cut, BooleanOp::Difference, name_a, name_b);
  }

  Mesh node(const CsgNode& n) {
    if (n.kind != CsgNode::Kind::Operation) return transformed(leaf(n), n.transform);
    std::vector<Mesh> parts(n.children.size());
    tbb::parallel_for(std::size_t{0}, n.children.size(), [&](std::size_t i) { parts[i] = node(n.children[i]); });
    Mesh out;
    if (n.op == BooleanOp::Difference && parts.size() > 1) {
      // A - B - C - ... = A - (B u C u ...)
      Mesh first = std::move(parts.front());
      parts.erase(parts.begin());
      out = subtract(std::move(first), std::move(parts), n.children[0].json_path, n.json_path + ".children[1..]");
    } else {
      out = reduce(std::move(parts), n.op, n.json_path + ".children");
    }
    return transformed(std::move(out), n.transform);
  }
};

}  // namespace

CsgNode parse_csg(const std::string& json_text, const std::string& name, const std::filesystem::path& base_dir) {
  json j;
  try {
    j = json::parse(json_text);
  } catch (const json::exception& e) {  // a syntax error, or a number past a double (out_of_range)
    throw Error(fmt::format("{}: not valid JSON: {}", name, e.what()));
  }
  try {
    return parse_node({name, base_dir}, j, "$");
  } catch (const json::exception& e) {  // a value of a type the checks above did not expect
    throw Error(fmt::format("{}: {}", name, e.what()));
  }
}

CsgNode read_csg(const std::filesystem::path& path) {
  detail::refuse_directory(path);  // (an ifstream opens a directory and then reads nothing)
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(fmt::format("{}: cannot open: {}", path.string(), std::strerror(errno)));
  std::stringstream s;
  s << in.rdbuf();
  return parse_csg(s.str(), path.string(), path.parent_path());
}

CsgResult evaluate(const CsgNode& tree, const CsgOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  if (!(options.tolerance > 0)) throw Error(fmt::format("csg: tolerance must be positive, got {}", options.tolerance));
  CsgResult result;
  Evaluator e{options};
  result.mesh = e.node(tree);
  result.primitives = e.primitives;
  result.operations = e.operations;
  // Parallel siblings finish in any order; sorted, the warnings read the same on every run.
  // (A difference retried whole after a split failed may repeat a warning.)
  result.warnings = std::move(e.warnings);
  std::sort(result.warnings.begin(), result.warnings.end());
  result.warnings.erase(std::unique(result.warnings.begin(), result.warnings.end()), result.warnings.end());
  result.volume = signed_volume(result.mesh);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace lodkit
