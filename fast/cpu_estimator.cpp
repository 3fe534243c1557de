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
  faces_used_ = 0;
  for (size_t u : used) faces_used_ += u;
  return out;
}

double CpuObvEstimator::estimate(const Obb& box, int m) const {
  VOBB_ASSERT(m >= 1, "cubemap resolution m >= 1");
  return estimate_one(box, m, &faces_used_);
}

double sum_texel_hits(const BoxPlan& plan, int m) {
  double sum = 0;
  for (const TexelSpan& span : plan.spans) {
    const LocalTriangle& t = plan.tris[span.tri];
    for (int i = span.i0; i <= span.i1; ++i) {
      const double u = texel_center(i, m);
      for (int j = span.j0; j <= span.j1; ++j) {
        double value;
        const Texel x{span.face, i, j, m, cubemap_direction(span.face, u, texel_center(j, m))};
        if (texel_hit(t, x, plan.far_count, &value)) sum += value;
      }
    }
  }
  return sum;
}

double CpuObvEstimator::estimate_one(const Obb& box, int m, size_t* faces_used) const {
  const BoxPlan plan = planner_.plan(box, m);
  *faces_used = plan.tris.size();
  if (plan.flat) return 0.0;
  const double texel_weight = 4.0 / (3.0 * m * m);
  return plan.frame.volume_scale * (plan.constant + texel_weight * sum_texel_hits(plan, m));
}

}  // namespace vobb
