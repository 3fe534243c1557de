// `vobb collide MESH TREE.json [TREE.json ...] [--colliders N] [--seconds S] [--seed S]
// [--collider-scale K] [--static] [--no-fcl] [--json] [-o FILE] [--record-queries FILE [--record-every K]]`:
// the collision experiment (paper §5, issue 7;
// validate/collision/collision_experiment.h). Thin: parses, loads, calls
// run_collision_experiment, prints. Exit 0 when every tree agrees with brute force, 1 when one
// does not, 2 on bad input (one line naming the file).
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>
#include <vector>

namespace vobb::app {

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

// Registers the subcommand on `app`; `flags` must outlive the parse.
CLI::App* add_collide_command(CLI::App& app, CollideFlags* flags);

// Runs it; returns the exit code.
int run_collide_command(const CollideFlags& flags);

}  // namespace vobb::app
