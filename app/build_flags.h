// The flags that `build` and `compare` share (the variational search's), declared once, and
// what both print while a tree is built.
#pragma once

#include <CLI/CLI.hpp>
#include <chrono>
#include <functional>
#include <string>
#include <vector>

#include "common/status.h"
#include "vobb/vobb.h"

namespace vobb::app {

struct BuildFlags {
  std::string method = "variational";
  std::string backend = "auto";
  std::string objective;  // "obv", "omv", or empty: the default (BuildOptions::objective)
  std::vector<std::string> queries;  // query files (build only)
  int threads = 0;
  bool quiet = false;
  bool no_axis_search = false, no_merge = false, no_refit = false;
  BuildOptions options;  // what the flags set, but for method, backend, objective and queries
};

// Adds the search's flags to `cmd`; `compare`: compare's wording and no --method, --collider-margin
// or --queries.
void add_build_flags(CLI::App* cmd, BuildFlags* flags, bool compare);
// The flags that contradict each other once parsed (an explicit --m with poly or --queries).
Status check_build_flags(const CLI::App* cmd, const BuildFlags& flags);
// The options the flags give, with progress, notes and the search's closing line printed on
// stderr (none but warnings with --quiet). The queries are read by the caller (read_queries), once
// the mesh is loaded.
BuildOptions build_options(const BuildFlags& flags);
// Test hooks: VOBB_TEST_KILL_AT_SPLIT_LEVELS=N kills the process (SIGKILL, as an outside kill
// would) right after the build state with N levels split is saved, and
// VOBB_TEST_KILL_AFTER_CERTIFIED_LAYERS=N right after a certification state with N finished
// layers is saved, so that the resume tests interrupt a run at a known point instead of
// racing it. Empty when the variable is not set.
std::function<void(const VariationalState&)> build_kill_hook();
std::function<void(const exact::CertifyState&)> certify_kill_hook();

}  // namespace vobb::app
