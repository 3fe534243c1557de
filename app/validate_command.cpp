#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "app/cli_support.h"
#include "app/command.h"
#include "validate/validation_suite.h"

namespace vobb::app {

namespace {

struct ValidateFlags {
  std::string suite = "quick";
  std::string out;     // default: validation-<suite> in the working folder
  std::string meshes;  // default: data/real, else the source tree's data/real
  bool cpu_only = false;
  bool quiet = false;
};

CLI::App* add_validate_command(CLI::App& app, ValidateFlags* f) {
  CLI::App* v = app.add_subcommand("validate",
                                   "Validation suite: error against m, error against time, sum OBV "
                                   ">= OMV, stiff cases; CSV, PNG, summary.md");
  v->add_option("--suite", f->suite,
                "quick (for CI, about 30 s on 2 cores) or full (under an hour)")
      ->capture_default_str()
      ->check(CLI::IsMember({"quick", "full"}));
  v->add_option("--out", f->out, "Output folder (default: validation-<suite>)")->check(app::kPath);
  v->add_option("--meshes", f->meshes,
                std::string("Folder of the real meshes (default: data/real in the working folder "
                            "if there is one, else ") +
                    VOBB_SOURCE_MESH_DIR + ", where this build's data/fetch_meshes.sh puts them)");
  v->add_flag("--cpu-only", f->cpu_only, "Skip the GL estimator (the CPU twin only)");
  v->add_flag("--quiet", f->quiet, "No progress on stderr");
  return v;
}

int run_validate_command(const ValidateFlags& f) {
  validate::SuiteOptions o;
  o.suite = f.suite == "full" ? validate::SuiteKind::kFull : validate::SuiteKind::kQuick;
  o.out_dir = f.out.empty() ? "validation-" + f.suite : f.out;
  o.mesh_dir = f.meshes;
  if (o.mesh_dir.empty())
    o.mesh_dir = std::filesystem::is_directory("data/real") ? "data/real" : VOBB_SOURCE_MESH_DIR;
  o.want_gl = !f.cpu_only;
  o.command = "vobb validate --suite " + f.suite + (f.out.empty() ? "" : " --out " + f.out) +
              (f.meshes.empty() ? "" : " --meshes " + f.meshes) + (f.cpu_only ? " --cpu-only" : "");
  if (!f.quiet)
    o.progress = [](const std::string& line) {
      std::fprintf(stderr, "validate: %s\n", line.c_str());
    };
  // The output folder, or the nearest folder above it that exists (where it will be made),
  // must take files before the suite runs for minutes: a folder such as /sys/kernel exists and
  // takes none. Nothing is made here.
  {
    namespace fs = std::filesystem;
    std::error_code ec;
    fs::path at = o.out_dir;
    while (!at.empty() && !fs::exists(fs::symlink_status(at, ec)) && at != at.parent_path())
      at = at.parent_path();
    if (at.empty()) at = ".";
    if (!fs::is_directory(at, ec))
      return refuse(Status::error("--out " + o.out_dir + ": " + at.string() + " is not a folder"));
    if (Status w = check_folder_takes_files("--out " + o.out_dir, at.string()); !w)
      return refuse(w);
  }
  validate::SuiteReport report;
  const Status s = validate::run_validation_suite(o, &report);
  if (!s) return report.ran ? could_not_finish(s) : refuse(s);
  for (const validate::SuiteCheck& c : report.checks)
    std::printf("%-4s %-50s %s\n", c.passed ? "ok" : "FAIL", c.name.c_str(), c.detail.c_str());
  for (const std::string& n : report.notes) std::printf("note: %s\n", n.c_str());
  std::printf("%s suite: %s in %.1f s; summary: %s\n", f.suite.c_str(),
              report.ok() ? "all checks passed" : "CHECKS FAILED", report.seconds,
              report.summary_path.c_str());
  return report.ok() ? kExitOk : kExitCheckFailed;
}

class ValidateCommand final : public Command {
 public:
  CLI::App* add(CLI::App& app) override { return add_validate_command(app, &f_); }
  int run() override { return run_validate_command(f_); }

 private:
  ValidateFlags f_;
};

}  // namespace

std::unique_ptr<Command> validate_command() { return std::make_unique<ValidateCommand>(); }

}  // namespace vobb::app
