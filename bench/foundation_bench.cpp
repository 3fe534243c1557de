// Times the foundation's stages on real meshes: load (parse + weld), solidity check (exact
// predicates), OBB-Tree baseline build at depth 8 and 12, and the exact conservativeness
// re-check of the depth-12 tree. Median of `--repeat` runs.
// Usage: vobb-bench-foundation [--repeat N] MESH...
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include "builder/obbtree_builder.h"
#include "common/io/mesh_io.h"
#include "common/solidity.h"

namespace {

double median_seconds(int repeat, const std::function<void()>& fn) {
  std::vector<double> t;
  for (int i = 0; i < repeat; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    fn();
    t.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  std::sort(t.begin(), t.end());
  return t[t.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  int repeat = 5;
  std::vector<std::string> meshes;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--repeat") && i + 1 < argc)
      repeat = std::max(1, std::atoi(argv[++i]));
    else
      meshes.push_back(argv[i]);
  }
  std::printf(
      "| mesh | faces | load s | solidity s | build d8 s | build d12 s | nodes d12 | recheck d12 s "
      "|\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  for (const std::string& path : meshes) {
    vobb::LoadedMesh lm;
    vobb::Status s = vobb::load_mesh(path, &lm);
    if (!s) {
      std::fprintf(stderr, "%s\n", s.message().c_str());
      return 2;
    }
    const vobb::Mesh& m = lm.mesh;
    const double load = median_seconds(repeat, [&] {
      vobb::LoadedMesh x;
      vobb::load_mesh(path, &x);
    });
    const double solid = median_seconds(repeat, [&] { vobb::check_solidity(m); });
    vobb::ObbTreeOptions o8, o12;
    o8.depth = 8;
    o12.depth = 12;
    const double b8 = median_seconds(repeat, [&] { vobb::build_obbtree(m, o8); });
    vobb::Tree t12;
    const double b12 = median_seconds(repeat, [&] { t12 = vobb::build_obbtree(m, o12); });
    bool ok = true;
    const double re = median_seconds(repeat, [&] { ok = vobb::check_conservative(m, t12).ok(); });
    const size_t slash = path.find_last_of('/');
    std::printf("| %s | %zu | %.3f | %.3f | %.3f | %.3f | %zu | %.3f%s |\n",
                path.substr(slash == std::string::npos ? 0 : slash + 1).c_str(), m.faces.size(),
                load, solid, b8, b12, t12.nodes.size(), re, ok ? "" : " (VIOLATION)");
  }
  return 0;
}
