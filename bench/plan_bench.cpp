// The texel plan's a-priori resolution bound on thin boxes (fast/texel_plan.h), and the time
// to plan a box: seeded corpora of leaf, mid and root-sized boxes (validate/box_corpus.h),
// each also flattened along its third axis to aspects 1e-4 and 1e-8. Per corpus: how many
// boxes have a face taken as passing near the centre (centre_near_surface, which doubles the
// bound), the median of resolution_bound / box volume at m, and microseconds per plan() and
// per CPU twin estimate (plan and texel sums, one thread). Then the texel sums alone, over the
// same plans: testing every texel of a span, against testing only the columns where the
// face's three edge dots may all lie on one side (sum_texel_hits' default), with the share of
// texels that tests; the sums must be the same doubles, or the run fails.
// Usage: vobb-bench-plan MESH [--m M] [--boxes N] [--repeat R] [--skip-from W]
//   W: the row width from which the skipping runs (default kSkipFromWidth), to compare widths
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <vector>

#include "common/io/mesh_report.h"
#include "fast/cpu_estimator.h"
#include "fast/texel_plan.h"
#include "validate/box_corpus.h"

int main(int argc, char** argv) {
  using namespace vobb;
  if (argc < 2) {
    std::fprintf(stderr,
                 "usage: vobb-bench-plan MESH [--m M] [--boxes N] [--repeat R] [--skip-from W]\n");
    return 2;
  }
  int m = 32, count = 200, repeat = 3, skip_from = kSkipFromWidth;
  for (int i = 2; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--m"))
      m = std::atoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--boxes"))
      count = std::atoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--repeat"))
      repeat = std::atoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--skip-from"))
      skip_from = std::atoi(argv[i + 1]);
    else {
      std::fprintf(stderr, "vobb-bench-plan: unknown option %s\n", argv[i]);
      return 2;
    }
  }
  if (m < 1 || count < 1 || repeat < 1 || skip_from < 1) {
    std::fprintf(stderr,
                 "vobb-bench-plan: --m, --boxes, --repeat and --skip-from must be at least 1\n");
    return 2;
  }
  LoadedMesh lm;
  const Status s = load_solid(argv[1], &lm);
  if (!s) {
    std::fprintf(stderr, "vobb-bench-plan: %s\n", s.message().c_str());
    return 2;
  }
  const BoxPlanner planner(lm.mesh);
  const CpuObvEstimator cpu(lm.mesh);
  std::printf("%-5s %-7s %6s %8s %14s %10s %10s %12s %12s %9s\n", "size", "aspect", "boxes",
              "flagged", "median bnd/vol", "us/plan", "us/CPU est", "us/sums all", "us/sums skip",
              "tested");
  bool differ = false;
  for (auto size : {validate::BoxSize::kLeaf, validate::BoxSize::kMid, validate::BoxSize::kRoot}) {
    const std::vector<Obb> corpus = validate::box_corpus(lm.mesh, size, count, 11);
    for (double aspect : {1.0, 1e-4, 1e-8}) {
      std::vector<Obb> boxes = corpus;
      for (Obb& b : boxes) b.half[2] *= aspect;
      std::vector<double> ratio;
      int flagged = 0;
      for (const Obb& b : boxes) {
        const BoxPlan p = planner.plan(b, m);
        if (p.flat) continue;
        flagged += p.centre_near_surface;
        ratio.push_back(resolution_bound(p, m) / volume(b));
      }
      std::sort(ratio.begin(), ratio.end());
      // Best of `repeat` passes over the corpus (plans are deterministic; the best pass is
      // the least disturbed by other work on the machine).
      double best = HUGE_VAL, best_cpu = HUGE_VAL, sum = 0;
      size_t sink = 0;
      for (int r = 0; r < repeat; ++r) {
        auto t0 = std::chrono::steady_clock::now();
        for (const Obb& b : boxes) sink += planner.plan(b, m).spans.size();
        best = std::min(
            best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
        t0 = std::chrono::steady_clock::now();
        for (const Obb& b : boxes) sum += cpu.estimate(b, m);
        best_cpu = std::min(
            best_cpu, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      }
      // The texel sums alone, each way, alternated, best of `repeat`.
      std::vector<BoxPlan> plans;
      for (const Obb& b : boxes) plans.push_back(planner.plan(b, m));
      double best_all = HUGE_VAL, best_skip = HUGE_VAL;
      size_t tested_all = 0, tested_skip = 0;
      std::vector<double> first;  // each way's sums, plan by plan: the same doubles
      for (int r = 0; r < repeat; ++r) {
        for (int way = 0; way < 2; ++way) {
          const int width = way == 0 ? std::numeric_limits<int>::max() : skip_from;
          size_t tested = 0;
          std::vector<double> sums;
          const auto t0 = std::chrono::steady_clock::now();
          for (const BoxPlan& p : plans) {
            size_t n = 0;
            sums.push_back(sum_texel_hits(p, m, width, &n));
            tested += n;
          }
          const double t =
              std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
          (way == 0 ? best_all : best_skip) = std::min(way == 0 ? best_all : best_skip, t);
          (way == 0 ? tested_all : tested_skip) = tested;
          if (way == 0)
            first = sums;
          else if (sums != first)
            differ = true;
        }
      }
      std::printf("%-5s %-7g %6zu %7.0f%% %14.3f %10.1f %10.1f %12.1f %12.1f %8.0f%%%s\n",
                  validate::to_string(size), aspect, ratio.size(),
                  100.0 * flagged / std::max<size_t>(1, ratio.size()),
                  ratio.empty() ? 0.0 : ratio[ratio.size() / 2], 1e6 * best / boxes.size(),
                  1e6 * best_cpu / boxes.size(), 1e6 * best_all / boxes.size(),
                  1e6 * best_skip / boxes.size(),
                  100.0 * tested_skip / std::max<size_t>(1, tested_all),
                  sink == 0 || !(sum > 0) ? " (no spans)" : "");
    }
  }
  if (differ) {
    std::fprintf(stderr, "vobb-bench-plan: skipping rejected texels changed a sum\n");
    return 1;
  }
  return 0;
}
