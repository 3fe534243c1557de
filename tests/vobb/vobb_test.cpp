// The public face, linked without its GL component: its wiring gives the trees and values of
// the libraries it wires, its refusals are one-line errors, and its e is the certificate's.
#include "vobb/vobb.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "builder/subtree_swaps.h"
#include "common/exact_predicates.h"
#include "common/sha256.h"
#include "data/analytic_meshes.h"
#include "fast/cpu_estimator.h"
#include "fast/cubemap_bound.h"
#include "fast/poly_overlap.h"
#include "fast/poly_solver.h"
#include "test_common.h"

namespace vobb {
namespace {

BuildOptions small_build() {
  BuildOptions o;
  o.depth = 3;
  o.m = 8;
  o.backend = Backend::kCpu;
  o.lloyd = 2;
  o.sweeps = 1;
  return o;
}

// compare with small_build and the exact values as rationals: whether it ran and certified
// both trees.
bool compare_small(const Mesh& mesh, CompareResult* r) {
  CompareOptions o;
  o.build = small_build();
  o.rational = true;
  const Status s = compare(mesh, o, r);
  EXPECT_TRUE(s.is_ok()) << s.message();
  return s.is_ok() && r->certified();
}

// build_tree's variational tree is build_variational's with the CPU twin, bit for bit, and its
// mesh_sha256 is the mesh's. Its objective is kOmv unless set, with the polyhedral solver's
// shares; set to kObv, the builder's own default, no share is taken.
TEST(BuildTree, IsTheBuilderWithTheChosenEstimator) {
  const Mesh mesh = analytic::polygonal_torus().mesh;
  const BuildOptions o = small_build();
  Tree via_face;
  BuildReport report;
  ASSERT_TRUE(build_tree(mesh, o, &via_face, &report).is_ok());
  EXPECT_EQ(report.estimator, "cpu");
  EXPECT_EQ(via_face.mesh_sha256, mesh_sha256(mesh));

  VariationalOptions v;
  v.depth = o.depth;
  v.lloyd_iterations = o.lloyd;
  v.max_sweeps = o.sweeps;
  v.concurrent_estimates = true;
  v.objective = Objective::kOmv;
  const PolyOverlapSolver shares(mesh);
  v.share = [&](const std::vector<ShareQuery>& q) { return shares.estimate(q); };
  const CpuObvEstimator cpu(mesh);
  // Each estimate moved into the range that holds the box's OBV, the solid's volume rounded up.
  const double solid = std::nextafter(to_double_nearest(exact_signed_volume(mesh)), 1e300);
  const ObvEstimate estimate = [&](const std::vector<Obb>& b) {
    std::vector<double> v = cpu.estimate(b, o.m);
    for (size_t i = 0; i < v.size(); ++i) v[i] = clamp_to_obv_range(b[i], v[i], solid);
    return v;
  };
  Tree direct = build_variational(mesh, v, estimate);
  direct.mesh_sha256 = mesh_sha256(mesh);
  EXPECT_EQ(tree_to_json(via_face), tree_to_json(direct));
  EXPECT_GT(report.search.overlaps, 0u);

  BuildOptions paper = o;
  paper.objective = Objective::kObv;
  Tree via_face_obv;
  ASSERT_TRUE(build_tree(mesh, paper, &via_face_obv, &report).is_ok());
  EXPECT_EQ(report.search.overlaps, 0u);
  v.objective = Objective::kObv;
  v.share = nullptr;
  Tree direct_obv = build_variational(mesh, v, estimate);
  direct_obv.mesh_sha256 = mesh_sha256(mesh);
  EXPECT_EQ(tree_to_json(via_face_obv), tree_to_json(direct_obv));
  EXPECT_NE(tree_to_json(via_face_obv), tree_to_json(via_face));  // the objective reached it
}

// With subtree_swaps, build_tree's tree is its tree without them, then swap_subtrees scored by
// the polyhedral solver (whatever the search's backend), bit for bit; `swapped` reports the
// step's counts, and on this torus it swaps.
TEST(BuildTree, SubtreeSwapsAreTheStepAfterTheSearch) {
  const Mesh mesh = analytic::polygonal_torus().mesh;
  BuildOptions o = small_build();
  o.depth = 4;
  Tree plain, swapped;
  ASSERT_TRUE(build_tree(mesh, o, &plain).is_ok());
  o.subtree_swaps = true;
  SubtreeSwapReport seen;
  bool called = false;
  o.swapped = [&](const SubtreeSwapReport& r) { seen = r, called = true; };
  ASSERT_TRUE(build_tree(mesh, o, &swapped).is_ok());
  ASSERT_TRUE(called);
  EXPECT_GT(seen.swaps, 0u);

  const PolyObvSolver obv(mesh);
  const PolyOverlapSolver shares(mesh);
  SubtreeSwapOptions so;
  so.estimate = [&](const std::vector<Obb>& b) { return obv.estimate(b); };
  so.share = [&](const std::vector<ShareQuery>& q) { return shares.estimate(q); };
  Tree direct = plain;
  SubtreeSwapReport r;
  swap_subtrees(mesh, so, &direct, &r);
  EXPECT_EQ(tree_to_json(swapped), tree_to_json(direct));
  EXPECT_EQ(seen.swaps, r.swaps);
  EXPECT_EQ(seen.e_after, r.e_after);
  EXPECT_EQ(swapped.mesh_sha256, mesh_sha256(mesh));
}

// With a collider margin the default objective is the sum (a collider in a shared region tests
// both boxes): the tree of kObv set, with no shares; kOmv set still takes them.
TEST(BuildTree, ColliderMarginDefaultsToTheSum) {
  const Mesh mesh = analytic::polygonal_torus().mesh;
  BuildOptions o = small_build();
  o.collider_margin = 0.05;
  EXPECT_EQ(search_objective(o), Objective::kObv);
  Tree by_default, by_sum, by_union;
  BuildReport report;
  ASSERT_TRUE(build_tree(mesh, o, &by_default, &report).is_ok());
  EXPECT_EQ(report.search.overlaps, 0u);
  o.objective = Objective::kObv;
  ASSERT_TRUE(build_tree(mesh, o, &by_sum).is_ok());
  EXPECT_EQ(tree_to_json(by_default), tree_to_json(by_sum));
  o.objective = Objective::kOmv;
  ASSERT_TRUE(build_tree(mesh, o, &by_union, &report).is_ok());
  EXPECT_GT(report.search.overlaps, 0u);
}

// Without the GL component, kGl is refused in one line and kAuto takes the CPU twin even from
// the m at which it would try a GPU.
TEST(BuildTree, WithoutTheGlComponentGlIsRefusedAndAutoTakesTheCpuTwin) {
  const Mesh mesh = analytic::cube().mesh;
  BuildOptions o = small_build();
  o.depth = 1;
  o.backend = Backend::kGl;
  Tree tree;
  const Status s = build_tree(mesh, o, &tree);
  ASSERT_FALSE(s.is_ok());
  EXPECT_NE(s.message().find("GL is not enabled"), std::string::npos) << s.message();
  EXPECT_EQ(s.message().find('\n'), std::string::npos);
  o.backend = Backend::kAuto;
  o.m = kAutoGlFromM;
  BuildReport report;
  ASSERT_TRUE(build_tree(mesh, o, &tree, &report).is_ok());
  EXPECT_EQ(report.estimator, "cpu");
}

// Options out of range or contradicting each other: an error naming the option.
TEST(BuildTree, RefusesOptionsThatContradictEachOther) {
  const Mesh mesh = analytic::cube().mesh;
  struct Case {
    std::function<void(BuildOptions*)> set;
    std::string names;
  };
  const std::vector<Case> cases = {
      {[](BuildOptions* o) { o->method = Method::kObbTree, o->checkpoint = "x"; }, "--checkpoint"},
      {[](BuildOptions* o) { o->method = Method::kObbTree, o->time_budget = 1; }, "--time-budget"},
      {[](BuildOptions* o) { o->method = Method::kObbTree, o->objective = Objective::kOmv; },
       "--objective"},
      {[](BuildOptions* o) { o->collider_margin = -1; }, "--collider-margin"},
      {[](BuildOptions* o) { o->collider_margin = 1e9; }, "bounding-box diagonal"},
      {[](BuildOptions* o) { o->method = Method::kObbTree, o->objective = Objective::kObv; },
       "--objective"},
      {[](BuildOptions* o) { o->queries.resize(1), o->objective = Objective::kOmv; }, "--queries"},
      {[](BuildOptions* o) { o->queries.resize(1), o->objective = Objective::kObv; }, "--queries"},
      {[](BuildOptions* o) { o->method = Method::kObbTree, o->subtree_swaps = true; },
       "--subtree-swaps"},
      {[](BuildOptions* o) { o->subtree_swaps = true, o->collider_margin = 0.1; },
       "--subtree-swaps"},
      {[](BuildOptions* o) { o->subtree_swaps = true, o->queries.resize(1); }, "--subtree-swaps"},
      {[](BuildOptions* o) { o->depth = 31; }, "--depth"},
      {[](BuildOptions* o) { o->arity = 1; }, "--arity"},
      {[](BuildOptions* o) { o->m = 0; }, "--m"},
      {[](BuildOptions* o) { o->lloyd = -1; }, "--lloyd"},
      {[](BuildOptions* o) { o->lloyd = 1001; }, "--lloyd"},
      {[](BuildOptions* o) { o->sweeps = -1; }, "--sweeps"},
      {[](BuildOptions* o) { o->sweeps = 101; }, "--sweeps"},
      {[](BuildOptions* o) { o->time_budget = -1; }, "--time-budget"},
      {[](BuildOptions* o) { o->time_budget = std::nan(""); }, "--time-budget"},
      {[](BuildOptions* o) { o->time_budget = 1e-4; }, "--time-budget"},
      // Values outside the enums' lists, which only a cast makes.
      {[](BuildOptions* o) { o->method = static_cast<Method>(2); }, "--method"},
      {[](BuildOptions* o) { o->backend = static_cast<Backend>(-1); }, "--backend"},
      {[](BuildOptions* o) { o->objective = static_cast<Objective>(2); }, "--objective"},
  };
  for (const Case& c : cases) {
    BuildOptions o = small_build();
    c.set(&o);
    Tree tree;
    const Status s = build_tree(mesh, o, &tree);
    ASSERT_FALSE(s.is_ok()) << c.names;
    EXPECT_NE(s.message().find(c.names), std::string::npos) << s.message();
  }
}

// A build interrupted after its first saved state and started again resumes (it says so) and
// gives the uninterrupted tree.
TEST(BuildTree, ResumesFromItsCheckpoint) {
  const Mesh mesh = analytic::polygonal_torus().mesh;
  BuildOptions o = small_build();
  Tree whole;
  ASSERT_TRUE(build_tree(mesh, o, &whole).is_ok());
  const std::string folder = test::temp_path("face_checkpoint");
  std::filesystem::remove_all(folder);
  o.checkpoint = folder;
  struct Stop {};
  o.saved = [](const VariationalState& st) {
    if (st.split_levels == 2) throw Stop{};
  };
  Tree tree;
  EXPECT_THROW(build_tree(mesh, o, &tree), Stop);
  o.saved = nullptr;
  std::vector<std::string> notes;
  o.note = [&](const std::string& line) { notes.push_back(line); };
  ASSERT_TRUE(build_tree(mesh, o, &tree).is_ok());
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_EQ(notes[0].rfind("resuming from ", 0), 0u) << notes[0];
  EXPECT_EQ(tree_to_json(tree), tree_to_json(whole));
  std::filesystem::remove_all(folder);
}

// A state saved after the time budget ran out holds baseline splits where the search was cut:
// a build without a budget refuses it (it would write that tree as its own) and leaves it as it
// was, as does compare, before its baseline is certified (no certification folder is made); a
// build with a budget resumes it, as spent.
TEST(BuildTree, RefusesToResumeASpentBudgetWithoutOne) {
  const Mesh mesh = analytic::polygonal_torus().mesh;
  BuildOptions o = small_build();
  const std::string folder = test::temp_path("spent_checkpoint");
  std::filesystem::remove_all(folder);
  o.checkpoint = folder;
  o.time_budget = 1e-3;  // the least accepted: spent before the first level is searched
  Tree spent;
  ASSERT_TRUE(build_tree(mesh, o, &spent).is_ok());
  const std::string state = folder + "/state.json";
  const std::string saved = test::slurp(state);
  ASSERT_NE(saved.find("\"budget_spent\":true"), std::string::npos) << "no spent state to resume";
  o.time_budget = 0;
  Tree tree;
  const Status s = build_tree(mesh, o, &tree);
  EXPECT_FALSE(s.is_ok());
  EXPECT_NE(s.message().find("--time-budget"), std::string::npos) << s.message();
  EXPECT_EQ(test::slurp(state), saved);
  CompareOptions co;
  co.build = o;
  CompareResult cr;
  const Status cs = compare(mesh, co, &cr);
  EXPECT_FALSE(cs.is_ok());
  EXPECT_NE(cs.message().find("--time-budget"), std::string::npos) << cs.message();
  EXPECT_FALSE(std::filesystem::exists(folder + "/certify-obbtree"));
  EXPECT_EQ(test::slurp(state), saved);
  o.time_budget = 1e-3;
  std::vector<std::string> notes;
  o.note = [&](const std::string& line) { notes.push_back(line); };
  ASSERT_TRUE(build_tree(mesh, o, &tree).is_ok());
  ASSERT_EQ(notes.size(), 1u);  // resumed, not built again (which gives the same tree here)
  EXPECT_EQ(notes[0].rfind("resuming from ", 0), 0u) << notes[0];
  EXPECT_EQ(tree_to_json(tree), tree_to_json(spent));
  std::filesystem::remove_all(folder);
}

// tree_error weighs layer l of a depth-D tree by D - l + 1 (DESIGN §1), written out here, and
// as the certificate does: equal as rationals.
TEST(Certify, TreeErrorIsTheCertificatesE) {
  EXPECT_TRUE(tree_error({Rational(7), Rational(7)}) == Rational(21));  // 2 * 7 + 1 * 7
  // 4 * 1 + 3 * 2 + 2 * 3 + 1 * 4
  EXPECT_TRUE(tree_error({Rational(1), Rational(2), Rational(3), Rational(4)}) == Rational(20));
  const Mesh mesh = analytic::polygonal_torus().mesh;
  Tree tree;
  ASSERT_TRUE(build_tree(mesh, small_build(), &tree).is_ok());
  CertifyOptions o;
  o.rational = true;
  exact::Certificate c;
  ASSERT_TRUE(certify(mesh, tree, o, &c).is_ok());
  ASSERT_TRUE(c.ok());
  std::vector<Rational> omv;
  Rational weighted = 0;
  const long depth = static_cast<long>(c.layers.size()) - 1;
  for (const exact::LayerCertificate& l : c.layers) {
    omv.push_back(l.omv);
    weighted += Rational(static_cast<double>(depth - l.level + 1)) * l.omv;
  }
  ASSERT_GE(depth, 2);
  EXPECT_TRUE(tree_error(omv) == c.weighted_error);
  EXPECT_TRUE(weighted == c.weighted_error);
}

TEST(Certify, RefusesAPathOutsideItsList) {
  const Mesh cube = analytic::cube().mesh;
  Tree tree;
  ASSERT_TRUE(build_tree(cube, small_build(), &tree).is_ok());
  CertifyOptions o;
  o.path = static_cast<exact::OmvPath>(4);
  exact::Certificate c;
  const Status s = certify(cube, tree, o, &c);
  ASSERT_FALSE(s.is_ok());
  EXPECT_NE(s.message().find("--path"), std::string::npos) << s.message();
}

TEST(Certify, RefusesATreeOfAnotherMesh) {
  const Mesh cube = analytic::cube().mesh;
  const Mesh scaled = analytic::cube(2.0).mesh;  // the same triangle count, other coordinates
  Tree tree;
  ASSERT_TRUE(build_tree(cube, small_build(), &tree).is_ok());
  exact::Certificate c;
  const Status s = certify(scaled, tree, CertifyOptions(), &c);
  ASSERT_FALSE(s.is_ok());
  EXPECT_NE(s.message().find("built for another mesh"), std::string::npos) << s.message();
}

// A mesh that no load_solid gives (no faces, an index out of range, a coordinate not finite or
// beyond 2^240) is refused by every call with one line, not a crash inside it.
TEST(PublicFace, RefusesMeshesThatBreakTheCallsOutright) {
  const Mesh cube = analytic::cube().mesh;
  Tree tree;
  ASSERT_TRUE(build_tree(cube, small_build(), &tree).is_ok());
  struct Case {
    std::function<void(Mesh*)> spoil;
    std::string says;
  };
  const std::vector<Case> cases = {
      {[](Mesh* m) { m->faces.clear(); }, "no faces"},
      {[](Mesh* m) { m->faces[3][1] = 1000000; }, "face 3: vertex index 1000000 out of range"},
      {[](Mesh* m) { m->faces[0][0] = -5; }, "face 0: vertex index -5 out of range"},
      {[](Mesh* m) { m->vertices[2].x() = std::nan(""); }, "vertex 2"},
      {[](Mesh* m) { m->vertices[1].y() = HUGE_VAL; }, "vertex 1"},
      {[](Mesh* m) { m->vertices[0].z() = 0x1p241; }, "beyond 2^240"},
  };
  for (const Case& c : cases) {
    Mesh m = cube;
    c.spoil(&m);
    for (Method method : {Method::kObbTree, Method::kVariational}) {
      BuildOptions o = small_build();
      o.method = method;
      Tree t;
      const Status s = build_tree(m, o, &t);
      ASSERT_FALSE(s.is_ok()) << c.says;
      EXPECT_NE(s.message().find(c.says), std::string::npos) << s.message();
    }
    exact::Certificate cert;
    Status s = certify(m, tree, CertifyOptions(), &cert);
    ASSERT_FALSE(s.is_ok()) << c.says;
    EXPECT_NE(s.message().find(c.says), std::string::npos) << s.message();
    ObvReport report;
    s = estimate_obv(m, {tree.nodes[0].box}, EstimateOptions(), &report);
    ASSERT_FALSE(s.is_ok()) << c.says;
    EXPECT_NE(s.message().find(c.says), std::string::npos) << s.message();
    CompareOptions co;
    co.build = small_build();
    CompareResult r;
    s = compare(m, co, &r);
    ASSERT_FALSE(s.is_ok()) << c.says;
    EXPECT_NE(s.message().find(c.says), std::string::npos) << s.message();
  }
}

// Recorded queries set in the options are checked as a query file's are.
TEST(BuildTree, RefusesCollidersAQueryFileWouldRefuse) {
  const Mesh cube = analytic::cube().mesh;
  collision::Collider good;
  good.center = Vec3(0.5, 0.5, 0.5);
  good.radius = 0.1;
  for (const double radius : {std::nan(""), -1.0, 0.0, HUGE_VAL}) {
    BuildOptions o = small_build();
    o.queries = {good, good};
    o.queries[1].radius = radius;
    Tree t;
    const Status s = build_tree(cube, o, &t);
    ASSERT_FALSE(s.is_ok()) << radius;
    EXPECT_NE(s.message().find("--queries: collider 1: radius"), std::string::npos) << s.message();
  }
  BuildOptions o = small_build();
  o.queries = {good};
  Tree t;
  EXPECT_TRUE(build_tree(cube, o, &t).is_ok());
}

// write_tree and write_boxes write no file their readers would refuse: a broken structure, or a
// box box_defect refuses.
TEST(WriteTree, WritesNoFileItsReaderWouldRefuse) {
  const Mesh cube = analytic::cube().mesh;
  Tree tree;
  ASSERT_TRUE(build_tree(cube, small_build(), &tree).is_ok());
  Tree far = tree;
  for (TreeNode& n : far.nodes) n.box.half = Vec3(1e300, 1e300, 1e300);
  const std::string path = test::temp_path("refused_tree.json");
  std::remove(path.c_str());
  Status s = write_tree(far, path);
  ASSERT_FALSE(s.is_ok());
  EXPECT_NE(s.message().find("node 0: extends beyond"), std::string::npos) << s.message();
  Tree child = tree;
  child.nodes[0].children[0] = 99;
  s = write_tree(child, path);
  ASSERT_FALSE(s.is_ok());
  EXPECT_NE(s.message().find("bad child 99"), std::string::npos) << s.message();
  EXPECT_FALSE(test::exists(path));
  Obb nan_box = tree.nodes[0].box;
  nan_box.center.x() = std::nan("");
  s = write_boxes({tree.nodes[0].box, nan_box}, path);
  ASSERT_FALSE(s.is_ok());
  EXPECT_NE(s.message().find("box 1"), std::string::npos) << s.message();
  EXPECT_FALSE(test::exists(path));
}

// compare's trees are build_tree's, its certificates certify's, and its e each tree's e.
TEST(Compare, IsBothBuildsCertified) {
  const Mesh mesh = analytic::polygonal_torus().mesh;
  CompareResult r;
  ASSERT_TRUE(compare_small(mesh, &r));
  for (int i = 0; i < 2; ++i) {
    BuildOptions b = small_build();
    b.method = i == 0 ? Method::kObbTree : Method::kVariational;
    Tree tree;
    ASSERT_TRUE(build_tree(mesh, b, &tree).is_ok());
    EXPECT_EQ(tree_to_json(tree), tree_to_json(r.trees[i])) << i;
    CertifyOptions co;
    co.rational = true;
    exact::Certificate c;
    ASSERT_TRUE(certify(mesh, tree, co, &c).is_ok());
    // Both trees reach depth 3 on the torus, so compare's e weighs layers as certify's does.
    ASSERT_EQ(r.trees[i].depth, 3);
    EXPECT_TRUE(r.e_exact[i] == c.weighted_error) << i;
    EXPECT_EQ(r.e[i], c.weighted_error_nearest) << i;
  }
}

// On a thin cuboid (2^13 by 1 by 2^-13, aspect 2^26), the cubemap's estimate of a box many
// times the solid's size may be near 0 or below it (its bound is of the order of the box):
// build_tree moves each estimate into the range that holds the OBV (clamp_to_obv_range), so the
// search does not take such a box for a gain, and the variational tree's exact e is no larger
// than OBB-Tree's. (With the raw estimates it is 5,000 times larger here.)
TEST(Compare, AThinCuboidIsNoWorseThanTheBaseline) {
  Mesh mesh = analytic::cube().mesh;
  for (Vec3& p : mesh.vertices) p = Vec3(p[0] * 0x1p13, p[1], p[2] * 0x1p-13);
  CompareResult r;
  ASSERT_TRUE(compare_small(mesh, &r));
  EXPECT_LE(r.e_exact[1], r.e_exact[0]) << r.e[1] << " against " << r.e[0];
}

// estimate_obv: each CPU estimate's certified error holds against the exact OBV, as rationals.
TEST(EstimateObv, CertifiedErrorsHoldAgainstTheExactValue) {
  const Mesh mesh = analytic::octahedron().mesh;
  Obb box;
  box.center = Vec3(0.2, 0.1, -0.3);
  box.axes = orthonormalize({Vec3(1, 0.2, 0), Vec3(-0.2, 1, 0.1), Vec3::Zero()});
  box.half = Vec3(0.6, 0.4, 0.5);
  EstimateOptions o;
  o.cpu = true;
  o.exact = true;
  o.ms = {4, 16};
  o.r_bound = true;
  o.rational = true;
  ObvReport r;
  ASSERT_TRUE(estimate_obv(mesh, {box}, o, &r).is_ok());
  ASSERT_EQ(r.runs.size(), 2u);
  ASSERT_EQ(r.exact_rational.size(), 1u);
  const Rational q = r.exact_rational[0];
  ASSERT_GT(q, 0);
  EXPECT_EQ(r.exact[0], to_double_nearest(q));
  for (const ObvRun& run : r.runs) {
    const Rational d = Rational(run.obv[0]) - q;
    const Rational err = d < 0 ? Rational(-d) : d;
    EXPECT_TRUE(err <= Rational(run.bound[0])) << run.m;
    EXPECT_TRUE(err <= Rational(run.r_bound[0])) << run.m;
    EXPECT_EQ(run.rel_error[0], to_double_nearest(Rational(err / q))) << run.m;
  }
  // Without the rationals asked for, the same values.
  o.rational = false;
  ObvReport enclosed;
  ASSERT_TRUE(estimate_obv(mesh, {box}, o, &enclosed).is_ok());
  EXPECT_TRUE(enclosed.exact_rational.empty());
  EXPECT_EQ(enclosed.exact, r.exact);
  for (size_t k = 0; k < r.runs.size(); ++k)
    EXPECT_EQ(enclosed.runs[k].rel_error, r.runs[k].rel_error) << r.runs[k].m;
  // A box inside the solid: OBV 0 exactly, and no relative error.
  Obb inner = box;
  inner.center = Vec3::Zero();
  inner.half = Vec3::Constant(0.1);
  ObvReport zero;
  ASSERT_TRUE(estimate_obv(mesh, {inner}, o, &zero).is_ok());
  EXPECT_EQ(zero.exact[0], 0.0);
  for (const ObvRun& run : zero.runs) EXPECT_TRUE(std::isnan(run.rel_error[0])) << run.m;
  o.cpu = false;
  o.gl = true;  // no GL component, no fallback: refused
  EXPECT_FALSE(estimate_obv(mesh, {box}, o, &r).is_ok());
}

}  // namespace
}  // namespace vobb
