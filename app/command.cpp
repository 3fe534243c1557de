#include "app/command.h"

#include <tbb/global_control.h>

#include <cstdio>
#include <exception>
#include <iostream>
#include <new>
#include <optional>
#include <string>

#include "app/cli_support.h"
#include "vobb/config.h"

namespace vobb::app {

namespace {

// The command named on the line, or "" when none; an unknown one is refused with the list, and
// so is an option before the command other than vobb's own (--help, --version).
bool named_command(int argc, char** argv, CLI::App& app, std::string* command) {
  if (argc < 2) return true;
  if (argv[1][0] == '-') {
    const std::string flag = argv[1];
    if (flag == "-h" || flag == "--help" || flag == "--version") return true;
    std::fprintf(stderr,
                 "vobb: usage: unknown option '%s' before the command; a command's options "
                 "follow it (see vobb --help)\n",
                 one_line(flag).c_str());
    return false;
  }
  std::string names;
  for (const CLI::App* sc : app.get_subcommands([](CLI::App*) { return true; })) {
    names += (names.empty() ? "" : ", ") + sc->get_name();
    if (sc->get_name() == argv[1]) *command = argv[1];
  }
  if (!command->empty()) return true;
  std::fprintf(stderr, "vobb: usage: unknown command '%s'; the commands are %s (see vobb --help)\n",
               one_line(argv[1]).c_str(), names.c_str());
  return false;
}

}  // namespace

int run_command_line(int argc, char** argv, std::vector<std::unique_ptr<Command>> commands) {
  CLI::App app{
      "vobb: tight oriented-bounding-box trees for solid meshes, with exact outer volumes"};
  app.require_subcommand(1);
  app.set_version_flag("--version", VOBB_VERSION);
  std::vector<CLI::App*> parsers;
  for (auto& c : commands) parsers.push_back(c->add(app));

  // A usage error of a known command points to that command's help.
  std::string command;
  if (!named_command(argc, argv, app, &command)) return kExitBadInput;
  // Help and the version go to standard output through CLI11 (std::cout): one that cannot
  // be written is no success either.
  auto said = [](int rc) {
    if (std::cout.flush()) return rc;
    std::fprintf(stderr, "vobb: cannot write standard output\n");
    return kExitCouldNotFinish;
  };
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return said(app.exit(e));
  } catch (const CLI::CallForAllHelp& e) {
    return said(app.exit(e));
  } catch (const CLI::CallForVersion& e) {
    return said(app.exit(e));
  } catch (const CLI::ParseError& e) {
    std::string what = e.what();
    for (char& c : what)
      if (c == '\n') c = ' ';
    const std::string help = command.empty() ? "vobb --help" : "vobb " + command + " --help";
    std::fprintf(stderr, "vobb%s: usage: %s (see %s)\n",
                 command.empty() ? "" : (" " + command).c_str(), one_line(what).c_str(),
                 help.c_str());
    return kExitBadInput;
  }
  Command* run = nullptr;
  for (size_t i = 0; i < commands.size(); ++i)
    if (parsers[i]->parsed()) run = commands[i].get();
  if (run == nullptr) return kExitBadInput;
  if (const Status s = run->check_outputs(); !s) return refuse(s);
  // The values, and so the trees and certificates, do not depend on how many threads.
  std::optional<tbb::global_control> thread_limit;
  if (run->threads() > 0)
    thread_limit.emplace(tbb::global_control::max_allowed_parallelism,
                         static_cast<size_t>(run->threads()));
  // Bad input never throws (it is a Status); what can is running out of memory, or a library's
  // own assertion (CGAL's). Either ends the run with one line, not an abort.
  const std::string who = command.empty() ? "vobb" : "vobb " + command;
  int rc;
  try {
    rc = run->run();
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "%s: out of memory\n", who.c_str());
    return kExitCouldNotFinish;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: internal error: %s\n", who.c_str(), one_line(e.what()).c_str());
    return kExitCouldNotFinish;
  }
  // A report printed to a full disk or a closed stream must not end as a success.
  if (std::fflush(stdout) != 0 || std::ferror(stdout)) {
    std::fprintf(stderr, "%s: cannot write standard output\n", who.c_str());
    return kExitCouldNotFinish;
  }
  // A run that ends with its results names the single-precision read (say_pending_notes); a
  // refusal or a run that could not finish keeps to its one line.
  if (rc == kExitOk || rc == kExitCheckFailed) say_pending_notes();
  return rc;
}

}  // namespace vobb::app
