// End-to-end: the lodkit binary as a user runs it.
#include <gtest/gtest.h>
#include <lodkit/inspect.h>
#include <lodkit/io.h>
#include <lodkit/metrics.h>
#include <lodkit/primitives.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <fmt/format.h>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

#include "bad_corpus.h"
#include "test_util.h"

#ifndef LODKIT_CLI
#error "LODKIT_CLI must name the lodkit executable"
#endif

namespace lodkit {
namespace {

struct CliRun {
  int status;
  std::string out, err;
};

CliRun run(const test::ScratchDir& dir, const std::string& args, const std::string& stdin_file = "") {
  const auto out = dir / ".stdout", err = dir / ".stderr";
  std::string cmd = "cd '" + dir.path().string() + "' && '" LODKIT_CLI "' " + args + " > '" + out.string() +
                    "' 2> '" + err.string() + "'";
  if (!stdin_file.empty()) cmd += " < '" + stdin_file + "'";
  const int raw = std::system(cmd.c_str());
  CliRun r{WIFEXITED(raw) ? WEXITSTATUS(raw) : -1, test::read_bytes(out), test::read_bytes(err)};
  std::filesystem::remove(out);
  std::filesystem::remove(err);
  return r;
}

TEST(Cli, VersionAndHelp) {
  test::ScratchDir dir("cli");
  CliRun r = run(dir, "--version");
  EXPECT_EQ(r.status, 0);
  EXPECT_NE(r.out.find("0."), std::string::npos);
  for (const char* cmd : {"--help", "info --help", "convert --help", "generate --help"}) {
    r = run(dir, cmd);
    EXPECT_EQ(r.status, 0) << cmd;
    EXPECT_NE(r.out.find("Examples:"), std::string::npos) << cmd;
  }
}

TEST(Cli, UsageErrorsExitTwo) {
  test::ScratchDir dir("cli");
  EXPECT_EQ(run(dir, "").status, 2);
  EXPECT_EQ(run(dir, "frobnicate").status, 2);
  EXPECT_EQ(run(dir, "generate dodecahedron -o x.ply").status, 2);
  EXPECT_EQ(run(dir, "generate torus").status, 2);  // no -o
  EXPECT_EQ(run(dir, "convert a.obj b.drc --quantize 99").status, 2);
}

TEST(Cli, ANumberOptionSaysBrieflyWhatIsWrongWithItsValue) {
  // CLI11's own checks named their upper bound, the largest double, in 310 digits, and called a word
  // out of range ("Value half not in range 0.000000 to 1.000000").
  test::ScratchDir dir("cli-numbers");
  ASSERT_EQ(run(dir, "generate grid -o g.ply").status, 0);
  const struct {
    const char* args;
    const char* says;
  } cases[] = {
      {"simplify g.ply -o s.ply --crease-weight -1", "--crease-weight: -1 is negative"},
      {"simplify g.ply -o s.ply --crease-weight abc", "--crease-weight: abc is not a number"},
      {"simplify g.ply -o s.ply --crease-weight inf", "--crease-weight: inf is not a finite number"},
      {"simplify g.ply -o s.ply --attribute-weights 0,x,1", "--attribute-weights: x is not a number"},
      {"simplify g.ply -o s.ply --faces -3", "--faces: -3 is negative"},
      {"compare g.ply g.ply --samples 0", "--samples: 0 is not above 0"},
      {"simplify g.ply -o s.ply --ratio 2", "--ratio: 2 is not between 0 and 1"},
      {"simplify g.ply -o s.ply --ratio half", "--ratio: half is not a number"},
      {"convert g.ply s.ply --quantize 99", "--quantize: 99 is not between 0 and 30"},
  };
  for (const auto& c : cases) {
    const CliRun r = run(dir, c.args);
    EXPECT_EQ(r.status, 2) << c.args;
    EXPECT_NE(r.err.find(c.says), std::string::npos) << c.args << ": " << r.err;
    EXPECT_LT(r.err.size(), 200u) << c.args << ": " << r.err;
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "s.ply"));
  EXPECT_EQ(run(dir, "simplify g.ply -o s.ply --crease-weight 2.5 --faces 8").status, 0);
}

TEST(CliSimplify, AnInputOfDegenerateFacesOnlySaysSoAndIsNotMeasured) {
  // Every face has a repeated corner: the engine drops them all, and --measure has no surface to measure.
  // It used to fail there ("compare: the second mesh has no faces", exit 1) after the output was written.
  test::ScratchDir dir("cli-degenerate");
  test::write_text(dir / "flat.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 1 1\nf 2 2 3\n");
  const CliRun text = run(dir, "simplify flat.obj -o s.ply --ratio 0.5 --measure");
  EXPECT_EQ(text.status, 0) << text.err;
  EXPECT_NE(text.err.find("dropped 2 degenerate faces"), std::string::npos) << text.err;
  EXPECT_NE(text.err.find("not measured: the output has no faces"), std::string::npos) << text.err;
  const CliRun json = run(dir, "simplify flat.obj -o s.ply --ratio 0.5 --measure --json");
  ASSERT_EQ(json.status, 0) << json.err;
  const auto j = nlohmann::json::parse(json.out);
  EXPECT_EQ(j["dropped_degenerate_faces"].get<int>(), 2);
  EXPECT_EQ(j["faces_out"].get<int>(), 0);
  EXPECT_TRUE(j["measured"].is_null());
  EXPECT_EQ(j["not_measured"].get<std::string>(), "the output has no faces");
  EXPECT_EQ(read_mesh((dir / "s.ply").string()).num_faces(), 0);
  // compare names the file that has no surface.
  const CliRun compared = run(dir, "compare flat.obj s.ply");
  EXPECT_EQ(compared.status, 1);
  EXPECT_NE(compared.err.find("s.ply: has no faces"), std::string::npos) << compared.err;
}

TEST(Cli, GeneratedTorusIsClosedManifoldGenusOne) {
  test::ScratchDir dir("cli");
  ASSERT_EQ(run(dir, "generate torus -o t.ply").status, 0);
  const CliRun r = run(dir, "info t.ply --json");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("\"closed\": true"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"manifold\": true"), std::string::npos);
  EXPECT_NE(r.out.find("\"genus\": 1"), std::string::npos);
  const CliRun text = run(dir, "info t.ply");
  EXPECT_NE(text.out.find("closed, manifold, oriented, 1 component, genus 1"), std::string::npos) << text.out;
}

TEST(Cli, ConvertChainKeepsCounts) {
  test::ScratchDir dir("cli");
  ASSERT_EQ(run(dir, "generate sphere -o s.obj --uvs --tolerance 0.01").status, 0);
  const Mesh original = read_mesh(dir / "s.obj");
  ASSERT_EQ(run(dir, "convert s.obj s.ply").status, 0);
  ASSERT_EQ(run(dir, "convert s.ply s.drc --quantize 16").status, 0);
  ASSERT_EQ(run(dir, "convert s.drc -o back.obj").status, 0);
  const Mesh back = read_mesh(dir / "back.obj");
  EXPECT_EQ(back.num_vertices(), original.num_vertices());
  EXPECT_EQ(back.num_faces(), original.num_faces());
  EXPECT_TRUE(back.has_uvs());
}

TEST(Cli, ConvertOrientTurnsDisagreeingFacesAndSaysHowMany) {
  test::ScratchDir dir("cli-convert-orient");
  const Mesh sphere = test::bumpy_sphere(2, 0.02);
  Mesh shuffled = sphere;
  Index turned = 0;
  for (Index f = 1; f < shuffled.num_faces(); f += 3) std::swap(shuffled.triangles(f, 1), shuffled.triangles(f, 2)), ++turned;
  write_mesh(shuffled, (dir / "s.ply").string());
  EXPECT_NE(run(dir, "info s.ply").out.find("hint         lodkit convert IN OUT --orient"), std::string::npos);
  const CliRun r = run(dir, "convert s.ply o.ply --orient");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find(fmt::format("turned {} faces", turned)), std::string::npos) << r.err;
  EXPECT_EQ(read_mesh((dir / "o.ply").string()).triangles, sphere.triangles);
  EXPECT_NE(run(dir, "convert o.ply p.ply --orient").err.find("turned 0 faces"), std::string::npos);
  EXPECT_EQ(run(dir, "info o.ply").out.find("hint"), std::string::npos);
}

TEST(Cli, StdinAndStdout) {
  test::ScratchDir dir("cli");
  ASSERT_EQ(run(dir, "generate box -o box.off").status, 0);
  const CliRun r = run(dir, "convert - - --from off --to obj", (dir / "box.off").string());
  ASSERT_EQ(r.status, 0) << r.err;
  const Mesh m = read_mesh_from_memory(r.out, MeshFormat::Obj, "stdout");
  EXPECT_EQ(m.num_faces(), 12);
  EXPECT_EQ(run(dir, "convert - out.ply", (dir / "box.off").string()).status, 1);  // no --from
}

TEST(Cli, RefusesToOverwriteTheInput) {
  test::ScratchDir dir("cli");
  ASSERT_EQ(run(dir, "generate box -o box.ply").status, 0);
  const std::string before = test::read_bytes(dir / "box.ply");
  const CliRun r = run(dir, "convert box.ply ./box.ply");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("refusing to overwrite the input"), std::string::npos) << r.err;
  EXPECT_EQ(test::read_bytes(dir / "box.ply"), before);

  // Every input counts, not only the first: a boolean's second mesh, a mesh a CSG tree reads (its path
  // relative to the tree's file), the tree itself, the mesh a level is proved against.
  ASSERT_EQ(run(dir, "generate sphere -o ball.ply --segments 12 --rings 8").status, 0);
  ASSERT_EQ(run(dir, "pm build ball.ply -o ball.pm").status, 0);
  std::filesystem::create_directory(dir / "parts");
  std::filesystem::copy_file(dir / "box.ply", dir / "parts" / "box.ply");
  test::write_text(dir / "parts" / "tree.json",
                   R"({"op": "union", "children": [{"mesh": "box.ply"}, {"primitive": "sphere", "radius": 0.7}]})");
  std::filesystem::copy_file(dir / "parts" / "tree.json", dir / "tree.ply");
  const std::string ball = test::read_bytes(dir / "ball.ply"), tree = test::read_bytes(dir / "tree.ply");
  for (const char* command : {"csg union box.ply ball.ply -o ball.ply", "csg difference box.ply ball.ply -o ./ball.ply",
                              "csg tree parts/tree.json -o parts/box.ply", "csg tree parts/tree.json -o parts/../parts/box.ply",
                              "csg tree tree.ply -o tree.ply", "pm extract ball.pm -o ball.ply --max-error 0.05 --prove-with ball.ply"}) {
    const CliRun refused = run(dir, command);
    EXPECT_EQ(refused.status, 1) << command;
    EXPECT_NE(refused.err.find("refusing to overwrite the input"), std::string::npos) << command << ": " << refused.err;
  }
  EXPECT_TRUE(test::read_bytes(dir / "parts" / "box.ply") == before);
  EXPECT_TRUE(test::read_bytes(dir / "ball.ply") == ball);
  EXPECT_TRUE(test::read_bytes(dir / "tree.ply") == tree);
}

TEST(Cli, StreamsGoThroughStdinAndStdout) {
  test::ScratchDir dir("cli");
  ASSERT_EQ(run(dir, "generate torus -o t.ply --major-segments 16 --minor-segments 8").status, 0);
  // A .pm stream to stdout is the file's bytes (it was written to a file named "-"), and every pm
  // command reads one from stdin.
  ASSERT_EQ(run(dir, "pm build t.ply -o t.pm").status, 0);
  CliRun r = run(dir, "pm build t.ply -o -");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(r.out == test::read_bytes(dir / "t.pm"));
  EXPECT_FALSE(std::filesystem::exists(dir / "-"));
  ASSERT_EQ(run(dir, "pm extract t.pm -o from_file.ply --faces 100").status, 0);
  r = run(dir, "pm extract - -o from_stdin.ply --faces 100", (dir / "t.pm").string());
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(test::read_bytes(dir / "from_stdin.ply") == test::read_bytes(dir / "from_file.ply"));
  EXPECT_EQ(run(dir, "pm info - --json", (dir / "t.pm").string()).status, 0);
  EXPECT_EQ(run(dir, "pm geomorph - --from 50 --to 100 --alpha 0.5 -o m.ply", (dir / "t.pm").string()).status, 0);

  // simplify's --format names the streams' format, not a file's: PLY in, OFF out.
  ASSERT_EQ(run(dir, "simplify t.ply -o s.off --ratio 0.5").status, 0);
  r = run(dir, "simplify t.ply -o - --format off --ratio 0.5");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(r.out == test::read_bytes(dir / "s.off"));
  r = run(dir, "simplify t.ply -o s.obj --format off --ratio 0.5");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("neither is used"), std::string::npos) << r.err;

  // One stdout: --json beside a mesh or stream written there is refused, as are frames named "-".
  for (const char* both : {"simplify t.ply -o - --format off --ratio 0.5 --json", "pm build t.ply -o - --json",
                           "pm extract t.pm -o - --format off --faces 50 --json",
                           "csg union t.ply t.ply -o - --format off --json"}) {
    r = run(dir, both);
    EXPECT_EQ(r.status, 1) << both;
    EXPECT_NE(r.err.find("--json prints there"), std::string::npos) << both << ": " << r.err;
    EXPECT_TRUE(r.out.empty()) << both;
  }
  r = run(dir, "pm geomorph t.pm --from 50 --to 100 --frames 3 -o -");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("file name"), std::string::npos) << r.err;
  // convert's streams take --from and --to, and its messages say so.
  EXPECT_NE(run(dir, "convert t.ply -").err.find("--to"), std::string::npos);
  EXPECT_NE(run(dir, "convert - x.ply", (dir / "t.ply").string()).err.find("--from"), std::string::npos);
  // Each stream's message names the command's own option, or says it takes none.
  EXPECT_NE(run(dir, "subdivide - -o x.ply", (dir / "t.ply").string()).err.find("--input-format"), std::string::npos);
  EXPECT_NE(run(dir, "compare - t.ply", (dir / "t.ply").string()).err.find("files only"), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(dir / "-"));
}

// Interrupted mid-write (SIGTERM here, SIGINT from Ctrl-C alike), lodkit removes its temporary file
// and dies of the signal: a killed 67-million-face terrain left a hidden 247 MB file beside its target.
TEST(Cli, AnInterruptedWriteLeavesNothingBehind) {
  test::ScratchDir dir("cli-signal");
  const std::string path = dir.path().string();
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {  // (only exec-safe calls here)
    if (chdir(path.c_str()) != 0) _exit(127);
    execl(LODKIT_CLI, LODKIT_CLI, "-q", "terrain", "-o", "big.ply", "--levels", "10", static_cast<char*>(nullptr));
    _exit(127);
  }
  const auto writing = [&] {
    for (const auto& e : std::filesystem::directory_iterator(dir.path()))
      if (e.path().filename().string().starts_with(".big.ply.tmp-")) return true;
    return false;
  };
  // Caught mid-write (the write takes about a quarter of a second): stopped while the temporary file
  // exists and the target does not, then terminated.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (!writing() && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  kill(pid, SIGSTOP);
  const bool caught = writing() && !std::filesystem::exists(dir / "big.ply");
  kill(pid, SIGTERM);
  kill(pid, SIGCONT);
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(caught) << "the write was not caught in progress";
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGTERM) << status;
  EXPECT_EQ(dir.entries(), 0u) << "a temporary file was left behind";
}

TEST(Cli, BadInputCorpusExitsOneNamingTheFileAndWritesNothing) {
  test::ScratchDir dir("cli-bad");
  const auto corpus = test::write_bad_corpus(dir.path());
  const std::size_t files_before = dir.entries();
  for (const auto& bad : corpus) {
    const CliRun r = run(dir, "convert '" + bad.name + "' out.ply");
    EXPECT_EQ(r.status, 1) << bad.name;
    const std::string prefix = "lodkit: error: " + bad.name + ": ";
    EXPECT_EQ(r.err.rfind(prefix, 0), 0u) << bad.name << ": " << r.err;
    EXPECT_NE(r.err.find(bad.expected), std::string::npos) << bad.name << ": " << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "out.ply")) << bad.name;
    EXPECT_EQ(run(dir, "info '" + bad.name + "'").status, 1) << bad.name;
  }
  EXPECT_EQ(run(dir, "info missing.obj").status, 1);
  EXPECT_EQ(dir.entries(), files_before) << "no stray output or temporary files";
}

}  // namespace
}  // namespace lodkit

namespace lodkit {
namespace {

TEST(CliSimplify, EveryMethodEndToEndWithJsonAndMeasure) {
  test::ScratchDir dir("cli-simplify");
  ASSERT_EQ(run(dir, "generate torus -o t.ply --tolerance 0.002").status, 0);
  for (const char* method : {"quadric", "hoppe", "edge-length", "schroeder"}) {
    const CliRun r = run(dir, std::string("simplify t.ply -o s.obj --ratio 0.2 --measure --json --method ") + method);
    ASSERT_EQ(r.status, 0) << method << ": " << r.err;
    EXPECT_NE(r.out.find(std::string("\"method\": \"") + method + "\""), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("\"hausdorff_percent\""), std::string::npos) << r.out;
    const Mesh out = read_mesh(dir / "s.obj");
    EXPECT_LT(out.num_faces(), read_mesh(dir / "t.ply").num_faces() / 4);
  }
  const CliRun compared = run(dir, "compare t.ply s.obj");
  EXPECT_EQ(compared.status, 0);
  EXPECT_NE(compared.out.find("Hausdorff"), std::string::npos);
}

TEST(CliCompare, ColoursAreReportedWhenBothMeshesHaveThem) {
  test::ScratchDir dir("cli-compare-colours");
  Mesh a = make_icosphere({.subdivisions = 2});
  a.attributes.colours = Colours::Constant(a.num_vertices(), 4, 0.5f);
  Mesh b = a;
  b.attributes.colours.col(1).array() += 0.25f;
  write_mesh(a, (dir / "a.ply").string());
  write_mesh(b, (dir / "b.ply").string());
  CliRun r = run(dir, "compare a.ply b.ply --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_NEAR(j["colour_rms"].get<double>(), 0.25, 1e-6);
  EXPECT_NEAR(j["b_to_a"]["colour_max"].get<double>(), 0.25, 1e-6);
  r = run(dir, "compare a.ply b.ply");
  EXPECT_NE(r.out.find("colour deviation"), std::string::npos) << r.out;
  r = run(dir, "simplify b.ply -o s.ply --ratio 0.5 --measure --json");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(nlohmann::json::parse(r.out)["measured"].contains("colour_rms")) << r.out;
  write_mesh(make_icosphere({.subdivisions = 2}), (dir / "plain.ply").string());
  EXPECT_FALSE(nlohmann::json::parse(run(dir, "compare a.ply plain.ply --json").out).contains("colour_rms"));
}

// The benchmarks' "flipped" count for any two files: B's faces facing against A's nearest face. A
// sphere against itself has none; with a cap of faces turned, those count.
TEST(CliCompare, CountsTheFacesOfBFacingAgainstA) {
  test::ScratchDir dir("cli-compare-against");
  const Mesh a = make_icosphere({.subdivisions = 2});
  Mesh b = a;
  Index turned = 0;
  for (Index f = 0; f < b.num_faces(); ++f)
    if (b.positions(b.triangles(f, 0), 2) > 0.5 && b.positions(b.triangles(f, 1), 2) > 0.5 &&
        b.positions(b.triangles(f, 2), 2) > 0.5)
      std::swap(b.triangles(f, 1), b.triangles(f, 2)), ++turned;
  ASSERT_GT(turned, 0);
  write_mesh(a, (dir / "a.ply").string());
  write_mesh(b, (dir / "b.ply").string());
  CliRun r = run(dir, "compare a.ply a.ply --json");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["b_faces_against_a"].get<Index>(), 0);
  r = run(dir, "compare a.ply b.ply --json");
  EXPECT_EQ(nlohmann::json::parse(r.out)["b_faces_against_a"].get<Index>(), turned);
  r = run(dir, "compare a.ply b.ply");
  EXPECT_NE(r.out.find(fmt::format("{} of B's {} faces face against", turned, b.num_faces())), std::string::npos) << r.out;
}

// An STL of one facet with two equal corners crashed compare (no face was nearest anything: the
// closest-point kernel gave NaN for such a triangle); found by fuzzing. It is a segment: 0 apart.
TEST(CliCompare, AMeshOfOneFaceWithARepeatedCornerIsMeasured) {
  test::ScratchDir dir("cli-compare-repeated");
  {
    std::ofstream out(dir / "seg.stl");
    out << "solid s\nfacet normal 0 0 0\nouter loop\nvertex 1 0 -1\nvertex 1 0 -1\nvertex 0.5 -0.8660254 -1\n"
           "endloop\nendfacet\nendsolid s\n";
  }
  const CliRun r = run(dir, "compare seg.stl seg.stl --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto json = nlohmann::json::parse(r.out);
  EXPECT_LT(json["hausdorff"].get<double>(), 1e-12);
  EXPECT_LT(json["hausdorff_bound"].get<double>(), 1e-12);
}

TEST(CliCompare, ShadingNormalsAreReportedWhenBothMeshesHaveThem) {
  test::ScratchDir dir("cli-compare-shading");
  Mesh a = make_icosphere({.subdivisions = 2});
  a.attributes.normals = compute_vertex_normals(a);
  Mesh b = a;
  b.attributes.normals.col(2).array() *= -1.0;  // every normal mirrored in z: 0 to 180 degrees off
  write_mesh(a, (dir / "a.ply").string());
  write_mesh(b, (dir / "b.ply").string());
  CliRun r = run(dir, "compare a.ply a.ply --json");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NEAR(nlohmann::json::parse(r.out)["shading_rms_deg"].get<double>(), 0.0, 1e-6);
  r = run(dir, "compare a.ply b.ply --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_GT(j["shading_rms_deg"].get<double>(), 30.0);
  EXPECT_GT(j["a_to_b"]["shading_max_deg"].get<double>(), 170.0);
  r = run(dir, "compare a.ply b.ply");
  EXPECT_NE(r.out.find("shading normals"), std::string::npos) << r.out;
  r = run(dir, "simplify a.ply -o s.ply --ratio 0.5 --measure --json");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(nlohmann::json::parse(r.out)["measured"].contains("shading_rms_deg")) << r.out;
  write_mesh(make_icosphere({.subdivisions = 2}), (dir / "plain.ply").string());
  EXPECT_FALSE(nlohmann::json::parse(run(dir, "compare a.ply plain.ply --json").out).contains("shading_rms_deg"));
}

TEST(CliCompare, UvDeviationIsReportedWhenBothMeshesHaveUvs) {
  // A UV sphere and its simplification: a UV distance within charts, most of the area compared, and
  // UV weights that lower it; in JSON, in the text and in simplify --measure. No UVs, no figure.
  test::ScratchDir dir("cli-compare-uv");
  ASSERT_EQ(run(dir, "generate sphere -o a.obj --uvs").status, 0);
  CliRun r = run(dir, "simplify a.obj -o s.obj --ratio 0.2 --measure --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const double measured = nlohmann::json::parse(r.out)["measured"]["uv_rms"].get<double>();
  r = run(dir, "compare a.obj s.obj --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_DOUBLE_EQ(j["uv_rms"].get<double>(), measured);
  EXPECT_GT(measured, 0.0);
  EXPECT_LT(j["a_to_b"]["uv_max"].get<double>(), 0.5);  // none compared across the u = 0 / 1 seam, 1 apart
  EXPECT_GT(j["a_to_b"]["uv_compared"].get<double>(), 0.9);
  EXPECT_GT(j["b_to_a"]["uv_compared"].get<double>(), 0.9);
  r = run(dir, "simplify a.obj -o w.obj --ratio 0.2 --attribute-weights 0,1,0 --measure --json");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_LT(nlohmann::json::parse(r.out)["measured"]["uv_rms"].get<double>(), measured);
  EXPECT_NE(run(dir, "compare a.obj s.obj").out.find("UV deviation"), std::string::npos);
  ASSERT_EQ(run(dir, "generate sphere -o plain.obj").status, 0);
  EXPECT_FALSE(nlohmann::json::parse(run(dir, "compare a.obj plain.obj --json").out).contains("uv_rms"));
}

TEST(CliSimplify, NormalsAndColoursAreFittedUnlessAskedNotTo) {
  test::ScratchDir dir("cli-simplify-attribute-fit");
  Mesh a = test::bumpy_sphere(3, 0.03);
  a.attributes.normals = compute_vertex_normals(a);
  write_mesh(a, (dir / "a.ply").string());
  CliRun r = run(dir, "simplify a.ply -o s.ply --ratio 0.1 --measure --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto fitted = nlohmann::json::parse(r.out);
  ASSERT_TRUE(fitted.contains("attribute_fit")) << r.out;
  EXPECT_TRUE(fitted["attribute_fit"]["normals"].get<bool>());
  EXPECT_FALSE(fitted["attribute_fit"]["colours"].get<bool>());
  r = run(dir, "simplify a.ply -o k.ply --ratio 0.1 --measure --json --no-attribute-fit");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto kept = nlohmann::json::parse(r.out);
  EXPECT_FALSE(kept.contains("attribute_fit"));
  EXPECT_LT(fitted["measured"]["shading_rms_deg"].get<double>(), kept["measured"]["shading_rms_deg"].get<double>());
  EXPECT_EQ(fitted["measured"]["hausdorff"].get<double>(), kept["measured"]["hausdorff"].get<double>());
  r = run(dir, "simplify a.ply -o s.ply --ratio 0.1");
  EXPECT_NE(r.err.find("normals fitted to the input's"), std::string::npos) << r.err;
  // schroeder: normals carried and fitted, or positions only.
  r = run(dir, "simplify a.ply -o d.ply --ratio 0.1 --method schroeder --json");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(nlohmann::json::parse(r.out)["attribute_fit"]["normals"].get<bool>()) << r.out;
  EXPECT_TRUE(read_mesh((dir / "d.ply").string()).has_normals());
  r = run(dir, "simplify a.ply -o d.ply --ratio 0.1 --method schroeder --no-attribute-fit --json");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_FALSE(nlohmann::json::parse(r.out).contains("attribute_fit")) << r.out;
  EXPECT_FALSE(read_mesh((dir / "d.ply").string()).has_normals());
}

TEST(CliCompare, WithinDecidesAndExitsByTheAnswer) {
  // --within E against the full comparison: just above its certified bound, proved within (exit 0);
  // just below the distance it attained, a point farther is named (exit 3).
  test::ScratchDir dir("cli-compare-within");
  write_mesh(test::bumpy_sphere(3, 0.05), (dir / "b.ply").string());
  ASSERT_EQ(run(dir, "simplify b.ply -o s.ply --ratio 0.05").status, 0);
  const CliRun full = run(dir, "compare b.ply s.ply --json");
  ASSERT_EQ(full.status, 0) << full.err;
  const auto c = nlohmann::json::parse(full.out);
  const double bound = c["hausdorff_bound"].get<double>(), attained = c["hausdorff"].get<double>();
  CliRun r = run(dir, fmt::format("compare b.ply s.ply --within {:.17g} --json", bound * (1 + 1e-6)));
  EXPECT_EQ(r.status, 0) << r.err;
  auto j = nlohmann::json::parse(r.out);
  EXPECT_TRUE(j["within"].get<bool>());
  EXPECT_LE(j["bound"].get<double>(), bound * (1 + 1e-6));
  r = run(dir, fmt::format("compare b.ply s.ply --within {:.17g} --json", attained * (1 - 1e-3)));
  EXPECT_EQ(r.status, 3) << r.err;
  j = nlohmann::json::parse(r.out);
  EXPECT_FALSE(j["within"].get<bool>());
  EXPECT_GT(j["attained"].get<double>(), attained * (1 - 1e-3));
  EXPECT_FALSE(j.contains("bound"));
  r = run(dir, "compare b.ply s.ply --within 50%");
  EXPECT_EQ(r.status, 0);
  EXPECT_NE(r.out.find("proved"), std::string::npos) << r.out;
  EXPECT_EQ(run(dir, "compare b.ply s.ply --within 1% --samples 100").status, 2);
  EXPECT_NE(run(dir, "compare b.ply s.ply --within -1%").status, 0);
}

TEST(CliSimplify, LanesAreReportedAndCanBeTurnedOff) {
  test::ScratchDir dir("cli-simplify-lanes");
  ASSERT_EQ(run(dir, "generate torus -o t.ply --tolerance 0.0005").status, 0);
  CliRun r = run(dir, "simplify t.ply -o s.ply --ratio 0.05 --lane-faces 2000");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("slabs simplified side by side"), std::string::npos) << r.err;
  r = run(dir, "simplify t.ply -o s.ply --ratio 0.05 --lane-faces 0 --json");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("\"lanes\": 1"), std::string::npos) << r.out;
  EXPECT_EQ(run(dir, "simplify t.ply -o s.ply --lane-faces -1").status, 2);
  // Unset, the slabs depend on the method: the 22k-face torus is too small for quadric's 125,000 faces
  // per slab, and gets two of hoppe's 8,000.
  r = run(dir, "simplify t.ply -o s.ply --ratio 0.05 --json");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["lanes"].get<int>(), 1);
  r = run(dir, "simplify t.ply -o s.ply --ratio 0.05 --method hoppe --json");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["lanes"].get<int>(), 2);
}

TEST(CliSimplify, TheRefitIsReportedAndCanBeTurnedOff) {
  // quadric refits by default: the JSON says what it did, the human output says it in one line, and
  // the measured Hausdorff distance is lower than with --refit-passes 0.
  test::ScratchDir dir("cli-simplify-refit");
  write_mesh(test::bumpy_sphere(4, 0.04), (dir / "b.ply").string());
  CliRun r = run(dir, "simplify b.ply -o s.ply --ratio 0.05 --measure --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto with = nlohmann::json::parse(r.out);
  ASSERT_TRUE(with.contains("refit")) << r.out;
  // Both stages: 10 passes towards the largest distances, then up to 8 towards the RMS.
  EXPECT_GT(with["refit"]["passes"].get<int>(), 10);
  EXPECT_LE(with["refit"]["passes"].get<int>(), 18);
  EXPECT_GT(with["refit"]["rms_steps"].get<int>(), 0);
  EXPECT_LT(with["refit"]["sampled_max_after"].get<double>(), with["refit"]["sampled_max_before"].get<double>());
  EXPECT_LT(with["refit"]["sampled_rms_after"].get<double>(), with["refit"]["sampled_rms_before"].get<double>());
  r = run(dir, "simplify b.ply -o s0.ply --ratio 0.05 --measure --json --refit-passes 0");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto without = nlohmann::json::parse(r.out);
  EXPECT_FALSE(without.contains("refit"));
  EXPECT_LT(with["measured"]["hausdorff"].get<double>(), without["measured"]["hausdorff"].get<double>());
  // The second stage lowers the RMS and keeps the largest distances.
  r = run(dir, "simplify b.ply -o s1.ply --ratio 0.05 --measure --json --refit-rms-passes 0");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto first_only = nlohmann::json::parse(r.out);
  EXPECT_EQ(first_only["refit"]["passes"].get<int>(), 10);
  EXPECT_LT(with["measured"]["rms"].get<double>(), first_only["measured"]["rms"].get<double>());
  EXPECT_LT(with["measured"]["hausdorff"].get<double>(), 1.02 * first_only["measured"]["hausdorff"].get<double>());
  r = run(dir, "simplify b.ply -o s.ply --ratio 0.05");
  EXPECT_NE(r.err.find("refit: largest sampled distance"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(", RMS "), std::string::npos) << r.err;
  // hoppe takes it when asked; schroeder has no such step and refuses the option.
  r = run(dir, "simplify b.ply -o s.ply --ratio 0.05 --method hoppe --refit-passes 3 --refit-rms-passes 0 --json");
  ASSERT_EQ(r.status, 0) << r.err;
  // (A fourth pass measures again before faces facing against the input are turned, where the first stage
  // ended on a step it undid.)
  const auto three = nlohmann::json::parse(r.out)["refit"];
  EXPECT_EQ(three["passes"].get<int>(), three["inverted_before"].get<int>() > 0 ? 4 : 3) << three;
  EXPECT_LE(three["steps"].get<int>(), 2);
  r = run(dir, "simplify b.ply -o s.ply --ratio 0.05 --method hoppe --refit-passes 0 --refit-rms-passes 2 --json");  // the second stage alone
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["refit"]["steps"].get<int>(), 0);
  EXPECT_LE(nlohmann::json::parse(r.out)["refit"]["passes"].get<int>(), 2);
  EXPECT_EQ(run(dir, "simplify b.ply -o s.ply --refit-rms-passes -1").status, 2);
  EXPECT_EQ(run(dir, "simplify b.ply -o s.ply --refit-passes -1").status, 2);
  EXPECT_EQ(run(dir, "simplify b.ply -o s.ply --refit-passes 3 --method schroeder").status, 2);
}

TEST(CliSimplify, HoppesFitIsReportedAndCanBeTurnedOff) {
  // hoppe fits its vertices after the collapses by default: the JSON gives the energy before and after,
  // the human output says it in one line, and with --hoppe-fit-passes 0 there is no fit and a higher RMS
  // (without the refit, which would move the vertices again).
  test::ScratchDir dir("cli-simplify-hoppe-fit");
  write_mesh(test::bumpy_sphere(4, 0.04), (dir / "b.ply").string());
  CliRun r = run(dir, "simplify b.ply -o s.ply --ratio 0.1 --method hoppe --measure --json --refit-passes 0");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto with = nlohmann::json::parse(r.out);
  ASSERT_TRUE(with.contains("hoppe_fit")) << r.out;
  EXPECT_EQ(with["hoppe_fit"]["passes"].get<int>(), 1);
  EXPECT_LT(with["hoppe_fit"]["energy_after"].get<double>(), with["hoppe_fit"]["energy_before"].get<double>());
  r = run(dir, "simplify b.ply -o s0.ply --ratio 0.1 --method hoppe --measure --json --hoppe-fit-passes 0 --refit-passes 0");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto without = nlohmann::json::parse(r.out);
  EXPECT_FALSE(without.contains("hoppe_fit"));
  EXPECT_LT(with["measured"]["rms"].get<double>(), without["measured"]["rms"].get<double>());
  // The quadric stage before the energy: where the energy took over, in the JSON and in one line.
  const int from = with["hoppe_energy_from_faces"].get<int>(), target = with["target_faces"].get<int>();
  EXPECT_TRUE(from == 2 * target || from == 2 * target + 1) << r.out;  // a collapse removes two faces
  EXPECT_FALSE(nlohmann::json::parse(run(dir, "simplify b.ply -o s.ply --ratio 0.1 --method hoppe --json --hoppe-energy-from 0").out)
                   .contains("hoppe_energy_from_faces"));
  EXPECT_EQ(run(dir, "simplify b.ply -o s.ply --method hoppe --hoppe-energy-from -1").status, 2);
  r = run(dir, "simplify b.ply -o s.ply --ratio 0.1 --method hoppe --hoppe-fit-passes 2");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("hoppe's fit: energy"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("in 2 passes"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("the quadric error ranked the collapses down to"), std::string::npos) << r.err;
  // Refused before anything is written: a negative count, or the option with another method.
  EXPECT_EQ(run(dir, "simplify b.ply -o t.ply --method hoppe --hoppe-fit-passes -1").status, 2);
  const CliRun other = run(dir, "simplify b.ply -o t.ply --hoppe-fit-passes 1");
  EXPECT_EQ(other.status, 2);
  EXPECT_NE(other.err.find("--hoppe-fit-passes: applies to --method hoppe"), std::string::npos) << other.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "t.ply"));
}

TEST(CliSimplify, FacesThatDisagreeOnOrientationAreTurnedFirstAndSaidSo) {
  // Every other face of a sphere turned: the JSON counts the faces turned, the summary says it, and
  // --measure counts faces facing against the turned input (none), not against the shuffled one.
  test::ScratchDir dir("cli-simplify-orient");
  Mesh m = test::bumpy_sphere(3, 0.02);
  Index turned = 0;
  for (Index f = 0; f < m.num_faces(); f += 2) std::swap(m.triangles(f, 1), m.triangles(f, 2)), ++turned;
  write_mesh(m, (dir / "s.ply").string());
  CliRun r = run(dir, "simplify s.ply -o o.ply --ratio 0.1 --measure --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["reason"], "target");
  EXPECT_EQ(j["measured"]["inverted_faces"].get<Index>(), 0);
  const Index reoriented = j["reoriented_faces"].get<Index>();
  EXPECT_TRUE(reoriented == turned || reoriented == m.num_faces() - turned) << reoriented;
  EXPECT_TRUE(inspect(read_mesh((dir / "o.ply").string())).oriented);
  r = run(dir, "simplify s.ply -o o.ply --ratio 0.1 --method schroeder");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("faces of the input to agree with their neighbours' orientation first"), std::string::npos) << r.err;
  // Kept as they are, the disagreeing edges lock their ends, and the reason says so.
  r = run(dir, "simplify s.ply -o k.ply --ratio 0.1 --keep-orientation --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto k = nlohmann::json::parse(r.out);
  EXPECT_EQ(k["reason"], "no-legal-collapse");
  EXPECT_EQ(k["reoriented_faces"].get<Index>(), 0);
  EXPECT_NE(k["reason_text"].get<std::string>().find("disagreeing on orientation"), std::string::npos) << k;
  r = run(dir, "pm build s.ply -o s.pm --json");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["reoriented_faces"].get<Index>(), reoriented);
}

TEST(CliSimplify, ReasonIsPrintedWhenTheTargetIsOutOfReach) {
  test::ScratchDir dir("cli-simplify");
  ASSERT_EQ(run(dir, "generate box -o b.ply --divisions 4").status, 0);
  const CliRun r = run(dir, "simplify b.ply -o s.ply --faces 4 --method schroeder");
  EXPECT_EQ(r.status, 0);
  EXPECT_NE(r.err.find("8 corner"), std::string::npos) << r.err;
  const CliRun q = run(dir, "simplify b.ply -o s.ply --faces 4 --max-error 0.1%");
  EXPECT_NE(q.err.find("stopped at 12 faces"), std::string::npos) << q.err;
  EXPECT_NE(q.err.find("error limit"), std::string::npos) << q.err;
  EXPECT_EQ(run(dir, "simplify b.ply -o s.ply --max-error 1x").status, 1);
  EXPECT_EQ(run(dir, "simplify b.ply -o s.ply --ratio 2").status, 2);
}

TEST(CliSimplify, StoppingAtTheValenceLimitNamesTheOptionThatLiftsIt) {
  test::ScratchDir dir("cli-simplify-valence");
  ASSERT_EQ(run(dir, "generate torus -o g.ply").status, 0);
  const CliRun r = run(dir, "simplify g.ply -o s.ply --faces 16 --max-valence 8 --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto json = nlohmann::json::parse(r.out);
  EXPECT_GT(json["blocked"]["valence"].get<int>(), 0);
  EXPECT_NE(json["hint"].get<std::string>().find("--max-valence 0"), std::string::npos) << json.dump();
  EXPECT_NE(run(dir, "simplify g.ply -o s.ply --faces 16 --max-valence 8").err.find("blocked by the valence limit"),
            std::string::npos);
  EXPECT_EQ(run(dir, "simplify g.ply -o s.ply --faces 16 --max-valence 0").err.find("valence"), std::string::npos);
  EXPECT_EQ(run(dir, "simplify g.ply -o s.ply --faces 16 --max-valence -3").status, 2);
}

TEST(CliSimplify, StoppingAtTheFlipLimitNamesTheOptionThatLiftsIt) {
  test::ScratchDir dir("cli-simplify-hint");
  ASSERT_EQ(run(dir, "generate torus -o t.ply --minor-radius 0.05 --major-segments 96 --minor-segments 8").status, 0);
  const CliRun r = run(dir, "simplify t.ply -o s.ply --faces 16");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("blocked by face flips"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("hint: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--max-normal-change 90"), std::string::npos) << r.err;
  const CliRun j = run(dir, "simplify t.ply -o s.ply --faces 16 --json");
  ASSERT_EQ(j.status, 0) << j.err;
  const auto json = nlohmann::json::parse(j.out);
  EXPECT_GT(json["blocked"]["flips"].get<int>(), 0);
  EXPECT_EQ(json["blocked"]["remaining"].get<int>(), json["faces_out"].get<int>() * 3 / 2);
  EXPECT_TRUE(json.contains("hint"));
  // Already at 90 degrees, or reaching the target: no hint.
  EXPECT_EQ(run(dir, "simplify t.ply -o s.ply --faces 16 --max-normal-change 90").err.find("hint"), std::string::npos);
  const CliRun reached = run(dir, "simplify t.ply -o s.ply --faces 400 --json");
  EXPECT_EQ(reached.err.find("hint"), std::string::npos) << reached.err;
  EXPECT_FALSE(nlohmann::json::parse(reached.out).contains("blocked"));
}

TEST(CliSimplify, FlatShadedInputNamesAndTakesRecomputeNormals) {
  // Every edge of a flat-shaded mesh is a normal seam: the run stops at once and says which option
  // lets it go; with it, the target is reached and the output has normals of its own.
  test::ScratchDir dir("cli-simplify-flat");
  write_mesh(test::flat_shaded(test::bumpy_sphere(3, 0.02)), (dir / "flat.ply").string());
  const CliRun stuck = run(dir, "simplify flat.ply -o s.ply --faces 128 --json");
  ASSERT_EQ(stuck.status, 0) << stuck.err;
  const auto j = nlohmann::json::parse(stuck.out);
  EXPECT_EQ(j["faces_out"].get<int>(), 1280);
  EXPECT_GT(j["blocked"]["seams"].get<int>(), 0);
  EXPECT_NE(j["hint"].get<std::string>().find("--recompute-normals"), std::string::npos) << j.dump();
  const CliRun done = run(dir, "simplify flat.ply -o s.ply --faces 128 --recompute-normals");
  ASSERT_EQ(done.status, 0) << done.err;
  EXPECT_EQ(done.err.find("hint"), std::string::npos) << done.err;
  const Mesh out = read_mesh((dir / "s.ply").string());
  EXPECT_EQ(out.num_faces(), 128);
  EXPECT_TRUE(out.has_normals());
  EXPECT_TRUE(inspect(out).closed);
}

TEST(CliSimplify, MaxHausdorffIsProvedAndMeasuredBelowTheLimit) {
  // --max-hausdorff 1%: the output's distance to the input, proved and then measured by compare, is
  // within 1 % of the diagonal, and the JSON names the next coarser level, farther than that.
  // --max-error 1% bounds each collapse's estimate only: its output lies farther than 1 % here.
  test::ScratchDir dir("cli-simplify-within");
  write_mesh(test::bumpy_sphere(3, 0.05), (dir / "b.ply").string());
  CliRun r = run(dir, "simplify b.ply -o s.ply --max-hausdorff 1% --measure --json");
  ASSERT_EQ(r.status, 0) << r.err;
  nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["reason"], "hausdorff-limit");
  const auto& limit = j["hausdorff_limit"];
  EXPECT_NEAR(limit["max_distance_percent"].get<double>(), 1.0, 1e-12);
  EXPECT_LE(limit["bound_percent"].get<double>(), 1.0);
  EXPECT_GT(limit["coarser_attained_percent"].get<double>(), 1.0);
  EXPECT_LT(limit["coarser_faces"].get<int>(), j["faces_out"].get<int>());
  EXPECT_LE(j["measured"]["hausdorff_percent"].get<double>(), 1.0);
  EXPECT_EQ(read_mesh((dir / "s.ply").string()).num_faces(), j["faces_out"].get<int>());
  r = run(dir, "simplify b.ply -o e.ply --max-error 1% --measure --json");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_GT(nlohmann::json::parse(r.out)["measured"]["hausdorff_percent"].get<double>(), 1.0);
  // Plain text says what was proved; a bad limit or a method without collapses is refused.
  r = run(dir, "simplify b.ply -o s.ply --max-hausdorff 0.01 --faces 500");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("proved at most"), std::string::npos) << r.err;
  // A pixel budget is the distance that projects to that many pixels at the bounding sphere's nearest
  // point: 1 px at distance 10, 60 degrees, 1080 px.
  r = run(dir, "simplify b.ply -o p.ply --pixel-error 1 --distance 10 --measure --json");
  ASSERT_EQ(r.status, 0) << r.err;
  j = nlohmann::json::parse(r.out);
  const double radius = 0.5 * bounding_box(test::bumpy_sphere(3, 0.05)).diagonal().norm();
  const double one_pixel = 2 * (10 - radius) * std::tan(std::numbers::pi / 6) / 1080;
  EXPECT_NEAR(j["hausdorff_limit"]["max_distance"].get<double>(), one_pixel, 1e-12);
  EXPECT_LE(j["measured"]["hausdorff"].get<double>(), one_pixel);
  EXPECT_EQ(j["hausdorff_limit"]["view"]["distance"].get<double>(), 10.0);
  // Inside the sphere any error can fill the screen: the input comes back, and the run says why.
  r = run(dir, "simplify b.ply -o p.ply --pixel-error 1 --distance 0.5 --json");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["faces_out"], nlohmann::json::parse(r.out)["faces_in"]);
  EXPECT_NE(r.err.find("inside the bounding sphere"), std::string::npos) << r.err;
  EXPECT_EQ(run(dir, "simplify b.ply -o x.ply --distance 10").status, 2);  // needs --pixel-error
  EXPECT_EQ(run(dir, "simplify b.ply -o x.ply --pixel-error 1 --max-hausdorff 1%").status, 2);
  EXPECT_NE(run(dir, "simplify b.ply -o x.ply --max-hausdorff -1%").status, 0);
  EXPECT_NE(run(dir, "simplify b.ply -o x.ply --max-hausdorff 1% --method schroeder").status, 0);
  EXPECT_FALSE(std::filesystem::exists(dir / "x.ply"));
}

TEST(CliSimplify, InvertedFacesAreAnOptionAndMeasureCountsThem) {
  // A lens 1/100 as thick as wide: --measure counts the faces facing against the input, which
  // --inverted-faces avoid and refuse leave none of at 3 %. Held to 8 faces, refuse stops short and
  // its hint names avoid, which goes further and says from where it let such faces be.
  test::ScratchDir dir("cli-simplify-inverted");
  write_mesh(test::thin_lens(), (dir / "lens.ply").string());
  auto measured = [&](const std::string& extra) {
    const CliRun r = run(dir, "simplify lens.ply -o s.ply --measure --json " + extra);
    EXPECT_EQ(r.status, 0) << r.err;
    return nlohmann::json::parse(r.out);
  };
  const nlohmann::json m = measured("--ratio 0.03")["measured"];
  EXPECT_EQ(m["inverted_faces"].get<int>(), 0);  // quadric avoids them
  // The Hausdorff distance comes with its certified bound and the point where it is attained, which
  // lies within the lens (1 wide, 1/100 thick, about the origin).
  EXPECT_GE(m["hausdorff_bound"].get<double>(), m["hausdorff"].get<double>());
  EXPECT_LE(m["hausdorff_bound"].get<double>(), 1.001 * m["hausdorff"].get<double>());
  ASSERT_EQ(m["hausdorff_at"].size(), 3u);
  for (const auto& x : m["hausdorff_at"]) EXPECT_LE(std::abs(x.get<double>()), 1.0);
  // hoppe's collapses allow them by default; its refit then turns them (both: docs/commands/simplify.md).
  EXPECT_GT(measured("--ratio 0.03 --method hoppe --refit-passes 0")["measured"]["inverted_faces"].get<int>(), 0);
  EXPECT_EQ(measured("--ratio 0.03 --method hoppe")["measured"]["inverted_faces"].get<int>(), 0);
  EXPECT_GT(measured("--ratio 0.03 --inverted-faces allow")["measured"]["inverted_faces"].get<int>(), 0);
  EXPECT_EQ(measured("--ratio 0.03 --inverted-faces avoid")["measured"]["inverted_faces"].get<int>(), 0);
  EXPECT_EQ(measured("--ratio 0.03 --inverted-faces refuse")["measured"]["inverted_faces"].get<int>(), 0);
  EXPECT_EQ(measured("--ratio 0.03 --no-inverted-faces")["measured"]["inverted_faces"].get<int>(), 0);
  const auto stuck = measured("--faces 8 --inverted-faces refuse");
  EXPECT_GT(stuck["faces_out"].get<int>(), 8);
  EXPECT_GT(stuck["blocked"]["inverted"].get<int>(), 0);
  EXPECT_FALSE(stuck.contains("inverted_allowed_at_faces"));
  EXPECT_NE(stuck["hint"].get<std::string>().find("--inverted-faces avoid"), std::string::npos) << stuck.dump();
  const auto avoided = measured("--faces 8 --inverted-faces avoid");
  EXPECT_LT(avoided["faces_out"].get<int>(), stuck["faces_out"].get<int>());
  EXPECT_GT(avoided["inverted_allowed_at_faces"].get<int>(), stuck["faces_out"].get<int>()) << avoided.dump();
  EXPECT_NE(avoided["reason_text"].get<std::string>().find("let face against the input"), std::string::npos);
  // A mode that is not one is refused before anything is read, as is naming both options.
  EXPECT_NE(run(dir, "simplify lens.ply -o t.ply --inverted-faces never").status, 0);
  EXPECT_NE(run(dir, "simplify lens.ply -o t.ply --inverted-faces avoid --no-inverted-faces").status, 0);
  EXPECT_FALSE(std::filesystem::exists(dir / "t.ply"));
}

TEST(CliSimplify, AnOptionTheMethodDoesNotReadIsRefused) {
  // Ignored in silence, --crease-weight with schroeder or --seed with quadric would look as if it
  // had done something: each is a usage error naming the option, and nothing is written.
  test::ScratchDir dir("cli-simplify-method-options");
  ASSERT_EQ(run(dir, "generate sphere -o s.ply").status, 0);
  for (const std::string args :
       {"--method schroeder --lane-faces 100", "--method schroeder --refit-passes 1",
        "--method schroeder --crease-weight 1", "--method schroeder --max-valence 8", "--feature-angle 20",
        "--method hoppe --accumulate-error", "--seed 3", "--method edge-length --hoppe-samples 2",
        "--method hoppe --crease-weight 1", "--hoppe-energy-from 3"}) {
    const CliRun r = run(dir, "simplify s.ply -o out.ply --ratio 0.5 " + args);
    EXPECT_EQ(r.status, 2) << args;
    const std::string option = args.substr(args.rfind("--"), args.find(' ', args.rfind("--")) - args.rfind("--"));
    EXPECT_NE(r.err.find(option + ": applies to"), std::string::npos) << args << ": " << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "out.ply")) << args;
  }
  // And with the method that reads it, each is fine.
  for (const std::string args : {"--method schroeder --feature-angle 20 --accumulate-error", "--method hoppe --seed 3",
                                  "--crease-weight 1 --inverted-faces avoid --max-valence 8",
                                  "--method schroeder --inverted-faces allow", "--method schroeder --inverted-faces avoid",
                                  "--method schroeder --no-inverted-faces"})
    EXPECT_EQ(run(dir, "simplify s.ply -o out.ply --ratio 0.5 " + args).status, 0) << args;
}

TEST(CliSimplify, TheTotalTurnLimitIsAnOptionToo) {
  // Held to 30 degrees from their input orientation, faces of a thin torus stop the run sooner than at
  // the default; outside 1..180 degrees the value is refused before anything is read.
  test::ScratchDir dir("cli-simplify-total-turn");
  ASSERT_EQ(run(dir, "generate torus -o t.ply --minor-radius 0.05 --major-segments 96 --minor-segments 8").status, 0);
  auto faces_out = [&](const std::string& extra) {
    const CliRun r = run(dir, "simplify t.ply -o s.ply --faces 16 --max-normal-change 30 --json " + extra);
    EXPECT_EQ(r.status, 0) << r.err;
    return nlohmann::json::parse(r.out)["faces_out"].get<int>();
  };
  EXPECT_GT(faces_out("--max-total-normal-change 30"), faces_out(""));
  // hoppe's default 60 degrees gives way to 90 at 24 faces of a plain torus, and says so (with the energy
  // throughout: see Simplify.TheDefaultTurnLimitGivesWayRatherThanStopShort).
  ASSERT_EQ(run(dir, "generate torus -o plain.ply").status, 0);
  const CliRun relaxed = run(dir, "simplify plain.ply -o s.ply --faces 20 --method hoppe --hoppe-energy-from 0 --json");
  ASSERT_EQ(relaxed.status, 0) << relaxed.err;
  const auto j = nlohmann::json::parse(relaxed.out);
  EXPECT_EQ(j["faces_out"].get<int>(), 20);
  EXPECT_EQ(j["turn_limit_relaxed_at_faces"].get<int>(), 24);
  EXPECT_NE(j["reason_text"].get<std::string>().find("90 degrees"), std::string::npos);
  EXPECT_EQ(run(dir, "simplify t.ply -o s.ply --max-total-normal-change 0.5").status, 2);
  EXPECT_EQ(run(dir, "simplify t.ply -o s.ply --max-total-normal-change 200").status, 2);
}

}  // namespace
}  // namespace lodkit

namespace lodkit {
namespace {

TEST(CliCsg, BooleansAndTreesEndToEnd) {
  test::ScratchDir dir("cli-csg");
  ASSERT_EQ(run(dir, "generate box -o a.ply").status, 0);
  ASSERT_EQ(run(dir, "generate sphere -o b.ply --radius 0.6 --tolerance 0.01").status, 0);
  for (const char* op : {"union", "difference", "intersection"}) {
    const CliRun r = run(dir, std::string("csg ") + op + " a.ply b.ply -o out.ply --json");
    ASSERT_EQ(r.status, 0) << op << ": " << r.err;
    EXPECT_NE(r.out.find("\"volume\""), std::string::npos);
    EXPECT_TRUE(inspect(read_mesh(dir / "out.ply")).closed) << op;
  }
  const CliRun tree = run(dir, "csg tree '" LODKIT_SOURCE_DIR "/data/csg/plate_with_holes.json' -o plate.ply --tolerance 0.02");
  ASSERT_EQ(tree.status, 0) << tree.err;
  EXPECT_EQ(*inspect(read_mesh(dir / "plate.ply")).genus, 5);
  // An open operand is refused with the reason, and nothing is written.
  ASSERT_EQ(run(dir, "generate grid -o open.ply").status, 0);
  const CliRun bad = run(dir, "csg union open.ply a.ply -o never.ply");
  EXPECT_EQ(bad.status, 1);
  EXPECT_NE(bad.err.find("lodkit: error: open.ply: is not closed"), std::string::npos) << bad.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "never.ply"));
  test::write_text(dir / "bad.json", R"({"op": "union", "children": [{"primitive": "box", "sise": 2}]})");
  const CliRun badtree = run(dir, "csg tree bad.json -o never.ply");
  EXPECT_EQ(badtree.status, 1);
  EXPECT_NE(badtree.err.find("$.children[0].sise: unknown key"), std::string::npos) << badtree.err;
  // Errors found while evaluating name the tree's file too, beside the node's path (they named the path alone).
  test::write_text(dir / "open.json", R"({"op": "union", "children": [{"primitive": "box"}, {"mesh": "open.ply"}]})");
  const CliRun opentree = run(dir, "csg tree open.json -o never.ply");
  EXPECT_EQ(opentree.status, 1);
  EXPECT_NE(opentree.err.find("lodkit: error: open.json: $.children[1]: open.ply: is not closed"), std::string::npos)
      << opentree.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "never.ply"));
  // A missing tree and a directory fail as a missing or directory mesh does: exit 1, naming the file.
  std::filesystem::create_directory(dir / "trees");
  for (const char* name : {"missing.json", "trees"}) {
    const CliRun r = run(dir, fmt::format("csg tree {} -o never.ply", name));
    EXPECT_EQ(r.status, 1) << r.err;
    EXPECT_NE(r.err.find(fmt::format("lodkit: error: {}: ", name)), std::string::npos) << r.err;
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "never.ply"));
}

}  // namespace
}  // namespace lodkit

namespace lodkit {
namespace {

TEST(CliPm, BuildInfoExtractGeomorphEndToEnd) {
  test::ScratchDir dir("cli-pm");
  ASSERT_EQ(run(dir, "generate torus -o t.ply").status, 0);
  CliRun r = run(dir, "pm build t.ply -o t.pm");
  ASSERT_EQ(r.status, 0) << r.err;
  r = run(dir, "pm info t.pm --json");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("\"input_order\": true"), std::string::npos);
  // The full level in input order is the input itself.
  const Mesh input = read_mesh(dir / "t.ply");
  r = run(dir, "pm extract t.pm -o full.ply --ratio 1 --input-order");
  ASSERT_EQ(r.status, 0) << r.err;
  const Mesh full = read_mesh(dir / "full.ply");
  EXPECT_TRUE(full.positions == input.positions && full.triangles == input.triangles);
  r = run(dir, "pm extract t.pm -o small.obj --faces 300");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_LE(read_mesh(dir / "small.obj").num_faces(), 300);
  // A ratio reads only the prefix its level needs, as a face count does.
  r = run(dir, "pm extract t.pm -o half.obj --ratio 0.25 --json");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_LE(read_mesh(dir / "half.obj").num_faces(), input.num_faces() / 4 + 1);
  const std::size_t at = r.out.find("\"bytes_read\": ");
  ASSERT_NE(at, std::string::npos) << r.out;
  EXPECT_LT(std::stoull(r.out.substr(at + 14)), std::filesystem::file_size(dir / "t.pm"));
  // So do error and screen-space budgets.
  auto bytes_read = [](const std::string& json) {
    const std::size_t where = json.find("\"bytes_read\": ");
    return where == std::string::npos ? std::uintmax_t(0) : std::uintmax_t(std::stoull(json.substr(where + 14)));
  };
  for (const char* budget : {"--pixel-error 1 --distance 100 --viewport 1080", "--max-error 0.1"}) {
    r = run(dir, std::string("pm extract t.pm -o far.ply --json ") + budget);
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_LT(read_mesh(dir / "far.ply").num_faces(), input.num_faces()) << budget;
    EXPECT_GT(bytes_read(r.out), 0u) << r.out;
    EXPECT_LT(bytes_read(r.out), std::filesystem::file_size(dir / "t.pm")) << budget;
  }
  // Measured levels: selection by what a viewer sees picks a coarser level than the bound does.
  r = run(dir, "pm build t.ply -o tm.pm --measure --json");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(run(dir, "pm info tm.pm").out.find("measured"), std::string::npos);
  const auto faces_of = [](const std::string& json) {
    const std::size_t where = json.find("\"faces\": ");
    return where == std::string::npos ? -1 : std::stoi(json.substr(where + 9));
  };
  const CliRun seen = run(dir, "pm extract tm.pm -o seen.ply --json --pixel-error 1 --distance 30");
  const CliRun certified = run(dir, "pm extract tm.pm -o certified.ply --json --pixel-error 1 --distance 30 --certified");
  ASSERT_EQ(seen.status, 0) << seen.err;
  ASSERT_EQ(certified.status, 0) << certified.err;
  EXPECT_NE(seen.out.find("measured error projects"), std::string::npos) << seen.out;
  EXPECT_GT(faces_of(seen.out), 0) << seen.out;
  EXPECT_LT(faces_of(seen.out), faces_of(certified.out)) << seen.out << certified.out;
  EXPECT_LE(compare(input, read_mesh(dir / "seen.ply")).hausdorff,
            30.0 * 2 * std::tan(std::numbers::pi / 6) / 1080.0);  // within one pixel at the nearest point
  // With the input at hand, levels between the measured ones are checked: a level no finer, and proved
  // (and measured here) within the same pixel.
  const double one_pixel = (30.0 - 0.5 * bounding_box(input).diagonal().norm()) * 2 * std::tan(std::numbers::pi / 6) / 1080.0;
  const CliRun proved = run(dir, "pm extract tm.pm -o proved.ply --json --pixel-error 1 --distance 30 --prove-with t.ply");
  ASSERT_EQ(proved.status, 0) << proved.err;
  const auto pj = nlohmann::json::parse(proved.out);
  EXPECT_LE(pj["faces"].get<int>(), faces_of(seen.out)) << proved.out;
  EXPECT_LE(pj["proved_bound"].get<double>(), one_pixel);
  EXPECT_GT(pj["checks"].get<int>(), 0);
  EXPECT_LE(compare(input, read_mesh(dir / "proved.ply")).hausdorff, one_pixel);
  EXPECT_NE(run(dir, "pm extract tm.pm -o x.ply --faces 100 --prove-with t.ply").status, 0);  // no budget
  EXPECT_EQ(run(dir, "pm extract tm.pm -o x.ply --max-error 0.1 --prove-with t.ply --certified").status, 2);
  write_mesh(make_box({}), (dir / "other.ply").string());
  const CliRun wrong = run(dir, "pm extract tm.pm -o x.ply --max-error 0.1 --prove-with other.ply");
  EXPECT_NE(wrong.status, 0);
  EXPECT_NE(wrong.err.find("other.ply"), std::string::npos) << wrong.err;
  // A budget met by the bound alone says that a measured stream would do with less; nothing else does.
  const std::string note = "holds no measured errors";
  EXPECT_NE(run(dir, "pm extract t.pm -o b.ply --pixel-error 1 --distance 30").err.find(note), std::string::npos);
  EXPECT_NE(run(dir, "pm extract t.pm -o b.ply --max-error 0.1").err.find(note), std::string::npos);
  EXPECT_EQ(run(dir, "pm extract t.pm -o b.ply --faces 100").err.find(note), std::string::npos);
  EXPECT_EQ(run(dir, "pm extract tm.pm -o b.ply --pixel-error 1 --distance 30").err.find(note), std::string::npos);
  r = run(dir, "pm geomorph t.pm --from 200 --to 800 --frames 3 -o m.ply");
  ASSERT_EQ(r.status, 0) << r.err;
  for (const char* f : {"m_000.ply", "m_001.ply", "m_002.ply"}) EXPECT_TRUE(std::filesystem::exists(dir / f)) << f;
  EXPECT_EQ(run(dir, "pm build t.ply -o q.pm --quantize 12 --draco").status, 0);
  for (const char* cmd : {"pm --help", "pm build --help", "pm extract --help", "pm geomorph --help", "pm info --help"})
    EXPECT_NE(run(dir, cmd).out.find("Example"), std::string::npos) << cmd;
}

TEST(CliPm, ExtractRefinesSelectivelyForAnEye) {
  // A terrain seen from above one corner: fine there, coarse far away, within the pixel budget.
  test::ScratchDir dir("cli-pm-eye");
  ASSERT_EQ(run(dir, "terrain -o t.ply --levels 6").status, 0);
  ASSERT_EQ(run(dir, "pm build t.ply -o t.pm").status, 0);
  const CliRun r = run(dir, "pm extract t.pm -o view.ply --json --pixel-error 2 --viewport 200 --eye -0.55,-0.55,0.1 --look-at 0.5,0.5,0");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  const Mesh view = read_mesh(dir / "view.ply");
  EXPECT_EQ(j["faces"].get<Index>(), view.num_faces());
  EXPECT_LE(j["max_pixels"].get<double>(), 2.0);
  EXPECT_EQ(j["selected_by"], "measured deviation");
  EXPECT_LT(view.num_faces(), j["uniform_level_faces"].get<Index>());
  const MeshReport report = inspect(view);
  EXPECT_TRUE(report.manifold);
  EXPECT_EQ(report.euler_characteristic, inspect(read_mesh(dir / "t.ply")).euler_characteristic);
  int near = 0, far = 0;
  for (Index v = 0; v < view.num_vertices(); ++v) {
    near += view.positions(v, 0) < -0.25 && view.positions(v, 1) < -0.25;
    far += view.positions(v, 0) > 0.25 && view.positions(v, 1) > 0.25;
  }
  EXPECT_GT(near, 2 * far) << near << " near, " << far << " far";
  // The guaranteed bound refines more; the text names what chose.
  const CliRun certified = run(dir, "pm extract t.pm -o c.ply --pixel-error 2 --viewport 200 --eye -0.55,-0.55,0.1 --look-at 0.5,0.5,0 --certified");
  ASSERT_EQ(certified.status, 0) << certified.err;
  EXPECT_NE(certified.err.find("error bound projects"), std::string::npos) << certified.err;
  EXPECT_GT(read_mesh(dir / "c.ply").num_faces(), view.num_faces());
  // A closed sphere seen from one side: back faces culled, fewer faces, the regions counted.
  ASSERT_EQ(run(dir, "generate icosphere -o ball.ply --subdivisions 4").status, 0);
  ASSERT_EQ(run(dir, "pm build ball.ply -o ball.pm").status, 0);
  const std::string ball_view = "pm extract ball.pm --json --pixel-error 1 --viewport 400 --eye 0,0,3 ";
  const CliRun both = run(dir, ball_view + "-o both.ply"), front = run(dir, ball_view + "-o front.ply --cull-backfaces");
  ASSERT_EQ(front.status, 0) << front.err;
  const auto bj = nlohmann::json::parse(both.out), fj = nlohmann::json::parse(front.out);
  EXPECT_EQ(bj["regions_facing_away"].get<Index>(), 0);
  EXPECT_GT(fj["regions_facing_away"].get<Index>(), 0);
  EXPECT_LT(fj["faces"].get<Index>(), bj["faces"].get<Index>());
  // What does not combine with an eye is refused, naming why.
  for (const char* bad : {"--eye 0,0,1", "--eye 0,0,1 --faces 10 --pixel-error 1", "--eye 0,0 --pixel-error 1",
                          "--eye 0,0,1 --pixel-error 1 --input-order", "--look-at 0,0,0 --pixel-error 1 --distance 3",
                          "--eye 0,0,1 --pixel-error 1 --distance 3", "--eye 0,0,1 --look-at 0,0,1 --pixel-error 1",
                          "--faces 10 --no-cull", "--faces 10 --cull-backfaces", "--faces 10 --allow-folds"}) {
    const CliRun b = run(dir, std::string("pm extract t.pm -o x.ply ") + bad);
    EXPECT_NE(b.status, 0) << bad;
    EXPECT_FALSE(b.err.empty()) << bad;
    EXPECT_FALSE(std::filesystem::exists(dir / "x.ply")) << bad;
  }
  // An eye at the centre looks nowhere unless told where: the message says how to go on.
  const Mesh terrain = read_mesh(dir / "t.ply");
  const Eigen::Vector3d mid = 0.5 * (terrain.positions.colwise().minCoeff() + terrain.positions.colwise().maxCoeff()).transpose();
  const std::string centre = fmt::format("{},{},{}", mid.x(), mid.y(), mid.z());
  const CliRun inside = run(dir, "pm extract t.pm -o x.ply --pixel-error 1 --eye " + centre);
  EXPECT_EQ(inside.status, 1);
  EXPECT_NE(inside.err.find("bounding box centre"), std::string::npos) << inside.err;
  EXPECT_NE(inside.err.find("--look-at"), std::string::npos) << inside.err;
  EXPECT_EQ(run(dir, "pm extract t.pm -o x.ply --pixel-error 1 --no-cull --eye " + centre).status, 0);
}

TEST(CliPm, ExtractUnfoldsWhatMixedLevelsFold) {
  // Close to a fractal pyramid, splits of different levels meet and a face folds (faces against the
  // input): the view is refined further there, says by how many splits, and nothing faces against the
  // input; --allow-folds leaves it.
  test::ScratchDir dir("cli-pm-unfold");
  ASSERT_EQ(run(dir, "terrain -o p.ply --base pyramid --levels 5").status, 0);
  ASSERT_EQ(run(dir, "pm build p.ply -o p.pm").status, 0);
  const std::string view = "pm extract p.pm --json --pixel-error 0.5 --viewport 400 --eye=-0.32,0.334,0.226 ";
  const CliRun unfolded = run(dir, view + "-o u.ply"), folded = run(dir, view + "-o f.ply --allow-folds");
  ASSERT_EQ(unfolded.status, 0) << unfolded.err;
  ASSERT_EQ(folded.status, 0) << folded.err;
  const auto uj = nlohmann::json::parse(unfolded.out), fj = nlohmann::json::parse(folded.out);
  const Index more = uj["splits_unfolding"].get<Index>();
  EXPECT_GT(more, 0);
  EXPECT_EQ(fj["splits_unfolding"].get<Index>(), 0);
  EXPECT_EQ(uj["splits_applied"].get<Index>(), fj["splits_applied"].get<Index>() + more);
  auto against = [&](const char* out) {
    return nlohmann::json::parse(run(dir, std::string("compare p.ply ") + out + " --json").out)["b_faces_against_a"].get<Index>();
  };
  EXPECT_EQ(against("u.ply"), 0);
  EXPECT_GT(against("f.ply"), 0);
}

TEST(CliPm, ExtractRefinesSelectivelyAlongAnEyePath) {
  // A camera path: each view is the mesh --eye gives for its eye, byte for byte, and the kept mesh
  // applies and undoes only what changes (the counts add up from view to view).
  test::ScratchDir dir("cli-pm-eye-path");
  ASSERT_EQ(run(dir, "terrain -o t.ply --levels 6").status, 0);
  ASSERT_EQ(run(dir, "pm build t.ply -o t.pm --measure").status, 0);
  test::write_text(dir / "path.csv", "# eye x,y,z[,look-at x,y,z]\n-0.55,-0.55,0.1\n\n-0.5 -0.45 0.1\n"
                                     "-0.45,-0.35,0.1\n0.9,0.9,0.3, 0.5,0.5,0\n");
  const std::string common = "pm extract t.pm --pixel-error 2 --viewport 200 --look-at 0.5,0.5,0 ";
  const CliRun r = run(dir, common + "-o view.ply --eye-path path.csv --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["views"].size(), 4u);
  const char* eyes[] = {"-0.55,-0.55,0.1 --look-at 0.5,0.5,0", "-0.5,-0.45,0.1 --look-at 0.5,0.5,0",
                        "-0.45,-0.35,0.1 --look-at 0.5,0.5,0", "0.9,0.9,0.3 --look-at 0.5,0.5,0"};
  Index applied = 0;
  for (int i = 0; i < 4; ++i) {
    const auto& v = j["views"][static_cast<std::size_t>(i)];
    const std::string name = fmt::format("view_{:03d}.ply", i);
    EXPECT_TRUE(v["output"].get<std::string>().ends_with(name)) << v["output"];
    ASSERT_EQ(run(dir, fmt::format("pm extract t.pm --pixel-error 2 --viewport 200 -o one.ply --eye {}", eyes[i])).status, 0);
    EXPECT_EQ(test::read_bytes(dir / name), test::read_bytes(dir / "one.ply")) << name;
    EXPECT_EQ(v["splits_applied"].get<Index>(), applied + v["splits_refined"].get<Index>() - v["splits_coarsened"].get<Index>());
    applied = v["splits_applied"].get<Index>();
    EXPECT_LE(v["max_pixels"].get<double>(), 2.0);
  }
  const auto& near_step = j["views"][1];  // a small step changes few splits
  EXPECT_LT(4 * (near_step["splits_refined"].get<Index>() + near_step["splits_coarsened"].get<Index>()),
            near_step["splits_applied"].get<Index>()) << near_step.dump();
  EXPECT_GT(j["views"][3]["splits_coarsened"].get<Index>(), 0);  // the far corner: the near one coarsens
  // Bad paths are refused by file and line, before any view is written.
  for (const auto& [text, words] : std::vector<std::pair<std::string, std::string>>{
           {"0,0,1\n1,2\n", "bad.csv:2: expected 3 numbers"},
           {"0,0,nan\n", "bad.csv:1: 'nan' is not a finite number"},
           {"0,0,1x\n", "bad.csv:1: '1x' is not a finite number"},
           {"# nothing\n\n", "bad.csv: no eye in the file"},
           {"0,0,1\n0.5,0.5,0\n", "bad.csv:2: the eye (0.5, 0.5, 0) is at the point looked at"}}) {
    test::write_text(dir / "bad.csv", text);
    const CliRun b = run(dir, common + "-o bad.ply --eye-path bad.csv");
    EXPECT_EQ(b.status, 1) << text;
    EXPECT_NE(b.err.find(words), std::string::npos) << b.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "bad_000.ply")) << text;
  }
  EXPECT_NE(run(dir, common + "-o bad.ply --eye-path missing.csv").err.find("missing.csv: cannot open"), std::string::npos);
  EXPECT_NE(run(dir, common + "-o - --eye-path path.csv").status, 0);                    // files, not stdout
  EXPECT_NE(run(dir, common + "-o bad.ply --eye-path path.csv --eye 0,0,1").status, 0);  // one or the other
}

TEST(CliPm, ExtractBlendsEachViewInWithGeomorphsWhenAsked) {
  // --morph-frames K: every K-th frame is the path's view, byte for byte; the frames between hold both
  // views' connectivity and move every vertex on a straight line from the view before to the next.
  test::ScratchDir dir("cli-pm-eye-path-morph");
  ASSERT_EQ(run(dir, "terrain -o t.ply --levels 6").status, 0);
  ASSERT_EQ(run(dir, "pm build t.ply -o t.pm --measure").status, 0);
  test::write_text(dir / "path.csv", "-0.55,-0.55,0.1\n-0.45,-0.35,0.1\n0.9,0.9,0.3\n");
  const std::string common = "pm extract t.pm --pixel-error 2 --viewport 200 --look-at 0.5,0.5,0 --eye-path path.csv ";
  ASSERT_EQ(run(dir, common + "-o view.ply").status, 0);
  const CliRun r = run(dir, common + "-o f.ply --morph-frames 4 --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["views"].size(), 3u);
  EXPECT_FALSE(j["views"][0].contains("morph_outputs"));
  for (int i = 0; i < 3; ++i)
    EXPECT_EQ(test::read_bytes(dir / fmt::format("f_{:03d}.ply", 4 * i)), test::read_bytes(dir / fmt::format("view_{:03d}.ply", i))) << i;
  EXPECT_FALSE(std::filesystem::exists(dir / "f_009.ply"));
  for (int step = 1; step < 3; ++step) {
    const auto& v = j["views"][static_cast<std::size_t>(step)];
    ASSERT_EQ(v["morph_outputs"].size(), 3u) << v.dump();
    std::vector<Mesh> frames;
    for (int k = 0; k < 3; ++k) {
      const std::string name = fmt::format("f_{:03d}.ply", 4 * (step - 1) + 1 + k);
      EXPECT_TRUE(v["morph_outputs"][static_cast<std::size_t>(k)].get<std::string>().ends_with(name));
      frames.push_back(read_mesh(dir / name));
    }
    const Mesh before = read_mesh(dir / fmt::format("view_{:03d}.ply", step - 1)), after = read_mesh(dir / fmt::format("view_{:03d}.ply", step));
    for (const Mesh& f : frames) {
      EXPECT_EQ(f.triangles, frames[0].triangles);
      EXPECT_EQ(f.num_vertices(), v["morph_vertices"].get<Index>());
      EXPECT_GE(f.num_faces(), std::max(before.num_faces(), after.num_faces()));
    }
    // Straight lines, evenly paced: the middle frame is halfway between the other two.
    EXPECT_LT((frames[1].positions - 0.5 * (frames[0].positions + frames[2].positions)).cwiseAbs().maxCoeff(), 1e-6);
    EXPECT_GT((frames[2].positions - frames[0].positions).cwiseAbs().maxCoeff(), 1e-4);  // they do move
  }
  // Asked where it cannot blend: clear errors, nothing written.
  for (const auto& [args, words] : std::vector<std::pair<std::string, std::string>>{
           {"--morph-frames 4 --eye 0,0,1", "--morph-frames blends from view to view: it needs --eye-path"},
           {"--morph-frames 4 --eye-path path.csv --fit-attributes", "--fit-attributes does not combine with --morph-frames"},
           {"--morph-frames 0 --eye-path path.csv", "--morph-frames"}}) {
    const CliRun b = run(dir, "pm extract t.pm --pixel-error 2 --look-at 0.5,0.5,0 -o bad.ply " + args);
    EXPECT_NE(b.status, 0) << args;
    EXPECT_NE(b.err.find(words), std::string::npos) << b.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "bad_000.ply") || std::filesystem::exists(dir / "bad.ply")) << args;
  }
}

TEST(CliPm, ExtractFitsNormalsAndColoursWhenAsked) {
  // A level keeps each collapse's values; --fit-attributes fits them to the finest level's, as simplify
  // fits its output's: the same faces and positions, lower shading and colour errors, and in input order
  // exactly simplify's output without the refit.
  test::ScratchDir dir("cli-pm-attribute-fit");
  Mesh a = test::bumpy_sphere(3, 0.03);
  a.attributes.normals = compute_vertex_normals(a);
  a.attributes.colours.resize(a.num_vertices(), 4);
  for (Index v = 0; v < a.num_vertices(); ++v)
    a.attributes.colours.row(v) << float(0.5 + 0.45 * a.positions(v, 0)), float(0.5 + 0.45 * a.positions(v, 2)), 0.25f, 1.0f;
  write_mesh(a, (dir / "a.ply").string());
  ASSERT_EQ(run(dir, "pm build a.ply -o a.pm").status, 0);
  CliRun r = run(dir, "pm extract a.pm -o kept.ply --faces 300 --input-order --json");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_FALSE(nlohmann::json::parse(r.out).contains("attribute_fit")) << r.out;
  r = run(dir, "pm extract a.pm -o fitted.ply --faces 300 --input-order --fit-attributes --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_TRUE(j.contains("attribute_fit")) << r.out;
  EXPECT_TRUE(j["attribute_fit"]["normals"].get<bool>());
  EXPECT_TRUE(j["attribute_fit"]["colours"].get<bool>());
  const Mesh kept = read_mesh(dir / "kept.ply"), fitted = read_mesh(dir / "fitted.ply");
  ASSERT_EQ(fitted.num_faces(), j["faces"].get<Index>());
  EXPECT_TRUE(fitted.positions == kept.positions && fitted.triangles == kept.triangles);
  const Comparison before = compare(a, kept), after = compare(a, fitted);
  ASSERT_TRUE(before.shading_rms_deg && after.shading_rms_deg && before.colour_rms && after.colour_rms);
  EXPECT_LT(*after.shading_rms_deg, 0.8 * *before.shading_rms_deg);
  EXPECT_LT(*after.colour_rms, 0.8 * *before.colour_rms);
  r = run(dir, fmt::format("simplify a.ply -o s.ply --faces {} --refit-passes 0", fitted.num_faces()));
  ASSERT_EQ(r.status, 0) << r.err;
  const Mesh simplified = read_mesh(dir / "s.ply");
  EXPECT_TRUE(simplified.positions == fitted.positions && simplified.triangles == fitted.triangles);
  EXPECT_TRUE(simplified.attributes.normals == fitted.attributes.normals);
  EXPECT_TRUE(simplified.attributes.colours == fitted.attributes.colours);
  // The summary says what was fitted; without normals or colours, that there was nothing to fit.
  EXPECT_NE(run(dir, "pm extract a.pm -o x.ply --faces 300 --fit-attributes").err.find("normals and colours fitted"),
            std::string::npos);
  write_mesh(test::bumpy_sphere(3, 0.03), (dir / "plain.ply").string());
  ASSERT_EQ(run(dir, "pm build plain.ply -o plain.pm").status, 0);
  r = run(dir, "pm extract plain.pm -o x.ply --faces 300 --fit-attributes");
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("nothing to fit"), std::string::npos) << r.err;
}

TEST(CliPm, FlatShadedInputNamesAndTakesDropNormals) {
  // The normals of a flat-shaded mesh make every edge a seam: no collapse, so no splits. The build
  // says so and names --drop-normals; with it the stream spans the shape's levels.
  test::ScratchDir dir("cli-pm-flat");
  write_mesh(test::flat_shaded(test::bumpy_sphere(3, 0.02)), (dir / "flat.ply").string());
  const CliRun stuck = run(dir, "pm build flat.ply -o f.pm");
  ASSERT_EQ(stuck.status, 0) << stuck.err;
  EXPECT_NE(stuck.err.find("--drop-normals"), std::string::npos) << stuck.err;
  const CliRun built = run(dir, "pm build flat.ply -o f.pm --drop-normals --json");
  ASSERT_EQ(built.status, 0) << built.err;
  const auto j = nlohmann::json::parse(built.out);
  EXPECT_LE(j["base_faces"].get<int>(), 8);  // a closed genus-0 surface goes down to a tetrahedron or so
  EXPECT_GE(j["splits"].get<int>(), 600);
  ASSERT_EQ(run(dir, "pm extract f.pm -o top.ply --faces 1280").status, 0);
  const Mesh top = read_mesh((dir / "top.ply").string());
  EXPECT_EQ(top.num_faces(), 1280);
  EXPECT_EQ(top.num_vertices(), 642);  // welded: the normals were what split the corners
  EXPECT_FALSE(top.has_normals());
}

// pm build takes simplify's --inverted-faces: by default quadric's levels avoid faces facing against the
// input (none at 3 % of a thin lens), with allow some level has them, and its levels stay simplify's.
TEST(CliPm, BuildTakesInvertedFacesAsSimplifyDoes) {
  test::ScratchDir dir("cli-pm-inverted");
  const Mesh lens = test::thin_lens();
  write_mesh(lens, (dir / "lens.ply").string());
  const Index faces = static_cast<Index>(std::llround(0.03 * lens.num_faces()));
  auto level = [&](const std::string& extra) {
    const CliRun r = run(dir, "pm build lens.ply -o lens.pm " + extra);
    EXPECT_EQ(r.status, 0) << r.err;
    const CliRun x = run(dir, fmt::format("pm extract lens.pm -o level.ply --faces {}", faces));
    EXPECT_EQ(x.status, 0) << x.err;
    return read_mesh(dir / "level.ply");
  };
  EXPECT_EQ(count_flipped_faces(lens, level("")), 0);
  const Mesh allowed = level("--inverted-faces allow");
  EXPECT_GT(count_flipped_faces(lens, allowed), 0);
  ASSERT_EQ(run(dir, fmt::format("simplify lens.ply -o s.ply --faces {} --inverted-faces allow", faces)).status, 0);
  EXPECT_EQ(allowed.num_faces(), read_mesh(dir / "s.ply").num_faces());
  const CliRun bad = run(dir, "pm build lens.ply -o bad.pm --inverted-faces sometimes");
  EXPECT_NE(bad.status, 0);
  EXPECT_NE(bad.err.find("--inverted-faces"), std::string::npos) << bad.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.pm"));
}

TEST(CliPm, BadStreamsAndOptionsFailClearly) {
  test::ScratchDir dir("cli-pm");
  ASSERT_EQ(run(dir, "generate torus -o t.ply").status, 0);
  ASSERT_EQ(run(dir, "pm build t.ply -o t.pm").status, 0);
  // Refuses to overwrite its input.
  CliRun r = run(dir, "pm extract t.pm -o t.pm --faces 100");
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.err.find("t.pm"), std::string::npos);
  EXPECT_GT(std::filesystem::file_size(dir / "t.pm"), 1000u);
  // Not a stream.
  r = run(dir, "pm info t.ply");
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.err.find("t.ply"), std::string::npos);
  EXPECT_NE(r.err.find("pm build"), std::string::npos) << r.err;
  // Truncated: the valid prefix and a warning.
  const std::string bytes = test::read_bytes(dir / "t.pm");
  test::write_text(dir / "cut.pm", bytes.substr(0, bytes.size() / 2));
  r = run(dir, "pm extract cut.pm -o cut.ply --ratio 1");
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("warning"), std::string::npos);
  // Two selections at once, or none.
  EXPECT_NE(run(dir, "pm extract t.pm -o x.ply --faces 10 --ratio 0.5").status, 0);
  EXPECT_NE(run(dir, "pm extract t.pm -o x.ply").status, 0);
  EXPECT_NE(run(dir, "pm build t.ply -o d.pm --draco").status, 0);  // Draco needs quantisation
  EXPECT_FALSE(std::filesystem::exists(dir / "x.ply"));
  EXPECT_FALSE(std::filesystem::exists(dir / "d.pm"));
}


TEST(CliTerrain, StreamedAndInMemoryOutputsEndToEnd) {
  test::ScratchDir dir("cli-terrain");
  CliRun r = run(dir, "terrain -o m.ply --levels 6 --colour --seed 3");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("16,384 faces"), std::string::npos) << r.err;
  const Mesh ply = read_mesh(dir / "m.ply");
  EXPECT_EQ(ply.num_faces(), 4 * 4096);
  EXPECT_TRUE(ply.has_face_colours());
  // The same terrain through the in-memory path (OBJ), up to the PLY's float32 positions.
  ASSERT_EQ(run(dir, "terrain -o m.obj --levels 6 --colour --seed 3").status, 0);
  const Mesh obj = read_mesh(dir / "m.obj");
  EXPECT_EQ(obj.triangles, ply.triangles);
  EXPECT_LT((obj.positions - ply.positions).cwiseAbs().maxCoeff(), 1e-6);
  // A closed base from a file stays closed; stdout works.
  ASSERT_EQ(run(dir, "generate icosphere -o ico.ply --subdivisions 1").status, 0);
  ASSERT_EQ(run(dir, "terrain --base ico.ply -o planet.off --levels 3 --sigma 2% --edge-direction normals").status, 0);
  EXPECT_TRUE(inspect(read_mesh(dir / "planet.off")).closed);
  r = run(dir, "terrain -o - --format obj --levels 2 --base grid");
  EXPECT_EQ(r.status, 0);
  EXPECT_EQ(read_mesh_from_memory(r.out, MeshFormat::Obj, "stdout").num_faces(), 32);
  for (const char* help : {"terrain --help", "subdivide --help"}) {
    r = run(dir, help);
    EXPECT_EQ(r.status, 0);
    EXPECT_NE(r.out.find("Examples:"), std::string::npos) << help;
  }
}

TEST(CliTerrain, BadOptionsAndBasesFailClearly) {
  test::ScratchDir dir("cli-terrain");
  CliRun r = run(dir, "terrain -o t.ply --sigma lots");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("--sigma"), std::string::npos) << r.err;
  EXPECT_EQ(run(dir, "terrain -o t.ply --levels 16").status, 2);
  r = run(dir, "terrain -o t.ply --roughness 2");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("roughness"), std::string::npos);
  r = run(dir, "terrain -o t.ply --base missing.obj");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("missing.obj"), std::string::npos);
  test::write_text(dir / "bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 nan\nf 1 2 3\n");
  r = run(dir, "terrain -o t.ply --base bad.obj");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("bad.obj"), std::string::npos);
  // Two corners at one position: a valid mesh file, but no terrain base. The error names the file.
  test::write_text(dir / "flat.obj", "v 0 0 0\nv 1 0 0\nv 0 0 0\nf 1 2 3\n");
  r = run(dir, "terrain -o t.ply --base flat.obj");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("flat.obj: terrain base: face 0 repeats a vertex"), std::string::npos) << r.err;
  ASSERT_EQ(run(dir, "generate icosphere -o ico.ply --subdivisions 1").status, 0);
  const std::string before = test::read_bytes(dir / "ico.ply");
  EXPECT_EQ(run(dir, "terrain --base ico.ply -o ico.ply").status, 1);
  EXPECT_EQ(test::read_bytes(dir / "ico.ply"), before) << "the base is never overwritten";
  r = run(dir, "terrain -o t.ply --levels 15 --base grid");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("2^31"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "t.ply"));
}

TEST(CliSubdivide, SchemesLevelsAndToleranceEndToEnd) {
  test::ScratchDir dir("cli-subdivide");
  test::write_text(dir / "cube.obj",
                   "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n"
                   "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n");
  CliRun r = run(dir, "subdivide cube.obj -o cc.ply --scheme catmull-clark --levels 2 --limit");
  ASSERT_EQ(r.status, 0) << r.err;
  const Mesh cc = read_mesh(dir / "cc.ply");
  EXPECT_EQ(cc.num_faces(), 6 * 16 * 2) << "quads were recovered from the OBJ";
  EXPECT_TRUE(inspect(cc).closed);
  r = run(dir, "subdivide cube.obj -o loop.ply --scheme loop --tolerance 1%");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("surface moves"), std::string::npos) << r.err;
  // Bad input: truncated file, unknown scheme, overwriting the input, a tolerance that is no number.
  test::write_text(dir / "cut.obj", "v 0 0 0\nv 1 0 0\nf 1 2 3\n");
  r = run(dir, "subdivide cut.obj -o x.ply");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("cut.obj"), std::string::npos) << r.err;
  EXPECT_EQ(run(dir, "subdivide cube.obj -o x.ply --scheme butterfly").status, 2);
  EXPECT_EQ(run(dir, "subdivide cube.obj -o cube.obj").status, 1);
  r = run(dir, "subdivide cube.obj -o x.ply --tolerance small");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("--tolerance"), std::string::npos);
  // Ten levels of the cube would be 6 x 4 x 4^9 x 2 = 12,582,912 triangles: past a limit of a million,
  // refused at once rather than refined until memory runs out.
  r = run(dir, "subdivide cube.obj -o x.ply --scheme catmull-clark --levels 10 --max-faces 1000000");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("would make 12582912 triangles"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "x.ply"));
}

}  // namespace
}  // namespace lodkit
