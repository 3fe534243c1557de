// The validation suite (DESIGN §6), run as `vobb validate [--suite quick|full]
// [--out DIR]`: the discretization study (discretization_study.h) with its stated bound B(m)
// and the Richardson estimate, error against run time for every solver, the upper bound
// sum OBV >= OMV on the layers of both builders' trees (upper_bound_study.h), and the stiff
// and extreme cases (stiff_cases.h). Writes, into DIR, CSV files, PNG plots (gnuplot, run as an
// external program; without it the plots are skipped with one line) and summary.md, which
// embeds the plots and tables. Every file appears atomically (temp + rename).
//
// quick: a few boxes per (mesh, size) on dino, elephant (fit) and knot1, armadillo (held out),
// trees of depth 3 on elephant; for CI, well under 5 minutes on 2 cores.
// full: more boxes, more held-out meshes, trees of depth 8 on dino, elephant and knot1.
//
// The checks, each of which fails the run (exit 1 from the command line):
//  - every estimate finite and within its rigorous per-box bound R(m) (a backstop against
//    gross errors: R(m) stays near the box's volume at every m);
//  - GL within its derived float bound of the CPU twin, box by box; GL ran, unless the run
//    was asked for the CPU twin alone (want_gl false) or GL is switched off (VOBB_GL=off);
//  - the median relative error converges at a fitted rate of at most -1.5 (see suite.cpp);
//  - the median relative error at m = 32 per box size within 2x the DESIGN §4 prototype;
//  - the held-out violation rate of B(m) at most its stated level alpha = 5 %;
//  - Nef and clipping equal as rationals on the boxes both ran (at least one);
//  - sum OBV >= OMV exactly on every layer of every tree, the OMV's two paths agreeing, and
//    every tree conservative;
//  - every stiff case as expected.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "common/status.h"
#include "validate/estimators.h"

namespace vobb::validate {

enum class SuiteKind { kQuick, kFull };

struct SuiteOptions {
  SuiteKind suite = SuiteKind::kQuick;
  std::string out_dir;           // created when missing
  std::string mesh_dir;          // holds dino.off, elephant.off, knot1.off, armadillo.off, ...
  bool want_gl = true;           // false: the CPU twin only (GL rows are then absent, and said so)
  std::string command;           // the command line, recorded in summary.md
  EstimatePerturbation perturb;  // tests only: breaks the estimator on purpose
  std::function<void(const std::string&)> progress;
};

struct SuiteCheck {
  std::string name;
  bool passed = false;
  std::string detail;
};

struct SuiteReport {
  std::vector<SuiteCheck> checks;
  std::vector<std::string> notes;  // e.g. "gnuplot not found: plots skipped"
  double seconds = 0;
  std::string summary_path;
  bool ran = false;  // the inputs were taken and the studies ran
  bool ok() const;
};

// Bad input (a missing mesh, an output folder that cannot be made) gives a failed Status with
// one line before any study runs (`ran` false). A file that cannot be written after the studies
// (a disk that fills) gives one too, with `ran` true, and the files written before it stay.
// Otherwise the report says which checks passed.
Status run_validation_suite(const SuiteOptions& options, SuiteReport* report);

}  // namespace vobb::validate
