// vobb build MESH -o TREE: builds a tree (vobb/vobb.h, build_tree) and writes it as JSON.
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>

#include "app/build_flags.h"
#include "app/cli_support.h"
#include "app/command.h"
#include "common/io/mesh_report.h"
#include "common/stopwatch.h"
#include "common/tree_io.h"

namespace vobb::app {

namespace {

class BuildCommand final : public Command {
 public:
  CLI::App* add(CLI::App& app) override {
    cmd_ = app.add_subcommand("build", "Build an OBB tree and write it as JSON");
    cmd_->add_option("MESH", mesh_, "Solid mesh file")->required();
    cmd_->add_option("-o,--output", out_, "Tree file to write")->required()->check(kPath);
    add_build_flags(cmd_, &flags_, /*compare=*/false);
    return cmd_;
  }

  Status check_outputs() const override {
    std::vector<std::string> inputs = flags_.queries;
    inputs.push_back(mesh_);
    Status s = check_output_is_not_input("-o", out_, inputs);
    if (s) s = check_build_flags(cmd_, flags_);
    if (s)
      s = check_output_is_not_checkpoint("-o", out_, flags_.options.checkpoint, {"state.json"});
    if (s) s = check_output_is_writable("-o", out_);
    return s;
  }

  int threads() const override { return flags_.threads; }

  int run() override {
    const auto t0 = std::chrono::steady_clock::now();
    BuildOptions o = build_options(flags_);
    // Refused before the mesh is read: the options as they will be once the query files are
    // (one stand-in collider per file, a unit sphere).
    BuildOptions shape = o;
    collision::Collider stand_in;
    stand_in.radius = 1;
    shape.queries.assign(flags_.queries.size(), stand_in);
    Status s = check_build_options(shape);
    if (!s) return refuse(s);
    LoadedMesh loaded;
    s = load_input_solid(mesh_, &loaded);
    if (!s) return refuse(s);
    if (!flags_.queries.empty()) {
      s = read_queries(loaded.mesh, flags_.queries, &o);
      if (!s) return refuse(s);
    }
    Tree tree;
    BuildReport report;
    s = build_tree(loaded.mesh, o, &tree, &report);
    if (!s) return refuse(s);
    s = write_tree(tree, out_);
    if (!s) return could_not_finish(s);  // its folder took a file when the run started
    std::fprintf(stderr, "vobb: %s tree of %zu nodes, depth %d, arity %d, in %.3f s -> %s\n",
                 tree.method.c_str(), tree.nodes.size(), tree.depth, tree.arity, seconds_since(t0),
                 out_.c_str());
    return kExitOk;
  }

 private:
  CLI::App* cmd_ = nullptr;
  std::string mesh_, out_;
  BuildFlags flags_;
};

}  // namespace

std::unique_ptr<Command> build_command() { return std::make_unique<BuildCommand>(); }

}  // namespace vobb::app
