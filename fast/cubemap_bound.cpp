#include "fast/cubemap_bound.h"

#include <cmath>
#include <limits>

namespace vobb {

// The GL deviation bound. Derivation: docs/derivations.md, "The GL deviation bound".
namespace {
constexpr double kFloatMin = 1.1754943508222875e-38;  // FLT_MIN, 2^-126
}  // namespace

bool gl_evaluates_in_float(const BoxPlan& plan) {
  for (const LocalTriangle& t : plan.tris) {
    const double fn = pow2_normalizer(t.normal[0], t.normal[1], t.normal[2]);
    if (t.plane != 0 && std::abs(t.plane * fn) < 3 * kFloatMin) return false;
  }
  return true;
}

double gl_deviation_bound(const BoxPlan& plan, int m) {
  if (!gl_evaluates_in_float(plan)) return 0.0;  // evaluated by the CPU twin's code (header)
  if (plan.flat || plan.spans.empty()) return cpu_rounding_bound(plan, m);
  constexpr double u = 1.0 / (1 << 24);
  const PlanRounding r = analyse_plan_rounding(plan, m, RoundingModel{u, 3 * kFloatMin, true});
  // The longest chain of float additions a texel's value passes through: its own sums, its
  // lane's run over the slice, the 8-level tree; the double sum of the slices adds at most
  // (slices - 1) 2^-53 < 2^-24 of their absolute sum, counted as one more.
  const double slice = std::min(6.0 * m * m, static_cast<double>(kReduceSliceTexels));
  const double K = r.most_per_texel + std::ceil(slice / 256) + 8 + (reduce_slices(m) > 1 ? 1 : 0);
  const double summation = K * u / (1 - K * u) * (r.sum_abs + 2 * r.uncertain);
  const double texel_weight = 4.0 / (3.0 * m * m);
  return plan.frame.volume_scale * texel_weight * (r.value_errors + 2 * r.uncertain + summation) +
         cpu_rounding_bound(plan, m);
}

namespace {

// The round-off term (header): 32 eps of the volume, plus 2^-1068 for underflow: where the
// volume scale or the products with it are subnormal, each of their roughly 20 operations may
// lose half a subnormal step (2^-1075) instead of a relative eps, and a volume that underflows
// to 0 (a flat plan) was below a few steps.
double roundoff_term(const Obb& box) {
  return 32 * std::numeric_limits<double>::epsilon() * volume(box) + 0x1p-1068;
}

}  // namespace

double range_bound(const Obb& box, double estimate) {
  // U: Hadamard's inequality, |det A| <= ||a0|| ||a1|| ||a2||, in double, carried as a mantissa
  // and a power of two so that no intermediate product underflows (a box may be 2^243 long and
  // 2^-1022 thin). Each norm is within 2 eps of its value (the dot product's roundings, halved
  // by the square root, and the root's own), each h_k ||a_k|| within one more (up to eps where
  // it is subnormal: h_k >= 2^-1022 by box_defect and ||a_k|| >= 1/2), and the 3 mantissa
  // products one eps each: under 12 eps, raised by 32 eps. The one final scaling, U - E and
  // the larger of the two lose at most one rounding each where the result is normal (the
  // factor 1 + 4 eps) and 2^-1075 absolutely where it underflows (2^-1068 covers them).
  constexpr double eps = std::numeric_limits<double>::epsilon();
  double mantissa = 8 * (1 + 32 * eps);
  int exponent = 0;
  for (int k = 0; k < 3; ++k) {
    int e = 0;
    mantissa *= std::frexp(box.half[k] * box.axes[k].norm(), &e);  // in [1/2, 1), or 0
    exponent += e;
  }
  const double u = std::ldexp(mantissa, exponent);
  return std::max(std::abs(estimate), std::abs(u - estimate)) * (1 + 4 * eps) + 0x1p-1068;
}

CubemapBounds cubemap_bounds(const BoxPlanner& planner, const Obb& box, int m) {
  const BoxPlan plan = planner.plan(box, m);
  return {resolution_bound(plan, m), gl_deviation_bound(plan, m), cpu_rounding_bound(plan, m),
          roundoff_term(box), plan.unresolved};
}

double cubemap_bound(const BoxPlanner& planner, bool gl, const Obb& box, int m, bool* unresolved) {
  const BoxPlan plan = planner.plan(box, m);
  if (unresolved) *unresolved = plan.unresolved;
  CubemapBounds b;
  b.resolution = resolution_bound(plan, m);
  b.roundoff = roundoff_term(box);
  if (!gl) {
    b.cpu_rounding = cpu_rounding_bound(plan, m);
    return b.cpu_rigorous();
  }
  // gl_deviation_bound includes the twin's round-off, except where GL runs the twin's code
  // and it is 0 (CubemapBounds::rigorous).
  b.deviation = gl_deviation_bound(plan, m);
  if (b.deviation == 0) b.cpu_rounding = cpu_rounding_bound(plan, m);
  return b.rigorous();
}

double clamp_to_obv_range(const Obb& box, double estimate, double solid_volume) {
  const double v = volume(box);
  const double lo = std::max(0.0, v - std::max(0.0, solid_volume));  // <= v
  return std::min(std::max(estimate, lo), v);
}

}  // namespace vobb
