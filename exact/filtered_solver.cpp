#include "exact/filtered_solver.h"

#include <CGAL/Interval_nt.h>

#include <algorithm>
#include <array>
#include <unordered_map>

#include "common/box_frame_clip.h"
#include "common/cell_clip.h"
#include "common/status.h"
#include "exact/convex_cell.h"

namespace vobb {

namespace exact {
namespace {

using Mp = MpInterval;
using Fast = CGAL::Interval_nt<false>;  // the prefilter's, under upward rounding (a Protector)

struct MpPlane {  // n . x <= d
  Mp n[3];
  Mp d;
};

// A half-space n . x <= d: always its double-interval enclosure (for the cheap decisions), and
// its MpInterval one, made at the first need.
class Plane {
 public:
  Fast n[3], d;

  static Plane from_mp(const MpPlane& h) {
    Plane p;
    for (int i = 0; i < 3; ++i) p.n[i] = Fast(h.n[i].inf(), h.n[i].sup());
    p.d = Fast(h.d.inf(), h.d.sup());
    p.mp_ = h;
    p.has_mp_ = true;
    return p;
  }
  // Side k of a face's prism: k < 3 the vertical plane through edge k, 3 below the face's
  // plane; `sign` is the sign of the face normal's z. Under upward rounding (a Protector).
  static Plane prism(const Vec3* corner[3], int k, int sign) {
    Plane p;
    p.corner_ = corner;
    p.k_ = k;
    p.sign_ = sign;
    p.coefficients<Fast>(p.n, &p.d);
    return p;
  }
  const MpPlane& mp() const {
    if (!has_mp_) {
      coefficients<Mp>(mp_.n, &mp_.d);
      has_mp_ = true;
    }
    return mp_;
  }
  Plane complement() const {  // n . x >= d, as (-n) . x <= -d
    Plane c;
    for (int i = 0; i < 3; ++i) c.n[i] = -n[i];
    c.d = -d;
    const MpPlane& h = mp();
    for (int i = 0; i < 3; ++i) c.mp_.n[i] = -h.n[i];
    c.mp_.d = -h.d;
    c.has_mp_ = true;
    return c;
  }

 private:
  // ClipSolver's prism planes, in NT.
  template <class NT>
  void coefficients(NT* nn, NT* dd) const {
    const Vec3 &a = *corner_[0], &b = *corner_[1], &c = *corner_[2];
    if (k_ < 3) {
      const Vec3& p = *corner_[k_];
      const Vec3& q = *corner_[(k_ + 1) % 3];
      nn[0] = NT(q[1]) - NT(p[1]);
      nn[1] = NT(p[0]) - NT(q[0]);
      nn[2] = NT(0);
      if (sign_ < 0) nn[0] = -nn[0], nn[1] = -nn[1];
      *dd = nn[0] * NT(p[0]) + nn[1] * NT(p[1]);
    } else {
      NT e1[3], e2[3];
      for (int i = 0; i < 3; ++i) e1[i] = NT(b[i]) - NT(a[i]), e2[i] = NT(c[i]) - NT(a[i]);
      const NT nrm[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                         e1[0] * e2[1] - e1[1] * e2[0]};
      for (int i = 0; i < 3; ++i) nn[i] = sign_ > 0 ? nrm[i] : NT(-nrm[i]);
      *dd = nn[0] * NT(a[0]) + nn[1] * NT(a[1]) + nn[2] * NT(a[2]);
    }
  }
  const Vec3* const* corner_ = nullptr;
  int k_ = 0, sign_ = 0;
  mutable MpPlane mp_;
  mutable bool has_mp_ = false;
};

// Where a cell's vertices lie relative to a plane: side -1, 0, +1 each, exactly; the
// MpInterval values of n . v - d where they were needed (has_value).
struct Sides {
  std::vector<int> side;
  std::vector<Mp> value;
  std::vector<char> has_value;
  bool any_pos = false, any_neg = false;
};

// The prism decomposition runs along whichever axis direction has the fewest faces in the
// cell's column (common/cell_clip.h: the same exact volume).
using cell_clip::column_of;
using cell_clip::to_direction;

// A bounded convex polyhedron with enclosed vertices: ConvexCell's clipping (exact/convex_cell.h)
// with every sign taken from the enclosures (double intervals first, then MpInterval; Undecided
// where both hold 0), so that its faces are the exact cell's and its vertices enclose the exact
// cell's.
class MpCell {
 public:
  static MpCell from_box(const box_clip::Frame<Mp>& f, int orientation) {
    MpCell cell;
    cell.v_.resize(8);
    cell.fv_.resize(8);
    for (int c = 0; c < 8; ++c) {
      for (int i = 0; i < 3; ++i) {
        Mp x = f.c[i];
        for (int k = 0; k < 3; ++k) x = ((c >> k) & 1) ? x + f.u[k][i] : x - f.u[k][i];
        cell.v_[c][i] = x;
      }
      cell.refresh(c);
    }
    for (const auto& q : kBoxQuads) {
      if (orientation > 0)
        cell.faces_.push_back({q[0], q[1], q[2], q[3]});
      else
        cell.faces_.push_back({q[3], q[2], q[1], q[0]});
    }
    return cell;
  }
  bool empty() const { return faces_.empty(); }

  // The cell under to_direction(d).
  MpCell mapped(int d) const {
    MpCell out;
    out.faces_ = faces_;
    out.v_.reserve(v_.size());
    out.fv_.resize(v_.size());
    for (size_t i = 0; i < v_.size(); ++i) {
      out.v_.push_back(to_direction(d, v_[i][0], v_[i][1], v_[i][2]));
      out.refresh(static_cast<int>(i));
    }
    return out;
  }

  void sides(const Plane& h, Sides* s) const {
    const size_t n = v_.size();
    s->side.assign(n, 2);  // 2: not decided yet
    s->value.resize(n);
    s->has_value.assign(n, 0);
    {
      Fast::Protector upward;
      for (size_t i = 0; i < n; ++i) {
        const Fast x = h.n[0] * fv_[i][0] + h.n[1] * fv_[i][1] + h.n[2] * fv_[i][2] - h.d;
        if (x.inf() > 0)
          s->side[i] = 1;
        else if (x.sup() < 0)
          s->side[i] = -1;
      }
    }
    s->any_pos = s->any_neg = false;
    for (size_t i = 0; i < n; ++i) {
      if (s->side[i] == 2) s->side[i] = value_at(h, s, static_cast<int>(i)).sign();  // may throw
      s->any_pos |= s->side[i] > 0;
      s->any_neg |= s->side[i] < 0;
    }
  }

  // The part in h (ConvexCell::clip, step for step), made without copying the cell first.
  MpCell clipped(const Plane& h) const {
    if (faces_.empty()) return MpCell();
    Sides s;
    sides(h, &s);
    return clipped_with(h, &s);
  }

  // The same, with the vertices' sides of h already known.
  MpCell clipped_with(const Plane& h, Sides* s) const {
    if (!s->any_pos) return *this;
    MpCell out;
    if (!s->any_neg) return out;  // nothing strictly inside: empty, or flat on the plane
    const int n = static_cast<int>(v_.size());
    std::vector<std::array<Mp, 3>> made;  // the cut points, ids n and upward
    std::vector<std::vector<int>> kept = clipped_faces(faces_, s->side, n, [&](int lo, int hi) {
      const Mp vl = value_at(h, s, lo), vh = value_at(h, s, hi);
      const Mp t = vl / (vl - vh);
      std::array<Mp, 3>& p = made.emplace_back();
      for (int i = 0; i < 3; ++i) p[i] = v_[lo][i] + t * (v_[hi][i] - v_[lo][i]);
      return n + static_cast<int>(made.size()) - 1;
    });
    if (kept.size() < 4) return out;  // cannot enclose volume
    const std::vector<int> old = compact_faces(&kept, n + made.size());
    out.v_.reserve(old.size());
    out.fv_.resize(old.size());
    for (size_t k = 0; k < old.size(); ++k) {
      out.v_.push_back(old[k] < n ? v_[old[k]] : made[old[k] - n]);
      out.refresh(static_cast<int>(k));
    }
    out.faces_ = std::move(kept);
    return out;
  }

  Mp volume() const { return cell_clip::cell_volume(v_, faces_); }

  Aabb bounds() const {
    Aabb b;
    for (const auto& p : fv_)
      for (int i = 0; i < 3; ++i) {
        b.lo[i] = std::min(b.lo[i], p[i].inf());
        b.hi[i] = std::max(b.hi[i], p[i].sup());
      }
    return b;
  }

 private:
  void refresh(int i) {
    for (int k = 0; k < 3; ++k) fv_[i][k] = Fast(v_[i][k].inf(), v_[i][k].sup());
  }
  const Mp& value_at(const Plane& h, Sides* s, int i) const {
    if (!s->has_value[i]) {
      const MpPlane& m = h.mp();
      s->value[i] = m.n[0] * v_[i][0] + m.n[1] * v_[i][1] + m.n[2] * v_[i][2] - m.d;
      s->has_value[i] = 1;
    }
    return s->value[i];
  }

  std::vector<std::array<Mp, 3>> v_;
  std::vector<std::array<Fast, 3>> fv_;  // double enclosures of v_
  std::vector<std::vector<int>> faces_;
};

// The six half-spaces of a box's certified solid (box_half_spaces, in Mp).
std::array<Plane, 6> box_planes(const box_clip::Frame<Mp>& f, int sigma) {
  const Mp abs_det = abs(f.det);
  std::array<Plane, 6> out;
  for (int k = 0; k < 3; ++k) {
    Mp wc = f.w[k][0] * f.c[0] + f.w[k][1] * f.c[1] + f.w[k][2] * f.c[2];
    if (sigma < 0) wc = -wc;
    MpPlane plus, minus;
    for (int i = 0; i < 3; ++i) {
      plus.n[i] = sigma > 0 ? f.w[k][i] : -f.w[k][i];
      minus.n[i] = -plus.n[i];
    }
    plus.d = abs_det + wc;
    minus.d = abs_det - wc;
    out[2 * k] = Plane::from_mp(plus);
    out[2 * k + 1] = Plane::from_mp(minus);
  }
  return out;
}

// The value `at` computes, in `bits` (MpInterval::kPrec or kMaxPrec); where a sign is
// undecided, in kMaxPrec (a sign within 1e-35 of 0 is decided there, an exact 0 is not); else
// `exact`'s rational.
template <class At, class Exact>
Enclosed in_tiers(mpfr_prec_t bits, bool collapse, At&& at, Exact&& exact) {
  Enclosed out;
  for (; bits <= MpInterval::kMaxPrec; bits *= 2) {
    try {
      const MpInterval::Precision precision(bits);
      const Mp v = at();
      out.value = collapse ? v.collapsed_for_tests() : v;
      out.bits = static_cast<int>(bits);
      return out;
    } catch (const Undecided&) {
    }
  }
  out.exact = true;
  out.q = exact();
  out.value = Mp(out.q);
  return out;
}

}  // namespace

FilteredSolver::FilteredSolver(const Mesh& mesh)
    : mesh_(mesh), faces_(AabbTree::over_faces(mesh)), clip_(mesh) {}

Enclosed FilteredSolver::obv(const Obb& box, mpfr_prec_t bits) const {
  // Relabelled so that its column meets few faces: the same solid, less work.
  const box_clip::Column column = box_clip::fewest_faces_column(box, mesh_, faces_);
  const Obb& labelled = column.box;
  if (column.flat) {
    Enclosed out;
    out.exact = true;  // no volume: 0, exactly
    return out;
  }
  return in_tiers(
      bits, collapse_,
      [&] {
        const box_clip::Frame<Mp> frame = box_clip::make_frame<Mp>(labelled);
        const Mp R = abs(frame.det);
        if (R.sign() == 0) return Mp(0);  // no volume
        Mp sum(0);
        std::unordered_map<int32_t, box_clip::Point<Mp>> tmap;  // faces share vertices
        auto to_t = [&](int32_t v) -> const box_clip::Point<Mp>& {
          auto it = tmap.find(v);
          if (it != tmap.end()) return it->second;
          return tmap.emplace(v, box_clip::to_frame(frame, mesh_.vertices[v])).first->second;
        };
        for (const int32_t f : column.faces) {
          const Face& face = mesh_.faces[f];
          const box_clip::Point<Mp> tri[3] = {to_t(face[0]), to_t(face[1]), to_t(face[2])};
          Mp term;
          if (box_clip::face_term6(tri, R, &term)) sum += term;
        }
        return box_clip::obv_from_sum6(sum, R);
      },
      [&] { return clip_.obv(box); });
}

Enclosed FilteredSolver::overlap_term(const std::vector<Obb>& boxes, size_t j,
                                      const std::vector<int32_t>& earlier, mpfr_prec_t bits) const {
  if (earlier.empty()) return Enclosed();  // [0, 0]: nothing earlier can meet box j
  return in_tiers(
      bits, collapse_,
      [&] {
        const box_clip::Frame<Mp> fj = box_clip::make_frame<Mp>(boxes[j]);
        const int orientation = fj.det.sign();
        if (orientation == 0) return Mp(0);  // a flat box: nothing inside it
        // Split box j against each earlier box: `pieces` is what none covers so far; each piece's
        // part inside box i is a cell of S_j (ClipSolver::shared_cells, step for step).
        std::vector<MpCell> shared, pieces{MpCell::from_box(fj, orientation)};
        Sides sides;
        for (int32_t i : earlier) {
          const box_clip::Frame<Mp> fi = box_clip::make_frame<Mp>(boxes[i]);
          const int sigma = fi.det.sign();
          if (sigma == 0) continue;
          const std::array<Plane, 6> hs = box_planes(fi, sigma);
          std::vector<MpCell> next;
          for (MpCell& p : pieces) {
            MpCell rest = std::move(p);
            for (const Plane& h : hs) {
              rest.sides(h, &sides);
              if (!sides.any_pos) continue;  // nothing of `rest` lies beyond this face
              if (!sides.any_neg) {          // all of it beyond or on the plane: it stays whole
                next.push_back(std::move(rest));
                rest = MpCell();
                break;
              }
              MpCell beyond = rest.clipped(h.complement());
              if (!beyond.empty()) next.push_back(std::move(beyond));
              rest = rest.clipped_with(h, &sides);
              if (rest.empty()) break;
            }
            if (!rest.empty()) shared.push_back(std::move(rest));
          }
          pieces = std::move(next);
          if (pieces.empty()) break;
        }
        Mp total(0);
        for (const MpCell& cell_xyz : shared) {
          const Mp vol = cell_xyz.volume();
          // vol(cell ∩ X) = sum over faces of sign * vol(cell ∩ prism), ClipSolver::inside_volume,
          // along the direction whose column holds the fewest faces.
          const Aabb bounds = cell_xyz.bounds();
          int dir = 0;
          size_t fewest = SIZE_MAX;
          for (int d = 0; d < 6; ++d) {
            size_t n = 0;
            const Aabb column = column_of(bounds, d);
            faces_.visit_accepted([&](const Aabb& b) { return column.overlaps(b); },
                                  [&](int32_t) { ++n; });
            if (n < fewest) fewest = n, dir = d;
          }
          const MpCell cell = cell_xyz.mapped(dir);
          Mp inside(0);
          long whole = 0;
          const Aabb column = column_of(bounds, dir);
          faces_.visit_accepted([&](const Aabb& b) { return column.overlaps(b); },
                                [&](int32_t f) {
                                  Vec3 mapped[3];
                                  for (int k = 0; k < 3; ++k) {
                                    const Vec3& p = mesh_.corner(f, k);
                                    const std::array<double, 3> q =
                                        to_direction(dir, p[0], p[1], p[2]);
                                    mapped[k] = Vec3(q[0], q[1], q[2]);
                                  }
                                  const Vec3 &a = mapped[0], &b = mapped[1], &c = mapped[2];
                                  const int sign = orient2d(
                                      a, b, c, 0, 1);  // the sign of the face normal's z, exactly
                                  if (sign == 0) return;  // a vertical face bounds no column
                                  const Vec3* corner[3] = {&a, &b, &c};
                                  // The prism's 4 half-spaces (3 vertical sides, then below the
                                  // face): which miss the cell, which hold it, which cut it; the
                                  // double intervals decide most of it.
                                  Plane h[4];
                                  {
                                    Fast::Protector upward;
                                    for (int k = 0; k < 4; ++k)
                                      h[k] = Plane::prism(corner, k, sign);
                                  }
                                  const Plane* cutting[4];
                                  int n_cutting = 0;
                                  for (int k = 0; k < 4; ++k) {
                                    cell.sides(h[k], &sides);
                                    if (!sides.any_neg)
                                      return;  // beyond or on the plane: the prism adds no volume
                                    if (sides.any_pos) cutting[n_cutting++] = &h[k];
                                  }
                                  if (n_cutting == 0) {
                                    whole += sign;
                                    return;
                                  }
                                  MpCell piece = cell.clipped(*cutting[0]);
                                  for (int k = 1; k < n_cutting && !piece.empty(); ++k)
                                    piece = piece.clipped(*cutting[k]);
                                  if (piece.empty()) return;
                                  inside += sign > 0 ? piece.volume() : -piece.volume();
                                });
          if (whole != 0) inside += Mp(static_cast<double>(whole)) * vol;
          total += vol - inside;
        }
        return total;
      },
      [&] { return clip_.overlap_term(boxes, j, earlier); });
}

}  // namespace exact
}  // namespace vobb
