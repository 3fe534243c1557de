#include "builder/subtree_swaps.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <iterator>
#include <limits>
#include <map>
#include <tuple>
#include <utility>
#include <vector>

#include "common/obb.h"
#include "common/status.h"

namespace vobb {
namespace {

using Axes = std::array<Vec3, 3>;

// The sorted faces f without `out` (a subset of f) and with `in` (disjoint from f).
std::vector<int32_t> traded(const std::vector<int32_t>& f, const std::vector<int32_t>& out,
                            const std::vector<int32_t>& in) {
  std::vector<int32_t> rest, r;
  std::set_difference(f.begin(), f.end(), out.begin(), out.end(), std::back_inserter(rest));
  std::merge(rest.begin(), rest.end(), in.begin(), in.end(), std::back_inserter(r));
  return r;
}

struct Change {
  int32_t node = 0;
  std::vector<int32_t> faces;
  Axes axes;
  Obb box;
  double obv = 0;
};

struct Swap {
  int32_t u = 0, v = 0;
  double gain = 0;  // the change in the estimated e (negative lowers it)
  std::vector<Change> changes;
};

// A swap's score kept from an earlier round, with what it was computed from: the nodes whose
// faces, boxes or parents it read (u, v and the chains), and per chain level the four boxes
// whose shares it asked (the pair before and after), which decide which of the layer's other
// boxes entered those shares.
struct Score {
  double gain = 0;
  std::vector<int32_t> nodes;
  std::vector<std::pair<int, std::array<Obb, 4>>> asked;  // (level, boxes)
};

// The tree with each node's axes, tight box and estimated OBV: what the search measures.
struct State {
  Tree tree;
  std::vector<Axes> axes;
  std::vector<Obb> box;
  std::vector<double> obv;
};

class Search {
 public:
  Search(const Mesh& mesh, const SubtreeSwapOptions& o, Tree tree) : mesh_(mesh), o_(o) {
    s_.tree = std::move(tree);
    for (const TreeNode& n : s_.tree.nodes) {
      s_.axes.push_back(n.box.axes);
      s_.box.push_back(tight_box(mesh_, n.faces, n.box.axes));
    }
    s_.obv = o_.estimate(s_.box);
    const int depth = s_.tree.depth;
    for (int l = 0; l <= depth; ++l) layers_.push_back(layer(s_.tree, l));
    changed_.assign(s_.tree.nodes.size(), 0);
  }

  // The estimated e: per layer, its boxes' OBV less each one's share with those before it.
  double e() const {
    const int depth = s_.tree.depth;
    std::vector<double> per(depth + 1);
    tbb::parallel_for(0, depth + 1, [&](int l) {
      std::vector<ShareQuery> q;
      std::vector<Obb> before;
      double sum = 0;
      for (int32_t i : layers_[l]) {
        sum += s_.obv[i];
        q.push_back({s_.box[i], boxes_meeting(s_.box[i], before)});
        if (q.back().earlier.empty()) q.pop_back();
        before.push_back(s_.box[i]);
      }
      for (double x : q.empty() ? std::vector<double>() : o_.share(q)) sum -= x;
      per[l] = layer_weight(depth, l) * sum;
    });
    double sum = 0;
    for (double x : per) sum += x;
    return sum;
  }

  // Pairs of level k that may trade places; false where it ran out of time.
  bool candidates(int k, std::vector<Swap>* out) const {
    const Tree& t = s_.tree;
    std::vector<int32_t> at;
    for (const TreeNode& n : t.nodes)
      if (n.level == k) at.push_back(n.id);
    for (size_t i = 0; i < at.size(); ++i) {
      if (o_.out_of_time && o_.out_of_time()) return false;
      for (size_t j = i + 1; j < at.size(); ++j) {
        const int32_t u = at[i], v = at[j];
        if (t.nodes[u].parent == t.nodes[v].parent) continue;
        if (t.nodes[common_ancestor(t, u, v)].level > k - o_.gap) continue;
        if (boxes_apart(s_.box[u], s_.box[v])) continue;
        Swap s;
        s.u = u;
        s.v = v;
        out->push_back(std::move(s));
      }
    }
    return true;
  }

  // The chain pairs (a on u's side, b on v's) between the swap's nodes and their common
  // ancestor, from the nodes' parents up.
  std::vector<std::pair<int32_t, int32_t>> chains(const Swap& s) const {
    const Tree& t = s_.tree;
    const int32_t c = common_ancestor(t, s.u, s.v);
    std::vector<std::pair<int32_t, int32_t>> r;
    for (int32_t a = t.nodes[s.u].parent, b = t.nodes[s.v].parent; a != c;
         a = t.nodes[a].parent, b = t.nodes[b].parent)
      r.emplace_back(a, b);
    return r;
  }

  // The layer's boxes other than nodes a and b.
  std::vector<Obb> others(int32_t a, int32_t b) const {
    std::vector<Obb> r;
    for (int32_t i : layers_[s_.tree.nodes[a].level])
      if (i != a && i != b) r.push_back(s_.box[i]);
    return r;
  }

  // What nodes a and b give their layer now: their OBV less a's share with the layer's other
  // boxes and b's with those and a. Many candidates share a chain pair (in a binary tree, every
  // pair whose ancestor is the root shares the level-1 one), so a round computes each once
  // (`before_`).
  double pair_value(int32_t a, int32_t b) const {
    std::vector<Obb> rest = others(a, b);
    std::vector<ShareQuery> q;
    q.push_back({s_.box[a], boxes_meeting(s_.box[a], rest)});
    rest.push_back(s_.box[a]);
    q.push_back({s_.box[b], boxes_meeting(s_.box[b], rest)});
    const std::vector<double> share = o_.share(q);
    return s_.obv[a] + s_.obv[b] - share[0] - share[1];
  }

  double before(int32_t a, int32_t b) const {
    const auto it = std::lower_bound(before_.begin(), before_.end(), std::pair(a, b),
                                     [](const auto& x, const auto& k) { return x.first < k; });
    VOBB_ASSERT(it != before_.end() && it->first == std::pair(a, b),
                "a chain pair's value before a swap was not computed");
    return it->second;
  }

  // Fills the swap's chains' new faces, axes, boxes and OBV, and its gain (its pairs' values
  // before must be in before_).
  void evaluate(Swap* s) const {
    const Tree& t = s_.tree;
    const std::vector<int32_t>& fu = t.nodes[s->u].faces;
    const std::vector<int32_t>& fv = t.nodes[s->v].faces;
    const std::vector<std::pair<int32_t, int32_t>> pairs = chains(*s);
    std::vector<Obb> boxes;
    for (const auto& [a, b] : pairs)
      for (const auto& [node, out, in] : {std::tuple(a, &fu, &fv), std::tuple(b, &fv, &fu)}) {
        Change& ch = s->changes.emplace_back();
        ch.node = node;
        ch.faces = traded(t.nodes[node].faces, *out, *in);
        ch.axes = turned(ch.faces, s_.axes[node]);
        ch.box = tight_box(mesh_, ch.faces, ch.axes);
        boxes.push_back(ch.box);
      }
    const std::vector<double> obv = o_.estimate(boxes);
    // Per chain level, the new pair's shares: a with the layer's other boxes, b with those
    // and a.
    std::vector<ShareQuery> q;
    for (size_t j = 0; j < s->changes.size(); j += 2) {
      Change& a = s->changes[j];
      Change& b = s->changes[j + 1];
      a.obv = obv[j];
      b.obv = obv[j + 1];
      std::vector<Obb> rest = others(a.node, b.node);
      q.push_back({a.box, boxes_meeting(a.box, rest)});
      rest.push_back(a.box);
      q.push_back({b.box, boxes_meeting(b.box, rest)});
    }
    const std::vector<double> share = o_.share(q);
    double gain = 0;
    for (size_t j = 0; j < s->changes.size(); j += 2) {
      const Change& a = s->changes[j];
      const Change& b = s->changes[j + 1];
      const double after = a.obv + b.obv - share[j] - share[j + 1];
      gain += layer_weight(t.depth, t.nodes[a.node].level) * (after - before(a.node, b.node));
    }
    s->gain = gain;
  }

  void apply(const Swap& s) {
    Tree& t = s_.tree;
    const int32_t p = t.nodes[s.u].parent, q = t.nodes[s.v].parent;
    std::replace(t.nodes[p].children.begin(), t.nodes[p].children.end(), s.u, s.v);
    std::replace(t.nodes[q].children.begin(), t.nodes[q].children.end(), s.v, s.u);
    std::sort(t.nodes[p].children.begin(), t.nodes[p].children.end());
    std::sort(t.nodes[q].children.begin(), t.nodes[q].children.end());
    t.nodes[s.u].parent = q;
    t.nodes[s.v].parent = p;
    forget(s);
    for (const Change& c : s.changes) {
      t.nodes[c.node].faces = c.faces;
      s_.axes[c.node] = c.axes;
      s_.box[c.node] = c.box;
      s_.obv[c.node] = c.obv;
      changed_[c.node] = 1;
    }
  }

  // Drops the kept scores that swap s changes: those that read a node it moves or changes, and
  // those whose shares at a changed node's level asked a box that meets the node's box before
  // or after (only then can the node enter or leave, or change within, such a share's list).
  void forget(const Swap& s) {
    std::vector<char> hit(s_.tree.nodes.size(), 0);
    hit[s.u] = hit[s.v] = 1;
    for (const Change& c : s.changes) hit[c.node] = 1;
    for (auto it = scores_.begin(); it != scores_.end();) {
      const Score& sc = it->second;
      bool stale = false;
      for (int32_t n : sc.nodes) stale = stale || hit[n];
      for (const Change& c : s.changes) {
        if (stale) break;
        const int level = s_.tree.nodes[c.node].level;
        for (const auto& [l, boxes] : sc.asked) {
          if (l != level) continue;
          for (const Obb& b : boxes)
            stale = stale || !boxes_apart(b, s_.box[c.node]) || !boxes_apart(b, c.box);
        }
      }
      if (!stale) {
        ++it;
        continue;
      }
      forgotten_.emplace_back(it->first, std::move(it->second));
      it = scores_.erase(it);
    }
  }

  // The kept scores as they were before the round's first swap: forget() is the only change
  // to them once a round applies swaps.
  void remember() {
    for (auto& [key, sc] : forgotten_) scores_.emplace(key, std::move(sc));
    forgotten_.clear();
  }

  // The score of an evaluated swap, and what it read.
  Score score_of(const Swap& s) const {
    Score sc;
    sc.gain = s.gain;
    sc.nodes = {s.u, s.v};
    for (size_t j = 0; j < s.changes.size(); j += 2) {
      const Change& a = s.changes[j];
      const Change& b = s.changes[j + 1];
      sc.nodes.push_back(a.node);
      sc.nodes.push_back(b.node);
      sc.asked.push_back(
          {s_.tree.nodes[a.node].level, {s_.box[a.node], s_.box[b.node], a.box, b.box}});
    }
    return sc;
  }

  // Evaluates the swaps at `todo` (the chain pairs' values before first), each once; false
  // where it ran out of time.
  bool evaluate_all(std::vector<Swap>* cand, const std::vector<size_t>& todo) {
    before_.clear();
    for (size_t i : todo)
      for (const auto& ab : chains((*cand)[i])) before_.emplace_back(ab, 0.0);
    std::sort(before_.begin(), before_.end());
    before_.erase(std::unique(before_.begin(), before_.end()), before_.end());
    std::atomic<bool> late{false};
    tbb::parallel_for(size_t(0), before_.size(), [&](size_t i) {
      if (late || (o_.out_of_time && o_.out_of_time())) return void(late = true);
      before_[i].second = pair_value(before_[i].first.first, before_[i].first.second);
    });
    tbb::parallel_for(size_t(0), todo.size(), [&](size_t i) {
      if (late || (o_.out_of_time && o_.out_of_time())) return void(late = true);
      evaluate(&(*cand)[todo[i]]);
    });
    return !late;
  }

  // One round at level k; false where it applied nothing (or ran out of time).
  bool round(int k, SubtreeSwapReport* r) {
    std::vector<Swap> cand;
    if (!candidates(k, &cand)) return r->stopped = true, false;
    // Scores kept from earlier rounds stand where nothing they read has changed since; the
    // rest are scored now. A kept score that may be applied is scored again for its changes,
    // from the same inputs, so to the same gain (were a kept score stale, only a pair that
    // now gains and was kept above the threshold could be missed).
    const double e0 = r->e_after;
    std::vector<size_t> todo, again;
    for (size_t i = 0; i < cand.size(); ++i) {
      const auto it = o_.reuse_scores ? scores_.find({cand[i].u, cand[i].v}) : scores_.end();
      if (it == scores_.end()) {
        todo.push_back(i);
      } else {
        cand[i].gain = it->second.gain;
        if (cand[i].gain <= -o_.min_drop * e0) again.push_back(i);
      }
    }
    if (!evaluate_all(&cand, todo)) return r->stopped = true, false;
    for (size_t i : todo) scores_[{cand[i].u, cand[i].v}] = score_of(cand[i]);
    if (!evaluate_all(&cand, again)) return r->stopped = true, false;
    r->candidates += cand.size();
    r->reused += cand.size() - todo.size();
    r->rescored += again.size();
    std::sort(cand.begin(), cand.end(), [](const Swap& a, const Swap& b) {
      return a.gain != b.gain ? a.gain < b.gain : std::pair(a.u, a.v) < std::pair(b.u, b.v);
    });
    if (o_.scored) {
      std::vector<ScoredPair> list;
      for (const Swap& s : cand) list.push_back({s.u, s.v, s.gain});
      o_.scored(k, list);
    }
    const State kept = s_;
    const std::vector<char> changed = changed_;
    forgotten_.clear();
    std::vector<char> touched(s_.tree.nodes.size(), 0);
    size_t applied = 0;
    for (const Swap& s : cand) {
      if (!(s.gain <= -o_.min_drop * e0)) break;
      bool clash = touched[s.u] || touched[s.v];
      for (const Change& c : s.changes) clash = clash || touched[c.node];
      if (clash) continue;
      apply(s);
      touched[s.u] = touched[s.v] = 1;
      for (const Change& c : s.changes) touched[c.node] = 1;
      ++applied;
    }
    if (applied == 0) return false;
    double e1 = e();
    // Swaps of one round meet in the layers they share; where together they lower e less than
    // the best one alone, take that one alone.
    if (applied > 1 && e1 > e0 + cand[0].gain) {
      s_ = kept;
      changed_ = changed;
      remember();
      apply(cand[0]);
      e1 = e();
      applied = 1;
      ++r->reverted;
    }
    // The best swap's gain is exact up to the estimators' error; where that error still leaves
    // e no lower, the round is undone and the level ends.
    if (!(e1 < e0)) {
      s_ = kept;
      changed_ = changed;
      remember();
      ++r->undone;
      return false;
    }
    r->swaps += applied;
    r->e_after = e1;
    ++r->rounds;
    return true;
  }

  void run(SubtreeSwapReport* r) {
    r->e_before = r->e_after = e();
    for (int pass = 0; pass < o_.passes && !r->stopped; ++pass)
      for (int k = o_.first_level; k <= s_.tree.depth && !r->stopped; ++k)
        for (int i = 0; i < o_.rounds; ++i) {
          if (o_.out_of_time && o_.out_of_time()) {
            r->stopped = true;
            break;
          }
          if (!round(k, r)) break;
        }
  }

  // The tree, the changed nodes boxed by fit_obb.
  Tree finished() {
    for (size_t i = 0; i < changed_.size(); ++i)
      if (changed_[i]) s_.tree.nodes[i].box = fit_obb(mesh_, s_.tree.nodes[i].faces, s_.axes[i]);
    return std::move(s_.tree);
  }

 private:
  // A chain node's axes for its new faces: the better of two descents on the tight volume from
  // its old axes, first turns of 0.02 and 0.2 rad (the descent ends in a local minimum, and
  // which one depends on its first turn).
  Axes turned(const std::vector<int32_t>& faces, const Axes& from) const {
    Axes best;
    double least = std::numeric_limits<double>::infinity();
    for (double step : kTurns) {
      const Axes a = descend_tight_volume(mesh_, faces, from, step);
      const double v = volume(tight_box(mesh_, faces, a));
      if (v < least) least = v, best = a;
    }
    return best;
  }
  static constexpr double kTurns[] = {0.02, 0.2};

  const Mesh& mesh_;
  const SubtreeSwapOptions& o_;
  State s_;
  std::vector<std::vector<int32_t>> layers_;
  std::vector<char> changed_;
  std::vector<std::pair<std::pair<int32_t, int32_t>, double>> before_;    // sorted chain pairs
  std::map<std::pair<int32_t, int32_t>, Score> scores_;                   // by (u, v)
  std::vector<std::pair<std::pair<int32_t, int32_t>, Score>> forgotten_;  // this round's
};

}  // namespace

void swap_subtrees(const Mesh& mesh, const SubtreeSwapOptions& options, Tree* tree,
                   SubtreeSwapReport* report) {
  VOBB_ASSERT(options.estimate && options.share, "swap_subtrees needs estimate and share");
  VOBB_ASSERT(options.first_level >= 1 && options.gap >= 2 && options.rounds >= 0 &&
                  options.passes >= 0 && options.min_drop >= 0,
              "swap_subtrees: an option out of range");
  SubtreeSwapReport r;
  Search search(mesh, options, std::move(*tree));
  search.run(&r);
  *tree = search.finished();
  if (report) *report = r;
}

}  // namespace vobb
