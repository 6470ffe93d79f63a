// The bad-input corpus through the library: every file is refused with an Error that names the file
// and the problem, and a failed write never leaves a file behind or touches an existing one.
#include <gtest/gtest.h>
#include <lodkit/error.h>
#include <lodkit/io.h>
#include <lodkit/pm_io.h>
#include <lodkit/primitives.h>

#include <fmt/format.h>

#include <sys/stat.h>

#include "bad_corpus.h"
#include "test_util.h"

namespace lodkit {
namespace {

TEST(BadInput, EveryCorpusFileIsAClearError) {
  test::ScratchDir dir("bad");
  const auto corpus = test::write_bad_corpus(dir.path());
  ASSERT_GE(corpus.size(), 30u);
  for (const auto& bad : corpus) {
    const std::string path = (dir / bad.name).string();
    try {
      read_mesh(path);
      ADD_FAILURE() << bad.name << ": was accepted";
    } catch (const Error& e) {
      const std::string msg = e.what();
      EXPECT_EQ(msg.rfind(path + ": ", 0), 0u) << bad.name << ": message does not start with the file: " << msg;
      EXPECT_NE(msg.find(bad.expected), std::string::npos) << bad.name << ": expected '" << bad.expected
                                                           << "' in: " << msg;
    }
  }
}

TEST(BadInput, MissingFileAndDirectory) {
  test::ScratchDir dir("missing");
  EXPECT_THROW(read_mesh(dir / "nope.ply"), Error);
  std::filesystem::create_directory(dir / "d.obj");
  try {
    read_mesh(dir / "d.obj");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("is a directory"), std::string::npos);
  }
  // Without an extension the file's own trouble comes first, not the format it cannot be told by.
  auto message = [](const std::filesystem::path& path) {
    try {
      read_mesh(path);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  std::filesystem::create_directory(dir / "scans");
  EXPECT_NE(message(dir / "scans").find("is a directory"), std::string::npos) << message(dir / "scans");
  EXPECT_NE(message(dir / "nope").find("cannot open"), std::string::npos) << message(dir / "nope");
  // The same for a directory named as the output, and for a .pm stream.
  try {
    write_mesh(make_box({.divisions = 1}), dir / "scans");
    ADD_FAILURE() << "wrote over a directory";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("is a directory"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(std::filesystem::is_directory(dir / "scans"));
  EXPECT_THROW(read_pm(dir / "scans"), Error);
}

TEST(BadInput, EveryTruncationOfAGoodFileIsHandled) {
  // Every prefix of a small file in each format either reads as a valid mesh or raises Error:
  // never a crash, never garbage (validate() holds for anything returned).
  const Mesh m = make_box({.divisions = 1});
  for (MeshFormat f : {MeshFormat::Obj, MeshFormat::Ply, MeshFormat::Off, MeshFormat::Stl, MeshFormat::Draco}) {
    WriteOptions w;
    const std::string bytes = write_mesh_to_memory(m, f, w);
    // A text file cut only in its trailing whitespace is still the whole file.
    const std::size_t content = bytes.find_last_not_of(" \t\r\n") + 1;
    int accepted = 0;
    for (std::size_t n = 0; n < content; ++n) {
      try {
        const Mesh part = read_mesh_from_memory(std::string_view(bytes).substr(0, n), f, "cut");
        validate(part);
        ++accepted;
      } catch (const Error&) {
      }
    }
    // Formats with counts in the header must refuse every proper prefix.
    if (f == MeshFormat::Ply || f == MeshFormat::Stl || f == MeshFormat::Off) {
      EXPECT_EQ(accepted, 0) << format_name(f);
    }
  }
}

TEST(BadInput, DracoRefusesValuesBeyondItsFloatsInsteadOfCrashing) {
  // A box as wide as 32-bit floats go (../shared's manifold_Cray_right.obj): quantising it overflowed
  // the extent Draco computes in float, and its encoder crashed.
  Mesh m = test::single_triangle();
  m.positions(0, 0) = -3.4028234e38;
  m.positions(1, 0) = 3.4028234e38;
  auto message = [](const Mesh& mesh, const WriteOptions& w) -> std::string {
    try {
      write_mesh_to_memory(mesh, MeshFormat::Draco, w);
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  };
  WriteOptions w;  // 14-bit positions
  EXPECT_NE(message(m, w).find("0 quantisation bits"), std::string::npos) << message(m, w);
  // Unquantised, Draco keeps the floats as they are.
  w.draco.position_bits = 0;
  const Mesh back = read_mesh_from_memory(write_mesh_to_memory(m, MeshFormat::Draco, w), MeshFormat::Draco, "x.drc");
  EXPECT_EQ(back.positions, m.positions.cast<float>().cast<double>());
  // Beyond the largest float there is nothing to store, quantised or not (and lodkit takes no mesh
  // that far out in any format).
  m.positions(2, 1) = 1e39;
  EXPECT_NE(message(m, w).find("vertex 2 has a coordinate of 1e+39"), std::string::npos) << message(m, w);
}

TEST(AtomicWrite, FailedWriteLeavesNothingAndKeepsTheOldFile) {
  test::ScratchDir dir("atomic");
  const auto target = dir / "out.drc";
  test::write_text(target, "precious");
  Mesh no_faces;
  no_faces.positions = Positions::Zero(3, 3);
  EXPECT_THROW(write_mesh(no_faces, target), Error);  // Draco refuses a mesh without faces
  EXPECT_EQ(test::read_bytes(target), "precious");
  EXPECT_EQ(dir.entries(), 1u);

  Mesh bad = test::single_triangle();
  bad.triangles(0, 0) = 7;
  EXPECT_THROW(write_mesh(bad, dir / "bad.ply"), Error);
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.ply"));
  EXPECT_EQ(dir.entries(), 1u);
}

// Written files get the permissions the umask allows, as any program's output: they were always 0644
// (a private umask of 077 made them world-readable; a group-writable 002 did not make them so).
TEST(AtomicWrite, FilesGetTheUmasksPermissions) {
  test::ScratchDir dir("atomic");
  const mode_t saved = ::umask(077);
  const auto mode_of = [](const std::filesystem::path& p) {
    struct stat st{};
    ::stat(p.c_str(), &st);
    return st.st_mode & 0777;
  };
  for (const mode_t mask : {mode_t{077}, mode_t{022}, mode_t{002}}) {
    ::umask(mask);
    const auto target = dir / fmt::format("out{:o}.ply", mask);
    write_mesh(test::single_triangle(), target);
    EXPECT_EQ(mode_of(target), 0666u & ~mask) << std::oct << mask;
  }
  ::umask(saved);
}

TEST(AtomicWrite, UnwritableDirectoryIsAClearError) {
  try {
    write_mesh(test::single_triangle(), "/nonexistent-dir-for-lodkit/x.ply");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent-dir-for-lodkit/x.ply"), std::string::npos);
  }
}

}  // namespace
}  // namespace lodkit
