// Stiff and extreme cases of the cubemap estimator (DESIGN §6). Each case is named and
// states its expected behaviour before it runs:
//  - "finite, within R(m)": every estimate (CPU twin and GL, at each m) is finite and within
//    its backend's rigorous per-box bound R(m) (EstimatorSet::bound); the outcome says on how
//    many estimates the error is above B(m) vol(O);
//  - "finite, within R(m) and B(m)": also within the stated statistical bound B(m) vol(O)
//    (for boxes of the kind B(m) was fitted on: real meshes, moved or scaled);
// and, on every case that estimates, the polyhedral solver's certified interval
// (fast/poly_solver.h) holds the exact rational OBV of every box;
//  - "refused with a clear message": the input is refused by a Status whose one-line message
//    names the defect, and nothing crashes.
// The cases: sliver and needle triangles; a box of aspect ratio 1e-4; a mesh offset by 1e6
// and scaled by 1e-6 and 1e6; the centre on a face, an edge and a vertex; faces parallel to
// the view rays; nested shells (a cavity); m = 1 and m = 1024; a box holding the whole mesh; a
// box disjoint from the mesh; and refusals (m = 0, a NaN box, m beyond the GL limit, a
// self-intersecting mesh, coordinates beyond 2^240).
#pragma once

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "common/mesh.h"
#include "validate/discretization_study.h"

namespace vobb::validate {

struct StiffCaseResult {
  std::string name;
  std::string expected;
  std::string outcome;  // what happened, in one line
  bool as_expected = false;
  double worst_rigorous_ratio = 0;      // max |E - V| / R(m) over the case's estimates
  double worst_bound_ratio = 0;         // max |E - V| / (B(m) vol(O))
  double tightest_rigorous = INFINITY;  // min R(m) / vol(O) over the case's estimates
  bool poly_enclosed = false;  // the polyhedral solver's interval held the exact OBV of every box
};

struct StiffConfig {
  const Mesh* real_mesh = nullptr;  // dino; cases that need a real mesh are skipped without one
  std::string real_mesh_name = "dino";
  std::string self_intersecting_mesh;  // path of a mesh that is not solid (camel), or empty
  std::vector<int> ms = {8, 32};
  bool want_gl = true;
  EstimatePerturbation perturb;  // tests only
  std::function<void(const std::string&)> progress;
};

std::vector<StiffCaseResult> run_stiff_cases(const StiffConfig& config, const StatedBound& bound);

}  // namespace vobb::validate
