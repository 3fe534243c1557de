#include "fast/cpu_estimator.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "common/status.h"
#include "fast/cubemap.h"

namespace vobb {

CpuObvEstimator::CpuObvEstimator(const Mesh& mesh) : planner_(mesh) {}

std::vector<double> CpuObvEstimator::estimate(const std::vector<Obb>& boxes, int m) const {
  VOBB_ASSERT(m >= 1, "cubemap resolution m >= 1");
  // Each box's value depends on that box alone and is computed by one thread, in the same
  // order of operations as alone: the same doubles for any number of threads.
  std::vector<double> out(boxes.size());
  std::vector<size_t> used(boxes.size());
  tbb::parallel_for(size_t{0}, boxes.size(),
                    [&](size_t i) { out[i] = estimate_one(boxes[i], m, &used[i]); });
  size_t total = 0;
  for (size_t u : used) total += u;
  faces_used_ = total;
  return out;
}

double CpuObvEstimator::estimate(const Obb& box, int m) const {
  VOBB_ASSERT(m >= 1, "cubemap resolution m >= 1");
  size_t used = 0;
  const double value = estimate_one(box, m, &used);
  faces_used_ = used;
  return value;
}

// Which texels of one span row may hit the face: for each side sigma = +1, -1 of the edges,
// the run of columns where sigma f_k >= -tie_k for all three edges k, f_k the row's computed
// dot with edge k (cpu_estimator.h).
// Why every hit lies in one of the two runs: texel_hit_dots, whose edge tests are exact
// (exact_edge_side), counts a hit only where all three edges give one side sigma; the exact
// dot E_k then has sigma E_k >= 0 (= 0 where a tie rule gives the side), and edge_tie bounds
// |f_k - E_k| for any evaluation of the dot as a 3-term dot product, so sigma f_k >= -tie_k.
// Why the runs are found by testing a few columns: f_k(j) = row_k + v_j eb_k is monotone in j
// (v_j = texel_center(j, m) is, and rounding is monotone), so {sigma f_k >= -tie_k} is a run
// at one end of the row (or all of it, or none). Its inner end starts from a guess (solving
// the condition in real arithmetic, with a reciprocal: it rounds) and moves until the
// condition fails just outside it; so the guess decides only how many columns are tested,
// never whether a hit is missed. The runs are intersected over k. Each search stays within the
// row: a wrong guess costs tests (a few per column at worst), never a hit.
void candidate_runs(const double* row, const double* eb, const double* inv_eb, const double* tie,
                    int j0, int j1, int m, TexelRun* runs, int guess_shift) {
  for (int side = 0; side < 2; ++side) {
    const double sigma = side == 0 ? 1.0 : -1.0;
    TexelRun& r = runs[side];
    r = {j0, j1};
    for (int k = 0; k < 3 && r.lo <= r.hi; ++k) {
      auto holds = [&](int j) { return sigma * (row[k] + texel_center(j, m) * eb[k]) >= -tie[k]; };
      if (eb[k] == 0) {  // the same for every column
        if (!holds(j0)) r.hi = r.lo - 1;
        continue;
      }
      // The column where f_k = -sigma tie_k, in real arithmetic: v = -1 + (2 j + 1) / m.
      const double v = (-sigma * tie[k] - row[k]) * inv_eb[k];
      double guess = ((v + 1) * m - 1) / 2 + guess_shift;
      if (!(guess == guess)) guess = sigma * eb[k] > 0 ? j0 : j1;  // NaN: no guess, the whole row
      const int g = static_cast<int>(std::clamp(std::floor(guess), j0 - 1.0, j1 + 1.0));
      if (sigma * eb[k] > 0) {  // sigma f_k rises with j: the run is [a, j1]
        int a = std::clamp(g, j0, j1 + 1);
        while (a <= j1 && !holds(a)) ++a;
        while (a > j0 && holds(a - 1)) --a;
        r.lo = std::max(r.lo, a);
      } else {  // the run is [j0, b]
        int b = std::clamp(g, j0 - 1, j1);
        while (b >= j0 && !holds(b)) --b;
        while (b < j1 && holds(b + 1)) ++b;
        r.hi = std::min(r.hi, b);
      }
    }
  }
}

double sum_texel_hits(const BoxPlan& plan, int m, int skip_from_width, size_t* texels_tested) {
  double sum = 0;
  size_t tested = 0;
  for (const TexelSpan& span : plan.spans) {
    const LocalTriangle& t = plan.tris[span.tri];
    // d = (s, u, v) on the face's axes (k, a, b): each dot is (s E_k + u E_a) + v E_b, the
    // first part once per row. That is a 3-term dot product in one fixed order, which is
    // what texel_hit_dots needs; the hits are those of texel_hit.
    const int k = span.face / 2, a = (k + 1) % 3, b = (k + 2) % 3;
    const double s = span.face % 2 == 0 ? 1.0 : -1.0;
    const double eb[3] = {t.edge_cross[0][b], t.edge_cross[1][b], t.edge_cross[2][b]};
    const bool skip = span.j1 - span.j0 + 1 >= skip_from_width;
    double inv_eb[3] = {0, 0, 0};
    if (skip)
      for (int c = 0; c < 3; ++c) inv_eb[c] = eb[c] != 0 ? 1 / eb[c] : 0;
    Texel x{span.face, 0, 0, m, Vec3::Zero()};
    for (int i = span.i0; i <= span.i1; ++i) {
      const double u = texel_center(i, m);
      double row[4];
      for (int c = 0; c < 3; ++c) row[c] = s * t.edge_cross[c][k] + u * t.edge_cross[c][a];
      row[3] = s * t.normal[k] + u * t.normal[a];
      x.i = i;
      auto visit = [&](int j) {
        const double v = texel_center(j, m);
        const double e[3] = {row[0] + v * eb[0], row[1] + v * eb[1], row[2] + v * eb[2]};
        const double nd = row[3] + v * t.normal[b];
        x.j = j;
        ++tested;
        double value;
        if (texel_hit_dots(t, x, e, nd, plan.far_count, &value)) sum += value;
      };
      if (!skip) {
        for (int j = span.j0; j <= span.j1; ++j) visit(j);
        continue;
      }
      // Only the columns of the two candidate runs, in column order as above (once each where
      // they overlap), so the sum adds the same hits in the same order.
      TexelRun runs[2];
      candidate_runs(row, eb, inv_eb, t.edge_tie, span.j0, span.j1, m, runs);
      if (runs[1].lo < runs[0].lo) std::swap(runs[0], runs[1]);
      int j = span.j0;
      for (const TexelRun& r : runs)
        for (j = std::max(j, r.lo); j <= r.hi; ++j) visit(j);
    }
  }
  if (texels_tested) *texels_tested = tested;
  return sum;
}

double CpuObvEstimator::estimate_one(const Obb& box, int m, size_t* faces_used) const {
  // One plan per thread, reused: its vectors keep their capacity from box to box. Planning
  // into fresh vectors spent a third of a build's time in growing them and in the page faults
  // of their first touch (perf, docs/BENCHMARKS.md). The values are the same: a plan does not
  // depend on what its vectors held before.
  thread_local BoxPlan plan;
  planner_.plan(box, m, &plan);
  *faces_used = plan.tris.size();
  const double value = evaluate_plan(plan, m);
  if (plan.tris.capacity() * sizeof(LocalTriangle) + plan.spans.capacity() * sizeof(TexelSpan) >
      kPlanKeepBytes)
    plan = BoxPlan{};
  return value;
}

double evaluate_plan(const BoxPlan& plan, int m) {
  if (plan.flat) return 0.0;
  const double texel_weight = 4.0 / (3.0 * m * m);
  return plan.frame.volume_scale * (plan.constant + texel_weight * sum_texel_hits(plan, m));
}

}  // namespace vobb
