// CGAL's double interval as the polyhedral solvers use it: operations assume upward rounding
// (CGAL::Protect_FPU_rounding<true>), and every sign is taken only where the enclosure
// decides it (box_clip::ClipTraits throws CGAL::Uncertain_conversion_exception elsewhere).
#pragma once

#include <CGAL/Interval_nt.h>

#include <utility>

#include "common/box_frame_clip.h"
#include "common/cell_clip.h"

namespace vobb {

using Interval = CGAL::Interval_nt<false>;

// The sign of x into *s where its enclosure decides it; false where it holds 0 and other values.
inline bool decided_sign(const Interval& x, int* s) {
  *s = x.inf() > 0 ? 1 : x.sup() < 0 ? -1 : 0;
  return *s != 0 || (x.inf() == 0 && x.sup() == 0);
}

template <>
struct box_clip::ClipTraits<Interval> {
  static int sign(const Interval& x) {
    int s;
    if (!decided_sign(x, &s)) throw CGAL::Uncertain_conversion_exception("an undecided sign");
    return s;
  }
};

template <>
struct cell_clip::NumberBounds<Interval> {
  static std::pair<double, double> of(const Interval& x) { return {x.inf(), x.sup()}; }
};

}  // namespace vobb
