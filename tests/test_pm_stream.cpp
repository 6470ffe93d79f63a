// The .pm stream: exact lossless round trips, quantised size and accuracy, prefix reads, and damage
// (every truncation, flipped bits) that must give a valid prefix or a clear error, never garbage.
#include <gtest/gtest.h>
#include <lodkit/error.h>
#include <lodkit/io.h>
#include <lodkit/metrics.h>
#include <lodkit/pm_io.h>
#include <lodkit/primitives.h>
#include <lodkit/progressive.h>

#include <cstring>
#include <zlib.h>

#include "test_util.h"

namespace lodkit {
namespace {

bool same_mesh(const Mesh& a, const Mesh& b) { return test::difference(a, b).empty(); }

Mesh attributed_sphere() {
  UvSphereOptions o;
  o.segments = 20;
  o.rings = 10;
  o.uvs = true;
  Mesh m = make_uv_sphere(o);
  m.attributes.normals = compute_vertex_normals(m);
  m.attributes.colours.resize(m.num_vertices(), 4);
  for (Index v = 0; v < m.num_vertices(); ++v)
    m.attributes.colours.row(v) << float(v % 5) / 4.0f, 0.25f, 1.0f, 1.0f;
  m.attributes.face_colours.resize(m.num_faces(), 4);
  for (Index f = 0; f < m.num_faces(); ++f) m.attributes.face_colours.row(f) << 1.0f, float(f % 3) / 2.0f, 0.0f, 1.0f;
  return m;
}

TEST(PmStream, LosslessRoundTripIsExactAtEveryLevel) {
  for (const Mesh& input : {test::bumpy_sphere(3, 0.05), attributed_sphere(), make_grid({})}) {
    ProgressiveOptions po;
    po.simplify.attribute_weights.uvs = input.has_uvs() ? 1.0 : 0.0;
    const ProgressiveMesh pm = build_progressive_mesh(input, po);
    PmWriteOptions wo;
    wo.splits_per_block = 37;
    const std::string bytes = write_pm_to_memory(pm, wo);
    const PmReadResult r = read_pm_from_memory(bytes, "mem.pm");
    EXPECT_TRUE(r.complete);
    EXPECT_TRUE(r.warning.empty()) << r.warning;
    ASSERT_EQ(r.pm.max_level(), pm.max_level());
    EXPECT_TRUE(same_mesh(extract_level(r.pm, r.pm.max_level()).mesh, input));
    for (Index level : {Index(0), pm.max_level() / 3, pm.max_level() - 1}) {
      EXPECT_TRUE(same_mesh(extract_level(r.pm, level).mesh, extract_level(pm, level).mesh)) << level;
      EXPECT_GE(r.pm.level_error[level], pm.level_error[level]);
      EXPECT_LE(r.pm.level_error[level], pm.level_error[level] * 1.05);
    }
  }
}

TEST(PmStream, AwkwardInputsSurviveTheStream) {
  Mesh m = test::bumpy_sphere(2, 0.05);
  const Index n = m.num_vertices();
  m.positions.conservativeResize(n + 1, 3);
  m.positions.row(n) = Eigen::RowVector3d(3, 3, 3);  // unreferenced
  const Index f = m.num_faces();
  m.triangles.conservativeResize(f + 1, 3);
  m.triangles.row(f) << 0, 0, 1;  // degenerate
  const ProgressiveMesh pm = build_progressive_mesh(m);
  const PmReadResult r = read_pm_from_memory(write_pm_to_memory(pm), "mem.pm");
  EXPECT_TRUE(same_mesh(extract_level(r.pm, r.pm.max_level()).mesh, m));
}

TEST(PmStream, QuantisedStreamIsCompactAndAccurate) {
  TorusOptions to;
  to.major_segments = 96;
  to.minor_segments = 32;
  const Mesh input = make_torus(to);  // 6144 faces, smooth
  const ProgressiveMesh pm = build_progressive_mesh(input);
  PmWriteOptions wo;
  wo.position_bits = 14;
  PmStreamStats stats;
  const std::string bytes = write_pm_to_memory(pm, wo, &stats);
  const double bits_per_vertex = 8.0 * double(bytes.size()) / input.num_vertices();
  // 77.5 when written (84 before the moved corners were predicted from the fan); raw 14-bit
  // positions alone take 84 per split.
  EXPECT_LT(bits_per_vertex, 80.0);
  EXPECT_EQ(stats.total_bytes, bytes.size());
  const PmReadResult r = read_pm_from_memory(bytes, "mem.pm");
  ASSERT_TRUE(r.complete);
  EXPECT_EQ(r.position_bits, 14);
  const Mesh full = extract_level(r.pm, r.pm.max_level(), VertexOrder::Stream).mesh;
  EXPECT_EQ(full.num_faces(), input.num_faces());
  const Eigen::AlignedBox3d box = bounding_box(input);
  const double step = box.sizes().maxCoeff() / ((1 << 14) - 1);
  EXPECT_LT(compare(input, full).hausdorff, step);
  // Bounds stay conservative after quantisation.
  for (Index level : {Index(0), pm.max_level() / 4, pm.max_level() / 2})
    EXPECT_LE(compare(input, extract_level(r.pm, level).mesh).hausdorff, r.pm.level_error[level]);
}

// Version 1 streams (moved-corner bits not yet predicted from the fan) still read. The fixture was
// written by lodkit 0.1 before the change: `lodkit pm build data/sphere_uv.obj --quantize 12`.
TEST(PmStream, VersionOneStreamsStillRead) {
  const std::string dir = LODKIT_SOURCE_DIR;
  const PmReadResult r = read_pm(dir + "/tests/data/sphere_uv_v1.pm");
  ASSERT_TRUE(r.complete) << r.warning;
  const Mesh input = read_mesh(dir + "/data/sphere_uv.obj");
  const Mesh full = extract_level(r.pm, r.pm.max_level()).mesh;
  EXPECT_EQ(full.num_faces(), input.num_faces());
  const double step = bounding_box(input).sizes().maxCoeff() / ((1 << 12) - 1);
  EXPECT_LT(compare(input, full).hausdorff, step);
}

TEST(PmStream, DracoBaseDecodesToTheSameLevels) {
  const Mesh input = attributed_sphere();
  ProgressiveOptions po;
  po.base_faces = 120;
  const ProgressiveMesh pm = build_progressive_mesh(input, po);
  PmWriteOptions wo;
  wo.position_bits = 16;
  wo.draco_base = true;
  wo.keep_order = true;  // faces keep their corner order, so triangles compare directly
  const PmReadResult r = read_pm_from_memory(write_pm_to_memory(pm, wo), "mem.pm");
  ASSERT_TRUE(r.complete);
  EXPECT_EQ(r.pm.num_faces(0), pm.num_faces(0));
  const Mesh a = extract_level(r.pm, r.pm.max_level(), VertexOrder::Stream).mesh;
  const Mesh b = extract_level(pm, pm.max_level(), VertexOrder::Stream).mesh;
  EXPECT_TRUE(a.triangles == b.triangles);
  EXPECT_LT((a.positions - b.positions).cwiseAbs().maxCoeff(), 1e-3);
  wo.position_bits = 0;
  EXPECT_THROW(write_pm_to_memory(pm, wo), Error);
  wo.position_bits = 12;
  wo.draco_compression_level = 11;  // (was taken)
  EXPECT_THROW(write_pm_to_memory(pm, wo), Error);
}

TEST(PmStream, DracoBaseFallsBackWhereDracoCannotQuantise) {
  // A box as wide as 32-bit floats go: Draco's encoder overflowed the extent and crashed on its base.
  // The stream keeps its own quantised base instead.
  Mesh box = make_box();  // the unit cube around the origin
  box.positions.col(0) *= 6.8e38;
  box.positions.col(1) *= 6.8e38;
  ProgressiveOptions po;
  po.base_faces = box.num_faces();
  const ProgressiveMesh pm = build_progressive_mesh(box, po);
  PmWriteOptions wo;
  wo.position_bits = 14;
  wo.draco_base = true;
  const PmReadResult r = read_pm_from_memory(write_pm_to_memory(pm, wo), "mem.pm");
  ASSERT_TRUE(r.complete);
  const Mesh back = extract_level(r.pm, r.pm.max_level()).mesh;
  ASSERT_EQ(back.num_faces(), box.num_faces());
  const double step = 6.8e38 / ((1 << 14) - 1);  // the longest side over the grid
  EXPECT_LE(compare(box, back).hausdorff, step);
}

TEST(PmStream, PrefixReadStopsAtTheFaceBudget) {
  const Mesh input = test::bumpy_sphere(3, 0.05);
  const ProgressiveMesh pm = build_progressive_mesh(input);
  PmWriteOptions wo;
  wo.splits_per_block = 16;
  const std::string bytes = write_pm_to_memory(pm, wo);
  PmReadOptions ro;
  ro.max_faces = 400;
  const PmReadResult r = read_pm_from_memory(bytes, "mem.pm", ro);
  EXPECT_FALSE(r.complete);
  EXPECT_TRUE(r.warning.empty());
  EXPECT_LE(r.pm.num_faces(r.pm.max_level()), 400);
  EXPECT_GE(r.pm.num_faces(r.pm.max_level()), 398);
  EXPECT_LT(r.bytes_read, bytes.size() / 2);
  // The prefix's top level is the same mesh as the whole stream's level (in stream order).
  EXPECT_TRUE(same_mesh(extract_level(r.pm, r.pm.max_level(), VertexOrder::Stream).mesh,
                        extract_level(pm, r.pm.max_level(), VertexOrder::Stream).mesh));
  EXPECT_EQ(r.total_faces, pm.num_faces(pm.max_level()));  // from the header, though not read

  // A ratio of the finest level's faces reads the same prefix as its face count; with both, the
  // smaller budget holds.
  PmReadOptions by_ratio;
  by_ratio.max_ratio = 0.25;
  const Index quarter = static_cast<Index>(std::llround(0.25 * double(pm.num_faces(pm.max_level()))));
  PmReadOptions by_faces;
  by_faces.max_faces = quarter;
  const PmReadResult a = read_pm_from_memory(bytes, "mem.pm", by_ratio), b = read_pm_from_memory(bytes, "mem.pm", by_faces);
  EXPECT_EQ(a.pm.max_level(), b.pm.max_level());
  EXPECT_EQ(a.bytes_read, b.bytes_read);
  EXPECT_LT(a.bytes_read, bytes.size());
  by_ratio.max_faces = 100;
  const PmReadResult c = read_pm_from_memory(bytes, "mem.pm", by_ratio);
  EXPECT_LE(c.pm.num_faces(c.pm.max_level()), 100);
  EXPECT_LT(c.pm.max_level(), a.pm.max_level());
  by_ratio.max_ratio = 1.5;
  EXPECT_THROW(read_pm_from_memory(bytes, "mem.pm", by_ratio), Error);
}

TEST(PmStream, ErrorAndViewBudgetsReadOnlyThePrefixTheirLevelNeeds) {
  const Mesh input = test::bumpy_sphere(3, 0.05);
  const ProgressiveMesh pm = build_progressive_mesh(input);
  for (int bits : {0, 14}) {
    PmWriteOptions wo;
    wo.position_bits = bits;
    wo.splits_per_block = 16;
    const std::string bytes = write_pm_to_memory(pm, wo);
    const PmReadResult whole = read_pm_from_memory(bytes, "mem.pm");
    const ProgressiveMesh& full = whole.pm;
    ASSERT_TRUE(whole.complete);
    // Budgets from above the base's bound down to zero: the prefix ends at the very level the whole
    // stream's selection picks, and that level is the same mesh.
    const double top = full.level_error[0];
    for (double budget : {2 * top, top, 0.3 * top, 0.05 * top, 0.01 * top, 0.0}) {
      PmReadOptions ro;
      ro.max_error = budget;
      const PmReadResult r = read_pm_from_memory(bytes, "mem.pm", ro);
      const Index level = level_for_error(full, budget);
      EXPECT_TRUE(r.warning.empty()) << r.warning;
      EXPECT_EQ(r.pm.max_level(), level) << bits << " bits, budget " << budget;
      EXPECT_EQ(level_for_error(r.pm, budget), level);
      EXPECT_EQ(r.complete, level == full.max_level());
      if (level + 32 < full.max_level()) {
        EXPECT_LT(r.bytes_read, whole.bytes_read) << budget;
      }
      EXPECT_TRUE(same_mesh(extract_level(r.pm, level, VertexOrder::Stream).mesh,
                            extract_level(full, level, VertexOrder::Stream).mesh));
    }
    for (double distance : {3.0, 10.0, 100.0}) {
      PmReadOptions ro;
      ro.view = ScreenSpaceBudget{1.0, distance, 60.0, 1080.0};
      const PmReadResult r = read_pm_from_memory(bytes, "mem.pm", ro);
      const Index level = level_for_view(full, *ro.view);
      EXPECT_EQ(r.pm.max_level(), level) << bits << " bits, distance " << distance;
      EXPECT_EQ(level_for_view(r.pm, *ro.view), level);
    }
    // With a face budget too, the coarser level wins.
    PmReadOptions both;
    both.max_error = 0.0;
    both.max_faces = 200;
    EXPECT_EQ(read_pm_from_memory(bytes, "mem.pm", both).pm.max_level(), level_for_faces(full, 200));
  }
  // Budgets that make no sense fail with the stream's name.
  const std::string bytes = write_pm_to_memory(pm);
  PmReadOptions negative;
  negative.max_error = -1.0;
  EXPECT_THROW(read_pm_from_memory(bytes, "mem.pm", negative), Error);
  PmReadOptions blind;
  blind.view = ScreenSpaceBudget{1.0, 10.0, 0.0, 1080.0};
  try {
    read_pm_from_memory(bytes, "mem.pm", blind);
    ADD_FAILURE() << "a zero field of view was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("mem.pm: "), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("field of view"), std::string::npos) << e.what();
  }
}

TEST(PmStream, MeasuredLevelsTravelWithTheStreamAndGuideThePrefixRead) {
  const Mesh input = test::bumpy_sphere(3, 0.05);
  ProgressiveOptions po;
  po.measure_levels = true;
  const ProgressiveMesh pm = build_progressive_mesh(input, po);
  ASSERT_FALSE(pm.measured.empty());
  for (int bits : {0, 14}) {
    PmWriteOptions wo;
    wo.position_bits = bits;
    wo.splits_per_block = 16;
    PmStreamStats stats;
    const std::string bytes = write_pm_to_memory(pm, wo, &stats);
    EXPECT_GT(stats.measured_bytes, 0u);
    const PmReadResult whole = read_pm_from_memory(bytes, "mem.pm");
    ASSERT_EQ(whole.pm.measured.size(), pm.measured.size());
    const double slack = bits ? 0.5 * std::sqrt(3.0) * pm.bounds.sizes().maxCoeff() / double((1 << bits) - 1) : 0.0;
    for (std::size_t i = 0; i < pm.measured.size(); ++i) {
      EXPECT_EQ(whole.pm.measured[i].level, pm.measured[i].level);
      EXPECT_EQ(whole.pm.measured[i].rms, pm.measured[i].rms);
      if (bits == 0) {
        EXPECT_EQ(whole.pm.measured[i].hausdorff, pm.measured[i].hausdorff);  // exact
      } else {  // plus the quantisation's reach, as the bounds
        EXPECT_NEAR(whole.pm.measured[i].hausdorff, pm.measured[i].hausdorff + slack, 0.01 * slack);
      }
    }
    // A prefix read by measured error stops at the level selection from the whole stream picks. (At a
    // measured level where the error drops: the values are kept monotone, so a finer level can share
    // a coarser one's, and selection then rightly picks the coarser.)
    auto drop_from = [&](std::size_t i) {
      while (i + 1 < pm.measured.size() && !(pm.measured[i].hausdorff < pm.measured[i - 1].hausdorff)) ++i;
      return i;
    };
    for (std::size_t i : {drop_from(1), drop_from(pm.measured.size() / 2)}) {
      PmReadOptions ro;
      ro.max_error = whole.pm.measured[i].hausdorff;
      ro.select_by = LevelErrorKind::Measured;
      const PmReadResult r = read_pm_from_memory(bytes, "mem.pm", ro);
      const Index level = level_for_error(whole.pm, *ro.max_error, LevelErrorKind::Measured);
      EXPECT_EQ(level, pm.measured[i].level);
      EXPECT_EQ(r.pm.max_level(), level);
      EXPECT_LT(r.bytes_read, bytes.size());
      EXPECT_EQ(level_for_error(r.pm, *ro.max_error, LevelErrorKind::Measured), level);
      EXPECT_LT(r.pm.max_level(), read_pm_from_memory(bytes, "mem.pm", PmReadOptions{.max_error = ro.max_error}).pm.max_level());
    }
  }
  // The block costs its own bytes only; damaged, it is caught like any other block.
  PmStreamStats stats;
  std::string bytes = write_pm_to_memory(pm, {}, &stats);
  const std::string plain = write_pm_to_memory(build_progressive_mesh(input));
  EXPECT_EQ(bytes.size() - plain.size(), stats.measured_bytes);
  bytes[stats.header_bytes + stats.base_bytes + 7] ^= 0x10;
  const PmReadResult damaged = read_pm_from_memory(bytes, "flip.pm");
  EXPECT_NE(damaged.warning.find("checksum"), std::string::npos) << damaged.warning;
  EXPECT_EQ(damaged.pm.max_level(), 0);
  EXPECT_TRUE(damaged.pm.measured.empty());
}

TEST(PmStream, EveryTruncationGivesAValidPrefixOrAClearError) {
  const Mesh input = test::bumpy_sphere(1, 0.05);  // 80 faces: a small stream, every byte tried
  ProgressiveOptions po;
  po.measure_levels = true;  // with every kind of block
  const ProgressiveMesh pm = build_progressive_mesh(input, po);
  for (int bits : {0, 12}) {
    PmWriteOptions wo;
    wo.splits_per_block = 4;
    wo.position_bits = bits;
    const std::string bytes = write_pm_to_memory(pm, wo);
    Index last_level = -1;
    for (std::size_t n = 0; n < bytes.size(); ++n) {
      try {
        const PmReadResult r = read_pm_from_memory(std::string_view(bytes).substr(0, n), "cut.pm");
        validate(r.pm);
        EXPECT_FALSE(r.warning.empty()) << "no warning when cut at " << n;
        EXPECT_GE(r.pm.max_level(), last_level);  // longer prefixes never give fewer levels
        last_level = r.pm.max_level();
        const Mesh m = extract_level(r.pm, r.pm.max_level(), VertexOrder::Stream).mesh;
        validate(m);
        if (bits == 0) {
          EXPECT_TRUE(same_mesh(m, extract_level(pm, r.pm.max_level(), VertexOrder::Stream).mesh));
        }
      } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("cut.pm"), std::string::npos);
        EXPECT_EQ(last_level, -1) << "an error after a longer prefix had worked, at " << n;
      }
    }
    EXPECT_EQ(last_level, pm.max_level()) << "the whole split list should be readable before the end block";
  }
}

TEST(PmStream, FlippedBitsAreCaughtByTheChecksums) {
  const Mesh input = test::bumpy_sphere(2, 0.05);
  const ProgressiveMesh pm = build_progressive_mesh(input);
  PmWriteOptions wo;
  wo.splits_per_block = 8;
  const std::string bytes = write_pm_to_memory(pm, wo);
  for (std::size_t at = 0; at < bytes.size(); at += 97) {
    std::string damaged = bytes;
    damaged[at] = static_cast<char>(damaged[at] ^ (1 << (at % 8)));
    try {
      const PmReadResult r = read_pm_from_memory(damaged, "flip.pm");
      // Either the flip hit a block (a warning and fewer levels or no order), or nothing it guards.
      EXPECT_FALSE(r.warning.empty()) << "a flipped bit at " << at << " went unnoticed";
      if (!r.warning.empty()) {
        EXPECT_NE(r.warning.find("flip.pm"), std::string::npos);
      }
      // Whatever survived is exactly what the intact stream has.
      EXPECT_TRUE(same_mesh(extract_level(r.pm, r.pm.max_level(), VertexOrder::Stream).mesh,
                            extract_level(pm, r.pm.max_level(), VertexOrder::Stream).mesh));
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("flip.pm"), std::string::npos);
    }
  }
}

// Replaces the first occurrence of `from`'s bytes after the header with `to`'s and mends the checksum
// of the chunk holding them: a stream that is intact but says something else.
std::string rewrite_double(std::string bytes, double from, double to) {
  const std::string a(reinterpret_cast<const char*>(&from), 8), b(reinterpret_cast<const char*>(&to), 8);
  const std::size_t at = bytes.find(a, 100);
  if (at == std::string::npos) return {};
  bytes.replace(at, 8, b);
  for (std::size_t chunk = 100; chunk + 9 <= bytes.size();) {  // type, u32 length, payload, u32 CRC
    std::uint32_t length = 0;
    std::memcpy(&length, bytes.data() + chunk + 1, 4);
    const std::size_t end = chunk + 5 + length;
    if (at >= chunk && at < end) {
      const std::uint32_t crc = static_cast<std::uint32_t>(
          crc32(0, reinterpret_cast<const unsigned char*>(bytes.data() + chunk), static_cast<unsigned>(end - chunk)));
      std::memcpy(bytes.data() + end, &crc, 4);
      return bytes;
    }
    chunk = end + 4;
  }
  return {};
}

TEST(PmStream, PositionsPastTheRangeOfAFloatAreRefused) {
  // A fuzzed stream put points near 1e210: finite, but their squares overflow, so regions, distances
  // and selective refinement's hierarchy turned to NaN. Such a split block is damage (the levels
  // before it survive), such a base an error, as for any mesh.
  const ProgressiveMesh pm = build_progressive_mesh(test::bumpy_sphere(2, 0.05));
  PmWriteOptions wo;
  wo.splits_per_block = 16;
  const std::string bytes = write_pm_to_memory(pm, wo);
  const std::size_t late = pm.splits.size() - 3;
  const std::string far_split = rewrite_double(bytes, pm.splits[late].position.x(), 1e210);
  ASSERT_FALSE(far_split.empty());
  const PmReadResult r = read_pm_from_memory(far_split, "far.pm");
  EXPECT_NE(r.warning.find("beyond the range of a float"), std::string::npos) << r.warning;
  EXPECT_LT(r.pm.max_level(), static_cast<Index>(late) + 1);
  EXPECT_GT(r.pm.max_level(), 0);
  (void)SelectiveRefiner(r.pm);  // what survives is sound
  const std::string far_base = rewrite_double(bytes, pm.base_positions[0].y(), -1e210);
  ASSERT_FALSE(far_base.empty());
  try {
    (void)read_pm_from_memory(far_base, "far.pm");
    ADD_FAILURE() << "a base point at -1e210 was read";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("beyond the range of a float"), std::string::npos) << e.what();
  }
  // And a progressive mesh made in memory is checked as one read from a file.
  ProgressiveMesh far = pm;
  far.splits[late].new_position.z() = 1e210;
  EXPECT_THROW(SelectiveRefiner{far}, Error);
}

TEST(PmStream, FilesAreWrittenAtomicallyAndBadFilesAreNamed) {
  test::ScratchDir dir("pm");
  const ProgressiveMesh pm = build_progressive_mesh(test::bumpy_sphere(2, 0.05));
  const PmStreamStats stats = write_pm(pm, dir / "a.pm");
  EXPECT_EQ(std::filesystem::file_size(dir / "a.pm"), stats.total_bytes);
  EXPECT_EQ(dir.entries(), 1u);
  const PmReadResult r = read_pm(dir / "a.pm");
  EXPECT_TRUE(r.complete);
  test::write_text(dir / "text.pm", "solid nothing\n");
  EXPECT_THROW(read_pm(dir / "text.pm"), Error);
  test::write_text(dir / "empty.pm", "");
  try {
    read_pm(dir / "empty.pm");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("empty.pm"), std::string::npos);
  }
  EXPECT_THROW(read_pm(dir / "missing.pm"), Error);
}

}  // namespace
}  // namespace lodkit
