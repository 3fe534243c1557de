// The collision experiment on small analytic meshes: every tree agrees with brute force, FCL's
// replay of a baseline tree gives our yes/no answers, counts are repeatable by seed, a looser
// tree never costs fewer tests, and bad trees are refused. Also `vobb collide` end to end.
#include "validate/collision/collision_experiment.h"

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "builder/obbtree_builder.h"
#include "common/io/mesh_io.h"
#include "common/obb.h"
#include "common/sha256.h"
#include "common/tree_io.h"
#include "data/analytic_meshes.h"
#include "test_common.h"
#include "validate/collision/collision_test_util.h"

namespace vobb::collision {
namespace {

Tree baseline(const Mesh& mesh, int depth) {
  ObbTreeOptions opt;
  opt.depth = depth;
  Tree t = build_obbtree(mesh, opt);
  t.mesh_sha256 = mesh_sha256(mesh);
  return t;
}

// The same tree with every box's half extents doubled: still conservative, never tighter.
Tree inflated(const Tree& t) {
  Tree out = t;
  for (TreeNode& n : out.nodes) n.box.half *= 2;
  out.method = "inflated";
  return out;
}

ExperimentReport run(const Mesh& mesh, const std::vector<NamedTree>& trees, bool dynamic,
                     int colliders, uint64_t seed = 1, double seconds = 2.0) {
  ExperimentOptions opt;
  opt.dynamic = dynamic;
  opt.colliders = colliders;
  opt.seconds = seconds;
  opt.seed = seed;
  ExperimentReport r;
  const Status s = run_collision_experiment(mesh, trees, opt, &r);
  EXPECT_TRUE(s) << s.message();
  return r;
}

// 50 colliders on and near a torus: both trees agree with brute force on every query, and the
// scene has touching and clear queries both (so the agreement is not vacuous).
TEST(CollisionExperiment, StaticSceneAgreesWithBruteForce) {
  const Mesh mesh = analytic::polygonal_torus().mesh;
  const Tree base = baseline(mesh, 4), loose = inflated(base);
  const ExperimentReport r = run(mesh, {{"base", &base}, {"loose", &loose}}, false, 50);
  EXPECT_TRUE(r.brute_force_agrees) << r.first_disagreement;
  EXPECT_EQ(r.queries, 50u);
  EXPECT_GT(r.touching_queries, 0u);
  EXPECT_LT(r.touching_queries, r.queries);
  for (const TreeResult& t : r.trees) {
    EXPECT_EQ(t.disagreements, 0u);
    EXPECT_GE(t.counts.box_tests, r.queries);  // the root at least
    EXPECT_GT(t.counts.contacts, 0u);
    // The split by level: one root test per query, a test at every level of the depth-4 tree
    // (some queries touch), and the parts add up to the total.
    ASSERT_EQ(t.counts.box_tests_by_level.size(), 5u);
    EXPECT_EQ(t.counts.box_tests_by_level[0], r.queries);
    uint64_t sum = 0;
    for (uint64_t n : t.counts.box_tests_by_level) {
      EXPECT_GT(n, 0u);
      sum += n;
    }
    EXPECT_EQ(sum, t.counts.box_tests);
  }
  EXPECT_EQ(r.trees[0].counts.contacts, r.trees[1].counts.contacts);
  // Inflated boxes contain the originals, so every node the baseline opens, they open too.
  EXPECT_GE(r.trees[1].counts.box_tests, r.trees[0].counts.box_tests);
  EXPECT_LE(reduction_pct(static_cast<double>(r.trees[0].counts.box_tests),
                          static_cast<double>(r.trees[1].counts.box_tests)),
            0.0);
}

// 50 falling colliders over the octahedron and the cube with a cavity (ODE): agreement on
// every query the physics asks.
TEST(CollisionExperiment, DynamicSceneAgreesWithBruteForce) {
  for (const analytic::AnalyticMesh& am : {analytic::octahedron(), analytic::cube_with_cavity()}) {
    SCOPED_TRACE(am.name);
    const Tree base = baseline(am.mesh, 3);
    const ExperimentReport r = run(am.mesh, {{"base", &base}}, true, 50, 3, 3.0);
    EXPECT_TRUE(r.brute_force_agrees) << r.first_disagreement;
    EXPECT_GT(r.queries, 50u);
    EXPECT_GT(r.touching_queries, 0u);
    EXPECT_GT(r.ode_contacts, 0u);
    // 3 s in steps of the default 0.01 s: 300 steps, and the time they make, as a product.
    EXPECT_EQ(r.simulated_seconds, 300 * ExperimentOptions().step);
  }
}

// FCL, replaying the poses on the baseline tree loaded through our splitter and fitter, and on
// its own OBB tree, gives the same yes/no answer as our traversal on every query.
// The check can fail: a tree whose answers are changed (one face dropped from every touching
// answer, one added to every clear one) disagrees on every query, and only that tree; the
// report says so and names it.
TEST(CollisionExperiment, ChangedAnswersAreCaughtOnEveryQuery) {
  const Mesh mesh = analytic::polygonal_torus().mesh;
  const Tree base = baseline(mesh, 4), loose = inflated(base);
  ExperimentOptions opt;
  opt.dynamic = false;
  opt.colliders = 60;
  opt.fcl = false;
  opt.tamper_answer = [](size_t tree, uint64_t, std::vector<int32_t>* faces) {
    if (tree != 1) return;
    if (faces->empty())
      faces->push_back(0);
    else
      faces->pop_back();
  };
  ExperimentReport r;
  ASSERT_TRUE(run_collision_experiment(mesh, {{"base", &base}, {"loose", &loose}}, opt, &r));
  EXPECT_FALSE(r.brute_force_agrees);
  EXPECT_EQ(r.trees[0].disagreements, 0u);
  EXPECT_EQ(r.trees[1].disagreements, r.queries);
  EXPECT_EQ(r.first_disagreement.rfind("loose: query 1 ", 0), 0u) << r.first_disagreement;
}

TEST(CollisionExperiment, FclReplayOfBaselineGivesOurAnswers) {
  const Mesh mesh = analytic::polygonal_torus().mesh;
  const Tree base = baseline(mesh, 4);
  const ExperimentReport r = run(mesh, {{"base", &base}}, false, 300, 5);
  ASSERT_TRUE(r.brute_force_agrees);
  const FclCounts& f = r.trees[0].fcl;
  ASSERT_TRUE(f.available) << f.note;
  EXPECT_EQ(f.answer_disagreements, 0u);
  EXPECT_EQ(r.fcl_own.answer_disagreements, 0u);
  EXPECT_GT(f.bv_tests, 0u);
  // Padding nodes only add tests; those on our nodes are at most our node count per query.
  EXPECT_LE(f.tree_node_bv_tests, f.bv_tests);
  EXPECT_LE(f.tree_node_bv_tests, r.queries * base.nodes.size());
  EXPECT_GT(f.tree_node_bv_tests, 0u);
}

// A node of more than two children reaches FCL's binary BVH through padding nodes
// (fcl_referee.h): the loaded arity-4 tree still holds our partition, so FCL's answers and
// touching faces are ours, and its tests on our nodes are fewer than its raw count.
TEST(CollisionExperiment, FclReplayOfAnArityFourTree) {
  const Mesh mesh = analytic::polygonal_torus().mesh;
  ObbTreeOptions opt;
  opt.depth = 3;
  opt.arity = 4;
  Tree quad = build_obbtree(mesh, opt);
  ASSERT_GT(quad.nodes[0].children.size(), 2u);
  const ExperimentReport r = run(mesh, {{"quad", &quad}}, false, 300, 6);
  ASSERT_TRUE(r.brute_force_agrees);
  const FclCounts& f = r.trees[0].fcl;
  ASSERT_TRUE(f.available) << f.note;
  EXPECT_EQ(f.answer_disagreements, 0u);
  EXPECT_EQ(f.face_disagreements, 0u);
  EXPECT_GT(f.tree_node_bv_tests, 0u);
  EXPECT_LT(f.tree_node_bv_tests, f.bv_tests);
}

TEST(CollisionExperiment, SameSeedSameCounts) {
  const Mesh mesh = analytic::polygonal_torus().mesh;
  const Tree base = baseline(mesh, 4);
  const ExperimentReport a = run(mesh, {{"base", &base}}, true, 40, 11, 1.0);
  const ExperimentReport b = run(mesh, {{"base", &base}}, true, 40, 11, 1.0);
  const ExperimentReport c = run(mesh, {{"base", &base}}, true, 40, 12, 1.0);
  EXPECT_EQ(a.queries, b.queries);
  EXPECT_EQ(a.trees[0].counts.box_tests, b.trees[0].counts.box_tests);
  EXPECT_EQ(a.trees[0].counts.leaf_tests, b.trees[0].counts.leaf_tests);
  EXPECT_EQ(a.trees[0].fcl.bv_tests, b.trees[0].fcl.bv_tests);
  EXPECT_NE(a.trees[0].counts.box_tests, c.trees[0].counts.box_tests);
}

// --collider-scale multiplies the sizes only. Tiny and huge colliders still agree with brute
// force on every query, and on the same draws (static: the same surface points, the offsets
// scaled with the size) larger colliders open strictly more boxes, so the scale is applied.
// Out-of-range scales are refused.
// The dynamic scene is defined relative to R (sizes, drops, gravity, the bounce threshold, and
// masses that do not grow with R^3), so a model's units do not change it. Scaling the mesh and
// its tree by a power of two scales every length exactly, so the counts must be equal, not
// close. (Before, a model 16 times larger saw 40 % fewer touching queries: ODE's bounce
// threshold and masses were absolute.)
TEST(CollisionExperiment, DynamicSceneDoesNotDependOnTheModelsUnits) {
  const Mesh unit = analytic::polygonal_torus().mesh;
  const Tree unit_tree = baseline(unit, 3);
  std::vector<ExperimentReport> reports;
  for (double scale : {0.25, 1.0, 4.0}) {
    Mesh mesh = unit;
    for (Vec3& v : mesh.vertices) v *= scale;
    Tree tree = unit_tree;
    for (TreeNode& n : tree.nodes) {
      n.box.center *= scale;
      n.box.half *= scale;
    }
    reports.push_back(run(mesh, {{"tree", &tree}}, true, 100, 1, 3.0));
    const ExperimentReport& r = reports.back();
    EXPECT_TRUE(r.brute_force_agrees) << r.first_disagreement;
    EXPECT_GT(r.touching_queries, 100u) << "scale " << scale;
  }
  for (size_t i = 1; i < reports.size(); ++i) {
    EXPECT_EQ(reports[i].queries, reports[0].queries) << i;
    EXPECT_EQ(reports[i].touching_queries, reports[0].touching_queries) << i;
    EXPECT_EQ(reports[i].ode_contacts, reports[0].ode_contacts) << i;
    EXPECT_EQ(reports[i].trees[0].counts.box_tests, reports[0].trees[0].counts.box_tests) << i;
    EXPECT_EQ(reports[i].trees[0].counts.leaf_tests, reports[0].trees[0].counts.leaf_tests) << i;
  }
}

TEST(CollisionExperiment, ColliderScaleKeepsAgreementAndGrowsTests) {
  const Mesh mesh = analytic::polygonal_torus().mesh;
  const Tree base = baseline(mesh, 4);
  uint64_t previous = 0;
  for (double scale : {0.05, 1.0, 5.0}) {
    SCOPED_TRACE(scale);
    ExperimentOptions opt;
    opt.dynamic = false;
    opt.colliders = 100;
    opt.seed = 7;
    opt.collider_scale = scale;
    ExperimentReport r;
    ASSERT_TRUE(run_collision_experiment(mesh, {{"base", &base}}, opt, &r));
    EXPECT_TRUE(r.brute_force_agrees) << r.first_disagreement;
    EXPECT_GT(r.touching_queries, 0u);
    EXPECT_GT(r.trees[0].counts.box_tests, previous);
    previous = r.trees[0].counts.box_tests;
  }
  ExperimentOptions dyn;
  dyn.colliders = 30;
  dyn.seconds = 2.0;
  dyn.collider_scale = 3.0;
  ExperimentReport r;
  ASSERT_TRUE(run_collision_experiment(mesh, {{"base", &base}}, dyn, &r));
  EXPECT_TRUE(r.brute_force_agrees) << r.first_disagreement;
  EXPECT_GT(r.touching_queries, 0u);
  for (double bad : {0.0, 0.009, 10.5, std::nan("")}) {
    dyn.collider_scale = bad;
    const Status s = run_collision_experiment(mesh, {{"base", &base}}, dyn, &r);
    ASSERT_FALSE(s) << bad;
    EXPECT_NE(s.message().find("collider scale"), std::string::npos) << s.message();
  }
}

// A tree whose box misses one of its faces is refused before any query: pruning on it could
// hide a touching face.
TEST(CollisionExperiment, RefusesANonConservativeTree) {
  const Mesh mesh = analytic::polygonal_torus().mesh;
  Tree bad = baseline(mesh, 3);
  bad.nodes.back().box.half *= 0.5;
  ExperimentOptions opt;
  opt.dynamic = false;
  opt.colliders = 5;
  ExperimentReport r;
  const Status s = run_collision_experiment(mesh, {{"bad.json", &bad}}, opt, &r);
  ASSERT_FALSE(s);
  EXPECT_NE(s.message().find("bad.json: not conservative"), std::string::npos) << s.message();
}

// The dynamic scene holds every collider as a physics body at once: beyond
// kMaxDynamicColliders it is refused before any body is made (10^7 took 10.5 GB), while the
// static scene takes as many poses as asked.
TEST(CollisionExperiment, DynamicSceneRefusesMoreBodiesThanItsLimit) {
  const Mesh mesh = analytic::octahedron().mesh;
  const Tree tree = baseline(mesh, 1);
  ExperimentOptions opt;
  opt.colliders = kMaxDynamicColliders + 1;
  opt.seconds = 0;
  opt.fcl = false;
  ExperimentReport r;
  const Status s = run_collision_experiment(mesh, {{"t.json", &tree}}, opt, &r);
  ASSERT_FALSE(s);
  EXPECT_NE(s.message().find("at most 1000000 colliders in the dynamic scene"), std::string::npos)
      << s.message();
  EXPECT_EQ(r.queries, 0u);
}

using test::CliRun;
using test::vobb_cli;

TEST(CollideCli, StaticRunJsonAndBadInput) {
  const Mesh torus = analytic::polygonal_torus().mesh, octa = analytic::octahedron().mesh;
  const std::string mesh_path = test::temp_path("torus.off"),
                    other_path = test::temp_path("octa.off");
  const std::string tree_path = test::temp_path("torus_tree.json"),
                    out_path = test::temp_path("collide.json");
  ASSERT_TRUE(save_mesh(torus, mesh_path, MeshFormat::kOff));
  ASSERT_TRUE(save_mesh(octa, other_path, MeshFormat::kOff));
  const std::string loose_path = test::temp_path("torus_loose.json");
  ASSERT_TRUE(write_tree(baseline(torus, 3), tree_path));
  ASSERT_TRUE(write_tree(inflated(baseline(torus, 3)), loose_path));

  CliRun r = vobb_cli("collide " + mesh_path + " " + tree_path + " " + loose_path +
                      " --static --colliders 60 --json -o " + out_path);
  EXPECT_EQ(r.code, 0) << r.err;
  std::ifstream in(out_path);
  const nlohmann::json j = nlohmann::json::parse(in);
  std::remove(loose_path.c_str());
  EXPECT_EQ(j["queries"], 60);
  EXPECT_EQ(j["brute_force_agrees"], true);
  ASSERT_EQ(j["trees"].size(), 2u);
  // The inflated boxes hold the baseline's, so they open every node it opens, and more here;
  // the change is the one the two counts give (1 - loose / base, in %; the report's own order
  // of operations, so exactly equal).
  const double base = j["trees"][0]["box_tests"], loose = j["trees"][1]["box_tests"];
  EXPECT_GT(loose, base);
  EXPECT_EQ(j["trees"][0]["reduction_pct"], 0.0);
  EXPECT_EQ(j["trees"][1]["reduction_pct"].get<double>(), 100.0 * (1.0 - loose / base));
  EXPECT_LT(j["trees"][1]["reduction_pct"].get<double>(), 0.0);
  EXPECT_EQ(j["trees"][0]["contacts"], j["trees"][1]["contacts"]);  // the same faces touched
  EXPECT_EQ(j["trees"][0]["box_tests_by_level"][0], 60);
  for (const char* key : {"file", "box_tests", "box_tests_by_level", "leaf_tests", "contacts",
                          "narrow_phase_seconds", "fcl_bv_tests", "reduction_pct"})
    EXPECT_TRUE(j["trees"][0].contains(key)) << key;

  // The tree belongs to another mesh: exit 2, one line naming the tree file.
  r = vobb_cli("collide " + other_path + " " + tree_path + " --static --colliders 5");
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find(tree_path), std::string::npos) << r.err;
  // A collider scale out of range, or not a number: a usage error naming the option.
  for (const char* scale : {"0", "nan", "11"}) {
    r = vobb_cli("collide " + mesh_path + " " + tree_path +
                 " --static --colliders 5 --collider-scale " + scale);
    EXPECT_EQ(r.code, 2) << scale;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find("collider-scale"), std::string::npos) << r.err;
  }
  r = vobb_cli("collide " + mesh_path + " " + tree_path +
               " --static --colliders 5 --json --collider-scale 0.5");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["collider_scale"], 0.5);
  r = vobb_cli("collide /nonexistent/mesh.off " + tree_path);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("mesh.off"), std::string::npos) << r.err;
  // Too short to reach the model (the colliders fall for at least 0.45 s): nothing was asked,
  // so nothing is reported as agreeing.
  r = vobb_cli("collide " + mesh_path + " " + tree_path + " --colliders 20 --seconds 0.2");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find("no collider reached the model"), std::string::npos) << r.err;

  // Text: where FCL did not run, its columns say "-", not a count of 0 or a change of -100 %.
  // A root with a single child (valid for us, not for FCL's binary BVH) is skipped by FCL with
  // a note; the baseline after it gets FCL counts but no change against the first tree.
  Tree single = test_util::root_with_one_child(torus);
  single.mesh_sha256 = mesh_sha256(torus);
  const std::string single_path = test::temp_path("single_child.json");
  ASSERT_TRUE(write_tree(single, single_path));
  r = vobb_cli("collide " + mesh_path + " " + single_path + " " + tree_path +
               " --static --colliders 20");
  EXPECT_EQ(r.code, 0) << r.err;
  std::istringstream lines(r.out);
  std::string line;
  int rows = 0;
  while (std::getline(lines, line)) {
    if (line.rfind(single_path, 0) == 0) {  // no FCL at all
      ++rows;
      EXPECT_NE(line.find("              -              -         -         -"), std::string::npos)
          << line;
    } else if (line.rfind(tree_path, 0) == 0) {  // FCL counts, no FCL change
      ++rows;
      EXPECT_NE(line.find("         -         -"), std::string::npos) << line;
      EXPECT_EQ(line.find("-100.00"), std::string::npos) << line;
    }
  }
  EXPECT_EQ(rows, 2) << r.out;
  EXPECT_NE(r.out.find("FCL skipped: " + single_path + ": a node has a single child"),
            std::string::npos)
      << r.out;
  for (const std::string& p : {mesh_path, other_path, tree_path, out_path, single_path})
    std::remove(p.c_str());
}

}  // namespace
}  // namespace vobb::collision
