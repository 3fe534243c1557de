// Per-box time of the polyhedral OBV solver (fast/poly_solver.h) against the cubemap at m (the
// CPU twin and GL, whatever EGL gives), on seeded leaf, mid and root corpora
// (validate/box_corpus.h) and on the baseline tree's level-8 boxes as built, on one thread and
// on all; and the solver's error against the exact rational on the first --exact-boxes boxes of
// each corpus. Every configuration runs in this
// one process, so the ratios compare like with like.
// Usage: vobb-bench-poly MESH [--m M] [--boxes N] [--exact-boxes N] [--no-gl]
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "bench/bench_util.h"
#include "builder/obbtree_builder.h"
#include "common/io/mesh_report.h"
#include "fast/cpu_estimator.h"
#include "fast/gl_estimator.h"
#include "fast/poly_solver.h"
#include "validate/box_corpus.h"

namespace {

using vobb::bench::seconds;

double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr,
                 "usage: vobb-bench-poly MESH [--m M] [--boxes N] [--exact-boxes N] [--no-gl]\n");
    return 2;
  }
  int m = 32, count = 200, exact_count = 20;
  bool want_gl = true;
  for (int i = 2; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--no-gl"))
      want_gl = false;
    else if (i + 1 < argc && !std::strcmp(argv[i], "--m"))
      m = std::atoi(argv[++i]);
    else if (i + 1 < argc && !std::strcmp(argv[i], "--boxes"))
      count = std::atoi(argv[++i]);
    else if (i + 1 < argc && !std::strcmp(argv[i], "--exact-boxes"))
      exact_count = std::atoi(argv[++i]);
  }
  vobb::LoadedMesh lm;
  if (!vobb::bench::load_or_say(argv[1], &lm)) return 2;
  std::unique_ptr<vobb::GlObvEstimator> gl;
  vobb::Status s;
  if (want_gl && !(s = vobb::GlObvEstimator::create(lm.mesh, &gl)))
    std::fprintf(stderr, "no GL: %s\n", s.message().c_str());
  const vobb::PolyObvSolver poly(lm.mesh);
  const vobb::CpuObvEstimator cpu(lm.mesh);
  std::printf("mesh %s, %zu faces, m = %d, renderer: %s\n", argv[1], lm.mesh.faces.size(), m,
              gl ? gl->renderer().c_str() : "(none)");
  std::printf("%-5s %5s %-34s %12s %12s\n", "boxes", "count", "configuration", "ms per box",
              "median rel");
  tbb::task_arena one(1);
  using vobb::validate::BoxSize;
  // The seeded corpora, then the level-8 boxes of the baseline tree as they are (tight boxes:
  // a mesh vertex lies within round-off of each of their faces).
  const vobb::Tree tree = vobb::build_obbtree(lm.mesh, vobb::ObbTreeOptions{});
  std::vector<vobb::Obb> tree8;
  for (const vobb::TreeNode& node : tree.nodes)
    if (node.level == tree.depth && static_cast<int>(tree8.size()) < count)
      tree8.push_back(node.box);
  for (int corpus = 0; corpus < 4; ++corpus) {
    const BoxSize size = corpus == 1   ? BoxSize::kMid
                         : corpus == 2 ? BoxSize::kRoot
                                       : BoxSize::kLeaf;
    const auto boxes = corpus == 3 ? tree8 : vobb::validate::box_corpus(lm.mesh, size, count, 2026);
    const char* name = corpus == 3 ? "tree8" : vobb::validate::to_string(size);
    const int n = static_cast<int>(boxes.size());
    auto row = [&](const char* what, double t, double rel = NAN) {
      std::printf("%-5s %5d %-34s %12.4f %12.2e\n", name, n, what, 1e3 * t / n, rel);
    };
    std::vector<double> est, cub;
    std::vector<vobb::PolyObv> ev;
    // Errors against the exact rational (of the box's volume), on the first exact_count boxes.
    const int ne = std::min(n, exact_count);
    std::vector<double> truth(ne);
    for (int i = 0; i < ne; ++i) truth[i] = vobb::to_double_nearest(poly.exact(boxes[i]));
    auto rel = [&](const std::vector<double>& v) {
      std::vector<double> r;
      for (int i = 0; i < ne; ++i) r.push_back(std::abs(v[i] - truth[i]) / vobb::volume(boxes[i]));
      return median(r);
    };
    poly.estimate(boxes);  // warm-up: the first touches of the mesh and the tree
    double t = seconds([&] { one.execute([&] { est = poly.estimate(boxes); }); });
    row("poly, double, one thread", t, rel(est));
    t = seconds([&] { one.execute([&] { ev = poly.evaluate(boxes); }); });
    std::vector<double> mid, width, visited;
    int exact_boxes = 0;
    long exact_faces = 0, exact_signs = 0;
    for (const vobb::PolyObv& r : ev) {
      mid.push_back(r.estimate);
      visited.push_back(r.faces);
      width.push_back((r.hi - r.lo) / vobb::volume(boxes[&r - ev.data()]));
      exact_boxes += r.exact_box;
      exact_faces += r.exact_faces;
      exact_signs += r.exact_signs;
    }
    row("poly, interval, one thread", t, rel(mid));
    std::printf(
        "%-5s %5d %-34s %12s %12.2e   (median width / vol; median %g faces visited; %d exact "
        "boxes, %ld exact "
        "faces, %ld exact signs)\n",
        name, n, "poly, interval width", "-", median(width), median(visited), exact_boxes,
        exact_faces, exact_signs);
    t = seconds([&] { est = poly.estimate(boxes); });
    row("poly, double, all threads", t);
    t = seconds([&] { ev = poly.evaluate(boxes); });
    row("poly, interval, all threads", t);
    t = seconds([&] { one.execute([&] { cub = cpu.estimate(boxes, m); }); });
    row("cpu twin, one thread", t, rel(cub));
    t = seconds([&] { cub = cpu.estimate(boxes, m); });
    row("cpu twin, all threads", t);
    if (gl) {
      gl->estimate(std::vector<vobb::Obb>(boxes.begin(), boxes.begin() + 1), m);  // warm-up
      t = seconds([&] { cub = gl->estimate(boxes, m); });
      row("gl, batched", t, rel(cub));
    }
  }
  return 0;
}
