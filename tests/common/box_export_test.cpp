#include "common/box_export.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "common/io/mesh_io.h"
#include "common/obb.h"
#include "common/solidity.h"
#include "test_common.h"

namespace vobb {
namespace {

// Each exported box, read back as a mesh, is a closed outward solid, and its exact volume
// is the certified parallelepiped's volume 8 |det[h0 a0, h1 a1, h2 a2]| up to the rounding of
// the corners, which is bounded here from first principles:
// - corners() forms each coordinate as c_j + sum_k (+-h_k) a_kj: 3 products and 3 sums, so
//   its error is at most gamma_6 (|c_j| + sum_k h_k |a_kj|) (Higham, gamma_n = n u / (1 - n u),
//   u = eps / 2); the text writer round-trips doubles (to_chars), so it adds nothing. A corner
//   moves by at most delta = sqrt(3) * that, taking the largest coordinate term M.
// - The triangulated volume V = 1/6 sum_t det(p1, p2, p3) has gradient 1/3 sum_{t at i} A_t n_t
//   at corner i (the link of a closed star telescopes), so the first-order change is at most
//   sum_i |dV/dp_i| delta <= S delta, S the surface area. The rest of the cubic expansion is
//   at most 1/6 (3 P delta^2 + delta^3) per triangle, P the largest |corner|; 12 triangles.
// Seeded boxes with centres up to 100 away and random rotations exercise the |c| term.
TEST(BoxExport, BoxesReadBackAsOutwardSolids) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Obb> boxes;
  {
    Obb b;  // a thin slab away from the origin
    b.center = Vec3(1, -2, 0.5);
    b.axes = orthonormalize({Vec3(1, 2, 3), Vec3(-2, 1, 0), Vec3::Zero()});
    b.half = Vec3(0.3, 1.7, 0.01);
    boxes.push_back(b);
  }
  for (int i = 0; i < 24; ++i) {
    Obb b;
    b.center = Vec3(u(rng), u(rng), u(rng)) * (i < 12 ? 3.0 : 100.0);
    b.axes =
        orthonormalize({Vec3(u(rng), u(rng), u(rng)), Vec3(u(rng), u(rng), u(rng)), Vec3::Zero()});
    b.half = Vec3(0.01 + std::abs(u(rng)), 0.01 + std::abs(u(rng)), 0.01 + std::abs(u(rng)));
    // Every third box left-handed (its third axis negated), as a tree or box file may give it:
    // its quads are written reversed, so that it too reads back as an outward solid.
    if (i % 3 == 2) b.axes[2] = -b.axes[2];
    boxes.push_back(b);
  }
  constexpr double kU = 0.5 * std::numeric_limits<double>::epsilon();
  const double gamma6 = 6 * kU / (1 - 6 * kU);
  for (const char* ext : {"obj", "ply"}) {
    for (size_t i = 0; i < boxes.size(); ++i) {
      const Obb& b = boxes[i];
      SCOPED_TRACE(std::string(ext) + " box " + std::to_string(i));
      const std::string path = test::temp_path(std::string("box.") + ext);
      ASSERT_TRUE(export_boxes({b}, {"node_0"}, path));
      LoadedMesh lm;
      ASSERT_TRUE(load_mesh(path, &lm));
      std::remove(path.c_str());
      EXPECT_EQ(lm.mesh.vertices.size(), 8u);
      EXPECT_EQ(lm.mesh.faces.size(), 12u);  // 6 quads, split
      const SolidityReport r = check_solidity(lm.mesh);
      ASSERT_TRUE(r.solid()) << r.verdict();

      double m = 0.0, p = 0.0;
      for (int j = 0; j < 3; ++j)
        m = std::max(m, std::abs(b.center[j]) + b.half[0] * std::abs(b.axes[0][j]) +
                            b.half[1] * std::abs(b.axes[1][j]) +
                            b.half[2] * std::abs(b.axes[2][j]));
      for (const Vec3& c : corners(b)) p = std::max(p, c.norm());
      const double delta = std::sqrt(3.0) * gamma6 * m;
      const double area =
          8 * (b.half[0] * b.half[1] + b.half[1] * b.half[2] + b.half[0] * b.half[2]);
      // Evaluating the bound takes fewer than 32 roundings; (1 + 64 u) covers them.
      const double bound =
          (1 + 64 * kU) * (area * delta + 2 * (3 * p * delta * delta + delta * delta * delta));
      const Rational exact = exact_volume(b);
      const Rational diff = abs(r.volume - exact);
      EXPECT_LE(diff, Rational(bound))
          << "off by " << to_double_nearest(diff) << ", bound " << bound;
      // The bound is not vacuous: it is below a millionth of the volume.
      EXPECT_LT(bound, 1e-6 * volume(b));
    }
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
