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
// outside, and thousands exactly on faces, edges and vertices of both shells, where the axis
// rays start on a face or run along one), and points far out on every side, are located
// exactly, by the ray locate_point chooses and by each of the others on every other point. The
// ray is tested only against the faces whose boxes it meets; a test that dropped a box the moved
// ray does meet would miscount.
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
        if ((i | j | k) % 2 == 0) {  // every ray, on the lattice of step 1/2
          for (int ray = 0; ray < kLocateRays; ++ray)
            ASSERT_EQ(locate_point_by_ray(solid.mesh, faces, p, ray), truth)
                << p.transpose() << " by ray " << ray;
        }
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

// The same cube and lattice moved to 2^50, where the lattice's step 1/4 is the coordinates'
// unit, and at 2^52 scaled to step 1 (a unit apart is all the doubles there have): no point
// between the lattice's can be formed, so a ray must be decided without any far point or
// retry. Axis rays run along the cube's edges and faces on most of these points.
TEST(LocatePoint, EveryPointOfALatticeAtTheCoordinatesLastUnit) {
  for (const double unit : {0.25, 1.0}) {
    const double base = unit == 1.0 ? 0x1p52 : 0x1p50;
    analytic::AnalyticMesh solid = analytic::cube_with_cavity(4.0, 1.0, 3.0);
    for (Vec3& v : solid.mesh.vertices) v = Vec3::Constant(base) + (unit * 4.0) * v;
    const AabbTree faces = AabbTree::over_faces(solid.mesh);
    for (int i = 0; i <= 24; i += 2)
      for (int j = 0; j <= 24; ++j)
        for (int k = 0; k <= 24; ++k) {
          const Vec3 q(-1 + 0.25 * i, -1 + 0.25 * j, -1 + 0.25 * k);
          const Vec3 p = Vec3::Constant(base) + (unit * 4.0) * q;
          ASSERT_EQ((p - Vec3::Constant(base)) / (unit * 4.0), q);  // the lattice is exact
          ASSERT_EQ(locate_point(solid.mesh, faces, p), cavity_cube_truth(q))
              << unit << ": " << q.transpose();
        }
  }
}

// The octahedron |x| + |y| + |z| <= 3 on the integer lattice over [-4, 4]^3, at the origin and
// moved to 2^52 (where the lattice is every double there is): its vertices lie on the axes and
// its edges in the coordinate planes, so the axis rays from many of these points pass through a
// vertex or along an edge's plane; the answer is known in integers. Every ray is tried.
TEST(LocatePoint, EveryPointOfALatticeAroundAnOctahedron) {
  for (const double base : {0.0, 0x1p52}) {
    analytic::AnalyticMesh solid = analytic::octahedron(3.0);
    for (Vec3& v : solid.mesh.vertices) v += Vec3::Constant(base);
    const AabbTree faces = AabbTree::over_faces(solid.mesh);
    for (int x = -4; x <= 4; ++x)
      for (int y = -4; y <= 4; ++y)
        for (int z = -4; z <= 4; ++z) {
          const int l1 = std::abs(x) + std::abs(y) + std::abs(z);
          const Location truth = l1 < 3    ? Location::kInside
                                 : l1 == 3 ? Location::kOnSurface
                                           : Location::kOutside;
          const Vec3 p = Vec3::Constant(base) + Vec3(x, y, z);
          ASSERT_EQ(locate_point(solid.mesh, faces, p), truth)
              << base << ": " << x << " " << y << " " << z;
          for (int ray = 0; ray < kLocateRays; ++ray)
            ASSERT_EQ(locate_point_by_ray(solid.mesh, faces, p, ray), truth)
                << base << ": " << x << " " << y << " " << z << " by ray " << ray;
        }
  }
}

// A unit cube at 2^52, where its corners are neighbouring doubles, and every lattice point
// around it: on it or outside (none of the doubles is strictly inside).
TEST(LocatePoint, EveryPointAroundAUnitCubeAtTheCoordinatesLastUnit) {
  const double base = 0x1p52;
  const analytic::AnalyticMesh solid = analytic::cube(1.0, Vec3::Constant(base));
  const AabbTree faces = AabbTree::over_faces(solid.mesh);
  for (int x = -3; x <= 4; ++x)
    for (int y = -3; y <= 4; ++y)
      for (int z = -3; z <= 4; ++z) {
        const bool on = x >= 0 && x <= 1 && y >= 0 && y <= 1 && z >= 0 && z <= 1;
        ASSERT_EQ(locate_point(solid.mesh, faces, Vec3::Constant(base) + Vec3(x, y, z)),
                  on ? Location::kOnSurface : Location::kOutside)
            << x << " " << y << " " << z;
      }
}

// A cube with a cavity holding an island, each shell's vertices located against the other two
// shells alone, as the solidity check does: the outer shell's are outside both, the cavity's
// inside the outer cube (the island does not enclose them), the island's inside the outer cube
// and the cavity, an even count, so outside.
TEST(LocatePoint, EachShellsVerticesAgainstTheOtherShells) {
  Mesh m = analytic::cube_with_cavity(4.0, 1.0, 3.0).mesh;  // faces 0-11 outer, 12-23 cavity
  const analytic::AnalyticMesh island = analytic::cube(1.0, Vec3(1.5, 1.5, 1.5));
  const int32_t base = static_cast<int32_t>(m.vertices.size());
  for (const Vec3& v : island.mesh.vertices) m.vertices.push_back(v);
  for (const Face& f : island.mesh.faces)
    m.faces.push_back({f[0] + base, f[1] + base, f[2] + base});
  const AabbTree faces = AabbTree::over_faces(m);
  const Location expected[3] = {Location::kOutside, Location::kInside, Location::kOutside};
  for (int s = 0; s < 3; ++s) {
    auto other = [&](int32_t f) { return f / 12 == s; };
    for (int32_t f = 12 * s; f < 12 * s + 12; ++f)
      for (int c = 0; c < 3; ++c) {
        EXPECT_EQ(locate_point_off_surface(m, faces, m.corner(f, c), other), expected[s]) << s;
        EXPECT_EQ(locate_point(m, faces, m.corner(f, c), other), expected[s]) << s;
        // Against every shell, the vertex lies on its own.
        EXPECT_EQ(locate_point(m, faces, m.corner(f, c)), Location::kOnSurface) << s;
      }
  }
}

// Cubes stacked along x, so that the ray along +x from a point in the first meets every
// one: the answers are the same as with few, whichever ray is cast.
TEST(LocatePoint, CubesStackedAlongTheFirstRay) {
  Mesh m;
  for (int k = 0; k < 400; ++k) {
    const analytic::AnalyticMesh t = analytic::cube(1.0, Vec3(2.0 * k, 0, 0));
    const int32_t base = static_cast<int32_t>(m.vertices.size());
    for (const Vec3& v : t.mesh.vertices) m.vertices.push_back(v);
    for (const Face& f : t.mesh.faces) m.faces.push_back({f[0] + base, f[1] + base, f[2] + base});
  }
  const AabbTree faces = AabbTree::over_faces(m);
  for (int k = 0; k < 400; k += 37) {
    EXPECT_EQ(locate_point(m, faces, Vec3(2.0 * k + 0.5, 0.5, 0.5)), Location::kInside) << k;
    EXPECT_EQ(locate_point(m, faces, Vec3(2.0 * k + 1.5, 0.5, 0.5)), Location::kOutside) << k;
    EXPECT_EQ(locate_point(m, faces, Vec3(2.0 * k + 1.0, 0.5, 0.5)), Location::kOnSurface) << k;
    EXPECT_EQ(locate_point(m, faces, Vec3(2.0 * k, 0.25, 1.0)), Location::kOnSurface) << k;
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
