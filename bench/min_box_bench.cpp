// How small can any box around the whole mesh be? A branch and bound over rotations proves a
// lower bound L on the volume of every box (orthonormal axes, DESIGN §1) that holds the mesh's
// vertices, so on every tree's root box: OMV(0) >= L - vol(X) for every tree, and the root's term
// in e is at least (D + 1)(L - vol(X)) at depth D. Cells of rotations are split best first until
// the least bound is within EPS of the least box volume found, or after MAXCELLS cells (a batch
// may pass it); the bounds are printed rounded down. Why each cell's bound holds, round-off
// included: docs/derivations.md, "A floor under every root box".
// Usage: vobb-bench-min-box MESH [TREE [EPS MAXCELLS]]
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <queue>
#include <string>
#include <vector>

#include "bench/bench_util.h"
#include "common/exact_predicates.h"
#include "common/obb.h"
#include "common/tree.h"

namespace {

using vobb::Vec3;

struct Cell {
  int face = 0;            // which quaternion coordinate is 1
  Eigen::Vector3d lo, hi;  // the cube in the other three coordinates
  double bound = 0;        // no rotation in the cell gives a smaller box volume
  double centre_volume = 0;
  bool operator<(const Cell& o) const { return bound > o.bound; }  // least bound on top
};

// q rounded toward minus infinity to `digits` decimals.
std::string down(const vobb::Rational& q, int digits = 6) {
  mpz_class scale = 1;
  for (int i = 0; i < digits; ++i) scale *= 10;
  mpz_class n;
  mpz_fdiv_q(n.get_mpz_t(), mpz_class(q.get_num() * scale).get_mpz_t(), q.get_den().get_mpz_t());
  const bool negative = n < 0;
  const std::string digits_of = mpz_class(abs(n)).get_str();
  std::string s =
      std::string(std::max(0, digits + 1 - static_cast<int>(digits_of.size())), '0') + digits_of;
  s.insert(s.size() - digits, ".");
  return (negative ? "-" : "") + s;
}

Eigen::Vector4d lift(int face, const Eigen::Vector3d& x) {
  Eigen::Vector4d q;
  for (int i = 0, j = 0; i < 4; ++i) q[i] = i == face ? 1.0 : x[j++];
  return q.normalized();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2 && argc != 3 && argc != 5) {
    std::fprintf(stderr, "usage: vobb-bench-min-box MESH [TREE [EPS MAXCELLS]]\n");
    return 2;
  }
  vobb::LoadedMesh loaded;
  if (!vobb::bench::load_or_say(argv[1], &loaded)) return 2;
  const vobb::Mesh& mesh = loaded.mesh;
  vobb::Tree tree;
  const bool with_tree = argc >= 3;
  if (with_tree && !vobb::bench::read_tree_or_say(argv[2], mesh, &tree)) return 2;
  const double eps = argc == 5 ? std::atof(argv[3]) : 1e-3;
  const long max_cells = argc == 5 ? std::atol(argv[4]) : 20000000;
  if (!(eps > 0 && eps < 1) || max_cells < 1) {
    std::fprintf(stderr, "need 0 < EPS < 1 and MAXCELLS >= 1\n");
    return 2;
  }
  std::vector<Vec3> p;
  {
    std::vector<char> used(mesh.vertices.size(), 0);
    for (const auto& f : mesh.faces)
      for (int k = 0; k < 3; ++k) used[f[k]] = 1;
    for (size_t i = 0; i < used.size(); ++i)
      if (used[i]) p.push_back(mesh.vertices[i]);
  }
  if (p.empty()) {
    std::fprintf(stderr, "%s: no faces\n", argv[1]);
    return 2;
  }
  Vec3 lo = p[0], hi = p[0];
  for (const Vec3& v : p) lo = lo.cwiseMin(v), hi = hi.cwiseMax(v);
  const Vec3 c = (lo + hi) / 2;
  double r = 0;
  for (const Vec3& v : p) r = std::max(r, (v - c).norm());
  // The projections are of the points as stored, so their round-off grows with |v| (about
  // 3e-16 |v| each): the slack covers it wherever the mesh lies.
  double far = 0;
  for (const Vec3& v : p) far = std::max(far, v.norm());
  const double slack = 1e-9 * (hi - lo).norm() + 1e-14 * far;
  r *= 1 + 1e-12;

  auto evaluate = [&](Cell* cell) {
    const Eigen::Vector3d mid = (cell->lo + cell->hi) / 2;
    const Eigen::Vector4d q0 = lift(cell->face, mid);
    // sin(a) from the largest chord d = |corner - centre| (a = 2 asin(d/2)): unlike 1 - cos^2,
    // it loses no digits when a is small.
    double d = 0;
    for (int corner = 0; corner < 8; ++corner) {
      Eigen::Vector3d x;
      for (int k = 0; k < 3; ++k) x[k] = (corner >> k & 1) ? cell->hi[k] : cell->lo[k];
      const Eigen::Vector4d q = lift(cell->face, x);
      // No cell straddles a coordinate 0 (6 cuts, then halvings), so <q, q0> > 0 and a < pi/2.
      d = std::max(d, (q - q0).norm());
    }
    const double sin_a =
        (d >= std::sqrt(2.0) ? 1.0 : d * std::sqrt(1 - d * d / 4)) * (1 + 1e-12) + 1e-15;
    const Eigen::Matrix3d R =
        Eigen::Quaterniond(q0[0], q0[1], q0[2], q0[3]).normalized().toRotationMatrix();
    double vol = 1, bound = 1;
    for (int k = 0; k < 3; ++k) {
      const Vec3 u = R.col(k);
      double a = u.dot(p[0]), b = a;
      for (const Vec3& v : p) {
        const double t = u.dot(v);
        a = std::min(a, t);
        b = std::max(b, t);
      }
      vol *= b - a;
      bound *= std::max(0.0, b - a - slack - 4 * r * sin_a);
    }
    cell->centre_volume = vol;
    cell->bound = bound;
  };

  std::priority_queue<Cell> open;
  double best = std::numeric_limits<double>::infinity();
  const int n0 = 6;  // each face cut in n0^3 cubes to start
  for (int face = 0; face < 4; ++face)
    for (int i = 0; i < n0 * n0 * n0; ++i) {
      Cell cell;
      cell.face = face;
      const int ijk[3] = {i % n0, i / n0 % n0, i / (n0 * n0)};
      for (int k = 0; k < 3; ++k) {
        cell.lo[k] = -1 + 2.0 * ijk[k] / n0;
        cell.hi[k] = -1 + 2.0 * (ijk[k] + 1) / n0;
      }
      evaluate(&cell);
      best = std::min(best, cell.centre_volume);
      open.push(cell);
    }
  long cells = 4L * n0 * n0 * n0;
  const double secs = vobb::bench::seconds([&] {
    // Up to 256 cells of least bound are split at once, their children evaluated in parallel.
    while (!open.empty() && cells < max_cells && open.top().bound < best * (1 - eps)) {
      std::vector<Cell> children;
      while (!open.empty() && children.size() < 2048 && open.top().bound < best * (1 - eps)) {
        const Cell top = open.top();
        open.pop();
        const Eigen::Vector3d mid = (top.lo + top.hi) / 2;
        for (int child = 0; child < 8; ++child) {
          Cell cell;
          cell.face = top.face;
          for (int k = 0; k < 3; ++k) {
            const bool upper = child >> k & 1;
            cell.lo[k] = upper ? mid[k] : top.lo[k];
            cell.hi[k] = upper ? top.hi[k] : mid[k];
          }
          children.push_back(cell);
        }
      }
      tbb::parallel_for(size_t(0), children.size(), [&](size_t i) { evaluate(&children[i]); });
      cells += static_cast<long>(children.size());
      for (const Cell& cell : children) best = std::min(best, cell.centre_volume);
      for (const Cell& cell : children)
        if (cell.bound < best) open.push(cell);
    }
  });
  // Every dropped cell's bound was at least the least volume found then, so no rotation in it
  // gives less than the least found now.
  const double least = open.empty() ? best : std::min(open.top().bound, best);
  // The bounds are printed rounded down, in rationals, so that each printed figure is proven.
  const vobb::Rational vol_x = vobb::exact_signed_volume(mesh);
  const vobb::Rational floor_omv = vobb::Rational(least) - vol_x;
  std::printf("vertices %zu, cells %ld in %.1f s, cells open %zu\n", p.size(), cells, secs,
              open.size());
  std::printf("every box holding the vertices has volume >= %s; least found %.6f (gap %.3f %%)\n",
              down(vobb::Rational(least)).c_str(), best, 100 * (best - least) / best);
  std::printf("vol(X) %.6f: every tree's OMV(0) >= %s\n", vobb::to_double_nearest(vol_x),
              down(floor_omv).c_str());
  if (with_tree) {
    double root = 0;
    for (const auto& nd : tree.nodes)
      if (nd.level == 0) root = vobb::volume(nd.box);
    const double omv = root - vobb::to_double_nearest(vol_x);
    std::printf(
        "the tree's root box %.6f (OMV %.6f), %.3f %% above the bound; at depth %d the root's "
        "term is >= %s for every tree, %.4f in this one\n",
        root, omv, 100 * (root - least) / least, tree.depth,
        down(vobb::Rational(tree.depth + 1) * floor_omv, 4).c_str(), (tree.depth + 1) * omv);
  }
  return 0;
}
