#include "data/analytic_meshes.h"

#include <gtest/gtest.h>

#include "common/solidity.h"

namespace vobb::analytic {
namespace {

TEST(AnalyticMeshes, EachIsSolidWithItsClosedFormVolume) {
  for (const AnalyticMesh& a : all()) {
    SCOPED_TRACE(a.name);
    const SolidityReport r = check_solidity(a.mesh);
    EXPECT_TRUE(r.solid()) << r.verdict();
    ASSERT_TRUE(r.volume_known);
    EXPECT_EQ(r.volume, a.volume);  // exact rationals
    EXPECT_EQ(exact_signed_volume(a.mesh), a.volume);
  }
}

TEST(AnalyticMeshes, ClosedFormsAtOtherSizes) {
  EXPECT_EQ(exact_signed_volume(cube(0.75, Vec3(-3, 2, 0.5)).mesh), Rational(27, 64));
  EXPECT_EQ(exact_signed_volume(tetrahedron(2).mesh), Rational(4, 3));  // 8 / 6
  EXPECT_EQ(exact_signed_volume(octahedron(0.5).mesh), Rational(1, 6));
  EXPECT_EQ(exact_signed_volume(polygonal_torus(2, 1, 0.25).mesh), Rational(21));  // 28 * 3 / 4
  EXPECT_EQ(exact_signed_volume(cube_with_cavity(8, 2, 3).mesh), Rational(511));
}

TEST(AnalyticMeshes, TorusHasGenusOneAndCavityTwoShells) {
  const SolidityReport torus = check_solidity(polygonal_torus().mesh);
  // Euler characteristic V - E + F = 2 - 2g.
  EXPECT_EQ(static_cast<long>(torus.vertices) - static_cast<long>(torus.edges) +
                static_cast<long>(torus.faces),
            0);
  EXPECT_EQ(check_solidity(cube_with_cavity().mesh).shells, 2u);
}

}  // namespace
}  // namespace vobb::analytic
