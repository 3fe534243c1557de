#include <CLI/CLI.hpp>
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "app/cli_support.h"
#include "app/command.h"
#include "collision/query_objective.h"
#include "common/atomic_file.h"
#include "common/io/mesh_report.h"
#include "common/sha256.h"
#include "common/text_util.h"
#include "common/tree_io.h"
#include "validate/collision/collision_experiment.h"
#include "validate/collision/experiment_report.h"

namespace vobb::app {

namespace {

struct CollideFlags {
  std::string mesh;
  std::vector<std::string> trees;
  int colliders = 1000;
  double seconds = 10.0;
  uint64_t seed = 1;
  double collider_scale = 1.0;
  bool static_mode = false;
  bool no_fcl = false;
  bool json = false;
  std::string output;  // empty: stdout
  // The query stream's colliders, every K-th, written as a query file (query_objective.h)
  // for `vobb build --queries`; empty: not recorded.
  std::string record_queries;
  int record_every = 1;
};

CLI::App* add_collide_command(CLI::App& app, CollideFlags* f) {
  CLI::App* c = app.add_subcommand(
      "collide",
      "Collision experiment (paper §5): collider–box tests per tree, checked against brute force");
  c->add_option("MESH", f->mesh, "The solid mesh the trees were built for")->required();
  c->add_option("TREES", f->trees, "Tree files; reductions are relative to the first")->required();
  c->add_option("--colliders", f->colliders,
                "Falling colliders (at most 10^6, all held in memory) or, with --static, poses (at "
                "most 10^7)")
      ->capture_default_str()
      ->transform(kCount)
      ->check(CLI::Range(1, 10000000));
  c->add_option("--seconds", f->seconds, "Simulated seconds (dynamic mode)")
      ->capture_default_str()
      ->check(vobb::app::kFinite)
      ->check(CLI::Range(0.0, 1e6));
  c->add_option("--seed", f->seed, "Seed of the collider stream")
      ->capture_default_str()
      ->check(vobb::app::kSeed);
  c->add_option(
       "--collider-scale", f->collider_scale,
       "Multiplies every collider's size (at 1: spheres of radius 2-8 % and boxes of half side "
       "1.5-6 % of R, half the diagonal of the first tree's root box); the random draws are the "
       "same for any value")
      ->capture_default_str()
      ->check(vobb::app::kFinite)
      ->check(CLI::Range(0.01, 10.0));
  c->add_flag("--static", f->static_mode, "No dynamics: poses sampled on and near the surface")
      ->excludes(c->get_option("--seconds"));
  c->add_flag("--no-fcl", f->no_fcl, "Skip the FCL replay");
  c->add_flag("--json", f->json, "Print JSON (DESIGN §7)");
  c->add_option("-o,--output", f->output,
                "Write the report to this file (atomically) instead of stdout")
      ->check(vobb::app::kPath);
  c->add_option(
       "--record-queries", f->record_queries,
       "Also write the run's queries (the colliders, in the mesh's frame) to this query file, for "
       "`vobb build --queries`; record with other seeds than the runs you report")
      ->check(vobb::app::kPath);
  CLI::Option* record = c->get_option("--record-queries");
  c->add_option("--record-every", f->record_every,
                "Record every K-th query only (with --record-queries)")
      ->capture_default_str()
      ->transform(kCount)
      ->check(CLI::Range(1, 1000000000))
      ->needs(record);
  return c;
}

int run_collide_command(const CollideFlags& f) {
  LoadedMesh mesh;
  Status s = load_input_solid(f.mesh, &mesh);
  if (!s) return refuse(s);
  const std::string sha = mesh_sha256(mesh.mesh);
  std::vector<Tree> trees(f.trees.size());
  std::vector<collision::NamedTree> named;
  for (size_t i = 0; i < f.trees.size(); ++i) {
    s = read_tree(f.trees[i], &trees[i]);
    if (s) s = check_tree_fits(mesh.mesh, trees[i], f.trees[i], sha);
    if (!s) return refuse(s);
    named.push_back({f.trees[i], &trees[i]});
  }
  collision::ExperimentOptions opt;
  opt.dynamic = !f.static_mode;
  opt.colliders = f.colliders;
  opt.seconds = f.seconds;
  opt.seed = f.seed;
  opt.collider_scale = f.collider_scale;
  opt.fcl = !f.no_fcl;
  collision::QueryStream recorded;
  recorded.mesh_sha256 = sha;
  uint64_t seen = 0;
  bool too_many = false;
  std::string unreadable;  // why the first query a query file cannot hold was refused
  if (!f.record_queries.empty())
    opt.on_query = [&](const collision::Collider& c) {
      if (seen++ % static_cast<uint64_t>(f.record_every) != 0 || !unreadable.empty()) return;
      const std::string defect = collision::collider_defect(c);
      if (!defect.empty())
        unreadable = "query " + std::to_string(seen - 1) + ": " + defect;
      else if (recorded.colliders.size() < collision::kMaxRecordedQueries)
        recorded.colliders.push_back(c);
      else
        too_many = true;
    };
  // Nothing has been written yet (outputs are written whole at the end), so ending here
  // leaves no partial file.
  opt.on_physics_failure = [&](const std::string& why) {
    std::fprintf(stderr,
                 "vobb: %s: the physics engine stopped: %s (its tolerances are absolute, so "
                 "extreme model scales trip it); use --static\n",
                 one_line(basename_of(f.mesh)).c_str(), one_line(why).c_str());
    std::fflush(stderr);
    std::_Exit(2);
  };
  collision::ExperimentReport report;
  s = collision::run_collision_experiment(mesh.mesh, named, opt, &report);
  if (!s) return refuse(s);
  const collision::ReportHeader header{f.mesh, f.colliders, f.seed, f.collider_scale};
  const std::string out = f.json ? collision::experiment_report_json(header, report)
                                 : collision::experiment_report_text(header, report);
  if (f.output.empty()) {
    std::fputs(out.c_str(), stdout);
  } else {
    s = write_file_atomic(f.output, out);
    if (!s) return could_not_finish(s);  // its folder took a file when the run started
  }
  // The report is written whole first: a recording over its limit loses only itself.
  if (too_many)
    return refuse(Status::error("--record-queries: the run made more than " +
                                std::to_string(collision::kMaxRecordedQueries) +
                                " queries to record, so none were written; raise --record-every"));
  if (!unreadable.empty())
    return refuse(Status::error("--record-queries: " + unreadable +
                                ", which a query file cannot hold, so none were written"));
  if (!f.record_queries.empty()) {
    s = collision::write_query_stream(recorded, f.record_queries);
    if (!s) return could_not_finish(s);  // its folder took a file when the run started
  }
  if (!report.brute_force_agrees) {
    std::fprintf(stderr, "vobb: collide: a tree disagrees with brute force: %s\n",
                 one_line(report.first_disagreement).c_str());
    return kExitCheckFailed;
  }
  return kExitOk;
}

class CollideCommand final : public Command {
 public:
  CLI::App* add(CLI::App& app) override { return add_collide_command(app, &f_); }
  Status check_outputs() const override {
    std::vector<std::string> inputs = f_.trees;
    inputs.push_back(f_.mesh);
    Status s = check_output_is_not_input("-o", f_.output, inputs);
    if (s) s = check_output_is_writable("-o", f_.output);
    if (s && !f_.record_queries.empty()) {
      s = check_output_is_not_input("--record-queries", f_.record_queries, inputs);
      if (s) s = check_outputs_differ("--record-queries", f_.record_queries, "-o", f_.output);
      if (s) s = check_output_is_writable("--record-queries", f_.record_queries);
    }
    return s;
  }
  int run() override { return run_collide_command(f_); }

 private:
  CollideFlags f_;
};

}  // namespace

std::unique_ptr<Command> collide_command() { return std::make_unique<CollideCommand>(); }

}  // namespace vobb::app
