// vobb export TREE --level L -o boxes.obj|ply: the boxes of one layer as a mesh.
#include <cstdio>
#include <memory>
#include <string>

#include "app/cli_support.h"
#include "app/command.h"
#include "common/box_export.h"
#include "common/text_util.h"
#include "common/tree_io.h"

namespace vobb::app {

namespace {

class ExportCommand final : public Command {
 public:
  CLI::App* add(CLI::App& app) override {
    CLI::App* c = app.add_subcommand("export", "Write the boxes of one layer as OBJ or PLY");
    c->add_option("TREE", tree_path_, "Tree file")->required();
    c->add_option("--level", level_, "Layer to export")->required()->transform(kCount);
    c->add_option("-o,--output", out_, "boxes.obj or boxes.ply")->required()->check(kPath);
    return c;
  }

  Status check_outputs() const override {
    Status s = check_output_is_not_input("-o", out_, {tree_path_});
    if (s) s = check_output_is_writable("-o", out_);
    if (s) s = check_box_export_path(out_);
    return s;
  }

  int run() override {
    Tree tree;
    Status s = read_tree(tree_path_, &tree);
    if (!s) return refuse(s);
    if (level_ < 0 || level_ > tree.depth)
      return refuse(Status::error("--level " + std::to_string(level_) + ": " +
                                  basename_of(tree_path_) + " has levels 0 to " +
                                  std::to_string(tree.depth)));
    s = export_layer(tree, level_, out_);
    if (!s) return could_not_finish(s);  // the level and the format were checked before
    std::fprintf(stderr, "vobb: layer %d (%zu boxes) -> %s\n", level_, layer(tree, level_).size(),
                 out_.c_str());
    return kExitOk;
  }

 private:
  std::string tree_path_, out_;
  int level_ = 0;
};

}  // namespace

std::unique_ptr<Command> export_command() { return std::make_unique<ExportCommand>(); }

}  // namespace vobb::app
