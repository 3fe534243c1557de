// Certification of a finished tree (DESIGN §1, §7): per layer the OMV, the sum of OBV and
// their difference (the overlap term), each as an enclosure of the exact value and its
// correctly rounded double, and whether sum OBV >= OMV holds, decided exactly; for the whole
// tree the weighted error e = sum_i (D - i + 1) OMV(layer i), and the exact containment check
// (every face of every node inside its box). By default the enclosures come from the filter
// (exact/filtered_solver.h) and rationals are computed only where a sign or a rounding needs
// them (the certificate says where); the rational paths compute every value exactly.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "common/exact_predicates.h"
#include "common/mesh.h"
#include "common/mp_interval.h"
#include "common/status.h"
#include "common/tree.h"
#include "exact/filtered_solver.h"

namespace vobb::exact {

enum class OmvPath {
  kAuto,  // filtered (exact/filtered_solver.h): enclosures, rationals only where a sign or a
          // rounding needs them; no Nef polyhedron
  kClip,  // the clipping path (b) in rationals for every layer
  kNef,   // the Nef path (a) in rationals for every layer
  kBoth,  // filtered, and both exact paths: Nef's OMV equal to clipping's and inside the
          // filtered enclosure, or the certificate fails (DESIGN §3: Nef is the arbiter)
};

// How a value was obtained: "filter" (its enclosure decided it) or "exact" (rationals).
struct LayerCertificate {
  int level = 0;
  size_t boxes = 0;
  size_t overlapping_boxes = 0;  // boxes that may meet another box of the layer (by bounds)
  // Enclosures of the exact values: OMV, sum of OBV, and the overlap term sum OBV - OMV.
  MpInterval omv_enclosure, sum_obv_enclosure, overlap_enclosure;
  // The doubles nearest to the exact values (ties to even), and how each was obtained.
  double omv_nearest = 0, sum_obv_nearest = 0, overlap_nearest = 0;
  std::string omv_rounded_by = "filter", sum_obv_rounded_by = "filter",
              overlap_rounded_by = "filter";
  bool upper_bound = true;          // sum OBV >= OMV, decided
  std::string bound_by = "filter";  // "exact": rationals, or no overlapping boxes (equality)
  size_t exact_obv = 0;             // boxes whose OBV the filter sent to rationals
  size_t exact_overlap = 0;         // boxes whose overlap term the filter sent to rationals
  size_t refined_obv = 0;           // boxes whose OBV needed 256 bits (a sign undecided in 128)
  size_t refined_overlap = 0;       // boxes whose overlap term needed 256 bits (a rounding or sign)
  // The exact rationals, where computed (`rational`): with --rational, on a rational path, or
  // where a rounding needed them.
  bool rational = false;
  Rational omv;
  Rational sum_obv;
  Rational overlap() const { return sum_obv - omv; }
  bool upper_bound_holds() const { return upper_bound; }
  std::string omv_path;  // "filtered", "clip", "nef", "none" (no overlaps), "both"
  // kBoth: Nef's OMV == clipping's, and inside the filter's enclosure; kAuto with `rational`:
  // Nef's OMV inside the filter's enclosure. Otherwise true.
  bool paths_agree = true;
  Rational omv_clip;  // kBoth only: clipping's OMV (omv holds Nef's, the arbiter's)
  // This layer's own work: its sums, overlap bounds and union. Not the boxes' OBV (computed
  // first, for all layers at once) nor the building of a Nef(X).
  double seconds = 0.0;
};

struct Certificate {
  std::vector<LayerCertificate> layers;
  MpInterval weighted_error_enclosure;
  double weighted_error_nearest = 0;
  std::string weighted_error_rounded_by = "filter";
  bool rational = false;  // weighted_error holds the exact e (every layer has its rationals)
  Rational weighted_error;
  ContainmentReport containment;
  size_t exact_obv = 0;  // boxes whose OBV the filter sent to rationals, over the tree
  double seconds = 0.0;
  bool ok() const;  // containment, every upper bound, and (kBoth) path agreement
};

// What a certification has finished, for a checkpoint: the boxes' OBV once all are computed,
// and each finished layer (in the order they finished).
struct CertifyState {
  std::vector<Enclosed> obv;             // per node id; empty until all are computed
  std::vector<LayerCertificate> layers;  // finished layers
};

struct CertifyOptions {
  OmvPath path = OmvPath::kAuto;
  // Compute the exact rationals of every value (kAuto: OBV by clipping, OMV by Nef where
  // boxes overlap), and check each lies in its enclosure.
  bool rational = false;
  // Called with one line per finished stage (per layer, in the order they finish), so long
  // runs show they are alive.
  std::function<void(const std::string&)> progress;
  // Called with everything finished so far after the boxes' OBV and after each layer, one call
  // at a time; may be empty.
  std::function<void(const CertifyState&)> checkpoint;
  // A state saved by `checkpoint` of a certification of the same mesh and tree with the same
  // path and options (CertifyCheckpoint::load checks it against the tree), and the same
  // kCertifyVersion. Its OBV are taken as they are; a finished layer is taken when its boxes,
  // overlap count, sum of OBV and path are the ones this run gives. Only the rest is computed,
  // and the certificate is the uninterrupted one (a resumed layer keeps the seconds it took).
  // The files' checksums guard against damage, not against a forged state.
  const CertifyState* resume = nullptr;
  // The memory the Nef polyhedra may take (layer_workers), in bytes; negative: what the
  // system has available now (available_memory_bytes). Tests set it to see the limit work.
  double memory_bytes = -1;
};

// Precondition: the mesh is solid and the tree validated against it (validate_tree, same
// triangle count). Creates no GL context.
// Threads: the boxes' OBV are computed in parallel, then the layers, the layers with most boxes
// first, each layer's boxes in parallel (TBB's threads: limit them with tbb::global_control or
// a task_arena). The filtered path holds one box's cells per thread. A rational path's union
// needs a Nef(X) per layer worker (each worker's thread builds its own), so there are at most
// as many layer workers as memory_bytes holds Nef(X) for (layer_workers), and at least one.
// The result is the same for any number of threads; only `seconds` varies.
Certificate certify(const Mesh& mesh, const Tree& tree, const CertifyOptions& options);

// Bytes of a Nef polyhedron of a mesh, per face: measured 9.2-10.6 KB on dino and bunny
// (docs/BENCHMARKS.md, "Memory against mesh size"), taken as 12 KB.
inline constexpr double kNefBytesPerFace = 12e3;

// How many threads certify layers at once: at most `concurrency` and the `layers` to do, and,
// where a layer may take Nef's path (`uses_nef`), at most as many Nef polyhedra of a mesh of
// `faces` faces as fit in `available_bytes` (kNefBytesPerFace each); never fewer than one.
int layer_workers(int layers, int concurrency, bool uses_nef, size_t faces, double available_bytes);

// The memory the system could give this process now (MemAvailable of /proc/meminfo), or
// infinity where it cannot be read.
double available_memory_bytes();

// What a checkpoint's fingerprint names as certify's own: bump it when certify's arithmetic or
// choices change, so that checkpoints of the older code are refused.
inline constexpr const char* kCertifyVersion = "certify 2";

// A certification's checkpoint, in a folder of two JSON files: obv.json, the boxes' OBV, written
// once; and layers.json, the finished layers, rewritten after each and naming obv.json's
// checksum, so that the large rationals are written once. Each file carries a `fingerprint`
// naming what the certification depends on (the caller's: mesh, tree and path), the
// rationals as exact "p/q" strings, and in `sha256` the SHA-256 of its compact JSON without
// that field. Writes are atomic (temporary file, then rename).
class CertifyCheckpoint {
 public:
  CertifyCheckpoint(std::string folder, std::string fingerprint);
  ~CertifyCheckpoint();
  // The saved state. Neither file there: ok with *found = false. Refused, with one line naming
  // the file: a damaged file (not JSON or nested too deep, bad checksum, unknown field, a
  // rational that does not parse or has a zero denominator), another certification's
  // (fingerprint), layers.json without obv.json or naming another one, and a state that does
  // not fit `tree`: an OBV count other than its nodes', a layer outside 0..depth or given
  // twice, a box count or a sum of OBV other than the layer's, or a path's result that
  // contradicts itself; and, for a run that computes every rational (`rational`), a box's OBV
  // whose rational (0 where the file leaves it out) lies outside its enclosure.
  Status load(const Tree& tree, CertifyState* state, bool* found, bool rational = false);
  // The files in `folder` checked as files only (JSON, format, fields, checksum), before the
  // tree they belong to is known: so that a run can refuse a damaged folder before its long
  // work rather than after it. load() checks the rest.
  static Status check_files(const std::string& folder);
  // Writes obv.json the first time `state` has OBV (not again once loaded or written), then
  // layers.json.
  Status save(const CertifyState& state);
  std::string obv_path() const;
  std::string layers_path() const;

 private:
  struct Written;  // finished layers as written, by level (certify.cpp)
  std::string folder_, fingerprint_;
  std::string obv_sha256_;  // of obv.json as written or loaded; empty: none yet
  std::unique_ptr<Written> written_;
};

}  // namespace vobb::exact
