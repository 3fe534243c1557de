#include <limits>
#include <memory>
#include <mutex>

#include "common/box_frame_clip.h"
#include "exact/convex_cell.h"
#include "exact/outer_volume.h"

namespace vobb::exact {

struct ClipSolver::Prism {
  int sign = 0;                // sign of the face normal's z: +1 the solid lies below, -1 above
  std::array<HalfSpace, 4> h;  // three vertical sides, then "below the face's plane"
};

namespace {

Rational dot(const Rational* n, const Vec3& p) {
  return n[0] * Rational(p[0]) + n[1] * Rational(p[1]) + n[2] * Rational(p[2]);
}

}  // namespace

ClipSolver::ClipSolver(const Mesh& mesh)
    : mesh_(mesh),
      faces_(AabbTree::over_faces(mesh)),
      prisms_(mesh.faces.size()),
      made_(std::make_unique<std::once_flag[]>(mesh.faces.size())) {}

const ClipSolver::Prism& ClipSolver::prism(int32_t f) const {
  std::call_once(made_[f], [&] { prisms_[f] = std::make_unique<Prism>(make_prism(f)); });
  return *prisms_[f];
}

ClipSolver::Prism ClipSolver::make_prism(int32_t f) const {
  Prism P;
  const Vec3 &a = mesh_.corner(f, 0), &b = mesh_.corner(f, 1), &c = mesh_.corner(f, 2);
  Rational e1[3], e2[3], nrm[3];
  for (int i = 0; i < 3; ++i) {
    e1[i] = Rational(b[i]) - Rational(a[i]);
    e2[i] = Rational(c[i]) - Rational(a[i]);
  }
  nrm[0] = e1[1] * e2[2] - e1[2] * e2[1];
  nrm[1] = e1[2] * e2[0] - e1[0] * e2[2];
  nrm[2] = e1[0] * e2[1] - e1[1] * e2[0];
  P.sign = sgn(nrm[2]);
  if (P.sign == 0) return P;  // a vertical face bounds no column
  const Vec3* corner[3] = {&a, &b, &c};
  for (int k = 0; k < 3; ++k) {
    const Vec3& p = *corner[k];
    const Vec3& q = *corner[(k + 1) % 3];
    // Vertical plane through edge pq, normal (q - p) x z; the shadow's inside is on the left
    // of pq when the projection runs counter-clockwise (sign +1), on the right otherwise.
    HalfSpace& h = P.h[k];
    h.n[0] = Rational(q[1]) - Rational(p[1]);
    h.n[1] = Rational(p[0]) - Rational(q[0]);
    h.n[2] = 0;
    if (P.sign < 0) {
      h.n[0] = -h.n[0];
      h.n[1] = -h.n[1];
    }
    h.d = dot(h.n, p);
  }
  // Below the face: moving along -z decreases sign * n . x.
  HalfSpace& below = P.h[3];
  for (int i = 0; i < 3; ++i) below.n[i] = P.sign > 0 ? nrm[i] : Rational(-nrm[i]);
  below.d = dot(below.n, a);
  for (HalfSpace& h : P.h) h.set_shadow();
  return P;
}

ClipSolver::~ClipSolver() = default;

Rational ClipSolver::obv(const Obb& box) const {
  return box_clip::box_obv_rational(mesh_, faces_, box);
}

Rational ClipSolver::inside_volume(const ConvexCell& cell) const {
  if (cell.empty()) return Rational(0);
  Aabb column = cell.bounds();
  column.hi[2] = std::numeric_limits<double>::infinity();  // faces above the cell count too
  std::vector<Rational> terms;
  long whole = 0;  // signed count of prisms that contain the whole cell
  faces_.for_each_overlap(column, [&](int32_t f) {
    const Prism& P = prism(f);
    if (P.sign == 0) return;
    // The filter settles most faces: a prism that surely misses the cell adds nothing, one
    // that surely contains it adds the cell's volume; only the rest are clipped exactly.
    const HalfSpace* cutting[4];
    int n_cutting = 0;
    for (const HalfSpace& h : P.h) {
      const Side side = cell.classify(h);
      if (side == Side::kOutside) return;
      if (side == Side::kCrossing) cutting[n_cutting++] = &h;
    }
    if (n_cutting == 0) {
      whole += P.sign;
      return;
    }
    ConvexCell piece = cell;
    for (int i = 0; i < n_cutting; ++i) {
      piece.clip(*cutting[i]);
      if (piece.empty()) return;
    }
    Rational v = piece.volume();
    if (P.sign < 0) v = -v;
    terms.push_back(std::move(v));
  });
  if (whole != 0) terms.push_back(Rational(whole) * cell.volume());
  return sum_pairwise(terms);
}

std::vector<char> ClipSolver::may_overlap(const std::vector<Obb>& boxes) const {
  std::vector<Aabb> bounds(boxes.size());
  for (size_t j = 0; j < boxes.size(); ++j) bounds[j] = ConvexCell::from_box(boxes[j]).bounds();
  AabbTree tree(bounds);
  std::vector<char> out(boxes.size(), 0);
  for (size_t j = 0; j < boxes.size(); ++j) {
    if (bounds[j].empty()) continue;
    tree.for_each_overlap(bounds[j], [&](int32_t i) {
      if (i != static_cast<int32_t>(j)) out[j] = 1;
    });
  }
  return out;
}

std::vector<std::vector<int32_t>> ClipSolver::earlier_neighbours(
    const std::vector<Obb>& boxes) const {
  const size_t n = boxes.size();
  std::vector<Aabb> bounds(n);
  for (size_t j = 0; j < n; ++j) bounds[j] = ConvexCell::from_box(boxes[j]).bounds();
  AabbTree tree(bounds);
  std::vector<std::vector<int32_t>> out(n);
  for (size_t j = 0; j < n; ++j) {
    if (bounds[j].empty()) continue;
    tree.for_each_overlap(bounds[j], [&](int32_t i) {
      if (i < static_cast<int32_t>(j) && !bounds[i].empty()) out[j].push_back(i);
    });
    std::sort(out[j].begin(), out[j].end());
  }
  return out;
}

std::vector<ConvexCell> ClipSolver::shared_cells(const std::vector<Obb>& boxes, size_t j,
                                                 const std::vector<int32_t>& earlier) const {
  std::vector<ConvexCell> shared;
  ConvexCell whole = ConvexCell::from_box(boxes[j]);
  if (whole.empty()) return shared;
  // Split box j against the earlier boxes it may meet: `pieces` is what no earlier box
  // covers; each piece's part inside box i goes to `shared`.
  std::vector<ConvexCell> pieces{std::move(whole)};
  for (int32_t i : earlier) {
    const std::array<HalfSpace, 6> hs = box_half_spaces(boxes[i]);
    std::vector<ConvexCell> next;
    for (ConvexCell& p : pieces) {
      ConvexCell rest = std::move(p);
      for (const HalfSpace& h : hs) {
        const Side side = rest.classify(h);
        if (side == Side::kInside) continue;  // nothing of `rest` lies beyond this face
        if (side == Side::kOutside) {         // all of `rest` lies beyond: it stays whole
          next.push_back(std::move(rest));
          rest = ConvexCell();
          break;
        }
        ConvexCell out = rest;
        out.clip(h.complement());
        if (!out.empty()) next.push_back(std::move(out));
        rest.clip(h);
        if (rest.empty()) break;
      }
      if (!rest.empty()) shared.push_back(std::move(rest));
    }
    pieces = std::move(next);
    if (pieces.empty()) break;
  }
  return shared;
}

Rational ClipSolver::overlap_term(const std::vector<Obb>& boxes, size_t j,
                                  const std::vector<int32_t>& earlier) const {
  std::vector<Rational> terms;
  for (const ConvexCell& c : shared_cells(boxes, j, earlier))
    terms.push_back(c.volume() - inside_volume(c));
  return sum_pairwise(terms);
}

std::vector<ConvexCell> ClipSolver::overlap_cells(const std::vector<Obb>& boxes) const {
  const std::vector<std::vector<int32_t>> earlier = earlier_neighbours(boxes);
  std::vector<ConvexCell> shared;
  for (size_t j = 0; j < boxes.size(); ++j)
    for (ConvexCell& c : shared_cells(boxes, j, earlier[j])) shared.push_back(std::move(c));
  return shared;
}

Rational ClipSolver::omv(const std::vector<Obb>& boxes) const {
  std::vector<Rational> obvs;
  for (const Obb& b : boxes) obvs.push_back(obv(b));
  return omv(boxes, sum_pairwise(obvs));
}

Rational ClipSolver::omv(const std::vector<Obb>& boxes, const Rational& sum_obv) const {
  // With S_j = B_j ∩ (B_1 ∪ ... ∪ B_{j-1}) split into the disjoint cells of overlap_cells:
  // vol(U B) = sum vol(B_j) - sum vol(S_j) and vol(X ∩ U B) = sum vol(X ∩ B_j) - sum
  // vol(X ∩ S_j), so OMV = sum OBV_j - sum vol(S_j \ X): the overlap term, over the cells.
  const std::vector<ConvexCell> shared = overlap_cells(boxes);
  std::vector<Rational> terms;
  terms.reserve(shared.size());
  for (const ConvexCell& c : shared) terms.push_back(c.volume() - inside_volume(c));
  return sum_obv - sum_pairwise(terms);
}

}  // namespace vobb::exact
