// lodkit compare: Hausdorff, mean and RMS distance and normal deviation between two meshes.
#include <lodkit/error.h>
#include <lodkit/metrics.h>

#include <fmt/format.h>
#include <memory>

#include "common.h"

namespace lodkit::cli {
namespace {

struct CompareCliOptions {
  std::string a, b;
  std::optional<long long> samples;
  std::optional<std::string> within;
  bool json = false;
};

// --within E: exit status 0 when the two surfaces are proved within E of each other, 3 when a point is
// farther (a decision by branch and bound, no sampling: far quicker than the full comparison).
constexpr int kNotWithin = 3;

int run_within(const CompareCliOptions& opt, const Mesh& a, const Mesh& b) {
  const auto box = bounding_box(a);
  const double diagonal = box.isEmpty() ? 0.0 : box.diagonal().norm();
  const LengthArgument limit_text = parse_length(*opt.within, "compare: --within");
  const double limit = limit_text.relative ? limit_text.value * diagonal : limit_text.value;
  const HausdorffCheck c = HausdorffChecker(a).check(b, limit);
  auto pct = [&](double v) { return diagonal > 0 ? 100.0 * v / diagonal : 0.0; };
  if (opt.json) {
    nlohmann::json j{{"a", opt.a}, {"b", opt.b}, {"diagonal", diagonal}, {"within", c.within},
                     {"max_distance", limit}, {"max_distance_percent", pct(limit)}, {"attained", c.attained},
                     {"attained_percent", pct(c.attained)},
                     {"attained_at", {c.attained_at.x(), c.attained_at.y(), c.attained_at.z()}},
                     {"queries", c.queries}};
    if (c.within) j["bound"] = c.bound, j["bound_percent"] = pct(c.bound);
    fmt::print("{}\n", j.dump(2));
  } else if (c.within) {
    fmt::print("within {:.6g} ({:.5f}%): proved, no point of either surface is farther than {:.6g} ({:.5f}%) from the "
               "other\n", limit, pct(limit), c.bound, pct(c.bound));
  } else {
    fmt::print("not within {:.6g} ({:.5f}%): the point ({:.6g}, {:.6g}, {:.6g}) lies {:.6g} ({:.5f}%) from the other "
               "surface\n", limit, pct(limit), c.attained_at.x(), c.attained_at.y(), c.attained_at.z(), c.attained,
               pct(c.attained));
  }
  return c.within ? 0 : kNotWithin;
}

nlohmann::json directed_json(const DirectedDistance& d, const Comparison& c) {
  nlohmann::json j{{"max", d.max}, {"max_percent", c.percent(d.max)}, {"max_bound", d.max_bound},
          {"max_bound_percent", c.percent(d.max_bound)}, {"max_queries", d.max_queries},
          {"max_at", {d.max_at.x(), d.max_at.y(), d.max_at.z()}},
          {"max_nearest", {d.max_nearest.x(), d.max_nearest.y(), d.max_nearest.z()}}, {"mean", d.mean}, {"mean_percent", c.percent(d.mean)},
          {"rms", d.rms}, {"rms_percent", c.percent(d.rms)}, {"normal_deviation_mean_deg", d.normal_deviation_mean_deg},
          {"normal_deviation_max_deg", d.normal_deviation_max_deg}, {"samples", d.samples}};
  if (d.colour_rms) j["colour_rms"] = *d.colour_rms, j["colour_max"] = *d.colour_max;
  if (d.shading_rms_deg) j["shading_rms_deg"] = *d.shading_rms_deg, j["shading_max_deg"] = *d.shading_max_deg;
  if (d.uv_rms) j["uv_rms"] = *d.uv_rms, j["uv_max"] = *d.uv_max, j["uv_compared"] = d.uv_compared;
  return j;
}

}  // namespace

Command add_compare_command(CLI::App& app, const GlobalOptions&) {
  auto opt = std::make_shared<CompareCliOptions>();
  CLI::App* sub = app.add_subcommand("compare", "Distance between two surfaces (Hausdorff, mean, RMS, normals, colours, UVs)");
  sub->add_option("a", opt->a, "First mesh (percentages refer to its bounding-box diagonal)")->required();
  sub->add_option("b", opt->b, "Second mesh")->required();
  sub->add_option("--samples", opt->samples, "Face samples per direction (default 10 per face of the larger mesh)")
      ->check(kPositive);
  auto* within = sub->add_option("--within", opt->within,
                                 "Only decide whether the surfaces lie within this distance (or N% of A's diagonal) of "
                                 "each other, proved: exit 0 if so, 3 if not, naming a point farther");
  sub->add_flag("--json", opt->json, "Print one JSON object");
  sub->get_option("--samples")->excludes(within);
  sub->footer(R"(Examples:
  lodkit compare bunny.ply bunny_10k.ply
  lodkit compare original.obj simplified.obj --json --samples 2000000
  lodkit compare original.obj simplified.obj --within 0.1%   # exit 0: proved within, 3: not)");
  return {sub, [opt] {
            const Mesh a = read_input(opt->a, std::nullopt, {}, nullptr), b = read_input(opt->b, std::nullopt, {}, nullptr);
            // Named by file: the library can only say "the first mesh" or "the second".
            for (const auto& [mesh, path] : {std::pair{&a, opt->a}, std::pair{&b, opt->b}})
              if (mesh->num_faces() == 0) throw Error(fmt::format("{}: has no faces, so no surface to compare", path));
            if (opt->within) return run_within(*opt, a, b);
            CompareOptions o;
            o.samples = opt->samples;
            const Comparison c = compare(a, b, o);
            // The benchmarks' "flipped" faces, with A as the input: B's faces facing against A's nearest.
            const Index against = count_flipped_faces(a, b);
            if (opt->json) {
              nlohmann::json j{{"a", opt->a}, {"b", opt->b}, {"diagonal", c.diagonal},
                               {"hausdorff", c.hausdorff}, {"hausdorff_percent", c.percent(c.hausdorff)},
                               {"hausdorff_bound", c.hausdorff_bound},
                               {"hausdorff_bound_percent", c.percent(c.hausdorff_bound)}, {"mean", c.mean}, {"mean_percent", c.percent(c.mean)},
                               {"rms", c.rms}, {"rms_percent", c.percent(c.rms)},
                               {"a_to_b", directed_json(c.a_to_b, c)}, {"b_to_a", directed_json(c.b_to_a, c)},
                               {"b_faces_against_a", against}};
              if (c.colour_rms) j["colour_rms"] = *c.colour_rms;
              if (c.shading_rms_deg) j["shading_rms_deg"] = *c.shading_rms_deg;
              if (c.uv_rms) j["uv_rms"] = *c.uv_rms;
              fmt::print("{}\n", j.dump(2));
              return 0;
            }
            fmt::print("{:<22} {:>14} {:>12}\n", "", "distance", "% diagonal");
            auto row = [&](const char* name, double v) { fmt::print("{:<22} {:>14.6g} {:>11.5f}%\n", name, v, c.percent(v)); };
            row("Hausdorff", c.hausdorff);
            row("  A -> B (max)", c.a_to_b.max);
            row("  B -> A (max)", c.b_to_a.max);
            row("  certified at most", c.hausdorff_bound);
            // Where the farther one-sided maximum lies: the place to look at first.
            const DirectedDistance& worst = c.farther();
            const bool a_side = &worst == &c.a_to_b;
            fmt::print("{:<22} ({:.6g}, {:.6g}, {:.6g}) on {}, nearest ({:.6g}, {:.6g}, {:.6g}) on {}\n", "  attained at",
                       worst.max_at.x(), worst.max_at.y(), worst.max_at.z(), a_side ? "A" : "B", worst.max_nearest.x(),
                       worst.max_nearest.y(), worst.max_nearest.z(), a_side ? "B" : "A");
            row("mean", c.mean);
            row("RMS", c.rms);
            fmt::print("{:<22} {:>14.3f} deg (mean), {:.1f} deg (max)\n", "normal deviation A->B",
                       c.a_to_b.normal_deviation_mean_deg, c.a_to_b.normal_deviation_max_deg);
            if (c.colour_rms)
              fmt::print("{:<22} {:>14.6g} (RMS), A->B {:.6g}, B->A {:.6g} (max)\n", "colour deviation", *c.colour_rms,
                         *c.a_to_b.colour_max, *c.b_to_a.colour_max);
            if (c.shading_rms_deg)
              fmt::print("{:<22} {:>14.3f} deg (RMS), A->B {:.1f}, B->A {:.1f} deg (max)\n", "shading normals",
                         *c.shading_rms_deg, *c.a_to_b.shading_max_deg, *c.b_to_a.shading_max_deg);
            if (c.uv_rms)
              fmt::print("{:<22} {:>14.6g} (RMS), A->B {:.6g}, B->A {:.6g} (max); within charts: {:.1f} % and {:.1f} % of "
                         "the area\n",
                         "UV deviation", *c.uv_rms, *c.a_to_b.uv_max, *c.b_to_a.uv_max, 100 * c.a_to_b.uv_compared,
                         100 * c.b_to_a.uv_compared);
            fmt::print("{:<22} {:>14} of B's {} faces face against A's nearest face\n", "faces against A",
                       thousands(against), thousands(b.num_faces()));
            fmt::print("{:<22} {:>14} ({} + {})\n", "samples", thousands(c.a_to_b.samples + c.b_to_a.samples),
                       thousands(c.a_to_b.samples), thousands(c.b_to_a.samples));
            fmt::print("{:<22} {:>14.6g}\n", "diagonal of A", c.diagonal);
            return 0;
          }};
}

}  // namespace lodkit::cli
