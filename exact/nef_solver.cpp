// Path (a) of the exact solver: CGAL Nef polyhedra. Kept alone in its translation unit: Nef
// is the heaviest thing to compile in the project (DESIGN §3).
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Nef_nary_union_3.h>
#include <CGAL/Nef_polyhedron_3.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polyhedron_3.h>

#include <type_traits>

// certify() runs NefSolvers on several threads at once, one per thread. CGAL's lazy exact
// kernel is safe for that (distinct objects on distinct threads) only when CGAL is built
// thread-aware (CGAL >= 5.4 with CGAL_HAS_THREADS).
#ifndef CGAL_HAS_THREADS
#error "certify runs NefSolvers on several threads: CGAL must be configured with CGAL_HAS_THREADS"
#endif
#include <unordered_map>

#include "common/solidity.h"
#include "exact/outer_volume.h"

namespace vobb::exact {
namespace {

using Kernel = CGAL::Exact_predicates_exact_constructions_kernel;
using Point = Kernel::Point_3;
using Polyhedron = CGAL::Polyhedron_3<Kernel>;
using Nef = CGAL::Nef_polyhedron_3<Kernel>;

Rational to_rational(const Kernel::FT& x) {
  // With CGAL_DO_NOT_USE_BOOST_MP and gmpxx present, Epeck's exact number type is mpq_class.
  static_assert(std::is_same_v<std::decay_t<decltype(CGAL::exact(x))>, Rational>,
                "Epeck's exact type is expected to be mpq_class");
  return CGAL::exact(x);
}

Nef nef_from_soup(const std::vector<Point>& points,
                  const std::vector<std::vector<std::size_t>>& polys) {
  Polyhedron poly;
  CGAL::Polygon_mesh_processing::polygon_soup_to_polygon_mesh(points, polys, poly);
  return Nef(poly);
}

// The certified solid of a box, or the empty set for a box of zero volume.
Nef nef_box(const Obb& box) {
  const ExactBoxFrame f(box);
  const Rational& det = f.det;
  if (sgn(det) == 0) return Nef(Nef::EMPTY);
  std::vector<Point> pts;
  for (int c = 0; c < 8; ++c) {
    Rational x[3];
    f.corner(c, x);
    pts.emplace_back(Kernel::FT(x[0]), Kernel::FT(x[1]), Kernel::FT(x[2]));
  }
  std::vector<std::vector<std::size_t>> quads;
  for (const auto& q : kBoxQuads) {
    if (sgn(det) > 0)
      quads.push_back({std::size_t(q[0]), std::size_t(q[1]), std::size_t(q[2]), std::size_t(q[3])});
    else
      quads.push_back({std::size_t(q[3]), std::size_t(q[2]), std::size_t(q[1]), std::size_t(q[0])});
  }
  return nef_from_soup(pts, quads);
}

// Volume of the marked volumes: for every halffacet that bounds a marked volume, the signed
// volume of the cones from one reference point over its cycles (outer cycle and holes, which
// run the other way). Nef orients every such halffacet the same way relative to the volume it
// bounds, so the sum is the volume up to one global sign; a facet between two marked volumes
// contributes twice with opposite signs and cancels.
Rational nef_volume(const Nef& nef) {
  std::vector<Rational> terms;
  Rational ref[3];
  bool have_ref = false;
  for (auto f = nef.halffacets_begin(); f != nef.halffacets_end(); ++f) {
    if (!f->incident_volume()->mark()) continue;
    for (auto fc = f->facet_cycles_begin(); fc != f->facet_cycles_end(); ++fc) {
      if (!fc.is_shalfedge()) continue;
      Nef::SHalfedge_const_handle se(fc);
      Nef::SHalfedge_around_facet_const_circulator hc(se), he(hc);
      std::vector<std::array<Rational, 3>> cycle;
      CGAL_For_all(hc, he) {
        const Point& p = hc->source()->center_vertex()->point();
        cycle.push_back({to_rational(p.x()), to_rational(p.y()), to_rational(p.z())});
      }
      if (cycle.size() < 3) continue;
      if (!have_ref) {
        for (int i = 0; i < 3; ++i) ref[i] = cycle[0][i];
        have_ref = true;
      }
      Rational a[3], b[3], c[3];
      for (int i = 0; i < 3; ++i) a[i] = cycle[0][i] - ref[i];
      for (size_t k = 1; k + 1 < cycle.size(); ++k) {
        for (int i = 0; i < 3; ++i) {
          b[i] = cycle[k][i] - ref[i];
          c[i] = cycle[k + 1][i] - ref[i];
        }
        Rational t = a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                     a[2] * (b[0] * c[1] - b[1] * c[0]);
        if (sgn(t) != 0) terms.push_back(std::move(t));
      }
    }
  }
  // Halffacet cycles run clockwise seen from outside the volume they bound: negate.
  return -sum_pairwise(terms) / 6;
}

}  // namespace

struct NefSolver::Impl {
  Nef solid;
};

NefSolver::NefSolver(const Mesh& mesh) : impl_(std::make_unique<Impl>()) {
  // Nef(shell) fills a closed shell whatever its orientation, so a solid with cavities is the
  // symmetric difference of its filled shells.
  Nef solid(Nef::EMPTY);
  for (const std::vector<int32_t>& shell : face_components(mesh)) {
    std::vector<Point> pts;
    std::vector<std::vector<std::size_t>> tris;
    std::unordered_map<int32_t, std::size_t> index;
    for (int32_t f : shell) {
      std::vector<std::size_t> t;
      for (int k = 0; k < 3; ++k) {
        const int32_t v = mesh.faces[f][k];
        auto [it, inserted] = index.emplace(v, pts.size());
        if (inserted)
          pts.emplace_back(mesh.vertices[v][0], mesh.vertices[v][1], mesh.vertices[v][2]);
        t.push_back(it->second);
      }
      tris.push_back(std::move(t));
    }
    solid = solid.symmetric_difference(nef_from_soup(pts, tris));
  }
  impl_->solid = std::move(solid);
}

NefSolver::~NefSolver() = default;

Rational NefSolver::obv(const Obb& box) const { return nef_volume(nef_box(box) - impl_->solid); }

Rational NefSolver::omv(const std::vector<Obb>& boxes) const {
  CGAL::Nef_nary_union_3<Nef> un;
  bool any = false;
  for (const Obb& b : boxes) {
    Nef n = nef_box(b);
    if (n.is_empty()) continue;
    un.add_polyhedron(n);
    any = true;
  }
  if (!any) return Rational(0);
  return nef_volume(un.get_union() - impl_->solid);
}

}  // namespace vobb::exact
