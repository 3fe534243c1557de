#include "common/mp_interval.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace vobb {
namespace {

// Random rationals with numerators and denominators up to 2^40, of either sign, some of them
// doubles and some 0: each operation's exact result must lie in the enclosure made from the
// operands' enclosures (which themselves are rounded: the rationals are not 128-bit numbers).
TEST(MpInterval, EveryOperationEnclosesTheExactResult) {
  std::mt19937_64 rng(11);
  std::uniform_int_distribution<int64_t> num(-(int64_t{1} << 40), int64_t{1} << 40);
  std::uniform_int_distribution<int64_t> den(1, int64_t{1} << 40);
  auto random_q = [&](int i) {
    if (i % 17 == 0) return Rational(0);
    if (i % 5 == 0) return Rational(std::ldexp(static_cast<double>(num(rng)), -20));  // a double
    Rational q(static_cast<long>(num(rng)), static_cast<long>(den(rng)));
    q.canonicalize();
    return q;
  };
  for (int i = 0; i < 4000; ++i) {
    const Rational a = random_q(i), b = random_q(i + 1);
    const MpInterval x(a), y(b);
    ASSERT_TRUE(x.contains(a));
    ASSERT_TRUE((x + y).contains(a + b));
    ASSERT_TRUE((x - y).contains(a - b));
    ASSERT_TRUE((x * y).contains(a * b));
    ASSERT_TRUE((-x).contains(-a));
    ASSERT_TRUE(abs(x).contains(abs(a)));
    if (sgn(b) != 0) {
      ASSERT_TRUE((x / y).contains(a / b));
    }
    // Wide operands of every sign class: (third - third) is an enclosure of 0 about 2^-128
    // wide, scaled to about +-2^-128 * 2^140 = +-4096, so a value of magnitude below that gets
    // an enclosure straddling 0 (the products' four-candidate case) and larger ones keep their
    // sign. The exact values stay a and b.
    const MpInterval third(Rational(1, 3)),
        spread = (third - third) * MpInterval(std::ldexp(1.0, 140));
    const MpInterval wx = x + spread, wy = y + spread;
    ASSERT_TRUE((wx * wy).contains(a * b));
    ASSERT_TRUE((wx * y).contains(a * b));
    ASSERT_TRUE((x * wy).contains(a * b));
    if (wy.inf() > 0 || wy.sup() < 0) {
      ASSERT_TRUE((wx / wy).contains(a / b));
    }
  }
}

TEST(MpInterval, SignIsDecidedOnlyWhereTheEnclosureDecidesIt) {
  EXPECT_EQ(MpInterval(0).sign(), 0);
  EXPECT_EQ(MpInterval(1e-300).sign(), 1);
  EXPECT_EQ(MpInterval(-2.5).sign(), -1);
  const MpInterval third(Rational(1, 3));
  EXPECT_EQ(third.sign(), 1);
  EXPECT_THROW((third - third).sign(), Undecided);  // [-w, w]: 0 and other values
  EXPECT_THROW(MpInterval(1) / (third - third), Undecided);
}

TEST(MpInterval, NearestIsTheCorrectRoundingOrNothing) {
  double d = 0;
  const Rational third(1, 3);
  ASSERT_TRUE(MpInterval(third).nearest(&d));
  EXPECT_EQ(d, to_double_nearest(third));
  // A tie between two doubles, 1 + 2^-53, is a 128-bit number: it rounds to even, 1.
  const Rational tie = Rational(1) + Rational(1, mpz_class(1) << 53);
  ASSERT_TRUE(MpInterval(tie).nearest(&d));
  EXPECT_EQ(d, 1.0);
  // Just above the tie, past 128 bits: the enclosure straddles it, so it decides nothing.
  const Rational above = tie + Rational(1, mpz_class(1) << 200);
  EXPECT_FALSE(MpInterval(above).nearest(&d));
  EXPECT_EQ(to_double_nearest(above), std::nextafter(1.0, 2.0));
}

TEST(MpInterval, OutwardDoublesAndTextRoundTrip) {
  const Rational q(22, 7);
  const MpInterval x(q);
  EXPECT_LE(Rational(x.inf()), q);
  EXPECT_GE(Rational(x.sup()), q);
  EXPECT_EQ(std::nextafter(x.inf(), 4.0), x.sup());  // the two doubles around 22/7
  std::string lo, hi;
  x.to_text(&lo, &hi);
  MpInterval back;
  ASSERT_TRUE(MpInterval::from_text(lo, hi, &back));
  EXPECT_EQ(back.lo_rational(), x.lo_rational());
  EXPECT_EQ(back.hi_rational(), x.hi_rational());
  EXPECT_FALSE(MpInterval::from_text(hi, lo, &back));  // lo > hi
  EXPECT_FALSE(MpInterval::from_text("0x1p0", "zero", &back));
  EXPECT_FALSE(MpInterval::from_text("", "0x1p0", &back));
}

}  // namespace
}  // namespace vobb
