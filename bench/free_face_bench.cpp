// Probe: faces that can change leaves for free. A face f of leaf L lies, as it is, inside the
// tight box of another leaf M and of each of M's ancestors below their common ancestor with L.
// Moving f to M then leaves every box on M's side as it is, and the boxes on L's side below
// the common ancestor can only shrink (their axes stay; the tight fit of fewer faces along the
// same axes lies inside the old one), so no layer's union of tight boxes grows. f is moved
// only where it touches an extent of a box on L's side (else nothing shrinks), and never out
// of a leaf it is the last face of. Passes repeat until none moves a face. Prints the estimated
// e before and after (polyhedral OBV and shares in double, as swap_subtrees), and
// writes the tree (fit_obb boxes along the same axes) to OUT for `vobb certify`.
// With ROUNDS, moves that are not free follow: a face that touches an extent of its leaf's
// chain moves to a leaf whose tight box, grown on each side by REACH times the face's largest
// centroid-to-vertex distance (default 0), holds its centroid, where the estimated e falls (the
// changed boxes' OBV less their shares with their layers' other boxes, over every layer they are
// in); candidates are scored at once, then applied best first, each scored again just before.
// Usage: vobb-bench-free-face MESH TREE OUT [ROUNDS [REACH]]
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <tuple>
#include <utility>

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

struct Range {
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 hi = -Vec3::Constant(std::numeric_limits<double>::infinity());
};

Range range(const Mesh& mesh, const std::vector<int32_t>& faces, const std::array<Vec3, 3>& a) {
  Range r;
  for (int32_t f : faces)
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 3; ++k) {
        const double t = mesh.vertices[mesh.faces[f][c]].dot(a[k]);
        r.lo[k] = std::min(r.lo[k], t);
        r.hi[k] = std::max(r.hi[k], t);
      }
  return r;
}

double estimated_e(const Mesh& mesh, const vobb::Tree& t) {
  const vobb::PolyObvSolver obv(mesh);
  const vobb::PolyOverlapSolver ov(mesh);
  std::vector<double> per(t.depth + 1, 0.0);
  tbb::parallel_for(0, t.depth + 1, [&](int l) {
    std::vector<Obb> before;
    double s = 0;
    for (const auto& n : t.nodes) {
      if (!(n.level == l || (n.level < l && n.children.empty()))) continue;
      const Obb b = vobb::tight_box(mesh, n.faces, n.box.axes);
      s += obv.estimate(b) - ov.estimate(b, before);
      before.push_back(b);
    }
    per[l] = (t.depth - l + 1) * s;
  });
  double e = 0;
  for (double x : per) e += x;
  return e;
}

// Moves that are not free, scored by the estimated e (see the header comment).
// leaf_of[f] is face f's leaf, kept up to date; leaves the leaves' ids.
size_t paid_moves(const Mesh& mesh, vobb::Tree* tree, std::vector<int32_t>& leaf_of,
                  const std::vector<int32_t>& leaves, int rounds, double grow) {
  vobb::Tree& t = *tree;
  const vobb::PolyObvSolver obv(mesh);
  const vobb::PolyOverlapSolver ov(mesh);
  const int D = t.depth;
  const size_t n = t.nodes.size();
  std::vector<Obb> box(n);
  for (size_t i = 0; i < n; ++i)
    box[i] = vobb::tight_box(mesh, t.nodes[i].faces, t.nodes[i].box.axes);
  std::vector<double> val = obv.estimate(box);
  auto last = [&](int32_t i) { return t.nodes[i].children.empty() ? D : t.nodes[i].level; };
  std::vector<std::vector<int32_t>> layer(D + 1);
  for (const auto& nd : t.nodes)
    for (int l = nd.level; l <= last(nd.id); ++l) layer[l].push_back(nd.id);
  auto lca = [&](int32_t a, int32_t b) { return vobb::common_ancestor(t, a, b); };
  struct Move {
    int32_t f, from, to;
    double gain = 0;
    std::vector<std::pair<int32_t, Obb>> boxes;  // the changed nodes' new tight boxes
    std::vector<double> vals;
  };
  auto evaluate = [&](Move* m) {
    const int32_t c = lca(m->from, m->to);
    m->boxes.clear();
    for (int32_t a = m->from; a != c; a = t.nodes[a].parent) {
      std::vector<int32_t> rest;
      for (int32_t g : t.nodes[a].faces)
        if (g != m->f) rest.push_back(g);
      m->boxes.emplace_back(a, vobb::tight_box(mesh, rest, t.nodes[a].box.axes));
    }
    for (int32_t b = m->to; b != c; b = t.nodes[b].parent) {
      std::vector<int32_t> more = t.nodes[b].faces;
      more.push_back(m->f);
      m->boxes.emplace_back(b, vobb::tight_box(mesh, more, t.nodes[b].box.axes));
    }
    m->vals.clear();
    for (const auto& [i, b] : m->boxes) m->vals.push_back(obv.estimate(b));
    double gain = 0;
    for (int l = 0; l <= D; ++l) {
      std::vector<size_t> here;  // indices into m->boxes of the changed nodes in layer l
      for (size_t j = 0; j < m->boxes.size(); ++j) {
        const int32_t i = m->boxes[j].first;
        if (t.nodes[i].level <= l && l <= last(i)) here.push_back(j);
      }
      if (here.empty()) continue;
      std::vector<Obb> others;
      for (int32_t i : layer[l]) {
        bool changed = false;
        for (size_t j : here) changed |= m->boxes[j].first == i;
        if (!changed) others.push_back(box[i]);
      }
      double before = 0, after = 0;
      std::vector<Obb> ob = others, oa = others;
      for (size_t j : here) {
        const int32_t i = m->boxes[j].first;
        before += val[i] - ov.estimate(box[i], ob);
        ob.push_back(box[i]);
        after += m->vals[j] - ov.estimate(m->boxes[j].second, oa);
        oa.push_back(m->boxes[j].second);
      }
      gain += (D - l + 1) * (after - before);
    }
    m->gain = gain;
  };
  // Whether f touches an extent of a box of its chain. Only a filter on the candidates, each of
  // which is scored: a box's centre and half extents are rebuilt from its projections with
  // round-off of about 1e-16 of them, so "touches" allows 1e-12, and a looser test would only
  // score more candidates.
  auto touches_chain = [&](int32_t f) {
    for (int32_t a = leaf_of[f]; a >= 0; a = t.nodes[a].parent) {
      const Obb& b = box[a];
      for (int c = 0; c < 3; ++c) {
        const Vec3 d = mesh.vertices[mesh.faces[f][c]] - b.center;
        for (int k = 0; k < 3; ++k)
          if (std::abs(std::abs(d.dot(b.axes[k])) - b.half[k]) <= 1e-12 * (1 + b.half[k]))
            return true;
      }
    }
    return false;
  };
  size_t moved = 0;
  for (int round = 1; round <= rounds; ++round) {
    std::vector<Move> cand;
    for (int32_t f = 0; f < static_cast<int32_t>(mesh.faces.size()); ++f) {
      if (t.nodes[leaf_of[f]].faces.size() < 2 || !touches_chain(f)) continue;
      const Vec3 g = (mesh.vertices[mesh.faces[f][0]] + mesh.vertices[mesh.faces[f][1]] +
                      mesh.vertices[mesh.faces[f][2]]) /
                     3;
      double reach = 0;
      for (int c = 0; c < 3; ++c)
        reach = std::max(reach, (mesh.vertices[mesh.faces[f][c]] - g).norm());
      reach *= grow;
      for (int32_t M : leaves) {
        if (M == leaf_of[f]) continue;
        const Obb& b = box[M];
        const Vec3 d = g - b.center;
        bool in = true;
        for (int k = 0; k < 3; ++k) in &= std::abs(d.dot(b.axes[k])) <= b.half[k] + reach;
        if (in) cand.push_back({f, leaf_of[f], M, 0, {}, {}});
      }
    }
    const double secs = vobb::bench::seconds(
        [&] { tbb::parallel_for(size_t(0), cand.size(), [&](size_t i) { evaluate(&cand[i]); }); });
    std::sort(cand.begin(), cand.end(), [](const Move& a, const Move& b) {
      return a.gain < b.gain || (a.gain == b.gain && std::tie(a.f, a.to) < std::tie(b.f, b.to));
    });
    size_t applied = 0;
    double total = 0;
    for (Move& m : cand) {
      if (!(m.gain < 0)) break;
      if (leaf_of[m.f] != m.from || t.nodes[m.from].faces.size() < 2) continue;
      evaluate(&m);  // again, against the tree as it now stands
      if (!(m.gain < -1e-9)) continue;
      const int32_t c = lca(m.from, m.to);
      for (int32_t a = m.from; a != c; a = t.nodes[a].parent) {
        auto& fs = t.nodes[a].faces;
        fs.erase(std::lower_bound(fs.begin(), fs.end(), m.f));
      }
      for (int32_t b = m.to; b != c; b = t.nodes[b].parent) {
        auto& fs = t.nodes[b].faces;
        fs.insert(std::lower_bound(fs.begin(), fs.end(), m.f), m.f);
      }
      for (size_t j = 0; j < m.boxes.size(); ++j) {
        box[m.boxes[j].first] = m.boxes[j].second;
        val[m.boxes[j].first] = m.vals[j];
      }
      leaf_of[m.f] = m.to;
      ++applied;
      total += m.gain;
    }
    std::printf("paid round %d: %zu candidates scored in %.1f s, %zu moves, estimated %+.6f\n",
                round, cand.size(), secs, applied, total);
    std::fflush(stdout);
    moved += applied;
    if (!applied) break;
  }
  return moved;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 4 || argc > 6) {
    std::fprintf(stderr, "usage: vobb-bench-free-face MESH TREE OUT [ROUNDS [REACH]]\n");
    return 2;
  }
  const int rounds = argc >= 5 ? std::atoi(argv[4]) : 0;
  const double grow = argc == 6 ? std::atof(argv[5]) : 0.0;
  if (rounds < 0 || !(grow >= 0 && grow <= 1e6)) {
    std::fprintf(stderr, "need ROUNDS >= 0 and 0 <= REACH <= 1e6\n");
    return 2;
  }
  vobb::LoadedMesh loaded;
  if (!vobb::bench::load_or_say(argv[1], &loaded)) return 2;
  const Mesh& mesh = loaded.mesh;
  vobb::Tree t;
  if (!vobb::bench::read_tree_or_say(argv[2], mesh, &t)) return 2;
  std::printf("start: estimated e %.6f\n", estimated_e(mesh, t));
  const size_t n = t.nodes.size();
  for (auto& nd : t.nodes) std::sort(nd.faces.begin(), nd.faces.end());
  std::vector<Range> r(n);
  for (size_t i = 0; i < n; ++i) r[i] = range(mesh, t.nodes[i].faces, t.nodes[i].box.axes);
  std::vector<int32_t> leaf_of(mesh.faces.size(), -1), leaves;
  for (const auto& nd : t.nodes)
    if (nd.children.empty()) {
      leaves.push_back(nd.id);
      for (int32_t f : nd.faces) leaf_of[f] = nd.id;
    }
  // Where face f's vertices project along node i's axes against its range: inside it, and
  // touching one of its ends.
  auto test = [&](int32_t i, int32_t f, bool* touches) {
    bool in = true;
    if (touches) *touches = false;
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 3; ++k) {
        const double p = mesh.vertices[mesh.faces[f][c]].dot(t.nodes[i].box.axes[k]);
        in &= p >= r[i].lo[k] && p <= r[i].hi[k];
        if (touches && (p == r[i].lo[k] || p == r[i].hi[k])) *touches = true;
      }
    return in;
  };
  auto lca = [&](int32_t a, int32_t b) { return vobb::common_ancestor(t, a, b); };
  size_t moved = 0;
  for (int pass = 1;; ++pass) {
    size_t moved_now = 0;
    for (int32_t f = 0; f < static_cast<int32_t>(mesh.faces.size()); ++f) {
      const int32_t L = leaf_of[f];
      if (t.nodes[L].faces.size() < 2) continue;
      for (int32_t M : leaves) {
        if (M == L || !test(M, f, nullptr)) continue;
        const int32_t c = lca(L, M);
        bool free = true;
        for (int32_t m = t.nodes[M].parent; free && m != c; m = t.nodes[m].parent)
          free = test(m, f, nullptr);
        if (!free) continue;
        // The source side's ranges without f; the move is kept only where one of them shrinks,
        // so the sum of the boxes' volumes falls with every move and the passes end.
        std::vector<std::pair<int32_t, Range>> after;
        bool shrinks = false;
        for (int32_t a = L; a != c; a = t.nodes[a].parent) {
          bool touches = false;
          test(a, f, &touches);
          if (!touches) continue;
          std::vector<int32_t> rest;
          for (int32_t g : t.nodes[a].faces)
            if (g != f) rest.push_back(g);
          const Range ra = range(mesh, rest, t.nodes[a].box.axes);
          shrinks |= ra.lo != r[a].lo || ra.hi != r[a].hi;
          after.emplace_back(a, ra);
        }
        if (!shrinks) continue;
        for (int32_t a = L; a != c; a = t.nodes[a].parent) {
          auto& fs = t.nodes[a].faces;
          fs.erase(std::lower_bound(fs.begin(), fs.end(), f));
        }
        for (const auto& [a, ra] : after) r[a] = ra;
        for (int32_t m = M; m != c; m = t.nodes[m].parent) {
          auto& fs = t.nodes[m].faces;
          fs.insert(std::lower_bound(fs.begin(), fs.end(), f), f);
        }
        leaf_of[f] = M;
        ++moved_now;
        break;
      }
    }
    moved += moved_now;
    std::printf("pass %d: %zu faces moved\n", pass, moved_now);
    if (!moved_now) break;
  }
  const size_t paid = rounds > 0 ? paid_moves(mesh, &t, leaf_of, leaves, rounds, grow) : 0;
  for (auto& nd : t.nodes) nd.box = vobb::fit_obb(mesh, nd.faces, nd.box.axes);
  std::printf("end: %zu free moves, %zu paid moves, estimated e %.6f\n", moved, paid,
              estimated_e(mesh, t));
  const vobb::Status w = vobb::write_tree(t, argv[3]);
  if (!w) {
    std::fprintf(stderr, "%s\n", w.message().c_str());
    return 2;
  }
  return 0;
}
