#include "fast/texel_plan.h"

#include <gtest/gtest.h>

#include <cmath>

#include "common/obb.h"
#include "fast/estimator_test_util.h"

namespace vobb {
namespace {

// Thin boxes tilted by 0.3 rad against a face of a rotated cube, their centres half their
// thin extent from its plane, at aspects 1e-3, 1e-4 and 1e-6. In box units the face passes
// at about 0.5 aspect / sin(0.3) from the centre (1.6e-6 at aspect 1e-6), and the faces'
// vertices lie up to 1 / aspect out along the thin axis. The plane the plan holds is off by u
// times the terms that make it up (texel_plan.cpp), which here stays below 1e-9 of the face's
// distance, far below the 2^-20 that would make the face "near the centre" and double the
// resolution bound. A bound of that rounding by vector norms counted the stretched axis twice
// and flagged these faces at aspects 1e-4 and 1e-6. (At 1e-8 the face passes 1.6e-8 box units
// from the centre and the componentwise bound is 1.6e-6 of that: such a box is flagged, and
// its bound doubled, rightly within the 2^-20 rule.)
TEST(TexelPlan, ThinBoxesDoNotTakeFarFacesAsNearTheCentre) {
  const Vec3 &a0 = test::kTurnedA0, &a1 = test::kTurnedA1, &a2 = test::kTurnedA2;
  const Mesh cube = test::turned_cube();
  const BoxPlanner planner(cube);
  // The face x = 1 of the cube's frame has outward normal a2. The boxes' thin axis is a2
  // turned by 0.3 rad towards a0.
  const double tilt = 0.3;
  const Vec3 thin = std::cos(tilt) * a2 + std::sin(tilt) * a0;
  const Vec3 across = -std::sin(tilt) * a2 + std::cos(tilt) * a0;
  for (double aspect : {1e-3, 1e-4, 1e-6}) {
    for (const Vec3& spot : {Vec3(0.1, 0.2, 0.0), Vec3(-0.3, 0.05, 0.1), Vec3(0.25, -0.4, -0.2)}) {
      Obb box;
      box.axes = orthonormalize({across, a1, thin});
      box.half = Vec3(0.3, 0.3, 0.3 * aspect);
      // On the face at (spot.x, spot.y) in its (a0, a1) coordinates, then moved inside along
      // the thin axis by half its extent.
      box.center = a2 + spot.x() * a0 + spot.y() * a1 - 0.5 * box.half.z() * box.axes[2];
      for (int m : {4, 32}) {
        const BoxPlan plan = planner.plan(box, m);
        ASSERT_FALSE(plan.tris.empty()) << "aspect " << aspect;  // the face crosses the box
        EXPECT_FALSE(plan.centre_near_surface) << "aspect " << aspect << " m " << m;
        for (const LocalTriangle& t : plan.tris) EXPECT_FALSE(t.near_centre) << "aspect " << aspect;
      }
    }
  }
}

}  // namespace
}  // namespace vobb
