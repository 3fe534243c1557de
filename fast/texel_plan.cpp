#include "fast/texel_plan.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>

#include "common/status.h"

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

// Sutherland-Hodgman: keep the part of a convex polygon where plane(p) >= 0.
template <class Plane>
int clip(const Vec3* in, int n, Vec3* out, const Plane& plane) {
  int k = 0;
  for (int a = 0; a < n; ++a) {
    const Vec3& p = in[a];
    const Vec3& q = in[(a + 1) % n];
    const double fp = plane(p), fq = plane(q);
    if (fp >= 0) out[k++] = p;
    if ((fp >= 0) != (fq >= 0)) out[k++] = p + (fp / (fp - fq)) * (q - p);
    VOBB_ASSERT(k <= 16, "clipped polygon fits its buffer");
  }
  return k;
}

// The texels of cubemap face `face` whose rays may meet triangle t (within the cube unless
// no_far_clip): t is clipped to the face's cone {zeta >= |u|, zeta >= |v|} (and zeta <= 1), and
// the texels whose centres lie in the projected clipped polygon's bounds form the span.
// A clipped vertex too close to the centre to project reliably gives the whole face.
bool texel_span(const LocalTriangle& t, int face, int m, bool no_far_clip, TexelSpan* span) {
  const int k = face / 2, a = (k + 1) % 3, b = (k + 2) % 3;
  const double s = face % 2 == 0 ? 1.0 : -1.0;
  Vec3 buf0[16], buf1[16];  // a convex polygon gains at most one vertex per plane: 3 + 5 <= 16
  for (int c = 0; c < 3; ++c) buf0[c] = Vec3(s * t.p[c][k], t.p[c][a], t.p[c][b]);  // (zeta, u, v)
  int n = 3;
  n = clip(buf0, n, buf1, [](const Vec3& p) { return p[0] - p[1]; });
  n = clip(buf1, n, buf0, [](const Vec3& p) { return p[0] + p[1]; });
  n = clip(buf0, n, buf1, [](const Vec3& p) { return p[0] - p[2]; });
  n = clip(buf1, n, buf0, [](const Vec3& p) { return p[0] + p[2]; });
  if (!no_far_clip) n = clip(buf0, n, buf1, [](const Vec3& p) { return 1 - p[0]; });
  const Vec3* poly = no_far_clip ? buf0 : buf1;
  if (n == 0) return false;
  double scale = 1;
  for (int c = 0; c < 3; ++c) scale = std::max(scale, t.p[c].cwiseAbs().maxCoeff());
  // Interpolated coordinates carry absolute errors of a few eps * scale; a vertex with
  // zeta > 1e-6 scale projects with relative error < 1e-9, far inside the one-texel margin.
  double ulo = 1, uhi = -1, vlo = 1, vhi = -1;
  bool whole = false;
  for (int c = 0; c < n; ++c) {
    const double zeta = poly[c][0];
    if (!(zeta > 1e-6 * scale)) {
      whole = true;
      break;
    }
    const double u = std::clamp(poly[c][1] / zeta, -1.0, 1.0), v = std::clamp(poly[c][2] / zeta, -1.0, 1.0);
    ulo = std::min(ulo, u);
    uhi = std::max(uhi, u);
    vlo = std::min(vlo, v);
    vhi = std::max(vhi, v);
  }
  span->face = face;
  if (whole) {
    span->i0 = span->j0 = span->ci0 = span->cj0 = 0;
    span->i1 = span->j1 = span->ci1 = span->cj1 = m - 1;
    return true;
  }
  constexpr double kDelta = 1e-8;  // see below
  // Cells: texel i covers u in [-1 + 2i/m, -1 + 2(i+1)/m]; widened by delta like the centres.
  auto cell = [&](double x) { return std::clamp(static_cast<int>(std::floor((x + 1) * m / 2)), 0, m - 1); };
  span->ci0 = cell(ulo - kDelta);
  span->ci1 = cell(uhi + kDelta);
  span->cj0 = cell(vlo - kDelta);
  span->cj1 = cell(vhi + kDelta);
  // Texel i's centre is -1 + (2i + 1) / m; keep the centres within [lo - delta, hi + delta].
  // A texel ray that hits the face inside the cone passes through the clipped polygon, so its
  // (u, v) lies in the projected bounds up to the projection's relative error, below 1e-9
  // (above): delta = 1e-8 keeps every such texel. A face that covers no texel centre gets none.
  auto lo = [&](double x) { return std::max(0, static_cast<int>(std::ceil(((x - kDelta + 1) * m - 1) / 2))); };
  auto hi = [&](double x) { return std::min(m - 1, static_cast<int>(std::floor(((x + kDelta + 1) * m - 1) / 2))); };
  span->i0 = lo(ulo);
  span->i1 = hi(uhi);
  span->j0 = lo(vlo);
  span->j1 = hi(vhi);
  if (span->i0 > span->i1 || span->j0 > span->j1) span->i0 = 1, span->i1 = 0;  // no centre: draw nothing
  return true;
}

}  // namespace

double resolution_bound(const BoxPlan& plan, int m) {
  if (plan.flat || plan.spans.empty()) return 0.0;
  std::vector<char> touched(6 * static_cast<size_t>(m) * m, 0);
  size_t count = 0;
  for (const TexelSpan& s : plan.spans)
    for (int i = s.ci0; i <= s.ci1; ++i)
      for (int j = s.cj0; j <= s.cj1; ++j) {
        char& t = touched[(static_cast<size_t>(s.face) * m + i) * m + j];
        count += t == 0;
        t = 1;
      }
  return plan.frame.volume_scale * 4.0 / (3.0 * m * m) * static_cast<double>(count);
}

BoxPlanner::BoxPlanner(const Mesh& mesh) : mesh_(mesh), faces_(AabbTree::over_faces(mesh)) {}

BoxPlan BoxPlanner::plan(const Obb& box, int m) const {
  VOBB_ASSERT(m >= 1, "cubemap resolution m >= 1");
  BoxPlan plan;
  if (volume(box) == 0.0) {
    plan.flat = true;
    return plan;
  }
  plan.frame = box_frame(box);
  plan.where = locate_point(mesh_, faces_, box.center);
  plan.far_count = plan.where == Location::kOnSurface;
  plan.constant = plan.far_count || plan.where == Location::kOutside ? 8.0 : 0.0;

  // Without culling, spans also cover the faces' parts beyond the box, as a renderer that
  // draws the whole mesh per cubemap face would.
  const bool no_far_clip = plan.far_count || !culling_;
  constexpr double kCullMargin = 1e-9;  // local units; culling only needs to be conservative
  auto consider = [&](int32_t f) {
    LocalTriangle t;
    for (int k = 0; k < 3; ++k) {
      t.id[k] = mesh_.faces[f][k];
      t.p[k] = plan.frame.local(mesh_.vertices[t.id[k]]);
    }
    if (!plan.far_count && culling_) {
      for (int axis = 0; axis < 3; ++axis) {
        const double lo = std::min({t.p[0][axis], t.p[1][axis], t.p[2][axis]});
        const double hi = std::max({t.p[0][axis], t.p[1][axis], t.p[2][axis]});
        if (lo > 1 + kCullMargin || hi < -1 - kCullMargin) return;  // misses the cube
      }
    }
    for (int k = 0; k < 3; ++k) {
      const int a = k, b = (k + 1) % 3;
      t.edge_cross[k] = t.id[a] < t.id[b] ? Vec3(t.p[a].cross(t.p[b])) : Vec3(-t.p[b].cross(t.p[a]));
    }
    t.normal = (t.p[1] - t.p[0]).cross(t.p[2] - t.p[0]);
    if (plan.frame.mirrored) t.normal = -t.normal;
    t.plane = t.normal.dot(t.p[0]);
    const int32_t index = static_cast<int32_t>(plan.tris.size());
    bool used = false;
    for (int face = 0; face < 6; ++face) {
      TexelSpan span;
      if (!texel_span(t, face, m, no_far_clip, &span)) continue;
      span.tri = index;
      plan.spans.push_back(span);
      used = true;
    }
    if (used) plan.tris.push_back(t);
  };
  if (plan.far_count || !culling_) {
    for (size_t f = 0; f < mesh_.faces.size(); ++f) consider(static_cast<int32_t>(f));
  } else {
    Aabb world;
    for (const Vec3& c : corners(box)) world.extend(c);
    const Vec3 pad = Vec3::Constant(1e-9 * (world.hi - world.lo).norm());
    world.lo -= pad;
    world.hi += pad;
    // Faces in mesh order, as without culling: the same plan, the same float blend order.
    std::vector<int32_t> ids;
    faces_.for_each_overlap(world, [&](int32_t f) { ids.push_back(f); });
    std::sort(ids.begin(), ids.end());
    for (int32_t f : ids) consider(f);
  }
  return plan;
}

}  // namespace vobb
