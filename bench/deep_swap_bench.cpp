// Probe: how much would swaps of whole subtrees between distant parents lower a finished
// tree's e? Two nodes u, v of level k whose lowest common ancestor c is at level k - GAP or
// above trade places; every node between them and c (their ancestors below c, the "chains")
// changes its faces and is turned by a descent on its tight volume from its axes. A swap is
// judged by the change in the estimated e over the layers it changes: per layer, the two chain
// boxes' OBV less their shares with the layer's other boxes and with each other (the marginal
// form, docs/derivations.md "Shared outer volume"), by the polyhedral solver and overlap in
// double. The merging sweeps try only GAP = 2 (c the parents' common parent) and turn only the
// parents. Each round scores every candidate pair of the level (boxes that may meet), applies
// the best ones whose nodes no applied swap touched, while each lowers e by 1e-4 of it, and
// takes e again; levels KMIN..KMAX in turn, PASSES times. Writes the tree (fit_obb boxes) to
// OUT for `vobb certify`. Not a builder step: see docs/BENCHMARKS.md, "Subtree swaps across
// distant parents".
// Usage: vobb-bench-deep-swap MESH TREE OUT [KMIN KMAX ROUNDS GAP PASSES]
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iterator>

#include "bench/bench_util.h"
#include "builder/variational_builder.h"
#include "common/obb.h"
#include "common/tree.h"
#include "common/tree_io.h"
#include "fast/poly_overlap.h"
#include "fast/poly_solver.h"

namespace {

using vobb::Mesh;
using vobb::Obb;
using vobb::Vec3;
using Axes = std::array<Vec3, 3>;

Axes turn(const Axes& a, int about, double angle) {
  const Eigen::Matrix3d r = Eigen::AngleAxisd(angle, a[about]).toRotationMatrix();
  return {r * a[0], r * a[1], r * a[2]};
}

Axes refine(const Mesh& mesh, const std::vector<int32_t>& faces, Axes a, double step) {
  double best = vobb::volume(vobb::tight_box(mesh, faces, a));
  for (; step > 1e-4; step *= 0.5)
    for (bool improved = true; improved;) {
      improved = false;
      for (int k = 0; k < 3; ++k)
        for (double s : {-1.0, 1.0}) {
          const Axes t = turn(a, k, s * step);
          const double v = vobb::volume(vobb::tight_box(mesh, faces, t));
          if (v < best) best = v, a = t, improved = true;
        }
    }
  return a;
}

std::vector<int32_t> swapped(const std::vector<int32_t>& f, const std::vector<int32_t>& out,
                             const std::vector<int32_t>& in) {
  std::vector<int32_t> rest, r;
  std::set_difference(f.begin(), f.end(), out.begin(), out.end(), std::back_inserter(rest));
  std::merge(rest.begin(), rest.end(), in.begin(), in.end(), std::back_inserter(r));
  return r;
}

struct Probe {
  const Mesh& mesh;
  vobb::Tree& t;
  vobb::PolyObvSolver obv;
  vobb::PolyOverlapSolver ov;
  int D = 0;
  std::vector<Axes> axes;
  std::vector<Obb> box;
  std::vector<double> val;  // OBV
  std::vector<std::vector<int32_t>> layers;

  Probe(const Mesh& m, vobb::Tree& tree) : mesh(m), t(tree), obv(m), ov(m) {
    D = t.depth;
    for (auto& n : t.nodes) {
      axes.push_back(n.box.axes);
      box.push_back(vobb::tight_box(mesh, n.faces, n.box.axes));
    }
    val = obv.estimate(box);
    layers.resize(D + 1);
    for (int l = 0; l <= D; ++l)
      for (auto& n : t.nodes)
        if (n.level == l || (n.level < l && n.children.empty())) layers[l].push_back(n.id);
  }
  double w(int l) const { return D - l + 1; }
  double share(const Obb& b, const std::vector<Obb>& earlier) const {
    std::vector<Obb> near;
    for (const Obb& e : earlier)
      if (!vobb::PolyOverlapSolver::apart(b, e)) near.push_back(e);
    return near.empty() ? 0.0 : ov.estimate(b, near);
  }
  double e() const {
    std::vector<double> per(D + 1);
    tbb::parallel_for(0, D + 1, [&](int l) {
      double s = 0;
      std::vector<Obb> before;
      for (int32_t i : layers[l]) {
        s += val[i] - share(box[i], before);
        before.push_back(box[i]);
      }
      per[l] = w(l) * s;
    });
    double s = 0;
    for (double x : per) s += x;
    return s;
  }
  int32_t lca(int32_t a, int32_t b) const { return vobb::bench::common_ancestor(t, a, b); }
  struct Change {
    int32_t node;
    std::vector<int32_t> faces;
    Axes axes;
    Obb box;
    double obv;
  };
  struct Swap {
    int32_t u, v;
    double gain = 0;  // change in e (negative is better)
    std::vector<Change> changes;
  };
  // The change in e, with the chains' boxes turned by a volume descent.
  void evaluate(Swap* s) const {
    const int32_t c = lca(s->u, s->v);
    const auto& fu = t.nodes[s->u].faces;
    const auto& fv = t.nodes[s->v].faces;
    std::vector<int32_t> ca, cb;
    for (int32_t a = t.nodes[s->u].parent; a != c; a = t.nodes[a].parent) ca.push_back(a);
    for (int32_t b = t.nodes[s->v].parent; b != c; b = t.nodes[b].parent) cb.push_back(b);
    double gain = 0;
    for (size_t j = 0; j < ca.size(); ++j) {
      const int32_t a = ca[j], b = cb[j];
      const int l = t.nodes[a].level;
      Change na{a, swapped(t.nodes[a].faces, fu, fv), {}, {}, 0};
      Change nb{b, swapped(t.nodes[b].faces, fv, fu), {}, {}, 0};
      na.axes = refine(mesh, na.faces, axes[a], 0.02);
      nb.axes = refine(mesh, nb.faces, axes[b], 0.02);
      na.box = vobb::tight_box(mesh, na.faces, na.axes);
      nb.box = vobb::tight_box(mesh, nb.faces, nb.axes);
      na.obv = obv.estimate(na.box);
      nb.obv = obv.estimate(nb.box);
      std::vector<Obb> others;
      for (int32_t i : layers[l])
        if (i != a && i != b) others.push_back(box[i]);
      const double before = val[a] + val[b] - share(box[a], others) - [&] {
        auto o = others;
        o.push_back(box[a]);
        return share(box[b], o);
      }();
      const double after = na.obv + nb.obv - share(na.box, others) - [&] {
        auto o = others;
        o.push_back(na.box);
        return share(nb.box, o);
      }();
      gain += w(l) * (after - before);
      s->changes.push_back(std::move(na));
      s->changes.push_back(std::move(nb));
    }
    s->gain = gain;
  }
  void apply(const Swap& s) {
    const int32_t p = t.nodes[s.u].parent, q = t.nodes[s.v].parent;
    for (auto& ch : t.nodes[p].children)
      if (ch == s.u) ch = s.v;
    for (auto& ch : t.nodes[q].children)
      if (ch == s.v) ch = s.u;
    t.nodes[s.u].parent = q;
    t.nodes[s.v].parent = p;
    for (const Change& c : s.changes) {
      t.nodes[c.node].faces = c.faces;
      axes[c.node] = c.axes;
      box[c.node] = c.box;
      val[c.node] = c.obv;
    }
  }
};

}  // namespace

int main(int argc, char** argv) {
  if (argc != 4 && argc != 9) {
    std::fprintf(stderr,
                 "usage: vobb-bench-deep-swap MESH TREE OUT [KMIN KMAX ROUNDS GAP PASSES]\n");
    return 2;
  }
  vobb::LoadedMesh loaded;
  if (!vobb::bench::load_or_say(argv[1], &loaded)) return 2;
  vobb::Tree tree;
  if (!vobb::bench::read_tree_or_say(argv[2], loaded.mesh, &tree)) return 2;
  const bool given = argc == 9;
  const int kmin = given ? std::atoi(argv[4]) : 2;
  const int kmax = given ? std::atoi(argv[5]) : tree.depth;
  const int rounds = given ? std::atoi(argv[6]) : 4;
  const int gap = given ? std::atoi(argv[7]) : 2;
  const int passes = given ? std::atoi(argv[8]) : 2;
  if (kmin < 1 || kmax < kmin || rounds < 1 || gap < 2 || passes < 1) {
    std::fprintf(stderr, "need 1 <= KMIN <= KMAX, ROUNDS >= 1, GAP >= 2, PASSES >= 1\n");
    return 2;
  }
  Probe p(loaded.mesh, tree);
  double e0 = p.e();
  std::printf("start: estimated e %.6f\n", e0);
  for (int pass = 0; pass < passes; ++pass)
    for (int k = kmin; k <= std::min(kmax, p.D); ++k) {
      for (int r = 0; r < rounds; ++r) {
        std::vector<Probe::Swap> cand;
        for (auto& u : tree.nodes)
          for (auto& v : tree.nodes)
            if (u.level == k && v.level == k && u.id < v.id && u.parent != v.parent &&
                tree.nodes[p.lca(u.id, v.id)].level <= k - gap &&
                !vobb::PolyOverlapSolver::apart(p.box[u.id], p.box[v.id]))
              cand.push_back({u.id, v.id, 0, {}});
        double t = vobb::bench::seconds([&] {
          tbb::parallel_for(size_t(0), cand.size(), [&](size_t i) { p.evaluate(&cand[i]); });
        });
        std::sort(cand.begin(), cand.end(),
                  [](const auto& a, const auto& b) { return a.gain < b.gain; });
        std::vector<char> touched(tree.nodes.size(), 0);
        int applied = 0;
        double predicted = 0;
        for (const auto& s : cand) {
          if (!(s.gain < -1e-4 * e0)) break;
          bool clash = touched[s.u] || touched[s.v];
          for (const auto& c : s.changes) clash |= touched[c.node] != 0;
          if (clash) continue;
          std::printf("  swap %d <-> %d: common ancestor at level %d, %+.6f\n", s.u, s.v,
                      tree.nodes[p.lca(s.u, s.v)].level, s.gain);
          p.apply(s);
          touched[s.u] = touched[s.v] = 1;
          for (const auto& c : s.changes) touched[c.node] = 1;
          ++applied;
          predicted += s.gain;
        }
        const double e1 = p.e();
        std::printf(
            "level %d round %d: %zu candidates in %.1f s, %d applied, predicted %+.4f, e %.6f "
            "(%+.4f)\n",
            k, r, cand.size(), t, applied, predicted, e1, e1 - e0);
        std::fflush(stdout);
        e0 = e1;
        if (!applied) break;
      }
    }
  for (size_t i = 0; i < tree.nodes.size(); ++i) {
    tree.nodes[i].box = vobb::fit_obb(loaded.mesh, tree.nodes[i].faces, p.axes[i]);
    std::sort(tree.nodes[i].children.begin(), tree.nodes[i].children.end());
  }
  const vobb::Status w = vobb::write_tree(tree, argv[3]);
  if (!w) {
    std::fprintf(stderr, "%s\n", w.message().c_str());
    return 2;
  }
  return 0;
}
