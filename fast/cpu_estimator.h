// The CPU twin of the cubemap OBV estimator (cubemap.h): the same texel directions, ray-cast in
// double. It is the reference for the GL estimator and a backend of its own (--backend cpu).
//
// The per-box plan (texel_plan.h) is shared with the GL estimator: only faces that can meet the
// box are cast against (AABB tree, then the face's box-normalized bounds), each only on the
// texels of its projection within the box. 1_X(centre) comes from an exact point
// classification; a centre exactly on the surface switches to the far-count mode.
#pragma once

#include <atomic>
#include <cstddef>
#include <vector>

#include "common/mesh.h"
#include "common/obb.h"
#include "fast/texel_plan.h"

namespace vobb {

class CpuObvEstimator {
 public:
  explicit CpuObvEstimator(const Mesh& mesh);  // keeps a reference
  // OBV estimate of each box at resolution m >= 1, in world volume units. The boxes of a batch
  // are estimated in parallel (TBB; as many threads as the caller's arena allows), each by one
  // thread exactly as alone, so the values do not depend on the number of threads.
  // May be called on one estimator from several threads at once (each thread plans into its
  // own scratch). Not to be called under a changed floating-point environment (a CGAL rounding
  // scope): TBB's workers keep the one captured when their arena started, so only the default
  // gives the single-box values.
  std::vector<double> estimate(const std::vector<Obb>& boxes, int m) const;
  double estimate(const Obb& box, int m) const;
  // For the culling ablation benchmark: cast against every face.
  void set_culling(bool on) { planner_.set_culling(on); }
  // Faces cast against in the last estimate() call to finish (the culling statistic).
  size_t faces_used() const { return faces_used_; }

 private:
  double estimate_one(const Obb& box, int m, size_t* faces_used) const;

  BoxPlanner planner_;
  mutable std::atomic<size_t> faces_used_{0};
};

// Span rows at least this many texels wide test only the columns where the face's edges
// may all be on one side (cpu_estimator.cpp); narrower rows test every texel, which costs
// less than finding those columns.
inline constexpr int kSkipFromWidth = 16;

// The sum over a plan's (texel, face) hits of their values (texel_plan.h), in double. Texels
// are visited span by span, row by row, in column order; a row at least `skip_from_width`
// wide skips, untested, the texels whose computed edge dots prove a miss (cpu_estimator.cpp
// says why that is sound), so the hits, their values and the order they are added in, and so
// the sum, are the same bits for any `skip_from_width`.
// `texels_tested`, when given, gets the number of texels tested (for the tests).
double sum_texel_hits(const BoxPlan& plan, int m, int skip_from_width = kSkipFromWidth,
                      size_t* texels_tested = nullptr);

// Which columns of one span row may hit the face (cpu_estimator.cpp says why), for
// sum_texel_hits and its tests: for each side sigma = +1 (runs[0]) and -1 (runs[1]), a run
// [lo, hi] of [j0, j1] (empty: lo > hi) holding every column j where
// sigma (row[k] + texel_center(j, m) eb[k]) >= -tie[k] for k = 0, 1, 2. inv_eb[k] is 1 / eb[k]
// (0 where eb[k] is 0); it only feeds the starting guess, as does `guess_shift` (columns added
// to every guess, for the tests: a wrong guess costs tests, not hits).
struct TexelRun {
  int lo, hi;
};
void candidate_runs(const double* row, const double* eb, const double* inv_eb, const double* tie,
                    int j0, int j1, int m, TexelRun* runs, int guess_shift = 0);

// The CPU twin's estimate from a plan: 0 for a flat plan, else
// scale * (constant + 4 / (3 m^2) * sum_texel_hits). The GL estimator evaluates the plans that
// float cannot hold with it, so that theirs are the twin's values bit for bit.
double evaluate_plan(const BoxPlan& plan, int m);

// A plan kept for reuse (one per thread here, one per window slot in the GL estimator) is
// dropped once its vectors hold more than this, so that plans over a very large mesh are not
// kept for the process's lifetime.
inline constexpr size_t kPlanKeepBytes = size_t{64} << 20;

}  // namespace vobb
