// The stability suite's fast part: meshes built to make simplifiers fail. The default method must
// never output a non-manifold edge it did not get, a flipped face, a non-finite coordinate, or a
// changed genus, components or boundary count — at any target, down to the smallest legal mesh.
#include <gtest/gtest.h>
#include <lodkit/decimate.h>
#include <lodkit/inspect.h>
#include <lodkit/metrics.h>
#include <lodkit/progressive.h>
#include <lodkit/simplify.h>

#include "stability_suite.h"

namespace lodkit {
namespace {

// The default method, as it is and avoiding or refusing faces that face against the input.
TEST(Stability, DefaultMethodStaysValidOnTheSuite) {
  const std::optional<InvertedFaces> modes[] = {std::nullopt, InvertedFaces::Avoid, InvertedFaces::Refuse};
  for (const test::StabilityCase& c : test::stability_suite()) {
    const MeshReport before = inspect(c.mesh);
    for (const std::optional<InvertedFaces> inverted : modes) {
      for (double ratio : {0.1, 0.01, 0.0}) {
        SCOPED_TRACE(c.name + " inverted faces: " + (inverted ? to_string(*inverted) : "default") +
                     " ratio: " + std::to_string(ratio));
        SimplifyOptions o;
        o.target_ratio = ratio;
        o.inverted_faces = inverted;
        const SimplifyResult r = simplify(c.mesh, o);
        ASSERT_TRUE(r.mesh.positions.allFinite());
        validate(r.mesh);
        const MeshReport after = inspect(r.mesh);
        EXPECT_LE(after.non_manifold_edges, before.non_manifold_edges);
        EXPECT_EQ(after.euler_characteristic, before.euler_characteristic);
        EXPECT_EQ(after.components, before.components);
        EXPECT_EQ(after.boundary_loops, before.boundary_loops);
        if (before.genus) {
          ASSERT_TRUE(after.genus);
          EXPECT_EQ(*after.genus, *before.genus);
        }
        // Faces against the nearest input face, while the output still follows the input; at the
        // extremes (a torus of nine vertices, a box of 12 faces at a tenth) "nearest" loses its
        // meaning: then a closed mesh must at least stay outward. Refused, there are none at any ratio.
        if ((ratio >= 0.1 && ratio * c.mesh.num_faces() > 4) || inverted == InvertedFaces::Refuse) {
          EXPECT_EQ(count_flipped_faces(c.mesh, r.mesh), 0);
        }
        if (inverted == InvertedFaces::Refuse) {
          EXPECT_FALSE(r.inverted_allowed_at);
        }
        if (before.volume && after.volume) {
          EXPECT_GT(*after.volume * *before.volume, 0.0);
        }
        EXPECT_LT(r.faces_out, c.mesh.num_faces());
        if (r.reason != StopReason::TargetReached) {
          EXPECT_FALSE(r.reason_text.empty());
        }
      }
    }
  }
}

// Every other method, and every level of a progressive mesh, outputs what validate() takes (so it
// can be written and read back): finite, and within a float's range where the input reaches it.
TEST(Stability, EveryMethodOutputsAValidMeshOnTheSuite) {
  for (const test::StabilityCase& c : test::stability_suite()) {
    for (const SimplifyMethod method : {SimplifyMethod::Hoppe, SimplifyMethod::EdgeLength}) {
      for (double ratio : {0.1, 0.0}) {
        SCOPED_TRACE(c.name + " " + to_string(method) + " ratio: " + std::to_string(ratio));
        const SimplifyResult r = simplify(c.mesh, {.method = method, .target_ratio = ratio});
        EXPECT_NO_THROW(validate(r.mesh));
      }
    }
    SCOPED_TRACE(c.name);
    EXPECT_NO_THROW(validate(decimate(c.mesh, {.target_ratio = 0.1}).mesh));
    const ProgressiveMesh pm = build_progressive_mesh(c.mesh);
    for (PMCursor cursor(pm);; cursor.refine()) {
      EXPECT_NO_THROW(validate(cursor.extract().mesh)) << "level " << cursor.level();
      if (cursor.level() + 1 >= pm.num_levels()) break;
      for (Index skip = 0; skip < pm.num_levels() / 8; ++skip) cursor.refine();  // about 9 levels each
    }
  }
}

}  // namespace
}  // namespace lodkit
