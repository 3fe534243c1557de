// vobb — the command line. Thin: each subcommand parses its arguments, calls the libraries
// and prints. Exit codes (DESIGN §7): 0 ok, 1 a check failed, 2 bad input or usage, with a
// one-line reason on stderr naming the file and the defect.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <chrono>
#include <cmath>
#include <memory>
#include <new>
#include <cstdio>
#include <cstdlib>
#include <csignal>
#include <exception>
#include <filesystem>
#include <optional>
#include <string>

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <functional>
#include <unistd.h>

#include "app/cli_support.h"
#include "common/atomic_file.h"
#include "common/box_export.h"
#include "common/io/mesh_report.h"
#include "common/png_io.h"
#include "common/sha256.h"
#include "common/text_util.h"
#include "common/tree_io.h"
#include "exact/certify.h"
#include "exact/outer_volume.h"
#include "fast/cpu_estimator.h"
#include "fast/gl_estimator.h"
#include "fast/poly_overlap.h"
#include "fast/poly_solver.h"
#include "fast/obbtree_builder.h"
#include "fast/tree_figure.h"
#include "fast/variational_builder.h"
#include "vobb/config.h"
#include "app/validate_command.h"
#include "validate/estimators.h"
#include "app/collide_command.h"
#include "validate/collision/query_objective.h"
#include "common/stopwatch.h"

namespace {

using vobb::seconds_since;

using vobb::app::kExitBadInput;
using vobb::app::kExitCheckFailed;
using vobb::app::kExitCouldNotFinish;
using vobb::app::kExitOk;
using vobb::app::one_line;
using vobb::app::refuse;

int run_info(const std::string& mesh, bool json, bool rational) {
  vobb::MeshReport report;
  vobb::Status s = vobb::inspect_mesh(mesh, &report);
  if (!s) return refuse(s);
  const std::string out = json ? vobb::format_report_json(report, rational)
                               : vobb::format_report_text(report, rational);
  std::fputs(out.c_str(), stdout);
  s = vobb::solidity_status(report);
  return s ? kExitOk : refuse(s);
}

struct BuildFlags {
  std::string method = "variational";
  int depth = 8, arity = 2, m = 32, lloyd = 4;
  uint64_t seed = 1;
  std::string backend = "auto";
  bool no_axis_search = false, adjust = false, no_merge = false, quiet = false;
  int sweeps = 3;
  int threads = 0;             // CPU twin's threads; 0: all the cores this process may use
  double collider_margin = 0;  // world units; 0: the paper's objective
  std::string objective = "obv";  // obv: sum of OBV; omv: less each pair's overlap term
  // Query files (validate/collision/query_objective.h): when given, the objective is the
  // recorded queries that hit each box, not its OBV, and no OBV estimator is made.
  std::vector<std::string> queries;
  std::string queries_digest;  // SHA-256 of the colliders read from them, for the fingerprint
  std::string checkpoint;    // folder; empty: none
  double time_budget = 0;    // seconds; 0: none
};

// Which GL the run got, on stderr (the library prints nothing).
void say_renderer(const vobb::GlContext& gl) {
  std::fprintf(stderr, "vobb: GL renderer: %s (EGL %s, OpenGL %s)\n", gl.renderer().c_str(), gl.platform().c_str(),
               gl.version().c_str());
}

// From this m on, `--backend auto` builds with GL where there is a GPU. Below it the CPU twin
// is as fast or faster even beside a GPU. With both searching the nodes of a level at once, an
// NVIDIA H100 with 16 cores built dino at depth 8 and m = 32 in 3.8 s (twin) against 4.9 s
// (GL), and at depth 6 and m = 64 in 3.3 s against 3.7 s; at m = 128 GL took 4.5 s against
// 7.0 s, and at 256 8.0 s against 15.7 s (docs/BENCHMARKS.md; the twin's times come from
// another machine of that kind, so the small gaps are rough). With fewer cores the twin slows
// and GL hardly does.
constexpr int kAutoGlFromM = 128;

const char* const kObjectiveHelp =
    "What the variational search minimises per set of boxes: obv (the sum of their OBV) or omv (that sum less "
    "what each shares outside the solid with those before it, by the polyhedral solver: their OMV)";

// The OBV estimator that the variational builder runs in its loop. auto: the GL estimator on an
// EGL device (a GPU) from m = kAutoGlFromM; below that m, on llvmpipe, or without a context,
// the CPU twin, which is faster there (docs/BENCHMARKS.md) and gives the same texels in double.
// No GL context is made where the CPU twin is chosen by m.
vobb::Status make_estimator(const vobb::Mesh& mesh, const BuildFlags& f, std::unique_ptr<vobb::GlObvEstimator>* gl,
                            std::unique_ptr<vobb::CpuObvEstimator>* cpu, std::unique_ptr<vobb::PolyObvSolver>* poly,
                            vobb::ObvEstimate* estimate) {
  if (f.backend == "poly") {  // the polyhedral solver's double evaluation: no m, no GL
    *poly = std::make_unique<vobb::PolyObvSolver>(mesh);
    const vobb::PolyObvSolver* p = poly->get();
    *estimate = [p](const std::vector<vobb::Obb>& boxes) { return p->estimate(boxes); };
    return vobb::Status::ok();
  }
  if (f.backend == "gl" || (f.backend == "auto" && f.m >= kAutoGlFromM)) {
    vobb::Status s = vobb::GlObvEstimator::create(mesh, gl, /*device_only=*/f.backend == "auto");
    if (!s && f.backend == "gl") return s;
    if (s && f.m > (*gl)->max_m())
      return vobb::Status::error("--m " + std::to_string(f.m) + " exceeds the GL estimator's limit");
    if (s && !f.quiet) say_renderer((*gl)->context());
  }
  const int m = f.m;
  if (*gl) {
    vobb::GlObvEstimator* g = gl->get();
    *estimate = [g, m](const std::vector<vobb::Obb>& boxes) { return g->estimate(boxes, m); };
  } else {
    *cpu = std::make_unique<vobb::CpuObvEstimator>(mesh);
    const vobb::CpuObvEstimator* c = cpu->get();
    *estimate = [c, m](const std::vector<vobb::Obb>& boxes) { return c->estimate(boxes, m); };
  }
  return vobb::Status::ok();
}

// Makes a --checkpoint folder (and its parents) if it is not there, and clears it of the
// temporary files of runs killed mid-write.
vobb::Status make_checkpoint_folder(const std::string& folder) {
  std::error_code ec;
  std::filesystem::create_directories(folder, ec);
  if (ec) return vobb::Status::error(folder + ": cannot make the checkpoint folder: " + ec.message());
  // Refused now, not warned about at every save of a run that could never resume (a folder
  // such as /sys/kernel exists and takes no file).
  if (vobb::Status s = vobb::app::check_folder_takes_files("--checkpoint " + folder, folder); !s) return s;
  // A run killed while it wrote a checkpoint left its temporary file here.
  vobb::remove_stray_temporaries(folder);
  return vobb::Status::ok();
}

// What a variational build depends on, for its checkpoints: a state saved under another
// fingerprint is refused, so a resumed build is the build that was interrupted.
std::string build_fingerprint(const vobb::Mesh& mesh, const BuildFlags& f, const vobb::GlObvEstimator* gl) {
  // "builder 2": bump when the builder's decisions change, so that older states are refused.
  return "builder 2; mesh " + vobb::mesh_sha256(mesh) + "; depth " + std::to_string(f.depth) + "; arity " + std::to_string(f.arity) +
         "; lloyd " + std::to_string(f.lloyd) + "; seed " + std::to_string(f.seed) + "; axis search " +
         (f.no_axis_search ? "off" : "on") + "; adjust " + (f.adjust ? "on" : "off") + "; merge " +
         (f.no_merge ? "off" : "on") + "; sweeps " + std::to_string(f.sweeps) + "; m " + std::to_string(f.m) +
         "; estimator " + (gl ? "gl " + gl->renderer() : f.backend == "poly" ? std::string("poly") : std::string("cpu")) +
         // Named only when set, so that states saved before the option existed still resume.
         (f.collider_margin > 0 ? "; collider margin " + vobb::format_double(f.collider_margin) : std::string()) +
         (f.queries.empty() ? std::string() : "; recorded queries " + f.queries_digest) +
         (f.objective == "omv" ? "; objective omv" : "");
}

vobb::Status build_tree(const vobb::Mesh& mesh, const BuildFlags& f, const vobb::ObvEstimate& estimate,
                        const vobb::GlObvEstimator* gl, vobb::Tree* tree) {
  if (f.method == "obbtree") {
    vobb::ObbTreeOptions opt;
    opt.depth = f.depth;
    opt.arity = f.arity;
    *tree = vobb::build_obbtree(mesh, opt);
    return vobb::Status::ok();
  }
  vobb::VariationalOptions opt;
  opt.depth = f.depth;
  opt.arity = f.arity;
  opt.lloyd_iterations = f.lloyd;
  opt.optimise_axes = !f.no_axis_search;
  opt.adjust = f.adjust;
  opt.merge = !f.no_merge;
  opt.max_sweeps = f.sweeps;
  opt.seed = f.seed;
  opt.margin = f.collider_margin;
  // The overlap-aware objective's shares: the polyhedral solver's doubles, whatever the OBV
  // estimator (the cubemap has no form for them).
  std::unique_ptr<vobb::PolyOverlapSolver> pairs;
  if (f.objective == "omv") {
    opt.objective = vobb::Objective::kOmv;
    pairs = std::make_unique<vobb::PolyOverlapSolver>(mesh);
    const vobb::PolyOverlapSolver* p = pairs.get();
    opt.share = [p](const std::vector<vobb::ShareQuery>& v) { return p->estimate(v); };
  }
  opt.concurrent_estimates = true;  // both estimators may be called from several threads at once
  const auto t0 = std::chrono::steady_clock::now();
  if (f.time_budget > 0) opt.out_of_time = [&] { return seconds_since(t0) > f.time_budget; };
  // On a terminal the line is redrawn in place twice a second; into a file or a pipe it is
  // a line of its own every 30 s, so a log stays readable.
  const bool tty = ::isatty(::fileno(stderr)) != 0;
  const double every = tty ? 0.5 : 30.0;
  const char* start = tty ? "\r" : "";
  const char* end = tty ? "     " : "\n";
  double last = -1, done0 = -1, sweep_t0 = 0;
  int sweep_seen = 0;
  if (!f.quiet)
    opt.progress = [&](const vobb::VariationalProgress& p) {
      const double now = seconds_since(t0);
      if (p.sweep != sweep_seen) {  // a new sweep: its pace is measured from here
        sweep_seen = p.sweep;
        sweep_t0 = now;
      }
      if (last >= 0 && now - last < every) return;
      last = now;
      if (done0 < 0) done0 = p.done;
      // Remaining: this run's pace over what is still to do, in the top-down pass or in the
      // current sweep (how many sweeps run depends on their gains: at most --sweeps).
      char eta[64] = "";
      if (p.sweep == 0) {
        if (p.done - done0 > 0.02)
          std::snprintf(eta, sizeof eta, "  ~%.0f s left to split", now * (1 - p.done) / (p.done - done0));
        std::fprintf(stderr, "%svobb: level %d/%d  nodes done %zu/%zu  iteration %d/%d  sum %s %.6g  %.1f s%s%s", start,
                     p.level, f.depth, p.node, p.nodes, p.iteration, f.lloyd,
                     !f.queries.empty()          ? "hits"
                     : f.objective == "omv"      ? (f.collider_margin > 0 ? "grown OMV" : "OMV")
                     : f.collider_margin > 0     ? "grown OBV"
                                                 : "OBV",
                     p.sum_obv, now, eta, end);
      } else {
        if (p.sweep_done > 0.02)
          std::snprintf(eta, sizeof eta, "  ~%.0f s left in this sweep",
                        (now - sweep_t0) * (1 - p.sweep_done) / p.sweep_done);
        std::fprintf(stderr, "%svobb: merging sweep %d (at most %d)  level %d  nodes done %zu/%zu  %.1f s%s%s", start,
                     p.sweep, f.sweeps, p.level, p.node, p.nodes, now, eta, tty ? "                    " : "\n");
      }
      std::fflush(stderr);
    };
  vobb::VariationalState resume;
  bool resuming = false;
  std::string state_path;
  vobb::Status save_error = vobb::Status::ok();
  if (!f.checkpoint.empty()) {
    vobb::Status made = make_checkpoint_folder(f.checkpoint);
    if (!made) return made;
    state_path = (std::filesystem::path(f.checkpoint) / "state.json").string();
    const std::string fingerprint = build_fingerprint(mesh, f, gl);
    vobb::Status s = vobb::read_variational_state(state_path, fingerprint, mesh.faces.size(), f.arity, f.depth, &resume,
                                                  &resuming);
    if (!s) return s;
    if (resuming && !f.quiet)
      std::fprintf(stderr, "vobb: resuming from %s (%d levels split, %d sweeps done)\n", state_path.c_str(),
                   resume.split_levels, resume.sweeps);
    // Test hook: VOBB_TEST_KILL_AT_SPLIT_LEVELS=N kills the process (SIGKILL, as an outside
    // kill would) right after the state with N levels split is saved, so the resume test
    // interrupts the build at a known point instead of racing it.
    const char* kill_env = std::getenv("VOBB_TEST_KILL_AT_SPLIT_LEVELS");
    const int kill_at = kill_env != nullptr ? std::atoi(kill_env) : -1;
    opt.checkpoint = [&, fingerprint, kill_at](const vobb::VariationalState& st) {
      vobb::Status w = vobb::write_variational_state(st, fingerprint, state_path);
      if (!w && save_error) {
        save_error = w;
        // On a terminal the progress line is still open: end it first.
        std::fprintf(stderr, "%svobb: warning: checkpoint not saved: %s\n", tty && last >= 0 ? "\n" : "",
                     one_line(w.message()).c_str());
      }
      if (w && st.split_levels == kill_at) ::raise(SIGKILL);
    };
  }
  vobb::VariationalReport report;
  *tree = vobb::build_variational(mesh, opt, estimate, resuming ? &resume : nullptr, &report);
  vobb::Status valid = vobb::validate_tree(*tree, "variational tree");
  VOBB_ASSERT(valid, valid.message().c_str());  // a builder bug, not bad input
  if (!f.quiet && last >= 0 && tty) std::fprintf(stderr, "\n");
  if (!f.quiet)
    std::fprintf(stderr,
                 "vobb: %zu boxes estimated (%zu more measured again, from the search's record), %zu shares of "
                 "overlap estimated, %zu adjusted splits and %zu merges kept, %d sweeps (%zu regroupings unchanged since they "
                 "found no move, not run again)%s\n",
                 report.estimates, report.reused, report.overlaps, report.adjustments, report.merges, report.sweeps,
                 report.regroups_skipped,
                 report.budget_spent ? "; time budget spent: the rest got the baseline split" : "");
  return vobb::Status::ok();
}

// Reads the --queries files for `mesh` into one stream; sets f->queries_digest.
vobb::Status read_queries(const vobb::Mesh& mesh, BuildFlags* f, std::vector<vobb::collision::Collider>* colliders) {
  const std::string sha = vobb::mesh_sha256(mesh);
  colliders->clear();
  for (const std::string& path : f->queries) {
    vobb::collision::QueryStream stream;
    vobb::Status s = vobb::collision::read_query_stream(path, &stream);
    if (!s) return s;
    if (stream.mesh_sha256 != sha)
      return vobb::Status::error(vobb::basename_of(path) + ": recorded for another mesh (sha256 differs)");
    if (colliders->size() + stream.colliders.size() > vobb::collision::kMaxRecordedQueries)
      return vobb::Status::error("--queries: more than " + std::to_string(vobb::collision::kMaxRecordedQueries) +
                                 " colliders in all");
    colliders->insert(colliders->end(), stream.colliders.begin(), stream.colliders.end());
  }
  if (colliders->empty()) return vobb::Status::error("--queries: the files hold no colliders");
  std::string bytes;
  for (const vobb::collision::Collider& c : *colliders) {
    double v[17] = {c.shape == vobb::collision::ColliderShape::kSphere ? 0.0 : 1.0, c.center[0], c.center[1], c.center[2],
                    c.radius, c.half[0], c.half[1], c.half[2]};
    for (int k = 0; k < 3; ++k)
      for (int i = 0; i < 3; ++i) v[8 + 3 * k + i] = c.axes[k][i];
    bytes.append(reinterpret_cast<const char*>(v), sizeof v);
  }
  f->queries_digest = vobb::sha256_hex(bytes.data(), bytes.size());
  return vobb::Status::ok();
}

int run_build(const std::string& mesh_path, const std::string& out, BuildFlags f) {
  const auto t0 = std::chrono::steady_clock::now();
  if (!std::isfinite(f.collider_margin) || f.collider_margin < 0)
    return refuse(vobb::Status::error("--collider-margin must be a finite length >= 0"));
  if (f.collider_margin > 0 && f.method != "variational")
    return refuse(vobb::Status::error("--collider-margin applies to --method variational only"));
  if (!f.queries.empty() && f.method != "variational")
    return refuse(vobb::Status::error("--queries applies to --method variational only"));
  if (!f.queries.empty() && f.collider_margin > 0)
    return refuse(vobb::Status::error("--queries and --collider-margin are two objectives; choose one"));
  if (f.objective == "omv" && f.method != "variational")
    return refuse(vobb::Status::error("--objective applies to --method variational only"));
  if (!f.queries.empty() && f.objective == "omv")
    return refuse(vobb::Status::error("--queries and --objective omv are two objectives; choose one"));
  // The baseline takes well under a second and has no search to budget or resume.
  if (!f.checkpoint.empty() && f.method != "variational")
    return refuse(vobb::Status::error("--checkpoint applies to --method variational only"));
  if (f.time_budget > 0 && f.method != "variational")
    return refuse(vobb::Status::error("--time-budget applies to --method variational only"));
  vobb::LoadedMesh loaded;
  vobb::Status s = vobb::load_solid(mesh_path, &loaded);
  if (!s) return refuse(s);
  vobb::app::note_precision(mesh_path, loaded);
  if (f.collider_margin > 0) {
    // A margin beyond the model's size is no collider of this model, and it keeps the grown
    // boxes' volumes far from overflow.
    const vobb::Aabb box = loaded.mesh.bounds();
    const double diagonal = (box.hi - box.lo).norm();
    if (f.collider_margin > diagonal)
      return refuse(vobb::Status::error("--collider-margin " + vobb::format_double(f.collider_margin) +
                                        " exceeds the mesh's bounding-box diagonal " + vobb::format_double(diagonal)));
  }
  std::unique_ptr<vobb::GlObvEstimator> gl;
  std::unique_ptr<vobb::CpuObvEstimator> cpu;
  std::unique_ptr<vobb::PolyObvSolver> poly;
  std::unique_ptr<vobb::collision::QueryHitObjective> hits;
  vobb::ObvEstimate estimate;
  if (!f.queries.empty()) {
    std::vector<vobb::collision::Collider> colliders;
    s = read_queries(loaded.mesh, &f, &colliders);
    if (!s) return refuse(s);
    hits = std::make_unique<vobb::collision::QueryHitObjective>(loaded.mesh, colliders);
    if (!f.quiet) std::fprintf(stderr, "vobb: objective: the hits of %zu recorded queries (no OBV estimator)\n", hits->size());
    const vobb::collision::QueryHitObjective* h = hits.get();
    estimate = [h](const std::vector<vobb::Obb>& boxes) { return (*h)(boxes); };
  } else if (f.method == "variational") {
    s = make_estimator(loaded.mesh, f, &gl, &cpu, &poly, &estimate);
    if (!s) return refuse(s);
  }
  vobb::Tree tree;
  s = build_tree(loaded.mesh, f, estimate, gl.get(), &tree);
  if (!s) return refuse(s);
  tree.mesh_sha256 = vobb::mesh_sha256(loaded.mesh);
  s = vobb::write_tree(tree, out);
  if (!s) return vobb::app::could_not_finish(s);  // its folder took a file when the run started
  std::fprintf(stderr, "vobb: %s tree of %zu nodes, depth %d, arity %d, in %.3f s -> %s\n",
               tree.method.c_str(), tree.nodes.size(), tree.depth, tree.arity, seconds_since(t0),
               out.c_str());
  return kExitOk;
}

int run_export(const std::string& tree_path, int level, const std::string& out) {
  vobb::Tree tree;
  vobb::Status s = vobb::read_tree(tree_path, &tree);
  if (!s) return refuse(s);
  if (level < 0 || level > tree.depth)
    return refuse(vobb::Status::error("--level " + std::to_string(level) + ": " + vobb::basename_of(tree_path) +
                                      " has levels 0 to " + std::to_string(tree.depth)));
  s = vobb::export_layer(tree, level, out);
  if (!s) return vobb::app::could_not_finish(s);  // the level and the format were checked before
  std::fprintf(stderr, "vobb: layer %d (%zu boxes) -> %s\n", level, vobb::layer(tree, level).size(),
               out.c_str());
  return kExitOk;
}

// Loads a solid mesh and a tree and checks that the tree indexes this mesh.
vobb::Status load_mesh_and_tree(const std::string& mesh_path, const std::string& tree_path,
                                vobb::LoadedMesh* mesh, vobb::Tree* tree) {
  vobb::Status s = vobb::load_solid(mesh_path, mesh);
  if (!s) return s;
  vobb::app::note_precision(mesh_path, *mesh);
  s = vobb::read_tree(tree_path, tree);
  if (!s) return s;
  if (tree->mesh_triangles != mesh->mesh.faces.size())
    return vobb::Status::error(tree_path + ": tree indexes " + std::to_string(tree->mesh_triangles) +
                               " triangles but the mesh has " + std::to_string(mesh->mesh.faces.size()));
  if (!tree->mesh_sha256.empty() && tree->mesh_sha256 != vobb::mesh_sha256(mesh->mesh))
    return vobb::Status::error(tree_path + ": built for another mesh (sha256 differs)");
  return vobb::Status::ok();
}

// A certification's checkpoint in `folder` (certify --checkpoint, and compare's per tree):
// loads what is saved into *resume and points `opt` at it, and saves after each stage. The
// fingerprint names the mesh, the tree and the path.
struct CertifySaver {
  CertifySaver() = default;
  CertifySaver(const CertifySaver&) = delete;  // opt's resume pointer and callback point into it
  CertifySaver& operator=(const CertifySaver&) = delete;
  vobb::exact::CertifyState resume;
  std::unique_ptr<vobb::exact::CertifyCheckpoint> files;
  bool warned = false;

  vobb::Status attach(const std::string& folder, const vobb::Mesh& mesh, const vobb::Tree& tree,
                      const std::string& path, vobb::exact::CertifyOptions* opt) {
    vobb::Status s = make_checkpoint_folder(folder);
    if (!s) return s;
    const std::string tree_json = vobb::tree_to_json(tree);
    files = std::make_unique<vobb::exact::CertifyCheckpoint>(
        folder, std::string(vobb::exact::kCertifyVersion) + "; mesh " + vobb::mesh_sha256(mesh) + "; tree " +
                    vobb::sha256_hex(tree_json.data(), tree_json.size()) + "; path " + path);
    bool resuming = false;
    s = files->load(tree, &resume, &resuming);
    if (!s) return s;
    opt->resume = resuming ? &resume : nullptr;
    // Said even with --quiet: it is what the certificate rests on, not progress.
    if (resuming)
      std::fprintf(stderr, "vobb: resuming from %s (the boxes' OBV, %zu of %d layers done)\n", folder.c_str(),
                   resume.layers.size(), tree.depth + 1);
    // Test hook: VOBB_TEST_KILL_AFTER_CERTIFIED_LAYERS=N kills the process (SIGKILL, as an
    // outside kill would) right after a state with N finished layers is saved.
    const char* kill_env = std::getenv("VOBB_TEST_KILL_AFTER_CERTIFIED_LAYERS");
    const long kill_at = kill_env != nullptr ? std::atol(kill_env) : -1;
    opt->checkpoint = [this, kill_at](const vobb::exact::CertifyState& st) {
      const vobb::Status w = files->save(st);
      if (!w && !warned) {
        warned = true;
        std::fprintf(stderr, "vobb: warning: checkpoint not saved: %s\n", one_line(w.message()).c_str());
      }
      if (w && !st.obv.empty() && static_cast<long>(st.layers.size()) == kill_at) ::raise(SIGKILL);
    };
    return vobb::Status::ok();
  }
};

int run_certify(const std::string& mesh_path, const std::string& tree_path, bool json, bool rational,
                const std::string& path, const std::string& checkpoint, bool quiet) {
  vobb::LoadedMesh mesh;
  vobb::Tree tree;
  vobb::Status s = load_mesh_and_tree(mesh_path, tree_path, &mesh, &tree);
  if (!s) return refuse(s);
  vobb::exact::CertifyOptions opt;
  opt.path = path == "clip" ? vobb::exact::OmvPath::kClip
             : path == "nef" ? vobb::exact::OmvPath::kNef
             : path == "both" ? vobb::exact::OmvPath::kBoth
                              : vobb::exact::OmvPath::kAuto;
  if (!quiet) opt.progress = [](const std::string& line) { std::fprintf(stderr, "certify: %s\n", line.c_str()); };
  CertifySaver saver;
  if (!checkpoint.empty()) {
    s = saver.attach(checkpoint, mesh.mesh, tree, path + (rational ? "; rational" : ""), &opt);
    if (!s) return refuse(s);
  }
  opt.rational = rational;
  const vobb::exact::Certificate c = vobb::exact::certify(mesh.mesh, tree, opt);
  auto enclosure = [](const vobb::exact::MpInterval& x) { return nlohmann::ordered_json::array({x.inf(), x.sup()}); };
  if (json) {
    nlohmann::ordered_json j;
    nlohmann::ordered_json levels = nlohmann::ordered_json::array();
    for (const auto& l : c.layers) {
      nlohmann::ordered_json jl;
      jl["level"] = l.level;
      jl["boxes"] = l.boxes;
      jl["omv"] = l.omv_nearest;
      jl["sum_obv"] = l.sum_obv_nearest;
      jl["overlap"] = l.overlap_nearest;
      // Outward doubles around the exact values, and what decided the doubles above.
      jl["omv_enclosure"] = enclosure(l.omv_enclosure);
      jl["sum_obv_enclosure"] = enclosure(l.sum_obv_enclosure);
      jl["overlap_enclosure"] = enclosure(l.overlap_enclosure);
      jl["omv_rounded_by"] = l.omv_rounded_by;
      jl["sum_obv_rounded_by"] = l.sum_obv_rounded_by;
      jl["overlap_rounded_by"] = l.overlap_rounded_by;
      jl["upper_bound_holds"] = l.upper_bound_holds();
      jl["bound_by"] = l.bound_by;
      jl["exact_obv"] = l.exact_obv;
      jl["exact_overlap"] = l.exact_overlap;
      jl["refined_obv"] = l.refined_obv;
      jl["refined_overlap"] = l.refined_overlap;
      jl["overlapping_boxes"] = l.overlapping_boxes;
      jl["omv_path"] = l.omv_path;
      if (l.omv_path == "both") {
        jl["paths_agree"] = l.paths_agree;
        jl["omv_clip"] = vobb::to_double_nearest(l.omv_clip);  // omv is Nef's, the arbiter's
      }
      jl["seconds"] = l.seconds;
      if (rational) {
        jl["omv_rational"] = l.omv.get_str();
        jl["sum_obv_rational"] = l.sum_obv.get_str();
        jl["overlap_rational"] = l.overlap().get_str();
        if (l.omv_path == "both") jl["omv_clip_rational"] = l.omv_clip.get_str();
      }
      levels.push_back(jl);
    }
    j["levels"] = levels;
    j["mesh_single_precision"] = mesh.single_precision;
    j["weighted_error"] = c.weighted_error_nearest;
    j["weighted_error_enclosure"] = enclosure(c.weighted_error_enclosure);
    j["weighted_error_rounded_by"] = c.weighted_error_rounded_by;
    if (rational) j["weighted_error_rational"] = c.weighted_error.get_str();
    j["exact_obv"] = c.exact_obv;
    nlohmann::ordered_json first = nlohmann::ordered_json::array();
    for (const auto& [node, face] : c.containment.first) first.push_back({{"node", node}, {"face", face}});
    j["containment"] = {{"ok", c.containment.ok()}, {"violations", c.containment.violations},
                        {"checked_pairs", c.containment.checked_pairs}, {"first", first}};
    j["seconds"] = c.seconds;
    std::printf("%s\n", vobb::app::report_json(j).c_str());
  } else {
    std::printf("%5s %7s %24s %24s %24s %6s\n", "level", "boxes", "OMV", "sum OBV", "overlap", "bound");
    for (const auto& l : c.layers)
      std::printf("%5d %7zu %24.17g %24.17g %24.17g %6s\n", l.level, l.boxes, l.omv_nearest, l.sum_obv_nearest,
                  l.overlap_nearest, l.upper_bound_holds() ? "holds" : "FAILS");
    std::printf("weighted error e: %.17g\n", c.weighted_error_nearest);
    if (rational) std::printf("e (rational): %s\n", c.weighted_error.get_str().c_str());
    std::printf("containment: %s (%zu violations in %zu node-face pairs)", c.containment.ok() ? "ok" : "FAILED",
                c.containment.violations, c.containment.checked_pairs);
    for (const auto& [node, face] : c.containment.first) std::printf(" [node %d face %d]", node, face);
    std::printf("\nseconds: %.3f\n", c.seconds);
  }
  if (!c.ok()) {
    std::fprintf(stderr, "vobb: %s: certification failed\n", one_line(tree_path).c_str());
    return kExitCheckFailed;
  }
  return kExitOk;
}

// The certified error of an estimate E: max(|E - lo|, |E - hi|) for an enclosure [lo, hi] of the
// exact OBV, rounded up (one ulp above the nearest double is above the true value).
double certified_error(double e, const vobb::PolyObv& r) {
  const double d = std::max(std::abs(e - r.lo), std::abs(e - r.hi));
  return d == 0 ? 0.0 : std::nextafter(d, INFINITY);
}

int run_obv(const std::string& mesh_path, const std::string& boxes_path, const std::vector<int>& ms,
            const std::string& backend, bool json, bool rational, bool r_bound) {
  vobb::LoadedMesh mesh;
  vobb::Status s = vobb::load_solid(mesh_path, &mesh);
  if (!s) return refuse(s);
  vobb::app::note_precision(mesh_path, mesh);
  std::vector<vobb::Obb> boxes;
  s = vobb::read_boxes(boxes_path, &boxes);
  if (!s) return refuse(s);
  const bool want_exact = backend == "exact" || backend == "all";
  const bool want_poly = backend == "poly" || backend == "all";
  bool want_cpu = backend == "cpu" || backend == "all";
  // A GL context only where GL is asked for; auto and all fall back to the CPU twin.
  std::unique_ptr<vobb::GlObvEstimator> gl;
  if (backend == "gl" || backend == "auto" || backend == "all") {
    s = vobb::GlObvEstimator::create(mesh.mesh, &gl);
    if (!s) {
      if (backend == "gl") return refuse(s);
      std::fprintf(stderr, "vobb: warning: %s; using the CPU twin instead\n", s.message().c_str());
      want_cpu = true;
    } else {
      say_renderer(gl->context());
      for (int m : ms)
        if (m > gl->max_m()) {
          const vobb::Status too_big = vobb::Status::error("--m " + std::to_string(m) + " exceeds the GL estimator's limit " +
                                                           std::to_string(gl->max_m()) + " on this renderer");
          if (backend == "gl") return refuse(too_big);
          std::fprintf(stderr, "vobb: warning: %s; using the CPU twin instead\n", too_big.message().c_str());
          gl.reset();
          want_cpu = true;
          break;
        }
    }
  }
  const size_t n = boxes.size();
  // Estimates per backend and m, each batch on every core: values, and the batch's seconds
  // amortised per box.
  struct Run {
    std::string backend;
    int m;  // 0: none (the polyhedral solver)
    std::vector<double> obv, seconds;
  };
  auto timed = [n](const std::string& name, int m, const std::function<std::vector<double>()>& f) {
    const auto t0 = std::chrono::steady_clock::now();
    Run r{name, m, f(), {}};
    r.seconds.assign(n, n ? seconds_since(t0) / n : 0.0);
    return r;
  };
  std::vector<Run> runs;
  const bool any_cubemap = want_cpu || gl;
  // The polyhedral solver's enclosures: the poly backend's values, and every cubemap
  // estimate's certified error.
  std::vector<vobb::PolyObv> poly;
  if (want_poly || any_cubemap) {
    const vobb::PolyObvSolver solver(mesh.mesh);
    Run r = timed("poly", 0, [&] {
      poly = solver.evaluate(boxes);
      std::vector<double> e(n);
      for (size_t i = 0; i < n; ++i) e[i] = poly[i].estimate;
      return e;
    });
    if (want_poly) runs.push_back(std::move(r));
    for (size_t i = 0; i < n; ++i)
      if (poly[i].exact_box)
        std::fprintf(stderr, "vobb: note: box %zu: %s; its interval comes from the exact rational instead\n", i,
                     poly[i].why.c_str());
  }
  if (want_cpu) {
    const vobb::CpuObvEstimator cpu(mesh.mesh);
    for (int m : ms) runs.push_back(timed("cpu", m, [&] { return cpu.estimate(boxes, m); }));
  }
  if (gl)
    for (int m : ms) runs.push_back(timed("gl", m, [&] { return gl->estimate(boxes, m); }));
  // Each estimate's certified error from the enclosure; R(m), the texel bound of
  // validate/estimators.h, only when asked for.
  std::vector<std::vector<double>> bound, rbound;
  std::optional<vobb::validate::EstimatorSet> r_source;
  if (r_bound && any_cubemap) r_source.emplace(mesh.mesh, false);
  // A box whose view of the mesh the cubemap's doubles cannot hold is estimated at half its
  // volume (texel_plan.h); R(m)'s plan finds it.
  std::vector<char> unresolved(n, 0);
  for (const Run& r : runs) {
    bound.emplace_back(n);
    rbound.emplace_back(n, NAN);
    for (size_t i = 0; i < n; ++i) {
      bound.back()[i] = certified_error(r.obv[i], poly[i]);
      if (r_source && r.m > 0) {
        bool u = false;
        rbound.back()[i] =
            std::min(r_source->bound(r.backend == "cpu" ? vobb::validate::Backend::kCpu : vobb::validate::Backend::kGl,
                                     boxes[i], r.m, &u),
                     vobb::validate::range_bound(boxes[i], r.obv[i]));
        unresolved[i] |= u;
      }
    }
  }
  for (size_t i = 0; i < n; ++i)
    if (unresolved[i])
      std::fprintf(stderr,
                   "vobb: warning: box %zu: its view of the mesh does not fit the cubemap's doubles (faces beyond "
                   "2^300 box units); estimated at half its volume\n",
                   i);
  std::vector<double> exact_value(n, 0.0), exact_seconds(n, 0.0);
  std::vector<std::string> exact_rational(n);
  if (want_exact) {
    const vobb::exact::ClipSolver exact(mesh.mesh);
    tbb::parallel_for(size_t{0}, n, [&](size_t i) {
      const auto t0 = std::chrono::steady_clock::now();
      const vobb::Rational v = exact.obv(boxes[i]);
      exact_seconds[i] = seconds_since(t0);
      exact_value[i] = vobb::to_double_nearest(v);
      exact_rational[i] = v.get_str();
    });
  }

  nlohmann::ordered_json out = nlohmann::ordered_json::array();
  if (!json)
    std::printf("%5s %8s %5s %24s %24s %12s %12s %10s%s%s\n", "box", "backend", "m", "OBV", "exact", "rel.error",
                "bound", "seconds", r_bound ? "         R(m)" : "", want_poly ? "  certified interval" : "");
  for (size_t i = 0; i < n; ++i) {
    nlohmann::ordered_json jb;
    jb["index"] = i;
    jb["box_volume"] = vobb::volume(boxes[i]);
    if (unresolved[i]) jb["unresolved"] = true;
    if (!poly.empty()) {
      jb["interval"] = {poly[i].lo, poly[i].hi};
      jb["interval_faces"] = poly[i].faces;              // faces visited
      jb["interval_exact_signs"] = poly[i].exact_signs;  // vertex signs decided in rationals
      jb["interval_exact_faces"] = poly[i].exact_faces;  // faces evaluated in rationals
      if (poly[i].exact_box) jb["interval_from_exact"] = poly[i].why;
    }
    if (want_exact) {
      jb["exact"] = exact_value[i];
      if (rational) jb["exact_rational"] = exact_rational[i];
      jb["exact_seconds"] = exact_seconds[i];
    }
    nlohmann::ordered_json est = nlohmann::ordered_json::array();
    for (size_t k = 0; k < runs.size(); ++k) {
      const Run& r = runs[k];
      nlohmann::ordered_json e = {{"backend", r.backend}};
      if (r.m > 0) e["m"] = r.m;
      e["obv"] = r.obv[i];
      e["bound"] = bound[k][i];
      if (r_bound && r.m > 0) e["r_bound"] = rbound[k][i];
      e["seconds"] = r.seconds[i];
      est.push_back(e);
      if (json) continue;
      char rel[32] = "-", ex[40] = "-", mm[16] = "-", rb[24] = "", iv[64] = "";
      if (want_exact && exact_value[i] != 0)
        std::snprintf(rel, sizeof rel, "%.3e", std::abs(r.obv[i] - exact_value[i]) / exact_value[i]);
      if (want_exact) std::snprintf(ex, sizeof ex, "%.17g", exact_value[i]);
      if (r.m > 0) std::snprintf(mm, sizeof mm, "%d", r.m);
      if (r_bound && r.m > 0) std::snprintf(rb, sizeof rb, " %12.3e", rbound[k][i]);
      if (r_bound && r.m == 0) std::snprintf(rb, sizeof rb, " %12s", "-");
      if (want_poly && r.m == 0) std::snprintf(iv, sizeof iv, "  [%.17g, %.17g]", poly[i].lo, poly[i].hi);
      std::printf("%5zu %8s %5s %24.17g %24s %12s %12.3e %10.6f%s%s\n", i, r.backend.c_str(), mm, r.obv[i], ex, rel,
                  bound[k][i], r.seconds[i], rb, iv);
    }
    if (!json && runs.empty())
      std::printf("%5zu %8s %5s %24.17g %24s %12s %12s %10.6f\n", i, "exact", "-", exact_value[i], "-", "-", "-",
                  exact_seconds[i]);
    jb["estimates"] = est;
    out.push_back(jb);
  }
  if (json) {
    nlohmann::ordered_json doc;
    if (gl) doc["renderer"] = gl->renderer();
    doc["mesh_single_precision"] = mesh.single_precision;
    doc["boxes"] = out;
    std::printf("%s\n", vobb::app::report_json(doc).c_str());
  } else if (rational && want_exact) {
    for (size_t i = 0; i < n; ++i) std::printf("box %zu exact (rational): %s\n", i, exact_rational[i].c_str());
  }
  return kExitOk;
}

// The folder in compare's checkpoint that keeps the certification of `method`'s tree, and the
// files there and beside it that compare writes (an output may name none of them).
std::string certify_folder(const std::string& checkpoint, const std::string& method) {
  return (std::filesystem::path(checkpoint) / ("certify-" + method)).string();
}
std::vector<std::string> compare_checkpoint_files() {
  std::vector<std::string> files = {"state.json"};
  for (const char* method : {"obbtree", "variational"})
    for (const char* name : {"obv.json", "layers.json"}) files.push_back(certify_folder("", method) + "/" + name);
  return files;
}

// compare's checkpoint, checked before its long work (the baseline's certification comes
// before the variational build): the variational build's state against this run's flags, and
// each certification's files as files (their trees, which the rest depends on, come later).
vobb::Status check_compare_checkpoint(const vobb::Mesh& mesh, const BuildFlags& flags, const vobb::GlObvEstimator* gl) {
  BuildFlags f = flags;
  f.method = "variational";
  vobb::Status s = make_checkpoint_folder(f.checkpoint);
  if (!s) return s;
  vobb::VariationalState state;
  bool found = false;
  s = vobb::read_variational_state((std::filesystem::path(f.checkpoint) / "state.json").string(),
                                   build_fingerprint(mesh, f, gl), mesh.faces.size(), f.arity, f.depth, &state, &found);
  if (!s) return s;
  for (const char* method : {"obbtree", "variational"}) {
    const std::string folder = certify_folder(f.checkpoint, method);
    s = make_checkpoint_folder(folder);  // made now, and must take files, as the build's
    if (!s) return s;
    s = vobb::exact::CertifyCheckpoint::check_files(folder);
    if (!s) return s;
  }
  return vobb::Status::ok();
}

// Both builders on one mesh, both trees certified exactly; per layer the exact OMV of each and
// the change, and each tree's weighted error e (DESIGN §1, §7). Where one tree stops sooner
// than the other (every leaf of it holds one face, or cannot be split), its layers below its
// last are its leaf layer again, as in its own layers, and both e are taken over the deeper
// tree's layers with the same weights: e of trees of different depths weighs their layers
// differently and is not to be compared.
// With `figure_path`, also draws both trees' layers over the mesh (fast/tree_figure.h) to a PNG.
int run_compare(const std::string& mesh_path, const BuildFlags& flags, bool json, bool rational,
                const std::string& figure_path, const std::string& figure_up) {
  vobb::LoadedMesh loaded;
  vobb::Status s = vobb::load_solid(mesh_path, &loaded);
  if (!s) return refuse(s);
  vobb::app::note_precision(mesh_path, loaded);
  std::unique_ptr<vobb::GlObvEstimator> gl;
  std::unique_ptr<vobb::CpuObvEstimator> cpu;
  std::unique_ptr<vobb::PolyObvSolver> poly;
  vobb::ObvEstimate estimate;
  s = make_estimator(loaded.mesh, flags, &gl, &cpu, &poly, &estimate);
  if (!s) return refuse(s);
  if (!flags.checkpoint.empty()) {
    s = check_compare_checkpoint(loaded.mesh, flags, gl.get());
    if (!s) return refuse(s);
  }
  vobb::exact::CertifyOptions copt;
  if (!flags.quiet) copt.progress = [](const std::string& line) { std::fprintf(stderr, "vobb: %s\n", line.c_str()); };
  copt.rational = rational;
  struct Result {
    vobb::Tree tree;
    vobb::exact::Certificate cert;
    double build_seconds = 0;
  } r[2];
  for (int i = 0; i < 2; ++i) {
    BuildFlags f = flags;
    f.method = i == 0 ? "obbtree" : "variational";
    const auto t0 = std::chrono::steady_clock::now();
    s = build_tree(loaded.mesh, f, estimate, gl.get(), &r[i].tree);
    if (!s) return refuse(s);
    r[i].build_seconds = seconds_since(t0);
    // With --checkpoint, each tree's certification keeps its own folder beside the build's state.
    CertifySaver saver;
    vobb::exact::CertifyOptions o = copt;
    if (!flags.checkpoint.empty()) {
      s = saver.attach(certify_folder(flags.checkpoint, f.method), loaded.mesh,
                       r[i].tree, rational ? "auto; rational" : "auto", &o);
      if (!s) return refuse(s);
    }
    r[i].cert = vobb::exact::certify(loaded.mesh, r[i].tree, o);
  }
  const bool ok = r[0].cert.ok() && r[1].cert.ok();
  const size_t levels = std::max(r[0].cert.layers.size(), r[1].cert.layers.size());
  auto layer_of = [&](int i, size_t l) -> const vobb::exact::LayerCertificate& {
    const auto& layers = r[i].cert.layers;
    return layers[std::min(l, layers.size() - 1)];
  };
  auto omv_exact = [&](int i, size_t l) -> const vobb::Rational& { return layer_of(i, l).omv; };
  auto omv = [&](int i, size_t l) { return layer_of(i, l).omv_nearest; };
  auto change = [](double a, double b) { return a == 0 ? 0.0 : 100.0 * (b - a) / a; };
  // e over layers 0 .. D of the deeper tree, with ω(l) = D - l + 1 (DESIGN §1). For a tree of
  // depth D this is certify's e. Its enclosure gives the nearest double; where it cannot (a
  // rounding tie within 1e-35), or with --rational, the layers' rationals do.
  vobb::Rational e_exact[2];
  double e_nearest[2];
  for (int i = 0; i < 2; ++i) {
    vobb::exact::MpInterval e(0);
    for (size_t l = 0; l < levels; ++l)
      e += vobb::exact::MpInterval(static_cast<int>(levels - l)) * layer_of(i, l).omv_enclosure;
    if (e.nearest(&e_nearest[i]) && !rational) continue;
    if (!r[i].cert.rational) {
      vobb::exact::CertifyOptions o = copt;
      o.rational = true;
      r[i].cert = vobb::exact::certify(loaded.mesh, r[i].tree, o);
    }
    for (size_t l = 0; l < levels; ++l) e_exact[i] += static_cast<long>(levels - l) * omv_exact(i, l);
    e_nearest[i] = vobb::to_double_nearest(e_exact[i]);
  }
  const double e0 = e_nearest[0], e1 = e_nearest[1];
  if (json) {
    nlohmann::ordered_json doc, rows = nlohmann::ordered_json::array();
    for (size_t l = 0; l < levels; ++l) {
      nlohmann::ordered_json row = {{"level", l}, {"omv_baseline", omv(0, l)}, {"omv_variational", omv(1, l)},
                                    {"change_pct", change(omv(0, l), omv(1, l))}};
      if (rational) {
        row["omv_baseline_rational"] = omv_exact(0, l).get_str();
        row["omv_variational_rational"] = omv_exact(1, l).get_str();
      }
      rows.push_back(row);
    }
    doc["levels"] = rows;
    doc["mesh_single_precision"] = loaded.single_precision;
    doc["depth_baseline"] = r[0].tree.depth;
    doc["depth_variational"] = r[1].tree.depth;
    doc["e_baseline"] = e0;
    doc["e_variational"] = e1;
    if (rational) {
      doc["e_baseline_rational"] = e_exact[0].get_str();
      doc["e_variational_rational"] = e_exact[1].get_str();
    }
    doc["seconds_baseline"] = r[0].build_seconds;
    doc["seconds_variational"] = r[1].build_seconds;
    doc["certified"] = ok;
    std::printf("%s\n", vobb::app::report_json(doc).c_str());
  } else {
    std::printf("%5s %24s %24s %10s\n", "layer", "OMV obbtree", "OMV variational", "change %");
    for (size_t l = 0; l < levels; ++l)
      std::printf("%5zu %24.17g %24.17g %+10.2f\n", l, omv(0, l), omv(1, l), change(omv(0, l), omv(1, l)));
    if (r[0].tree.depth != r[1].tree.depth)
      std::printf("\nthe obbtree tree has depth %d and the variational one %d: the shallower one's leaf layer is repeated "
                  "below its last, and both e are over layers 0..%zu\n",
                  r[0].tree.depth, r[1].tree.depth, levels - 1);
    std::printf("\ne obbtree %.17g, e variational %.17g, change %+.2f %%\n", e0, e1, change(e0, e1));
    if (rational) std::printf("e obbtree (rational): %s\ne variational (rational): %s\n", e_exact[0].get_str().c_str(), e_exact[1].get_str().c_str());
    std::printf("build seconds: obbtree %.3f, variational %.3f; both certified: %s\n", r[0].build_seconds,
                r[1].build_seconds, ok ? "yes" : "NO");
  }
  if (!figure_path.empty()) {
    // The estimator's context when it made one, else a context of our own (llvmpipe will do).
    std::unique_ptr<vobb::GlContext> own;
    if (!gl) {
      s = vobb::GlContext::create(&own);
      if (!s) return refuse(vobb::Status::error(figure_path + ": cannot draw the figure: " + s.message()));
      if (!flags.quiet) say_renderer(*own);
    }
    const std::vector<vobb::FigureRow> rows = {{"obbtree", &r[0].tree}, {"variational", &r[1].tree}};
    vobb::FigureOptions fo;
    fo.levels = vobb::default_figure_levels(rows);
    s = vobb::set_figure_up(figure_up, &fo);
    if (!s) return refuse(s);
    vobb::RgbaImage image;
    s = vobb::render_tree_figure(gl ? gl->context() : *own, loaded.mesh, rows, fo, &image);
    if (!s) return refuse(s);
    s = vobb::write_png(figure_path, image);
    if (!s) return vobb::app::could_not_finish(s);  // its folder took a file when the run started
    std::fprintf(stderr, "vobb: figure %s: %dx%d px; row 1 obbtree (baseline), row 2 variational; columns levels %d..%d\n",
                 figure_path.c_str(), image.width, image.height, fo.levels.front(), fo.levels.back());
  }
  return ok ? kExitOk : kExitCheckFailed;
}

}  // namespace

constexpr const char* kThreadsHelp =
    "Threads of a variational build: the nodes of a level searched at once, and each batch's "
    "estimates (CPU twin) or plans (GL) (default: every core this process may use); the tree is "
    "the same for any number. No effect on obbtree";
constexpr const char* kCertifyThreadsHelp =
    "Threads for the boxes' OBV and for the layers, one layer per thread at a time (default: every "
    "core this process may use); the values are exact, so the same for any number. Each thread "
    "that computes a union holds its own Nef polyhedron of the mesh";
constexpr const char* kCompareThreadsHelp =
    "Threads for the variational search (the nodes of a level at once, and each batch's estimates "
    "or GL plans) and for certifying both trees (default: every core this process may use); trees "
    "and values are the same for any number. No effect on obbtree's build";

int main(int argc, char** argv) {
  // A reader that closes the pipe early (vobb info M | head -1) makes a write fail with EPIPE,
  // which ends the run with one line and exit 3, instead of killing it silently with SIGPIPE.
  std::signal(SIGPIPE, SIG_IGN);
  CLI::App app{"vobb: tight oriented-bounding-box trees for solid meshes, with exact outer volumes"};
  app.require_subcommand(1);
  app.set_version_flag("--version", VOBB_VERSION);

  std::string mesh, tree_path, out;
  bool json = false, rational = false;
  int level = 0;

  CLI::App* info = app.add_subcommand("info", "Counts, exact enclosed volume, bounding box and solidity verdict");
  info->add_option("MESH", mesh, "Mesh file (OFF, OBJ, PLY, STL; others through assimp)")->required();
  info->add_flag("--json", json, "Print JSON");
  info->add_flag("--rational", rational, "Also print the exact volume as a rational");

  BuildFlags bf;
  CLI::App* build = app.add_subcommand("build", "Build an OBB tree and write it as JSON");
  build->add_option("MESH", mesh, "Solid mesh file")->required();
  build->add_option("-o,--output", out, "Tree file to write")->required()->check(vobb::app::kPath);
  build->add_option("--method", bf.method, "variational (the paper's) or obbtree (the OBB-Tree baseline)")
      ->capture_default_str()->check(CLI::IsMember({"variational", "obbtree"}));
  build->add_option("--depth", bf.depth, "Deepest level; the root is level 0")
      ->capture_default_str()->check(CLI::Range(0, 30));
  build->add_option("--arity", bf.arity, "Most children per node")
      ->capture_default_str()->check(CLI::Range(2, 64));
  build->add_option("--m", bf.m, "Cubemap resolution of the OBV estimator (variational)")
      ->capture_default_str()->check(CLI::Range(1, 4096));
  const std::string backend_help = "OBV estimator: auto (GL on a GPU from --m " + std::to_string(kAutoGlFromM) +
                                   ", where it was measured faster; else the CPU twin), gl, cpu, or poly (the "
                                   "polyhedral solver: exact to round-off, no --m)";
  build->add_option("--backend", bf.backend, backend_help)
      ->capture_default_str()->check(CLI::IsMember({"auto", "gl", "cpu", "poly"}));
  build->add_option("--lloyd", bf.lloyd, "Most Lloyd iterations per node (variational)")
      ->capture_default_str()->check(CLI::Range(0, 1000));
  build->add_option("--seed", bf.seed, "Seed of the orientation search's random starts")
      ->capture_default_str()->check(vobb::app::kSeed);
  build->add_flag("--no-axis-search", bf.no_axis_search, "Ablation: keep covariance axes (no orientation search)");
  build->add_flag("--adjust", bf.adjust, "Also run the adjustment step (Lloyd from other planar splits at levels 1-4; measured to raise e, so off)");
  build->add_flag("--no-merge", bf.no_merge, "Ablation: no bottom-up merging sweeps");
  build->add_option("--objective", bf.objective, kObjectiveHelp)
      ->capture_default_str()->check(CLI::IsMember({"obv", "omv"}));
  build->add_option("--sweeps", bf.sweeps, "Most bottom-up merging sweeps")->capture_default_str()->check(CLI::Range(0, 100));
  build->add_option("--collider-margin", bf.collider_margin,
                    "Variational: minimise the OBV of each box grown by this length on every side (world units), "
                    "for colliders of about this radius; 0 is the paper's objective, and at most the mesh's "
                    "bounding-box diagonal. The stored boxes stay tight")
      ->capture_default_str()->check(vobb::app::kFinite);
  build->add_option("--queries", bf.queries,
                    "Variational: minimise, instead of OBV, the recorded collider queries that hit each box "
                    "(query files from `vobb collide --record-queries`, for this mesh; several are merged). "
                    "An objective for one application's colliders, beyond the paper; no OBV estimator is used")
      ->check(vobb::app::kPath)
      ->allow_extra_args(false);  // one file per --queries, so that a MESH after it stays the MESH
  build->add_option("--checkpoint", bf.checkpoint, "Folder for the build state after each level and sweep; "
                    "a build started again with it resumes and gives the same tree")
      ->check(vobb::app::kPath);
  build->add_option("--time-budget", bf.time_budget, "Seconds; then the search stops and the rest gets the baseline split")
      ->check(vobb::app::kFinite)->check(CLI::Range(1e-3, 1e9));
  build->add_flag("--quiet", bf.quiet, "No progress line");
  build->add_option("--threads", bf.threads, kThreadsHelp)->check(CLI::Range(1, 4096));

  std::string omv_path = "auto";
  bool quiet = false;
  CLI::App* cert = app.add_subcommand("certify", "Exact OMV, sum of OBV and containment per layer");
  cert->add_option("MESH", mesh, "The solid mesh the tree was built for")->required();
  cert->add_option("TREE", tree_path, "Tree file")->required();
  cert->add_flag("--json", json, "Print JSON");
  cert->add_flag("--rational", rational, "Also compute and print the exact values as rationals (OMV by Nef where boxes overlap)");
  cert->add_option("--path", omv_path, "auto: enclosures, rationals only where a sign or a rounding needs them; clip or nef: every value in rationals by that path; both: auto, and Nef's and clipping's rationals compared with it")
      ->capture_default_str()->check(CLI::IsMember({"auto", "clip", "nef", "both"}));
  cert->add_flag("--quiet", quiet, "No per-layer progress on stderr");
  std::string certify_checkpoint;
  cert->add_option("--checkpoint", certify_checkpoint,
                   "Folder for what is certified so far (obv.json: the boxes' OBV; layers.json: each finished "
                   "layer); a run started again with the same folder resumes it and prints the same certificate")
      ->check(vobb::app::kPath);
  int certify_threads = 0;
  cert->add_option("--threads", certify_threads, kCertifyThreadsHelp)->check(CLI::Range(1, 4096));

  std::string boxes_path, backend = "auto";
  std::vector<int> ms = {8, 16, 32};
  CLI::App* obv = app.add_subcommand("obv", "OBV of boxes: cubemap estimates at several m, and the exact value");
  obv->add_option("MESH", mesh, "Solid mesh")->required();
  obv->add_option("--boxes", boxes_path, "Box file {\"boxes\":[{center, axes, half_extents}]}")->required();
  obv->add_option("--m", ms, "Cubemap resolutions, e.g. 8,16,32")->delimiter(',')->check(CLI::Range(1, 4096));
  obv->add_option("--backend", backend,
                  "gl (EGL: a GPU, else llvmpipe), cpu (the double-precision twin), poly (the polyhedral solver: "
                  "an estimate and its certified interval), exact, all, or auto (gl, else cpu with a warning)")
      ->capture_default_str()->check(CLI::IsMember({"auto", "gl", "cpu", "poly", "exact", "all"}));
  bool r_bound = false;
  obv->add_flag("--r-bound", r_bound,
                "Also print R(m), the cubemap's rigorous texel bound, beside each cubemap estimate's certified error");
  obv->add_flag("--json", json, "Print JSON");
  obv->add_flag("--rational", rational, "With the exact backend, also print each exact OBV as a rational");

  bool compare_json = false;
  BuildFlags cf;
  CLI::App* cmp = app.add_subcommand("compare", "Both builders, both trees certified exactly: OMV per layer and e");
  cmp->add_option("MESH", mesh, "Solid mesh")->required();
  cmp->add_option("--depth", cf.depth, "Deepest level")->capture_default_str()->check(CLI::Range(0, 30));
  cmp->add_option("--arity", cf.arity, "Most children per node")->capture_default_str()->check(CLI::Range(2, 64));
  cmp->add_option("--m", cf.m, "Cubemap resolution of the variational builder's estimator")
      ->capture_default_str()->check(CLI::Range(1, 4096));
  cmp->add_option("--backend", cf.backend, "auto (as for build), gl, cpu or poly")
      ->capture_default_str()->check(CLI::IsMember({"auto", "gl", "cpu", "poly"}));
  cmp->add_option("--lloyd", cf.lloyd, "Most Lloyd iterations per node")->capture_default_str()->check(CLI::Range(0, 1000));
  cmp->add_option("--seed", cf.seed, "Seed of the orientation search's random starts")
      ->capture_default_str()->check(vobb::app::kSeed);
  cmp->add_flag("--no-axis-search", cf.no_axis_search, "Ablation: keep covariance axes");
  cmp->add_flag("--adjust", cf.adjust, "Also run the adjustment step (see build --help)");
  cmp->add_flag("--no-merge", cf.no_merge, "Ablation: no bottom-up merging sweeps");
  cmp->add_option("--objective", cf.objective, kObjectiveHelp)
      ->capture_default_str()->check(CLI::IsMember({"obv", "omv"}));
  cmp->add_option("--sweeps", cf.sweeps, "Most bottom-up merging sweeps")->capture_default_str()->check(CLI::Range(0, 100));
  cmp->add_option("--checkpoint", cf.checkpoint, "Folder for the variational build's state after each level and sweep, "
                  "as for build (the same flags make the same build: either command resumes the other's), and "
                  "for each tree's certification as for certify (certify-obbtree/, certify-variational/)")
      ->check(vobb::app::kPath);
  cmp->add_option("--time-budget", cf.time_budget, "Seconds for the variational search, as for build")
      ->check(vobb::app::kFinite)->check(CLI::Range(1e-3, 1e9));
  cmp->add_flag("--json", compare_json, "Print JSON (DESIGN §7)");
  cmp->add_flag("--rational", rational, "Also print each exact value (OMV per layer, e) as a rational");
  cmp->add_flag("--quiet", cf.quiet, "No progress on stderr");
  cmp->add_option("--threads", cf.threads, kCompareThreadsHelp)->check(CLI::Range(1, 4096));
  std::string compare_figure;
  cmp->add_option("--figure", compare_figure, "Also draw both trees' boxes at levels 1..8 over the mesh to this PNG")
      ->check(vobb::app::kPath);
  std::string compare_figure_up = "y";
  cmp->add_option("--figure-up", compare_figure_up, "The mesh's up axis in the figure: x, y, z, -x, -y or -z")
      ->capture_default_str()->check(CLI::IsMember({"x", "y", "z", "-x", "-y", "-z"}));

  vobb::app::ValidateFlags validate_flags;
  CLI::App* validate_cmd = vobb::app::add_validate_command(app, &validate_flags);
  vobb::app::CollideFlags collide_flags;
  CLI::App* collide_cmd = vobb::app::add_collide_command(app, &collide_flags);

  CLI::App* exp = app.add_subcommand("export", "Write the boxes of one layer as OBJ or PLY");
  exp->add_option("TREE", tree_path, "Tree file")->required();
  exp->add_option("--level", level, "Layer to export")->required();
  exp->add_option("-o,--output", out, "boxes.obj or boxes.ply")->required()->check(vobb::app::kPath);

  // The command named on the line: an unknown one is named back with the list, and a usage
  // error of a known one points to that command's help.
  std::string command;
  if (argc >= 2 && argv[1][0] != '-') {
    std::string names;
    for (const CLI::App* sc : app.get_subcommands([](CLI::App*) { return true; })) {
      names += (names.empty() ? "" : ", ") + sc->get_name();
      if (sc->get_name() == argv[1]) command = argv[1];
    }
    if (command.empty()) {
      std::fprintf(stderr, "vobb: usage: unknown command '%s'; the commands are %s (see vobb --help)\n",
                   one_line(argv[1]).c_str(), names.c_str());
      return kExitBadInput;
    }
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::string what = e.what();
    for (char& c : what)
      if (c == '\n') c = ' ';
    const std::string help = command.empty() ? "vobb --help" : "vobb " + command + " --help";
    std::fprintf(stderr, "vobb%s: usage: %s (see %s)\n", command.empty() ? "" : (" " + command).c_str(),
                 one_line(what).c_str(), help.c_str());
    return kExitBadInput;
  }
  // The CPU twin estimates each batch of boxes in parallel, and certify computes OBVs and
  // layers in parallel; the values, and so the trees, do not depend on how many threads
  // (fast/cpu_estimator.h, exact/certify.h).
  const int threads = build->parsed() ? bf.threads : cmp->parsed() ? cf.threads : cert->parsed() ? certify_threads : 0;
  std::optional<tbb::global_control> thread_limit;
  if (threads > 0) thread_limit.emplace(tbb::global_control::max_allowed_parallelism, static_cast<size_t>(threads));
  {
    vobb::Status s = vobb::Status::ok();
    if (build->parsed()) {
      std::vector<std::string> inputs = bf.queries;
      inputs.push_back(mesh);
      s = vobb::app::check_output_is_not_input("-o", out, inputs);
      // The recorded queries replace the OBV estimator that these two choose.
      if (s && !bf.queries.empty() && (build->count("--m") > 0 || build->count("--backend") > 0))
        s = vobb::Status::error("--m and --backend choose the OBV estimator, which --queries replaces");
    }
    // The polyhedral solver has no resolution: an explicit --m with it is a mistake.
    for (const auto& [cmd, flags] : {std::pair{build, &bf}, {cmp, &cf}})
      if (s && cmd->parsed() && flags->backend == "poly" && cmd->count("--m") > 0)
        s = vobb::Status::error("--m is the cubemap's resolution; --backend poly uses no cubemap");
    if (exp->parsed()) s = vobb::app::check_output_is_not_input("-o", out, {tree_path});
    if (s && build->parsed()) s = vobb::app::check_output_is_not_checkpoint("-o", out, bf.checkpoint, {"state.json"});
    if (s && (build->parsed() || exp->parsed())) s = vobb::app::check_output_is_writable("-o", out);
    if (s && cmp->parsed()) s = vobb::app::check_output_is_not_input("--figure", compare_figure, {mesh});
    if (s && cmp->parsed())
      s = vobb::app::check_output_is_not_checkpoint("--figure", compare_figure, cf.checkpoint, compare_checkpoint_files());
    if (s && cmp->parsed()) s = vobb::app::check_output_is_writable("--figure", compare_figure);
    if (s && exp->parsed()) s = vobb::check_box_export_path(out);
    if (collide_cmd->parsed()) {
      std::vector<std::string> inputs = collide_flags.trees;
      inputs.push_back(collide_flags.mesh);
      s = vobb::app::check_output_is_not_input("-o", collide_flags.output, inputs);
      if (s) s = vobb::app::check_output_is_writable("-o", collide_flags.output);
      if (s && !collide_flags.record_queries.empty()) {
        s = vobb::app::check_output_is_not_input("--record-queries", collide_flags.record_queries, inputs);
        if (s) s = vobb::app::check_outputs_differ("--record-queries", collide_flags.record_queries, "-o", collide_flags.output);
        if (s) s = vobb::app::check_output_is_writable("--record-queries", collide_flags.record_queries);
      }
    }
    if (!s) return refuse(s);
  }
  auto run = [&]() -> int {
    if (info->parsed()) return run_info(mesh, json, rational);
    if (build->parsed()) return run_build(mesh, out, bf);
    if (exp->parsed()) return run_export(tree_path, level, out);
    if (validate_cmd->parsed()) return vobb::app::run_validate_command(validate_flags);
    if (collide_cmd->parsed()) return vobb::app::run_collide_command(collide_flags);
    if (obv->parsed()) return run_obv(mesh, boxes_path, ms, backend, json, rational, r_bound);
    if (cmp->parsed()) return run_compare(mesh, cf, compare_json, rational, compare_figure, compare_figure_up);
    if (cert->parsed()) return run_certify(mesh, tree_path, json, rational, omv_path, certify_checkpoint, quiet);
    return kExitBadInput;
  };
  // Bad input never throws (it is a Status); what can is running out of memory, or a library's
  // own assertion (CGAL's). Either ends the run with one line, not an abort.
  const std::string who = command.empty() ? "vobb" : "vobb " + command;
  int rc;
  try {
    rc = run();
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "%s: out of memory\n", who.c_str());
    return kExitCouldNotFinish;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: internal error: %s\n", who.c_str(), one_line(e.what()).c_str());
    return kExitCouldNotFinish;
  }
  // A report printed to a full disk or a closed stream must not end as a success.
  if (std::fflush(stdout) != 0 || std::ferror(stdout)) {
    std::fprintf(stderr, "%s: cannot write standard output\n", who.c_str());
    return kExitCouldNotFinish;
  }
  // A run that ends with its results names the single-precision read (say_pending_notes); a
  // refusal or a run that could not finish keeps to its one line.
  if (rc == kExitOk || rc == kExitCheckFailed) vobb::app::say_pending_notes();
  return rc;
}
