#include "common/obb.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>

#include "common/solidity.h"  // kMaxCoordinate
#include "data/analytic_meshes.h"
#include "test_common.h"

namespace vobb {
namespace {

std::array<Vec3, 3> random_axes(std::mt19937_64& rng) {
  std::normal_distribution<double> n;
  return orthonormalize({Vec3(n(rng), n(rng), n(rng)), Vec3(n(rng), n(rng), n(rng)), Vec3::Zero()});
}

Mesh random_soup(std::mt19937_64& rng, int faces, double scale, const Vec3& offset) {
  std::uniform_real_distribution<double> u(-1, 1);
  Mesh m;
  for (int f = 0; f < faces; ++f) {
    for (int k = 0; k < 3; ++k) m.vertices.push_back(offset + scale * Vec3(u(rng), u(rng), u(rng)));
    m.faces.push_back({3 * f, 3 * f + 1, 3 * f + 2});
  }
  return m;
}

TEST(Obb, VolumeAndCorners) {
  Obb b;
  b.center = Vec3(1, 2, 3);
  b.half = Vec3(0.5, 1, 2);
  EXPECT_EQ(volume(b), 8.0);
  EXPECT_EQ(exact_volume(b), 8);
  const auto c = corners(b);
  EXPECT_EQ(c[0], Vec3(0.5, 1, 1));
  EXPECT_EQ(c[7], Vec3(1.5, 3, 5));
}

// A turned box's stored axes are orthonormal only to round-off: its certified solid's volume is
// 8 h0 h1 h2 |det[a0 a1 a2]| of the stored doubles, which exact_volume gives exactly, an
// independent rational triple product here. volume(), its double estimate, is within 16 eps of
// it: some ten roundings of at most eps / 2 each (its products, and the cross and dot products
// of the determinant, well conditioned for near-orthonormal axes).
TEST(Obb, ExactVolumeIsTheCertifiedSolids) {
  const Obb b = rotated_box(Vec3(0.1, 0.2, 0.3), Vec3(0.3, 0.7, 1.1), 0.9);
  Rational a[3][3];
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i < 3; ++i) a[k][i] = Rational(b.axes[k][i]);
  const Rational det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
                       a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
                       a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
  const Rational expected =
      8 * Rational(b.half[0]) * Rational(b.half[1]) * Rational(b.half[2]) * abs(det);
  EXPECT_EQ(exact_volume(b), expected);
  EXPECT_NE(det, 1);  // the stored axes are not exactly orthonormal: the test is not trivial
  EXPECT_LE(abs(Rational(volume(b)) - expected),
            expected * Rational(16 * std::numeric_limits<double>::epsilon()));
}

// Apart only across a gap: boxes that overlap or touch may meet.
TEST(Obb, ApartOnlyAcrossAGap) {
  const Obb a = rotated_box(Vec3(0.5, 0.5, 0.5), Vec3(1, 1, 1));
  EXPECT_TRUE(boxes_apart(a, rotated_box(Vec3(4, 0.5, 0.5), Vec3(1, 1, 1), 0.7)));
  EXPECT_FALSE(boxes_apart(a, rotated_box(Vec3(2.5, 0.5, 0.5), Vec3(1, 1, 1))));  // x = 1.5
  EXPECT_TRUE(boxes_apart(a, rotated_box(Vec3(2.5 + 1e-6, 0.5, 0.5), Vec3(1, 1, 1))));
  EXPECT_FALSE(boxes_apart(a, rotated_box(Vec3(1, 1, 1), Vec3(1, 1, 1), 0.3)));
  // Two bars crossing at right angles: apart 0.1 above each other, meeting 0.02 above.
  Obb x, y;
  x.center = Vec3(0, 0, 0);
  x.half = Vec3(1, 0.01, 0.01);
  y.center = Vec3(0, 0, 0.1);
  y.axes = {Vec3(0, 1, 0), Vec3(0, 0, 1), Vec3(1, 0, 0)};
  y.half = Vec3(1, 0.01, 0.01);
  EXPECT_TRUE(boxes_apart(x, y));
  y.center.z() = 0.02;
  EXPECT_FALSE(boxes_apart(x, y));
}

TEST(Orthonormalize, GivesRightHandedUnitFrame) {
  std::mt19937_64 rng(3);
  for (int i = 0; i < 100; ++i) {
    const auto a = random_axes(rng);
    // Gram-Schmidt in double: a few ulps off orthonormal (test_common.h derives the bounds).
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(a[k].norm(), 1.0, test::kOrthonormalTol) << i;
      for (int l = k + 1; l < 3; ++l)
        EXPECT_NEAR(a[k].dot(a[l]), 0.0, test::kOrthonormalTol) << i << " " << k << l;
    }
    EXPECT_NEAR(a[0].cross(a[1]).dot(a[2]), 1.0, test::kRightHandedTol) << i;
  }
}

// fit_obb: every vertex inside the certified solid (exactly), and every one of the six box
// faces within fit_slack's padding plus the same again for rounding of some vertex: tight.
TEST(FitObb, ConservativeAndTightOnRandomSoups) {
  std::mt19937_64 rng(5);
  const Vec3 offsets[] = {Vec3::Zero(), Vec3(1e6, -2e6, 3e6), Vec3(1e-6, 0, 0)};
  const double scales[] = {1.0, 1e-6, 1e6};
  for (const Vec3& off : offsets)
    for (double scale : scales) {
      Mesh m = random_soup(rng, 40, scale, off);
      std::vector<int32_t> faces(m.faces.size());
      std::iota(faces.begin(), faces.end(), 0);
      for (int t = 0; t < 10; ++t) {
        const Obb box = fit_obb(m, faces, random_axes(rng));
        ExactBoxContainment inside(box);
        double mesh_scale = 0;
        for (const Vec3& v : m.vertices) {
          ASSERT_TRUE(inside.contains(v));
          mesh_scale = std::max(mesh_scale, v.cwiseAbs().maxCoeff());
        }
        const double slack = fit_slack(box, mesh_scale);
        for (int k = 0; k < 3; ++k) {
          double hi = -INFINITY, lo = INFINITY;
          for (const Vec3& v : m.vertices) {
            const double s = (v - box.center).dot(box.axes[k]);
            hi = std::max(hi, s);
            lo = std::min(lo, s);
          }
          EXPECT_LE(box.half[k] - hi, 2 * slack) << "face +" << k << " not touched";
          EXPECT_LE(box.half[k] + lo, 2 * slack) << "face -" << k << " not touched";
          EXPECT_GT(box.half[k] - hi, -2 * slack);
        }
      }
    }
}

TEST(FitObb, SingleFaceGetsAThinButValidBox) {
  Mesh m;
  m.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  m.faces = {{0, 1, 2}};
  const Obb box = fit_obb(m, {0}, {Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitZ()});
  EXPECT_GT(box.half[2], 0.0);
  EXPECT_LE(box.half[2], 2 * fit_slack(box, 1.0));
  ExactBoxContainment inside(box);
  for (const Vec3& v : m.vertices) EXPECT_TRUE(inside.contains(v));
}

// A box fit around faces within the mesh range reaches at most 3 kMaxCoordinate
// (docs/derivations.md, "The reach of a fitted box"): box_defect takes it. These axes are the
// ones a search over rotations found to reach furthest around the whole range's cube, about
// 2.837 kMaxCoordinate in x; a limit of twice the range refused that box.
TEST(FitObb, BoxesAroundTheWholeCoordinateRangePassBoxDefect) {
  const double r = kMaxCoordinate;
  const Mesh m = analytic::cube(2 * r, Vec3::Constant(-r)).mesh;
  std::vector<int32_t> faces(m.faces.size());
  std::iota(faces.begin(), faces.end(), 0);
  const Eigen::Matrix3d rot = Eigen::Quaterniond(0.43302023128856754, -0.7865646551718255,
                                                 -0.07945384911397368, -0.433008785580843)
                                  .normalized()
                                  .toRotationMatrix();
  std::mt19937_64 rng(11);
  std::vector<std::array<Vec3, 3>> frames = {{rot.col(0), rot.col(1), rot.col(2)}};
  for (int t = 0; t < 200; ++t) frames.push_back(random_axes(rng));
  double furthest = 0;
  for (const auto& axes : frames) {
    const Obb box = fit_obb(m, faces, axes);
    EXPECT_EQ(box_defect(box), "");
    for (const Vec3& c : corners(box)) {
      ASSERT_LE(c.cwiseAbs().maxCoeff(), 3 * r * (1 + 0x1p-40));  // the derived bound
      furthest = std::max(furthest, c.cwiseAbs().maxCoeff());
    }
  }
  EXPECT_GT(furthest, 2.8 * r);  // the case the derivation's bound is about
}

// At the small end: faces of a solid's tiny shell (its coordinates near 2^-1000, or subnormal)
// get boxes whose half extents are normal doubles, so box_defect and the tree files take them,
// and whose solids still hold every vertex exactly. A flat face's box is as thin as allowed.
TEST(FitObb, BoxesAroundTinyFacesPassBoxDefect) {
  std::mt19937_64 rng(12);
  for (const double s : {0x1p-970, 0x1p-1000, 0x1p-1026, 0x1p-1040, 0x1p-1070}) {
    const Mesh m = analytic::tetrahedron(s).mesh;
    for (int t = 0; t < 50; ++t) {
      const std::array<Vec3, 3> axes =
          t == 0 ? std::array<Vec3, 3>{Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitZ()}
                 : random_axes(rng);
      for (const std::vector<int32_t>& faces : {std::vector<int32_t>{0}, {0, 1, 2, 3}}) {
        const Obb box = fit_obb(m, faces, axes);
        EXPECT_EQ(box_defect(box), "") << s << " " << t;
        ExactBoxContainment inside(box);
        for (int32_t f : faces)
          for (int j = 0; j < 3; ++j) EXPECT_TRUE(inside.contains(m.corner(f, j))) << s;
      }
    }
    // The corner face lies in z = 0: along z only the padding remains, the least normal double
    // from 2^-1026 down (16 eps s is below it there).
    const Obb flat = fit_obb(m, {0}, {Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitZ()});
    EXPECT_EQ(flat.half[2], fit_slack(flat, s)) << s;
    if (s <= 0x1p-1026) {
      EXPECT_EQ(flat.half[2], std::numeric_limits<double>::min()) << s;
    }
  }
}

TEST(BoxDefect, RefusesABoxReachingBeyondTheLimitInAnyCoordinate) {
  for (int j = 0; j < 3; ++j) {
    Obb box;
    box.half = Vec3::Constant(0x1p200);
    box.center[j] = kMaxBoxReach - 0x1p200;  // its face at the limit exactly: taken
    EXPECT_EQ(box_defect(box), "");
    box.center[j] = -kMaxBoxReach;  // one face 2^200 beyond it
    EXPECT_EQ(box_defect(box), "extends beyond +-2^242 (about 7.1e72)");
  }
}

TEST(ExactBoxContainment, BoundaryIsInsideAndOneUlpBeyondIsOutside) {
  Obb b;
  b.center = Vec3(0.1, 0.2, 0.3);
  b.half = Vec3(0.5, 0.25, 1.0);
  ExactBoxContainment inside(b);
  // Axis-aligned: the face x = 0.1 + 0.5 is the exact rational sum, which may not be a double;
  // test with a centre and extents whose sums are exact instead.
  Obb e;
  e.center = Vec3(1, 2, 3);
  e.half = Vec3(0.5, 0.25, 1);
  ExactBoxContainment in_e(e);
  EXPECT_TRUE(in_e.contains(Vec3(1.5, 2.25, 4)));  // a corner
  EXPECT_FALSE(in_e.contains(Vec3(std::nextafter(1.5, 2.0), 2, 3)));
  EXPECT_FALSE(in_e.contains(Vec3(1, 2, std::nextafter(2.0, 0.0))));
  EXPECT_TRUE(inside.contains(b.center));
}

// The filter runs in units near the box's size: at 2^-300 (where the unscaled determinant is
// far below the filter's floor) and at 2^200, a corner is inside and one ulp beyond a face is
// out, and points near the faces of a rotated box agree with the rational test.
TEST(ExactBoxContainment, DecidesAtEveryScale) {
  for (const int k : {-300, 200, 0}) {
    Obb e;
    e.center = Vec3(std::ldexp(1, k), std::ldexp(2, k), std::ldexp(3, k));
    e.half = Vec3(std::ldexp(0.5, k), std::ldexp(0.25, k), std::ldexp(1, k));
    const ExactBoxContainment in_e(e);
    const double x = std::ldexp(1.5, k), y = std::ldexp(2.25, k), z = std::ldexp(4, k);
    EXPECT_TRUE(in_e.contains(Vec3(x, y, z))) << k;
    EXPECT_FALSE(in_e.contains(Vec3(std::nextafter(x, 2 * x), y, z))) << k;
    EXPECT_FALSE(in_e.contains(Vec3(x, std::nextafter(y, 2 * y), z))) << k;
    Obb r = rotated_box(e.center, e.half, 0.7, Vec3(1, 2, 3));
    const ExactBoxContainment in_r(r);
    const ExactBoxFrame f(r);
    std::mt19937 rng(k + 1000);
    std::uniform_real_distribution<double> t(-1.0, 1.0);
    int in = 0, out = 0;
    for (int i = 0; i < 400; ++i) {
      Vec3 p = r.center;
      const int face = i % 3;
      for (int j = 0; j < 3; ++j) {
        const double tj = j == face ? (i % 2 ? 1.0 : -1.0) * (1 + std::ldexp(t(rng), -45)) : t(rng);
        p += tj * r.half[j] * r.axes[j];
      }
      bool exact_in = true;
      for (int j = 0; j < 3; ++j) {
        Rational dot = 0;
        for (int a = 0; a < 3; ++a) dot += (Rational(p[a]) - f.c[a]) * f.w[j][a];
        exact_in = exact_in && abs(dot) <= abs(f.det);
      }
      EXPECT_EQ(in_r.contains(p), exact_in) << k << " point " << i;
      (exact_in ? in : out)++;
    }
    EXPECT_GT(in, 50);
    EXPECT_GT(out, 50);
  }
}

// A box with zero half extents is the closed parallelepiped all the same (DESIGN §1): a
// rectangle, a segment or a point, boundary included, and nothing one ulp off it.
TEST(ExactBoxContainment, FlatBoxesAreClosedRectanglesSegmentsAndPoints) {
  Obb rect;
  rect.center = Vec3(1, 2, 3);
  rect.axes = {Vec3(0.6, 0.8, 0), Vec3(-0.8, 0.6, 0), Vec3(0, 0, 1)};
  rect.half = Vec3(0.5, 0.25, 0);
  const ExactBoxContainment in_rect(rect);
  EXPECT_TRUE(in_rect.contains(rect.center));
  EXPECT_TRUE(in_rect.contains(Vec3(1.15, 2.2, 3)));  // about c + 0.25 a0, in the plane z = 3
  EXPECT_FALSE(in_rect.contains(Vec3(1.15, 2.2, std::nextafter(3.0, 4.0))));  // off the plane
  EXPECT_FALSE(in_rect.contains(Vec3(1.6, 2.8, 3)));  // in the plane, about c + a0: beyond t = 1
  Obb aligned = rect;  // axis-aligned, so that its edges are exact in double
  aligned.axes = {Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitZ()};
  const ExactBoxContainment in_aligned(aligned);
  EXPECT_TRUE(in_aligned.contains(Vec3(1.5, 2.25, 3)));  // a corner
  EXPECT_FALSE(in_aligned.contains(Vec3(std::nextafter(1.5, 2.0), 2, 3)));
  EXPECT_FALSE(in_aligned.contains(Vec3(1, std::nextafter(1.75, 0.0), 3)));
  Obb seg = rect;
  seg.half = Vec3(0, 0, 2);
  const ExactBoxContainment in_seg(seg);
  EXPECT_TRUE(in_seg.contains(Vec3(1, 2, 5)));  // an end
  EXPECT_TRUE(in_seg.contains(Vec3(1, 2, 1.5)));
  EXPECT_FALSE(in_seg.contains(Vec3(1, 2, std::nextafter(5.0, 6.0))));
  EXPECT_FALSE(in_seg.contains(Vec3(std::nextafter(1.0, 2.0), 2, 4)));
  Obb point = rect;
  point.half = Vec3::Zero();
  const ExactBoxContainment in_point(point);
  EXPECT_TRUE(in_point.contains(rect.center));
  EXPECT_FALSE(in_point.contains(Vec3(1, 2, std::nextafter(3.0, 4.0))));
}

// A box rotated by the 3-4-5 rotation about z: its axes (3/5, 4/5, 0) round in double, and the
// certified solid is the parallelepiped of the rounded axes. Points strictly inside by a
// margin far above rounding are inside; points as far outside are out.
TEST(ExactBoxContainment, RotatedBox) {
  Obb b;
  b.axes = {Vec3(0.6, 0.8, 0), Vec3(-0.8, 0.6, 0), Vec3(0, 0, 1)};
  b.half = Vec3(2, 1, 1);
  ExactBoxContainment inside(b);
  EXPECT_TRUE(inside.contains(1.999 * b.axes[0] + 0.999 * b.axes[1]));
  EXPECT_FALSE(inside.contains(2.001 * b.axes[0]));
  EXPECT_FALSE(inside.contains(1.001 * b.axes[1]));
}

}  // namespace
}  // namespace vobb
