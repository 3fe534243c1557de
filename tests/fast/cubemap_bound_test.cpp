#include "fast/cubemap_bound.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "common/exact_predicates.h"
#include "common/obb.h"

namespace vobb {
namespace {

Obb make_box(const Vec3& half, const std::array<Vec3, 3>& axes) {
  Obb b;
  b.center = Vec3(0.25, -0.5, 1);
  b.axes = axes;
  b.half = half;
  return b;
}

// range_bound must hold against the exact range [0, V*] of the OBV, compared in rationals: for
// estimates below, inside and above the range, it is at least the distance from the estimate
// to both ends. Boxes: axis-aligned, and turned with axes off orthonormal by a few 1e-6 (where
// V* is not the product of the extents), 2^200 long and 2^-1000 thin, extents (2^-600, 2^-500,
// 2^200) and (2^-209, 2^-1022, 2^235), whose product taken left to right underflows on the way
// to a normal V* (volume(), common/obb.cpp, had that defect), tiny (V* below the doubles), and
// flat.
TEST(RangeBound, CoversTheDistanceToBothEndsOfTheExactRange) {
  std::mt19937_64 rng(7);
  auto uniform = [&] { return static_cast<double>(rng() >> 11) * 0x1.0p-53; };
  const std::array<Vec3, 3> identity = {Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitZ()};
  std::vector<Obb> boxes = {make_box(Vec3(1, 2, 3), identity),
                            make_box(Vec3(0x1p200, 0x1p-1000, 0.75), identity),
                            make_box(Vec3(0x1p-600, 0x1p-500, 0x1p200), identity),
                            make_box(Vec3(0x1p-209, 0x1p-1022, 0x1p235), identity),
                            make_box(Vec3(0x1p-400, 0x1p-400, 0x1p-300), identity),
                            make_box(Vec3(1, 0, 2), identity)};
  for (int i = 0; i < 20; ++i) {
    std::array<Vec3, 3> axes =
        orthonormalize({Vec3(uniform() - 0.5, uniform() - 0.5, uniform() - 0.5),
                        Vec3(uniform() - 0.5, uniform() - 0.5, uniform() - 0.5), Vec3::Zero()});
    // Off by up to 1.5e-6 per component: each dot product within 2 sqrt(3) 1.5e-6 + 7e-12 <
    // 5.3e-6 of the identity's, inside box_defect's 1e-5.
    for (Vec3& a : axes)
      for (int c = 0; c < 3; ++c) a[c] += 3e-6 * (uniform() - 0.5);
    boxes.push_back(make_box(Vec3(0.1 + uniform(), 0.1 + uniform(), 0.1 + uniform()), axes));
  }
  for (const Obb& box : boxes) {
    ASSERT_EQ(box_defect(box), "");
    const Rational v = exact_volume(box);
    const double vd = to_double_nearest(v);
    for (double e : {-1.0, -vd, 0.0, 0.5 * vd, vd, 2 * vd, 3.0}) {
      const Rational bound(range_bound(box, e));
      EXPECT_GE(bound, Rational(std::abs(e))) << e;           // the OBV 0
      EXPECT_GE(bound, Rational(abs(v - Rational(e)))) << e;  // the OBV V*
    }
  }
}

// And it is tight where the estimate is the range's middle: about half the box's volume.
TEST(RangeBound, IsHalfTheVolumeForAnEstimateInTheMiddle) {
  const Obb box = make_box(Vec3(1, 2, 3), {Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitZ()});
  // V* = 48, so the range's half is 24. range_bound raises U = 48 by 32 eps of itself, which is
  // 64 eps of U - 24 = 24, then the difference by 4 eps; one rounding of the result (the rest
  // are exact for these powers of two and 3) adds at most one eps more. Compared as rationals.
  constexpr double eps = std::numeric_limits<double>::epsilon();
  const Rational bound(range_bound(box, 24));
  EXPECT_GE(bound, Rational(24));
  EXPECT_LE(bound,
            Rational(24) * Rational(1 + 64 * eps) * Rational(1 + 4 * eps) * Rational(1 + eps));
}

// clamp_to_obv_range never moves an estimate away from the exact OBV, which lies in its range
// [max(0, V - S), V]. The solid is the unit cube [0, 1]^3 (S = 1), and the boxes' OBV are
// closed forms: a box holding the cube has V - 1, one beside it V, one inside it 0, one
// 2^10 times the cube's size in each direction V - 1 (estimated near 0, it moves to its OBV). The
// extents are powers of two, so volume() is exact and the comparison exact too (as rationals).
TEST(ClampToObvRange, NeverMovesAnEstimateAwayFromTheExactObv) {
  const std::array<Vec3, 3> identity = {Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitZ()};
  auto box = [&](const Vec3& center, const Vec3& half) {
    Obb b;
    b.center = center;
    b.axes = identity;
    b.half = half;
    return b;
  };
  struct Case {
    Obb box;
    Rational obv;
  };
  const Vec3 mid(0.5, 0.5, 0.5);
  const std::vector<Case> cases = {
      {box(mid, Vec3(1, 1, 1)), Rational(7)},                           // holds the cube
      {box(Vec3(4, 0.5, 0.5), Vec3(1, 0.5, 0.25)), Rational(1)},        // beside it: all of V = 1
      {box(mid, Vec3(0.25, 0.125, 0.25)), Rational(0)},                 // inside it
      {box(mid, Vec3(0x1p10, 0x1p10, 0x1p10)), Rational(0x1p33) - 1}};  // 2^10 times its size
  for (const Case& c : cases) {
    const double v = volume(c.box);
    ASSERT_EQ(Rational(v), exact_volume(c.box));
    for (double e : {-v, -1.0, 0.0, 0.25 * v, 0.5 * v, v - 1, v, 2 * v}) {
      const double moved = clamp_to_obv_range(c.box, e, 1.0);
      EXPECT_LE(abs(Rational(moved) - c.obv), abs(Rational(e) - c.obv)) << e;
      EXPECT_GE(Rational(moved), Rational(0)) << e;
      EXPECT_LE(Rational(moved), Rational(v)) << e;
    }
    // An estimate at the exact OBV stays there.
    const double at = to_double_nearest(c.obv);
    if (Rational(at) == c.obv) {
      EXPECT_EQ(clamp_to_obv_range(c.box, at, 1.0), at);
    }
  }
  // The large box estimated at 0 moves to its OBV.
  EXPECT_EQ(Rational(clamp_to_obv_range(cases[3].box, 0, 1.0)), cases[3].obv);
}

}  // namespace
}  // namespace vobb
