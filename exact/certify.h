// Certification of a finished tree (DESIGN §1, §7): per layer the exact OMV, the exact
// sum of OBV, their difference (the overlap term) and whether sum OBV >= OMV holds as
// rationals; for the whole tree the weighted error e = sum_i (D - i + 1) OMV(layer i) and the
// exact containment check (every face of every node inside its box).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "common/exact_predicates.h"
#include "common/mesh.h"
#include "common/tree.h"

namespace vobb::exact {

enum class OmvPath {
  kAuto,  // OBV by clipping in each box's frame; OMV = sum OBV without overlaps, else Nef
  kClip,  // path (b) for every layer
  kNef,   // path (a) for every layer
  kBoth,  // both, and a check that they are equal; Nef's OMV is reported (DESIGN §3: where
          // two exact paths disagree, Nef is the arbiter), clipping's is kept beside it
};

struct LayerCertificate {
  int level = 0;
  size_t boxes = 0;
  size_t overlapping_boxes = 0;  // boxes that may meet another box of the layer (by bounds)
  Rational omv;
  Rational sum_obv;
  Rational overlap() const { return sum_obv - omv; }
  bool upper_bound_holds() const { return sum_obv >= omv; }
  std::string omv_path;        // "clip", "nef", "none" (no overlaps: OMV = sum OBV), "both"
  bool paths_agree = true;     // kBoth only: Nef's OMV == clipping's OMV
  Rational omv_clip;           // kBoth only: clipping's OMV (omv holds Nef's, the arbiter's)
  // This layer's own work: its sums, overlap bounds and union. Not the boxes' OBV (computed
  // first, for all layers at once) nor the building of a thread's Nef(X).
  double seconds = 0.0;
};

struct Certificate {
  std::vector<LayerCertificate> layers;
  Rational weighted_error;
  ContainmentReport containment;
  double seconds = 0.0;
  bool ok() const;  // containment, every upper bound, and (kBoth) path agreement
};

struct CertifyOptions {
  OmvPath path = OmvPath::kAuto;
  // Called with one line per finished stage (per layer, in the order they finish), so long
  // runs show they are alive.
  std::function<void(const std::string&)> progress;
};

// Precondition: the mesh is solid and the tree validated against it (validate_tree, same
// triangle count). Creates no GL context.
// Threads: the boxes' OBV are computed in parallel, then the layers, one per thread at a time,
// the layers with most boxes first; each thread that needs a union builds its own Nef(X), so
// memory grows with the threads (TBB's: limit them with tbb::global_control or a task_arena).
// The result is the same rationals for any number of threads; only `seconds` and the order of
// the progress lines vary. `progress` is called from any of the threads, one call at a time.
Certificate certify(const Mesh& mesh, const Tree& tree, const CertifyOptions& options);

}  // namespace vobb::exact
