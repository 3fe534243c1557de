// Per-box exact OBV timings: median time of one OBV_exact on the leaf boxes of a baseline
// tree and on its root box, with each exact path (clipping in the box frame; Nef).
// Usage: vobb-bench-exact MESH [--depth D] [--leaves N]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "bench/bench_util.h"
#include "builder/obbtree_builder.h"
#include "common/io/mesh_io.h"
#include "exact/outer_volume.h"

namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

using vobb::bench::seconds;

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: vobb-bench-exact MESH [--depth D] [--leaves N]\n");
    return 2;
  }
  int depth = 8;
  size_t leaves = 32;
  for (int i = 2; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--depth")) depth = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--leaves")) leaves = std::strtoul(argv[i + 1], nullptr, 10);
  }
  vobb::LoadedMesh lm;
  vobb::Status s = vobb::load_mesh(argv[1], &lm);
  if (!s) {
    std::fprintf(stderr, "%s\n", s.message().c_str());
    return 2;
  }
  vobb::ObbTreeOptions o;
  o.depth = depth;
  const vobb::Tree tree = vobb::build_obbtree(lm.mesh, o);
  std::vector<vobb::Obb> leaf_boxes;
  for (const auto& n : tree.nodes)
    if (n.is_leaf() && leaf_boxes.size() < leaves) leaf_boxes.push_back(n.box);
  vobb::exact::ClipSolver clip(lm.mesh);
  double nef_build = 0;
  std::unique_ptr<vobb::exact::NefSolver> nef;
  nef_build = seconds([&] { nef = std::make_unique<vobb::exact::NefSolver>(lm.mesh); });
  std::vector<double> leaf_clip, leaf_nef;
  size_t disagree = 0;
  for (const vobb::Obb& b : leaf_boxes) {
    vobb::Rational a, c;
    leaf_clip.push_back(seconds([&] { c = clip.obv(b); }));
    leaf_nef.push_back(seconds([&] { a = nef->obv(b); }));
    disagree += a != c;
  }
  vobb::Rational a, c;
  const double root_clip = seconds([&] { c = clip.obv(tree.nodes[0].box); });
  const double root_nef = seconds([&] { a = nef->obv(tree.nodes[0].box); });
  disagree += a != c;
  std::printf(
      "| mesh | depth | boxes | path | median leaf OBV s | root OBV s "
      "|\n|---|---|---|---|---|---|\n");
  std::printf("| %s | %d | %zu leaves + root | clip (box frame) | %.4f | %.4f |\n", argv[1], depth,
              leaf_boxes.size(), median(leaf_clip), root_clip);
  std::printf("| %s | %d | %zu leaves + root | Nef (Nef(X) built once: %.2f s) | %.4f | %.4f |\n",
              argv[1], depth, leaf_boxes.size(), nef_build, median(leaf_nef), root_nef);
  std::printf("paths disagree on %zu boxes\n", disagree);
  return disagree ? 1 : 0;
}
