// A variational build's state between two steps (after a level of the top-down pass or a
// merging sweep), and its checkpoint file.
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "common/obb.h"
#include "common/status.h"
#include "common/tree.h"

namespace vobb {

// The state of a build between two steps: what a checkpoint holds.
struct VariationalState {
  int split_levels = 0;  // levels made by the top-down pass (0: only the root)
  int sweeps = 0;        // merging sweeps done
  bool sweeping_done = false;
  bool budget_spent = false;
  std::vector<TreeNode> nodes;            // boxes unset; faces sorted ascending
  std::vector<std::array<Vec3, 3>> axes;  // per node: the searched orientation
};

// Checkpoint files: JSON with a `fingerprint` naming everything the build depends on (the
// caller's: mesh hash, options, estimator and m) and a SHA-256 of the rest. Doubles round-trip
// bit for bit. Writes are atomic (temp file + rename). Reading checks the checksum (a state
// without one, from before checksums, is read unchecked), the fingerprint and the state's
// structure.
Status write_variational_state(const VariationalState& state, const std::string& fingerprint,
                               const std::string& path);
// Not found: ok with *found = false. Wrong fingerprint or a damaged file: an error. The state
// must fit the build it resumes: faces below mesh_faces, at most `arity` children per node and
// no node below level `depth` (a state edited by hand could otherwise pass the fingerprint).
Status read_variational_state(const std::string& path, const std::string& fingerprint,
                              size_t mesh_faces, int arity, int depth, VariationalState* state,
                              bool* found);

}  // namespace vobb
