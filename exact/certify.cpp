#include "exact/certify.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <atomic>
#include <exception>
#include <chrono>
#include <cstdio>
#include <memory>
#include <mutex>
#include <numeric>

#include "exact/outer_volume.h"
#include "common/stopwatch.h"

// Threads share no CGAL object: each builds its own NefSolver (nef_solver.cpp checks that CGAL
// is built thread-aware). ClipSolver's const members read shared rationals and write nothing.

namespace vobb::exact {

bool Certificate::ok() const {
  if (!containment.ok()) return false;
  for (const LayerCertificate& l : layers)
    if (!l.upper_bound_holds() || !l.paths_agree) return false;
  return true;
}

Certificate certify(const Mesh& mesh, const Tree& tree, const CertifyOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  Certificate cert;
  std::mutex say_mutex;  // progress lines come from any thread, one at a time
  auto say = [&](const std::string& line) {
    if (!options.progress) return;
    std::lock_guard<std::mutex> lock(say_mutex);
    options.progress(line);
  };
  cert.containment = check_conservative(mesh, tree);
  say("containment: " + std::to_string(cert.containment.violations) + " violations in " +
      std::to_string(cert.containment.checked_pairs) + " (node, face) pairs");

  // OBV once per node (a leaf above level i belongs to every later layer too), by clipping,
  // one node per task: every node belongs to the layer of its own level.
  const ClipSolver clip(mesh);
  const auto tobv = std::chrono::steady_clock::now();
  std::vector<Rational> obv(tree.nodes.size());
  tbb::parallel_for(size_t{0}, tree.nodes.size(), [&](size_t id) { obv[id] = clip.obv(tree.nodes[id].box); });
  {
    char buf[96];
    std::snprintf(buf, sizeof buf, "OBV of %zu boxes in %.2f s", tree.nodes.size(), seconds_since(tobv));
    say(buf);
  }

  // One task per layer, the layers with most boxes (the costly unions) first, each taken by
  // the next free thread. A thread builds its own Nef(X) when a layer first needs it.
  const int levels = tree.depth + 1;
  cert.layers.resize(levels);
  std::vector<int> order(levels);
  std::vector<std::vector<int32_t>> ids(levels);
  for (int level = 0; level < levels; ++level) ids[level] = layer(tree, level);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return ids[a].size() > ids[b].size(); });
  std::atomic<int> next{0};
  auto certify_layers = [&]() {
    std::unique_ptr<NefSolver> nef;  // this thread's own
    double nef_build_seconds = 0;    // within the current layer, kept out of its time
    auto need_nef = [&]() -> const NefSolver& {
      if (!nef) {
        const auto tn = std::chrono::steady_clock::now();
        nef = std::make_unique<NefSolver>(mesh);
        nef_build_seconds = seconds_since(tn);
        char buf[96];
        std::snprintf(buf, sizeof buf, "Nef polyhedron of the mesh built in %.2f s (once per thread)",
                      nef_build_seconds);
        say(buf);
      }
      return *nef;
    };
    auto certify_layer = [&](int level) {
      const auto tl = std::chrono::steady_clock::now();
      nef_build_seconds = 0;
      LayerCertificate& lc = cert.layers[level];
      lc.level = level;
      lc.boxes = ids[level].size();
      std::vector<Obb> boxes;
      std::vector<Rational> obvs;
      for (int32_t id : ids[level]) {
        boxes.push_back(tree.nodes[id].box);
        obvs.push_back(obv[id]);
      }
      lc.sum_obv = sum_pairwise(obvs);
      // Which boxes may meet another one (conservative bounds): boxes that overlap nothing
      // skip the union work.
      std::vector<char> overlapped = clip.may_overlap(boxes);
      for (char o : overlapped) lc.overlapping_boxes += o ? 1 : 0;
      OmvPath path = options.path;
      // Auto: Nef for layers with overlaps. Measured on dino (docs/BENCHMARKS.md), Nef's union
      // beats the clipping path's overlap cells on every overlapping layer of baseline trees.
      if (path == OmvPath::kAuto) path = OmvPath::kNef;
      if (lc.overlapping_boxes == 0 && path != OmvPath::kBoth) {
        lc.omv = lc.sum_obv;  // disjoint boxes: the union's outer volume is the sum
        lc.omv_path = "none";
      } else if (path == OmvPath::kNef) {
        lc.omv = need_nef().omv(boxes);
        lc.omv_path = "nef";
      } else if (path == OmvPath::kClip) {
        lc.omv = clip.omv(boxes, lc.sum_obv);
        lc.omv_path = "clip";
      } else {  // both: Nef is the arbiter, and a disagreement fails the certificate
        lc.omv_clip = clip.omv(boxes, lc.sum_obv);
        lc.omv = need_nef().omv(boxes);
        lc.paths_agree = lc.omv == lc.omv_clip;
        lc.omv_path = "both";
      }
      lc.seconds = seconds_since(tl) - nef_build_seconds;
      const std::string disagree =
          lc.paths_agree ? "" : ", PATHS DISAGREE (Nef's OMV above; clipping's " + format_nearest(lc.omv_clip) + ")";
      char buf[300];
      std::snprintf(buf, sizeof buf, "layer %d/%d: %zu boxes (%zu overlapping), OMV %s, sum OBV %s%s, %.2f s",
                    level, tree.depth, lc.boxes, lc.overlapping_boxes, format_nearest(lc.omv).c_str(),
                    format_nearest(lc.sum_obv).c_str(), disagree.c_str(), lc.seconds);
      say(buf);
    };
    try {
      for (int k; (k = next.fetch_add(1)) < levels;) certify_layer(order[k]);
    } catch (...) {
      next = levels;  // a failure: the other threads take no further layer
      throw;          // task_group passes it on to the caller
    }
  };
  const int workers = std::min(levels, tbb::this_task_arena::max_concurrency());
  tbb::task_group group;
  for (int w = 1; w < workers; ++w) group.run(certify_layers);
  // This thread takes layers too. Its failure is held until the workers have stopped: the
  // group must be waited for before it is destroyed, and its wait rethrows a worker's failure,
  // which during the unwinding of this thread's own would end the process.
  std::exception_ptr failed;
  try {
    certify_layers();
  } catch (...) {
    failed = std::current_exception();
  }
  group.wait();  // a worker's failure, if any, goes on from here
  if (failed) std::rethrow_exception(failed);

  std::vector<Rational> weighted;
  for (const LayerCertificate& lc : cert.layers) weighted.push_back(Rational(tree.depth - lc.level + 1) * lc.omv);
  cert.weighted_error = sum_pairwise(weighted);
  cert.seconds = seconds_since(t0);
  return cert;
}

}  // namespace vobb::exact
