#include "fast/variational_builder.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <queue>
#include <random>
#include <tuple>

#include "common/status.h"
#include "fast/obbtree_builder.h"

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

Obb tight_box(const Mesh& mesh, const std::vector<int32_t>& faces, const std::array<Vec3, 3>& axes) {
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
  return (mesh.vertices[mesh.faces[f][0]] + mesh.vertices[mesh.faces[f][1]] + mesh.vertices[mesh.faces[f][2]]) / 3.0;
}

std::array<Vec3, 3> rotate(const std::array<Vec3, 3>& axes, int about, double angle) {
  const Eigen::Matrix3d r = Eigen::AngleAxisd(angle, axes[about]).toRotationMatrix();
  return orthonormalize({r * axes[0], r * axes[1], r * axes[2]});
}

class NodeSplitter {
 public:
  NodeSplitter(const Mesh& mesh, const std::vector<std::array<int32_t, 3>>& adjacency,
               const VariationalOptions& options, const ObvEstimate& estimate, size_t* estimates)
      : mesh_(mesh), adj_(adjacency), options_(options), estimate_(estimate), estimates_(estimates) {}

  struct State {
    std::vector<std::vector<int32_t>> groups;
    std::vector<std::array<Vec3, 3>> axes;
    std::vector<double> obv;
    double sum() const { return std::accumulate(obv.begin(), obv.end(), 0.0); }
  };

  // The root: one group, its axes optimised like any child's.
  void set_level(int level) { level_ = level; }

  std::array<Vec3, 3> optimise_single(const std::vector<int32_t>& faces) {
    State s;
    s.groups = {faces};
    s.axes = {covariance_axes(mesh_, faces)};
    update_boxes(&s);
    return s.axes[0];
  }

  // Splits `faces` into at most `arity` groups; returns the groups and their axes.
  State split(const std::vector<int32_t>& faces, const std::function<void(int, double)>& report) {
    State state;
    state.groups = split_into_groups(mesh_, faces, options_.arity);
    for (const auto& g : state.groups) state.axes.push_back(covariance_axes(mesh_, g));
    update_boxes(&state);
    State best = state;
    report(0, best.sum());
    if (state.groups.size() < 2) return best;
    for (int it = 1; it <= options_.lloyd_iterations; ++it) {
      if (!partition(faces, &state)) break;
      update_boxes(&state);
      report(it, state.sum());
      const double before = best.sum();
      if (state.sum() < before) best = state;
      if (!(state.sum() < before * (1 - 1e-3))) break;
    }
    return best;
  }

 private:
  std::vector<double> measure(const std::vector<Obb>& boxes) {
    *estimates_ += boxes.size();
    return estimate_(boxes);
  }

  // Box update: per group, a pattern search over rotations (or the covariance axes alone).
  void update_boxes(State* s) {
    s->obv.assign(s->groups.size(), 0.0);
    for (size_t g = 0; g < s->groups.size(); ++g) {
      const auto& faces = s->groups[g];
      std::array<Vec3, 3> axes = s->axes[g];
      double best = measure({tight_box(mesh_, faces, axes)})[0];
      if (options_.optimise_axes) {
        // Other starts: the covariance axes of the (new) group, and seeded random orientations
        // (uniform unit quaternions), so that the search is not stuck in the start's basin.
        // More for the big boxes of the top levels, which weigh most in e.
        std::vector<std::array<Vec3, 3>> starts{covariance_axes(mesh_, faces)};
        const int random_starts = level_ <= 3 ? 32 : 4;
        std::mt19937_64 rng(options_.seed ^ (0x9e3779b97f4a7c15ull * (faces.front() + 1)) ^ faces.size());
        for (int r = 0; r < random_starts; ++r) {
          Eigen::Quaterniond q;
          auto gauss = [&] {  // Box-Muller on the generator's raw bits: the same on every machine
            const double u1 = (static_cast<double>(rng() >> 11) + 1) * 0x1.0p-53, u2 = static_cast<double>(rng() >> 11) * 0x1.0p-53;
            return std::sqrt(-2 * std::log(u1)) * std::cos(2 * M_PI * u2);
          };
          q.coeffs() << gauss(), gauss(), gauss(), gauss();
          const Eigen::Matrix3d rot = q.normalized().toRotationMatrix();
          starts.push_back(orthonormalize({Vec3(rot.col(0)), Vec3(rot.col(1)), Vec3(rot.col(2))}));
        }
        std::vector<Obb> start_boxes;
        for (const auto& a : starts) start_boxes.push_back(tight_box(mesh_, faces, a));
        const std::vector<double> sv = measure(start_boxes);
        for (size_t i = 0; i < starts.size(); ++i)
          if (sv[i] < best) best = sv[i], axes = starts[i];
        for (double step = 0.2; step >= 0.0125;) {
          std::vector<std::array<Vec3, 3>> trial;
          std::vector<Obb> boxes;
          for (int about = 0; about < 3; ++about)
            for (double sign : {1.0, -1.0}) {
              trial.push_back(rotate(axes, about, sign * step));
              boxes.push_back(tight_box(mesh_, faces, trial.back()));
            }
          const std::vector<double> v = measure(boxes);
          const size_t i = std::min_element(v.begin(), v.end()) - v.begin();
          if (v[i] < best) {
            best = v[i];
            axes = trial[i];
          } else {
            step *= 0.5;
          }
        }
      }
      s->axes[g] = axes;
      s->obv[g] = best;
    }
  }

  // Flooding partition from the current boxes; false when it cannot make `groups` groups.
  bool partition(const std::vector<int32_t>& faces, State* s) {
    const size_t k = s->groups.size();
    std::vector<Obb> boxes;
    for (size_t g = 0; g < k; ++g) boxes.push_back(tight_box(mesh_, s->groups[g], s->axes[g]));
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
    auto make_box = [&](size_t g, const Vec3& l, const Vec3& h) { return box_from_projections(s->axes[g], l, h); };
    using Entry = std::tuple<double, int32_t, int32_t>;  // distance, local face, group
    std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> queue;
    auto assign = [&](int32_t i, size_t g, const Vec3& l, const Vec3& h, bool grew, double new_obv) {
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
        queue.emplace((cent[j] - boxes[g].center).norm(), j, static_cast<int32_t>(g));
      }
    };
    // Seeds: per box the nearest face to its centre not taken by an earlier box.
    for (size_t g = 0; g < k; ++g) {
      int32_t best = -1;
      double bd = INFINITY;
      for (size_t i = 0; i < faces.size(); ++i) {
        if (owner[i] >= 0) continue;
        const double d = (cent[i] - boxes[g].center).norm();
        if (d < bd) bd = d, best = static_cast<int32_t>(i);
      }
      if (best < 0) return false;
      Vec3 l, h;
      box_with(g, faces[best], &l, &h);
      assign(best, g, l, h, true, -1);
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
            const double d = (cent[i] - boxes[g].center).norm();
            if (d < bd) bd = d, best = static_cast<int32_t>(i);
          }
        queue.emplace(bd, best, -1);
      }
      const auto [dist, i, from] = queue.top();
      queue.pop();
      if (owner[i] >= 0) continue;
      // Candidates: the groups of the assigned neighbours (all groups for an isolated seed).
      std::vector<size_t> cand;
      if (from < 0) {
        for (size_t g = 0; g < k; ++g) cand.push_back(g);
      } else {
        for (int32_t n : adj_[faces[i]]) {
          const int32_t j = local_[n];
          if (j >= 0 && owner[j] >= 0) cand.push_back(owner[j]);
        }
        std::sort(cand.begin(), cand.end());
        cand.erase(std::unique(cand.begin(), cand.end()), cand.end());
      }
      std::vector<Vec3> nl(cand.size()), nh(cand.size());
      std::vector<bool> grows(cand.size());
      for (size_t c = 0; c < cand.size(); ++c) grows[c] = box_with(cand[c], faces[i], &nl[c], &nh[c]);
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
          const double d = (cent[i] - boxes[cand[c]].center).norm();
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
  size_t* estimates_;
  int level_ = 0;                // level of the boxes being fitted
  std::vector<int32_t> local_;   // mesh face -> index in the node being partitioned, else -1
};

}  // namespace

Tree build_variational(const Mesh& mesh, const VariationalOptions& options, const ObvEstimate& estimate) {
  VOBB_ASSERT(options.depth >= 0 && options.arity >= 2, "depth >= 0 and arity >= 2");
  VOBB_ASSERT(!mesh.faces.empty(), "build_variational needs faces");
  const auto adjacency = face_neighbours(mesh);
  Tree tree;
  tree.method = "variational";
  tree.arity = options.arity;
  tree.mesh_triangles = mesh.faces.size();
  TreeNode root;
  root.faces.resize(mesh.faces.size());
  std::iota(root.faces.begin(), root.faces.end(), 0);
  tree.nodes.push_back(root);
  size_t estimates = 0;
  NodeSplitter splitter(mesh, adjacency, options, estimate, &estimates);
  std::vector<std::array<Vec3, 3>> axes{splitter.optimise_single(root.faces)};
  // The root's axes: the best of the covariance axes and a pattern search, like any group.
  VariationalProgress progress;
  // Breadth first, level by level: ids grow level by level, children after their parent.
  for (size_t i = 0; i < tree.nodes.size(); ++i) {
    TreeNode& node = tree.nodes[i];
    node.box = fit_obb(mesh, node.faces, axes[i]);
    tree.depth = std::max(tree.depth, static_cast<int>(node.level));
    if (node.level >= options.depth || node.faces.size() < 2) continue;
    if (progress.level != node.level + 1) {
      progress.level = node.level + 1;
      progress.node = 0;
      progress.sum_obv = 0;
      progress.nodes = 0;
      for (size_t j = i; j < tree.nodes.size(); ++j)
        progress.nodes += tree.nodes[j].level == node.level && tree.nodes[j].faces.size() >= 2;
    }
    const std::vector<int32_t> faces = node.faces;
    const int32_t level = node.level + 1;
    splitter.set_level(level);
    const NodeSplitter::State s = splitter.split(faces, [&](int it, double sum) {
      progress.iteration = it;
      progress.estimates = estimates;
      if (options.progress) {
        VariationalProgress p = progress;
        p.sum_obv += sum;
        options.progress(p);
      }
    });
    progress.sum_obv += s.sum();
    ++progress.node;
    for (size_t g = 0; g < s.groups.size(); ++g) {
      TreeNode child;
      child.id = static_cast<int32_t>(tree.nodes.size());
      child.parent = static_cast<int32_t>(i);
      child.level = level;
      child.faces = s.groups[g];
      tree.nodes[i].children.push_back(child.id);
      tree.nodes.push_back(std::move(child));
      axes.push_back(s.axes[g]);
    }
  }
  return tree;
}

}  // namespace vobb
