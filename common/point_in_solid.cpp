#include "common/point_in_solid.h"

#include <cstddef>

#include "common/exact_predicates.h"
#include "common/status.h"

namespace vobb {
namespace {

// The ray from p + si eps e_i + sj eps^2 e_j (eps > 0 infinitesimal) along s e_k, (k, i, j) a
// cyclic order of the axes, s, si, sj = +-1: docs/derivations.md, "Locating a point".
struct AxisRay {
  Vec3 p;
  int k, i, j, s, si, sj;
};

constexpr int kRays = kLocateRays;

// Ray r of kRays: along +x, -x, +y, ..., each moved four ways; ray 0 runs along +x.
AxisRay axis_ray(const Vec3& p, int r) {
  const int k = r / 8;
  return {p, k, (k + 1) % 3, (k + 2) % 3, r & 4 ? -1 : 1, r & 1 ? -1 : 1, r & 2 ? -1 : 1};
}

// Whether the moved coordinate p + sign eps lies in [lo, hi].
bool moved_within(double lo, double p, double hi, int sign) {
  return sign > 0 ? lo <= p && p < hi : lo < p && p <= hi;
}

// Whether the ray meets the closed box b, exactly. Along its axis it needs a point of b
// strictly ahead of p, where every crossing lies (a face through p itself is found by
// on_triangle).
inline bool ray_meets(const AxisRay& r, const Aabb& b) {
  return moved_within(b.lo[r.i], r.p[r.i], b.hi[r.i], r.si) &&
         moved_within(b.lo[r.j], r.p[r.j], b.hi[r.j], r.sj) &&
         (r.s > 0 ? r.p[r.k] < b.hi[r.k] : b.lo[r.k] < r.p[r.k]);
}

// The side of the directed edge a -> b, projected on (i, j), where the moved start lies: the
// sign of orient2d(a, b, p + si eps e_i + sj eps^2 e_j), whose terms in eps and eps^2 are
// si (a_j - b_j) and sj (b_i - a_i). 0 only where a and b project to one point.
int moved_side(const Vec3& a, const Vec3& b, const AxisRay& r) {
  const int d = orient2d(a, b, r.p, r.i, r.j);
  if (d != 0) return d;
  if (a[r.j] != b[r.j]) return a[r.j] > b[r.j] ? r.si : -r.si;
  return b[r.i] > a[r.i] ? r.sj : b[r.i] < a[r.i] ? -r.sj : 0;
}

enum class Cross { kNo, kYes, kFromFace };

// Whether the ray crosses the triangle abc ahead of its start (kFromFace: p lies on it).
Cross crosses(const AxisRay& r, const Vec3& a, const Vec3& b, const Vec3& c) {
  const int t = orient2d(a, b, c, r.i, r.j);  // the sign of the normal's k component
  if (t == 0) return Cross::kNo;              // projects to a segment: the moved line misses it
  if (moved_side(a, b, r) != t || moved_side(b, c, r) != t || moved_side(c, a, r) != t)
    return Cross::kNo;
  const int o = orient3d(a, b, c, r.p);  // sign of n . (p - a)
  if (o == 0) return Cross::kFromFace;
  return o * r.s * t < 0 ? Cross::kYes : Cross::kNo;  // the plane lies ahead along s e_k
}

// Whether p lies on the closed triangle abc, exactly (false for a degenerate one).
bool on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  if (orient3d(a, b, c, p) != 0) return false;
  for (int k = 0; k < 3; ++k) {  // a projection in which abc has area
    const int i = (k + 1) % 3, j = (k + 2) % 3;
    const int t = orient2d(a, b, c, i, j);
    if (t == 0) continue;
    return orient2d(a, b, p, i, j) * t >= 0 && orient2d(b, c, p, i, j) * t >= 0 &&
           orient2d(c, a, p, i, j) * t >= 0;
  }
  return false;
}

// Calls visit(f) for each face f not left out whose box the ray meets (and, with find_surface,
// whose box holds r.p) until it returns false.
template <class Visit>
void walk(const AabbTree& faces, const AxisRay& r, bool find_surface,
          const std::function<bool(int32_t)>& left_out, const Visit& visit) {
  faces.visit_accepted_until(
      [&](const Aabb& b) { return ray_meets(r, b) || (find_surface && b.holds(r.p)); },
      [&](int32_t f) { return (left_out && left_out(f)) || visit(f); });
}

// The ray's faces (those not left out whose boxes it meets), counted up to `limit`.
size_t count_faces(const AabbTree& faces, const AxisRay& r,
                   const std::function<bool(int32_t)>& left_out, size_t limit) {
  size_t n = 0;
  if (limit > 0) walk(faces, r, false, left_out, [&](int32_t) { return ++n < limit; });
  return n;
}

// Casts the ray: where p lies.
void cast(const Mesh& mesh, const AabbTree& faces, const AxisRay& r, bool find_surface,
          const std::function<bool(int32_t)>& left_out, Location* out) {
  bool odd = false, on_surface = false;
  walk(faces, r, find_surface, left_out, [&](int32_t f) {
    const Vec3 &a = mesh.corner(f, 0), &b = mesh.corner(f, 1), &c = mesh.corner(f, 2);
    if (find_surface && faces.primitive_bounds(f).holds(r.p) && on_triangle(r.p, a, b, c)) {
      on_surface = true;
      return false;
    }
    if (!ray_meets(r, faces.primitive_bounds(f))) return true;
    switch (crosses(r, a, b, c)) {
      case Cross::kYes:
        odd = !odd;
        break;
      case Cross::kFromFace:
        on_surface = true;
        return false;
      case Cross::kNo:
        break;
    }
    return true;
  });
  *out = on_surface ? Location::kOnSurface : odd ? Location::kInside : Location::kOutside;
}

// Ray 0 is cast where it meets at most this many faces.
constexpr size_t kFirstLimit = 16;

Location locate(const Mesh& mesh, const AabbTree& faces, const Vec3& p, bool find_surface,
                const std::function<bool(int32_t)>& left_out) {
  // Counted first, so that no predicate is spent on a ray that is not cast.
  int best = count_faces(faces, axis_ray(p, 0), left_out, kFirstLimit + 1) <= kFirstLimit ? 0 : -1;
  // Rounds that count each ray's faces up to a cap doubled each round: once a ray's count ends
  // below the cap, the fewest is among those that ended, so a round costs at most kRays caps.
  // Ray 0, known to meet more than kFirstLimit, comes last.
  for (size_t cap = 2 * kFirstLimit; best < 0; cap *= 2) {
    size_t fewest = cap;
    for (int q = 1; q <= kRays && fewest > 0; ++q) {
      const int r = q % kRays;
      const size_t n = count_faces(faces, axis_ray(p, r), left_out, fewest);
      if (n < fewest) fewest = n, best = r;
    }
  }
  Location at = Location::kOnSurface;
  cast(mesh, faces, axis_ray(p, best), find_surface, left_out, &at);
  return at;
}

}  // namespace

Location locate_point_by_ray(const Mesh& mesh, const AabbTree& faces, const Vec3& p, int ray) {
  VOBB_ASSERT(ray >= 0 && ray < kRays, "locate_point_by_ray: a ray of kLocateRays");
  Location at = Location::kOnSurface;
  cast(mesh, faces, axis_ray(p, ray), true, nullptr, &at);
  return at;
}

Location locate_point(const Mesh& mesh, const AabbTree& faces, const Vec3& p) {
  return locate(mesh, faces, p, true, nullptr);
}

Location locate_point(const Mesh& mesh, const AabbTree& faces, const Vec3& p,
                      const std::function<bool(int32_t)>& left_out) {
  return locate(mesh, faces, p, true, left_out);
}

Location locate_point_off_surface(const Mesh& mesh, const AabbTree& faces, const Vec3& p,
                                  const std::function<bool(int32_t)>& left_out) {
  return locate(mesh, faces, p, false, left_out);
}

}  // namespace vobb
