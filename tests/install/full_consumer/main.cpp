// vobb_full_consumer MESH TREE PNG: through every component of an installed vobb, checks each
// result against its contract (exit 1 and a line on stderr otherwise):
// - GL: estimates of the tree's level-2 boxes by the GL estimator and the CPU twin, each within
//   its certified error of the exact OBV (compared as rationals), and a figure of a comparison;
// - collision: the static experiment on TREE, every answer equal to brute force and to FCL's;
// - assimp: the mesh written as assimp's RAW format reads back as the same solid.
#include <vobb/gl.h>
#include <vobb/vobb.h>

#include <cstdio>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "common/io/assimp_reader.h"
#include "common/solidity.h"
#include "validate/collision/collision_experiment.h"

namespace {

int failures = 0;

void check(bool ok, const std::string& what) {
  if (!ok) {
    std::fprintf(stderr, "vobb_full_consumer: FAILED: %s\n", what.c_str());
    ++failures;
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 4) return std::fprintf(stderr, "usage: vobb_full_consumer MESH TREE PNG\n"), 2;
  vobb::enable_gl();
  vobb::enable_assimp();
  vobb::LoadedMesh solid;
  vobb::Tree tree;
  if (!vobb::load_solid(argv[1], &solid) || !vobb::read_tree(argv[2], &tree)) return 1;
  const vobb::Mesh& mesh = solid.mesh;

  std::vector<vobb::Obb> boxes;
  for (int32_t id : vobb::layer(tree, 2)) boxes.push_back(tree.nodes[id].box);
  vobb::EstimateOptions estimate;
  estimate.gl = estimate.cpu = estimate.exact = estimate.rational = true;
  estimate.ms = {8, 32};
  vobb::ObvReport report;
  const vobb::Status s = vobb::estimate_obv(mesh, boxes, estimate, &report);
  check(s.is_ok(), "estimate_obv: " + s.message());
  check(report.runs.size() == 4, "estimate_obv: CPU and GL at two m each");
  for (const vobb::ObvRun& run : report.runs)
    for (size_t i = 0; i < boxes.size(); ++i) {
      check(report.exact[i] == vobb::to_double_nearest(report.exact_rational[i]),
            "estimate_obv: the exact OBV's double is the rational's nearest, box " +
                std::to_string(i));
      vobb::Rational d = vobb::Rational(run.obv[i]) - report.exact_rational[i];
      if (d < 0) d = -d;
      check(d <= vobb::Rational(run.bound[i]),
            run.backend + " within its certified error, box " + std::to_string(i));
    }

  vobb::CompareOptions compare;
  compare.build.depth = 2;
  compare.build.m = 8;
  vobb::CompareResult result;
  check(vobb::compare(mesh, compare, &result).is_ok() && result.certified(),
        "compare: both trees certified");
  vobb::RgbaImage image;
  vobb::CompareFigure figure;
  check(vobb::draw_compare_figure(mesh, result, "y", nullptr, &image, &figure).is_ok() &&
            vobb::write_png(argv[3], image).is_ok(),
        "figure drawn and written");
  // In a context made ahead (compare --figure's way), twice: the same pixels.
  std::unique_ptr<vobb::FigureContext> context;
  check(vobb::FigureContext::create(&context).is_ok(), "figure context made ahead");
  for (int k = 0; k < 2; ++k) {
    vobb::RgbaImage again;
    vobb::CompareFigure f;
    check(
        vobb::draw_compare_figure(mesh, result, "y", nullptr, &again, &f, context.get()).is_ok() &&
            again.width == image.width && again.height == image.height && again.rgba == image.rgba,
        "figure drawn in a context made ahead, the same pixels");
  }
  vobb::CompareResult spoiled = result;  // a child that is no node: refused, not drawn
  spoiled.trees[1].nodes[0].children[0] = 100000000;
  const vobb::Status refused =
      vobb::draw_compare_figure(mesh, spoiled, "y", nullptr, &image, &figure);
  check(!refused.is_ok() && refused.message().find("bad child 100000000") != std::string::npos,
        "figure of a broken tree refused: " + refused.message());

  vobb::collision::ExperimentOptions collide;
  collide.dynamic = false;
  collide.colliders = 50;
  vobb::collision::ExperimentReport experiment;
  const vobb::Status ran =
      vobb::collision::run_collision_experiment(mesh, {{"tree", &tree}}, collide, &experiment);
  check(ran.is_ok(), "collision experiment: " + ran.message());
  check(experiment.queries == 50 && experiment.brute_force_agrees,
        "collision: 50 queries, all agree with brute force");
  check(experiment.trees.size() == 1 && experiment.trees[0].fcl.available &&
            experiment.trees[0].fcl.answer_disagreements == 0 &&
            experiment.trees[0].fcl.face_disagreements == 0,
        "collision: FCL agrees");

  // Assimp's RAW format: nine numbers per triangle. Read back in single precision; the mesh's
  // coordinates are small integers and halves (vobb-make-analytic's torus), exact in float.
  const std::string raw = std::string(argv[3]) + ".raw";
  {
    std::ofstream out(raw);
    for (size_t f = 0; f < mesh.faces.size(); ++f) {
      for (int k = 0; k < 3; ++k)
        for (int c = 0; c < 3; ++c) out << mesh.corner(f, k)[c] << ' ';
      out << '\n';
    }
  }
  vobb::LoadedMesh again;
  check(vobb::load_solid(raw, &again).is_ok() && again.single_precision,
        "assimp: RAW read as a solid");
  check(vobb::check_solidity(again.mesh).volume == vobb::check_solidity(mesh).volume,
        "assimp: the same volume");
  std::remove(raw.c_str());
  return failures ? 1 : 0;
}
