// One `vobb` command: it declares its flags, checks its outputs once they are parsed, and runs.
// main.cpp registers the commands and runs the one named on the line.
#pragma once

#include <CLI/CLI.hpp>
#include <memory>
#include <vector>

#include "common/status.h"

namespace vobb::app {

class Command {
 public:
  virtual ~Command() = default;
  // Adds the command and its flags to `app`; returns it.
  virtual CLI::App* add(CLI::App& app) = 0;
  // After parsing, before any work: the outputs (not an input, writable, not a checkpoint's).
  virtual Status check_outputs() const { return Status::ok(); }
  // Threads asked for with --threads; 0: every core this process may use.
  virtual int threads() const { return 0; }
  // The exit code (cli_support.h).
  virtual int run() = 0;
};

// Parses the line, runs the command it names after its output checks, with --threads applied,
// and returns the exit code: usage errors, bad input, a thrown exception (out of memory, a
// library's internal check) and an unwritable standard output each end in one line on stderr.
int run_command_line(int argc, char** argv, std::vector<std::unique_ptr<Command>> commands);

std::unique_ptr<Command> info_command();
std::unique_ptr<Command> build_command();
std::unique_ptr<Command> certify_command();
std::unique_ptr<Command> obv_command();
std::unique_ptr<Command> compare_command();
std::unique_ptr<Command> validate_command();
std::unique_ptr<Command> collide_command();
std::unique_ptr<Command> export_command();

}  // namespace vobb::app
