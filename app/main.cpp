// vobb — the command line. Thin: each subcommand parses its arguments, calls the libraries
// and prints. Exit codes (DESIGN §7): 0 ok, 1 a check failed, 2 bad input or usage, with a
// one-line reason on stderr naming the file and the defect.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <string>

#include "common/box_export.h"
#include "common/io/mesh_report.h"
#include "common/sha256.h"
#include "common/tree_io.h"
#include "fast/obbtree_builder.h"
#include "vobb/config.h"

namespace {

constexpr int kExitOk = 0;
constexpr int kExitBadInput = 2;

int refuse(const vobb::Status& s) {
  std::fprintf(stderr, "vobb: %s\n", s.message().c_str());
  return kExitBadInput;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

int run_info(const std::string& mesh, bool json, bool rational) {
  vobb::MeshReport report;
  vobb::Status s = vobb::inspect_mesh(mesh, &report);
  if (!s) return refuse(s);
  const std::string out = json ? vobb::format_report_json(report, rational)
                               : vobb::format_report_text(report, rational);
  std::fputs(out.c_str(), stdout);
  s = vobb::solidity_status(report);
  return s ? kExitOk : refuse(s);
}

int run_build(const std::string& mesh_path, const std::string& out, const std::string& method,
              int depth, int arity) {
  if (method != "obbtree")
    return refuse(vobb::Status::error("method '" + method +
                                      "' is not available in this build (available: obbtree)"));
  const auto t0 = std::chrono::steady_clock::now();
  vobb::LoadedMesh loaded;
  vobb::Status s = vobb::load_solid(mesh_path, &loaded);
  if (!s) return refuse(s);
  vobb::ObbTreeOptions opt;
  opt.depth = depth;
  opt.arity = arity;
  vobb::Tree tree = vobb::build_obbtree(loaded.mesh, opt);
  tree.mesh_sha256 = vobb::mesh_sha256(loaded.mesh);
  s = vobb::write_tree(tree, out);
  if (!s) return refuse(s);
  std::fprintf(stderr, "vobb: %s tree of %zu nodes, depth %d, arity %d, in %.3f s -> %s\n",
               tree.method.c_str(), tree.nodes.size(), tree.depth, tree.arity, seconds_since(t0),
               out.c_str());
  return kExitOk;
}

int run_export(const std::string& tree_path, int level, const std::string& out) {
  vobb::Tree tree;
  vobb::Status s = vobb::read_tree(tree_path, &tree);
  if (!s) return refuse(s);
  s = vobb::export_layer(tree, level, out);
  if (!s) return refuse(s);
  std::fprintf(stderr, "vobb: layer %d (%zu boxes) -> %s\n", level, vobb::layer(tree, level).size(),
               out.c_str());
  return kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"vobb: tight oriented-bounding-box trees for solid meshes, with exact outer volumes"};
  app.require_subcommand(1);
  app.set_version_flag("--version", VOBB_VERSION);

  std::string mesh, tree_path, out, method = "obbtree";
  bool json = false, rational = false;
  int depth = 8, arity = 2, level = 0;

  CLI::App* info = app.add_subcommand("info", "Counts, exact enclosed volume, bounding box and solidity verdict");
  info->add_option("MESH", mesh, "Mesh file (OFF, OBJ, PLY, STL; others through assimp)")->required();
  info->add_flag("--json", json, "Print JSON");
  info->add_flag("--rational", rational, "Also print the exact volume as a rational");

  CLI::App* build = app.add_subcommand("build", "Build an OBB tree and write it as JSON");
  build->add_option("MESH", mesh, "Solid mesh file")->required();
  build->add_option("-o,--output", out, "Tree file to write")->required();
  build->add_option("--method", method, "obbtree (the OBB-Tree baseline)")->capture_default_str();
  build->add_option("--depth", depth, "Deepest level; the root is level 0")
      ->capture_default_str()->check(CLI::Range(0, 30));
  build->add_option("--arity", arity, "Most children per node")
      ->capture_default_str()->check(CLI::Range(2, 64));

  CLI::App* exp = app.add_subcommand("export", "Write the boxes of one layer as OBJ or PLY");
  exp->add_option("TREE", tree_path, "Tree file")->required();
  exp->add_option("--level", level, "Layer to export")->required();
  exp->add_option("-o,--output", out, "boxes.obj or boxes.ply")->required();

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::string what = e.what();
    for (char& c : what)
      if (c == '\n') c = ' ';
    std::fprintf(stderr, "vobb: usage: %s (see vobb --help)\n", what.c_str());
    return kExitBadInput;
  }
  if (info->parsed()) return run_info(mesh, json, rational);
  if (build->parsed()) return run_build(mesh, out, method, depth, arity);
  if (exp->parsed()) return run_export(tree_path, level, out);
  return kExitBadInput;
}
