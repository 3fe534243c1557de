// Uses every installed vobb library once, through installed headers only, and checks each
// result against its contract (exit 1 and a line on stderr otherwise):
//   vobb_consumer DIR   writes DIR/torus.off and DIR/tree.json, prints "e <rational>" on stdout.
// The exact checks compare rationals; the estimator's only tolerances are its stated bounds.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "common/exact_predicates.h"
#include "common/io/mesh_io.h"
#include "common/sha256.h"
#include "common/solidity.h"
#include "common/tree_io.h"
#include "data/analytic_meshes.h"
#include "exact/certify.h"
#include "exact/outer_volume.h"
#include "fast/cpu_estimator.h"
#include "fast/gl_estimator.h"
#include "fast/obbtree_builder.h"
#include "fast/texel_plan.h"
#include "validate/box_corpus.h"
#include "validate/collision/collision_experiment.h"

namespace {

int failures = 0;

void check(bool ok, const std::string& what) {
  if (!ok) {
    std::fprintf(stderr, "vobb_consumer: FAILED: %s\n", what.c_str());
    ++failures;
  }
}

vobb::Rational abs_diff(double estimate, const vobb::Rational& exact) {
  vobb::Rational d = vobb::Rational(estimate) - exact;
  return d < 0 ? vobb::Rational(-d) : d;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: vobb_consumer DIR\n");
    return 2;
  }
  const std::string dir = argv[1];
  const auto torus = vobb::analytic::polygonal_torus();

  // Mesh I/O and solidity: the written file reads back as a solid of the closed-form volume.
  const std::string mesh_path = dir + "/torus.off";
  check(vobb::save_mesh(torus.mesh, mesh_path, vobb::MeshFormat::kOff).is_ok(), "save_mesh");
  vobb::LoadedMesh loaded;
  const vobb::Status read = vobb::load_mesh(mesh_path, &loaded);
  check(read.is_ok(), "load_mesh: " + read.message());
  if (!read.is_ok()) return 1;
  const vobb::Mesh& mesh = loaded.mesh;
  const vobb::SolidityReport solidity = vobb::check_solidity(mesh);
  check(solidity.defects.empty() && solidity.volume_known, "check_solidity: a solid");
  check(solidity.volume == torus.volume, "exact volume == closed form");

  // The baseline tree, written as a tree file the installed `vobb` reads.
  vobb::ObbTreeOptions tree_options;
  tree_options.depth = 3;
  vobb::Tree tree = vobb::build_obbtree(mesh, tree_options);
  tree.mesh_sha256 = vobb::mesh_sha256(mesh);
  check(vobb::write_tree(tree, dir + "/tree.json").is_ok(), "write_tree");

  // Exact certificate: conservative, sum OBV >= OMV on every layer; with the rationals, for the
  // comparison with the installed command's.
  vobb::exact::CertifyOptions certify_options;
  certify_options.rational = true;
  const vobb::exact::Certificate cert = vobb::exact::certify(mesh, tree, certify_options);
  check(cert.ok(), "certify: ok");
  check(cert.layers.size() == 4, "certify: one layer per level 0..3");

  // Estimators on a box corpus: the CPU twin within its rigorous resolution bound of the exact
  // OBV, and the GL estimator within its float32 deviation bound of the CPU twin.
  const int m = 16;
  const std::vector<vobb::Obb> boxes = vobb::validate::box_corpus(mesh, vobb::validate::BoxSize::kMid, 4, 7);
  check(boxes.size() == 4, "box_corpus: 4 boxes");
  const vobb::exact::ClipSolver clip(mesh);
  const vobb::CpuObvEstimator cpu(mesh);
  const vobb::BoxPlanner planner(mesh);
  const std::vector<double> cpu_values = cpu.estimate(boxes, m);
  std::unique_ptr<vobb::GlObvEstimator> gl;
  const vobb::Status gl_status = vobb::GlObvEstimator::create(mesh, &gl);
  check(gl_status.is_ok(), "GL estimator: " + gl_status.message());
  const std::vector<double> gl_values = gl ? gl->estimate(boxes, m) : std::vector<double>();
  for (size_t i = 0; i < boxes.size(); ++i) {
    const vobb::BoxPlan plan = planner.plan(boxes[i], m);
    const vobb::Rational exact = clip.obv(boxes[i]);
    check(abs_diff(cpu_values[i], exact) <= vobb::Rational(vobb::resolution_bound(plan, m)),
          "CPU twin within resolution_bound of the exact OBV, box " + std::to_string(i));
    if (gl)
      check(std::abs(gl_values[i] - cpu_values[i]) <= vobb::gl_deviation_bound(plan, m),
            "GL within gl_deviation_bound of the CPU twin, box " + std::to_string(i));
  }

  // The collision experiment, static: every answer equals brute force, also through FCL.
  vobb::collision::ExperimentOptions collide;
  collide.dynamic = false;
  collide.colliders = 50;
  vobb::collision::ExperimentReport report;
  const vobb::Status ran = vobb::collision::run_collision_experiment(mesh, {{"tree", &tree}}, collide, &report);
  check(ran.is_ok(), "collision experiment: " + ran.message());
  check(report.queries == 50 && report.brute_force_agrees, "collision: 50 queries, all agree with brute force");
  check(report.trees.size() == 1 && report.trees[0].fcl.available &&
            report.trees[0].fcl.answer_disagreements == 0 && report.trees[0].fcl.face_disagreements == 0,
        "collision: FCL agrees on the loaded tree");

  std::printf("e %s\n", cert.weighted_error.get_str().c_str());
  return failures ? 1 : 0;
}
