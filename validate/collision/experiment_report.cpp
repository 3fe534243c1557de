#include "validate/collision/experiment_report.h"

#include <fmt/printf.h>

#include <nlohmann/json.hpp>

namespace vobb::collision {

std::string experiment_report_json(const ReportHeader& f, const ExperimentReport& r) {
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
  // Indented by 2, with bytes that are not UTF-8 (a file name may hold any) replaced by U+FFFD.
  return j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
}

std::string experiment_report_text(const ReportHeader& f, const ExperimentReport& r) {
  using ull = unsigned long long;
  // The text shows changes (negative: fewer tests), the JSON reductions (positive: fewer).
  // Adding +0.0 turns the first tree's -0.0 into 0.0, which prints without a sign.
  auto change_pct = [](double first, double other) { return -reduction_pct(first, other) + 0.0; };
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
  // FCL decides contact in floating point (libccd's GJK), brute force and the trees exactly:
  // where they differ, the pose is one to look at, not a failure of the trees.
  auto fcl_against_brute_force = [&](const std::string& name, const FclCounts& c) {
    if (c.available)
      out += fmt::sprintf(
          "FCL against brute force, %s: yes/no differs on %llu of %llu queries, "
          "the touching faces on %llu\n",
          name.c_str(), static_cast<ull>(c.answer_disagreements), static_cast<ull>(r.queries),
          static_cast<ull>(c.face_disagreements));
  };
  for (const auto& t : r.trees) fcl_against_brute_force(t.name, t.fcl);
  fcl_against_brute_force("FCL's own OBB tree", r.fcl_own);
  if (r.touching_queries == 0)
    out +=
        "no query touched the mesh: every answer was empty, so agreeing with brute force says "
        "little\n";
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

}  // namespace vobb::collision
