#include "app/build_flags.h"

#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <memory>

#include "app/cli_support.h"
#include "common/stopwatch.h"

namespace vobb::app {

namespace {

const char* const kObjectiveHelp =
    "What the variational search minimises per set of boxes: omv (the default: the sum of their "
    "OBV less what each shares outside the solid with those before it, by the polyhedral solver: "
    "their OMV, which the certificate charges; with --collider-margin the default is obv) or obv "
    "(the sum of their OBV, the paper's; faster)";
const char* const kThreadsHelp =
    "Threads of a variational build: the nodes of a level searched at once, and each batch's "
    "estimates (CPU twin) or plans (GL) (default: every core this process may use); the tree is "
    "the same for any number. No effect on obbtree";
const char* const kCompareThreadsHelp =
    "Threads for the variational search (the nodes of a level at once, and each batch's estimates "
    "or GL plans) and for certifying both trees (default: every core this process may use); trees "
    "and values are the same for any number. No effect on obbtree's build";

// The progress line: on a terminal redrawn in place twice a second; into a file or a pipe a
// line of its own every 30 s, so that a log stays readable.
struct ProgressLine {
  BuildFlags flags;
  bool tty = ::isatty(::fileno(stderr)) != 0;
  std::chrono::steady_clock::time_point t0 = std::chrono::steady_clock::now();
  double last = -1, done0 = -1, sweep_t0 = 0;
  int sweep_seen = 0;

  Objective objective = Objective::kObv;  // search_objective() of the build's options

  const char* objective_name() const {
    const bool grown = flags.options.collider_margin > 0;
    if (!flags.queries.empty()) return "hits";
    if (objective == Objective::kOmv) return grown ? "grown OMV" : "OMV";
    return grown ? "grown OBV" : "OBV";
  }

  void operator()(const VariationalProgress& p) {
    const double now = seconds_since(t0);
    if (p.sweep != sweep_seen) {  // a new sweep: its pace is measured from here
      sweep_seen = p.sweep;
      sweep_t0 = now;
    }
    if (last >= 0 && now - last < (tty ? 0.5 : 30.0)) return;
    last = now;
    if (done0 < 0) done0 = p.done;
    const char* start = tty ? "\r" : "";
    // Remaining: this run's pace over what is still to do, in the top-down pass or in the
    // current sweep (how many sweeps run depends on their gains: at most --sweeps).
    char eta[64] = "";
    if (p.sweep == 0) {
      if (p.done - done0 > 0.02)
        std::snprintf(eta, sizeof eta, "  ~%.0f s left to split",
                      now * (1 - p.done) / (p.done - done0));
      std::fprintf(
          stderr,
          "%svobb: level %d/%d  nodes done %zu/%zu  iteration %d/%d  sum %s %.6g  %.1f s%s%s",
          start, p.level, flags.options.depth, p.node, p.nodes, p.iteration, flags.options.lloyd,
          objective_name(), p.sum_obv, now, eta, tty ? "     " : "\n");
    } else {
      if (p.sweep_done > 0.02)
        std::snprintf(eta, sizeof eta, "  ~%.0f s left in this sweep",
                      (now - sweep_t0) * (1 - p.sweep_done) / p.sweep_done);
      std::fprintf(
          stderr, "%svobb: merging sweep %d (at most %d)  level %d  nodes done %zu/%zu  %.1f s%s%s",
          start, p.sweep, flags.options.sweeps, p.level, p.node, p.nodes, now, eta,
          tty ? "                    " : "\n");
    }
    std::fflush(stderr);
  }
};

// The one line after a variational build.
void say_report(const VariationalReport& r) {
  std::fprintf(stderr,
               "vobb: %zu boxes estimated (%zu more asked again, answered from a record: %zu of "
               "them from the node's regrouping in an earlier sweep), %zu shares of overlap "
               "estimated, %zu adjusted splits and %zu merges kept, %d sweeps (%zu regroupings "
               "unchanged since they found no move, not run again), %zu boxes turned by the "
               "refit%s\n",
               r.estimates, r.reused, r.reused_earlier, r.overlaps, r.adjustments, r.merges,
               r.sweeps, r.regroups_skipped, r.refitted,
               r.budget_spent ? "; time budget spent: the rest got the baseline split" : "");
}

}  // namespace

void add_build_flags(CLI::App* cmd, BuildFlags* f, bool compare) {
  BuildOptions& o = f->options;
  if (!compare)
    cmd->add_option("--method", f->method,
                    "variational (the paper's) or obbtree (the OBB-Tree baseline)")
        ->capture_default_str()
        ->check(CLI::IsMember({"variational", "obbtree"}));
  cmd->add_option("--depth", o.depth, "Deepest level; the root is level 0")
      ->capture_default_str()
      ->transform(kCount)
      ->check(CLI::Range(0, 30));
  cmd->add_option("--arity", o.arity, "Most children per node")
      ->capture_default_str()
      ->transform(kCount)
      ->check(CLI::Range(2, 64));
  cmd->add_option("--m", o.m, "Cubemap resolution of the OBV estimator (variational)")
      ->capture_default_str()
      ->transform(kCount)
      ->check(CLI::Range(1, 4096));
  const std::string backend_help =
      "OBV estimator: auto (GL on a GPU from --m " + std::to_string(kAutoGlFromM) +
      ", where it was measured faster; else the CPU twin), gl, cpu, or poly (the "
      "polyhedral solver: exact to round-off, no --m)";
  cmd->add_option("--backend", f->backend, backend_help)
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "gl", "cpu", "poly"}));
  cmd->add_option("--lloyd", o.lloyd, "Most Lloyd iterations per node (variational)")
      ->capture_default_str()
      ->transform(kCount)
      ->check(CLI::Range(0, 1000));
  cmd->add_option("--seed", o.seed, "Seed of the orientation search's random starts")
      ->capture_default_str()
      ->check(kSeed);
  cmd->add_flag("--no-axis-search", f->no_axis_search,
                "Ablation: keep covariance axes (no orientation search)");
  cmd->add_flag("--adjust", o.adjust,
                "Also run the adjustment step (Lloyd from other planar splits at levels 1-4; "
                "measured to raise e, so off)");
  cmd->add_flag("--no-merge", f->no_merge, "Ablation: no bottom-up merging sweeps");
  cmd->add_flag("--no-refit", f->no_refit,
                "Ablation: under omv, no last step turning each box of levels 0-4 (its faces "
                "fixed) where that lowers its layers' estimated OMV");
  cmd->add_flag("--subtree-swaps", o.subtree_swaps,
                "After the search, let subtrees under distant parents trade places while that "
                "lowers the estimated e (scored by the polyhedral solver; several times the "
                "search's time)");
  cmd->add_option("--objective", f->objective, kObjectiveHelp)
      ->check(CLI::IsMember({"obv", "omv"}));
  cmd->add_option("--sweeps", o.sweeps, "Most bottom-up merging sweeps")
      ->capture_default_str()
      ->transform(kCount)
      ->check(CLI::Range(0, 100));
  if (!compare) {
    cmd->add_option(
           "--collider-margin", o.collider_margin,
           "Variational: minimise the OBV of each box grown by this length on every side (world "
           "units), "
           "for colliders of about this radius; 0: no margin (the objective is then --objective's "
           "default), at most the mesh's bounding-box diagonal. The stored boxes stay tight")
        ->capture_default_str()
        ->check(kFinite);
    cmd->add_option(
           "--queries", f->queries,
           "Variational: minimise, instead of OBV, the recorded collider queries that hit each box "
           "(query files from `vobb collide --record-queries`, for this mesh; several are merged). "
           "An objective for one application's colliders, beyond the paper; no OBV estimator is "
           "used")
        ->check(kPath)
        ->allow_extra_args(
            false);  // one file per --queries, so that a MESH after it stays the MESH
  }
  cmd->add_option(
         "--checkpoint", o.checkpoint,
         compare
             ? "Folder for the variational build's state after each level and sweep, as for build "
               "(the "
               "same flags make the same build: either command resumes the other's), and for each "
               "tree's certification as for certify (certify-obbtree/, certify-variational/)"
             : "Folder for the build state after each level and sweep; a build started again with "
               "it resumes and gives the same tree (a state whose --time-budget ran out only with "
               "a --time-budget)")
      ->check(kPath);
  cmd->add_option("--time-budget", o.time_budget,
                  "Seconds, for the search and then --subtree-swaps; the search stops and the "
                  "nodes not yet split get the baseline split, the swaps keep the rounds done")
      ->check(kFinite)
      ->check(CLI::Range(1e-3, 1e9));
  cmd->add_flag("--quiet", f->quiet, compare ? "No progress on stderr" : "No progress line");
  cmd->add_option("--threads", f->threads, compare ? kCompareThreadsHelp : kThreadsHelp)
      ->transform(kCount)
      ->check(CLI::Range(1, 4096));
}

Status check_build_flags(const CLI::App* cmd, const BuildFlags& f) {
  // The recorded queries replace the OBV estimator that these two choose.
  if (!f.queries.empty() && (cmd->count("--m") > 0 || cmd->count("--backend") > 0))
    return Status::error("--m and --backend choose the OBV estimator, which --queries replaces");
  // The polyhedral solver has no resolution: an explicit --m with it is a mistake.
  if (f.backend == "poly" && cmd->count("--m") > 0)
    return Status::error("--m is the cubemap's resolution; --backend poly uses no cubemap");
  return Status::ok();
}

BuildOptions build_options(const BuildFlags& f) {
  BuildOptions o = f.options;
  o.method = f.method == "obbtree" ? Method::kObbTree : Method::kVariational;
  o.backend = f.backend == "gl"     ? Backend::kGl
              : f.backend == "cpu"  ? Backend::kCpu
              : f.backend == "poly" ? Backend::kPoly
                                    : Backend::kAuto;
  if (!f.objective.empty()) o.objective = f.objective == "omv" ? Objective::kOmv : Objective::kObv;
  o.axis_search = !f.no_axis_search;
  o.merge = !f.no_merge;
  o.refit = !f.no_refit;
  auto line = std::make_shared<ProgressLine>();
  line->flags = f;
  line->objective = search_objective(o);
  if (!f.quiet) o.progress = [line](const VariationalProgress& p) { (*line)(p); };
  // Under --quiet only the resume notice, which says where the result came from (certify says
  // it too).
  o.note = [quiet = f.quiet](const std::string& s) {
    if (quiet && s.rfind("resuming from ", 0) != 0) return;
    std::fprintf(stderr, "vobb: %s\n", one_line(s).c_str());
  };
  // A warning is said even with --quiet; on a terminal the progress line is still open: end it
  // first.
  o.warning = [line](const std::string& s) {
    std::fprintf(stderr, "%svobb: %s\n", line->tty && line->last >= 0 ? "\n" : "",
                 one_line(s).c_str());
  };
  o.saved = build_kill_hook();
  // The line's clock starts with the search, not with the loading or the baseline before it.
  o.started = [line] { line->t0 = std::chrono::steady_clock::now(); };
  if (!f.quiet)
    o.finished = [line](const VariationalReport& r) {
      if (line->tty && line->last >= 0) std::fprintf(stderr, "\n");  // end the progress line
      line->last = -1;
      say_report(r);
    };
  if (!f.quiet)
    o.swapped = [](const SubtreeSwapReport& r) {
      std::fprintf(stderr,
                   "vobb: subtree swaps: %zu pairs scored, %zu swaps in %zu rounds kept (%zu "
                   "rounds replaced by their best swap, %zu undone), estimated e %.9g -> %.9g "
                   "(%zu scores kept from an earlier round, %zu of them scored again)%s\n",
                   r.candidates, r.swaps, r.rounds, r.reverted, r.undone, r.e_before, r.e_after,
                   r.reused, r.rescored, r.stopped ? "; time budget spent" : "");
    };
  return o;
}

std::function<void(const VariationalState&)> build_kill_hook() {
  const char* at = std::getenv("VOBB_TEST_KILL_AT_SPLIT_LEVELS");
  if (at == nullptr) return nullptr;
  return [levels = std::atoi(at)](const VariationalState& st) {
    if (st.split_levels == levels) ::raise(SIGKILL);
  };
}

std::function<void(const exact::CertifyState&)> certify_kill_hook() {
  const char* at = std::getenv("VOBB_TEST_KILL_AFTER_CERTIFIED_LAYERS");
  if (at == nullptr) return nullptr;
  return [layers = std::atol(at)](const exact::CertifyState& st) {
    if (!st.obv.empty() && static_cast<long>(st.layers.size()) == layers) ::raise(SIGKILL);
  };
}

}  // namespace vobb::app
