// The per-box work that both cubemap backends share (cubemap.h): the box frame, the exact class
// of the centre, the faces that can meet the box in box-normalized coordinates, and for each
// (face, cubemap face) pair the rectangle of texels whose rays may hit the face. The CPU twin
// ray-casts those texels in double; the GL estimator draws one quad per rectangle and runs the
// same per-texel test (texel_hit) in float. Sharing the plan makes the two differ only in
// arithmetic precision.
//
// A box's local OBV at resolution m is
//   constant + (4 / (3 m^2)) * sum over (texel, face) hits of the hit's value,
// with, in the normal mode (centre inside or outside the solid, 1_X(centre) known exactly),
//   constant = 8 (1 - 1_X(centre)),  value = s (1 - zeta^3) for 0 < zeta < 1, else nothing;
// and in the far-count mode (centre exactly on the surface, where 1_X(centre) is undefined),
//   constant = 8,  value = -s zeta^3 for 0 < zeta < 1, -s for zeta >= 1,
// which uses sum over all crossings of s = 1_X(centre) (the ray ends outside the solid), so
// that 1 - c per texel becomes 1 - (sum of s beyond the box): only faces, no centre class.
// The far-count mode draws every face of the mesh (no culling): a ray's far crossings can be
// anywhere. Its hits at zeta -> 0 contribute -> 0, so faces through the centre do no harm.
#pragma once

#include <cstdint>
#include <vector>

#include "common/bvh.h"
#include "common/mesh.h"
#include "common/obb.h"
#include "common/point_in_solid.h"
#include "fast/cubemap.h"

namespace vobb {

// A mesh face in box-normalized coordinates, ready for texel rays from the origin.
struct LocalTriangle {
  Vec3 p[3];
  int32_t id[3];       // mesh vertex ids
  Vec3 edge_cross[3];  // fl(+-(p[k] x p[k+1])): a ray d passes edge k on the side of sign(d . E*)
  // E* = +-(p[k] x p[k+1]) taken exactly (the p as the plan holds them). edge_cross is E*
  // rounded, computed in canonical order (lower vertex id first) and negated when needed, so
  // the two faces that share an edge hold exact negatives whatever the compiler fuses. Where
  // d . E* is exactly 0 the side is decided by simulation of simplicity: the ray is taken as
  // d + eps e_a + eps^2 e_b + eps^3 e_k (face axis k, a = k+1, b = k+2), whose sign is that of
  // the first nonzero of E*_a, E*_b, E*_k. That is one consistent perturbed ray for every
  // face, so a ray through a shared edge or a vertex is claimed exactly as a ray beside it.
  // The rounded crosses alone are not consistent around a vertex: the planes of the rounded
  // crosses of the edges at a vertex v no longer meet on the ray through v, so a ray within
  // rounding of v may be claimed by several of v's faces or by none (a texel's value then
  // leaves [0, 1]). The CPU twin therefore decides every edge test within edge_tie[k] of 0
  // exactly (cpu_edge_side).
  double edge_tie[3];  // bounds |fl(d . edge_cross[k]) - d* . E*| over the texel directions
  // E* of edge k is exactly the zero vector: its line passes through the centre (a box centred
  // on a mesh vertex, or on an edge), and every texel's exact test gives 0. Decided once per
  // edge by plan(), so that exact_edge_side need not redo it in rationals for every texel.
  bool edge_zero[3] = {false, false, false};
  Vec3 normal;   // (p1 - p0) x (p2 - p0), outward for a solid (corrected for mirrored frames)
  double plane;  // normal . p0: along d the face's plane is at zeta = plane / (normal . d)
  // The exact face, or this plane's rounding, may pass so near the centre that the plan's
  // hits on it cannot be trusted (docs/derivations.md, "Edge ties"; resolution_bound counts them
  // whole).
  bool near_centre = false;
};

// Texels [i0, i1] x [j0, j1] of cubemap face `face` whose centre rays may hit triangle `tri`,
// and texels [ci0, ci1] x [cj0, cj1] whose cones the triangle may meet (for resolution_bound).
struct TexelSpan {
  int32_t tri;
  int32_t face;
  int32_t i0, i1, j0, j1;
  int32_t ci0, ci1, cj0, cj1;
};

struct BoxPlan {
  BoxFrame frame;
  Location where = Location::kOutside;
  bool far_count = false;  // the centre is on the surface (see above)
  double constant = 0;     // local-volume constant of the formula above
  std::vector<LocalTriangle> tris;
  std::vector<TexelSpan> spans;
  bool flat = false;  // zero volume, or a scale that underflows (docs/derivations.md, "The box
                      // frame's rounding"): OBV 0, nothing to draw
  // A face may pass within the frame's rounding of the centre (docs/derivations.md, "Faces near the
  // centre"): the exact class of the centre and the plan's faces may disagree there, so a texel the
  // faces cover may be off by two pyramids instead of one (resolution_bound).
  bool centre_near_surface = false;
  // The box's view of the mesh does not fit the plan's doubles: axes that double cannot
  // invert, or a face the box keeps lying beyond 2^300 box units (a half extent 1e-306 beside
  // a mesh of size 1), where local coordinates, crosses or planes would overflow. Nothing is
  // drawn; the estimate is half the box's volume (constant 4) and resolution_bound the other
  // half, which holds whatever the OBV. No box of a real tree comes near this.
  bool unresolved = false;
};

// A texel of the cubemap: face `face`, column i and row j at resolution m. Its exact centre
// direction d* has components +-1, -1 + (2i+1)/m and -1 + (2j+1)/m (cubemap.h); `d` is d*
// rounded to double (cubemap_direction of texel_center).
struct Texel {
  int face, i, j, m;
  Vec3 d;
};

// The side of edge k of t for the exact texel ray d* (see LocalTriangle): the sign of
// d* . E*, exactly (by the first of the two paths below that decides it), with simulation of
// simplicity for an exact 0; 0 when E* is the zero vector (the edge's line passes through the
// centre, and so does the face's plane).
int exact_edge_side(const LocalTriangle& t, int k, const Texel& x);
// The same sign by two paths. By floating-point expansions (a filter first), without
// allocation: false where they could not decide it exactly (a product of two coordinates
// outside [2^-800, 2^1000] and not 0, m above 4096, or a rounding mode other than to nearest).
// In rationals: always decides; exact_edge_side's path where the first is false, and its
// reference in the tests.
bool exact_edge_side_by_expansion(const LocalTriangle& t, int k, const Texel& x, int* side);
int exact_edge_side_rational(const LocalTriangle& t, int k, const Texel& x);

// The CPU twin's edge test: that exact side, computed in double where the double is decisive.
// `e` is d . edge_cross[k] computed as a 3-term dot product in any order (edge_tie allows it).
inline int edge_side_of_dot(const LocalTriangle& t, int k, double e, const Texel& x) {
  if (__builtin_expect(std::abs(e) > t.edge_tie[k], 1)) return e > 0 ? 1 : -1;
  return exact_edge_side(t, k, x);  // rays within rounding of the edge's plane: rare
}
inline int cpu_edge_side(const LocalTriangle& t, int k, const Texel& x) {
  return edge_side_of_dot(t, k, x.d.dot(t.edge_cross[k]), x);
}

// One texel ray against one face, in double (the CPU twin): whether it hits, and the hit's
// value (above), given the ray's three edge dots e[k] = d . edge_cross[k] and nd = d . normal,
// each computed as a 3-term dot product in any order (what edge_tie and the rounding analysis
// allow). The edge tests are exact (cpu_edge_side), so around every vertex and edge each ray
// is claimed by the faces an exact ray cast would claim; the depth is in double.
inline bool texel_hit_dots(const LocalTriangle& t, const Texel& x, const double* e, double nd,
                           bool far_count, double* value) {
  const bool clear01 = std::abs(e[0]) > t.edge_tie[0] && std::abs(e[1]) > t.edge_tie[1];
  if (__builtin_expect(clear01, 1)) {
    if ((e[0] > 0) != (e[1] > 0)) return false;  // the usual miss, decided by two edges
    if (edge_side_of_dot(t, 2, e[2], x) != (e[0] > 0 ? 1 : -1)) return false;
  } else {  // a ray within rounding of edge 0's or 1's plane
    int side = 0;
    for (int k = 0; k < 3; ++k) {
      const int sk = edge_side_of_dot(t, k, e[k], x);
      if (sk == 0) return false;
      if (k == 0)
        side = sk;
      else if (sk != side)
        return false;
    }
  }
  if (nd == 0) return false;  // the ray runs in the face's plane
  const double zeta = t.plane / nd;
  if (!(zeta > 0)) return false;  // behind the centre, or at it
  const double s = nd > 0 ? 1.0 : -1.0;
  if (!far_count) {
    if (!(zeta < 1)) return false;
    *value = s * (1 - zeta * zeta * zeta);
  } else {
    *value = zeta < 1 ? -s * zeta * zeta * zeta : -s;
  }
  return true;
}

// The same for one texel, computing the dots.
inline bool texel_hit(const LocalTriangle& t, const Texel& x, bool far_count, double* value) {
  const double e[3] = {x.d.dot(t.edge_cross[0]), x.d.dot(t.edge_cross[1]),
                       x.d.dot(t.edge_cross[2])};
  return texel_hit_dots(t, x, e, t.normal.dot(x.d), far_count, value);
}

// A rigorous a-priori bound on |estimate - exact OBV| for this plan at resolution m, in world
// volume units: scale * (4 / (3 m^2)) * (number of texels whose cone the surface may meet
// within the box). A texel whose cone the surface misses is entirely inside or outside the
// solid, and the estimate integrates it exactly (exact pyramid weights); any other texel's
// estimated and true outer fractions both lie in [0, 1], so it is off by at most its pyramid.
// (The estimated fraction lies in [0, 1] because the reference evaluation is a consistent ray
// cast: its edge tests are exact, LocalTriangle.) This is a guarantee, not an estimate, and it
// does not fall with m where the surface crosses the box: every texel whose ray crosses the
// surface within the box counts, and their share of the 6 m^2 stays about the same (measured:
// docs/BENCHMARKS.md, "The cubemap's a-priori bound against m"). The observed
// error falls as m^-2, since the per-texel errors cancel (DESIGN §4); validate/ measures it.
// "Exact OBV" is that of the box as stored (its doubles taken exactly) and the mesh. The plan
// holds the faces in box-normalized coordinates rounded to double (BoxFrame::local_error,
// about u |v - c| / h_k on axis k, up to 1e-10 and more in thin boxes far from the faces'
// vertices): culling and the texel cones are widened by that error, so the counted texels
// cover the exact faces too, and a face that reaches into the box by less than it is kept.
// Where a face may pass within that error of the centre, or its plane's rounding may move a
// hit by over 2^-20 of its depth (near_centre, centre_near_surface; bounded componentwise, so
// that a thin box's stretched local axis does not inflate it), the centre's exact class and
// the plan's faces may disagree: the bound counts two pyramids per covered texel, and two
// more per texel such a face covers (its hits may be wrong either way). Every other face's
// plane, as the plan holds it, puts each hit within 2^-20 of its depth (docs/derivations.md, "Faces
// near the centre"), worth 3e-6 pyramids per (texel, face) pair, which the bound adds. Evaluating
// the plan's doubles is bounded apart (cpu_rounding_bound, gl_deviation_bound), and so is the
// volume scale's rounding (fast/cubemap_bound.h).
double resolution_bound(const BoxPlan& plan, int m);

// Scale factor 2^-e bringing the largest |x_i| into [0.5, 1): exact in binary, so it keeps
// zeros, signs, exact negations between the faces of a shared edge, and the ratio plane/nd.
inline double pow2_normalizer(double a, double b, double c, double d = 0) {
  const double big = std::max({std::abs(a), std::abs(b), std::abs(c), std::abs(d)});
  if (big == 0 || !std::isfinite(big)) return 1;
  int e;
  std::frexp(big, &e);
  return std::ldexp(1.0, -e);
}

// Round-off of evaluating a plan in a floating-point format, against evaluating the same plan
// (the same doubles) in exact arithmetic. docs/derivations.md ("Round-off of evaluating a plan")
// derives the per-pair terms; both estimators' bounds are built from it (cpu_rounding_bound below,
// gl_deviation_bound).
struct RoundingModel {
  double u;  // unit round-off: 2^-53 for double, 2^-24 for float
  // Three times the least magnitude the format keeps (FLT_MIN where GLSL may flush
  // subnormals, 2^-1074 with gradual underflow): what underflow may cost a 3-term dot
  // product, and the |plane| (normal scaled to [0.5, 1)) below which zeta may become 0.
  double tiny;
  // Whether the evaluation scales each edge cross to [0.5, 1) before rounding (the shader
  // does, so its underflow cost is `tiny` in scaled units; the CPU twin does not, so its cost
  // is `tiny` in unscaled units).
  bool scaled_inputs;
  // For the CPU twin, whose edge tests are exact (cpu_edge_side): none is uncertain.
  bool exact_edges = false;
};
struct PlanRounding {
  double value_errors = 0;  // sum over hits of the value's error, plus threshold ambiguities
  double uncertain = 0;     // (texel, face) pairs whose hit or miss may differ from exact
  double sum_abs = 0;       // upper bound on the sum over hits of |value|
  double pairs = 0;         // hits plus uncertain pairs: the terms a texel sum may add
  int most_per_texel = 0;   // the most such terms in one texel
};
PlanRounding analyse_plan_rounding(const BoxPlan& plan, int m, const RoundingModel& model);

// A rigorous bound on |CPU twin estimate - exact-arithmetic evaluation of the same plan| at
// resolution m, in world volume units: the per-pair terms above in double, plus the recursive
// summation over all terms and the final assembly (Higham's gamma_n). It says nothing about
// the plan's own rounding (the box frame and local coordinates), which resolution_bound covers.
double cpu_rounding_bound(const BoxPlan& plan, int m);

class BoxPlanner {
 public:
  explicit BoxPlanner(const Mesh& mesh);  // keeps a reference
  // Precondition: m >= 1.
  BoxPlan plan(const Obb& box, int m) const;
  // The same plan, written into *out, whose vectors keep their capacity: a caller that plans
  // many boxes in turn (the CPU twin, per thread) allocates only when a plan outgrows the last.
  void plan(const Obb& box, int m, BoxPlan* out) const;
  // For the culling ablation: consider every face for every box.
  void set_culling(bool on) { culling_ = on; }
  bool culling() const { return culling_; }
  const Mesh& mesh() const { return mesh_; }
  const AabbTree& face_tree() const { return faces_; }

 private:
  const Mesh& mesh_;
  AabbTree faces_;
  bool culling_ = true;
};

}  // namespace vobb
