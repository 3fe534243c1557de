#include <fmt/printf.h>

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

std::string format_json(const CollideFlags& f, const collision::ExperimentReport& r) {
  using collision::reduction_pct;
  nlohmann::ordered_json j;
  j["mode"] = r.dynamic ? "dynamic" : "static";
  j["mesh"] = f.mesh;
  j["colliders"] = f.colliders;
  j["seed"] = f.seed;
  j["collider_scale"] = f.collider_scale;
  j["simulated_seconds"] = r.simulated_seconds;
  j["queries"] = r.queries;
  j["touching_queries"] = r.touching_queries;
  j["brute_force_agrees"] = r.brute_force_agrees;
  if (!r.brute_force_agrees) j["first_disagreement"] = r.first_disagreement;
  j["brute_force_seconds"] = r.brute_force_seconds;
  j["exact_fallbacks"] = r.exact_fallbacks;
  if (r.dynamic) j["ode_contacts"] = r.ode_contacts;
  const double unit = r.dynamic ? r.simulated_seconds : static_cast<double>(r.queries);
  const auto& t0 = r.trees.front();
  nlohmann::ordered_json trees = nlohmann::ordered_json::array();
  for (const auto& t : r.trees) {
    nlohmann::ordered_json jt;
    jt["file"] = t.name;
    jt["method"] = t.method;
    jt["depth"] = t.depth;
    jt["arity"] = t.arity;
    jt["nodes"] = t.nodes;
    jt["box_tests"] = t.counts.box_tests;
    jt["box_tests_by_level"] = t.counts.box_tests_by_level;
    jt["leaf_tests"] = t.counts.leaf_tests;
    jt["contacts"] = t.counts.contacts;
    jt["narrow_phase_seconds"] = t.narrow_phase_seconds;
    jt[r.dynamic ? "box_tests_per_second" : "box_tests_per_query"] = t.counts.box_tests / unit;
    jt["reduction_pct"] = reduction_pct(t0.counts.box_tests, t.counts.box_tests);
    jt["disagreements"] = t.disagreements;
    if (t.fcl.available) {
      jt["fcl_bv_tests"] = t.fcl.bv_tests;
      jt["fcl_tree_node_bv_tests"] = t.fcl.tree_node_bv_tests;
      jt["fcl_leaf_tests"] = t.fcl.leaf_tests;
      if (t0.fcl.available) {
        jt["fcl_reduction_pct"] = reduction_pct(t0.fcl.bv_tests, t.fcl.bv_tests);
        jt["fcl_tree_node_reduction_pct"] =
            reduction_pct(t0.fcl.tree_node_bv_tests, t.fcl.tree_node_bv_tests);
      }
      jt["fcl_answer_disagreements"] = t.fcl.answer_disagreements;
      jt["fcl_face_disagreements"] = t.fcl.face_disagreements;
    } else {
      jt["fcl_bv_tests"] = nullptr;
      if (!t.fcl.note.empty()) jt["fcl_note"] = t.fcl.note;
    }
    trees.push_back(jt);
  }
  j["trees"] = trees;
  if (r.fcl_own.available)
    j["fcl_own_obb_tree"] = {{"bv_tests", r.fcl_own.bv_tests},
                             {"leaf_tests", r.fcl_own.leaf_tests},
                             {"answer_disagreements", r.fcl_own.answer_disagreements},
                             {"face_disagreements", r.fcl_own.face_disagreements}};
  return vobb::app::report_json(j) + "\n";
}

std::string format_text(const CollideFlags& f, const collision::ExperimentReport& r) {
  using ull = unsigned long long;
  // The text shows changes (negative: fewer tests), the JSON reductions (positive: fewer).
  // Adding +0.0 turns the first tree's -0.0 into 0.0, which prints without a sign.
  auto change_pct = [](double first, double other) {
    return -collision::reduction_pct(first, other) + 0.0;
  };
  std::string out;
  const double unit = r.dynamic ? r.simulated_seconds : static_cast<double>(r.queries);
  out += fmt::sprintf(
      "%s: %llu queries (%llu touching), %.3g s simulated, collider scale %g; brute force agrees: "
      "%s\n",
      r.dynamic ? "dynamic" : "static", static_cast<ull>(r.queries),
      static_cast<ull>(r.touching_queries), r.simulated_seconds, f.collider_scale,
      r.brute_force_agrees ? "yes" : ("NO (" + r.first_disagreement + ")").c_str());
  out += fmt::sprintf("%-28s %14s %10s %14s %10s %10s %9s %14s %14s %9s %9s\n", "tree", "box tests",
                      r.dynamic ? "per s" : "per query", "leaf tests", "contacts", "narrow s",
                      "change %", "fcl bv tests", "fcl on nodes", "fcl %", "nodes %");
  const auto& t0 = r.trees.front();
  for (const auto& t : r.trees) {
    out +=
        fmt::sprintf("%-28s %14llu %10.4g %14llu %10llu %10.3f %+9.2f", t.name.c_str(),
                     static_cast<ull>(t.counts.box_tests), t.counts.box_tests / unit,
                     static_cast<ull>(t.counts.leaf_tests), static_cast<ull>(t.counts.contacts),
                     t.narrow_phase_seconds, change_pct(t0.counts.box_tests, t.counts.box_tests));
    // FCL's columns only where it ran on this tree, its changes only where it ran on the first.
    if (!t.fcl.available) {
      out += fmt::sprintf(" %14s %14s %9s %9s\n", "-", "-", "-", "-");
      continue;
    }
    out += fmt::sprintf(" %14llu %14llu", static_cast<ull>(t.fcl.bv_tests),
                        static_cast<ull>(t.fcl.tree_node_bv_tests));
    if (t0.fcl.available)
      out += fmt::sprintf(" %+9.2f %+9.2f\n", change_pct(t0.fcl.bv_tests, t.fcl.bv_tests),
                          change_pct(t0.fcl.tree_node_bv_tests, t.fcl.tree_node_bv_tests));
    else
      out += fmt::sprintf(" %9s %9s\n", "-", "-");
  }
  for (const auto& t : r.trees)
    if (!t.fcl.available && !t.fcl.note.empty()) out += "FCL skipped: " + t.fcl.note + "\n";
  out += "box tests by level (root = 0), change % against the first tree:\n";
  for (const auto& t : r.trees) {
    out += "  " + t.name + ":";
    for (size_t l = 0; l < t.counts.box_tests_by_level.size(); ++l) {
      const uint64_t n = t.counts.box_tests_by_level[l];
      out += fmt::sprintf(" %llu", static_cast<ull>(n));
      if (&t != &t0 && l < t0.counts.box_tests_by_level.size())
        out += fmt::sprintf(" (%+.1f)", change_pct(t0.counts.box_tests_by_level[l], n));
    }
    out += "\n";
  }
  if (r.fcl_own.available)
    out +=
        fmt::sprintf("FCL's own OBB tree: %llu bv tests, %llu leaf tests\n",
                     static_cast<ull>(r.fcl_own.bv_tests), static_cast<ull>(r.fcl_own.leaf_tests));
  return out;
}

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
  c->add_flag("--static", f->static_mode, "No dynamics: poses sampled on and near the surface");
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
      ->check(CLI::Range(1, 1000000000))
      ->needs(record);
  return c;
}

int run_collide_command(const CollideFlags& f) {
  LoadedMesh mesh;
  Status s = load_solid(f.mesh, &mesh);
  if (!s) return refuse(s);
  note_precision(f.mesh, mesh);
  const std::string sha = mesh_sha256(mesh.mesh);
  std::vector<Tree> trees(f.trees.size());
  std::vector<collision::NamedTree> named;
  for (size_t i = 0; i < f.trees.size(); ++i) {
    s = read_tree(f.trees[i], &trees[i]);
    if (!s) return refuse(s);
    if (!trees[i].mesh_sha256.empty() && trees[i].mesh_sha256 != sha)
      return refuse(Status::error(f.trees[i] + ": built for another mesh (sha256 differs)"));
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
  if (!f.record_queries.empty())
    opt.on_query = [&](const collision::Collider& c) {
      if (seen++ % static_cast<uint64_t>(f.record_every) != 0) return;
      if (recorded.colliders.size() < collision::kMaxRecordedQueries)
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
  const std::string out = f.json ? format_json(f, report) : format_text(f, report);
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
