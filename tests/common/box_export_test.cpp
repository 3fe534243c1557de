#include "common/box_export.h"

#include <gtest/gtest.h>

#include "common/io/mesh_io.h"
#include "common/solidity.h"
#include "test_common.h"

namespace vobb {
namespace {

// Each exported box, read back as a mesh, is a closed outward solid whose exact volume is the
// box's volume up to the rounding of its corners (each corner is 3 roundings off: the
// relative volume error is below 3 * 3 * 2 eps per face; 64 eps bounds it generously).
TEST(BoxExport, BoxesReadBackAsOutwardSolids) {
  Obb b;
  b.center = Vec3(1, -2, 0.5);
  b.axes = orthonormalize({Vec3(1, 2, 3), Vec3(-2, 1, 0), Vec3::Zero()});
  b.half = Vec3(0.3, 1.7, 0.01);
  for (const char* ext : {"obj", "ply"}) {
    const std::string path = test::temp_path(std::string("box.") + ext);
    ASSERT_TRUE(export_boxes({b}, {"node_0"}, path));
    LoadedMesh lm;
    ASSERT_TRUE(load_mesh(path, &lm));
    EXPECT_EQ(lm.mesh.vertices.size(), 8u);
    EXPECT_EQ(lm.mesh.faces.size(), 12u);  // 6 quads, split
    const SolidityReport r = check_solidity(lm.mesh);
    ASSERT_TRUE(r.solid()) << r.verdict();
    EXPECT_NEAR(to_double_nearest(r.volume), volume(b), 64 * 2.2e-16 * volume(b));
    std::remove(path.c_str());
  }
}

TEST(BoxExport, RefusesUnknownExtensionAndBadLevel) {
  EXPECT_FALSE(export_boxes({Obb()}, {}, test::temp_path("box.stl")));
  Tree t;
  t.depth = 0;
  EXPECT_FALSE(export_layer(t, 1, test::temp_path("x.obj")));
}

}  // namespace
}  // namespace vobb
