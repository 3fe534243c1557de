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
// Usage: vobb-bench-two-box-cover MESH [TREE] [K D TOP]
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numeric>
#include <random>

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

// Descent on the rotation from R: small turns about each frame axis, halving the step when no
// turn lowers the tight volume.
Mat3 refine(const Mesh& mesh, const std::vector<int32_t>& faces, Mat3 R) {
  double best = tight_volume(mesh, faces, R);
  for (double step = 0.2; step > 1e-4; step *= 0.5)
    for (bool improved = true; improved;) {
      improved = false;
      for (int axis = 0; axis < 3; ++axis)
        for (double sign : {-1.0, 1.0}) {
          const Mat3 turned =
              Eigen::AngleAxisd(sign * step, Vec3::Unit(axis)).toRotationMatrix() * R;
          const double v = tight_volume(mesh, faces, turned);
          if (v < best) best = v, R = turned, improved = true;
        }
    }
  return R;
}

Obb fit(const Mesh& mesh, const std::vector<int32_t>& faces, const Mat3& R) {
  return vobb::fit_obb(mesh, faces, {Vec3(R.row(0)), Vec3(R.row(1)), Vec3(R.row(2))});
}

// The two boxes' OMV, enclosed: [lo, hi].
std::pair<double, double> omv(const vobb::exact::FilteredSolver& fs, const Obb& a, const Obb& b) {
  const std::vector<Obb> boxes{a, b};
  vobb::exact::MpInterval sum = fs.obv(a).value + fs.obv(b).value;
  sum -= fs.overlap_term(boxes, 1, {0}).value;
  return {sum.inf(), sum.sup()};
}

Vec3 direction(int d, int D) {  // the d-th of D points of a Fibonacci hemisphere
  const double golden = M_PI * (3 - std::sqrt(5.0));
  const double z = 1 - (d + 0.5) / D, r = std::sqrt(1 - z * z);
  return Vec3(r * std::cos(golden * d), r * std::sin(golden * d), z);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2 && argc != 3 && argc != 5 && argc != 6) {
    std::fprintf(stderr, "usage: vobb-bench-two-box-cover MESH [TREE] [K D TOP]\n");
    return 2;
  }
  vobb::LoadedMesh loaded;
  if (!vobb::bench::load_or_say(argv[1], &loaded)) return 2;
  const Mesh& mesh = loaded.mesh;
  const bool with_tree = argc == 3 || argc == 6;
  const int K = argc >= 5 ? std::atoi(argv[argc - 3]) : 300;
  const int D = argc >= 5 ? std::atoi(argv[argc - 2]) : 200;
  const int top = argc >= 5 ? std::atoi(argv[argc - 1]) : 60;
  constexpr int S = 64;
  if (K < 1 || D < 1 || top < 1) {
    std::fprintf(stderr, "K, D and TOP must be positive\n");
    return 2;
  }
  const vobb::exact::FilteredSolver fs(mesh);
  std::mt19937_64 rng(7);
  // Box-Muller on the generator's raw bits (whose sequence the standard fixes), so that every
  // standard library draws the same rotations; std::normal_distribution's algorithm is not
  // fixed.
  auto gauss = [&] {
    const double u1 = (static_cast<double>(rng() >> 11) + 1) * 0x1.0p-53,
                 u2 = static_cast<double>(rng() >> 11) * 0x1.0p-53;
    return std::sqrt(-2 * std::log(u1)) * std::cos(2 * M_PI * u2);
  };
  std::vector<Mat3> rotations;
  for (int k = 0; k < K; ++k) {
    Eigen::Quaterniond q;
    q.coeffs() << gauss(), gauss(), gauss(), gauss();
    rotations.push_back(q.normalized().toRotationMatrix());
  }
  auto best_rotation = [&](const std::vector<int32_t>& faces) {
    size_t best = 0;
    double v = INFINITY;
    for (size_t k = 0; k < rotations.size(); ++k) {
      const double w = tight_volume(mesh, faces, rotations[k]);
      if (w < v) v = w, best = k;
    }
    return refine(mesh, faces, rotations[best]);
  };
  if (with_tree) {
    vobb::Tree tree;
    if (!vobb::bench::read_tree_or_say(argv[2], &tree)) return 2;
    std::vector<int32_t> ids = vobb::layer(tree, 1);
    if (ids.size() != 2) {
      std::fprintf(stderr, "%s: level 1 has %zu boxes, not 2\n", argv[2], ids.size());
      return 2;
    }
    const auto& fa = tree.nodes[ids[0]].faces;
    const auto& fb = tree.nodes[ids[1]].faces;
    const auto [as_built_lo, as_built_hi] = omv(fs, tree.nodes[ids[0]].box, tree.nodes[ids[1]].box);
    const auto [lo, hi] =
        omv(fs, fit(mesh, fa, best_rotation(fa)), fit(mesh, fb, best_rotation(fb)));
    std::printf(
        "tree's level 1 (%zu + %zu faces): OMV %.6f as built, %.6f refitted (widths %.1e, %.1e)\n",
        fa.size(), fb.size(), 0.5 * (as_built_lo + as_built_hi), 0.5 * (lo + hi),
        as_built_hi - as_built_lo, hi - lo);
  }
  const size_t n = mesh.faces.size();
  if (n < 2 * S) {
    std::fprintf(stderr, "%s: %zu faces, fewer than %d to cut\n", argv[1], n, 2 * S);
    return 2;
  }
  std::vector<Vec3> centroid(n);
  for (size_t f = 0; f < n; ++f)
    centroid[f] = (mesh.corner(f, 0) + mesh.corner(f, 1) + mesh.corner(f, 2)) / 3;
  // Per rotation and face: the face's bounds in the rotated frame (lo xyz, hi xyz).
  std::vector<std::array<double, 6>> bounds(static_cast<size_t>(K) * n);
  for (int k = 0; k < K; ++k)
    for (size_t f = 0; f < n; ++f) {
      std::array<double, 6>& b = bounds[k * n + f];
      b = {INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY, -INFINITY};
      for (int c = 0; c < 3; ++c) {
        const Vec3 p = rotations[k] * mesh.corner(f, c);
        for (int i = 0; i < 3; ++i)
          b[i] = std::min(b[i], p[i]), b[3 + i] = std::max(b[3 + i], p[i]);
      }
    }
  auto sorted_along = [&](const Vec3& dir) {
    std::vector<int32_t> order(n);
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](int32_t a, int32_t b) {
      return centroid[a].dot(dir) < centroid[b].dot(dir);
    });
    return order;
  };
  struct Split {
    double screen;  // the two parts' least tight volumes over the rotations
    int dir, cut;
  };
  std::vector<int> cut_at(n + 1, -1);  // the cut that holds the faces [0, edge) of an order
  for (int c = 1; c < S; ++c) cut_at[n * c / S] = c;
  std::vector<Split> splits;
  const double t_screen = vobb::bench::seconds([&] {
    for (int d = 0; d < D; ++d) {
      const std::vector<int32_t> order = sorted_along(direction(d, D));
      std::vector<double> below(S, INFINITY), above(S, INFINITY);  // by cut c: faces < n c / S
      for (int k = 0; k < K; ++k) {
        // Prefix and suffix bounds, read at every cut.
        for (int pass = 0; pass < 2; ++pass) {
          std::array<double, 6> acc = {INFINITY,  INFINITY,  INFINITY,
                                       -INFINITY, -INFINITY, -INFINITY};
          for (size_t i = 0; i < n; ++i) {
            const size_t at = pass == 0 ? i : n - 1 - i;
            const auto& b = bounds[k * n + order[at]];
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
  std::printf("screened %zu splits (%d directions, %d cuts, %d rotations) in %.1f s\n",
              splits.size(), D, S - 1, K, t_screen);
  double best = INFINITY;
  for (int r = 0; r < std::min<int>(top, static_cast<int>(splits.size())); ++r) {
    const std::vector<int32_t> order = sorted_along(direction(splits[r].dir, D));
    const size_t cut = n * splits[r].cut / S;
    std::vector<int32_t> a(order.begin(), order.begin() + cut), b(order.begin() + cut, order.end());
    std::sort(a.begin(), a.end());
    std::sort(b.begin(), b.end());
    const auto [lo, hi] = omv(fs, fit(mesh, a, best_rotation(a)), fit(mesh, b, best_rotation(b)));
    if (0.5 * (lo + hi) < best) {
      best = 0.5 * (lo + hi);
      std::printf("rank %d (direction %d, cut %d/%d, %zu + %zu faces): OMV %.6f (width %.1e)\n", r,
                  splits[r].dir, splits[r].cut, S, a.size(), b.size(), best, hi - lo);
    }
  }
  std::printf("least level-1 OMV over the %d best screened splits: %.6f\n", top, best);
  return 0;
}
