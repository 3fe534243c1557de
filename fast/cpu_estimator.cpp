#include "fast/cpu_estimator.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>

#include "common/point_in_solid.h"
#include "common/status.h"
#include "fast/cubemap.h"

namespace vobb {

BoxFrame box_frame(const Obb& box) {
  Eigen::Matrix3d m;
  for (int k = 0; k < 3; ++k) m.col(k) = box.half[k] * box.axes[k];
  const double det = m.determinant();
  VOBB_ASSERT(det != 0 && std::isfinite(det), "box_frame of a flat box");
  BoxFrame f;
  f.to_local = m.inverse();
  f.center = box.center;
  f.volume_scale = std::abs(det);
  f.mirrored = det < 0;
  return f;
}

namespace {

// A face in box-normalized coordinates, ready for texel rays from the origin.
struct LocalTriangle {
  Vec3 p[3];
  int32_t id[3];       // mesh vertex ids: the tie rule on shared edges
  Vec3 edge_cross[3];  // for edge k (p[k] -> p[k+1]): P x Q in canonical (lower id first) order
  bool edge_flip[3];   // the canonical order is q -> p: negate
  Vec3 normal;         // (p1 - p0) x (p2 - p0), outward for a solid (mirror-corrected)
  double plane;        // normal . p0
};

// Sign of d . (P x Q) for the edge, with exact zeros broken by vertex ids: the two faces
// sharing an edge run it in opposite directions, so exactly one of them claims the ray.
inline int edge_side(const LocalTriangle& t, int k, const Vec3& d) {
  const double e = d.dot(t.edge_cross[k]);
  const double s = t.edge_flip[k] ? -e : e;
  if (s > 0) return 1;
  if (s < 0) return -1;
  return t.id[k] < t.id[(k + 1) % 3] ? 1 : -1;
}

}  // namespace

CpuObvEstimator::CpuObvEstimator(const Mesh& mesh) : mesh_(mesh), faces_(AabbTree::over_faces(mesh)) {}

std::vector<double> CpuObvEstimator::estimate(const std::vector<Obb>& boxes, int m) const {
  std::vector<double> out;
  out.reserve(boxes.size());
  size_t used = 0;
  for (const Obb& b : boxes) {
    out.push_back(estimate(b, m));
    used += faces_used_;
  }
  faces_used_ = used;
  return out;
}

double CpuObvEstimator::estimate(const Obb& box, int m) const {
  VOBB_ASSERT(m >= 1, "cubemap resolution m >= 1");
  faces_used_ = 0;
  if (volume(box) == 0.0) return 0.0;
  const BoxFrame frame = box_frame(box);
  const Location where = locate_point(mesh_, faces_, box.center);
  const bool far_count = where == Location::kOnSurface;  // see cpu_estimator.h

  std::vector<LocalTriangle> tris;
  constexpr double kCullMargin = 1e-9;  // local units; culling only needs to be conservative
  auto consider = [&](int32_t f) {
    LocalTriangle t;
    for (int k = 0; k < 3; ++k) {
      t.id[k] = mesh_.faces[f][k];
      t.p[k] = frame.local(mesh_.vertices[t.id[k]]);
    }
    if (!far_count && culling_) {
      for (int axis = 0; axis < 3; ++axis) {
        const double lo = std::min({t.p[0][axis], t.p[1][axis], t.p[2][axis]});
        const double hi = std::max({t.p[0][axis], t.p[1][axis], t.p[2][axis]});
        if (lo > 1 + kCullMargin || hi < -1 - kCullMargin) return;  // misses the cube
      }
    }
    for (int k = 0; k < 3; ++k) {
      const int a = k, b = (k + 1) % 3;
      t.edge_flip[k] = t.id[a] > t.id[b];
      t.edge_cross[k] = t.edge_flip[k] ? t.p[b].cross(t.p[a]) : t.p[a].cross(t.p[b]);
    }
    t.normal = (t.p[1] - t.p[0]).cross(t.p[2] - t.p[0]);
    if (frame.mirrored) t.normal = -t.normal;
    t.plane = t.normal.dot(t.p[0]);
    tris.push_back(t);
  };
  if (far_count || !culling_) {
    for (size_t f = 0; f < mesh_.faces.size(); ++f) consider(static_cast<int32_t>(f));
  } else {
    Aabb world;
    for (const Vec3& c : corners(box)) world.extend(c);
    const Vec3 pad = Vec3::Constant(1e-9 * (world.hi - world.lo).norm());
    world.lo -= pad;
    world.hi += pad;
    faces_.for_each_overlap(world, consider);
  }
  faces_used_ = tris.size();

  // Normal mode: sum over crossings of s (1 - zeta^3). Far-count mode: per texel.
  double crossing_sum = 0.0;
  std::vector<double> inside, beyond;
  if (far_count) {
    inside.assign(6 * static_cast<size_t>(m) * m, 0.0);
    beyond.assign(inside.size(), 0.0);
  }
  const double half_m = 0.5 * m;
  for (int face = 0; face < 6; ++face) {
    const int k = face / 2;
    const double s = face % 2 == 0 ? 1.0 : -1.0;
    for (const LocalTriangle& t : tris) {
      // Texels the face's projection may cover: the rectangle of the projected corners
      // when all lie in front, else the whole face. One texel of slack on each side.
      int i0 = 0, i1 = m - 1, j0 = 0, j1 = m - 1;
      double z[3];
      bool all_front = true, all_behind = true;
      for (int c = 0; c < 3; ++c) {
        z[c] = s * t.p[c][k];
        all_front &= z[c] > 0;
        all_behind &= z[c] <= 0;
      }
      if (all_behind) continue;
      if (all_front) {
        double ulo = INFINITY, uhi = -INFINITY, vlo = INFINITY, vhi = -INFINITY;
        for (int c = 0; c < 3; ++c) {
          const double u = t.p[c][(k + 1) % 3] / z[c], v = t.p[c][(k + 2) % 3] / z[c];
          ulo = std::min(ulo, u);
          uhi = std::max(uhi, u);
          vlo = std::min(vlo, v);
          vhi = std::max(vhi, v);
        }
        if (ulo > 1 || uhi < -1 || vlo > 1 || vhi < -1) continue;
        // Clamp in double first: a face close to the centre projects far outside [-1, 1].
        auto texel_lo = [&](double x) {
          return static_cast<int>(std::max(0.0, std::floor((std::max(x, -1.0) + 1) * half_m) - 1));
        };
        auto texel_hi = [&](double x) {
          return static_cast<int>(std::min(m - 1.0, std::ceil((std::min(x, 1.0) + 1) * half_m) + 1));
        };
        i0 = texel_lo(ulo);
        i1 = texel_hi(uhi);
        j0 = texel_lo(vlo);
        j1 = texel_hi(vhi);
      }
      for (int i = i0; i <= i1; ++i) {
        const double u = texel_center(i, m);
        for (int j = j0; j <= j1; ++j) {
          const Vec3 d = cubemap_direction(face, u, texel_center(j, m));
          const int e0 = edge_side(t, 0, d);
          if (edge_side(t, 1, d) != e0 || edge_side(t, 2, d) != e0) continue;
          const double nd = t.normal.dot(d);
          if (nd == 0) continue;  // the ray runs in the face's plane
          const double zeta = t.plane / nd;
          if (!(zeta > 0)) continue;  // behind the centre (or at it)
          const double sign = nd > 0 ? 1.0 : -1.0;
          if (!far_count) {
            if (zeta < 1) crossing_sum += sign * (1 - zeta * zeta * zeta);
          } else {
            const size_t texel = (static_cast<size_t>(face) * m + i) * m + j;
            if (zeta < 1) inside[texel] += sign * zeta * zeta * zeta;
            else beyond[texel] += sign;
          }
        }
      }
    }
  }
  const double texel_weight = 4.0 / (3.0 * m * m);
  double local_obv;
  if (!far_count) {
    const double inside_centre = where == Location::kInside ? 1.0 : 0.0;
    local_obv = 8.0 * (1.0 - inside_centre) + texel_weight * crossing_sum;
  } else {
    double sum = 0.0;
    for (size_t texel = 0; texel < inside.size(); ++texel) sum += 1.0 - beyond[texel] - inside[texel];
    local_obv = texel_weight * sum;
  }
  return frame.volume_scale * local_obv;
}

}  // namespace vobb
