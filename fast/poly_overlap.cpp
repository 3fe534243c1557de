#include "fast/poly_overlap.h"

#include <tbb/parallel_for.h>

#include <cmath>

#include "common/cell_clip.h"
#include "fast/interval.h"

namespace vobb {

PolyOverlapSolver::PolyOverlapSolver(const Mesh& mesh) : mesh_(mesh), faces_(AabbTree::over_faces(mesh)) {}

bool PolyOverlapSolver::apart(const Obb& a, const Obb& b) {
  const Vec3 d = b.center - a.center;
  // Every projection below is a few products and sums of numbers no larger than `scale`: their
  // rounding is far below 1e-12 of it, so a gap wider than that is a true gap.
  const double scale = d.cwiseAbs().sum() + a.half.sum() + b.half.sum();
  const double slack = 1e-12 * scale + 1e-300;
  auto split_by = [&](const Vec3& axis) {
    const double n = axis.norm();
    if (!(n > 1e-6)) return false;  // parallel edges: a degenerate axis decides nothing
    const Vec3 u = axis / n;
    double ra = 0, rb = 0;
    for (int k = 0; k < 3; ++k) {
      ra += a.half[k] * std::abs(u.dot(a.axes[k]));
      rb += b.half[k] * std::abs(u.dot(b.axes[k]));
    }
    return std::abs(u.dot(d)) > ra + rb + slack;
  };
  for (int k = 0; k < 3; ++k)
    if (split_by(a.axes[k]) || split_by(b.axes[k])) return true;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (split_by(a.axes[i].cross(b.axes[j]))) return true;
  return false;
}

namespace {

// A double box holding A ∩ B: the intersection of the boxes' bounds, each grown by 1e-12 of
// its coordinates' magnitude, far beyond the rounding of c +- h_0 a_0 +- h_1 a_1 +- h_2 a_2.
Aabb reach_of(const Obb& a, const Obb& b) {
  Aabb out;
  for (int i = 0; i < 3; ++i) {
    double lo = -INFINITY, hi = INFINITY;
    for (const Obb* box : {&a, &b}) {
      double r = 0, mag = std::abs(box->center[i]);
      for (int k = 0; k < 3; ++k) r += box->half[k] * std::abs(box->axes[k][i]);
      mag += r;
      const double pad = 1e-12 * mag + 1e-300;
      lo = std::max(lo, box->center[i] - r - pad);
      hi = std::min(hi, box->center[i] + r + pad);
    }
    out.lo[i] = lo;
    out.hi[i] = hi;
  }
  return out;
}

}  // namespace

Rational PolyOverlapSolver::exact(const Obb& a, const Obb& b) const {
  return cell_clip::outside_volume(mesh_, faces_, cell_clip::box_pair_cell<Rational>(a, b), reach_of(a, b));
}

PolyOverlap PolyOverlapSolver::evaluate(const Obb& a, const Obb& b) const {
  PolyOverlap r;
  if (apart(a, b)) return r;  // [0, 0]: nothing shared
  try {
    CGAL::Protect_FPU_rounding<true> upward;
    const Interval v = cell_clip::outside_volume(mesh_, faces_, cell_clip::box_pair_cell<Interval>(a, b), reach_of(a, b));
    if (CGAL::is_finite(v)) {
      r.lo = std::max(v.inf(), 0.0);  // an outer volume is >= 0
      r.hi = v.sup();
      r.estimate = r.lo + 0.5 * (r.hi - r.lo);  // rounded upward, still within [lo, hi]
      return r;
    }
  } catch (const CGAL::Uncertain_conversion_exception&) {
  }
  const Rational q = exact(a, b);
  enclose(q, &r.lo, &r.hi);
  r.estimate = to_double_nearest(q);
  r.exact = true;
  return r;
}

double PolyOverlapSolver::estimate(const Obb& a, const Obb& b) const {
  if (apart(a, b)) return 0;
  try {
    CGAL::Protect_FPU_rounding<true> nearest(CGAL_FE_TONEAREST);
    const double v = cell_clip::outside_volume(mesh_, faces_, cell_clip::box_pair_cell<double>(a, b), reach_of(a, b));
    if (std::isfinite(v)) return std::max(v, 0.0);
  } catch (const cell_clip::InconsistentSides&) {  // rounded signs contradicted each other
  }
  return evaluate(a, b).estimate;
}

std::vector<double> PolyOverlapSolver::estimate(const std::vector<std::pair<Obb, Obb>>& pairs) const {
  std::vector<double> out(pairs.size());
  tbb::parallel_for(size_t{0}, pairs.size(), [&](size_t i) { out[i] = estimate(pairs[i].first, pairs[i].second); });
  return out;
}

}  // namespace vobb
