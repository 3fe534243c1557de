// Helpers shared by the benchmark programs.
#pragma once

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <string>

#include "common/io/mesh_report.h"
#include "common/tree_io.h"

namespace vobb::bench {

// Wall-clock seconds of one call, on the monotonic clock.
template <typename F>
double seconds(F&& f) {
  const auto t0 = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Loads a solid, or prints why not (one line on stderr) and returns false.
inline bool load_or_say(const std::string& path, LoadedMesh* mesh) {
  const Status s = load_solid(path, mesh);
  if (!s) std::fprintf(stderr, "%s\n", s.message().c_str());
  return static_cast<bool>(s);
}

// Reads a tree of this mesh (check_tree_fits), or prints why not (one line on stderr) and returns
// false.
inline bool read_tree_or_say(const std::string& path, const Mesh& mesh, Tree* tree) {
  Status s = read_tree(path, tree);
  if (s) s = check_tree_fits(mesh, *tree, path);
  if (!s) std::fprintf(stderr, "%s\n", s.message().c_str());
  return static_cast<bool>(s);
}

}  // namespace vobb::bench
