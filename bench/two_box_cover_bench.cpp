// How low can a tree's level 1 go? The OMV of two boxes over the mesh's faces split by a plane,
// searched wide: D split directions (a Fibonacci hemisphere) times 63 cuts (every 64th of the
// faces by their centroids' projection), each part's box screened over K seeded rotations by
// its tight volume, the `top` best splits by the screen then refined (each part's rotation by
// a descent on its tight volume) and measured. A level's OMV is what the variational builder's
// level 1 is judged by: what a better root split could give, as far as a search
// over plane splits finds (not a proven optimum).
// With a tree, its level-1 partition is refitted the same way first, to compare like with like.
// Every OMV printed is certify's filter (exact/filtered_solver.h): OBV(A) + OBV(B) less B's
// share with A, an enclosure of the exact value of the two fit_obb boxes, printed as its
// midpoint with its width.
// With T and U, level 2 as well: each half of the T best level-1 splits is searched the same
// way, and the U best splits of one half are paired with the U best of the other; each four
// boxes' OMV (overlaps between the halves' boxes counted once) is the level 2 they give, and
// 8 OMV(1) + 7 OMV(2) what the two levels weigh in e at depth 8 (DESIGN §1's weights).
// Usage: vobb-bench-two-box-cover MESH [TREE] [K D TOP [T U]]
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numeric>
#include <random>
#include <tuple>
#include <utility>

#include "bench/bench_util.h"
#include "builder/variational_builder.h"
#include "common/obb.h"
#include "common/tree.h"
#include "common/tree_io.h"
#include "exact/filtered_solver.h"

namespace {

using vobb::Mesh;
using vobb::Obb;
using vobb::Vec3;
using Mat3 = Eigen::Matrix3d;

// The faces' tight box volume along the rows of R (the builder's tight_box).
double tight_volume(const Mesh& mesh, const std::vector<int32_t>& faces, const Mat3& R) {
  return vobb::volume(
      vobb::tight_box(mesh, faces, {Vec3(R.row(0)), Vec3(R.row(1)), Vec3(R.row(2))}));
}

// The faces' box along the rows of R, after the builder's descent on its tight volume from
// there (first step 0.2 rad).
Obb refined_fit(const Mesh& mesh, const std::vector<int32_t>& faces, const Mat3& R) {
  const std::array<Vec3, 3> axes = vobb::descend_tight_volume(
      mesh, faces, vobb::orthonormalize({Vec3(R.row(0)), Vec3(R.row(1)), Vec3(R.row(2))}), 0.2);
  return vobb::fit_obb(mesh, faces, axes);
}

// A set of boxes' OMV, enclosed: [lo, hi]. `obv` holds each box's enclosed OBV.
std::pair<double, double> omv(const vobb::exact::FilteredSolver& fs, const std::vector<Obb>& boxes,
                              const std::vector<vobb::MpInterval>& obv) {
  const std::vector<std::vector<int32_t>> earlier = fs.rational().earlier_neighbours(boxes);
  vobb::MpInterval sum = obv[0];
  for (size_t j = 1; j < boxes.size(); ++j) sum += obv[j];
  for (size_t j = 1; j < boxes.size(); ++j) sum -= fs.overlap_term(boxes, j, earlier[j]).value;
  return {sum.inf(), sum.sup()};
}

// The two boxes' OMV, enclosed: [lo, hi].
std::pair<double, double> omv(const vobb::exact::FilteredSolver& fs, const Obb& a, const Obb& b) {
  return omv(fs, {a, b}, {fs.obv(a).value, fs.obv(b).value});
}

Vec3 direction(int d, int D) {  // the d-th of D points of a Fibonacci hemisphere
  const double golden = M_PI * (3 - std::sqrt(5.0));
  const double z = 1 - (d + 0.5) / D, r = std::sqrt(1 - z * z);
  return Vec3(r * std::cos(golden * d), r * std::sin(golden * d), z);
}

// A plane split of a set of faces into two boxes, refined and measured.
struct Cover {
  std::vector<int32_t> a, b;  // the two parts, ascending
  Obb box_a, box_b;
  double lo, hi;  // the two boxes' OMV, enclosed
  int rank, dir, cut;
  double mid() const { return 0.5 * (lo + hi); }
};

// The search over plane splits: K seeded rotations, each face's bounds in each rotated frame,
// D directions times S - 1 cuts.
class Search {
 public:
  static constexpr int S = 64;

  Search(const Mesh& mesh, const vobb::exact::FilteredSolver& fs, int K, int D)
      : mesh_(mesh), fs_(fs), D_(D), n_(mesh.faces.size()) {
    std::mt19937_64 rng(7);
    // Box-Muller on the generator's raw bits (whose sequence the standard fixes), so that every
    // standard library draws the same rotations; std::normal_distribution's algorithm is not
    // fixed.
    auto gauss = [&] {
      const double u1 = (static_cast<double>(rng() >> 11) + 1) * 0x1.0p-53,
                   u2 = static_cast<double>(rng() >> 11) * 0x1.0p-53;
      return std::sqrt(-2 * std::log(u1)) * std::cos(2 * M_PI * u2);
    };
    for (int k = 0; k < K; ++k) {
      Eigen::Quaterniond q;
      q.coeffs() << gauss(), gauss(), gauss(), gauss();
      rotations_.push_back(q.normalized().toRotationMatrix());
    }
    centroid_.resize(n_);
    for (size_t f = 0; f < n_; ++f)
      centroid_[f] = (mesh.corner(f, 0) + mesh.corner(f, 1) + mesh.corner(f, 2)) / 3;
    // Per rotation and face: the face's bounds in the rotated frame (lo xyz, hi xyz).
    bounds_.resize(static_cast<size_t>(K) * n_);
    for (int k = 0; k < K; ++k)
      for (size_t f = 0; f < n_; ++f) {
        std::array<double, 6>& b = bounds_[k * n_ + f];
        b = {INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY, -INFINITY};
        for (int c = 0; c < 3; ++c) {
          const Vec3 p = rotations_[k] * mesh.corner(f, c);
          for (int i = 0; i < 3; ++i)
            b[i] = std::min(b[i], p[i]), b[3 + i] = std::max(b[3 + i], p[i]);
        }
      }
  }

  // The faces' box: the least tight volume over the rotations, then refined.
  Obb box(const std::vector<int32_t>& faces) const {
    size_t best = 0;
    double v = INFINITY;
    for (size_t k = 0; k < rotations_.size(); ++k) {
      const double w = tight_volume(mesh_, faces, rotations_[k]);
      if (w < v) v = w, best = k;
    }
    return refined_fit(mesh_, faces, rotations_[best]);
  }

  // The `top` best splits of `faces` (ascending) by the screen, in the screen's order, each
  // refined and measured; `screen_seconds` gets the screen's time. None where there are fewer
  // than 2 S faces (every cut must leave faces on both sides).
  std::vector<Cover> splits(const std::vector<int32_t>& faces, int top,
                            double* screen_seconds) const {
    const size_t n = faces.size();
    *screen_seconds = 0;
    if (n < 2 * S) return {};
    struct Split {
      double screen;  // the two parts' least tight volumes over the rotations
      int dir, cut;
    };
    std::vector<int> cut_at(n + 1, -1);  // the cut that holds the faces [0, edge) of an order
    for (int c = 1; c < S; ++c) cut_at[n * c / S] = c;
    std::vector<Split> splits;
    const int K = static_cast<int>(rotations_.size());
    *screen_seconds = vobb::bench::seconds([&] {
      for (int d = 0; d < D_; ++d) {
        const std::vector<int32_t> order = sorted_along(faces, direction(d, D_));
        std::vector<double> below(S, INFINITY), above(S, INFINITY);  // by cut c: faces < n c / S
        for (int k = 0; k < K; ++k) {
          // Prefix and suffix bounds, read at every cut.
          for (int pass = 0; pass < 2; ++pass) {
            std::array<double, 6> acc = {INFINITY,  INFINITY,  INFINITY,
                                         -INFINITY, -INFINITY, -INFINITY};
            for (size_t i = 0; i < n; ++i) {
              const size_t at = pass == 0 ? i : n - 1 - i;
              const auto& b = bounds_[k * n_ + order[at]];
              for (int j = 0; j < 3; ++j)
                acc[j] = std::min(acc[j], b[j]), acc[3 + j] = std::max(acc[3 + j], b[3 + j]);
              // pass 0: the faces [0, i]; a cut c holds [0, n c / S). pass 1: [at, n).
              const size_t edge = pass == 0 ? i + 1 : at;
              const int c = cut_at[edge];
              if (c < 0) continue;
              const double v = (acc[3] - acc[0]) * (acc[4] - acc[1]) * (acc[5] - acc[2]);
              double& slot = pass == 0 ? below[c] : above[c];
              slot = std::min(slot, v);
            }
          }
        }
        for (int c = 1; c < S; ++c) splits.push_back({below[c] + above[c], d, c});
      }
    });
    std::sort(splits.begin(), splits.end(),
              [](const Split& a, const Split& b) { return a.screen < b.screen; });
    std::vector<Cover> covers;
    for (int r = 0; r < std::min<int>(top, static_cast<int>(splits.size())); ++r) {
      const std::vector<int32_t> order = sorted_along(faces, direction(splits[r].dir, D_));
      const size_t cut = n * splits[r].cut / S;
      Cover cover;
      cover.a.assign(order.begin(), order.begin() + cut);
      cover.b.assign(order.begin() + cut, order.end());
      std::sort(cover.a.begin(), cover.a.end());
      std::sort(cover.b.begin(), cover.b.end());
      cover.box_a = box(cover.a);
      cover.box_b = box(cover.b);
      std::tie(cover.lo, cover.hi) = omv(fs_, cover.box_a, cover.box_b);
      cover.rank = r, cover.dir = splits[r].dir, cover.cut = splits[r].cut;
      covers.push_back(std::move(cover));
    }
    return covers;
  }

 private:
  std::vector<int32_t> sorted_along(std::vector<int32_t> order, const Vec3& dir) const {
    std::stable_sort(order.begin(), order.end(), [&](int32_t a, int32_t b) {
      return centroid_[a].dot(dir) < centroid_[b].dot(dir);
    });
    return order;
  }

  const Mesh& mesh_;
  const vobb::exact::FilteredSolver& fs_;
  const int D_;
  const size_t n_;
  std::vector<Mat3> rotations_;
  std::vector<Vec3> centroid_;
  std::vector<std::array<double, 6>> bounds_;
};

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2 && argc != 3 && !(argc >= 5 && argc <= 8)) {
    std::fprintf(stderr, "usage: vobb-bench-two-box-cover MESH [TREE] [K D TOP [T U]]\n");
    return 2;
  }
  vobb::LoadedMesh loaded;
  if (!vobb::bench::load_or_say(argv[1], &loaded)) return 2;
  const Mesh& mesh = loaded.mesh;
  // The counts are the last three or five arguments; a tree comes second where one more is given.
  const int counts = argc >= 7 ? 5 : argc >= 5 ? 3 : 0;
  const bool with_tree = argc - 2 - counts == 1;
  if (argc - 2 - counts != 0 && !with_tree) {
    std::fprintf(stderr, "usage: vobb-bench-two-box-cover MESH [TREE] [K D TOP [T U]]\n");
    return 2;
  }
  const int at = argc - counts;
  const int K = counts ? std::atoi(argv[at]) : 300;
  const int D = counts ? std::atoi(argv[at + 1]) : 200;
  const int top = counts ? std::atoi(argv[at + 2]) : 60;
  const int T = counts == 5 ? std::atoi(argv[at + 3]) : 0;
  const int U = counts == 5 ? std::atoi(argv[at + 4]) : 0;
  if (K < 1 || D < 1 || top < 1 || (counts == 5 && (T < 1 || U < 1))) {
    std::fprintf(stderr, "K, D, TOP, T and U must be positive\n");
    return 2;
  }
  const vobb::exact::FilteredSolver fs(mesh);
  const size_t n = mesh.faces.size();
  if (n < 2 * Search::S) {
    std::fprintf(stderr, "%s: %zu faces, fewer than %d to cut\n", argv[1], n, 2 * Search::S);
    return 2;
  }
  const Search search(mesh, fs, K, D);
  double tree_l1 = NAN, tree_l2 = NAN;
  if (with_tree) {
    vobb::Tree tree;
    if (!vobb::bench::read_tree_or_say(argv[2], mesh, &tree)) return 2;
    std::vector<int32_t> ids = vobb::layer(tree, 1);
    if (ids.size() != 2) {
      std::fprintf(stderr, "%s: level 1 has %zu boxes, not 2\n", argv[2], ids.size());
      return 2;
    }
    const auto& fa = tree.nodes[ids[0]].faces;
    const auto& fb = tree.nodes[ids[1]].faces;
    const auto [as_built_lo, as_built_hi] = omv(fs, tree.nodes[ids[0]].box, tree.nodes[ids[1]].box);
    const auto [lo, hi] = omv(fs, search.box(fa), search.box(fb));
    tree_l1 = 0.5 * (as_built_lo + as_built_hi);
    std::printf(
        "tree's level 1 (%zu + %zu faces): OMV %.6f as built, %.6f refitted (widths %.1e, %.1e)\n",
        fa.size(), fb.size(), tree_l1, 0.5 * (lo + hi), as_built_hi - as_built_lo, hi - lo);
    if (counts == 5) {
      const std::vector<int32_t> ids2 = vobb::layer(tree, 2);
      std::vector<Obb> boxes;
      std::vector<vobb::MpInterval> obv;
      for (int32_t id : ids2) {
        boxes.push_back(tree.nodes[id].box);
        obv.push_back(fs.obv(boxes.back()).value);
      }
      const auto [lo2, hi2] = omv(fs, boxes, obv);
      tree_l2 = 0.5 * (lo2 + hi2);
      std::printf(
          "tree's level 2 (%zu boxes): OMV %.6f as built (width %.1e); 8 OMV(1) + 7 OMV(2) = "
          "%.4f\n",
          ids2.size(), tree_l2, hi2 - lo2, 8 * tree_l1 + 7 * tree_l2);
    }
  }
  std::vector<int32_t> all(n);
  std::iota(all.begin(), all.end(), 0);
  double t_screen = 0;
  std::vector<Cover> level1 = search.splits(all, top, &t_screen);
  std::printf("screened %zu splits (%d directions, %d cuts, %d rotations) in %.1f s\n",
              static_cast<size_t>(D) * (Search::S - 1), D, Search::S - 1, K, t_screen);
  double best = INFINITY;
  for (const Cover& c : level1)
    if (c.mid() < best) {
      best = c.mid();
      std::printf("rank %d (direction %d, cut %d/%d, %zu + %zu faces): OMV %.6f (width %.1e)\n",
                  c.rank, c.dir, c.cut, Search::S, c.a.size(), c.b.size(), best, c.hi - c.lo);
    }
  std::printf("least level-1 OMV over the %d best screened splits: %.6f\n", top, best);
  if (counts != 5) return 0;

  // Level 2 under the T best level-1 splits.
  std::stable_sort(level1.begin(), level1.end(),
                   [](const Cover& a, const Cover& b) { return a.mid() < b.mid(); });
  double least_l2 = INFINITY, least_sum = INFINITY;
  for (int t = 0; t < std::min<int>(T, static_cast<int>(level1.size())); ++t) {
    const Cover& c = level1[t];
    std::vector<Cover> halves[2];
    double t_halves = 0;
    for (int h = 0; h < 2; ++h) {
      double ts = 0;
      halves[h] = search.splits(h == 0 ? c.a : c.b, top, &ts);
      t_halves += ts;
      if (halves[h].empty()) break;
      std::stable_sort(halves[h].begin(), halves[h].end(),
                       [](const Cover& x, const Cover& y) { return x.mid() < y.mid(); });
      halves[h].resize(std::min<size_t>(halves[h].size(), U));
    }
    if (halves[0].empty() || halves[1].empty()) {
      std::printf("level-1 split %d (rank %d): a half has fewer than %d faces to cut\n", t, c.rank,
                  2 * Search::S);
      continue;
    }
    // Each box's OBV once; then every pairing's four boxes.
    std::vector<vobb::MpInterval> obv[2];
    for (int h = 0; h < 2; ++h)
      for (const Cover& s : halves[h]) {
        obv[h].push_back(fs.obv(s.box_a).value);
        obv[h].push_back(fs.obv(s.box_b).value);
      }
    double l2 = INFINITY, width = 0;
    for (size_t i = 0; i < halves[0].size(); ++i)
      for (size_t j = 0; j < halves[1].size(); ++j) {
        const std::vector<Obb> boxes{halves[0][i].box_a, halves[0][i].box_b, halves[1][j].box_a,
                                     halves[1][j].box_b};
        const std::vector<vobb::MpInterval> v{obv[0][2 * i], obv[0][2 * i + 1], obv[1][2 * j],
                                              obv[1][2 * j + 1]};
        const auto [lo, hi] = omv(fs, boxes, v);
        if (0.5 * (lo + hi) < l2) l2 = 0.5 * (lo + hi), width = hi - lo;
      }
    least_l2 = std::min(least_l2, l2);
    least_sum = std::min(least_sum, 8 * c.mid() + 7 * l2);
    std::printf(
        "level-1 split %d (rank %d, OMV %.6f): least level-2 OMV %.6f (width %.1e) over %zu x %zu "
        "pairings (halves screened in %.1f s); 8 OMV(1) + 7 OMV(2) = %.4f\n",
        t, c.rank, c.mid(), l2, width, halves[0].size(), halves[1].size(), t_halves,
        8 * c.mid() + 7 * l2);
  }
  if (least_l2 == INFINITY) {
    std::printf("no level 2 searched\n");
    return 0;
  }
  std::printf("least level-2 OMV: %.6f; least 8 OMV(1) + 7 OMV(2): %.4f", least_l2, least_sum);
  if (with_tree) std::printf(" (the tree's: %.4f)", 8 * tree_l1 + 7 * tree_l2);
  std::printf("\n");
  return 0;
}
