// Trees as their builder measured them, for tests that compare builders' sums with no slack
// (the variational builder's tests and the recorded-query objective's).
#pragma once

#include <gtest/gtest.h>

#include <array>
#include <string>
#include <vector>

#include "builder/obbtree_builder.h"
#include "builder/variational_builder.h"
#include "common/mesh.h"
#include "common/tree.h"
#include "common/tree_io.h"

namespace vobb::test {

// A tree with the orientation its builder measured each node's faces in: the variational
// search's axes (its last checkpoint state), or the baseline's covariance axes (the search's
// starting state). The written boxes are not that measure: fit_obb orthonormalizes the axes
// again (not bit for bit the same) and pads the box by a few ulps, either of which may move a
// silhouette texel. Through tight boxes of these axes the sums below are the builder's own,
// and comparisons between them need no slack.
struct Measured {
  Tree tree;
  std::vector<std::array<Vec3, 3>> axes;  // per node
};

inline Measured build_measured(const Mesh& mesh, VariationalOptions o, const ObvEstimate& estimate,
                               VariationalReport* report = nullptr) {
  VariationalState last;
  o.checkpoint = [&](const VariationalState& st) { last = st; };
  Measured out{build_variational(mesh, o, estimate, nullptr, report), {}};
  out.axes = last.axes;
  EXPECT_EQ(out.axes.size(), out.tree.nodes.size());
  return out;
}

inline Measured baseline_measured(const Mesh& mesh, int depth) {
  ObbTreeOptions b;
  b.depth = depth;
  Measured out{build_obbtree(mesh, b), {}};
  for (const TreeNode& n : out.tree.nodes) out.axes.push_back(covariance_axes(mesh, n.faces));
  return out;
}

// The tree of a build resumed from `state`, after the state has gone through a checkpoint file
// at `path` (written, then read back under the options' arity and depth): what a killed build
// started again gives. Empty where the file did not round-trip (a test failure is recorded).
inline std::string resumed_tree(const Mesh& mesh, VariationalOptions o, const ObvEstimate& estimate,
                                const VariationalState& state, const std::string& path) {
  EXPECT_TRUE(static_cast<bool>(write_variational_state(state, "fp", path)));
  VariationalState back;
  bool found = false;
  const bool read = static_cast<bool>(
      read_variational_state(path, "fp", mesh.faces.size(), o.arity, o.depth, &back, &found));
  EXPECT_TRUE(read && found);
  if (!read || !found) return std::string();
  o.checkpoint = nullptr;
  return tree_to_json(build_variational(mesh, o, estimate, &back));
}

}  // namespace vobb::test
