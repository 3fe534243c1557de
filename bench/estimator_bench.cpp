// Per-OBV time of the cubemap estimator (issue 4): GL (whatever EGL gives: llvmpipe here, a GPU
// on the device machine) and the CPU twin, amortised over seeded corpora of leaf-sized and
// root-sized boxes (validate/box_corpus.h), with the culling and batching ablations.
// Every configuration runs in this one process, so the ratios compare like with like. Each GL
// value of the full batch is also checked against gl_deviation_bound; the run fails above it.
// Usage: vobb-bench-estimator MESH [--m M] [--leaves N] [--roots N] [--ablation-boxes N]
#include <tbb/task_arena.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "bench/bench_util.h"
#include "common/io/mesh_report.h"
#include "fast/cpu_estimator.h"
#include "fast/gl_estimator.h"
#include "validate/box_corpus.h"

namespace {

using vobb::bench::seconds;

double max_abs_diff(const std::vector<double>& a, const std::vector<double>& b) {
  double d = 0;
  for (size_t i = 0; i < a.size(); ++i)
    d = std::max(d, std::abs(a[i] - b[i]) / std::max(1e-300, std::abs(b[i])));
  return d;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(
        stderr,
        "usage: vobb-bench-estimator MESH [--m M] [--leaves N] [--roots N] [--ablation-boxes N]\n");
    return 2;
  }
  int m = 32, leaves = 1000, roots = 100, ablation = 100;
  for (int i = 2; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--m")) m = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--leaves")) leaves = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--roots")) roots = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--ablation-boxes")) ablation = std::atoi(argv[i + 1]);
  }
  vobb::LoadedMesh lm;
  if (!vobb::bench::load_or_say(argv[1], &lm)) return 2;
  std::unique_ptr<vobb::GlObvEstimator> gl;
  vobb::Status s = vobb::GlObvEstimator::create(lm.mesh, &gl);
  if (!s) {
    std::fprintf(stderr, "%s\n", s.message().c_str());
    return 2;
  }
  vobb::CpuObvEstimator cpu(lm.mesh);
  std::printf("mesh %s, %zu faces, m = %d, renderer: %s\n", argv[1], lm.mesh.faces.size(), m,
              gl->renderer().c_str());
  std::printf("%-6s %6s %-28s %12s %14s\n", "boxes", "count", "configuration", "ms per OBV",
              "max rel diff");
  bool bound_exceeded = false;
  using vobb::validate::BoxSize;
  for (BoxSize size : {BoxSize::kLeaf, BoxSize::kRoot}) {
    const int count = size == BoxSize::kLeaf ? leaves : roots;
    const auto boxes = vobb::validate::box_corpus(lm.mesh, size, count, 2026);
    const char* name = vobb::validate::to_string(size);
    gl->estimate(std::vector<vobb::Obb>(boxes.begin(), boxes.begin() + 1),
                 m);  // warm-up: shader JIT, atlas
    std::vector<double> ref, v;
    double t = seconds([&] { ref = cpu.estimate(boxes, m); });
    std::printf("%-6s %6d %-28s %12.4f %14s\n", name, count, "cpu twin, all threads",
                1e3 * t / count, "(reference)");
    // The same batch on one thread: the values must not change (each box is one thread's).
    t = seconds([&] { tbb::task_arena(1).execute([&] { v = cpu.estimate(boxes, m); }); });
    std::printf("%-6s %6d %-28s %12.4f %14.2e\n", name, count, "cpu twin, one thread",
                1e3 * t / count, max_abs_diff(v, ref));
    size_t trips = gl->round_trips();
    t = seconds([&] { v = gl->estimate(boxes, m); });
    std::printf("%-6s %6d %-28s %12.4f %14.2e   (%zu round trips)\n", name, count,
                "gl, batched, first call", 1e3 * t / count, max_abs_diff(v, ref),
                gl->round_trips() - trips);
    // Each GL value against the CPU twin's within the derived float bound (gl_estimator.h):
    // the worst |GL - CPU| / bound over the batch. Above 1 is a defect, and fails the run.
    double worst = 0;
    for (size_t i = 0; i < boxes.size(); ++i) {
      const double bound = vobb::gl_deviation_bound(gl->planner().plan(boxes[i], m), m);
      const double diff = std::abs(v[i] - ref[i]);
      if (!(diff <= bound)) bound_exceeded = true;  // a NaN on either side too
      const double ratio = diff == 0 ? 0.0 : bound > 0 ? diff / bound : HUGE_VAL;
      worst = std::isnan(ratio) ? HUGE_VAL : std::max(worst, ratio);
    }
    std::printf("%-6s %6d %-28s %12s %14.2e   (worst |gl - cpu| / gl_deviation_bound)\n", name,
                count, "gl against its bound", "-", worst);
    // The first call pays for first touches of the atlas's pages; the rest are steady state.
    // Ablations on the first `ablation` boxes, against the full configuration on the same boxes.
    const std::vector<vobb::Obb> few(boxes.begin(),
                                     boxes.begin() + std::min<size_t>(boxes.size(), ablation));
    const int n = static_cast<int>(few.size());
    std::vector<double> few_ref;
    t = seconds([&] { few_ref = gl->estimate(few, m); });
    std::printf("%-6s %6d %-28s %12.4f %14s\n", name, n, "gl, culled, batched (again)", 1e3 * t / n,
                "-");
    gl->set_batching(false);
    t = seconds([&] { v = gl->estimate(few, m); });
    std::printf("%-6s %6d %-28s %12.4f %14.2e\n", name, n, "gl, culled, one box per trip",
                1e3 * t / n, max_abs_diff(v, few_ref));
    gl->set_batching(true);
    gl->set_culling(false);
    t = seconds([&] { v = gl->estimate(few, m); });
    std::printf("%-6s %6d %-28s %12.4f %14.2e\n", name, n, "gl, all faces, batched", 1e3 * t / n,
                max_abs_diff(v, few_ref));
    gl->set_culling(true);
    cpu.set_culling(false);
    t = seconds([&] { v = cpu.estimate(few, m); });
    std::printf("%-6s %6d %-28s %12.4f %14.2e\n", name, n, "cpu twin, all faces", 1e3 * t / n,
                max_abs_diff(v, few_ref));
    cpu.set_culling(true);
    // Where the time goes: the CPU-side plan alone (shared by both backends), on one thread
    // (GL plans a batch on every core, the CPU twin each box on one).
    t = seconds([&] {
      for (const auto& b : few) (void)gl->planner().plan(b, m);
    });
    std::printf("%-6s %6d %-28s %12.4f %14s\n", name, n, "plan only, one thread", 1e3 * t / n, "-");
  }
  if (bound_exceeded) {
    std::fprintf(
        stderr,
        "vobb-bench-estimator: a GL value is outside gl_deviation_bound of the CPU twin's\n");
    return 1;
  }
  return 0;
}
