// The statistics of the discretization study on synthetic errors whose answers are known:
// quantiles, the least-squares rate, and the fit and held-out check of the stated bound B(m).
#include "validate/discretization_study.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace vobb {
namespace {

using validate::DiscretizationResult;
using validate::StudyEval;
using validate::StudySample;

TEST(DiscretizationStudy, QuantileMedianAndSlope) {
  EXPECT_EQ(validate::median({3, 1, 2}), 2);
  EXPECT_EQ(validate::median({4, 1, 2, 3}), 2.5);
  EXPECT_EQ(validate::quantile({0, 10}, 0.25), 2.5);
  // log y = 3 - 2 log x, exactly a line: the slope is -2 up to the round-off of a few logs and
  // sums, under 100 eps relative to it.
  std::vector<double> x, y;
  for (int m : {4, 8, 16, 32}) x.push_back(std::log(m)), y.push_back(3 - 2 * std::log(m));
  EXPECT_NEAR(validate::lsq_slope(x, y), -2.0, 2 * 100 * std::numeric_limits<double>::epsilon());
}

// Fit errors u_i m^-2 vol(O) with u_i = i/100, i = 1..100, at every m: the 97.5 % quantile is
// 0.97525 m^-2 (linear interpolation between 0.97 and 0.98), so B(m) = 0.97525 m^-2 vol(O)
// and 3 % of the fit corpus (u = 0.98, 0.99, 1.00) lies above it. Held-out errors 0.99 m^-2 (above)
// on 3 boxes and 0.5 m^-2 (below) on 97: a violation rate of exactly 3 %.
TEST(DiscretizationStudy, StatedBoundFitAndHeldOutCheck) {
  DiscretizationResult r;
  const int kMs[] = {4, 8, 16, 32, 64};
  auto add = [&](bool held_out, double u) {
    StudySample s;
    s.held_out = held_out;
    s.box_volume = 2.0;
    s.exact = s.lo = s.hi = 1.0;  // a point interval: the certified error is |E - 1|
    r.samples.push_back(s);
    for (int m : kMs) {
      StudyEval e;
      e.sample = r.samples.size() - 1;
      e.m = m;
      e.estimate = s.exact + u * s.box_volume / (double(m) * m);
      r.evals.push_back(e);
    }
  };
  for (int i = 1; i <= 100; ++i) add(false, i / 100.0);
  for (int i = 0; i < 100; ++i) add(true, i < 3 ? 0.99 : 0.5);
  const validate::StatedBound b = validate::fit_stated_bound(r, 0.05);
  // delta bounds each log q_m's error. q_m reads errors E - 1 with E = 1 + u vol / m^2 rounded
  // once: off by eps / 2 absolutely, relative to the least error the 97.5 % quantile reads
  // (u = 0.97 at m = 64). Relative to q_m also: u = i / 100's rounding (eps / 2), abs_error's
  // rounding up (one ulp, eps) and the interpolation's two roundings (2 eps): 3.5 eps. Then the
  // log: glibc's is within one ulp of the true value, and |log q_m| < 16, where an ulp is 8 eps.
  // The slope over x = ln m = ln 2 (2 .. 6) moves by at most delta sum|x - mean| / sum (x - mean)^2
  // = delta 6 / (10 ln 2) < 0.87 delta, plus its own arithmetic's 100 eps (the test above); c = max
  // q_m m^p by delta, by the slope's error times ln 64, and by the power's roundings.
  constexpr double eps = std::numeric_limits<double>::epsilon();
  const double delta = (eps / 2) / (0.97 * 2.0 / (64 * 64)) + 3.5 * eps + 8 * eps;
  const double dp = 0.87 * delta + 2 * 100 * eps;
  EXPECT_NEAR(b.p, 2.0, dp);
  EXPECT_NEAR(b.c, 0.97525, 0.97525 * (delta + dp * std::log(64.0) + 4 * eps));
  EXPECT_EQ(b.fit_n, 100u * 5);
  EXPECT_EQ(b.fit_violations, 3u * 5);
  EXPECT_EQ(b.held_out_n, 100u * 5);
  EXPECT_EQ(b.held_out_violations, 3u * 5);
  EXPECT_TRUE(b.holds());  // 3 % <= 5 %
  // One more violator per m among the held-out boxes and the rate passes the stated level.
  for (int i = 3; i < 6; ++i)
    for (size_t k = 0; k < 5; ++k) {
      StudyEval& e = r.evals[(100 + i) * 5 + k];
      e.estimate = 1.0 + 0.99 * 2.0 / (double(e.m) * e.m);
    }
  EXPECT_FALSE(validate::fit_stated_bound(r, 0.05).holds());  // 6 % > 5 %
  // A non-finite estimate counts as a violation.
  r.evals.back().estimate = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(validate::fit_stated_bound(r, 0.05).held_out_violations, 6u * 5 + 1);
}

}  // namespace
}  // namespace vobb
