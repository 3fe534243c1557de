#include "fast/cpu_estimator.h"

#include <tbb/parallel_for.h>

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
  tbb::parallel_for(size_t{0}, boxes.size(), [&](size_t i) { out[i] = estimate_one(boxes[i], m, &used[i]); });
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

double sum_texel_hits(const BoxPlan& plan, int m) {
  double sum = 0;
  for (const TexelSpan& span : plan.spans) {
    const LocalTriangle& t = plan.tris[span.tri];
    // d = (s, u, v) on the face's axes (k, a, b): each dot is (s E_k + u E_a) + v E_b, the
    // first part once per row. That is a 3-term dot product in one fixed order, which is
    // what texel_hit_dots needs; the hits are those of texel_hit.
    const int k = span.face / 2, a = (k + 1) % 3, b = (k + 2) % 3;
    const double s = span.face % 2 == 0 ? 1.0 : -1.0;
    Texel x{span.face, 0, 0, m, Vec3::Zero()};
    for (int i = span.i0; i <= span.i1; ++i) {
      const double u = texel_center(i, m);
      double row[4];
      for (int c = 0; c < 3; ++c) row[c] = s * t.edge_cross[c][k] + u * t.edge_cross[c][a];
      row[3] = s * t.normal[k] + u * t.normal[a];
      x.i = i;
      for (int j = span.j0; j <= span.j1; ++j) {
        const double v = texel_center(j, m);
        const double e[3] = {row[0] + v * t.edge_cross[0][b], row[1] + v * t.edge_cross[1][b],
                             row[2] + v * t.edge_cross[2][b]};
        const double nd = row[3] + v * t.normal[b];
        x.j = j;
        double value;
        if (texel_hit_dots(t, x, e, nd, plan.far_count, &value)) sum += value;
      }
    }
  }
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
  if (plan.tris.capacity() * sizeof(LocalTriangle) + plan.spans.capacity() * sizeof(TexelSpan) > kPlanKeepBytes)
    plan = BoxPlan{};
  return value;
}

double evaluate_plan(const BoxPlan& plan, int m) {
  if (plan.flat) return 0.0;
  const double texel_weight = 4.0 / (3.0 * m * m);
  return plan.frame.volume_scale * (plan.constant + texel_weight * sum_texel_hits(plan, m));
}

}  // namespace vobb
