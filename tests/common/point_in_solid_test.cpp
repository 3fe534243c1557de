#include "common/point_in_solid.h"

#include <gtest/gtest.h>

#include <cmath>

#include "data/analytic_meshes.h"

namespace vobb {
namespace {

// The cube [0, 4]^3 with the cavity [1, 3]^3: where a point lies is known exactly.
Location cavity_cube_truth(const Vec3& p) {
  auto within = [&](double lo, double hi) {
    return p.x() >= lo && p.x() <= hi && p.y() >= lo && p.y() <= hi && p.z() >= lo && p.z() <= hi;
  };
  auto strictly_within = [&](double lo, double hi) {
    return p.x() > lo && p.x() < hi && p.y() > lo && p.y() < hi && p.z() > lo && p.z() < hi;
  };
  if (!within(0, 4)) return Location::kOutside;
  if (!strictly_within(0, 4)) return Location::kOnSurface;
  if (strictly_within(1, 3)) return Location::kOutside;  // in the cavity
  if (within(1, 3)) return Location::kOnSurface;
  return Location::kInside;
}

// Every point of a lattice of step 1/4 over [-1, 5]^3 (15,625 points: inside, in the cavity,
// outside, and thousands exactly on faces, edges and vertices of both shells, where the
// segment towards the far point starts on a face or runs along one), and points far out on
// every side, are located exactly. The segment is tested only against the faces whose boxes it
// may meet (a slab test); a test that dropped a box the segment does meet would miscount.
TEST(LocatePoint, EveryPointOfALatticeAroundACubeWithACavity) {
  const analytic::AnalyticMesh solid = analytic::cube_with_cavity(4.0, 1.0, 3.0);
  const AabbTree faces = AabbTree::over_faces(solid.mesh);
  int counts[3] = {0, 0, 0};
  for (int i = 0; i <= 24; ++i) {
    for (int j = 0; j <= 24; ++j) {
      for (int k = 0; k <= 24; ++k) {
        const Vec3 p(-1 + 0.25 * i, -1 + 0.25 * j, -1 + 0.25 * k);
        const Location truth = cavity_cube_truth(p);
        ++counts[static_cast<int>(truth)];
        ASSERT_EQ(locate_point(solid.mesh, faces, p), truth) << p.transpose();
      }
    }
  }
  // Each class is well represented.
  EXPECT_GT(counts[static_cast<int>(Location::kInside)], 1000);
  EXPECT_GT(counts[static_cast<int>(Location::kOutside)], 1000);
  EXPECT_GT(counts[static_cast<int>(Location::kOnSurface)], 1000);
  for (const Vec3& far : {Vec3(1e6, 2, 2), Vec3(-1e6, 2, 2), Vec3(2, 1e6, 2), Vec3(2, -1e6, 2),
                          Vec3(2, 2, 1e6), Vec3(2, 2, -1e6), Vec3(-3e5, -3e5, -3e5)})
    EXPECT_EQ(locate_point(solid.mesh, faces, far), Location::kOutside) << far.transpose();
}

// With the far point taken just beyond a region holding every face kept (here the mesh's own
// bounds, and a region only just holding them), the same answers on the lattice.
TEST(LocatePoint, ARegionHoldingTheFacesGivesTheSameAnswers) {
  const analytic::AnalyticMesh solid = analytic::cube_with_cavity(4.0, 1.0, 3.0);
  const AabbTree faces = AabbTree::over_faces(solid.mesh);
  Aabb tight;
  for (const Vec3& v : solid.mesh.vertices) tight.extend(v);
  for (int i = 0; i <= 12; ++i)
    for (int j = 0; j <= 12; ++j)
      for (int k = 0; k <= 12; ++k) {
        const Vec3 p(-1 + 0.5 * i, -1 + 0.5 * j, -1 + 0.5 * k);
        ASSERT_EQ(locate_point(solid.mesh, faces, p, nullptr, tight), cavity_cube_truth(p))
            << p.transpose();
      }
}

// Points just off a face, by one unit in the last place on either side.
TEST(LocatePoint, PointsOneUlpOffAFace) {
  const analytic::AnalyticMesh solid = analytic::cube_with_cavity(4.0, 1.0, 3.0);
  const AabbTree faces = AabbTree::over_faces(solid.mesh);
  for (double y : {0.5, 1.7, 3.25}) {
    EXPECT_EQ(locate_point(solid.mesh, faces, Vec3(std::nextafter(4.0, 5.0), y, 0.5)),
              Location::kOutside);
    EXPECT_EQ(locate_point(solid.mesh, faces, Vec3(std::nextafter(4.0, 3.0), y, 0.5)),
              Location::kInside);
    EXPECT_EQ(locate_point(solid.mesh, faces, Vec3(std::nextafter(0.0, -1.0), y, 0.5)),
              Location::kOutside);
    EXPECT_EQ(locate_point(solid.mesh, faces, Vec3(std::nextafter(0.0, 1.0), y, 0.5)),
              Location::kInside);
  }
  // The cavity's face x = 3, from the cavity and from the material.
  EXPECT_EQ(locate_point(solid.mesh, faces, Vec3(std::nextafter(3.0, 2.0), 2, 2)),
            Location::kOutside);
  EXPECT_EQ(locate_point(solid.mesh, faces, Vec3(std::nextafter(3.0, 4.0), 2, 2)),
            Location::kInside);
}

}  // namespace
}  // namespace vobb
