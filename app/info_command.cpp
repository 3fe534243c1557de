// vobb info MESH: counts, exact enclosed volume, bounding box and solidity verdict.
#include <cstdio>
#include <memory>
#include <string>

#include "app/cli_support.h"
#include "app/command.h"
#include "common/io/mesh_report.h"

namespace vobb::app {

namespace {

class InfoCommand final : public Command {
 public:
  CLI::App* add(CLI::App& app) override {
    CLI::App* c = app.add_subcommand(
        "info", "Counts, exact enclosed volume, bounding box and solidity verdict");
    c->add_option("MESH", mesh_, "Mesh file (OFF, OBJ, PLY, STL; others through assimp)")
        ->required();
    c->add_flag("--json", json_, "Print JSON");
    c->add_flag("--rational", rational_, "Also print the exact volume as a rational");
    return c;
  }

  int run() override {
    MeshReport report;
    Status s = inspect_mesh(mesh_, &report);
    if (!s) return refuse(s);
    const std::string out =
        json_ ? format_report_json(report, rational_) : format_report_text(report, rational_);
    std::fputs(out.c_str(), stdout);
    s = solidity_status(report);
    return s ? kExitOk : refuse(s);
  }

 private:
  std::string mesh_;
  bool json_ = false, rational_ = false;
};

}  // namespace

std::unique_ptr<Command> info_command() { return std::make_unique<InfoCommand>(); }

}  // namespace vobb::app
