// How much of each layer's overlap term G = sum OBV - OMV comes from siblings and how much from
// cousins (issue 33). Per parent p, G_sib(p) = sum OBV(children of p) - OMV(children of p), the
// overlap of its children's union; since the union of a layer is at most the union of its
// families, G >= sum_p G_sib(p), and G_cousin = G - sum_p G_sib(p) >= 0 is the part that only
// boxes of different parents share. Every value is certify's filter (exact/filtered_solver.h):
// enclosures of the exact values, printed as their correctly rounded doubles; a layer whose
// enclosures cannot be rounded (a one-family layer: cousins exactly 0) is computed in rationals.
// Usage: vobb-bench-overlap-split MESH TREE
#include <tbb/parallel_for.h>

#include <cstdio>
#include <map>

#include "bench/bench_util.h"
#include "common/tree.h"
#include "common/tree_io.h"
#include "exact/filtered_solver.h"

namespace {

using vobb::MpInterval;
using vobb::Obb;
using vobb::Rational;
using vobb::exact::Enclosed;
using vobb::exact::FilteredSolver;

// The overlap term of `boxes` (sum over j of box j's share): its enclosure, and the rational
// when `exact` (the clipping path, box by box).
MpInterval overlap(const FilteredSolver& fs, const std::vector<Obb>& boxes, bool exact,
                   Rational* q) {
  const std::vector<std::vector<int32_t>> earlier = fs.rational().earlier_neighbours(boxes);
  std::vector<Enclosed> terms(boxes.size());
  tbb::parallel_for(size_t{0}, boxes.size(),
                    [&](size_t j) { terms[j] = fs.overlap_term(boxes, j, earlier[j]); });
  MpInterval sum(0);
  for (const Enclosed& t : terms) sum += t.value;
  if (!exact) return sum;
  std::vector<Rational> qs(boxes.size());
  tbb::parallel_for(size_t{0}, boxes.size(), [&](size_t j) {
    qs[j] = terms[j].exact ? terms[j].q : fs.rational().overlap_term(boxes, j, earlier[j]);
  });
  *q = vobb::sum_pairwise(qs);
  return sum;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: vobb-bench-overlap-split MESH TREE\n");
    return 2;
  }
  vobb::LoadedMesh mesh;
  if (!vobb::bench::load_or_say(argv[1], &mesh)) return 2;
  vobb::Tree tree;
  if (!vobb::bench::read_tree_or_say(argv[2], mesh.mesh, &tree)) return 2;
  const FilteredSolver fs(mesh.mesh);
  std::printf("%5s %6s %14s %14s %14s %8s %s\n", "level", "boxes", "G (all)", "siblings", "cousins",
              "cousin %", "by");
  for (int level = 1; level <= tree.depth; ++level) {
    std::vector<Obb> boxes;
    std::map<int32_t, std::vector<Obb>> families;  // by parent
    for (int32_t id : vobb::layer(tree, level)) {
      boxes.push_back(tree.nodes[id].box);
      families[tree.nodes[id].level == level ? tree.nodes[id].parent : id].push_back(
          tree.nodes[id].box);
    }
    // The enclosures first; where one of the three cannot be rounded, the layer in rationals.
    for (bool exact : {false, true}) {
      Rational q_all, q_sib, q;
      const MpInterval all = overlap(fs, boxes, exact, &q_all);
      MpInterval siblings(0);
      for (const auto& [parent, family] : families) {
        siblings += overlap(fs, family, exact, &q);
        q_sib += q;
      }
      const MpInterval cousins = all - siblings;
      double g, sib, c;
      if (!exact && !(all.nearest(&g) && siblings.nearest(&sib) && cousins.nearest(&c))) continue;
      if (exact) {
        g = vobb::to_double_nearest(q_all);
        sib = vobb::to_double_nearest(q_sib);
        c = vobb::to_double_nearest(Rational(q_all - q_sib));
      }
      std::printf("%5d %6zu %14.6g %14.6g %14.6g %8.1f %s\n", level, boxes.size(), g, sib, c,
                  g > 0 ? 100.0 * c / g : 0.0, exact ? "rationals" : "filter");
      break;
    }
  }
  return 0;
}
