#include "common/exact_predicates.h"

#include <gtest/gtest.h>

#include <cfenv>
#include <cmath>
#include <limits>
#include <random>

namespace vobb {
namespace {

int reference_orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  Rational u[3], v[3], w[3];
  for (int i = 0; i < 3; ++i) {
    u[i] = Rational(b[i]) - Rational(a[i]);
    v[i] = Rational(c[i]) - Rational(a[i]);
    w[i] = Rational(d[i]) - Rational(a[i]);
  }
  return sgn(u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
             u[2] * (v[0] * w[1] - v[1] * w[0]));
}

int reference_orient2d(const Vec3& a, const Vec3& b, const Vec3& c, int i, int j);

TEST(Orient3d, SignsOfSimpleCases) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  EXPECT_EQ(orient3d(a, b, c, Vec3(0.3, 0.3, 1)), 1);
  EXPECT_EQ(orient3d(a, b, c, Vec3(0.3, 0.3, -1)), -1);
  EXPECT_EQ(orient3d(a, b, c, Vec3(5, -7, 0)), 0);
  EXPECT_EQ(orient3d(a, b, c, Vec3(0, 0, std::ldexp(1.0, -1074))), 1);  // smallest subnormal
}

// Points exactly on the plane z = x + y with large coordinates, where the double evaluation
// rounds: the filter must hand these to the exact path, which must say 0; one unit off the
// plane must give opposite signs. Checked against an independent rational evaluation.
TEST(Orient3d, NearDegenerateLargeCoordinatesMatchRationalReference) {
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<int64_t> big(-(int64_t(1) << 51), int64_t(1) << 51);
  for (int trial = 0; trial < 2000; ++trial) {
    Vec3 p[4];
    for (auto& q : p) {
      const double x = static_cast<double>(big(rng)), y = static_cast<double>(big(rng));
      q = Vec3(x, y, x + y);  // |x + y| < 2^52: exact
    }
    ASSERT_EQ(orient3d(p[0], p[1], p[2], p[3]), 0);
    const Vec3 up = p[3] + Vec3(0, 0, 1), down = p[3] - Vec3(0, 0, 1);
    const int su = orient3d(p[0], p[1], p[2], up), sd = orient3d(p[0], p[1], p[2], down);
    ASSERT_EQ(su, reference_orient3d(p[0], p[1], p[2], up));
    ASSERT_EQ(sd, reference_orient3d(p[0], p[1], p[2], down));
    if (su != 0) {
      ASSERT_EQ(su, -sd);
    }
  }
}

// The exact path takes its inputs in one integer unit, the least set bit among them: points of
// one plane whose coordinates' scales differ by up to 2^1900 (subnormal to 2^900), on it and
// one unit of each point's own scale off it, against the rationals.
TEST(Orient3d, MixedScalesOnOnePlaneMatchRationalReference) {
  std::mt19937_64 rng(19);
  std::uniform_int_distribution<int64_t> big(-(int64_t(1) << 50), int64_t(1) << 50);
  std::uniform_int_distribution<int> scale(-1074, 900);
  for (int trial = 0; trial < 20000; ++trial) {
    Vec3 p[4];
    double unit[4];
    for (int n = 0; n < 4; ++n) {
      unit[n] = std::ldexp(1.0, scale(rng));
      const double x = static_cast<double>(big(rng)) * unit[n];
      const double y = static_cast<double>(big(rng)) * unit[n];
      p[n] = Vec3(x, y, x + y);  // |x + y| < 2^51 units of a power of two: exact
    }
    ASSERT_EQ(orient3d(p[0], p[1], p[2], p[3]), 0) << trial;
    const Vec3 off = p[3] + Vec3(0, 0, unit[3]);
    ASSERT_EQ(orient3d(p[0], p[1], p[2], off), reference_orient3d(p[0], p[1], p[2], off)) << trial;
    ASSERT_EQ(orient2d(p[0], p[1], off, 0, 2), reference_orient2d(p[0], p[1], off, 0, 2)) << trial;
  }
}

TEST(Orient3d, RandomPointsMatchRationalReference) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 5000; ++trial) {
    Vec3 p[4];
    for (auto& q : p) q = Vec3(u(rng), u(rng), u(rng)) * std::pow(10.0, trial % 7 - 3);
    // Every 3rd case lies near the plane of the first three.
    if (trial % 3 == 0) p[3] = p[0] + 0.25 * (p[1] - p[0]) + 0.5 * (p[2] - p[0]);
    ASSERT_EQ(orient3d(p[0], p[1], p[2], p[3]), reference_orient3d(p[0], p[1], p[2], p[3]));
  }
}

// Subnormal coordinates: products underflow, which Shewchuk's relative bound does not cover
// (a review found the filter confidently wrong here before the underflow slack was added).
TEST(Orient3d, SubnormalCoordinatesMatchRationalReference) {
  const Vec3 a(-0x1.e7fe8b008553dp+0, -0x1.4c6b934abf8d8p-3, 0x0.0000000000231p-1022);
  const Vec3 b(-0x1.9fda85c67d136p-1, -0x1.15f63946305dcp-2, -0x0.000000000006ap-1022);
  const Vec3 c(-0x1.7a44ae1818522p+0, -0x1.606abb225c768p-1, -0x0.0000000000987p-1022);
  const Vec3 d(0x1.4ead9ea3923f2p+0, -0x1.1957d21b5d73ep-1, -0x0.00000000006fp-1022);
  EXPECT_EQ(orient3d(a, b, c, d), reference_orient3d(a, b, c, d));
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> u(-2, 2);
  std::uniform_int_distribution<int> tiny(-5000, 5000);
  for (int trial = 0; trial < 200000; ++trial) {
    Vec3 p[4];
    for (auto& q : p) q = Vec3(u(rng), u(rng), tiny(rng) * std::ldexp(1.0, -1074));
    ASSERT_EQ(orient3d(p[0], p[1], p[2], p[3]), reference_orient3d(p[0], p[1], p[2], p[3]))
        << trial;
  }
}

int reference_orient2d(const Vec3& a, const Vec3& b, const Vec3& c, int i, int j) {
  return sgn((Rational(b[i]) - Rational(a[i])) * (Rational(c[j]) - Rational(a[j])) -
             (Rational(b[j]) - Rational(a[j])) * (Rational(c[i]) - Rational(a[i])));
}

// The rounding mode in force while it lives; round to nearest again after.
struct Rounding {
  explicit Rounding(int mode) { std::fesetround(mode); }
  ~Rounding() { std::fesetround(FE_TONEAREST); }
};

// The predicates are called under upward rounding too (the polyhedral solver's intervals): their
// filters hold in every rounding mode. Nearly collinear and nearly coplanar points, whose
// double determinants are mostly round-off, against the rationals, in each mode; and a case
// found by a review, whose determinant computed under upward rounding is 8.9e-16 with the exact
// value -2.5e-17 (a filter derived for round to nearest took that sign as decided). Triples
// shaped like it (a near the origin, c on the line from a through b, beyond a) find such cases
// too: with the round-to-nearest bound the sweep fails within its first thousand.
TEST(OrientInAnyRounding, NearDegeneratePointsMatchTheRationals) {
  const Vec3 a(-0.0002834642645193493, -0.0003402336428779418, 0);
  const Vec3 b(1.5372483323999604, -1.1801000423521457, 0);
  const Vec3 c(-1.0223610699141537, 0.7839076649326921, 0);
  ASSERT_EQ(reference_orient2d(a, b, c, 0, 1), -1);
  for (const int mode : {FE_TONEAREST, FE_UPWARD, FE_DOWNWARD, FE_TOWARDZERO}) {
    {
      const Rounding r(mode);
      EXPECT_EQ(orient2d(a, b, c, 0, 1), -1) << "mode " << mode;
    }
    std::mt19937_64 rng(17);
    std::uniform_real_distribution<double> u(-2, 2), t(-1, 2);
    std::uniform_int_distribution<int> nudge(-1, 1);
    for (int trial = 0; trial < 100000; ++trial) {
      Vec3 p[5];
      for (auto& q : p) q = Vec3(u(rng), u(rng), u(rng));
      // p2 on the line p0 p1 and p4 on the plane p0 p1 p3, as rounded, each then moved by an
      // ulp (or toward 0) in every coordinate.
      const double s = t(rng), w = t(rng);
      p[2] = p[0] + s * (p[1] - p[0]);
      p[4] = p[0] + s * (p[1] - p[0]) + w * (p[3] - p[0]);
      for (int k = 0; k < 3; ++k) {
        p[2][k] = std::nextafter(p[2][k], nudge(rng) * 1e300);
        p[4][k] = std::nextafter(p[4][k], nudge(rng) * 1e300);
      }
      int got2, got3;
      {
        const Rounding r(mode);
        got2 = orient2d(p[0], p[1], p[2], 0, 1);
        got3 = orient3d(p[0], p[1], p[3], p[4]);
      }
      ASSERT_EQ(got2, reference_orient2d(p[0], p[1], p[2], 0, 1))
          << "mode " << mode << ", " << trial;
      // As the review's case: a near the origin, c on the line from a through b, beyond a.
      const Vec3 a2 = 1e-3 * Vec3(u(rng), u(rng), 0), c2 = a2 - 0.5 * (t(rng) + 1) * (p[1] - a2);
      {
        const Rounding r(mode);
        got2 = orient2d(a2, p[1], c2, 0, 1);
      }
      ASSERT_EQ(got2, reference_orient2d(a2, p[1], c2, 0, 1)) << "mode " << mode << ", " << trial;
      ASSERT_EQ(got3, reference_orient3d(p[0], p[1], p[3], p[4]))
          << "mode " << mode << ", " << trial;
    }
  }
}

// Inputs whose differences overflow: under a directed rounding an overflowing difference is the
// largest double, not infinity, so the filter would see a value off by half of it. Cases an
// audit found, where the filter gave the wrong sign rounding upward: such inputs go to rationals.
TEST(OrientInAnyRounding, DifferencesThatOverflowGoToTheRationals) {
  const double M = std::numeric_limits<double>::max();
  const Vec3 a(M, 0, 0), b(-M, 0x1.8p-47, 0), c(std::nextafter(M, 0.0), 0x1p-100, 0);
  ASSERT_EQ(reference_orient2d(a, b, c, 0, 1), -1);
  const Vec3 A(M, 0, 0), B(M, 0, 1), C(-M, 0x1.8p-47, 0), D(std::nextafter(M, 0.0), 0x1p-100, 0);
  ASSERT_EQ(reference_orient3d(A, B, C, D), -1);
  for (const int mode : {FE_TONEAREST, FE_UPWARD, FE_DOWNWARD, FE_TOWARDZERO}) {
    int got2, got3;
    {
      const Rounding r(mode);
      got2 = orient2d(a, b, c, 0, 1);
      got3 = orient3d(A, B, C, D);
    }
    EXPECT_EQ(got2, -1) << "mode " << mode;
    EXPECT_EQ(got3, -1) << "mode " << mode;
  }
}

TEST(Orient2d, CollinearityIsExact) {
  EXPECT_TRUE(collinear(Vec3(0, 0, 0), Vec3(1, 1, 1), Vec3(3, 3, 3)));
  EXPECT_FALSE(collinear(Vec3(0, 0, 0), Vec3(1, 1, 1), Vec3(3, 3, std::nextafter(3.0, 4.0))));
  // In binary, 0.9 is not exactly 3 * 0.3 nor 0.3 exactly 3 * 0.1: nearly collinear, and the
  // rational cross product decides.
  const Vec3 a(0, 0, 0), b(0.1, 0.3, 0), c(0.3, 0.9, 0);
  const Rational cross = Rational(b[0]) * Rational(c[1]) - Rational(b[1]) * Rational(c[0]);
  EXPECT_NE(cross, 0);
  EXPECT_FALSE(collinear(a, b, c));
  EXPECT_TRUE(collinear(a, Vec3(0.1, 0.2, 0), Vec3(0.3, 0.6, 0)));  // y = 2x exactly
  EXPECT_EQ(orient2d(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), 0, 1), 1);
  EXPECT_EQ(orient2d(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, -1, 0), 0, 1), -1);
}

// The volume's integer sum against the definition in rationals, on soups whose coordinates
// span the doubles: subnormals, zeros, both signs, up to 2^240, and odd mantissas.
TEST(ExactSignedVolume, IsTheRationalSumOfTripleProductsOverSix) {
  auto reference = [](const Mesh& m) -> Rational {  // not GMP's expression, which would dangle
    Rational six_v = 0;
    for (size_t f = 0; f < m.faces.size(); ++f) {
      Rational a[3], b[3], c[3];
      for (int k = 0; k < 3; ++k) {
        a[k] = Rational(m.corner(f, 0)[k]);
        b[k] = Rational(m.corner(f, 1)[k]);
        c[k] = Rational(m.corner(f, 2)[k]);
      }
      six_v += a[0] * (b[1] * c[2] - b[2] * c[1]) + a[1] * (b[2] * c[0] - b[0] * c[2]) +
               a[2] * (b[0] * c[1] - b[1] * c[0]);
    }
    return six_v / 6;
  };
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<double> unit(-1, 1);
  // Scales 2^240 down by up to 0, 40 or 1320 binades (the last reaching subnormals).
  for (const int spread : {0, 40, 1320}) {
    std::uniform_int_distribution<int> drop(0, spread);
    for (int trial = 0; trial < 20; ++trial) {
      Mesh m;
      for (int v = 0; v < 12; ++v) {
        Vec3 p;
        for (int k = 0; k < 3; ++k)
          p[k] = rng() % 7 == 0 ? 0.0 : std::ldexp(unit(rng), 240 - drop(rng));
        m.vertices.push_back(p);
      }
      for (int f = 0; f < 16; ++f)
        m.faces.push_back({static_cast<int32_t>(rng() % 12), static_cast<int32_t>(rng() % 12),
                           static_cast<int32_t>(rng() % 12)});
      EXPECT_EQ(exact_signed_volume(m), reference(m)) << spread << " " << trial;
    }
  }
  Mesh zero;  // every coordinate 0
  zero.vertices.assign(3, Vec3::Zero());
  zero.faces = {{0, 1, 2}};
  EXPECT_EQ(exact_signed_volume(zero), Rational(0));
}

TEST(ToDoubleNearest, RoundsToNearestNotTowardZero) {
  EXPECT_EQ(to_double_nearest(Rational(1, 3)), 1.0 / 3.0);  // IEEE division rounds to nearest
  // 1 + 2^-53 + 2^-80 lies just above the midpoint of 1 and 1 + 2^-52: nearest is the latter,
  // while truncation (mpq_get_d) gives 1.
  Rational q = 1;
  q += Rational(1) / (Rational(mpz_class(1) << 53));
  q += Rational(1) / (Rational(mpz_class(1) << 80));
  EXPECT_EQ(to_double_nearest(q), 1.0 + std::ldexp(1.0, -52));
  EXPECT_EQ(q.get_d(), 1.0);
  EXPECT_EQ(format_nearest(Rational(1, 10)), "0.10000000000000001");
}

// Beyond the doubles: the nearest is infinity from 2^1024 - 2^970 (the midpoint between the
// largest double and 2^1024) on, and enclose gives the largest double and infinity.
TEST(ToDoubleNearest, BeyondTheDoublesIsInfinityAndEnclosedByTheLargestOne) {
  const Rational two_1024(mpz_class(1) << 1024), two_970(mpz_class(1) << 970);
  const double most = std::numeric_limits<double>::max();  // 2^1024 - 2^971
  EXPECT_EQ(to_double_nearest(two_1024 - two_970 - 1), most);
  EXPECT_EQ(to_double_nearest(two_1024 - two_970), INFINITY);  // a tie: to even, 2^1024
  EXPECT_EQ(to_double_nearest(-two_1024), -INFINITY);
  double lo = 0, hi = 0;
  enclose(two_1024, &lo, &hi);
  EXPECT_EQ(lo, most);
  EXPECT_EQ(hi, INFINITY);
  enclose(-two_1024 - two_1024, &lo, &hi);
  EXPECT_EQ(lo, -INFINITY);
  EXPECT_EQ(hi, -most);
  enclose(Rational(most), &lo, &hi);  // the largest double itself
  EXPECT_EQ(lo, most);
  EXPECT_EQ(hi, most);
}

// Below 2^-1022 the doubles are the multiples of 2^-1074: one rounding to nearest, ties to
// even, and no double rounding through 53 bits (which sent (0.5 + 2^-60) 2^-1074 to 0).
TEST(ToDoubleNearest, SubnormalsRoundOnce) {
  const Rational tiny = Rational(1) / Rational(mpz_class(1) << 1074);  // 2^-1074
  const double least = std::ldexp(1.0, -1074);
  const Rational just_above_half =
      (Rational(1, 2) + Rational(1) / Rational(mpz_class(1) << 60)) * tiny;
  EXPECT_EQ(to_double_nearest(just_above_half), least);
  EXPECT_EQ(to_double_nearest(-just_above_half), -least);
  EXPECT_EQ(to_double_nearest(Rational(1, 2) * tiny), 0.0);        // tie: to even (0)
  EXPECT_EQ(to_double_nearest(Rational(3, 2) * tiny), 2 * least);  // tie: to even (2)
  EXPECT_EQ(to_double_nearest(Rational(5, 2) * tiny), 2 * least);  // tie: to even (2)
  EXPECT_EQ(to_double_nearest(Rational(7, 3) * tiny), 2 * least);
  // The top of the subnormal range rounds up into the least normal double.
  const Rational least_normal = Rational(1) / Rational(mpz_class(1) << 1022);
  EXPECT_EQ(to_double_nearest(least_normal - Rational(1, 4) * tiny), std::ldexp(1.0, -1022));
  EXPECT_EQ(to_double_nearest(least_normal - Rational(3, 4) * tiny),
            std::ldexp(1.0, -1022) - least);
  // Every subnormal double converts back to itself.
  for (double d :
       {least, 3 * least, std::ldexp(1.0, -1030) + least, std::ldexp(1.0, -1022) - least})
    EXPECT_EQ(to_double_nearest(Rational(d)), d);
}

}  // namespace
}  // namespace vobb
