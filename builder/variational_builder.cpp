#include "builder/variational_builder.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <iterator>
#include <limits>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <numeric>
#include <optional>
#include <queue>
#include <random>
#include <set>
#include <tuple>
#include <unordered_map>

#include "builder/obbtree_builder.h"
#include "common/atomic_file.h"
#include "common/json_parse.h"
#include "common/status.h"
#include "common/text_util.h"

namespace vobb {

namespace {

// The box spanning projections [lo_k, hi_k] along orthonormal axes a_k.
Obb box_from_projections(const std::array<Vec3, 3>& axes, const Vec3& lo, const Vec3& hi) {
  Obb b;
  b.axes = axes;
  b.center = Vec3::Zero();
  for (int k = 0; k < 3; ++k) {
    b.center += 0.5 * (lo[k] + hi[k]) * axes[k];
    b.half[k] = 0.5 * (hi[k] - lo[k]);
  }
  return b;
}

}  // namespace

Obb tight_box(const Mesh& mesh, const std::vector<int32_t>& faces,
              const std::array<Vec3, 3>& axes) {
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (int32_t f : faces)
    for (int c = 0; c < 3; ++c) {
      const Vec3& p = mesh.vertices[mesh.faces[f][c]];
      for (int k = 0; k < 3; ++k) {
        const double t = p.dot(axes[k]);
        lo[k] = std::min(lo[k], t);
        hi[k] = std::max(hi[k], t);
      }
    }
  return box_from_projections(axes, lo, hi);
}

namespace {

// Face adjacency across edges (a solid: two faces per edge).
std::vector<std::array<int32_t, 3>> face_neighbours(const Mesh& mesh) {
  std::map<std::pair<int32_t, int32_t>, int32_t> first;
  std::vector<std::array<int32_t, 3>> out(mesh.faces.size(), {-1, -1, -1});
  for (size_t f = 0; f < mesh.faces.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      int32_t a = mesh.faces[f][k], b = mesh.faces[f][(k + 1) % 3];
      if (a > b) std::swap(a, b);
      auto [it, fresh] = first.emplace(std::make_pair(a, b), static_cast<int32_t>(f));
      if (fresh) continue;
      const int32_t g = it->second;
      for (int j = 0; j < 3; ++j)
        if (out[f][j] < 0) {
          out[f][j] = g;
          break;
        }
      for (int j = 0; j < 3; ++j)
        if (out[g][j] < 0) {
          out[g][j] = static_cast<int32_t>(f);
          break;
        }
    }
  return out;
}

Vec3 centroid(const Mesh& mesh, int32_t f) {
  return (mesh.vertices[mesh.faces[f][0]] + mesh.vertices[mesh.faces[f][1]] +
          mesh.vertices[mesh.faces[f][2]]) /
         3.0;
}

std::array<Vec3, 3> rotate(const std::array<Vec3, 3>& axes, int about, double angle) {
  const Eigen::Matrix3d r = Eigen::AngleAxisd(angle, axes[about]).toRotationMatrix();
  return orthonormalize({r * axes[0], r * axes[1], r * axes[2]});
}

// The adjustment step runs for children at levels 1..kAdjustLevels: those weigh most in e
// (ω, layer_weight in common/tree.h) and are few, so it costs little there.
constexpr int kAdjustLevels = 4;

// Under kOmv the top-down orientation search weighs each trial box's shares for the boxes of
// levels 1..kShareSearchLevels, the few big ones that shape the top; below, it minimises OBV
// and the Lloyd states are still scored with their shares (why this bound: docs/derivations.md,
// "The variational builder", Objective).
constexpr int kShareSearchLevels = 2;

// The final refit under kOmv (VariationalOptions::refit), for the boxes of levels
// 0..kRefitLevels: kRefitRotations seeded rotations screened by each node's tight volume, the
// kRefitStarts best of them and the node's own axes descended on that volume, and for the
// boxes of levels 0..kRefitObjectiveLevels a descent on the estimated objective itself (why
// these: docs/derivations.md, "The final refit").
constexpr int kRefitLevels = 4;
constexpr int kRefitRotations = 1000;
// A step of the search (a Lloyd iteration, a sweep's move, a sweep, a refit's turn) counts as a
// gain only for a drop of this fraction of its objective or more: smaller drops are within the
// estimator's discretization error at the m the builders use (docs/BENCHMARKS.md: median
// relative error ~1e-4, tails ~1e-3), so they would chase noise.
constexpr double kMinDrop = 1e-3;
constexpr int kRefitStarts = 3;
constexpr int kRefitObjectiveLevels = 2;

// A uniformly random orientation (a unit quaternion from four normal deviates), drawn by
// Box-Muller on the generator's raw bits, so that every machine and standard library draws the
// same.
std::array<Vec3, 3> random_axes(std::mt19937_64& rng) {
  auto gauss = [&] {
    const double u1 = (static_cast<double>(rng() >> 11) + 1) * 0x1.0p-53,
                 u2 = static_cast<double>(rng() >> 11) * 0x1.0p-53;
    return std::sqrt(-2 * std::log(u1)) * std::cos(2 * M_PI * u2);
  };
  Eigen::Quaterniond q;
  q.coeffs() << gauss(), gauss(), gauss(), gauss();
  const Eigen::Matrix3d rot = q.normalized().toRotationMatrix();
  return orthonormalize({Vec3(rot.col(0)), Vec3(rot.col(1)), Vec3(rot.col(2))});
}

// The mesh vertices of the faces, each once, ascending.
std::vector<int32_t> distinct_vertices(const Mesh& mesh, const std::vector<int32_t>& faces) {
  std::vector<int32_t> v;
  v.reserve(3 * faces.size());
  for (int32_t f : faces)
    for (int c = 0; c < 3; ++c) v.push_back(mesh.faces[f][c]);
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
  return v;
}

// The product of the points' extents along the axes: the tight box's volume over 8.
double extent_product(const Mesh& mesh, const std::vector<int32_t>& vertices,
                      const std::array<Vec3, 3>& axes) {
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (int32_t v : vertices)
    for (int k = 0; k < 3; ++k) {
      const double t = mesh.vertices[v].dot(axes[k]);
      lo[k] = std::min(lo[k], t);
      hi[k] = std::max(hi[k], t);
    }
  return (hi - lo).prod();
}

// Descent on the tight volume from `axes`: turns of +-step about each axis, the same step again
// while one gains, then half of it, while the step is above 1e-4 rad.
std::array<Vec3, 3> descend_volume(const Mesh& mesh, const std::vector<int32_t>& vertices,
                                   std::array<Vec3, 3> axes, double step) {
  double best = extent_product(mesh, vertices, axes);
  for (; step > 1e-4; step *= 0.5)
    for (bool gained = true; gained;) {
      gained = false;
      for (int about = 0; about < 3; ++about)
        for (double sign : {1.0, -1.0}) {
          const std::array<Vec3, 3> turned = rotate(axes, about, sign * step);
          const double v = extent_product(mesh, vertices, turned);
          if (v < best) best = v, axes = turned, gained = true;
        }
    }
  return axes;
}

// Pattern search on a box's value over turns about its axes: each round scores the six turns
// of +-step in one call of value(boxes) and keeps the least where it is below *best, else
// halves the step, while the step is at least `last`. chosen(i) is told which of the call's
// boxes was kept. False where stop(), asked before each round, ends it early.
template <class Value, class Chosen, class Stop>
bool descend_value(const Mesh& mesh, const std::vector<int32_t>& faces, double step, double last,
                   std::array<Vec3, 3>* axes, double* best, const Value& value,
                   const Chosen& chosen, const Stop& stop) {
  while (step >= last) {
    if (stop()) return false;
    std::vector<std::array<Vec3, 3>> turned;
    std::vector<Obb> boxes;
    for (int about = 0; about < 3; ++about)
      for (double sign : {1.0, -1.0}) {
        turned.push_back(rotate(*axes, about, sign * step));
        boxes.push_back(tight_box(mesh, faces, turned.back()));
      }
    const std::vector<double> v = value(boxes);
    const size_t i = std::min_element(v.begin(), v.end()) - v.begin();
    if (v[i] < *best) {
      *best = v[i];
      *axes = turned[i];
      chosen(i);
    } else {
      step *= 0.5;
    }
  }
  return true;
}

// What the splitters of one build share. With concurrent_estimates, several splitters (one
// per thread) search nodes at once: the counts add up, and the time budget once spent is
// spent for all.
struct SearchShared {
  std::atomic<size_t> estimates{0};
  std::atomic<size_t> reused{0};  // boxes of a search measured again, answered from its record
  std::atomic<size_t> reused_earlier{0};  // of those, answered from an earlier search's record
  std::atomic<size_t> overlaps{0};        // shares estimated (kOmv)
  std::atomic<size_t> adjustments{0};
  std::atomic<size_t> merges{0};
  std::atomic<size_t> regroups_skipped{0};
  std::atomic<size_t> refitted{0};  // boxes the final refit turned (kOmv)
  std::atomic<bool> spent{false};   // a stopped() has returned true
};

class NodeSplitter {
 public:
  NodeSplitter(const Mesh& mesh, const std::vector<std::array<int32_t, 3>>& adjacency,
               const VariationalOptions& options, const ObvEstimate& estimate, SearchShared* shared)
      : mesh_(mesh), adj_(adjacency), options_(options), estimate_(estimate), shared_(shared) {}

  struct State {
    std::vector<std::vector<int32_t>> groups;
    std::vector<std::array<Vec3, 3>> axes;
    std::vector<double> obv;
    // kOmv: what the groups' boxes share, outside the solid, with the context boxes and with
    // each other (each box's share with the context and the boxes before it); 0 under kObv.
    double overlap = 0;
    double sum() const { return std::accumulate(obv.begin(), obv.end(), 0.0); }
    // What the search minimises: the sum of OBV, less the overlap under kOmv: the boxes'
    // estimated OMV with the context's, less the context's own (under kObv the sum, bit for bit).
    double objective() const { return sum() - overlap; }
  };

  // Level of the boxes being fitted: the orientation search tries more starts near the root.
  void set_level(int level) { level_ = level; }
  // Boxes of another level follow: the pace measured so far is forgotten. The builder calls it
  // on every thread's splitter, between parallel steps.
  void forget_pace() { pace_ = share_pace_ = 0; }

  // Boxes that stay as they are while this splitter's groups change, whose overlap with each
  // group counts in the objective under kOmv (a regrouping's other boxes of the layer); none
  // by default.
  void set_context(std::vector<Obb> boxes) { context_ = std::move(boxes); }

  // A new search (a node's split, the root's, a regrouping) begins: the boxes measured so far
  // are forgotten. Within one search a box is often measured again (a group that a Lloyd
  // iteration left as it was gets the same orientation starts; a regrouping's passes screen the
  // same groups), and its value is the one measured before: an estimate depends on the box
  // alone. Kept per search, the record stays small, and what it saves does not depend on
  // which thread ran which search.
  void begin_search() {
    measured_.clear();
    measured_shares_.clear();
    earlier_.boxes.clear();
    context_.clear();
  }

  // What a search measured: its boxes' values, by their bits. (Not its shares: a later
  // regrouping asks again for few of them, docs/BENCHMARKS.md, "Regroupings that start from
  // their last run's record".)
  struct Record;
  // A new search that may also answer from what an earlier one measured (a node's regrouping
  // in a later sweep asks again for many of the boxes its run in the sweep before measured);
  // as begin_search() otherwise. The values are those the estimator would give again (it
  // depends on the box alone), so the search's decisions are the same with the record or
  // without.
  void begin_search_from(Record record);
  // What the current search asked for, with the values it got (answered from the earlier
  // record or not), taken out; the earlier record's other entries are dropped, so a record
  // carried from search to search holds no more than one search's boxes.
  Record take_record();

  // The root: one group, its axes optimised like any child's.
  std::array<Vec3, 3> optimise_single(const std::vector<int32_t>& faces) {
    begin_search();
    State s;
    s.groups = {faces};
    s.axes = {covariance_axes(mesh_, faces)};
    update_boxes(&s);
    return s.axes[0];
  }

  // Splits `faces` into at most `arity` groups; returns the groups and their axes.
  State split(const std::vector<int32_t>& faces, const std::function<void(int, double)>& report) {
    begin_search();
    State state;
    state.groups = split_into_groups(mesh_, faces, options_.arity);
    for (const auto& g : state.groups) state.axes.push_back(covariance_axes(mesh_, g));
    const bool whole = update_boxes(&state);
    State best = state;
    if (!whole) return best;  // its sum is not reported: some boxes were not estimated
    report(0, best.objective());
    if (state.groups.size() < 2) return best;
    iterate(faces, state, &best, report);
    if (options_.adjust && level_ <= kAdjustLevels && !stopped()) adjust(faces, &best, report);
    return best;
  }

  // Whether the time budget is spent. It is asked before every call to the estimator (see
  // measure()), so that a spent budget ends the search within the call under way: at a large m
  // one node's Lloyd iterations are hundreds of batches of seconds each. Once true it stays
  // true: time only grows.
  bool stopped() {
    if (!shared_->spent && options_.out_of_time && options_.out_of_time()) shared_->spent = true;
    return shared_->spent;
  }
  // Whether stopped() has said so: the search may have been cut short.
  bool spent() const { return shared_->spent; }

  // Box update: per group, the orientation search (or the covariance axes alone), starting
  // from s->axes; fills s->obv, and under kOmv scores the state's overlaps (score_overlaps).
  // Under kOmv the search itself weighs each trial box's share with the other groups' boxes
  // for boxes of levels 1..kShareSearchLevels, unless shares_in_search is false; else it
  // minimises OBV alone, and only the state's score sees the overlaps. False when the time budget
  // cut it short: then the groups not reached keep their axes and an OBV of 0, so s->sum() is not
  // to be compared.
  bool update_boxes(State* s, bool shares_in_search = true) {
    const bool search_omv = omv() && shares_in_search && level_ <= kShareSearchLevels;
    s->obv.assign(s->groups.size(), 0.0);
    for (size_t g = 0; g < s->groups.size(); ++g) {
      if (stopped()) return false;
      const auto& faces = s->groups[g];
      std::array<Vec3, 3> axes = s->axes[g];
      // Under kOmv a box's value is its OBV less what it shares with the other groups' boxes as
      // they stand (those before g already searched). Under kObv it is its OBV.
      std::vector<Obb> others;
      if (search_omv)
        for (size_t h = 0; h < s->groups.size(); ++h)
          if (h != g) others.push_back(tight_box(mesh_, s->groups[h], s->axes[h]));
      auto values = [&](const std::vector<Obb>& boxes, std::vector<double>* obv) {
        *obv = measure(boxes);
        std::vector<double> v = *obv;
        if (search_omv && !stopped()) {
          const std::vector<double> shared = overlap_with(boxes, others);
          for (size_t i = 0; i < v.size(); ++i) v[i] -= shared[i];
        }
        return v;
      };
      std::vector<double> obv_of;
      double best = values({tight_box(mesh_, faces, axes)}, &obv_of)[0];
      double best_obv = obv_of[0];
      bool cut = false;
      if (options_.optimise_axes && !(cut = stopped())) {
        // Other starts: the covariance axes of the (new) group, and seeded random orientations
        // (uniform unit quaternions), so that the search is not stuck in the start's basin.
        // More for the big boxes of the top levels, which weigh most in e.
        std::vector<std::array<Vec3, 3>> starts{covariance_axes(mesh_, faces)};
        const int random_starts = level_ <= 3 ? 32 : 4;
        std::mt19937_64 rng(options_.seed ^ (0x9e3779b97f4a7c15ull * (faces.front() + 1)) ^
                            faces.size());
        for (int r = 0; r < random_starts; ++r) starts.push_back(random_axes(rng));
        std::vector<Obb> start_boxes;
        for (const auto& a : starts) start_boxes.push_back(tight_box(mesh_, faces, a));
        const std::vector<double> sv = values(start_boxes, &obv_of);
        for (size_t i = 0; i < starts.size(); ++i)
          if (sv[i] < best) best = sv[i], best_obv = obv_of[i], axes = starts[i];
        cut = !descend_value(
            mesh_, faces, 0.2, 0.0125, &axes, &best,
            [&](const std::vector<Obb>& boxes) { return values(boxes, &obv_of); },
            [&](size_t i) { best_obv = obv_of[i]; }, [&] { return stopped(); });
      }
      s->axes[g] = axes;
      s->obv[g] = best_obv;
      // Cut, or the budget ran out inside one of this group's calls (whose boxes not reached
      // are +inf): the state is not complete.
      if (cut || spent()) return false;
    }
    score_overlaps(s);
    return !omv() || !spent();  // a spent budget may have left the shares out
  }

  // Under kOmv: s->overlap for the groups' boxes at s->axes (0 under kObv).
  void score_overlaps(State* s) {
    s->overlap = 0;
    if (!omv()) return;
    std::vector<ShareQuery> queries;
    for (size_t g = 0; g < s->groups.size(); ++g) {
      ShareQuery& q = queries.emplace_back();
      q.box = tight_box(mesh_, s->groups[g], s->axes[g]);
      for (const Obb& c : context_)
        if (may_meet(q.box, c)) q.earlier.push_back(c);
      for (size_t h = 0; h < g; ++h)
        if (may_meet(q.box, queries[h].box)) q.earlier.push_back(queries[h].box);
    }
    for (double v : measure_share(queries)) s->overlap += v;
  }

  // The objective of each box: its estimated OBV, grown by the collider margin first.
  // Under a time budget the batch is estimated in chunks, the budget asked before each; boxes
  // not reached get +inf, which no comparison picks, and the callers see stopped() and stop.
  // A chunk is about options_.budget_check_seconds of estimates at the pace measured so far at
  // this level, and one box per thread (the CPU twin's unit of parallel work) until that pace
  // is known: the first call of a level, or of a sweep's e. So at the builders' usual m a
  // batch stays one call (the GL estimator reads its atlas back once per call), while at a
  // large m, where one box of a big node takes seconds, the budget is asked every box per
  // thread. The pace is forgotten when the level changes: boxes of another level take another
  // time.
  std::vector<double> measure(const std::vector<Obb>& boxes) {
    std::vector<Obb> grown;
    if (options_.margin > 0) {
      grown = boxes;
      for (Obb& b : grown) b.half.array() += options_.margin;
    }
    const std::vector<Obb>& all = options_.margin > 0 ? grown : boxes;
    // Boxes this search measured before take their recorded value; the rest are estimated.
    std::vector<double> out(all.size(), std::numeric_limits<double>::infinity());
    std::vector<Obb> in;
    std::vector<size_t> at;
    std::vector<BoxBits> keys;
    for (size_t i = 0; i < all.size(); ++i) {
      BoxBits key = bits_of(all[i]);
      const auto hit = options_.reuse_known ? measured_.find(key) : measured_.end();
      if (hit != measured_.end()) {
        out[i] = hit->second;
        continue;
      }
      if (const auto old = earlier_.boxes.find(key); old != earlier_.boxes.end()) {
        out[i] = old->second;
        measured_.emplace(key, old->second);
        ++shared_->reused_earlier;
        continue;
      }
      in.push_back(all[i]);
      at.push_back(i);
      keys.push_back(key);
    }
    shared_->reused += all.size() - in.size();
    auto keep = [&](size_t j, double v) {
      out[at[j]] = v;
      if (options_.reuse_known) measured_.emplace(keys[j], v);
    };
    if (in.empty()) return out;
    if (!options_.out_of_time) {
      shared_->estimates += in.size();
      const std::vector<double> v = call(in);
      for (size_t j = 0; j < in.size(); ++j) keep(j, v[j]);
      return out;
    }
    const size_t threads =
        static_cast<size_t>(std::max(1, tbb::this_task_arena::max_concurrency()));
    auto chunk_at = [&](double per_box, size_t left) {
      if (per_box <= 0) return threads;  // not measured yet
      const double t = options_.budget_check_seconds;
      return per_box * left <= t ? left : std::max(threads, static_cast<size_t>(t / per_box));
    };
    // Boxes not reached before the budget ran out keep +inf, and are not recorded.
    for (size_t i = 0; i < in.size() && !stopped();) {
      const size_t n = std::min(chunk_at(pace_, in.size() - i), in.size() - i);
      const auto t0 = std::chrono::steady_clock::now();
      const std::vector<double> v = call(std::vector<Obb>(in.begin() + i, in.begin() + i + n));
      for (size_t j = 0; j < n; ++j) keep(i + j, v[j]);
      shared_->estimates += n;
      i += n;
      // Never 0 once measured (a call too quick for the clock counts as 1 ns a box).
      pace_ = std::max(
          1e-9, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / n);
    }
    return out;
  }

  bool omv() const { return options_.objective == Objective::kOmv; }

  // Per box of `boxes`: what it shares, outside the solid, with `others`: the objective's drop
  // for that box alone when they stay as they are, leaving out the context (the orientation
  // search's measure, for its cost: docs/BENCHMARKS.md, "Overlap-aware objective"; a state's
  // score, score_overlaps(), takes the context in).
  std::vector<double> overlap_with(const std::vector<Obb>& boxes, const std::vector<Obb>& others) {
    std::vector<ShareQuery> queries;
    for (const Obb& b : boxes) {
      ShareQuery& q = queries.emplace_back();
      q.box = b;
      for (const Obb& o : others)
        if (may_meet(b, o)) q.earlier.push_back(o);
    }
    return measure_share(queries);
  }

  // Whether two boxes (grown by the margin) may share volume: false when their circumscribed
  // spheres are apart, and then they share none.
  bool may_meet(const Obb& a, const Obb& b) const {
    const double grow = 2 * std::sqrt(3.0) * options_.margin;
    return (a.center - b.center).norm() <= (a.half.norm() + b.half.norm() + grow) * (1 + 1e-12);
  }

  // The estimated share of each query (its boxes grown by the margin first), recorded per
  // search like measure()'s boxes. A query that no earlier box may meet is 0 unasked. Not asked
  // once the budget is spent (0 then; the callers see stopped() and discard the state).
  std::vector<double> measure_share(const std::vector<ShareQuery>& queries) {
    std::vector<double> out(queries.size(), 0.0);
    if (queries.empty() || stopped()) return out;
    std::vector<ShareQuery> in;
    std::vector<size_t> at;
    std::vector<std::vector<uint64_t>> keys;
    for (size_t i = 0; i < queries.size(); ++i) {
      if (queries[i].earlier.empty()) continue;
      ShareQuery q = queries[i];
      if (options_.margin > 0) {
        q.box.half.array() += options_.margin;
        for (Obb& e : q.earlier) e.half.array() += options_.margin;
      }
      std::vector<uint64_t> key;  // the bits of the box, then of each earlier box
      const BoxBits own = bits_of(q.box);
      key.insert(key.end(), own.begin(), own.end());
      for (const Obb& e : q.earlier) {
        const BoxBits k = bits_of(e);
        key.insert(key.end(), k.begin(), k.end());
      }
      const auto hit = options_.reuse_known ? measured_shares_.find(key) : measured_shares_.end();
      if (hit != measured_shares_.end()) {
        out[i] = hit->second;
        continue;
      }
      in.push_back(std::move(q));
      at.push_back(i);
      keys.push_back(std::move(key));
    }
    if (in.empty()) return out;
    auto call_share = [&](const std::vector<ShareQuery>& batch) {
      std::vector<double> v;
      if (options_.concurrent_estimates) {
        tbb::this_task_arena::isolate([&] { v = options_.share(batch); });
      } else {
        v = options_.share(batch);
      }
      shared_->overlaps += batch.size();
      return v;
    };
    auto keep = [&](size_t j, double v) {
      out[at[j]] = v;
      if (options_.reuse_known) measured_shares_.emplace(std::move(keys[j]), v);
    };
    if (!options_.out_of_time) {
      const std::vector<double> v = call_share(in);
      for (size_t j = 0; j < in.size(); ++j) keep(j, v[j]);
      return out;
    }
    // Under a budget, in chunks as measure() does, at the pace of the shares.
    const size_t threads =
        static_cast<size_t>(std::max(1, tbb::this_task_arena::max_concurrency()));
    for (size_t i = 0; i < in.size() && !stopped();) {
      size_t n = threads;
      if (share_pace_ > 0)
        n = std::max(threads, static_cast<size_t>(options_.budget_check_seconds / share_pace_));
      n = std::min(n, in.size() - i);
      const auto t0 = std::chrono::steady_clock::now();
      const std::vector<double> v =
          call_share(std::vector<ShareQuery>(in.begin() + i, in.begin() + i + n));
      for (size_t j = 0; j < n; ++j) keep(i + j, v[j]);
      i += n;
      share_pace_ = std::max(
          1e-9, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / n);
    }
    return out;
  }

 private:
  // One estimator call. When nodes are searched in parallel, the estimator's own parallel work
  // is isolated: a thread waiting for its batch helps with that batch only, and does not start
  // another node's search on top of this one (Builder::splitters_).
  std::vector<double> call(const std::vector<Obb>& boxes) {
    if (!options_.concurrent_estimates) return estimate_(boxes);
    std::vector<double> v;
    tbb::this_task_arena::isolate([&] { v = estimate_(boxes); });
    return v;
  }

  // Lloyd iterations from `state`; `best` keeps the lowest sum seen.
  void iterate(const std::vector<int32_t>& faces, State state, State* best,
               const std::function<void(int, double)>& report) {
    for (int it = 1; it <= options_.lloyd_iterations; ++it) {
      if (!partition(faces, &state)) break;
      if (!update_boxes(&state)) break;  // cut short by the time budget: not comparable
      report(it, state.objective());
      const double before = best->objective();
      if (state.objective() < before) *best = state;
      if (!(state.objective() < before * (1 - kMinDrop))) break;
    }
  }

  // The adjustment: Lloyd iterations started from other planar splits of the node, kept when
  // they end lower. Alternatives: along each covariance axis of the node's faces, cut into
  // `arity` chunks of equal face count and of equal extent. All are screened by the estimated
  // sum of their groups' covariance-axis boxes; the two best screened run the full iterations.
  void adjust(const std::vector<int32_t>& faces, State* best,
              const std::function<void(int, double)>& report) {
    const std::array<Vec3, 3> axes = covariance_axes(mesh_, faces);
    std::vector<State> alternatives;
    std::vector<double> screen;
    for (int a = 0; a < 3; ++a)
      for (bool equal_count : {true, false}) {
        State s;
        s.groups = planar_split(faces, axes[a], equal_count);
        if (s.groups.size() < 2) continue;
        if (stopped()) return;
        std::vector<Obb> boxes;
        for (const auto& g : s.groups) {
          s.axes.push_back(covariance_axes(mesh_, g));
          boxes.push_back(tight_box(mesh_, g, s.axes.back()));
        }
        s.obv = measure(boxes);
        score_overlaps(&s);
        screen.push_back(s.objective());
        alternatives.push_back(std::move(s));
      }
    std::vector<size_t> order(alternatives.size());
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(),
                     [&](size_t x, size_t y) { return screen[x] < screen[y]; });
    for (size_t r = 0; r < std::min<size_t>(2, order.size()); ++r) {
      State trial = alternatives[order[r]];
      if (!update_boxes(&trial)) return;
      State trial_best = trial;
      iterate(faces, trial, &trial_best, report);
      if (trial_best.objective() < best->objective()) {
        *best = std::move(trial_best);
        ++shared_->adjustments;
      }
    }
  }

  // `faces` ordered by their centroids' projection on `dir` (ties by id), cut into `arity`
  // contiguous chunks: of equal count, or at equal steps of the projection's range.
  std::vector<std::vector<int32_t>> planar_split(const std::vector<int32_t>& faces, const Vec3& dir,
                                                 bool equal_count) {
    std::vector<std::pair<double, int32_t>> key;
    for (int32_t f : faces) key.emplace_back(centroid(mesh_, f).dot(dir), f);
    std::sort(key.begin(), key.end());
    const size_t k = static_cast<size_t>(options_.arity);
    std::vector<std::vector<int32_t>> groups(k);
    const double lo = key.front().first, span = key.back().first - key.front().first;
    for (size_t i = 0; i < key.size(); ++i) {
      size_t g = equal_count ? i * k / key.size()
                             : (span > 0 ? static_cast<size_t>((key[i].first - lo) / span * k) : 0);
      groups[std::min(g, k - 1)].push_back(key[i].second);
    }
    std::vector<std::vector<int32_t>> out;
    for (auto& g : groups)
      if (!g.empty()) {
        std::sort(g.begin(), g.end());
        out.push_back(std::move(g));
      }
    return out;
  }

  // The groups a face may join in the flooding partition: those of its assigned neighbours
  // (owner, by local id), ascending and without repeats; all k groups for an isolated seed
  // (`from` < 0).
  std::vector<size_t> flood_candidates(int32_t face, int32_t from, size_t k,
                                       const std::vector<int32_t>& owner) const {
    std::vector<size_t> cand;
    if (from < 0) {
      for (size_t g = 0; g < k; ++g) cand.push_back(g);
      return cand;
    }
    for (int32_t n : adj_[face]) {
      const int32_t j = local_[n];
      if (j >= 0 && owner[j] >= 0) cand.push_back(owner[j]);
    }
    std::sort(cand.begin(), cand.end());
    cand.erase(std::unique(cand.begin(), cand.end()), cand.end());
    return cand;
  }

  // Flooding partition from the current boxes; false when it cannot make `groups` groups, or
  // when the time budget is spent before one of its batches of estimates.
  bool partition(const std::vector<int32_t>& faces, State* s) {
    const size_t k = s->groups.size();
    std::vector<Vec3> origin;  // where each region's distances are measured from
    for (size_t g = 0; g < k; ++g)
      origin.push_back(tight_box(mesh_, s->groups[g], s->axes[g]).center);
    // Local ids of this node's faces (-1 for other faces), cleared again on the way out.
    if (local_.size() != mesh_.faces.size()) local_.assign(mesh_.faces.size(), -1);
    for (size_t i = 0; i < faces.size(); ++i) local_[faces[i]] = static_cast<int32_t>(i);
    struct Clear {
      std::vector<int32_t>& local;
      const std::vector<int32_t>& faces;
      ~Clear() {
        for (int32_t f : faces) local[f] = -1;
      }
    } clear{local_, faces};
    std::vector<int32_t> owner(faces.size(), -1);
    std::vector<Vec3> cent(faces.size());
    for (size_t i = 0; i < faces.size(); ++i) cent[i] = centroid(mesh_, faces[i]);
    // Per group: running projections along its axes, the OBV of the box so far (or stale).
    std::vector<Vec3> lo(k, Vec3::Constant(INFINITY)), hi(k, Vec3::Constant(-INFINITY));
    std::vector<double> obv(k, 0.0);
    std::vector<bool> fresh(k, false);
    auto box_with = [&](size_t g, int32_t f, Vec3* nlo, Vec3* nhi) {
      *nlo = lo[g];
      *nhi = hi[g];
      for (int c = 0; c < 3; ++c) {
        const Vec3& p = mesh_.vertices[mesh_.faces[f][c]];
        for (int a = 0; a < 3; ++a) {
          const double t = p.dot(s->axes[g][a]);
          (*nlo)[a] = std::min((*nlo)[a], t);
          (*nhi)[a] = std::max((*nhi)[a], t);
        }
      }
      return *nlo != lo[g] || *nhi != hi[g];
    };
    auto make_box = [&](size_t g, const Vec3& l, const Vec3& h) {
      return box_from_projections(s->axes[g], l, h);
    };
    using Entry = std::tuple<double, int32_t, int32_t>;  // distance, local face, group
    std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> queue;
    auto assign = [&](int32_t i, size_t g, const Vec3& l, const Vec3& h, bool grew,
                      double new_obv) {
      owner[i] = static_cast<int32_t>(g);
      if (grew) {
        lo[g] = l;
        hi[g] = h;
        fresh[g] = new_obv >= 0;
        if (fresh[g]) obv[g] = new_obv;
      }
      for (int32_t n : adj_[faces[i]]) {
        const int32_t j = local_[n];
        if (j < 0 || owner[j] >= 0) continue;
        queue.emplace((cent[j] - origin[g]).norm(), j, static_cast<int32_t>(g));
      }
    };
    auto seed = [&](size_t g, int32_t i) {
      Vec3 l, h;
      box_with(g, faces[i], &l, &h);
      assign(i, g, l, h, true, -1);
    };
    // Seeds: per box the nearest face to its centre not taken by an earlier box.
    for (size_t g = 0; g < k; ++g) {
      int32_t best = -1;
      double bd = INFINITY;
      for (size_t i = 0; i < faces.size(); ++i) {
        if (owner[i] >= 0) continue;
        const double d = (cent[i] - origin[g]).norm();
        if (d < bd) bd = d, best = static_cast<int32_t>(i);
      }
      if (best < 0) return false;
      seed(g, best);
    }
    size_t left = faces.size() - k;
    while (left > 0) {
      if (queue.empty()) {
        // A part of the node's faces not connected to any region: its face nearest to a box
        // centre joins the box whose OBV grows least, and flooding goes on from there.
        int32_t best = -1;
        double bd = INFINITY;
        for (size_t i = 0; i < faces.size(); ++i)
          for (size_t g = 0; g < k && owner[i] < 0; ++g) {
            const double d = (cent[i] - origin[g]).norm();
            if (d < bd) bd = d, best = static_cast<int32_t>(i);
          }
        queue.emplace(bd, best, -1);
      }
      const auto [dist, i, from] = queue.top();
      queue.pop();
      if (owner[i] >= 0) continue;
      const std::vector<size_t> cand = flood_candidates(faces[i], from, k, owner);
      std::vector<Vec3> nl(cand.size()), nh(cand.size());
      std::vector<bool> grows(cand.size());
      for (size_t c = 0; c < cand.size(); ++c)
        grows[c] = box_with(cand[c], faces[i], &nl[c], &nh[c]);
      size_t pick = 0;
      double pick_obv = -1;
      bool any_free = false;
      for (size_t c = 0; c < cand.size(); ++c) any_free |= !grows[c];
      if (cand.size() > 1 && !any_free) {
        // dOBV per candidate: OBV(grown) - OBV(current), estimated in one batch.
        std::vector<Obb> batch;
        std::vector<int> current_at(cand.size(), -1);
        for (size_t c = 0; c < cand.size(); ++c) {
          if (!fresh[cand[c]]) {
            current_at[c] = static_cast<int>(batch.size());
            batch.push_back(make_box(cand[c], lo[cand[c]], hi[cand[c]]));
          }
          batch.push_back(make_box(cand[c], nl[c], nh[c]));
        }
        const std::vector<double> v = measure(batch);
        if (stopped()) return false;  // some of v may be missing (+inf)
        double best = INFINITY;
        size_t at = 0;
        for (size_t c = 0; c < cand.size(); ++c) {
          if (current_at[c] >= 0) {
            obv[cand[c]] = v[at++];
            fresh[cand[c]] = true;
          }
          const double grown = v[at++];
          const double d = grown - obv[cand[c]];
          if (d < best) best = d, pick = c, pick_obv = grown;
        }
      } else if (cand.size() > 1) {
        // Free for some: the nearest such box centre.
        double best = INFINITY;
        for (size_t c = 0; c < cand.size(); ++c) {
          if (grows[c]) continue;
          const double d = (cent[i] - origin[cand[c]]).norm();
          if (d < best) best = d, pick = c;
        }
      }
      assign(i, cand[pick], nl[pick], nh[pick], grows[pick], pick_obv);
      --left;
    }
    std::vector<std::vector<int32_t>> groups(k);
    for (size_t i = 0; i < faces.size(); ++i) groups[owner[i]].push_back(faces[i]);
    for (const auto& g : groups)
      if (g.empty()) return false;
    s->groups = std::move(groups);
    return true;
  }

  const Mesh& mesh_;
  const std::vector<std::array<int32_t, 3>>& adj_;
  const VariationalOptions& options_;
  const ObvEstimate& estimate_;
  SearchShared* shared_;
  int level_ = 0;  // level of the boxes being fitted
  // Seconds per box of this splitter's last chunk under a budget; 0: unknown. Each thread's
  // own: the nodes searched at once differ in size, and a chunk's length is this thread's.
  double pace_ = 0;
  double share_pace_ = 0;       // the same for measure_share()
  std::vector<int32_t> local_;  // mesh face -> index in the node being partitioned, else -1
  // A box's bits: centre, axes and half extents, as the estimator sees them.
  using BoxBits = std::array<uint64_t, 15>;
  struct BoxBitsHash {
    size_t operator()(const BoxBits& b) const {
      uint64_t h = 0x9e3779b97f4a7c15ull;
      for (uint64_t w : b) h = (h ^ w) * 0x100000001b3ull + (h >> 29);
      // splitmix64's finaliser, so that the last words' high bits reach the low bits too
      h = (h ^ (h >> 30)) * 0xbf58476d1ce4e5b9ull;
      h = (h ^ (h >> 27)) * 0x94d049bb133111ebull;
      return static_cast<size_t>(h ^ (h >> 31));
    }
  };
  static BoxBits bits_of(const Obb& b) {
    BoxBits k;
    auto put = [&k](size_t at, const Vec3& v) {
      for (int c = 0; c < 3; ++c) std::memcpy(&k[at + c], &v[c], sizeof(uint64_t));
    };
    put(0, b.center);
    for (int a = 0; a < 3; ++a) put(3 + 3 * a, b.axes[a]);
    put(12, b.half);
    return k;
  }
  // The current search's boxes and their values (begin_search()).
  std::unordered_map<BoxBits, double, BoxBitsHash> measured_;
  struct WordsHash {
    size_t operator()(const std::vector<uint64_t>& w) const {
      uint64_t h = 0x9e3779b97f4a7c15ull;
      for (uint64_t x : w) h = (h ^ x) * 0x100000001b3ull + (h >> 29);
      h = (h ^ (h >> 30)) * 0xbf58476d1ce4e5b9ull;
      return static_cast<size_t>(h ^ (h >> 31));
    }
  };
  // The current search's shares, keyed by their boxes' bits (measure_share()).
  std::unordered_map<std::vector<uint64_t>, double, WordsHash> measured_shares_;
  std::vector<Obb> context_;  // set_context()

 public:
  struct Record {
    std::unordered_map<BoxBits, double, BoxBitsHash> boxes;
  };

 private:
  Record earlier_;  // begin_search_from(): answers what measured_ lacks
};

void NodeSplitter::begin_search_from(Record record) {
  begin_search();
  earlier_ = std::move(record);
}

NodeSplitter::Record NodeSplitter::take_record() {
  Record r{std::move(measured_)};
  begin_search();
  return r;
}

std::vector<int32_t> merged(const std::vector<int32_t>& a, const std::vector<int32_t>& b) {
  std::vector<int32_t> out;
  out.reserve(a.size() + b.size());
  std::merge(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(out));
  return out;
}

class Builder {
  struct Move {
    int32_t a, b;                 // the two parents
    std::vector<int32_t> ua, ub;  // their new units
  };

 public:
  Builder(const Mesh& mesh, const VariationalOptions& options, const ObvEstimate& estimate)
      : mesh_(mesh),
        options_(options),
        adjacency_(face_neighbours(mesh)),
        splitters_([this, &estimate] {
          return NodeSplitter(mesh_, adjacency_, options_, estimate, &shared_);
        }) {}

  // Whether the time budget is spent (a state resumed after it was keeps it spent). Only
  // between parallel steps: it writes the state.
  bool out_of_time(VariationalState* st) {
    if (!st->budget_spent && budget_gone(*st)) st->budget_spent = true;
    return st->budget_spent;
  }

  // A search that the budget cut short marks the state spent, and a checkpoint saves it so
  // (test CutRootSearchIsSavedAsSpent).
  void record_cut(VariationalState* st) {
    if (shared_.spent) st->budget_spent = true;
  }

  void count(VariationalReport* report) const {
    report->estimates = shared_.estimates;
    report->reused = shared_.reused;
    report->reused_earlier = shared_.reused_earlier;
    report->overlaps = shared_.overlaps;
    report->adjustments = shared_.adjustments;
    report->merges = shared_.merges;
    report->regroups_skipped = shared_.regroups_skipped;
    report->refitted = shared_.refitted;
  }

  void start(VariationalState* st) {
    TreeNode root;
    root.faces.resize(mesh_.faces.size());
    std::iota(root.faces.begin(), root.faces.end(), 0);
    st->nodes = {root};
    NodeSplitter& splitter = splitters_.local();
    splitter.set_level(0);
    // The root's axes: the best of the covariance axes and the search, like any group's.
    st->axes = {out_of_time(st) ? covariance_axes(mesh_, root.faces)
                                : splitter.optimise_single(root.faces)};
    record_cut(st);  // if the root's search was cut short
  }

  // Splits every node of level st->split_levels that can be split.
  void split_level(VariationalState* st) {
    const int32_t level = st->split_levels + 1;
    std::vector<int32_t> parents;
    for (const TreeNode& n : st->nodes)
      if (n.level == level - 1 && n.faces.size() >= 2) parents.push_back(n.id);
    VariationalProgress progress;
    progress.level = level;
    progress.nodes = parents.size();
    forget_pace();  // boxes of another level take another time
    std::mutex progress_mutex;
    // Each node's split depends on its faces alone (the orientation starts are seeded by the
    // group), so the nodes may be split in any order, or at once: the children are appended in
    // the parents' order below, and the tree is the same.
    std::vector<NodeSplitter::State> split(parents.size());
    for_each_node(parents.size(), [&](size_t i) {
      const std::vector<int32_t>& faces =
          st->nodes[parents[i]].faces;  // not written until all are split
      NodeSplitter::State& s = split[i];
      bool complete = false;
      if (budget_gone(*st)) {  // the time budget is spent: the baseline's split and axes
        s.groups = split_into_groups(mesh_, faces, options_.arity);
        for (const auto& g : s.groups) s.axes.push_back(covariance_axes(mesh_, g));
      } else {
        NodeSplitter& splitter = splitters_.local();
        splitter.set_level(level);
        s = splitter.split(faces, [&](int it, double sum) {
          std::lock_guard<std::mutex> lock(progress_mutex);
          progress.iteration = it;
          progress.estimates = shared_.estimates;
          progress.done = (st->split_levels + static_cast<double>(progress.node) / parents.size()) /
                          options_.depth;
          if (options_.progress) {
            VariationalProgress q = progress;
            q.sum_obv += sum;
            options_.progress(q);
          }
        });
        complete = !splitter.spent();
      }
      std::lock_guard<std::mutex> lock(progress_mutex);
      if (complete) progress.sum_obv += s.objective();  // a cut state's sum is incomplete
      ++progress.node;
    });
    for (size_t i = 0; i < parents.size(); ++i) {
      const int32_t p = parents[i];
      const NodeSplitter::State& s = split[i];
      for (size_t g = 0; g < s.groups.size(); ++g) {
        TreeNode child;
        child.id = static_cast<int32_t>(st->nodes.size());
        child.parent = p;
        child.level = level;
        child.faces = s.groups[g];
        st->nodes[p].children.push_back(child.id);
        st->nodes.push_back(std::move(child));
        st->axes.push_back(s.axes[g]);
      }
    }
    ++st->split_levels;
    record_cut(st);  // if a node's search was cut short, or the budget ran out
  }

  int depth(const VariationalState& st) const {
    int d = 0;
    for (const TreeNode& n : st.nodes) d = std::max(d, static_cast<int>(n.level));
    return d;
  }

  // Estimated e: sum over layers of ω(l) times the layer's estimated sum of OBV.
  double estimated_e(const VariationalState& st) {
    const int d = depth(st);
    std::vector<Obb> boxes;
    for (size_t i = 0; i < st.nodes.size(); ++i)
      boxes.push_back(tight_box(mesh_, st.nodes[i].faces, st.axes[i]));
    forget_pace();  // the root first, then ever smaller boxes
    NodeSplitter& splitter = splitters_.local();
    // Not this thread's last search's boxes: which search that was depends on timing, and the
    // counts must not.
    splitter.begin_search();
    const std::vector<double> v = splitter.measure(boxes);
    double e = 0;
    for (size_t i = 0; i < st.nodes.size(); ++i) {
      const TreeNode& n = st.nodes[i];
      // A node is in layers n.level .. (n is a leaf ? d : n.level).
      const int last = n.children.empty() ? d : n.level;
      for (int l = n.level; l <= last; ++l) e += layer_weight(d, l) * v[i];
    }
    if (options_.objective == Objective::kOmv) {
      // Less each layer's overlap term (each box's share with the layer's boxes before it),
      // weighed like the layer.
      for (int l = 0; l <= d; ++l) {
        const std::vector<int32_t> layer = layer_members(st, l);
        std::vector<ShareQuery> queries;
        for (size_t j = 0; j < layer.size(); ++j) {
          ShareQuery& q = queries.emplace_back();
          q.box = boxes[layer[j]];
          for (size_t i = 0; i < j; ++i)
            if (splitter.may_meet(q.box, boxes[layer[i]])) q.earlier.push_back(boxes[layer[i]]);
        }
        for (double o : splitter.measure_share(queries)) e -= layer_weight(d, l) * o;
      }
    }
    return e;
  }

  // The last step under kOmv (VariationalOptions::refit): each box of levels 0..kRefitLevels
  // turned, its faces fixed, where that lowers the estimated e. A box's part of e is, over the
  // layers it is in, ω(l) times its OBV less what it shares with the layer's other boxes (its OMV
  // with them less theirs without it), so each turn kept lowers the estimated e by the drop it was
  // kept for. The candidates are geometry alone (the nodes at once); their OBV is one batch per
  // level; the choices are made node by node, root first, each against the boxes as they stand.
  void refit(VariationalState* st) {
    const int d = depth(*st);
    const size_t n = st->nodes.size();
    std::mt19937_64 rng(options_.seed ^ 0x5851f42d4c957f2dull);
    std::vector<std::array<Vec3, 3>> rotations;
    for (int k = 0; k < kRefitRotations; ++k) rotations.push_back(random_axes(rng));
    // Per node: its axes, then the descents from them and from its best screened rotations.
    std::vector<std::vector<std::array<Vec3, 3>>> candidates(n);
    for_each_node(n, [&](size_t i) {
      if (st->nodes[i].level > kRefitLevels) return;
      const std::vector<int32_t> vertices = distinct_vertices(mesh_, st->nodes[i].faces);
      std::vector<std::pair<double, int>> screen;
      for (int k = 0; k < kRefitRotations; ++k)
        screen.emplace_back(extent_product(mesh_, vertices, rotations[k]), k);
      std::partial_sort(screen.begin(), screen.begin() + kRefitStarts, screen.end());
      auto& c = candidates[i];
      c.push_back(st->axes[i]);
      // The box's own basin first, at a step below the search's last (0.0125 rad).
      c.push_back(descend_volume(mesh_, vertices, st->axes[i], 0.01));
      for (int k = 0; k < kRefitStarts; ++k)
        c.push_back(descend_volume(mesh_, vertices, rotations[screen[k].second], 0.2));
    });
    std::vector<Obb> boxes;  // the boxes as they stand
    for (size_t i = 0; i < n; ++i)
      boxes.push_back(tight_box(mesh_, st->nodes[i].faces, st->axes[i]));
    std::vector<std::vector<int32_t>> layers(d + 1);
    for (int l = 0; l <= d; ++l) layers[l] = layer_members(*st, l);
    NodeSplitter& splitter = splitters_.local();
    splitter.begin_search();
    for (int level = 0; level <= std::min(d, kRefitLevels); ++level) {
      // The OBV of every candidate of the level's nodes: one batch.
      std::vector<size_t> ids, at{0};  // node ids[j]'s candidates are batch[at[j] .. at[j + 1])
      std::vector<Obb> batch;
      for (size_t i = 0; i < n; ++i)
        if (st->nodes[i].level == level) {
          ids.push_back(i);
          for (const auto& a : candidates[i])
            batch.push_back(tight_box(mesh_, st->nodes[i].faces, a));
          at.push_back(batch.size());
        }
      forget_pace();
      const std::vector<double> obv = splitter.measure(batch);
      if (splitter.stopped()) return;  // values missing: the boxes stay as they are
      for (size_t j = 0; j < ids.size(); ++j) {
        const size_t i = ids[j];
        std::vector<Obb> mine(batch.begin() + at[j], batch.begin() + at[j + 1]);
        std::vector<double> value =
            refit_values(*st, layers, boxes, i, mine,
                         std::vector<double>(obv.begin() + at[j], obv.begin() + at[j + 1]));
        if (splitter.stopped()) return;
        size_t best = std::min_element(value.begin(), value.end()) - value.begin();
        std::array<Vec3, 3> axes = candidates[i][best];
        double least = value[best];
        if (level <= kRefitObjectiveLevels) {
          // The few big boxes: a descent on the value itself from the best candidate.
          descend_value(
              mesh_, st->nodes[i].faces, 0.02, 6.25e-4, &axes, &least,
              [&](const std::vector<Obb>& trial) {
                return refit_values(*st, layers, boxes, i, trial, splitter.measure(trial));
              },
              [](size_t) {}, [&] { return splitter.stopped(); });
          // Cut short, or values missing from its last call (stopped() stays true once true):
          // the boxes stay as they are.
          if (splitter.stopped()) return;
        }
        if (least < value[0] - kMinDrop * std::abs(value[0])) {
          st->axes[i] = axes;
          boxes[i] = tight_box(mesh_, st->nodes[i].faces, axes);
          ++shared_.refitted;
        }
      }
    }
  }

  // Per box of `trial` (node i's faces along other axes, with their estimated OBV): its part
  // of the estimated e with the boxes as they stand, Σ over the layers i is in of ω(l) (OBV less
  // its share with the layer's other boxes).
  std::vector<double> refit_values(const VariationalState& st,
                                   const std::vector<std::vector<int32_t>>& layers,
                                   const std::vector<Obb>& boxes, size_t i,
                                   const std::vector<Obb>& trial, const std::vector<double>& obv) {
    const int d = static_cast<int>(layers.size()) - 1;
    const TreeNode& node = st.nodes[i];
    const int last = node.children.empty() ? d : node.level;
    std::vector<double> value(trial.size(), 0.0);
    NodeSplitter& splitter = splitters_.local();
    for (int l = node.level; l <= last; ++l) {
      std::vector<Obb> others;
      for (int32_t j : layers[l])
        if (j != static_cast<int32_t>(i)) others.push_back(boxes[j]);
      const std::vector<double> shared = splitter.overlap_with(trial, others);
      for (size_t c = 0; c < trial.size(); ++c)
        value[c] += layer_weight(d, l) * (obv[c] - shared[c]);
    }
    return value;
  }

  // The nodes of layer l: those of level l, and the leaves above it.
  static std::vector<int32_t> layer_members(const VariationalState& st, int l) {
    std::vector<int32_t> out;
    for (const TreeNode& n : st.nodes)
      if (n.level == l || (n.level < l && n.children.empty())) out.push_back(n.id);
    return out;
  }

  // One bottom-up sweep; returns the drop in estimated e it made.
  double sweep(VariationalState* st) {
    const int d = depth(*st);
    double gain = 0;
    // Sized here, on this thread: the parallel regroupings of a level each write only their
    // own slot.
    settled_.resize(st->nodes.size());
    known_.resize(st->nodes.size());
    for (int l = d - 1; l >= 1 && !out_of_time(st); --l) {
      std::vector<int32_t> grand;
      for (const TreeNode& n : st->nodes)
        if (n.level == l - 1 && n.children.size() >= 2) grand.push_back(n.id);
      forget_pace();
      VariationalProgress progress;
      progress.level = l;
      progress.sweep = st->sweeps + 1;
      progress.nodes = grand.size();
      size_t level_faces = 0, faces_done = 0;
      for (int32_t g : grand) level_faces += st->nodes[g].faces.size();
      std::mutex progress_mutex;
      // Under kOmv a regrouping's parents count their overlap with the layer's other boxes:
      // those under other grandparents as they stand now, whatever the regroupings running at
      // once do to them, so that the tree does not depend on their order.
      layer_.clear();
      if (options_.objective == Objective::kOmv)
        for (int32_t id : layer_members(*st, l))
          layer_.push_back(
              {st->nodes[id].parent, tight_box(mesh_, st->nodes[id].faces, st->axes[id])});
      // Each regrouping reads and writes only the children and grandchildren of its node g, so
      // those of one level may run at once. The gains are added in the nodes' order, as one
      // after another would: the same sum, to the bit, and so the same decision to sweep again.
      std::vector<double> gains(grand.size(), 0.0);
      for_each_node(grand.size(), [&](size_t i) {
        if (budget_gone(*st)) return;
        NodeSplitter& splitter = splitters_.local();
        splitter.set_level(l);
        gains[i] = regroup(st, grand[i], &splitter);
        std::lock_guard<std::mutex> lock(progress_mutex);
        faces_done += st->nodes[grand[i]].faces.size();
        ++progress.node;
        progress.estimates = shared_.estimates;
        progress.sweep_done =
            ((d - 1 - l) + static_cast<double>(faces_done) / std::max<size_t>(level_faces, 1)) /
            std::max(d - 1, 1);
        if (options_.progress) options_.progress(progress);
      });
      for (double g : gains) gain += layer_weight(d, l) * g;
    }
    record_cut(st);  // if a regrouping was cut short
    return gain;
  }

 private:
  // Re-groups the grandchildren of node g among its children; returns the drop in the
  // estimated sum of OBV of its children.
  // Reads st's other nodes only where no other regrouping of the level writes (see sweep()).
  double regroup(VariationalState* st, int32_t g, NodeSplitter* splitter) {
    std::vector<int32_t> parents;
    for (int32_t c : st->nodes[g].children)
      if (!st->nodes[c].children.empty()) parents.push_back(c);
    if (parents.size() < 2) return 0;
    // A regrouping is a function of its inputs (regroup_inputs): where they are those with
    // which it last ended by finding no move, it would find none again, so it is not run.
    if (options_.reuse_known && settled_[g] && *settled_[g] == regroup_inputs(*st, g)) {
      ++shared_.regroups_skipped;
      return 0;
    }
    settled_[g].reset();
    // The record of g's last regrouping, if any, and g's record again when this one ends
    // (under kOmv only: see known_).
    const bool omv = options_.objective == Objective::kOmv;
    const bool records = options_.reuse_known && omv;
    if (records && known_[g]) {
      splitter->begin_search_from(std::move(*known_[g]));
      known_[g].reset();
    } else {
      splitter->begin_search();
    }
    struct KeepRecord {
      NodeSplitter* splitter;
      std::optional<NodeSplitter::Record>* into;
      bool keep;
      ~KeepRecord() {
        if (keep) *into = splitter->take_record();
      }
    } keep_record{splitter, &known_[g], records};
    std::vector<Obb> boxes;
    for (int32_t p : parents) boxes.push_back(tight_box(mesh_, st->nodes[p].faces, st->axes[p]));
    const std::vector<double> v = splitter->measure(boxes);
    std::map<int32_t, double> cur;
    for (size_t i = 0; i < parents.size(); ++i) cur[parents[i]] = v[i];
    // Under kOmv: the objective of parents a and b as they stand, their overlap with each other
    // and with the layer's other boxes included (context_for); else their sum of OBV.
    auto current = [&](int32_t a, int32_t b) {
      if (!omv) return cur[a] + cur[b];
      NodeSplitter::State s;
      for (int32_t p : {a, b}) {
        s.groups.push_back(st->nodes[p].faces);
        s.axes.push_back(st->axes[p]);
        s.obv.push_back(cur[p]);
      }
      splitter->set_context(context_for(*st, g, a, b));
      splitter->score_overlaps(&s);
      return s.objective();
    };
    double total = 0;
    for (int pass = 0; pass < 3 && !budget_gone(*st); ++pass) {
      std::vector<Move> moves;
      std::set<std::pair<std::vector<int32_t>, std::vector<int32_t>>> seen;
      auto add = [&](int32_t a, int32_t b, std::vector<int32_t> ua, std::vector<int32_t> ub) {
        std::sort(ua.begin(), ua.end());
        std::sort(ub.begin(), ub.end());
        if (seen.insert({ua, ub}).second) moves.push_back({a, b, std::move(ua), std::move(ub)});
      };
      for (size_t i = 0; i < parents.size(); ++i)
        for (size_t j = i + 1; j < parents.size(); ++j) {
          const int32_t a = parents[i], b = parents[j];
          const auto& ca = st->nodes[a].children;
          const auto& cb = st->nodes[b].children;
          for (size_t x = 0; x < ca.size(); ++x)
            for (size_t y = 0; y < cb.size(); ++y) {  // swap ca[x] and cb[y]
              std::vector<int32_t> ua = ca, ub = cb;
              std::swap(ua[x], ub[y]);
              add(a, b, ua, ub);
            }
          for (int dir = 0; dir < 2; ++dir) {  // move one unit from one to the other
            const auto& from = dir ? cb : ca;
            const auto& to = dir ? ca : cb;
            if (from.size() < 2 || static_cast<int>(to.size()) >= options_.arity) continue;
            for (size_t x = 0; x < from.size(); ++x) {
              std::vector<int32_t> uf = from, ut = to;
              ut.push_back(uf[x]);
              uf.erase(uf.begin() + x);
              if (dir)
                add(a, b, ut, uf);
              else
                add(a, b, uf, ut);
            }
          }
        }
      // Screen every move by the sum of OBV of the best of a few fixed orientations per new group
      // (the two old parents' axes and the group's covariance axes); only the two best screened
      // get the full orientation search, which costs a hundred estimates or more per group.
      // Under either objective the screen and that search weigh OBV alone; under kOmv the move
      // is judged by the searched state's objective, overlaps included (why: docs/derivations.md,
      // "The variational builder", Objective).
      std::vector<NodeSplitter::State> cand(moves.size());
      std::vector<double> screen(moves.size());
      for (size_t c = 0; c < moves.size(); ++c) {
        if (budget_gone(*st)) return total;  // nothing of this pass is applied
        const Move& mv = moves[c];
        NodeSplitter::State& s = cand[c];
        std::vector<Obb> boxes;
        for (const auto* units : {&mv.ua, &mv.ub}) {
          std::vector<int32_t> faces;
          for (int32_t u : *units) faces = merged(faces, st->nodes[u].faces);
          for (const auto& ax : {st->axes[mv.a], st->axes[mv.b], covariance_axes(mesh_, faces)})
            boxes.push_back(tight_box(mesh_, faces, ax));
          s.groups.push_back(std::move(faces));
        }
        const std::vector<double> v = splitter->measure(boxes);
        screen[c] = 0;
        for (int k = 0; k < 2; ++k) {
          const size_t at = std::min_element(v.begin() + 3 * k, v.begin() + 3 * k + 3) - v.begin();
          screen[c] += v[at];
          s.axes.push_back(boxes[at].axes);
          s.obv.push_back(v[at]);
        }
      }
      std::vector<size_t> order(moves.size());
      std::iota(order.begin(), order.end(), 0);
      std::stable_sort(order.begin(), order.end(),
                       [&](size_t x, size_t y) { return screen[x] < screen[y]; });
      double best_gain = 0;
      NodeSplitter::State best_state;
      const Move* best = nullptr;
      for (size_t r = 0; r < std::min<size_t>(2, order.size()); ++r) {
        const Move& mv = moves[order[r]];
        NodeSplitter::State s = cand[order[r]];
        const double before = current(mv.a, mv.b);  // sets the context for mv.a and mv.b
        if (!splitter->update_boxes(&s, false))
          break;  // cut short by the time budget: not comparable
        // Kept only for a drop of kMinDrop or more of the pair's objective.
        const double gain = before - s.objective();
        if (gain > before * kMinDrop && gain > best_gain)
          best_gain = gain, best = &mv, best_state = s;
      }
      if (!best) {
        // No move of this pass gains: a regrouping started from this state would find the
        // same in its first pass (the parents' boxes measured afresh are the boxes measured
        // here: the same faces, axes and estimator values). Not so for a pass that the budget
        // cut short.
        if (options_.reuse_known && !budget_gone(*st)) settled_[g] = regroup_inputs(*st, g);
        break;
      }
      apply(st, *best, best_state);
      cur[best->a] = best_state.obv[0];
      cur[best->b] = best_state.obv[1];
      total += best_gain;
      ++shared_.merges;
    }
    return total;
  }

  // What regroup(g) reads: g's children in order, and per child its axes (their bits) and its
  // units in order, each with its faces. (A child's own faces are its units'.) The level, and
  // with it the orientation search's starts, is g's, which no move changes.
  struct RegroupInputs {
    std::vector<int32_t> ids;    // per child: its id, its unit count, then per unit its id,
                                 // its face count and its faces
    std::vector<uint64_t> axes;  // per child: its 9 axis components' bits
    // kOmv: the bits of the layer's boxes under other nodes that may meet g's (context_for),
    // which a regrouping's scores depend on too.
    std::vector<uint64_t> context;
    bool operator==(const RegroupInputs& o) const {
      return ids == o.ids && axes == o.axes && context == o.context;
    }
  };
  RegroupInputs regroup_inputs(const VariationalState& st, int32_t g) const {
    RegroupInputs in;
    for (int32_t c : st.nodes[g].children) {
      in.ids.push_back(c);
      for (const Vec3& a : st.axes[c])
        for (int k = 0; k < 3; ++k) {
          uint64_t bits;
          std::memcpy(&bits, &a[k], sizeof bits);
          in.axes.push_back(bits);
        }
      in.ids.push_back(static_cast<int32_t>(st.nodes[c].children.size()));
      for (int32_t u : st.nodes[c].children) {
        in.ids.push_back(u);
        in.ids.push_back(static_cast<int32_t>(st.nodes[u].faces.size()));
        in.ids.insert(in.ids.end(), st.nodes[u].faces.begin(), st.nodes[u].faces.end());
      }
    }
    if (options_.objective == Objective::kOmv)
      for (const Obb& q : layer_context(g, tight_box(mesh_, st.nodes[g].faces, st.axes[g]))) {
        const auto words = [&in](const double* v, int n) {
          for (int k = 0; k < n; ++k) {
            uint64_t bits;
            std::memcpy(&bits, &v[k], sizeof bits);
            in.context.push_back(bits);
          }
        };
        words(q.center.data(), 3);
        for (const Vec3& a : q.axes) words(a.data(), 3);
        words(q.half.data(), 3);
      }
    return in;
  }

  // The boxes whose overlap with regrouped parents a and b (children of g) counts in their
  // objective: g's other children as they stand, and the layer's boxes under other nodes as
  // they stood when the level's regroupings began (layer_). Only those that may meet a box of
  // g's faces: every tight box of them, whatever its axes, lies in the ball of radius
  // sqrt(3) |h| about g's box's centre c (g's box lies in the ball of radius |h| about c, and a
  // tight box spans at most that ball's extent along each of its axes).
  std::vector<Obb> context_for(const VariationalState& st, int32_t g, int32_t a, int32_t b) const {
    const Obb gb = tight_box(mesh_, st.nodes[g].faces, st.axes[g]);
    std::vector<Obb> out;
    for (int32_t c : st.nodes[g].children)
      if (c != a && c != b) {
        const Obb q = tight_box(mesh_, st.nodes[c].faces, st.axes[c]);
        if (near_node(gb, q)) out.push_back(q);
      }
    for (const Obb& q : layer_context(g, gb)) out.push_back(q);
    return out;
  }

  // The boxes of layer_ under other nodes than g that may meet a box of g's faces (gb: g's
  // tight box).
  std::vector<Obb> layer_context(int32_t g, const Obb& gb) const {
    std::vector<Obb> out;
    for (const LayerBox& q : layer_)
      if (q.parent != g && near_node(gb, q.box)) out.push_back(q.box);
    return out;
  }

  bool near_node(const Obb& gb, const Obb& q) const {
    const double reach = std::sqrt(3.0) * gb.half.norm() + 2 * std::sqrt(3.0) * options_.margin;
    return (q.center - gb.center).norm() <= (reach + q.half.norm()) * (1 + 1e-12);
  }

  void apply(VariationalState* st, const Move& mv, const NodeSplitter::State& s) {
    const int32_t ids[2] = {mv.a, mv.b};
    const std::vector<int32_t>* units[2] = {&mv.ua, &mv.ub};
    for (int k = 0; k < 2; ++k) {
      TreeNode& p = st->nodes[ids[k]];
      p.children = *units[k];
      for (int32_t u : p.children) st->nodes[u].parent = p.id;
      p.faces = s.groups[k];
      st->axes[p.id] = s.axes[k];
    }
  }

  void forget_pace() {
    for (NodeSplitter& splitter : splitters_) splitter.forget_pace();
  }

  // Whether the time budget is spent; safe to ask from the parallel steps.
  bool budget_gone(const VariationalState& st) {
    return st.budget_spent || splitters_.local().stopped();
  }

  // f(0) ... f(n - 1): at once where the estimator may be called from several threads, else in
  // order on this thread.
  template <class F>
  void for_each_node(size_t n, const F& f) {
    if (!options_.concurrent_estimates || n < 2) {
      for (size_t i = 0; i < n; ++i) f(i);
      return;
    }
    // One node a task: nodes differ in size by orders of magnitude.
    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, n, 1),
        [&](const tbb::blocked_range<size_t>& r) {
          for (size_t i = r.begin(); i != r.end(); ++i) f(i);
        },
        tbb::simple_partitioner());
  }

  const Mesh& mesh_;
  const VariationalOptions& options_;
  const std::vector<std::array<int32_t, 3>> adjacency_;
  SearchShared shared_;
  // One splitter per thread, each with its own scratch and pace. A thread runs one search at a
  // time: NodeSplitter::call isolates its waits, so that a thread waiting for its batch does not
  // start another node's search on its stack (which would hold the first node back and deepen
  // the stack by a search per node; the scratch would survive it, as nodes of a level have
  // disjoint faces and partition() restores its entries).
  tbb::enumerable_thread_specific<NodeSplitter> splitters_;
  // Per node g whose regrouping last ended by finding no move: the inputs it ended with
  // (regroup_inputs). Not saved in a checkpoint: a resumed build runs those regroupings again
  // and finds no move again, the same tree. At most one copy of the mesh's face ids per level
  // above the last two, and none where reuse_known is off.
  std::vector<std::optional<RegroupInputs>> settled_;
  // Per node g, under kOmv: what its last regrouping measured (NodeSplitter::Record), which its
  // next one may answer from. Under kOmv a regrouping runs again where only its context (the
  // layer's other boxes) changed, and asks again for most of the boxes of its last run; under
  // kObv it runs again only where its own inputs changed, and asks for few of them
  // (docs/BENCHMARKS.md, "Regroupings that start from their last run's record"), so nothing is
  // kept. Per node, so what it saves does not depend on which thread ran which regrouping; not
  // saved in a checkpoint (a resumed build measures those boxes again, to the same values).
  // Empty where reuse_known is off.
  std::vector<std::optional<NodeSplitter::Record>> known_;
  // Under kOmv, the boxes of the layer being regrouped, as they stood when its regroupings began.
  struct LayerBox {
    int32_t parent;
    Obb box;
  };
  std::vector<LayerBox> layer_;
};

}  // namespace

Tree build_variational(const Mesh& mesh, const VariationalOptions& options,
                       const ObvEstimate& estimate, const VariationalState* resume,
                       VariationalReport* report) {
  VOBB_ASSERT(options.depth >= 0 && options.arity >= 2, "depth >= 0 and arity >= 2");
  VOBB_ASSERT(!mesh.faces.empty(), "build_variational needs faces");
  VOBB_ASSERT(std::isfinite(options.margin) && options.margin >= 0, "margin finite and >= 0");
  VOBB_ASSERT(options.budget_check_seconds > 0, "budget_check_seconds > 0");
  VOBB_ASSERT(options.objective == Objective::kObv || options.share,
              "the kOmv objective needs a share estimate");
  VariationalReport local_report;
  if (!report) report = &local_report;
  *report = VariationalReport{};
  Builder builder(mesh, options, estimate);
  VariationalState st;
  if (resume) {
    st = *resume;
  } else {
    builder.start(&st);
  }
  auto save = [&] {
    if (options.checkpoint) options.checkpoint(st);
  };
  if (!resume) save();
  // Top-down, level by level: ids grow level by level, children after their parent.
  while (st.split_levels < options.depth) {
    bool any = false;
    for (const TreeNode& n : st.nodes) any |= n.level == st.split_levels && n.faces.size() >= 2;
    if (!any) {
      st.split_levels = options.depth;
      break;
    }
    builder.split_level(&st);
    save();
  }
  // Bottom-up merging sweeps while the estimated e drops by 0.1 % or more.
  // The estimated e after the last sweep, where it was taken.
  bool have_known_e = false;
  double known_e = 0;
  while (options.merge && !st.sweeping_done && !builder.out_of_time(&st)) {
    if (st.sweeps >= options.max_sweeps) {
      st.sweeping_done = true;
      break;
    }
    const double e = have_known_e ? known_e : builder.estimated_e(st);
    have_known_e = false;
    if (builder.out_of_time(&st)) break;  // e may be missing boxes; no sweep is started
    double gain = builder.sweep(&st);
    if (options.objective == Objective::kOmv && !builder.out_of_time(&st)) {
      // The regroupings of a level each score against the layer as it stood before them, so
      // two of them may both count a region their moves free: the sum of their gains can
      // exceed the drop. The drop itself decides (and the next sweep starts from that e).
      known_e = builder.estimated_e(st);
      have_known_e = true;
      gain = e - known_e;
    }
    ++st.sweeps;
    if (!(gain >= kMinDrop * e) || st.sweeps >= options.max_sweeps) st.sweeping_done = true;
    save();
  }
  if (options.objective == Objective::kOmv && options.refit && !builder.out_of_time(&st))
    builder.refit(&st);
  report->budget_spent = st.budget_spent;
  report->sweeps = st.sweeps;
  builder.count(report);

  Tree tree;
  tree.method = "variational";
  tree.arity = options.arity;
  tree.mesh_triangles = mesh.faces.size();
  tree.nodes = st.nodes;
  for (size_t i = 0; i < tree.nodes.size(); ++i) {
    TreeNode& n = tree.nodes[i];
    n.box = fit_obb(mesh, n.faces, st.axes[i]);
    std::sort(n.children.begin(), n.children.end());
    tree.depth = std::max(tree.depth, static_cast<int>(n.level));
  }
  return tree;
}

std::array<Vec3, 3> descend_tight_volume(const Mesh& mesh, const std::vector<int32_t>& faces,
                                         const std::array<Vec3, 3>& axes, double step) {
  return descend_volume(mesh, distinct_vertices(mesh, faces), axes, step);
}

}  // namespace vobb
