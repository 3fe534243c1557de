#include "exact/certify.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>

#include "common/atomic_file.h"
#include "common/json_parse.h"
#include "common/stopwatch.h"
#include "common/text_util.h"
#include "exact/outer_volume.h"

// Threads share no CGAL object: each builds its own NefSolver (nef_solver.cpp checks that CGAL
// is built thread-aware). ClipSolver's const members read shared rationals and write nothing.

namespace vobb::exact {

bool Certificate::ok() const {
  if (!containment.ok()) return false;
  for (const LayerCertificate& l : layers)
    if (!l.upper_bound_holds() || !l.paths_agree) return false;
  return true;
}

namespace {

// The path a layer takes: "none" for boxes that overlap nothing (OMV = sum of OBV) unless both
// paths are asked for.
std::string layer_path(OmvPath path, size_t overlapping_boxes) {
  if (path == OmvPath::kBoth) return "both";
  if (overlapping_boxes == 0) return "none";
  return path == OmvPath::kClip ? "clip" : path == OmvPath::kNef ? "nef" : "filtered";
}

// Two enclosures with the same ends, exactly.
bool same_enclosure(const MpInterval& a, const MpInterval& b) {
  return a.lo_rational() == b.lo_rational() && a.hi_rational() == b.hi_rational();
}

// Whether a layer's enclosure of its sum of OBV is the one certify gives it, `boxes_sum` being
// the sum of its boxes' enclosures in id order: that sum, or on a rational path (nef, clip) the
// enclosure of its exact sum of OBV, which that sum must then hold.
bool sum_obv_fits(const LayerCertificate& l, const MpInterval& boxes_sum) {
  if (l.omv_path == "nef" || l.omv_path == "clip")
    return l.rational && boxes_sum.contains(l.sum_obv) &&
           same_enclosure(l.sum_obv_enclosure, MpInterval(l.sum_obv));
  return same_enclosure(l.sum_obv_enclosure, boxes_sum);
}

MpInterval sum_of(const std::vector<MpInterval>& xs) {
  MpInterval s(0);
  for (const MpInterval& x : xs) s += x;  // in order: the same enclosure on every run
  return s;
}

// Progress lines, from any thread, passed to options.progress one at a time (none where it is
// empty).
class Say {
 public:
  explicit Say(const CertifyOptions& options) : options_(options) {}
  void operator()(const std::string& line) {
    if (!options_.progress) return;
    std::lock_guard<std::mutex> lock(mutex_);
    options_.progress(line);
  }

 private:
  const CertifyOptions& options_;
  std::mutex mutex_;
};

// What certify's stages share: the inputs, the solvers, the boxes' OBV, each layer's node ids,
// and the state the checkpoint callback is given.
struct CertifyRun {
  CertifyRun(const Mesh& mesh, const Tree& tree, const CertifyOptions& options, Say& say)
      : mesh(mesh),
        tree(tree),
        options(options),
        say(say),
        all_rational(options.rational || options.path == OmvPath::kClip ||
                     options.path == OmvPath::kNef),
        filtered(mesh),
        clip(filtered.rational()),
        obv(tree.nodes.size()) {}

  const Mesh& mesh;
  const Tree& tree;
  const CertifyOptions& options;
  Say& say;
  const bool all_rational;  // every value in rationals too: asked for, or a rational path
  const FilteredSolver filtered;
  const ClipSolver& clip;
  std::vector<Enclosed> obv;              // per node id
  std::vector<std::vector<int32_t>> ids;  // per level, the layer's node ids
  CertifyState done;                      // everything finished, for the checkpoint callback
  std::mutex done_mutex;                  // one checkpoint call at a time
};

// Gives the checkpoint callback (if any) everything finished so far, with `lc` (where not null)
// added to the finished layers; one call at a time.
void checkpoint_finished(CertifyRun& run, const LayerCertificate* lc) {
  if (!run.options.checkpoint) return;
  std::lock_guard<std::mutex> lock(run.done_mutex);
  if (lc) run.done.layers.push_back(*lc);
  run.options.checkpoint(run.done);
}

// A layer's boxes, in the order of its node ids.
std::vector<Obb> layer_boxes(const CertifyRun& run, int level) {
  std::vector<Obb> boxes;
  for (int32_t id : run.ids[level]) boxes.push_back(run.tree.nodes[id].box);
  return boxes;
}

// The enclosure of a layer's sum of OBV from its boxes' enclosures, summed in the order of its
// node ids `ids`: the one certify writes and a checkpoint's loader checks.
MpInterval layer_sum_obv(const std::vector<int32_t>& ids, const std::vector<Enclosed>& obv) {
  std::vector<MpInterval> xs;
  for (int32_t id : ids) xs.push_back(obv[id].value);
  return sum_of(xs);
}

MpInterval layer_sum_obv(const CertifyRun& run, int level) {
  return layer_sum_obv(run.ids[level], run.obv);
}

// The boxes that may meet another box of the layer, by bounds: box j with an earlier
// neighbour, and each such neighbour.
size_t overlap_count(const std::vector<std::vector<int32_t>>& earlier) {
  std::vector<char> o(earlier.size(), 0);
  for (size_t j = 0; j < earlier.size(); ++j)
    for (int32_t i : earlier[j]) o[j] = o[i] = 1;
  size_t n = 0;
  for (char c : o) n += c ? 1 : 0;
  return n;
}

// OBV once per node, into run.obv and (with a checkpoint callback) the checkpoint's state: from
// the resumed state, or enclosed by the filter (or exactly, where it sends the box to
// rationals; or by clipping in rationals on a rational path). Counts in cert.exact_obv the
// boxes in rationals.
void certify_obv(CertifyRun& run, Certificate& cert) {
  const CertifyOptions& options = run.options;
  const Tree& tree = run.tree;
  const CertifyState* resume = options.resume;
  const FilteredSolver& filtered = run.filtered;
  const ClipSolver& clip = run.clip;
  std::vector<Enclosed>& obv = run.obv;
  if (resume && !resume->obv.empty()) {
    obv = resume->obv;
    for (const Enclosed& e : obv) cert.exact_obv += e.exact ? 1 : 0;
    run.say("OBV of " + std::to_string(tree.nodes.size()) + " boxes: from the checkpoint");
  } else {
    const auto tobv = std::chrono::steady_clock::now();
    tbb::parallel_for(size_t{0}, tree.nodes.size(), [&](size_t id) {
      const Obb& box = tree.nodes[id].box;
      if (options.path == OmvPath::kClip || options.path == OmvPath::kNef) {
        obv[id].q = clip.obv(box);
        obv[id].value = MpInterval(obv[id].q);
        obv[id].exact = true;
        return;
      }
      obv[id] = filtered.obv(box);
      if (options.rational && !obv[id].exact) obv[id].q = clip.obv(box);
    });
    for (const Enclosed& e : obv) cert.exact_obv += e.exact ? 1 : 0;
    char buf[160];
    std::snprintf(buf, sizeof buf, "OBV of %zu boxes in %.2f s (%zu in rationals)",
                  tree.nodes.size(), seconds_since(tobv), cert.exact_obv);
    run.say(buf);
  }
  if (options.rational)  // every rational inside its enclosure, or the filter is broken
    for (size_t id = 0; id < obv.size(); ++id)
      VOBB_ASSERT(obv[id].value.contains(obv[id].q), "the OBV of a box lies outside its enclosure");
  if (options.checkpoint) run.done.obv = obv;
}

// Takes the resumed state's finished layers that are the ones this run gives (its boxes,
// overlap count, path and sum of OBV, and rationals where every value is asked in rationals)
// as they are, into cert and the checkpoint's state, and says how many. Returns, per level,
// whether it was taken.
std::vector<char> resume_layers(CertifyRun& run, Certificate& cert) {
  const CertifyOptions& options = run.options;
  const CertifyState* resume = options.resume;
  const std::vector<std::vector<int32_t>>& ids = run.ids;
  const int levels = run.tree.depth + 1;
  std::vector<char> resumed(levels, 0);
  size_t taken = 0, again = 0;
  if (resume)
    for (const LayerCertificate& lc : resume->layers) {
      VOBB_ASSERT(lc.level >= 0 && lc.level < levels && !resumed[lc.level],
                  "a resumed state fits the tree (CertifyCheckpoint::load checks it)");
      const size_t overlapping =
          overlap_count(run.clip.earlier_neighbours(layer_boxes(run, lc.level)));
      if (lc.boxes != ids[lc.level].size() || lc.overlapping_boxes != overlapping ||
          lc.omv_path != layer_path(options.path, overlapping) ||
          !sum_obv_fits(lc, layer_sum_obv(run, lc.level)) || (run.all_rational && !lc.rational)) {
        ++again;
        continue;
      }
      cert.layers[lc.level] = lc;
      resumed[lc.level] = 1;
      ++taken;
      if (options.checkpoint) run.done.layers.push_back(lc);
    }
  if (resume && !resume->layers.empty())
    run.say(
        std::to_string(taken) + " of " + std::to_string(levels) + " layers: from the checkpoint" +
        (again > 0
             ? "; " + std::to_string(again) + " saved layers do not match this run, certified again"
             : ""));
  return resumed;
}

// One thread's Nef polyhedron of the mesh, built the first time a layer needs it, and the
// seconds its building took within the current layer (kept out of the layer's time).
struct ThreadNef {
  std::unique_ptr<NefSolver> nef;
  double build_seconds = 0;
};

// The thread's Nef polyhedron of the mesh; built, and said, the first time.
const NefSolver& need_nef(CertifyRun& run, ThreadNef& thread_nef) {
  if (!thread_nef.nef) {
    const auto tn = std::chrono::steady_clock::now();
    thread_nef.nef = std::make_unique<NefSolver>(run.mesh);
    thread_nef.build_seconds = seconds_since(tn);
    char buf[96];
    std::snprintf(buf, sizeof buf, "Nef polyhedron of the mesh built in %.2f s (once per thread)",
                  thread_nef.build_seconds);
    run.say(buf);
  }
  return *thread_nef.nef;
}

// One layer's certification on one thread: the certificate being made, the layer's boxes with
// each box's earlier neighbours, and the filter's overlap terms, box by box.
struct LayerWork {
  CertifyRun& run;
  ThreadNef& nef;
  LayerCertificate& lc;
  const int level;
  const std::vector<Obb>& boxes;
  const std::vector<std::vector<int32_t>>& earlier;
  std::vector<Enclosed>& terms;
  const bool rational_path;  // a rational path (or both): reports its rationals rounded
};

// The layer's exact values, made once: on a rational path, when asked, or where the filter
// cannot decide.
void make_rational(LayerWork& w) {
  LayerCertificate& lc = w.lc;
  if (lc.rational) return;
  const CertifyOptions& options = w.run.options;
  const ClipSolver& clip = w.run.clip;
  const std::vector<Enclosed>& obv = w.run.obv;
  const std::vector<Obb>& boxes = w.boxes;
  const std::vector<std::vector<int32_t>>& earlier = w.earlier;
  const std::vector<Enclosed>& terms = w.terms;
  std::vector<Rational> qs;
  for (int32_t id : w.run.ids[w.level])
    qs.push_back(obv[id].exact || options.rational ? obv[id].q
                                                   : clip.obv(w.run.tree.nodes[id].box));
  lc.sum_obv = sum_pairwise(qs);
  if (lc.omv_path == "none") {
    lc.omv = lc.sum_obv;  // disjoint boxes: the union's outer volume is the sum
  } else if (lc.omv_path == "nef" || ((lc.omv_path == "filtered") && options.rational)) {
    lc.omv = need_nef(w.run, w.nef).omv(boxes);
  } else {  // the clipping path's overlap terms, box by box (filtered: where not yet exact)
    std::vector<Rational> over(boxes.size());
    tbb::parallel_for(size_t{0}, boxes.size(), [&](size_t j) {
      over[j] = terms[j].exact ? terms[j].q : clip.overlap_term(boxes, j, earlier[j]);
    });
    lc.omv = lc.sum_obv - sum_pairwise(over);
  }
  lc.rational = true;
}

// The filter's enclosures of the layer's overlap term (the sum of its terms) and of its OMV.
void sum_terms(LayerWork& w) {
  std::vector<MpInterval> xs;
  for (const Enclosed& t : w.terms) xs.push_back(t.value);
  w.lc.overlap_enclosure = sum_of(xs);
  w.lc.omv_enclosure = w.lc.sum_obv_enclosure - w.lc.overlap_enclosure;
}

// The filter's enclosures of the layer's overlap term and OMV, from its terms; where the sums
// cannot decide a rounding (and the path is not a rational one), the widest terms again in 256
// bits (slivers between nearly coplanar box faces widen a term far past 128 bits' round-off),
// a batch at a time, widest first, until they do or none is left (then rationals, later).
void sum_and_refine_terms(LayerWork& w) {
  const FilteredSolver& filtered = w.run.filtered;
  LayerCertificate& lc = w.lc;
  const std::vector<Obb>& boxes = w.boxes;
  const std::vector<std::vector<int32_t>>& earlier = w.earlier;
  std::vector<Enclosed>& terms = w.terms;
  sum_terms(w);
  auto decides = [&] {
    double d;
    return lc.omv_enclosure.nearest(&d) && lc.overlap_enclosure.nearest(&d);
  };
  std::vector<size_t> widest;
  for (size_t j = 0; j < terms.size(); ++j)
    if (!terms[j].exact && terms[j].bits < MpInterval::kMaxPrec) widest.push_back(j);
  std::stable_sort(widest.begin(), widest.end(), [&](size_t a, size_t b) {
    return terms[a].value.sup() - terms[a].value.inf() >
           terms[b].value.sup() - terms[b].value.inf();
  });
  for (size_t refined = 0; !w.rational_path && refined < widest.size() && !decides();) {
    const size_t end = std::min(widest.size(), refined + std::max<size_t>(16, widest.size() / 8));
    tbb::parallel_for(refined, end, [&](size_t k) {
      const size_t j = widest[k];
      terms[j] = filtered.overlap_term(boxes, j, earlier[j], MpInterval::kMaxPrec);
    });
    refined = end;
    sum_terms(w);
  }
}

// Sum OBV >= OMV: the overlap term's sign, by its enclosure while the layer has no rationals,
// else exactly. No overlapping boxes: 0, exactly.
void decide_upper_bound(LayerWork& w) {
  LayerCertificate& lc = w.lc;
  if (lc.omv_path == "none") {
    lc.upper_bound = true;
    lc.bound_by = "exact";
  } else if (lc.overlap_enclosure.inf() >= 0 && !lc.rational) {
    lc.upper_bound = true;
  } else if (lc.overlap_enclosure.sup() < 0 && !lc.rational) {
    lc.upper_bound = false;
  } else {
    make_rational(w);
    lc.upper_bound = lc.sum_obv >= lc.omv;
    lc.bound_by = "exact";
  }
}

// The nearest doubles: the path's rationals rounded on a rational path; otherwise the filter's
// where its enclosure lies in one rounding cell, and the rationals' where not. Returns whether
// a layer not on a rational path rounded a value exactly.
bool round_nearest(LayerWork& w) {
  LayerCertificate& lc = w.lc;
  const bool rational_path = w.rational_path;
  auto round = [&](const MpInterval& enclosure, const std::function<Rational()>& exact, double* out,
                   std::string* by) {
    if (!rational_path && enclosure.nearest(out)) {
      *by = "filter";
      return;
    }
    make_rational(w);
    *out = to_double_nearest(exact());
    *by = "exact";
  };
  round(
      lc.omv_enclosure, [&] { return lc.omv; }, &lc.omv_nearest, &lc.omv_rounded_by);
  round(
      lc.sum_obv_enclosure, [&] { return lc.sum_obv; }, &lc.sum_obv_nearest,
      &lc.sum_obv_rounded_by);
  round(
      lc.overlap_enclosure, [&] { return lc.overlap(); }, &lc.overlap_nearest,
      &lc.overlap_rounded_by);
  return !rational_path && (lc.omv_rounded_by == "exact" || lc.sum_obv_rounded_by == "exact" ||
                            lc.overlap_rounded_by == "exact");
}

// The progress line of a finished layer of a tree of depth `depth`.
std::string layer_line(const LayerCertificate& lc, int depth, bool rounded_exactly) {
  const std::string disagree =
      lc.paths_agree ? ""
      : lc.omv_path == "both"
          ? ", PATHS DISAGREE (Nef's OMV above; clipping's " + format_nearest(lc.omv_clip) + ")"
          : ", PATHS DISAGREE (the exact OMV above lies outside the filter's enclosure)";
  char buf[400];
  std::snprintf(buf, sizeof buf,
                "layer %d/%d: %zu boxes (%zu overlapping), OMV %.17g, sum OBV %.17g%s; in 256 "
                "bits: %zu OBV, %zu overlap terms; in rationals: %zu OBV, %zu overlap terms%s, "
                "%.2f s",
                lc.level, depth, lc.boxes, lc.overlapping_boxes, lc.omv_nearest, lc.sum_obv_nearest,
                disagree.c_str(), lc.refined_obv, lc.refined_overlap, lc.exact_obv,
                lc.exact_overlap, rounded_exactly ? ", rounding" : "", lc.seconds);
  return buf;
}

// One layer's certificate, into cert.layers[level], on this thread (with its Nef polyhedron,
// where one is needed); said, and given to the checkpoint callback.
void certify_layer(CertifyRun& run, ThreadNef& nef, Certificate& cert, int level) {
  const CertifyOptions& options = run.options;
  const FilteredSolver& filtered = run.filtered;
  const std::vector<Enclosed>& obv = run.obv;
  const auto tl = std::chrono::steady_clock::now();
  nef.build_seconds = 0;
  LayerCertificate& lc = cert.layers[level];
  lc.level = level;
  lc.boxes = run.ids[level].size();
  const std::vector<Obb> boxes = layer_boxes(run, level);
  const std::vector<std::vector<int32_t>> earlier = run.clip.earlier_neighbours(boxes);
  lc.overlapping_boxes = overlap_count(earlier);
  lc.omv_path = layer_path(options.path, lc.overlapping_boxes);
  lc.sum_obv_enclosure = layer_sum_obv(run, level);
  for (int32_t id : run.ids[level]) {
    lc.exact_obv += obv[id].exact ? 1 : 0;
    lc.refined_obv += !obv[id].exact && obv[id].bits > MpInterval::kPrec ? 1 : 0;
  }
  // The filter's overlap term, box by box, the boxes split across the threads.
  std::vector<Enclosed> terms(boxes.size());
  const bool filter_overlap = lc.omv_path == "filtered" || lc.omv_path == "both";
  // A rational path (and both, whose OMV is Nef's) reports its rationals rounded.
  const bool rational_path = run.all_rational || lc.omv_path == "both";
  if (filter_overlap)
    tbb::parallel_for(size_t{0}, boxes.size(),
                      [&](size_t j) { terms[j] = filtered.overlap_term(boxes, j, earlier[j]); });
  LayerWork w{run, nef, lc, level, boxes, earlier, terms, rational_path};
  if (filter_overlap) sum_and_refine_terms(w);
  for (const Enclosed& t : terms) {
    lc.exact_overlap += t.exact ? 1 : 0;
    lc.refined_overlap += !t.exact && t.bits > MpInterval::kPrec ? 1 : 0;
  }
  if (lc.omv_path == "none") {
    lc.overlap_enclosure = MpInterval(0);
    lc.omv_enclosure = lc.sum_obv_enclosure;
  }
  if (run.all_rational) make_rational(w);
  if (!filter_overlap && lc.omv_path != "none") {  // a rational path: its own rationals
    lc.omv_enclosure = MpInterval(lc.omv);
    lc.overlap_enclosure = MpInterval(lc.overlap());
    lc.sum_obv_enclosure = MpInterval(lc.sum_obv);
  }
  if (lc.omv_path == "both") {  // Nef is the arbiter; clipping's and the filter's must agree
    make_rational(w);
    lc.omv_clip = lc.omv;
    lc.omv = need_nef(run, nef).omv(boxes);
    lc.paths_agree = lc.omv == lc.omv_clip && lc.omv_enclosure.contains(lc.omv);
  }
  decide_upper_bound(w);
  const bool rounded_exactly = round_nearest(w);
  // Wherever rationals were made on a filtered layer (Nef's with --rational, the clipping
  // path's for a bound or a rounding), they are checked against the filter's enclosure: a
  // miss fails the certificate as a disagreement of paths would.
  if (lc.rational && lc.omv_path == "filtered" && !lc.omv_enclosure.contains(lc.omv))
    lc.paths_agree = false;
  lc.seconds = seconds_since(tl) - nef.build_seconds;
  run.say(layer_line(lc, run.tree.depth, rounded_exactly));
  checkpoint_finished(run, &lc);
}

// One thread's share of the layers: the next layer of `order` that no thread has taken yet
// (`next`), until none is left. A failure stops the other threads taking further layers, and
// goes on to the caller.
void take_layers(CertifyRun& run, Certificate& cert, const std::vector<int>& order,
                 std::atomic<int>& next) {
  const int todo = static_cast<int>(order.size());
  ThreadNef nef;  // this thread's own
  try {
    for (int k; (k = next.fetch_add(1)) < todo;) certify_layer(run, nef, cert, order[k]);
  } catch (...) {
    next = todo;  // a failure: the other threads take no further layer
    throw;        // task_group passes it on to the caller
  }
}

// The layers not `resumed`, the layers with most boxes first, on as many threads as the
// concurrency and the memory for Nef polyhedra allow (layer_workers). A thread's failure goes
// on to the caller once every thread has stopped.
void certify_layers(CertifyRun& run, Certificate& cert, const std::vector<char>& resumed) {
  const CertifyOptions& options = run.options;
  const Mesh& mesh = run.mesh;
  const std::vector<std::vector<int32_t>>& ids = run.ids;
  const int levels = run.tree.depth + 1;
  std::vector<int> order;
  for (int level = 0; level < levels; ++level)
    if (!resumed[level]) order.push_back(level);
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return ids[a].size() > ids[b].size(); });
  const int todo = static_cast<int>(order.size());
  std::atomic<int> next{0};
  auto work = [&]() { take_layers(run, cert, order, next); };
  const int concurrency = tbb::this_task_arena::max_concurrency();
  const bool uses_nef =
      options.path != OmvPath::kClip && (options.path != OmvPath::kAuto || options.rational);
  const double available =
      options.memory_bytes >= 0 ? options.memory_bytes : available_memory_bytes();
  const int workers = layer_workers(todo, concurrency, uses_nef, mesh.faces.size(), available);
  if (workers < std::min(todo, concurrency)) {
    char buf[200];
    std::snprintf(buf, sizeof buf,
                  "layers on %d threads, not %d: a Nef polyhedron of this mesh takes about "
                  "%.2f GB, and %.2f GB is available",
                  workers, std::min(todo, concurrency),
                  kNefBytesPerFace * static_cast<double>(mesh.faces.size()) / 1e9, available / 1e9);
    run.say(buf);
  }
  tbb::task_group group;
  for (int w = 1; w < workers; ++w) group.run(work);
  std::exception_ptr failed;
  try {
    work();
  } catch (...) {
    failed = std::current_exception();
  }
  group.wait();  // a worker's failure, if any, goes on from here
  if (failed) std::rethrow_exception(failed);
}

// e = sum ω(l) OMV(l) (layer_weight, common/tree.h): its enclosure, rounded by the filter or,
// failing that, exactly (where a layer lacks its rationals, from a certification in
// rationals).
void certify_weighted_error(CertifyRun& run, Certificate& cert) {
  const Mesh& mesh = run.mesh;
  const Tree& tree = run.tree;
  const CertifyOptions& options = run.options;
  std::vector<MpInterval> weighted;
  for (const LayerCertificate& lc : cert.layers)
    weighted.push_back(MpInterval(layer_weight(tree.depth, lc.level)) * lc.omv_enclosure);
  cert.weighted_error_enclosure = sum_of(weighted);
  cert.rational = true;
  for (const LayerCertificate& lc : cert.layers) cert.rational &= lc.rational;
  // On a rational path (and on both, whose OMV are Nef's) e is its rationals' rounded.
  const bool rational_path = run.all_rational || options.path == OmvPath::kBoth;
  const bool filtered_rounding =
      !rational_path && cert.weighted_error_enclosure.nearest(&cert.weighted_error_nearest);
  if (!filtered_rounding && !cert.rational) {
    // Rare (e within 1e-35 of a rounding tie): the layers' rationals, as a rational path has
    // them.
    CertifyOptions exact = options;
    exact.rational = true;
    exact.resume = nullptr;
    exact.checkpoint = nullptr;
    exact.progress = nullptr;
    run.say("e: its enclosure does not decide the rounding; every layer in rationals");
    const Certificate c = certify(mesh, tree, exact);
    for (size_t i = 0; i < cert.layers.size(); ++i) {
      LayerCertificate& lc = cert.layers[i];
      if (lc.rational) continue;
      lc.omv = c.layers[i].omv;
      lc.sum_obv = c.layers[i].sum_obv;
      lc.rational = true;
    }
    cert.weighted_error = c.weighted_error;
    cert.rational = true;
  } else if (cert.rational) {
    std::vector<Rational> terms;
    for (const LayerCertificate& lc : cert.layers)
      terms.push_back(Rational(layer_weight(tree.depth, lc.level)) * lc.omv);
    cert.weighted_error = sum_pairwise(terms);
  }
  if (!filtered_rounding) {
    cert.weighted_error_nearest = to_double_nearest(cert.weighted_error);
    cert.weighted_error_rounded_by = "exact";
  }
}

}  // namespace

Certificate certify(const Mesh& mesh, const Tree& tree, const CertifyOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  Certificate cert;
  Say say(options);  // progress lines come from any thread, one at a time
  cert.containment = check_conservative(mesh, tree);
  say("containment: " + std::to_string(cert.containment.violations) + " violations in " +
      std::to_string(cert.containment.checked_pairs) + " (node, face) pairs");
  const CertifyState* resume = options.resume;
  VOBB_ASSERT(!resume || resume->obv.empty() || resume->obv.size() == tree.nodes.size(),
              "a resumed state fits the tree (CertifyCheckpoint::load checks it)");
  CertifyRun run(mesh, tree, options, say);
  certify_obv(run, cert);
  const int levels = tree.depth + 1;
  cert.layers.resize(levels);
  run.ids.resize(levels);
  for (int level = 0; level < levels; ++level) run.ids[level] = layer(tree, level);
  const std::vector<char> resumed = resume_layers(run, cert);
  checkpoint_finished(run, nullptr);
  certify_layers(run, cert, resumed);
  certify_weighted_error(run, cert);
  cert.seconds = seconds_since(t0);
  return cert;
}

int layer_workers(int layers, int concurrency, bool uses_nef, size_t faces,
                  double available_bytes) {
  int workers = std::min(layers, concurrency);
  if (uses_nef) {
    const double fit = std::floor(
        available_bytes / (kNefBytesPerFace * static_cast<double>(std::max<size_t>(faces, 1))));
    if (fit < workers) workers = static_cast<int>(fit);
  }
  return std::max(1, workers);
}

double available_memory_bytes() {
  std::FILE* f = std::fopen("/proc/meminfo", "r");
  if (f == nullptr) return std::numeric_limits<double>::infinity();
  char line[256];
  double kib = -1;
  while (std::fgets(line, sizeof line, f) != nullptr)
    if (std::sscanf(line, "MemAvailable: %lf kB", &kib) == 1) break;
  std::fclose(f);
  return kib >= 0 ? kib * 1024 : std::numeric_limits<double>::infinity();
}

namespace {

constexpr const char* kObvFormat = "vobb-certify-obv";
constexpr const char* kLayersFormat = "vobb-certify-layers";
constexpr int64_t kFileVersion = 2;  // 2: enclosures and the rationals where computed

// "p/q" (or "p") in base 10, q > 0, as mpq_class writes it; false for anything else, and for a
// zero denominator, which mpq would divide by.
bool parse_rational(const nlohmann::json& v, Rational* out) {
  if (!v.is_string()) return false;
  const std::string& text = v.get_ref<const std::string&>();
  const size_t slash = text.find('/');
  mpz_class num, den(1);
  auto whole = [](const std::string& digits, mpz_class* z, bool sign_ok) {
    if (digits.empty()) return false;
    for (size_t i = 0; i < digits.size(); ++i)
      if (!(std::isdigit(static_cast<unsigned char>(digits[i])) ||
            (sign_ok && i == 0 && digits[i] == '-' && digits.size() > 1)))
        return false;
    return z->set_str(digits, 10) == 0;
  };
  if (!whole(text.substr(0, slash), &num, true)) return false;
  if (slash != std::string::npos && !whole(text.substr(slash + 1), &den, false)) return false;
  if (den == 0) return false;
  *out = Rational(num, den);
  out->canonicalize();
  return true;
}

nlohmann::json interval_to_json(const MpInterval& x) {
  std::string lo, hi;
  x.to_text(&lo, &hi);
  return nlohmann::json::array({lo, hi});
}

bool parse_interval(const nlohmann::json& v, MpInterval* out) {
  return v.is_array() && v.size() == 2 && v[0].is_string() && v[1].is_string() &&
         MpInterval::from_text(v[0].get<std::string>(), v[1].get<std::string>(), out);
}

nlohmann::json enclosed_to_json(const Enclosed& e) {
  nlohmann::json j = {
      {"enclosure", interval_to_json(e.value)}, {"exact", e.exact}, {"bits", e.bits}};
  if (e.exact || sgn(e.q) != 0) j["rational"] = e.q.get_str();
  return j;
}

nlohmann::json layer_to_json(const LayerCertificate& l) {
  nlohmann::json jl = {{"level", l.level},
                       {"boxes", l.boxes},
                       {"overlapping_boxes", l.overlapping_boxes},
                       {"omv_path", l.omv_path},
                       {"omv_enclosure", interval_to_json(l.omv_enclosure)},
                       {"sum_obv_enclosure", interval_to_json(l.sum_obv_enclosure)},
                       {"overlap_enclosure", interval_to_json(l.overlap_enclosure)},
                       {"omv_nearest", l.omv_nearest},
                       {"sum_obv_nearest", l.sum_obv_nearest},
                       {"overlap_nearest", l.overlap_nearest},
                       {"omv_rounded_by", l.omv_rounded_by},
                       {"sum_obv_rounded_by", l.sum_obv_rounded_by},
                       {"overlap_rounded_by", l.overlap_rounded_by},
                       {"upper_bound", l.upper_bound},
                       {"bound_by", l.bound_by},
                       {"exact_obv", l.exact_obv},
                       {"exact_overlap", l.exact_overlap},
                       {"refined_obv", l.refined_obv},
                       {"refined_overlap", l.refined_overlap},
                       {"rational", l.rational},
                       {"seconds", l.seconds}};
  if (l.rational) {
    jl["omv"] = l.omv.get_str();
    jl["sum_obv"] = l.sum_obv.get_str();
  }
  if (l.omv_path == "both") {
    jl["paths_agree"] = l.paths_agree;
    jl["omv_clip"] = l.omv_clip.get_str();
  }
  return jl;
}

// Reads one of the two files: JSON object, format, known fields, checksum, fingerprint.
// *text gets the file's bytes.
// `fingerprint` null: the file is checked as a file (JSON, format, fields, checksum), not as
// this certification's.
Status read_checkpoint_file(const std::string& path, const char* format,
                            const std::set<std::string>& known, const std::string* fingerprint,
                            nlohmann::json* j, std::string* text) {
  const Status read = read_regular_file(path, path, "checkpoint file", text, true);
  if (!read) return read;
  auto bad = [&](const std::string& why) {
    return Status::error(path + ": damaged certify checkpoint: " + why);
  };
  // The deepest values are at depth 2 (layers.json: file, layers, a layer); 8 leaves room.
  bool too_deep = false;
  std::string twice;
  if (!parse_json_within(*text, 8, j, &too_deep, &twice))
    return bad(json_refusal(too_deep, twice, "a checkpoint"));
  if (!j->is_object()) return bad("not a JSON object");
  // Types first: value() throws on a field of another type ("format": 5).
  const bool format_ok = j->contains("format") && (*j)["format"].is_string() &&
                         (*j)["format"].get<std::string>() == format;
  const bool has_version = j->contains("version") && (*j)["version"].is_number_integer();
  if (!format_ok || !has_version) return bad("not a vobb certify checkpoint");
  const int64_t version = (*j)["version"].get<int64_t>();
  if (version == 1)
    return Status::error(
        path +
        ": a certify checkpoint of an older vobb (format 1, rationals only); this one "
        "keeps enclosures: remove the folder or use another --checkpoint");
  if (version != kFileVersion) return bad("not a vobb certify checkpoint");
  for (const auto& item : j->items())
    if (!known.count(item.key())) return bad("unknown field '" + item.key().substr(0, 40) + "'");
  if (!j->contains("sha256") || !(*j)["sha256"].is_string() ||
      (*j)["sha256"].get<std::string>() != json_checksum(*j))
    return bad("checksum does not match the contents");
  if (!j->contains("fingerprint") || !(*j)["fingerprint"].is_string()) return bad("no fingerprint");
  if (fingerprint == nullptr) return Status::ok();
  if ((*j)["fingerprint"].get<std::string>() != *fingerprint)
    return Status::error(
        path +
        ": checkpoint of another certification (mesh, tree, path or certify version differ); "
        "use another --checkpoint folder or remove it");
  return Status::ok();
}

const std::set<std::string> kObvFields = {"format", "version", "fingerprint", "obv", "sha256"};
const std::set<std::string> kLayersFields = {"format",     "version", "fingerprint",
                                             "obv_sha256", "layers",  "sha256"};

// Both files of a checkpoint, each checked as read_checkpoint_file checks it. An absent file
// leaves its JSON null; layers.json without obv.json is damage.
Status read_checkpoint_files(const std::string& obv_file, const std::string& layers_file,
                             const std::string* fingerprint, nlohmann::json* obv,
                             nlohmann::json* layers) {
  *obv = nlohmann::json();
  *layers = nlohmann::json();
  const bool has_obv = !path_absent(obv_file), has_layers = !path_absent(layers_file);
  if (has_layers && !has_obv)
    return Status::error(layers_file +
                         ": damaged certify checkpoint: layers without the boxes' OBV (" +
                         obv_file + ")");
  std::string text;
  if (has_obv) {
    Status s = read_checkpoint_file(obv_file, kObvFormat, kObvFields, fingerprint, obv, &text);
    if (!s) return s;
  }
  if (has_layers) {
    Status s =
        read_checkpoint_file(layers_file, kLayersFormat, kLayersFields, fingerprint, layers, &text);
    if (!s) return s;
  }
  return Status::ok();
}

// Whether layers.json (read, not null) names obv.json (read) by its checksum: it was written
// after that obv.json, not another.
bool layers_name_obv(const nlohmann::json& obv, const nlohmann::json& layers) {
  return layers.contains("obv_sha256") && layers["obv_sha256"].is_string() &&
         layers["obv_sha256"] == obv["sha256"];
}
constexpr const char* kLayersOfAnotherObv = "its layers belong to another obv.json";

// The error of a damaged checkpoint file: one line naming the file and what is wrong.
Status damaged(const std::string& file, const std::string& why) {
  return Status::error(file + ": damaged certify checkpoint: " + why);
}

// obv.json's (read from `file`) OBV into *out, one per node of `tree`: each an enclosure, its
// bits 128 or 256, no unknown field, and its rational where given (inside the enclosure; given
// where exact; in a `rational` run, one not given is 0, and must lie inside it too). A field
// missing or of another type throws nlohmann's exception.
Status parse_obv(const nlohmann::json& jo, const Tree& tree, const std::string& file, bool rational,
                 std::vector<Enclosed>* out) {
  auto bad = [&](const std::string& why) { return damaged(file, why); };
  const nlohmann::json& obv = jo.at("obv");
  if (!obv.is_array() || obv.size() != tree.nodes.size())
    return bad("OBV of " + std::to_string(obv.size()) + " boxes for a tree of " +
               std::to_string(tree.nodes.size()));
  for (size_t i = 0; i < obv.size(); ++i) {
    Enclosed e;
    const nlohmann::json& jo_i = obv[i];
    const std::string at = "OBV of node " + std::to_string(i);
    if (!jo_i.is_object() || !parse_interval(jo_i.at("enclosure"), &e.value) ||
        !jo_i.at("exact").is_boolean())
      return bad(at + " is not an enclosure");
    e.exact = jo_i["exact"].get<bool>();
    const nlohmann::json& bits = jo_i.at("bits");
    if (!bits.is_number_integer() ||
        (bits.get<int64_t>() != MpInterval::kPrec && bits.get<int64_t>() != MpInterval::kMaxPrec))
      return bad(at + ": bits is neither 128 nor 256");
    e.bits = static_cast<int>(bits.get<int64_t>());
    for (const auto& item : jo_i.items())
      if (item.key() != "enclosure" && item.key() != "exact" && item.key() != "rational" &&
          item.key() != "bits")
        return bad(at + ": unknown field '" + item.key().substr(0, 40) + "'");
    if (jo_i.contains("rational") &&
        (!parse_rational(jo_i["rational"], &e.q) || !e.value.contains(e.q)))
      return bad(at + ": its rational is not one, or lies outside its enclosure");
    if (e.exact && !jo_i.contains("rational")) return bad(at + ": exact, without its rational");
    // The writer leaves out a rational 0; in a run of every rational, that 0 is the rational.
    if (rational && !jo_i.contains("rational") && !e.value.contains(e.q))
      return bad(at + ": its rational (0, not written) lies outside its enclosure");
    out->push_back(std::move(e));
  }
  return Status::ok();
}

// A layer's values (of layers.json, read from `file`; `at` names the layer) into *out, after its
// level: only fields the writer puts there, its box count the tree's, its overlap count up to
// it, its enclosures, its nearest doubles, how each was obtained, its counts, and its rationals
// where it says it has them. A field missing or of another type throws nlohmann's exception.
Status parse_layer_values(const nlohmann::json& jl, const Tree& tree, const std::string& file,
                          const std::string& at, LayerCertificate* out) {
  auto bad = [&](const std::string& why) { return damaged(file, why); };
  LayerCertificate& l = *out;
  // Every field must be one the writer puts there.
  static const std::set<std::string> kLayerFields{"level",
                                                  "boxes",
                                                  "overlapping_boxes",
                                                  "omv_path",
                                                  "omv_enclosure",
                                                  "sum_obv_enclosure",
                                                  "overlap_enclosure",
                                                  "omv_nearest",
                                                  "sum_obv_nearest",
                                                  "overlap_nearest",
                                                  "omv_rounded_by",
                                                  "sum_obv_rounded_by",
                                                  "overlap_rounded_by",
                                                  "upper_bound",
                                                  "bound_by",
                                                  "exact_obv",
                                                  "exact_overlap",
                                                  "refined_obv",
                                                  "refined_overlap",
                                                  "rational",
                                                  "seconds",
                                                  "omv",
                                                  "sum_obv",
                                                  "paths_agree",
                                                  "omv_clip"};
  for (const auto& item : jl.items())
    if (!kLayerFields.count(item.key()))
      return bad(at + "unknown field '" + item.key().substr(0, 40) + "'");
  const std::vector<int32_t> ids = layer(tree, l.level);
  const nlohmann::json& boxes = jl.at("boxes");
  const nlohmann::json& overlapping = jl.at("overlapping_boxes");
  if (!boxes.is_number_unsigned() || boxes.get<uint64_t>() != ids.size())
    return bad(at + "box count is not the tree's");
  if (!overlapping.is_number_unsigned() || overlapping.get<uint64_t>() > ids.size())
    return bad(at + "overlapping boxes are not a count up to its boxes");
  l.boxes = ids.size();
  l.overlapping_boxes = overlapping.get<uint64_t>();
  if (!parse_interval(jl.at("omv_enclosure"), &l.omv_enclosure) ||
      !parse_interval(jl.at("sum_obv_enclosure"), &l.sum_obv_enclosure) ||
      !parse_interval(jl.at("overlap_enclosure"), &l.overlap_enclosure))
    return bad(at + "an enclosure is not one");
  for (const char* key : {"omv_nearest", "sum_obv_nearest", "overlap_nearest"})
    if (!jl.at(key).is_number()) return bad(at + key + " is not a number");
  l.omv_nearest = jl["omv_nearest"].get<double>();
  l.sum_obv_nearest = jl["sum_obv_nearest"].get<double>();
  l.overlap_nearest = jl["overlap_nearest"].get<double>();
  l.omv_rounded_by = jl.at("omv_rounded_by").get<std::string>();
  l.sum_obv_rounded_by = jl.at("sum_obv_rounded_by").get<std::string>();
  l.overlap_rounded_by = jl.at("overlap_rounded_by").get<std::string>();
  l.bound_by = jl.at("bound_by").get<std::string>();
  for (const std::string* by :
       {&l.omv_rounded_by, &l.sum_obv_rounded_by, &l.overlap_rounded_by, &l.bound_by})
    if (*by != "filter" && *by != "exact")
      return bad(at + "a value's rounded_by or bound_by is neither filter nor exact");
  l.upper_bound = jl.at("upper_bound").get<bool>();
  // Counts of the layer's boxes: whole numbers up to its box count (get<uint64_t> would wrap a
  // negative one and truncate 1.5).
  for (const auto& [key, count] :
       {std::pair{"exact_obv", &l.exact_obv}, std::pair{"exact_overlap", &l.exact_overlap},
        std::pair{"refined_obv", &l.refined_obv},
        std::pair{"refined_overlap", &l.refined_overlap}}) {
    int64_t x = 0;
    if (!json_integer_in(jl.at(key), 0, static_cast<int64_t>(ids.size()), &x))
      return bad(at + key + " is not a count up to its boxes");
    *count = static_cast<size_t>(x);
  }
  l.rational = jl.at("rational").get<bool>();
  if (l.rational) {
    if (!parse_rational(jl.at("omv"), &l.omv) || !parse_rational(jl.at("sum_obv"), &l.sum_obv))
      return bad(at + "OMV or sum of OBV is not a rational");
  } else if (jl.contains("omv") || jl.contains("sum_obv")) {
    return bad(at + "rationals in a layer that says it has none");
  }
  return Status::ok();
}

// A layer's path into *out (its values read): "none" only where no boxes overlap, "both" with
// clipping's OMV and whether the paths agree (checked against the two OMV), or "nef", "clip" or
// "filtered", which hold no second path's OMV; a filtered layer's rationals agree when its
// enclosure holds its OMV.
Status parse_layer_path(const nlohmann::json& jl, const std::string& file, const std::string& at,
                        LayerCertificate* out) {
  auto bad = [&](const std::string& why) { return damaged(file, why); };
  LayerCertificate& l = *out;
  l.omv_path = jl.at("omv_path").get<std::string>();
  if (l.omv_path == "none") {
    if (l.overlapping_boxes != 0 || l.overlap_enclosure.lo_rational() != 0 ||
        l.overlap_enclosure.hi_rational() != 0)
      return bad(at + "path none, but boxes overlap");
  } else if (l.omv_path == "both") {
    if (!l.rational || !parse_rational(jl.at("omv_clip"), &l.omv_clip))
      return bad(at + "clipping's OMV is not a rational");
    l.paths_agree = jl.at("paths_agree").get<bool>();
    if (l.paths_agree != (l.omv == l.omv_clip && l.omv_enclosure.contains(l.omv)))
      return bad(at + "paths_agree contradicts the two OMV");
  } else if (l.omv_path != "nef" && l.omv_path != "clip" && l.omv_path != "filtered") {
    return bad(at + "unknown path '" + l.omv_path.substr(0, 20) + "'");
  }
  if (l.omv_path != "both" && (jl.contains("paths_agree") || jl.contains("omv_clip")))
    return bad(at + "a second path's OMV on a layer of path " + l.omv_path);
  if (l.omv_path == "filtered" && l.rational) l.paths_agree = l.omv_enclosure.contains(l.omv);
  return Status::ok();
}

// Whether what a layer (read as `l`) says follows from its own values, as certify makes them:
// its OMV's enclosure from its path, its bound and its nearest doubles.
Status check_layer_follows(const std::string& file, const std::string& at,
                           const LayerCertificate& l) {
  auto bad = [&](const std::string& why) { return damaged(file, why); };
  if (l.omv_path == "none" &&
      (!same_enclosure(l.omv_enclosure, l.sum_obv_enclosure) || (l.rational && l.omv != l.sum_obv)))
    return bad(at + "path none, but OMV is not the sum of OBV");
  if ((l.omv_path == "filtered" || l.omv_path == "both") &&
      !same_enclosure(l.omv_enclosure, l.sum_obv_enclosure - l.overlap_enclosure))
    return bad(at + "OMV's enclosure is not the sum of OBV's less the overlap's");
  if ((l.omv_path == "nef" || l.omv_path == "clip") &&
      (!l.rational || !l.omv_enclosure.contains(l.omv)))
    return bad(at + "a rational path's OMV lies outside its enclosure");
  const bool bound_ok = l.bound_by == "exact"
                            ? (l.rational ? l.upper_bound == (l.sum_obv >= l.omv)
                                          : l.omv_path == "none" && l.upper_bound)
                            : (l.upper_bound ? l.overlap_enclosure.lo_rational() >= 0
                                             : l.overlap_enclosure.hi_rational() < 0);
  if (!bound_ok) return bad(at + "its bound does not follow from its values");
  auto rounding_ok = [&](const MpInterval& e, const std::function<Rational()>& q, double d,
                         const std::string& by) {
    double f;
    if (by == "filter") return e.nearest(&f) && f == d;
    return l.rational && to_double_nearest(q()) == d;
  };
  if (!rounding_ok(
          l.omv_enclosure, [&] { return l.omv; }, l.omv_nearest, l.omv_rounded_by) ||
      !rounding_ok(
          l.sum_obv_enclosure, [&] { return l.sum_obv; }, l.sum_obv_nearest,
          l.sum_obv_rounded_by) ||
      !rounding_ok(
          l.overlap_enclosure, [&] { return l.overlap(); }, l.overlap_nearest,
          l.overlap_rounded_by))
    return bad(at + "a double is not its value rounded");
  return Status::ok();
}

// One layer of layers.json (read from `file`) into *out: an object, its level in 0..depth and
// not yet `seen` (then marked), its values and path, its sum of OBV's enclosure the one its
// boxes' `obv` give (sum_obv_fits) and holding its rational sum, what it says following from
// them, and its seconds a time. A field missing or of another type throws nlohmann's exception.
Status parse_layer(const nlohmann::json& jl, const Tree& tree, const std::vector<Enclosed>& obv,
                   const std::string& file, std::vector<char>* seen, LayerCertificate* out) {
  auto bad = [&](const std::string& why) { return damaged(file, why); };
  LayerCertificate& l = *out;
  if (!jl.is_object()) return bad("a layer is not an object");
  const nlohmann::json& level = jl.at("level");
  if (!level.is_number_integer() || level.get<int64_t>() < 0 || level.get<int64_t>() > tree.depth)
    return bad("a layer's level is not an integer in 0.." + std::to_string(tree.depth));
  l.level = static_cast<int>(level.get<int64_t>());
  const std::string at = "layer " + std::to_string(l.level) + ": ";
  if ((*seen)[l.level]) return bad(at + "given twice");
  (*seen)[l.level] = 1;
  Status s = parse_layer_values(jl, tree, file, at, &l);
  if (!s) return s;
  s = parse_layer_path(jl, file, at, &l);
  if (!s) return s;
  if (!sum_obv_fits(l, layer_sum_obv(layer(tree, l.level), obv)))
    return bad(at + "sum of OBV is not the sum of its boxes' OBV");
  if (l.rational && !l.sum_obv_enclosure.contains(l.sum_obv))
    return bad(at + "sum of OBV lies outside its enclosure");
  s = check_layer_follows(file, at, l);
  if (!s) return s;
  const nlohmann::json& seconds = jl.at("seconds");
  if (!seconds.is_number() || !(seconds.get<double>() >= 0))
    return bad(at + "seconds is not a time");
  l.seconds = seconds.get<double>();
  return Status::ok();
}

// layers.json's (read from `file`) finished layers into *out, in its order, each as parse_layer
// reads it (against `tree` and the boxes' `obv`). A field missing or of another type throws
// nlohmann's exception.
Status parse_layers(const nlohmann::json& j, const Tree& tree, const std::vector<Enclosed>& obv,
                    const std::string& file, std::vector<LayerCertificate>* out) {
  const nlohmann::json& layers = j.at("layers");
  if (!layers.is_array()) return damaged(file, "layers is not a list");
  std::vector<char> seen(tree.depth + 1, 0);
  for (const nlohmann::json& jl : layers) {
    LayerCertificate l;
    const Status s = parse_layer(jl, tree, obv, file, &seen, &l);
    if (!s) return s;
    out->push_back(std::move(l));
  }
  return Status::ok();
}

}  // namespace

Status CertifyCheckpoint::check_files(const std::string& folder) {
  nlohmann::json obv, layers;
  const std::string layers_file = folder + "/layers.json";
  Status s = read_checkpoint_files(folder + "/obv.json", layers_file, nullptr, &obv, &layers);
  if (s && !layers.is_null() && !layers_name_obv(obv, layers))
    return Status::error(layers_file + ": damaged certify checkpoint: " + kLayersOfAnotherObv);
  return s;
}

struct CertifyCheckpoint::Written {
  std::map<int, nlohmann::json> layers;
};

CertifyCheckpoint::CertifyCheckpoint(std::string folder, std::string fingerprint)
    : folder_(std::move(folder)), fingerprint_(std::move(fingerprint)), written_(new Written) {}

CertifyCheckpoint::~CertifyCheckpoint() = default;

std::string CertifyCheckpoint::obv_path() const { return folder_ + "/obv.json"; }
std::string CertifyCheckpoint::layers_path() const { return folder_ + "/layers.json"; }

Status CertifyCheckpoint::save(const CertifyState& state) {
  if (!state.obv.empty() && obv_sha256_.empty()) {
    nlohmann::json j;
    j["format"] = kObvFormat;
    j["version"] = kFileVersion;
    j["fingerprint"] = fingerprint_;
    nlohmann::json obv = nlohmann::json::array();
    for (const Enclosed& e : state.obv) obv.push_back(enclosed_to_json(e));
    j["obv"] = std::move(obv);
    j["sha256"] = json_checksum(j);
    const std::string text = j.dump() + "\n";
    const Status w = write_file_atomic(obv_path(), text);
    if (!w) return w;
    obv_sha256_ = j["sha256"].get<std::string>();
  }
  if (obv_sha256_.empty()) return Status::ok();  // nothing finished yet
  nlohmann::json j;
  j["format"] = kLayersFormat;
  j["version"] = kFileVersion;
  j["fingerprint"] = fingerprint_;
  j["obv_sha256"] = obv_sha256_;
  nlohmann::json layers = nlohmann::json::array();
  for (const LayerCertificate& l : state.layers) {
    // A finished layer does not change: its decimal strings (up to some 10^5 digits each) are
    // made once, not at every save.
    auto cached = written_->layers.find(l.level);
    if (cached != written_->layers.end()) {
      layers.push_back(cached->second);
      continue;
    }
    nlohmann::json jl = layer_to_json(l);
    layers.push_back(jl);
    written_->layers.emplace(l.level, std::move(jl));
  }
  j["layers"] = std::move(layers);
  j["sha256"] = json_checksum(j);
  return write_file_atomic(layers_path(), j.dump() + "\n");
}

Status CertifyCheckpoint::load(const Tree& tree, CertifyState* state, bool* found, bool rational) {
  *found = false;
  const std::string obv_file = obv_path(), layers_file = layers_path();
  if (path_absent(obv_file) && path_absent(layers_file)) return Status::ok();
  *found = true;
  CertifyState s;
  std::string current;  // the file being read, for the messages
  auto bad = [&](const std::string& why) { return damaged(current, why); };
  try {
    nlohmann::json jo, j;
    Status r = read_checkpoint_files(obv_file, layers_file, &fingerprint_, &jo, &j);
    if (!r) return r;
    current = obv_file;
    // obv.json's checksum of its contents (read_checkpoint_files checked it).
    const std::string obv_sha = jo["sha256"].get<std::string>();
    r = parse_obv(jo, tree, current, rational, &s.obv);
    if (!r) return r;
    if (!j.is_null()) {
      current = layers_file;
      if (!layers_name_obv(jo, j)) return bad(kLayersOfAnotherObv);
      r = parse_layers(j, tree, s.obv, current, &s.layers);
      if (!r) return r;
    }
    obv_sha256_ = obv_sha;
  } catch (const nlohmann::json::exception& e) {
    // A field missing or of another type: nlohmann's one-line reason ("key 'x' not found",
    // "type must be boolean, but is string") without its "[json.exception.type_error.302] ".
    const std::string what = e.what();
    const size_t tag = what.rfind("[json.exception.", 0) == 0 ? what.find("] ") : std::string::npos;
    return bad(tag == std::string::npos ? what : what.substr(tag + 2));
  }
  *state = std::move(s);
  return Status::ok();
}

}  // namespace vobb::exact
