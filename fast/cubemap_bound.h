// The cubemap estimator's error bounds: rigorous bounds on |estimate - exact OBV| for one box at
// resolution m, for the CPU twin and for the GL estimator, and a bound from the OBV's range
// alone. They depend on the box's plan (texel_plan.h) and on no GL context.
#pragma once

#include <algorithm>

#include "common/obb.h"
#include "fast/texel_plan.h"

namespace vobb {

// An upper bound on |GL estimate - CPU twin estimate| for a box with this plan at resolution
// m, in world volume units, from float32 rounding in the shaders (docs/derivations.md, "The GL
// deviation bound").
double gl_deviation_bound(const BoxPlan& plan, int m);

// The GL estimator's sum of a box's 6 m^2 texels (shaders/reduce_tiles.comp): slices of at most
// kReduceSliceTexels texels, each summed in float by 256 lanes (a lane takes every 256th texel
// of its slice, at most 1,024 of them: far below the loop trips a driver may allow a shader,
// 65,535 on llvmpipe, and a short float sum), then by a tree of 8 levels; the host adds a box's
// slices in double.
inline constexpr int kReduceSliceTexels = 256 * 1024;
inline int reduce_slices(int m) {
  return (6 * m * m + kReduceSliceTexels - 1) / kReduceSliceTexels;  // an int below m = 18,918
}

// Whether the shaders can evaluate this plan (above): false when a face's scaled plane is
// nonzero but below 3 FLT_MIN, the threshold under which analyse_plan_rounding counts its
// pairs as uncertain in float.
bool gl_evaluates_in_float(const BoxPlan& plan);

// A rigorous bound on |estimate - exact OBV| for one box at resolution m, for either backend:
// resolution_bound (texel_plan.h) plus gl_deviation_bound (or cpu_rounding_bound where GL
// runs the twin's code) plus 32 eps vol(O) + 2^-1068. For the CPU
// twin the float bound is kept too: it bounds the same sums' round-off in float32, so it
// covers the twin's double round-off of the texel sum (2^29 times smaller). The last term is
// the round-off outside the texel sum, which both bounds leave out (it matters where they
// are 0, e.g. a box that meets no face): the volume scale h0 h1 h2 |det[a0 a1 a2]| (the
// determinant's 5 roundings per term, its sum of |terms| at most sqrt(3) |det| for axes
// orthonormal to round-off, then 3 products: under 9 eps), the products with the constant
// and the texel weight (2 eps), and the exact value's rounding to the nearest double
// (eps/2): under 12 eps, taken as 32 eps for margin; plus 2^-1068 where these underflow
// (each operation then loses up to 2^-1075 absolutely). The plan's rounding of the
// faces into the box's frame is in resolution_bound (texel_plan.h), which widens its texel
// cones by it.
// The parts: resolution_bound, gl_deviation_bound (the bound on |GL - CPU twin|),
// cpu_rounding_bound (on |CPU twin - exact evaluation of the plan|) and the round-off term.
// rigorous() holds for either backend; cpu_rigorous() is the tighter one for the CPU twin
// alone (its double round-off instead of the float deviation).
struct CubemapBounds {
  double resolution = 0, deviation = 0, cpu_rounding = 0, roundoff = 0;
  bool unresolved = false;  // the plan could not hold the box (BoxPlan::unresolved)
  // deviation bounds |GL - CPU twin| and includes cpu_rounding; where GL runs the twin's own
  // code (gl_evaluates_in_float false) it is 0, and the twin's round-off is what remains.
  double rigorous() const { return resolution + std::max(deviation, cpu_rounding) + roundoff; }
  double cpu_rigorous() const { return resolution + cpu_rounding + roundoff; }
};

// The parts for one box at resolution m (the planner's plan of it).
CubemapBounds cubemap_bounds(const BoxPlanner& planner, const Obb& box, int m);
// The bound for one backend's estimate (rigorous() for GL, cpu_rigorous() for the CPU twin),
// computing only the round-off part that backend needs; `unresolved`: the plan could not hold
// the box (BoxPlan::unresolved).
double cubemap_bound(const BoxPlanner& planner, bool gl, const Obb& box, int m,
                     bool* unresolved = nullptr);

// A bound on |estimate - exact OBV| from the OBV's range alone: the exact OBV lies in [0, V*],
// V* = 8 h0 h1 h2 |det[a0 a1 a2]| the parallelepiped's exact volume, so |E - OBV| <=
// max(|E|, |U - E|) for any U >= V*. The rigorous bound above can exceed the box's volume
// (at small m each texel may be off by its whole pyramid; an unresolved plan); `vobb obv`
// reports the smaller of the two. Holds for every box that box_defect accepts (common/obb.h),
// and for an estimate outside [0, V*] too.
double range_bound(const Obb& box, double estimate);

// The estimate moved into [max(0, V - S), V], V = volume(box) and S >= vol(X) the solid's
// volume: the exact OBV, V - vol(B ∩ X), lies there, so the moved estimate is never farther
// from it than the estimate, to the rounding of V (a few eps of V). Where the box is far larger
// than the solid, or the estimate falls outside [0, V] (an extreme box at small m, whose
// bound is of the order of V), this is what keeps a search from taking noise for a gain.
double clamp_to_obv_range(const Obb& box, double estimate, double solid_volume);

}  // namespace vobb
