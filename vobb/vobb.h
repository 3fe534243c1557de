// vobb's public face: the one header a C++ user includes. Load a solid, build a tree, certify
// it exactly, estimate the outer volume of boxes, compare the two builders, and weigh layers
// into the tree error e (DESIGN §1).
//
// - Meshes: the calls take a solid mesh, as load_solid gives it (a precondition; load_solid
//   refuses a mesh that is no solid, naming the defect). What breaks the calls outright is
//   checked in one pass and refused with an error: no faces, a vertex index out of range, a
//   coordinate not finite or beyond 2^240.
// - Every call returns a Status: bad input (a tree of another mesh or of a broken structure,
//   options out of range or contradicting each other, a damaged checkpoint) is an error with a
//   one-line message, not an exception or an abort. Out of memory throws std::bad_alloc.
// - The library prints nothing: what a run would say (the renderer, a resumed state, a
//   checkpoint not saved) goes to the `note` and `warning` callbacks. Callbacks may be called
//   from TBB's threads, one call at a time.
//
// The core (target vobb::vobb) needs CGAL, Eigen, GMP, MPFR, TBB and OpenSSL's libcrypto. The GL
// backend and the figures are the GL component (<vobb/gl.h>, target vobb::gl, enable_gl()):
// without it, Backend::kGl is refused and kAuto takes the CPU twin. Formats other than OFF,
// OBJ, PLY and STL need the assimp component (vobb::assimp, enable_assimp()).
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "builder/subtree_swaps.h"
#include "builder/variational_builder.h"
#include "collision/contact_predicates.h"
#include "common/io/mesh_io.h"
#include "common/io/mesh_report.h"
#include "common/mesh.h"
#include "common/obb.h"
#include "common/status.h"
#include "common/tree.h"
#include "common/tree_io.h"
#include "exact/certify.h"
#include "fast/poly_solver.h"

namespace vobb {

// ---- loading -------------------------------------------------------------------------------
// load_solid(path, &loaded) (common/io/mesh_report.h): reads OFF, OBJ, PLY and STL exactly
// (others through the assimp component, in single precision) and refuses a mesh that is not a
// solid, naming the defect. read_tree and write_tree (common/tree_io.h) read and write trees.

// ---- the tree error ------------------------------------------------------------------------
// e = Σ_l ω(l) OMV(layer l), ω(l) = D - l + 1 (layer_weight, common/tree.h). Given the OMV of
// layers 0..L-1, e with the weights of a tree of depth L - 1, exactly.
Rational tree_error(const std::vector<Rational>& layer_omv);

// ---- building ------------------------------------------------------------------------------
enum class Method { kVariational, kObbTree };
// The OBV estimator of the variational search. kAuto: the GL estimator on a GPU (an EGL device,
// with the GL component enabled) from m = kAutoGlFromM (the crossover: docs/BENCHMARKS.md); else
// the CPU twin, which gives the same texels in double. kPoly: the polyhedral solver (no m).
enum class Backend { kAuto, kCpu, kGl, kPoly };
inline constexpr int kAutoGlFromM = 128;

struct BuildOptions {
  Method method = Method::kVariational;
  int depth = 8;  // 0..30
  int arity = 2;  // 2..64
  // The variational search (VariationalOptions, builder/variational_builder.h):
  int m = 32;  // cubemap resolution, 1..4096; unused by kPoly
  Backend backend = Backend::kAuto;
  int lloyd = 4;
  uint64_t seed = 1;
  bool axis_search = true, adjust = false, merge = true;
  int sweeps = 3;
  bool refit = true;  // under kOmv: the last step's turns of boxes with their faces fixed
  // After the search, swaps of subtrees across distant parents while each lowers the estimated
  // e (builder/subtree_swaps.h), scored by the polyhedral solver whatever the backend. Off by
  // default: it takes several times the search's time (docs/BENCHMARKS.md).
  bool subtree_swaps = false;
  // What the search minimises per set of boxes; unset: kOmv (docs/BENCHMARKS.md: it gives the
  // lower exact e), but kObv with a collider margin (a collider in a region two boxes share
  // tests both: the sum counts the tests). kOmv takes its shares from the polyhedral solver,
  // whatever the backend. Set, it is refused with kObbTree and with queries.
  std::optional<Objective> objective;
  double collider_margin = 0;  // world units, 0 .. the mesh's bounding-box diagonal
  // When not empty, the search minimises the recorded queries that hit each box instead of
  // OBV (collision/query_objective.h), and no OBV estimator is made.
  std::vector<collision::Collider> queries;
  // A folder; empty: none. A build started again with it resumes, but for a state whose
  // time_budget ran out, which a build without one refuses.
  std::string checkpoint;
  // Seconds, 0: none; for the search and then the subtree swaps. The search's nodes not yet
  // split get the baseline split; the swaps keep the rounds they finished.
  double time_budget = 0;
  std::function<void(const VariationalProgress&)> progress;
  // One line each; may be empty. note: what the run chose or found (the renderer, a resumed
  // state); warning: what it could not do and went on without (a checkpoint not saved).
  std::function<void(const std::string&)> note, warning;
  // Called after each checkpoint saved, with its state (a test's place to interrupt a run).
  std::function<void(const VariationalState&)> saved;
  // Called when the variational search starts and when it ends, with its counts.
  std::function<void()> started;
  std::function<void(const VariationalReport&)> finished;
  // Called after the subtree swaps, with their counts.
  std::function<void(const SubtreeSwapReport&)> swapped;
};

struct BuildReport {
  VariationalReport search;  // the variational search's counts
  std::string estimator;     // "cpu", "poly", "gl <renderer>", "queries", or "" (obbtree)
};

// Reads recorded-query files (`vobb collide --record-queries`) made for this mesh into
// options->queries.
Status read_queries(const Mesh& mesh, const std::vector<std::string>& paths, BuildOptions* options);
// What a variational build with these options minimises per set of boxes: the objective set,
// else kOmv, but kObv with a collider margin; with queries the search counts hits and takes no
// shares (kObv).
Objective search_objective(const BuildOptions& options);
// The combinations of options that contradict each other, and values out of range (enums
// cast from outside their lists included), refused with the flag's name.
Status check_build_options(const BuildOptions& options);
// Builds the tree of a solid mesh; fills every field, mesh_sha256 included. Deterministic: the
// same mesh and options give the same tree on any number of threads, and a build resumed from
// its checkpoint gives the uninterrupted one's.
Status build_tree(const Mesh& mesh, const BuildOptions& options, Tree* tree,
                  BuildReport* report = nullptr);

// ---- certifying ----------------------------------------------------------------------------
struct CertifyOptions {
  exact::OmvPath path = exact::OmvPath::kAuto;
  bool rational = false;   // also the exact rationals of every value (exact::CertifyOptions)
  std::string checkpoint;  // a folder; empty: none. A run started again with it resumes.
  std::function<void(const std::string&)> progress;       // one line per finished stage
  std::function<void(const std::string&)> note, warning;  // as for BuildOptions
  std::function<void(const exact::CertifyState&)> saved;  // after each checkpoint saved
  std::string tree_name = "tree";  // how messages name the tree (its file, say)
};
// Checks the path (one of OmvPath's), that the tree is well formed and indexes this mesh
// (check_tree_fits, common/tree.h, which also serves alone), then certifies it (exact/certify.h):
// OMV, sum of OBV and overlap per layer, e, containment. Creates no GL context. *certificate->ok()
// says whether it certifies.
Status certify(const Mesh& mesh, const Tree& tree, const CertifyOptions& options,
               exact::Certificate* certificate);

// ---- estimating OBV ------------------------------------------------------------------------
struct EstimateOptions {
  bool gl = false, cpu = false, poly = false, exact = false;  // which estimates to make
  bool gl_fallback = false;  // where GL cannot run (or m exceeds its limit): the CPU twin, noted
  std::vector<int> ms = {8, 16, 32};  // the cubemap's resolutions, each 1..4096
  bool r_bound = false;               // also R(m), the cubemap's rigorous texel bound
  bool rational = false;  // with exact: also each exact OBV as a rational (exact_rational)
  std::function<void(const std::string&)> note;
};
struct ObvRun {
  std::string backend;               // "poly", "cpu" or "gl"
  int m = 0;                         // 0: none (poly)
  std::vector<double> obv, seconds;  // per box; seconds: the batch's amortised
  // Per box: the estimate's certified error from the polyhedral enclosure (rounded up), and
  // R(m) (min with the range bound; NaN when not asked or for poly).
  std::vector<double> bound, r_bound;
  // Per box, with exact: |obv - exact OBV| / exact OBV, correctly rounded; NaN where the exact
  // OBV is 0.
  std::vector<double> rel_error;
};
struct ObvReport {
  std::string renderer;          // GL's, when it ran
  std::vector<PolyObv> poly;     // the enclosures, when any estimate was made
  std::vector<ObvRun> runs;      // poly first, then CPU, then GL, each in the order of ms
  std::vector<char> unresolved;  // per box: the cubemap's plan could not hold it
  // Per box, with exact: the exact OBV correctly rounded, and with rational, as a rational.
  std::vector<double> exact;
  std::vector<Rational> exact_rational;
  std::vector<double> exact_seconds;
};
// Estimates of each box's OBV. Every cubemap estimate gets its certified error from the
// polyhedral solver's enclosure. The exact OBV and each estimate's relative error are rounded
// from certify's enclosures (exact/filtered_solver.h) where those decide the rounding, and from
// the rationals elsewhere; `rational` also returns the rationals. Boxes must pass box_defect
// (read_boxes checks them).
Status estimate_obv(const Mesh& mesh, const std::vector<Obb>& boxes, const EstimateOptions& options,
                    ObvReport* report);

// ---- comparing the builders ----------------------------------------------------------------
struct CompareOptions {
  BuildOptions build;  // its method is ignored: the baseline and the variational tree are built
  bool rational = false;
  std::function<void(const std::string&)> progress;  // the certifications' stages
  // build.warning also gets the certifications' notes and warnings (a resumed certification is
  // said even where notes are not wanted).
  std::function<void(const exact::CertifyState&)>
      certify_saved;  // after each certification checkpoint
};
struct CompareResult {
  Tree trees[2];  // [0] obbtree, [1] variational
  exact::Certificate certificates[2];
  double build_seconds[2] = {0, 0};
  VariationalReport search;  // the variational build's counts
  // Layers 0..levels-1 of the deeper tree; a shallower tree's leaf layer repeats below its last.
  size_t levels = 0;
  // e of each tree over those layers with the deeper tree's weights: the nearest double, and the
  // rational where `rational` was asked or the enclosure could not round (e_rational[i]).
  double e[2] = {0, 0};
  bool e_rational[2] = {false, false};
  Rational e_exact[2];
  bool certified() const { return certificates[0].ok() && certificates[1].ok(); }
  // Layer `level` of tree 0 or 1 (its leaf layer below its last). Precondition: compare()
  // filled this in.
  const exact::LayerCertificate& layer(int tree, size_t level) const;
};
// Both builders on one mesh, both trees certified; `*result` is replaced. build.queries is
// refused (the recorded-query objective is build_tree's). With build.checkpoint, the variational
// build keeps its state there as build_tree does, and each certification its own folder
// (certify-obbtree/, certify-variational/).
Status compare(const Mesh& mesh, const CompareOptions& options, CompareResult* result);
// The files compare keeps in its checkpoint folder, relative to it.
std::vector<std::string> compare_checkpoint_files();

}  // namespace vobb
