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

// Reads a tree of the mesh's faces, or prints why not (one line on stderr) and returns false.
inline bool read_tree_or_say(const std::string& path, const Mesh& mesh, Tree* tree) {
  const Status s = read_tree(path, tree);
  if (!s) {
    std::fprintf(stderr, "%s\n", s.message().c_str());
    return false;
  }
  if (tree->mesh_triangles != mesh.faces.size()) {
    std::fprintf(stderr, "%s: the tree indexes %zu triangles but the mesh has %zu\n", path.c_str(),
                 static_cast<size_t>(tree->mesh_triangles), mesh.faces.size());
    return false;
  }
  return true;
}

// The lowest common ancestor of nodes a and b of a tree (node ids).
inline int32_t common_ancestor(const Tree& t, int32_t a, int32_t b) {
  while (a != b) {
    if (t.nodes[a].level > t.nodes[b].level)
      a = t.nodes[a].parent;
    else if (t.nodes[b].level > t.nodes[a].level)
      b = t.nodes[b].parent;
    else
      a = t.nodes[a].parent, b = t.nodes[b].parent;
  }
  return a;
}

}  // namespace vobb::bench
