// vobb — the command line: registers the commands (one file each under app/) and runs the one
// named on the line (command.h). Exit codes (DESIGN §7): 0 ok, 1 a check failed, 2 bad input or
// usage, 3 the run could not finish; with a one-line reason on stderr.
#include <csignal>
#include <memory>
#include <utility>
#include <vector>

#include "app/command.h"
#include "common/io/assimp_reader.h"
#include "vobb/config.h"
#include "vobb/gl.h"

int main(int argc, char** argv) {
  // A reader that closes the pipe early (vobb info M | head -1) makes a write fail with EPIPE,
  // which ends the run with one line and exit 3, instead of killing it silently with SIGPIPE.
  std::signal(SIGPIPE, SIG_IGN);
  vobb::enable_gl();
#if VOBB_HAVE_ASSIMP
  vobb::enable_assimp();
#endif
  std::vector<std::unique_ptr<vobb::app::Command>> commands;
  commands.push_back(vobb::app::info_command());
  commands.push_back(vobb::app::build_command());
  commands.push_back(vobb::app::certify_command());
  commands.push_back(vobb::app::obv_command());
  commands.push_back(vobb::app::compare_command());
  commands.push_back(vobb::app::validate_command());
  commands.push_back(vobb::app::collide_command());
  commands.push_back(vobb::app::export_command());
  return vobb::app::run_command_line(argc, argv, std::move(commands));
}
