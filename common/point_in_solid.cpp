#include "common/point_in_solid.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "common/exact_predicates.h"
#include "common/status.h"

namespace vobb {
namespace {

enum class Hit { kNone, kProper, kDegenerate, kOnFace };

// Segment p -> q against the closed triangle abc, exactly.
Hit segment_vs_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c) {
  const int op = orient3d(a, b, c, p), oq = orient3d(a, b, c, q);
  if (op == 0) {
    // p in the triangle's plane: on the face if inside the triangle (coplanar 2D test).
    const Vec3 n = (b - a).cross(c - a);
    int i = 0, j = 1;
    if (std::abs(n[0]) >= std::abs(n[1]) && std::abs(n[0]) >= std::abs(n[2]))
      i = 1, j = 2;
    else if (std::abs(n[1]) >= std::abs(n[2]))
      i = 2, j = 0;
    const int s = orient2d(a, b, c, i, j);
    if (s == 0) {  // the double normal picked a degenerate projection: try the others
      for (int k = 0; k < 3 && s == 0; ++k) {
        i = k;
        j = (k + 1) % 3;
        if (orient2d(a, b, c, i, j) != 0) break;
      }
    }
    const int t = orient2d(a, b, c, i, j);
    const int e0 = orient2d(a, b, p, i, j) * t, e1 = orient2d(b, c, p, i, j) * t,
              e2 = orient2d(c, a, p, i, j) * t;
    if (e0 >= 0 && e1 >= 0 && e2 >= 0) return Hit::kOnFace;
    return oq == 0 ? Hit::kDegenerate : Hit::kNone;  // a segment in the plane: retry
  }
  if (oq == 0) return Hit::kDegenerate;  // the far point should not lie on a face's plane
  if (op == oq) return Hit::kNone;
  const int s1 = orient3d(p, q, a, b), s2 = orient3d(p, q, b, c), s3 = orient3d(p, q, c, a);
  if ((s1 > 0 && s2 > 0 && s3 > 0) || (s1 < 0 && s2 < 0 && s3 < 0)) return Hit::kProper;
  if ((s1 >= 0 && s2 >= 0 && s3 >= 0) || (s1 <= 0 && s2 <= 0 && s3 <= 0)) return Hit::kDegenerate;
  return Hit::kNone;
}

// Whether the segment p -> q may meet the closed box: conservative (true whenever it does).
// The box is widened by 2^-30 of the largest coordinate or extent involved, far above the few
// roundings of the slab parameters (each within a few u relative, i.e. a few u times that
// scale in position); the parameter interval is widened by 2^-30 too.
bool segment_may_meet(const Vec3& p, const Vec3& q, const Aabb& box) {
  const double scale = std::max({p.cwiseAbs().maxCoeff(), q.cwiseAbs().maxCoeff(),
                                 box.lo.cwiseAbs().maxCoeff(), box.hi.cwiseAbs().maxCoeff()});
  const double pad = 0x1p-30 * scale;
  double t0 = 0, t1 = 1;
  for (int k = 0; k < 3; ++k) {
    const double lo = box.lo[k] - pad, hi = box.hi[k] + pad, d = q[k] - p[k];
    if (d == 0) {  // parallel to the slab: inside it or not at all
      if (p[k] < lo || p[k] > hi) return false;
      continue;
    }
    double a = (lo - p[k]) / d, b = (hi - p[k]) / d;
    if (a > b) std::swap(a, b);
    t0 = std::max(t0, a);
    t1 = std::min(t1, b);
  }
  return !(t0 > t1 + 0x1p-30);  // NaN (an empty box) keeps the box
}

}  // namespace

Location locate_point(const Mesh& mesh, const AabbTree& faces, const Vec3& p) {
  return locate_point(mesh, faces, p, nullptr);
}

Location locate_point(const Mesh& mesh, const AabbTree& faces, const Vec3& p,
                      const std::function<bool(int32_t)>& left_out) {
  // The tree's root: no pass over the vertices per query.
  return locate_point(mesh, faces, p, left_out, faces.bounds());
}

Location locate_point(const Mesh& mesh, const AabbTree& faces, const Vec3& p,
                      const std::function<bool(int32_t)>& left_out, const Aabb& bb) {
  const double reach = 2.0 * (bb.hi - bb.lo).norm() + (p - 0.5 * (bb.lo + bb.hi)).norm() + 1.0;
  // Directions with irrational-looking ratios make edge and vertex hits rare; each retry
  // turns the direction deterministically.
  Vec3 dir(0.5773502691896258, 0.3437184391289216, 0.7404171463391124);
  for (int attempt = 0; attempt < 64; ++attempt) {
    const Vec3 q = p + reach * dir;
    int crossings = 0;
    bool degenerate = false, on_face = false;
    // Only faces whose box the segment may meet are tested: a face it misses cannot be
    // crossed or touched, and the parity over the others is the answer (any segment gives the
    // same exact answer; a plane merely containing q or the segment no longer forces a retry
    // when its face is far away). The segment's own bounding box would accept most of the
    // mesh for a long diagonal segment; the slab test accepts only the boxes along it.
    faces.for_each_accepted([&](const Aabb& box) { return segment_may_meet(p, q, box); },
                            [&](int32_t f) {
                              if (degenerate || on_face || (left_out && left_out(f))) return;
                              switch (segment_vs_triangle(p, q, mesh.corner(f, 0),
                                                          mesh.corner(f, 1), mesh.corner(f, 2))) {
                                case Hit::kProper:
                                  ++crossings;
                                  break;
                                case Hit::kDegenerate:
                                  degenerate = true;
                                  break;
                                case Hit::kOnFace:
                                  on_face = true;
                                  break;
                                case Hit::kNone:
                                  break;
                              }
                            });
    if (on_face) return Location::kOnSurface;
    if (!degenerate) return crossings % 2 ? Location::kInside : Location::kOutside;
    dir = Vec3(dir[1] + 0.1234567, dir[2] - 0.3141593, dir[0] + 0.2718282).normalized();
  }
  VOBB_ASSERT(false, "locate_point: every ray was degenerate");
  return Location::kOnSurface;
}

}  // namespace vobb
