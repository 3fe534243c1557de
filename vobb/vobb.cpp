#include "vobb/vobb.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <memory>
#include <optional>

#include "builder/obbtree_builder.h"
#include "builder/subtree_swaps.h"
#include "collision/query_objective.h"
#include "common/atomic_file.h"
#include "common/exact_predicates.h"
#include "common/sha256.h"
#include "common/solidity.h"
#include "common/stopwatch.h"
#include "common/text_util.h"
#include "exact/filtered_solver.h"
#include "exact/outer_volume.h"
#include "fast/cpu_estimator.h"
#include "fast/cubemap_bound.h"
#include "fast/poly_overlap.h"
#include "fast/texel_plan.h"
#include "vobb/gl_backend.h"

namespace vobb {

namespace detail {
namespace {
std::atomic<GlFactory> the_gl_factory{nullptr};
}  // namespace
void set_gl_factory(GlFactory factory) { the_gl_factory = factory; }
GlFactory gl_factory() { return the_gl_factory; }
}  // namespace detail

namespace {

void say(const std::function<void(const std::string&)>& to, const std::string& line) {
  if (to) to(line);
}

Status make_gl(const Mesh& mesh, bool device_only, std::unique_ptr<detail::GlEstimate>* out) {
  const detail::GlFactory factory = detail::gl_factory();
  if (factory == nullptr)
    return Status::error(
        "GL is not enabled in this program (link vobb::gl and call vobb::enable_gl())");
  return factory(mesh, device_only, out);
}

// The objective of a variational build: an OBV estimator, or the recorded queries' hits.
struct Estimator {
  std::unique_ptr<detail::GlEstimate> gl;
  std::unique_ptr<CpuObvEstimator> cpu;
  std::unique_ptr<PolyObvSolver> poly;
  std::unique_ptr<collision::QueryHitObjective> hits;
  ObvEstimate estimate;
  std::string name;  // for the fingerprint and the report
};

// kAuto: GL on an EGL device from m = kAutoGlFromM; below it, on llvmpipe or without GL, the
// CPU twin. No GL context is made where the CPU twin is chosen by m.
Status make_estimator(const Mesh& mesh, const BuildOptions& o, Estimator* e) {
  if (!o.queries.empty()) {
    e->hits = std::make_unique<collision::QueryHitObjective>(mesh, o.queries);
    say(o.note, "objective: the hits of " + std::to_string(e->hits->size()) +
                    " recorded queries (no OBV estimator)");
    const collision::QueryHitObjective* h = e->hits.get();
    e->estimate = [h](const std::vector<Obb>& boxes) { return (*h)(boxes); };
    e->name = "queries";
    return Status::ok();
  }
  if (o.backend == Backend::kPoly) {
    e->poly = std::make_unique<PolyObvSolver>(mesh);
    const PolyObvSolver* p = e->poly.get();
    e->estimate = [p](const std::vector<Obb>& boxes) { return p->estimate(boxes); };
    e->name = "poly";
    return Status::ok();
  }
  if (o.backend == Backend::kGl || (o.backend == Backend::kAuto && o.m >= kAutoGlFromM)) {
    const bool auto_gl = o.backend == Backend::kAuto;
    const Status s = make_gl(mesh, auto_gl, &e->gl);  // under kAuto a failure falls back
    if (!s && !auto_gl) return s;
    if (s && o.m > e->gl->max_m())
      return Status::error("--m " + std::to_string(o.m) + " exceeds the GL estimator's limit");
    if (s) say(o.note, e->gl->description());
  }
  const int m = o.m;
  if (e->gl) {
    detail::GlEstimate* g = e->gl.get();
    e->estimate = [g, m](const std::vector<Obb>& boxes) { return g->estimate(boxes, m); };
    e->name = "gl " + g->renderer();
  } else {
    e->cpu = std::make_unique<CpuObvEstimator>(mesh);
    const CpuObvEstimator* c = e->cpu.get();
    e->estimate = [c, m](const std::vector<Obb>& boxes) { return c->estimate(boxes, m); };
    e->name = "cpu";
  }
  // The search sees each cubemap estimate moved into the range that holds the box's OBV
  // (clamp_to_obv_range): on an extreme box the estimate can be off by the box's volume, and a
  // search would take a box far larger than the solid, estimated near 0, for a gain. The
  // solid's volume is rounded up, so the range still holds the OBV.
  const double solid = std::nextafter(to_double_nearest(exact_signed_volume(mesh)),
                                      std::numeric_limits<double>::infinity());
  e->estimate = [raw = std::move(e->estimate), solid](const std::vector<Obb>& boxes) {
    std::vector<double> v = raw(boxes);
    for (size_t i = 0; i < v.size(); ++i) v[i] = clamp_to_obv_range(boxes[i], v[i], solid);
    return v;
  };
  return Status::ok();
}

// The SHA-256 of recorded colliders: each as 17 doubles (shape, centre, radius, half extents,
// axes), the checkpoint's name for them.
std::string queries_digest(const std::vector<collision::Collider>& colliders) {
  std::string bytes;
  for (const collision::Collider& c : colliders) {
    double v[17] = {c.shape == collision::ColliderShape::kSphere ? 0.0 : 1.0,
                    c.center[0],
                    c.center[1],
                    c.center[2],
                    c.radius,
                    c.half[0],
                    c.half[1],
                    c.half[2]};
    for (int k = 0; k < 3; ++k)
      for (int i = 0; i < 3; ++i) v[8 + 3 * k + i] = c.axes[k][i];
    bytes.append(reinterpret_cast<const char*>(v), sizeof v);
  }
  return sha256_hex(bytes.data(), bytes.size());
}

// What a variational build depends on, for its checkpoints: a state saved under another
// fingerprint is refused, so a resumed build is the build that was interrupted. "builder 4":
// bump when the builder's decisions change, so that older states are refused. The refit
// (BuildOptions::refit) runs after the last state, so the states are the same with it or
// without, and it is not named.
std::string build_fingerprint(const Mesh& mesh, const BuildOptions& o,
                              const std::string& estimator) {
  auto on = [](bool b) { return std::string(b ? "on" : "off"); };
  // The recorded-query builds name the estimator they would have had, as they always did.
  const std::string named =
      estimator == "queries" ? (o.backend == Backend::kPoly ? "poly" : "cpu") : estimator;
  return "builder 4; mesh " + mesh_sha256(mesh) + "; depth " + std::to_string(o.depth) +
         "; arity " + std::to_string(o.arity) + "; lloyd " + std::to_string(o.lloyd) + "; seed " +
         std::to_string(o.seed) + "; axis search " + on(o.axis_search) + "; adjust " +
         on(o.adjust) + "; merge " + on(o.merge) + "; sweeps " + std::to_string(o.sweeps) + "; m " +
         std::to_string(o.m) + "; estimator " + named +
         // Named only when set, so that states saved before the option existed still resume.
         (o.collider_margin > 0 ? "; collider margin " + format_double(o.collider_margin)
                                : std::string()) +
         (o.queries.empty() ? std::string() : "; recorded queries " + queries_digest(o.queries)) +
         (search_objective(o) == Objective::kOmv ? "; objective omv" : "");
}

// A resumed state whose time budget ran out holds baseline splits where the search was cut
// short: a build without a budget would write that tree, not its own, so it is refused.
Status check_spent_budget(const VariationalState& state, const BuildOptions& o,
                          const std::string& path) {
  if (!state.budget_spent || o.time_budget > 0) return Status::ok();
  return Status::error(path +
                       ": saved by a build whose --time-budget ran out, so a build without one "
                       "cannot resume it (remove the folder to start again)");
}

// The OBB-Tree baseline at the options' depth and arity.
Tree baseline_tree(const Mesh& mesh, const BuildOptions& o) {
  ObbTreeOptions opt;
  opt.depth = o.depth;
  opt.arity = o.arity;
  return build_obbtree(mesh, opt);
}

// What any mesh load_solid gives has, checked in one pass where a caller passes another: faces,
// each indexing the vertices, and finite coordinates within kMaxCoordinate. The rest of
// solidity (closed, manifold, no self-intersections) stays the caller's precondition.
Status check_mesh(const Mesh& mesh) {
  if (mesh.faces.empty()) return Status::error("the mesh has no faces");
  const size_t n = mesh.vertices.size();
  for (size_t f = 0; f < mesh.faces.size(); ++f)
    for (const int32_t v : mesh.faces[f])
      if (v < 0 || static_cast<size_t>(v) >= n)
        return Status::error("face " + std::to_string(f) + ": vertex index " + std::to_string(v) +
                             " out of range (" + std::to_string(n) + " vertices)");
  for (size_t v = 0; v < n; ++v)
    if (!(mesh.vertices[v].cwiseAbs().maxCoeff() <= kMaxCoordinate))  // NaN fails too
      return Status::error("vertex " + std::to_string(v) +
                           ": a coordinate is not finite or beyond 2^240");
  return Status::ok();
}

// A margin beyond the model's size is no collider of this model, and it keeps the grown boxes'
// volumes far from overflow.
Status check_margin(const Mesh& mesh, const BuildOptions& o) {
  if (o.collider_margin <= 0) return Status::ok();
  const Aabb box = mesh.bounds();
  const double diagonal = (box.hi - box.lo).norm();
  if (o.collider_margin > diagonal)
    return Status::error("--collider-margin " + format_double(o.collider_margin) +
                         " exceeds the mesh's bounding-box diagonal " + format_double(diagonal));
  return Status::ok();
}

std::string state_path(const std::string& checkpoint) {
  return (std::filesystem::path(checkpoint) / "state.json").string();
}

Status build_variational_tree(const Mesh& mesh, const BuildOptions& o, const Estimator& est,
                              Tree* tree, VariationalReport* report) {
  VariationalOptions opt;
  opt.depth = o.depth;
  opt.arity = o.arity;
  opt.lloyd_iterations = o.lloyd;
  opt.optimise_axes = o.axis_search;
  opt.adjust = o.adjust;
  opt.merge = o.merge;
  opt.refit = o.refit;
  opt.max_sweeps = o.sweeps;
  opt.seed = o.seed;
  opt.margin = o.collider_margin;
  // The overlap-aware objective's shares: the polyhedral solver's doubles, whatever the OBV
  // estimator (the cubemap has no form for them).
  std::unique_ptr<PolyOverlapSolver> shares;
  if (search_objective(o) == Objective::kOmv) {
    opt.objective = Objective::kOmv;
    shares = std::make_unique<PolyOverlapSolver>(mesh);
    const PolyOverlapSolver* p = shares.get();
    opt.share = [p](const std::vector<ShareQuery>& v) { return p->estimate(v); };
  }
  opt.concurrent_estimates =
      true;  // every estimator here may be called from several threads at once
  const auto t0 = std::chrono::steady_clock::now();
  if (o.time_budget > 0) opt.out_of_time = [&] { return seconds_since(t0) > o.time_budget; };
  opt.progress = o.progress;
  VariationalState resume;
  bool resuming = false;
  bool warned = false;
  if (!o.checkpoint.empty()) {
    Status s = make_checkpoint_folder("--checkpoint " + o.checkpoint, o.checkpoint);
    if (!s) return s;
    const std::string path = state_path(o.checkpoint);
    const std::string fingerprint = build_fingerprint(mesh, o, est.name);
    s = read_variational_state(path, fingerprint, mesh.faces.size(), o.arity, o.depth, &resume,
                               &resuming);
    if (!s) return s;
    if (resuming && !(s = check_spent_budget(resume, o, path))) return s;
    if (resuming)
      say(o.note, "resuming from " + path + " (" + std::to_string(resume.split_levels) +
                      " levels split, " + std::to_string(resume.sweeps) + " sweeps done)");
    opt.checkpoint = [&, fingerprint, path](const VariationalState& st) {
      const Status w = write_variational_state(st, fingerprint, path);
      if (!w && !warned) {
        warned = true;
        say(o.warning, "warning: checkpoint not saved: " + w.message());
      }
      if (w && o.saved) o.saved(st);
    };
  }
  if (o.started) o.started();
  *tree = build_variational(mesh, opt, est.estimate, resuming ? &resume : nullptr, report);
  if (o.finished) o.finished(*report);
  if (o.subtree_swaps) {
    // Scored by the polyhedral solver whatever the backend: a swap's gain may be as small as
    // 1e-4 of e, the cubemap's median error at m = 32 (docs/BENCHMARKS.md).
    std::unique_ptr<PolyObvSolver> own;
    const PolyObvSolver* obv = est.poly.get();  // the build's own, with --backend poly
    if (!obv) obv = (own = std::make_unique<PolyObvSolver>(mesh)).get();
    if (!shares) shares = std::make_unique<PolyOverlapSolver>(mesh);
    const PolyOverlapSolver* p = shares.get();
    SubtreeSwapOptions so;
    so.estimate = [obv](const std::vector<Obb>& b) { return obv->estimate(b); };
    so.share = [p](const std::vector<ShareQuery>& q) { return p->estimate(q); };
    so.out_of_time = opt.out_of_time;
    SubtreeSwapReport sr;
    swap_subtrees(mesh, so, tree, &sr);
    if (o.swapped) o.swapped(sr);
  }
  const Status valid = validate_tree(*tree, "variational tree");
  VOBB_ASSERT(valid, valid.message().c_str());  // a builder bug, not bad input
  return Status::ok();
}

// A certification's checkpoint in `folder`: loads what is saved into `resume` and points `opt`
// at it, and saves after each stage. The fingerprint names the mesh, the tree and the path.
struct CertifySaver {
  CertifySaver() = default;
  CertifySaver(const CertifySaver&) = delete;  // opt's resume pointer and callback point into it
  CertifySaver& operator=(const CertifySaver&) = delete;
  exact::CertifyState resume;
  std::unique_ptr<exact::CertifyCheckpoint> files;
  bool warned = false;

  Status attach(const std::string& folder, const Mesh& mesh, const Tree& tree,
                const std::string& path, const CertifyOptions& o, exact::CertifyOptions* opt) {
    Status s = make_checkpoint_folder("--checkpoint " + folder, folder);
    if (!s) return s;
    const std::string tree_json = tree_to_json(tree);
    files = std::make_unique<exact::CertifyCheckpoint>(
        folder, std::string(exact::kCertifyVersion) + "; mesh " + mesh_sha256(mesh) + "; tree " +
                    sha256_hex(tree_json.data(), tree_json.size()) + "; path " + path);
    bool resuming = false;
    s = files->load(tree, &resume, &resuming, o.rational);
    if (!s) return s;
    opt->resume = resuming ? &resume : nullptr;
    if (resuming)
      say(o.note, "resuming from " + folder + " (the boxes' OBV, " +
                      std::to_string(resume.layers.size()) + " of " +
                      std::to_string(tree.depth + 1) + " layers done)");
    opt->checkpoint = [this, &o](const exact::CertifyState& st) {
      const Status w = files->save(st);
      if (!w && !warned) {
        warned = true;
        say(o.warning, "warning: checkpoint not saved: " + w.message());
      }
      if (w && o.saved) o.saved(st);
    };
    return Status::ok();
  }
};

const char* path_name(exact::OmvPath p) {
  switch (p) {
    case exact::OmvPath::kClip:
      return "clip";
    case exact::OmvPath::kNef:
      return "nef";
    case exact::OmvPath::kBoth:
      return "both";
    default:
      return "auto";
  }
}

Status certify_with(const Mesh& mesh, const Tree& tree, const CertifyOptions& o,
                    const std::string& folder, const std::string& fingerprint_path,
                    exact::Certificate* out) {
  exact::CertifyOptions opt;
  opt.path = o.path;
  opt.rational = o.rational;
  opt.progress = o.progress;
  CertifySaver saver;
  if (!folder.empty()) {
    const Status s = saver.attach(folder, mesh, tree, fingerprint_path, o, &opt);
    if (!s) return s;
  }
  *out = exact::certify(mesh, tree, opt);
  return Status::ok();
}

std::string certify_folder(const std::string& checkpoint, const std::string& method) {
  return (std::filesystem::path(checkpoint) / ("certify-" + method)).string();
}

// compare's checkpoint, checked before its long work: the variational build's state against
// these options (check_spent_budget too), and each certification's files as files.
Status check_compare_checkpoint(const Mesh& mesh, const BuildOptions& o,
                                const std::string& estimator) {
  Status s = make_checkpoint_folder("--checkpoint " + o.checkpoint, o.checkpoint);
  if (!s) return s;
  VariationalState state;
  bool found = false;
  s = read_variational_state(state_path(o.checkpoint), build_fingerprint(mesh, o, estimator),
                             mesh.faces.size(), o.arity, o.depth, &state, &found);
  if (!s) return s;
  if (found && !(s = check_spent_budget(state, o, state_path(o.checkpoint)))) return s;
  for (const char* method : {"obbtree", "variational"}) {
    const std::string folder = certify_folder(o.checkpoint, method);
    s = make_checkpoint_folder("--checkpoint " + folder, folder);
    if (!s) return s;
    s = exact::CertifyCheckpoint::check_files(folder);
    if (!s) return s;
  }
  return Status::ok();
}

// The certified error of an estimate E: max(|E - lo|, |E - hi|) for an enclosure [lo, hi] of the
// exact OBV, rounded up (one ulp above the nearest double is above the true value).
double certified_error(double e, const PolyObv& r) {
  const double d = std::max(std::abs(e - r.lo), std::abs(e - r.hi));
  return d == 0 ? 0.0 : std::nextafter(d, INFINITY);
}

}  // namespace

Rational tree_error(const std::vector<Rational>& layer_omv) {
  const int depth = static_cast<int>(layer_omv.size()) - 1;
  Rational e(0);
  for (int l = 0; l <= depth; ++l) e += Rational(layer_weight(depth, l)) * layer_omv[l];
  return e;
}

Objective search_objective(const BuildOptions& o) {
  if (!o.queries.empty()) return Objective::kObv;
  return o.objective.value_or(o.collider_margin > 0 ? Objective::kObv : Objective::kOmv);
}

Status check_build_options(const BuildOptions& o) {
  // Values cast into the enums from outside their lists (the CLI cannot make them).
  if (o.method != Method::kVariational && o.method != Method::kObbTree)
    return Status::error("--method is neither variational nor obbtree");
  if (o.backend != Backend::kAuto && o.backend != Backend::kCpu && o.backend != Backend::kGl &&
      o.backend != Backend::kPoly)
    return Status::error("--backend is none of auto, cpu, gl, poly");
  if (o.objective && *o.objective != Objective::kObv && *o.objective != Objective::kOmv)
    return Status::error("--objective is neither obv nor omv");
  const bool variational = o.method == Method::kVariational;
  if (!std::isfinite(o.collider_margin) || o.collider_margin < 0)
    return Status::error("--collider-margin must be a finite length >= 0");
  if (o.collider_margin > 0 && !variational)
    return Status::error("--collider-margin applies to --method variational only");
  if (!o.queries.empty() && !variational)
    return Status::error("--queries applies to --method variational only");
  if (!o.queries.empty() && o.collider_margin > 0)
    return Status::error("--queries and --collider-margin are two objectives; choose one");
  if (o.objective && !variational)
    return Status::error("--objective applies to --method variational only");
  if (!o.queries.empty() && o.objective)
    return Status::error("--queries and --objective are two objectives; choose one");
  if (o.subtree_swaps && !variational)
    return Status::error("--subtree-swaps applies to --method variational only");
  if (o.subtree_swaps && (!o.queries.empty() || o.collider_margin > 0))
    return Status::error(std::string("--subtree-swaps lowers e, which ") +
                         (o.queries.empty() ? "--collider-margin" : "--queries") +
                         " does not minimise");
  // The baseline takes well under a second and has no search to budget or resume.
  if (!o.checkpoint.empty() && !variational)
    return Status::error("--checkpoint applies to --method variational only");
  if (o.queries.size() > collision::kMaxRecordedQueries)
    return Status::error("--queries: more than " + std::to_string(collision::kMaxRecordedQueries) +
                         " colliders");
  for (size_t i = 0; i < o.queries.size(); ++i)
    if (const std::string bad = collision::collider_defect(o.queries[i]); !bad.empty())
      return Status::error("--queries: collider " + std::to_string(i) + ": " + bad);
  if (o.time_budget > 0 && !variational)
    return Status::error("--time-budget applies to --method variational only");
  if (o.depth < 0 || o.depth > 30) return Status::error("--depth must be within 0..30");
  if (o.arity < 2 || o.arity > 64) return Status::error("--arity must be within 2..64");
  if (o.m < 1 || o.m > 4096) return Status::error("--m must be within 1..4096");
  if (o.lloyd < 0 || o.lloyd > 1000) return Status::error("--lloyd must be within 0..1000");
  if (o.sweeps < 0 || o.sweeps > 100) return Status::error("--sweeps must be within 0..100");
  if (!(o.time_budget == 0 || (o.time_budget >= 1e-3 && o.time_budget <= 1e9)))
    return Status::error("--time-budget must be 0 (none) or within 1e-3..1e9 seconds");
  return Status::ok();
}

Status build_tree(const Mesh& mesh, const BuildOptions& o, Tree* tree, BuildReport* report) {
  Status s = check_build_options(o);
  if (!s) return s;
  s = check_mesh(mesh);
  if (!s) return s;
  s = check_margin(mesh, o);
  if (!s) return s;
  BuildReport local;
  BuildReport* r = report ? report : &local;
  *r = BuildReport();
  if (o.method == Method::kObbTree) {
    *tree = baseline_tree(mesh, o);
  } else {
    Estimator est;
    s = make_estimator(mesh, o, &est);
    if (!s) return s;
    r->estimator = est.name;
    s = build_variational_tree(mesh, o, est, tree, &r->search);
    if (!s) return s;
  }
  tree->mesh_sha256 = mesh_sha256(mesh);
  return Status::ok();
}

Status read_queries(const Mesh& mesh, const std::vector<std::string>& paths, BuildOptions* o) {
  const std::string sha = mesh_sha256(mesh);
  std::vector<collision::Collider>& colliders = o->queries;
  colliders.clear();
  for (const std::string& path : paths) {
    collision::QueryStream stream;
    const Status s = collision::read_query_stream(path, &stream);
    if (!s) return s;
    if (stream.mesh_sha256 != sha)
      return Status::error(basename_of(path) + ": recorded for another mesh (sha256 differs)");
    if (colliders.size() + stream.colliders.size() > collision::kMaxRecordedQueries)
      return Status::error("--queries: more than " +
                           std::to_string(collision::kMaxRecordedQueries) + " colliders in all");
    colliders.insert(colliders.end(), stream.colliders.begin(), stream.colliders.end());
  }
  if (colliders.empty()) return Status::error("--queries: the files hold no colliders");
  return Status::ok();
}

Status certify(const Mesh& mesh, const Tree& tree, const CertifyOptions& o,
               exact::Certificate* certificate) {
  if (o.path != exact::OmvPath::kAuto && o.path != exact::OmvPath::kClip &&
      o.path != exact::OmvPath::kNef && o.path != exact::OmvPath::kBoth)
    return Status::error("--path is none of auto, clip, nef, both");
  Status s = check_mesh(mesh);
  if (!s) return s;
  s = check_tree_fits(mesh, tree, o.tree_name);
  if (!s) return s;
  return certify_with(mesh, tree, o, o.checkpoint,
                      std::string(path_name(o.path)) + (o.rational ? "; rational" : ""),
                      certificate);
}

namespace {

// A box's exact OBV for estimate_obv: its enclosure from certify's filter (128 bits, then 256
// where that does not round to one double), and the rational only where an enclosure cannot
// decide a rounding asked of it, or where rational() asks for it.
class ExactObv {
 public:
  ExactObv(const exact::FilteredSolver& filter, const Obb& box)
      : filter_(filter), box_(box), e_(filter.obv(box)) {
    double d;
    if (!e_.exact && e_.bits < MpInterval::kMaxPrec && !e_.value.nearest(&d))
      e_ = filter.obv(box, MpInterval::kMaxPrec);
  }
  double nearest() {
    double d;
    if (!e_.exact && e_.value.nearest(&d)) return d;
    return to_double_nearest(rational_value());
  }
  const Rational& rational() { return rational_value(); }
  // |estimate - OBV| / OBV correctly rounded; NaN where the OBV is 0 (or the estimate not finite).
  double relative_error(double estimate) {
    if (!std::isfinite(estimate)) return std::nan("");
    // Outward ends both 0: the enclosure is [0, 0] (a positive end rounds up above 0, a negative
    // one down below it).
    if (!e_.exact && e_.value.inf() == 0 && e_.value.sup() == 0) return std::nan("");
    if (!e_.exact) {
      try {
        const MpInterval::Precision precision(e_.bits);
        const MpInterval rel = abs(MpInterval(estimate) - e_.value) / e_.value;
        double d;
        if (rel.nearest(&d)) return d;
      } catch (const Undecided&) {  // the enclosure holds 0: the rational decides
      }
    }
    const Rational& q = rational_value();
    if (q == 0) return std::nan("");
    return to_double_nearest(Rational(abs(Rational(estimate) - q) / q));
  }

 private:
  const Rational& rational_value() {
    if (!q_) q_ = e_.exact ? e_.q : filter_.rational().obv(box_);
    return *q_;
  }
  const exact::FilteredSolver& filter_;
  const Obb& box_;
  exact::Enclosed e_;
  std::optional<Rational> q_;
};

}  // namespace

Status estimate_obv(const Mesh& mesh, const std::vector<Obb>& boxes, const EstimateOptions& o,
                    ObvReport* out) {
  *out = ObvReport();
  if (Status s = check_mesh(mesh); !s) return s;
  const size_t n = boxes.size();
  for (const Obb& b : boxes)
    if (const std::string d = box_defect(b); !d.empty()) return Status::error("box refused: " + d);
  for (int m : o.ms)
    if (m < 1 || m > 4096)
      return Status::error("--m " + std::to_string(m) + " is not within 1..4096");
  bool want_cpu = o.cpu;
  std::unique_ptr<detail::GlEstimate> gl;
  if (o.gl) {
    Status s = make_gl(mesh, false, &gl);
    if (!s) {
      if (!o.gl_fallback) return s;
      say(o.note, "warning: " + s.message() + "; using the CPU twin instead");
      want_cpu = true;
    } else {
      say(o.note, gl->description());
      out->renderer = gl->renderer();
      for (int m : o.ms)
        if (m > gl->max_m()) {
          const Status too_big =
              Status::error("--m " + std::to_string(m) + " exceeds the GL estimator's limit " +
                            std::to_string(gl->max_m()) + " on this renderer");
          if (!o.gl_fallback) return too_big;
          say(o.note, "warning: " + too_big.message() + "; using the CPU twin instead");
          gl.reset();
          out->renderer.clear();
          want_cpu = true;
          break;
        }
    }
  }
  // Each batch on every core: values, and the batch's seconds amortised per box.
  auto timed = [n](const std::string& name, int m, const std::function<std::vector<double>()>& f) {
    const auto t0 = std::chrono::steady_clock::now();
    ObvRun r;
    r.backend = name;
    r.m = m;
    r.obv = f();
    r.seconds.assign(n, n ? seconds_since(t0) / n : 0.0);
    return r;
  };
  const bool any_cubemap = want_cpu || gl;
  // The polyhedral solver's enclosures: the poly backend's values, and every cubemap
  // estimate's certified error.
  if (o.poly || any_cubemap) {
    const PolyObvSolver solver(mesh);
    ObvRun r = timed("poly", 0, [&] {
      out->poly = solver.evaluate(boxes);
      std::vector<double> e(n);
      for (size_t i = 0; i < n; ++i) e[i] = out->poly[i].estimate;
      return e;
    });
    if (o.poly) out->runs.push_back(std::move(r));
    for (size_t i = 0; i < n; ++i)
      if (out->poly[i].exact_box)
        say(o.note, "note: box " + std::to_string(i) + ": " + out->poly[i].why +
                        "; its interval comes from the exact rational instead");
  }
  if (want_cpu) {
    const CpuObvEstimator cpu(mesh);
    for (int m : o.ms) out->runs.push_back(timed("cpu", m, [&] { return cpu.estimate(boxes, m); }));
  }
  if (gl)
    for (int m : o.ms) out->runs.push_back(timed("gl", m, [&] { return gl->estimate(boxes, m); }));
  // Each estimate's certified error from the enclosure; R(m) (fast/cubemap_bound.h) when asked.
  std::unique_ptr<BoxPlanner> planner;
  if (o.r_bound && any_cubemap) planner = std::make_unique<BoxPlanner>(mesh);
  out->unresolved.assign(n, 0);
  for (ObvRun& r : out->runs) {
    r.bound.resize(n);
    r.r_bound.assign(n, NAN);
    for (size_t i = 0; i < n; ++i) {
      r.bound[i] = certified_error(r.obv[i], out->poly[i]);
      if (planner && r.m > 0) {
        bool u = false;
        r.r_bound[i] = std::min(cubemap_bound(*planner, r.backend == "gl", boxes[i], r.m, &u),
                                range_bound(boxes[i], r.obv[i]));
        out->unresolved[i] |= u;
      }
    }
  }
  for (size_t i = 0; i < n; ++i)
    if (out->unresolved[i])
      say(o.note, "warning: box " + std::to_string(i) +
                      ": its view of the mesh does not fit the cubemap's doubles (faces beyond "
                      "2^300 box units); "
                      "estimated at half its volume");
  if (o.exact) {
    out->exact.assign(n, 0.0);
    out->exact_seconds.assign(n, 0.0);
    if (o.rational) out->exact_rational.assign(n, Rational(0));
    for (ObvRun& run : out->runs) run.rel_error.assign(n, std::nan(""));
    const exact::FilteredSolver filter(mesh);
    tbb::parallel_for(size_t{0}, n, [&](size_t i) {
      const auto t0 = std::chrono::steady_clock::now();
      ExactObv x(filter, boxes[i]);
      out->exact[i] = x.nearest();
      if (o.rational) out->exact_rational[i] = x.rational();
      for (ObvRun& run : out->runs) run.rel_error[i] = x.relative_error(run.obv[i]);
      out->exact_seconds[i] = seconds_since(t0);
    });
  }
  return Status::ok();
}

std::vector<std::string> compare_checkpoint_files() {
  std::vector<std::string> files = {"state.json"};
  for (const char* method : {"obbtree", "variational"})
    for (const char* name : {"obv.json", "layers.json"})
      files.push_back(certify_folder("", method) + "/" + name);
  return files;
}

const exact::LayerCertificate& CompareResult::layer(int tree, size_t level) const {
  const auto& layers = certificates[tree].layers;
  VOBB_ASSERT(!layers.empty(), "layer() of a comparison that compare() filled in");
  return layers[std::min(level, layers.size() - 1)];
}

Status compare(const Mesh& mesh, const CompareOptions& co, CompareResult* r) {
  *r = CompareResult();
  BuildOptions o = co.build;
  o.method = Method::kVariational;
  if (!o.queries.empty()) return Status::error("--queries applies to build only");
  Status s = check_build_options(o);
  if (!s) return s;
  s = check_mesh(mesh);
  if (!s) return s;
  s = check_margin(mesh, o);
  if (!s) return s;
  Estimator est;
  s = make_estimator(mesh, o, &est);
  if (!s) return s;
  if (!o.checkpoint.empty()) {
    s = check_compare_checkpoint(mesh, o, est.name);
    if (!s) return s;
  }
  CertifyOptions copt;
  copt.rational = co.rational;
  copt.progress = co.progress;
  copt.note = o.warning;  // a resumed certification is said even where notes are not
  copt.warning = o.warning;
  copt.saved = co.certify_saved;
  for (int i = 0; i < 2; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    if (i == 0) {
      r->trees[0] = baseline_tree(mesh, o);
    } else {
      s = build_variational_tree(mesh, o, est, &r->trees[1], &r->search);
      if (!s) return s;
    }
    r->build_seconds[i] = seconds_since(t0);
    // With a checkpoint, each tree's certification keeps its own folder beside the build's
    // state. Its fingerprint hashes the tree without its mesh hash, as compare's checkpoints
    // always have (the mesh is named in the fingerprint on its own).
    const std::string folder =
        o.checkpoint.empty() ? std::string() : certify_folder(o.checkpoint, r->trees[i].method);
    s = certify_with(mesh, r->trees[i], copt, folder, co.rational ? "auto; rational" : "auto",
                     &r->certificates[i]);
    if (!s) return s;
  }
  const std::string sha = mesh_sha256(mesh);
  for (Tree& t : r->trees) t.mesh_sha256 = sha;
  r->levels = std::max(r->certificates[0].layers.size(), r->certificates[1].layers.size());
  // e over layers 0 .. D of the deeper tree, with its weights. For a tree of depth D this is
  // certify's e. Its enclosure gives the nearest double; where it cannot (a rounding tie within
  // 1e-35), or with `rational`, the layers' rationals do.
  const int depth = static_cast<int>(r->levels) - 1;
  for (int i = 0; i < 2; ++i) {
    MpInterval e(0);
    for (size_t l = 0; l < r->levels; ++l)
      e += MpInterval(layer_weight(depth, static_cast<int>(l))) * r->layer(i, l).omv_enclosure;
    if (e.nearest(&r->e[i]) && !co.rational) continue;
    if (!r->certificates[i].rational) {
      CertifyOptions again = copt;
      again.rational = true;
      s = certify_with(mesh, r->trees[i], again, "", "", &r->certificates[i]);
      if (!s) return s;
    }
    std::vector<Rational> omv;
    for (size_t l = 0; l < r->levels; ++l) omv.push_back(r->layer(i, l).omv);
    r->e_exact[i] = tree_error(omv);
    r->e[i] = to_double_nearest(r->e_exact[i]);
    r->e_rational[i] = true;
  }
  return Status::ok();
}

}  // namespace vobb
