// Tolerance helpers shared by the estimator tests (CPU twin and GL).
#pragma once

#include <algorithm>
#include <cmath>

#include "common/mesh.h"
#include "common/obb.h"

namespace vobb::test {

// The plan's own rounding for an axis-aligned box over a mesh of surface area `area`: a local
// coordinate is (p - c) (1 rounding) times 1 / h from Eigen's inverse of diag(h) (cofactor,
// determinant and quotient: 4), a product (1): relative error gamma_6 in each coordinate, so
// the surface the plan encodes lies within gamma_6 |p - c| of the mesh's, and the volume it
// cuts from the box moves by at most area * sqrt(3) gamma_6 max|p - c| (first order; the
// second-order terms are 1e-16 times smaller and covered by taking gamma_7).
inline double aligned_plan_round_off(const Mesh& mesh, double area, const Obb& box) {
  double far = 0;
  for (const Vec3& v : mesh.vertices) far = std::max(far, (v - box.center).norm());
  const double u = 0x1p-53;
  return area * std::sqrt(3.0) * 7 * u / (1 - 7 * u) * far;
}

}  // namespace vobb::test
