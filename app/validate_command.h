// `vobb validate [--suite quick|full] [--out DIR] [--meshes DIR] [--cpu-only]`: the validation
// suite (validate/validation_suite.h). Thin: parses, calls run_validation_suite, prints the
// checks. Exit 0 when every check passes, 1 when one fails, 2 on bad input (one line).
#pragma once

#include <CLI/CLI.hpp>
#include <string>

namespace vobb::app {

struct ValidateFlags {
  std::string suite = "quick";
  std::string out;     // default: validation-<suite> in the working folder
  std::string meshes;  // default: data/real, else the source tree's data/real
  bool cpu_only = false;
  bool quiet = false;
};

// Registers the subcommand on `app`; `flags` must outlive the parse.
CLI::App* add_validate_command(CLI::App& app, ValidateFlags* flags);

// Runs it; returns the exit code.
int run_validate_command(const ValidateFlags& flags);

}  // namespace vobb::app
