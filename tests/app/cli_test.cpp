// End-to-end tests of the `vobb` command line: exit codes, one-line errors, no partial
// output, and the bad-input corpus in tests/data/bad.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>

#include "common/exact_predicates.h"
#include "common/sha256.h"
#include "common/tree_io.h"
#include "data/analytic_meshes.h"
#include "test_common.h"

namespace vobb {
namespace {

using test::CliRun;
using test::vobb_cli;
using test::vobb_cli_in;

size_t line_count(const std::string& s) { return std::count(s.begin(), s.end(), '\n'); }

using test::slurp;

// Every file in the corpus: exit 2, exactly one line on stderr naming the file and the
// defect phrase from EXPECTED.tsv; `build` on it writes no tree file.
TEST(CliBadInput, CorpusGivesExitTwoAndOneClearLine) {
  const std::string dir = test::data_dir() + "/bad";
  std::ifstream list(dir + "/EXPECTED.tsv");
  ASSERT_TRUE(list);
  std::string line;
  int cases = 0;
  while (std::getline(list, line)) {
    if (line.empty() || line[0] == '#') continue;
    const size_t tab = line.find('\t');
    const std::string file = line.substr(0, tab), phrase = line.substr(tab + 1);
    SCOPED_TRACE(file);
    const CliRun info = vobb_cli("info " + dir + "/" + file);
    EXPECT_EQ(info.code, 2);
    EXPECT_EQ(line_count(info.err), 1u) << info.err;
    EXPECT_NE(info.err.find(file), std::string::npos) << info.err;
    EXPECT_NE(info.err.find(phrase), std::string::npos) << info.err;
    const std::string out = test::temp_path("bad_tree.json");
    const CliRun build = vobb_cli("build " + dir + "/" + file + " -o " + out + " --method obbtree");
    EXPECT_EQ(build.code, 2);
    EXPECT_EQ(line_count(build.err), 1u) << build.err;
    EXPECT_FALSE(test::exists(out)) << "a tree was written for a bad mesh";
    ++cases;
  }
  EXPECT_GE(cases, 15);
}

TEST(CliBadInput, MissingFileDirectoryAndUsage) {
  CliRun r = vobb_cli("info /nonexistent/mesh.off");
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(line_count(r.err), 1u);
  EXPECT_NE(r.err.find("mesh.off: cannot open"), std::string::npos) << r.err;
  r = vobb_cli("info " + test::data_dir());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("is a directory"), std::string::npos) << r.err;
  for (const char* args :
       {"", "frobnicate", "info", "build x.off", "build x.off -o t.json --depth -1",
        "build x.off -o t.json --arity 1", "export t.json -o b.obj"}) {
    r = vobb_cli(args);
    EXPECT_EQ(r.code, 2) << args;
    EXPECT_EQ(line_count(r.err), 1u) << args << ": " << r.err;
  }
  // An unknown command is named back with the list of commands; a known command's usage
  // error names the command.
  r = vobb_cli("frobnicate");
  EXPECT_NE(r.err.find("unknown command 'frobnicate'; the commands are info, build"),
            std::string::npos)
      << r.err;
  // An option before the command is named as such, not taken for a missing argument.
  r = vobb_cli("-x info");
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(line_count(r.err), 1u) << r.err;
  EXPECT_NE(r.err.find("unknown option '-x' before the command"), std::string::npos) << r.err;
  r = vobb_cli("build x.off");
  EXPECT_EQ(r.err.rfind("vobb build: usage: ", 0), 0u) << r.err;
  EXPECT_NE(r.err.find("see vobb build --help"), std::string::npos) << r.err;
  // A bad margin is refused before the mesh is read, so the line names the flag, not x.off.
  for (const char* args :
       {"build x.off -o t.json --collider-margin -1", "build x.off -o t.json --collider-margin nan",
        "build x.off -o t.json --collider-margin 0.1 --method obbtree"}) {
    r = vobb_cli(args);
    EXPECT_EQ(r.code, 2) << args;
    EXPECT_EQ(line_count(r.err), 1u) << args << ": " << r.err;
    EXPECT_NE(r.err.find("--collider-margin"), std::string::npos) << args << ": " << r.err;
  }
  // Numbers are decimal: hexadecimal, blanks, infinities and text are refused, naming the flag;
  // a sign, a point and an exponent are taken.
  for (const char* value : {"0x10", "' 2'", "'2 '", "inf", "1e309", ".", "1e", "+", "2x", "1..2"}) {
    r = vobb_cli(std::string("build x.off -o t.json --time-budget ") + value);
    EXPECT_EQ(r.code, 2) << value;
    EXPECT_EQ(line_count(r.err), 1u) << value << ": " << r.err;
    EXPECT_NE(r.err.find("--time-budget"), std::string::npos) << value << ": " << r.err;
  }
  for (const char* value : {"2", "+2.5", ".5", "5.", "1e2", "2.5E-1"}) {
    r = vobb_cli(std::string("build x.off -o t.json --time-budget ") + value);
    EXPECT_EQ(r.code, 2) << value;  // taken: the missing mesh is what is refused
    EXPECT_NE(r.err.find("x.off"), std::string::npos) << value << ": " << r.err;
  }
  // An objective that is neither, and two objectives at once, before the mesh is read.
  for (const char* args : {"build x.off -o t.json --objective sum",
                           "build x.off -o t.json --objective omv --queries q.json",
                           "build x.off -o t.json --objective obv --queries q.json",
                           "build x.off -o t.json --objective obv --method obbtree"}) {
    r = vobb_cli(args);
    EXPECT_EQ(r.code, 2) << args;
    EXPECT_EQ(line_count(r.err), 1u) << args << ": " << r.err;
    EXPECT_NE(r.err.find("objective"), std::string::npos) << args << ": " << r.err;
  }
}

// The unit cube as OFF, scaled.
std::string write_cube(const std::string& name, double scale) {
  const std::string mesh = test::temp_path(name);
  std::ofstream f(mesh);
  f.precision(17);
  f << "OFF\n8 12 0\n";
  for (int i = 0; i < 8; ++i)
    f << scale * (i & 1) << " " << scale * ((i >> 1) & 1) << " " << scale * ((i >> 2) & 1) << "\n";
  f << "3 0 4 6\n3 0 6 2\n3 1 3 7\n3 1 7 5\n3 0 1 5\n3 0 5 4\n3 2 6 7\n3 2 7 3\n3 0 2 3\n3 0 3 1\n"
       "3 4 5 7\n3 4 7 6\n";
  return mesh;
}

// Numbers CLI11 would let through (NaN passes a range check; "-1" becomes 2^64 - 1 in an
// unsigned seed), an out-of-range --level, and a file name with a newline: one line, exit 2.
TEST(CliBadInput, NonFiniteAndNegativeNumbersAndOddNames) {
  const std::string mesh = write_cube("flags_cube.off", 1);
  const std::string tree = test::temp_path("flags_tree.json");
  ASSERT_EQ(vobb_cli("build " + mesh + " -o " + tree + " --method obbtree --depth 2").code, 0);
  const std::string out = test::temp_path("flags_out.json"), obj = test::temp_path("flags_out.obj");
  // Each case with the file it would write ("": compare writes to standard output, and the
  // figure's folder does not exist).
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"collide " + mesh + " " + tree + " --seconds nan --colliders 5 -o " + out, out},
      {"collide " + mesh + " " + tree + " --seed -1 --static --colliders 5 -o " + out, out},
      {"build " + mesh + " -o " + out + " --time-budget nan", out},
      {"build " + mesh + " -o " + out + " --seed -1", out},
      {"build " + mesh + " -o " + out + " --seed 18446744073709551616", out},
      {"compare " + mesh + " --seed 1e23 --depth 1", ""},
      {"export " + tree + " --level 3 -o " + obj, obj},
      {"compare " + mesh + " --depth 1 --backend cpu --figure /nonexistent/folder/f.png", ""}};
  for (const auto& [args, written] : cases) {
    std::remove(out.c_str());
    std::remove(obj.c_str());
    const CliRun r = vobb_cli(args);
    EXPECT_EQ(r.code, 2) << args;
    EXPECT_EQ(line_count(r.err), 1u) << args << ": " << r.err;
    if (!written.empty()) {
      EXPECT_FALSE(test::exists(written)) << args;
    }
  }
  const CliRun level = vobb_cli("export " + tree + " --level 3 -o " + obj);
  EXPECT_NE(level.err.find("--level 3"), std::string::npos) << level.err;
  // A newline in a file name is printed escaped, so the error stays one line.
  const CliRun odd = vobb_cli("info '" + test::temp_path("no\nsuch.off") + "'");
  EXPECT_EQ(odd.code, 2);
  EXPECT_EQ(line_count(odd.err), 1u) << odd.err;
  EXPECT_NE(odd.err.find("no\\x0asuch.off"), std::string::npos) << odd.err;
}

// An output that is one of the run's inputs, by another spelling of its path, is refused
// before anything runs, and the input is left as it was (it used to be replaced, exit 0).
TEST(CliBadInput, OutputThatIsAnInputIsRefused) {
  const std::string mesh = write_cube("same_cube.off", 1);
  const std::string tree = test::temp_path("same_tree.json");
  ASSERT_EQ(vobb_cli("build " + mesh + " -o " + tree + " --method obbtree --depth 1").code, 0);
  const std::string mesh_bytes = slurp(mesh), tree_bytes = slurp(tree);
  const std::string dir = mesh.substr(0, mesh.find_last_of('/'));
  const std::string mesh_again = dir + "/./" + mesh.substr(mesh.find_last_of('/') + 1);
  for (const std::string& args :
       {"build " + mesh + " -o " + mesh_again + " --method obbtree --depth 1",
        "export " + tree + " --level 0 -o " + tree,
        "collide " + mesh + " " + tree + " --static --colliders 5 -o " + tree,
        "collide " + mesh + " " + tree + " --static --colliders 5 -o " + mesh,
        "compare " + mesh + " --depth 1 --backend cpu --m 4 --quiet --figure " + mesh_again}) {
    const CliRun r = vobb_cli(args);
    EXPECT_EQ(r.code, 2) << args;
    EXPECT_EQ(line_count(r.err), 1u) << args << ": " << r.err;
    EXPECT_NE(r.err.find("is the input file"), std::string::npos) << args << ": " << r.err;
  }
  EXPECT_EQ(slurp(mesh), mesh_bytes);
  EXPECT_EQ(slurp(tree), tree_bytes);
}

// The mesh and the tree given the other way round: the JSON file is said to be no mesh, in one
// line, whichever command takes a mesh first.
TEST(CliBadInput, AJsonFileGivenAsTheMeshIsSaidToBeNone) {
  const std::string mesh = write_cube("swapped_cube.off", 1);
  const std::string tree = test::temp_path("swapped_tree.json");
  ASSERT_EQ(vobb_cli("build " + mesh + " -o " + tree + " --method obbtree --depth 1").code, 0);
  for (const std::string& args : {"certify " + tree + " " + mesh, "info " + tree,
                                  "build " + tree + " -o " + tree + ".out.json --depth 1"}) {
    const CliRun r = vobb_cli(args);
    EXPECT_EQ(r.code, 2) << args << ": " << r.err;
    EXPECT_EQ(line_count(r.err), 1u) << args << ": " << r.err;
    EXPECT_NE(r.err.find("a JSON file, not a mesh"), std::string::npos) << args << ": " << r.err;
  }
  EXPECT_FALSE(std::filesystem::exists(tree + ".out.json"));
}

// An output that cannot be written is refused before the run: the mesh given here is open,
// and the message is still about the output, so it was checked first. A folder is no output,
// nor a name longer than the folder takes. The check leaves nothing in the folder, and a pipe
// reached through /dev/stdout is written in place.
TEST(CliBadInput, UnwritableOutputIsRefusedBeforeTheRun) {
  const std::string open_mesh = test::data_dir() + "/bad/open_cube.off";
  const std::string mesh = write_cube("out_cube.off", 1);
  const std::string tree = test::temp_path("out_tree.json");
  ASSERT_EQ(vobb_cli("build " + mesh + " -o " + tree + " --method obbtree --depth 1").code, 0);
  const std::string dir = ::testing::TempDir();
  struct Case {
    std::string args, says;
  };
  for (const Case& c :
       {Case{"build " + open_mesh + " -o /nonexistent/t.json --backend cpu",
             "no such folder /nonexistent"},
        Case{"build " + open_mesh + " -o " + dir + " --backend cpu", "is a folder"},
        // A file where the folder should be: named for what it is.
        Case{"build " + open_mesh + " -o " + mesh + "/t.json --backend cpu",
             mesh + " is not a folder"},
        Case{"certify " + mesh + " " + tree + " --checkpoint " + mesh + "/ck",
             mesh + " is not a folder"},
        // A checkpoint that names a file: said so, not "cannot make the folder: File exists".
        Case{"certify " + mesh + " " + tree + " --checkpoint " + tree, tree + " is not a folder"},
        Case{"build " + mesh + " -o " + dir + "/t.json --backend cpu --checkpoint " + mesh,
             mesh + " is not a folder"},
        Case{"export " + tree + " --level 1 -o /nonexistent/b.obj", "no such folder /nonexistent"},
        Case{"collide " + open_mesh + " " + tree + " --static --colliders 5 -o /nonexistent/c.json",
             "no such folder /nonexistent"},
        Case{"build " + open_mesh + " -o /proc/t.json --backend cpu", "cannot write in /proc"},
        Case{"build " + open_mesh + " -o " + dir + "/" + std::string(300, 'a') + ".json",
             "file name longer than"},
        Case{"compare " + open_mesh + " --depth 1 --backend cpu --figure " + dir, "is a folder"},
        Case{"export " + tree + " --level 1 -o " + dir + "/b.stl", "unknown box export format"},
        // An empty name names nothing (it was taken for "no file" and the run
        // failed only at its end).
        Case{"build " + open_mesh + " -o '' --backend cpu", "an empty name"},
        Case{"collide " + open_mesh + " " + tree + " --static -o ''", "an empty name"},
        Case{"compare " + open_mesh + " --figure ''", "an empty name"},
        // Folders that exist and take no file: refused before the run, not warned
        // about at every save.
        Case{"build " + mesh + " -o " + dir + "/t.json --backend cpu --checkpoint /proc/self",
             "cannot write in /proc/self"},
        Case{"certify " + mesh + " " + tree + " --checkpoint /proc/self",
             "cannot write in /proc/self"},
        Case{"validate --cpu-only --out /proc/self/v", "cannot write in /proc/self"},
        // A checkpoint folder is made, not its parent: a mistyped parent is refused as
        // -o refuses it, not made into a chain of folders.
        Case{"certify " + mesh + " " + tree + " --checkpoint " + dir + "/none/ck",
             "/none/ck: no such folder "},
        Case{"build " + mesh + " -o " + dir + "/t.json --backend cpu --checkpoint " + dir +
                 "/none/ck",
             "/none/ck: no such folder "}}) {
    const CliRun r = vobb_cli(c.args);
    EXPECT_EQ(r.code, 2) << c.args << ": " << r.err;
    EXPECT_EQ(line_count(r.err), 1u) << c.args << ": " << r.err;
    EXPECT_NE(r.err.find(c.says), std::string::npos) << c.args << ": " << r.err;
  }
  EXPECT_FALSE(std::filesystem::exists(dir + "/none"));
  const std::string empty = test::temp_path("out_empty_dir");
  std::filesystem::remove_all(empty);
  ASSERT_TRUE(std::filesystem::create_directory(empty));
  CliRun ok = vobb_cli("build " + mesh + " -o " + empty + "/t.json --method obbtree --depth 1");
  ASSERT_EQ(ok.code, 0) << ok.err;
  std::vector<std::string> left;
  for (const auto& e : std::filesystem::directory_iterator(empty))
    left.push_back(e.path().filename().string());
  EXPECT_EQ(left, std::vector<std::string>{"t.json"});
  std::filesystem::remove_all(empty);
  ok = vobb_cli("build " + mesh +
                " -o /dev/stdout --method obbtree --depth 1");  // stdout is popen's pipe
  ASSERT_EQ(ok.code, 0) << ok.err;
  Tree piped;
  const std::string piped_path = test::temp_path("out_piped.json");
  { std::ofstream(piped_path) << ok.out; }
  EXPECT_TRUE(read_tree(piped_path, &piped)) << ok.out;
  std::remove(piped_path.c_str());
  // A device is written in place; one that is full shows only when written: exit 3, as for a
  // full standard output.
  const CliRun full = vobb_cli("build " + mesh + " -o /dev/full --method obbtree --depth 1");
  EXPECT_EQ(full.code, 3) << full.err;
  EXPECT_EQ(line_count(full.err), 1u) << full.err;
  EXPECT_NE(full.err.find("No space left on device"), std::string::npos) << full.err;
  std::remove(mesh.c_str());
  std::remove(tree.c_str());
}

// An output named by a symbolic link: the link is kept and the file it names is written, also
// where that file does not exist yet (the link used to be replaced by the file); a link into a
// missing folder, or a loop of links, is refused before the run; and an output that is the
// run's own checkpoint file (which it would write over at its end) is refused.
TEST(CliBadInput, OutputsThroughLinksAndTheRunsOwnCheckpoint) {
  namespace fs = std::filesystem;
  const std::string mesh = write_cube("link_cube.off", 1);
  const fs::path dir = test::temp_path("link_dir");
  fs::remove_all(dir);
  fs::create_directories(dir / "real");
  fs::create_symlink("real/tree.json", dir / "a.json");  // relative, to a file not there yet
  fs::create_symlink("/nonexistent/dir/tree.json", dir / "b.json");
  fs::create_symlink("c.json", dir / "c.json");
  CliRun r = vobb_cli("build " + mesh + " -o " + (dir / "a.json").string() +
                      " --method obbtree --depth 1 --quiet");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::is_symlink(fs::symlink_status(dir / "a.json")));
  Tree t;
  EXPECT_TRUE(read_tree((dir / "real" / "tree.json").string(), &t));
  for (const auto& [link, says] :
       {std::pair<std::string, std::string>{"b.json", "no such folder /nonexistent/dir"},
        {"c.json", "cannot follow the link"}}) {
    r = vobb_cli("build " + mesh + " -o " + (dir / link).string() + " --method obbtree --depth 1");
    EXPECT_EQ(r.code, 2) << link;
    EXPECT_EQ(line_count(r.err), 1u) << r.err;
    EXPECT_NE(r.err.find(says), std::string::npos) << r.err;
    EXPECT_TRUE(fs::is_symlink(fs::symlink_status(dir / link))) << link;
  }
  // The checkpoint folder is not there yet; relative and absolute spellings are mixed (run in
  // `dir`, through a shell's cd).
  const std::string ck = (dir / "ck").string(), in_dir = "cd " + dir.string() + " && ";
  const std::string small = " --depth 1 --m 4 --backend cpu";
  for (const auto& [args, says] : std::vector<std::pair<std::string, std::string>>{
           {"build " + mesh + " -o " + ck + "/state.json --checkpoint " + ck + small,
            "checkpoint file"},
           {"build " + mesh + " -o " + ck + "/../ck/state.json --checkpoint " + ck + "/." + small,
            "checkpoint file"},
           {"build " + mesh + " -o ck/state.json --checkpoint ./ck" + small, "checkpoint file"},
           {"build " + mesh + " -o ck/state.json --checkpoint " + ck + small, "checkpoint file"},
           {"build " + mesh + " -o ck --checkpoint ck" + small,
            "is a folder of this run's checkpoint"},
           {"build " + mesh + " -o x --checkpoint x/ck" + small,
            "is a folder of this run's checkpoint"},
           {"compare " + mesh + small +
                " --checkpoint ck --figure ck/certify-variational/layers.json",
            "checkpoint file"},
           {"compare " + mesh + small + " --checkpoint ck --figure ck/certify-obbtree",
            "is a folder of this run's checkpoint"}}) {
    const CliRun run = vobb_cli_in(in_dir, args);
    EXPECT_EQ(run.code, 2) << args;
    EXPECT_EQ(line_count(run.err), 1u) << run.err;
    EXPECT_NE(run.err.find(says), std::string::npos) << args << ": " << run.err;
  }
  EXPECT_FALSE(fs::exists(ck));
  EXPECT_FALSE(fs::exists(dir / "x"));
  fs::remove_all(dir);
  std::remove(mesh.c_str());
}

// A reader that has gone (vobb info M | head -1 after head's line): the write fails, and the
// run ends with one line and exit 3, not silently by SIGPIPE. The pipe's reading end is closed
// before vobb starts, so every write meets it closed.
TEST(CliBadInput, StandardOutputWithNoReaderEndsWithExitThree) {
  const std::string mesh = write_cube("pipe_cube.off", 1);
  const std::string err_path = test::temp_path("pipe_err.txt");
  int fds[2];
  ASSERT_EQ(::pipe(fds), 0);
  ::close(fds[0]);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    ::dup2(fds[1], 1);
    const int err = ::open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(err, 2);
    ::signal(SIGPIPE, SIG_DFL);  // as a shell starts it
    ::execl(VOBB_CLI, VOBB_CLI, "info", mesh.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  ::close(fds[1]);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  const std::string err = slurp(err_path);
  EXPECT_FALSE(WIFSIGNALED(status)) << "killed by signal " << WTERMSIG(status);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 3) << err;
  EXPECT_EQ(line_count(err), 1u) << err;
  EXPECT_NE(err.find("cannot write standard output"), std::string::npos) << err;
  std::remove(err_path.c_str());
  std::remove(mesh.c_str());
}

// The baseline has no search: a checkpoint, a time budget or subtree swaps asked of it are
// refused, not silently ignored (no checkpoint folder appeared, exit 0).
TEST(CliBadInput, VariationalOnlyOptionsAreRefusedForTheBaseline) {
  const std::string mesh = write_cube("only_cube.off", 1);
  const std::string tree = test::temp_path("only_tree.json");
  for (const std::string& flag : {std::string("--checkpoint ") + test::temp_path("only_ck"),
                                  std::string("--time-budget 1"), std::string("--subtree-swaps")}) {
    const CliRun r = vobb_cli("build " + mesh + " -o " + tree + " --method obbtree " + flag);
    EXPECT_EQ(r.code, 2) << flag;
    EXPECT_EQ(line_count(r.err), 1u) << r.err;
    EXPECT_NE(r.err.find("applies to --method variational only"), std::string::npos) << r.err;
    EXPECT_FALSE(test::exists(tree));
  }
  EXPECT_FALSE(test::exists(test::temp_path("only_ck")));
  std::remove(mesh.c_str());
}

// A mesh read through assimp is in float32 (DESIGN §3): every command that reads it says so on
// stderr, and the JSON reports carry mesh_single_precision. The same cube as OFF is read as
// written and draws no such line.
TEST(Cli, SinglePrecisionReadsAreNamed) {
  const std::string raw = test::temp_path("sp_cube.raw");
  {
    // The unit cube as RAW (one triangle per line, 9 numbers), a format only assimp reads.
    std::ofstream f(raw);
    const int tri[12][3] = {{0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}, {0, 1, 5}, {0, 5, 4},
                            {2, 6, 7}, {2, 7, 3}, {0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}};
    for (const auto& t : tri) {
      for (int c = 0; c < 3; ++c)
        f << (t[c] & 1) << " " << ((t[c] >> 1) & 1) << " " << ((t[c] >> 2) & 1) << " ";
      f << "\n";
    }
  }
  const std::string off = write_cube("sp_cube.off", 1);
  for (const std::string& mesh : {raw, off}) {
    const bool single = mesh == raw;
    SCOPED_TRACE(mesh);
    const std::string tree = test::temp_path("sp_tree.json");
    const std::string boxes = test::temp_path("sp_boxes.json");
    CliRun r = vobb_cli("build " + mesh + " -o " + tree + " --method obbtree --depth 1");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(r.err.find("single precision") != std::string::npos, single) << r.err;
    Tree t;
    ASSERT_TRUE(read_tree(tree, &t));
    ASSERT_TRUE(write_boxes({t.nodes[0].box}, boxes));
    for (const std::string& args :
         {"certify " + mesh + " " + tree + " --json --quiet",
          "obv " + mesh + " --boxes " + boxes + " --backend cpu --m 4 --json",
          "compare " + mesh + " --depth 1 --backend cpu --m 4 --json --quiet"}) {
      r = vobb_cli(args);
      ASSERT_EQ(r.code, 0) << args << ": " << r.err;
      EXPECT_EQ(r.err.find("read in single precision through assimp") != std::string::npos, single)
          << args << ": " << r.err;
      EXPECT_EQ(nlohmann::json::parse(r.out).at("mesh_single_precision").get<bool>(), single)
          << args;
    }
    r = vobb_cli("collide " + mesh + " " + tree + " --static --colliders 5 --no-fcl");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(r.err.find("single precision") != std::string::npos, single) << r.err;
    // A report that cannot be written (a full disk): exit 3 and its one line, with no note.
    r = vobb_cli("obv " + mesh + " --boxes " + boxes + " --backend cpu --m 4 >/dev/full");
    EXPECT_EQ(r.code, 3) << r.err;
    EXPECT_EQ(line_count(r.err), 1u) << r.err;
    // Input refused after the mesh was read (a margin beyond the cube, a box file that is
    // not one): the refusal is the one line, with no note before it.
    for (const std::string& args :
         {"build " + mesh + " -o " + tree + " --collider-margin 100 --backend cpu",
          "obv " + mesh + " --boxes " + mesh + " --backend cpu"}) {
      r = vobb_cli(args);
      EXPECT_EQ(r.code, 2) << args;
      EXPECT_EQ(line_count(r.err), 1u) << args << ": " << r.err;
      EXPECT_EQ(r.err.find("single precision"), std::string::npos) << args << ": " << r.err;
    }
    std::remove(tree.c_str());
    std::remove(boxes.c_str());
  }
  std::remove(raw.c_str());
  std::remove(off.c_str());
}

// Where the two builders stop at different depths (a cube: the baseline stops when its leaves
// hold one face), compare takes both e over the deeper tree's layers, the shallower tree's leaf
// layer repeated below its last: each e, as a rational, equals that sum of the per-layer OMV
// it prints, and the deeper tree's equals certify's e of the same tree built alone.
TEST(Cli, CompareWeighsTreesOfDifferentDepthsAlike) {
  const std::string mesh = write_cube("cmp_cube.off", 1);
  const std::string flags = " --depth 10 --m 8 --backend cpu --quiet";
  CliRun r = vobb_cli("compare " + mesh + flags + " --json --rational");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json doc = nlohmann::json::parse(r.out);
  const int d0 = doc.at("depth_baseline"), d1 = doc.at("depth_variational");
  ASSERT_NE(d0, d1) << "the case needs trees of different depths";
  const size_t levels = doc.at("levels").size();
  ASSERT_EQ(levels, static_cast<size_t>(std::max(d0, d1)) + 1);
  Rational e[2];
  for (size_t l = 0; l < levels; ++l) {
    const auto& row = doc["levels"][l];
    e[0] += static_cast<long>(levels - l) *
            Rational(row.at("omv_baseline_rational").get<std::string>());
    e[1] += static_cast<long>(levels - l) *
            Rational(row.at("omv_variational_rational").get<std::string>());
  }
  EXPECT_TRUE(e[0] == Rational(doc.at("e_baseline_rational").get<std::string>()));
  EXPECT_TRUE(e[1] == Rational(doc.at("e_variational_rational").get<std::string>()));
  // The shallower tree's rows below its depth d repeat its row d.
  const int d = std::min(d0, d1), deep = std::max(d0, d1);
  const char* shallow_key = d0 < d1 ? "omv_baseline_rational" : "omv_variational_rational";
  for (int l = d + 1; l <= deep; ++l)
    EXPECT_EQ(doc["levels"][l].at(shallow_key), doc["levels"][d].at(shallow_key)) << l;
  // And its e over D = deep layers, from its own certificate over d layers (e_d, OMV_l):
  // e_D = e_d + (D - d) sum_{l <= d} OMV_l + (D - d)(D - d + 1) / 2 OMV_d.
  {
    const std::string shallow_tree = test::temp_path("cmp_shallow.json");
    r = vobb_cli("build " + mesh + " -o " + shallow_tree + " --method " +
                 (d0 < d1 ? "obbtree" : "variational") + flags);
    ASSERT_EQ(r.code, 0) << r.err;
    r = vobb_cli("certify " + mesh + " " + shallow_tree + " --json --rational --quiet");
    ASSERT_EQ(r.code, 0) << r.err;
    const nlohmann::json c = nlohmann::json::parse(r.out);
    ASSERT_EQ(c.at("levels").size(), static_cast<size_t>(d) + 1);
    Rational sum;
    for (const auto& l : c["levels"]) sum += Rational(l.at("omv_rational").get<std::string>());
    const Rational last(c["levels"][d].at("omv_rational").get<std::string>());
    const long k = deep - d;
    const Rational expected = Rational(c.at("weighted_error_rational").get<std::string>()) +
                              k * sum + (k * (k + 1) / 2) * last;
    EXPECT_TRUE(expected == e[d0 < d1 ? 0 : 1]);
    std::remove(shallow_tree.c_str());
  }
  // The deeper tree alone, certified: the same e.
  const bool variational_deeper = d1 > d0;
  const std::string tree = test::temp_path("cmp_tree.json");
  r = vobb_cli("build " + mesh + " -o " + tree + " --method " +
               (variational_deeper ? "variational" : "obbtree") + flags);
  ASSERT_EQ(r.code, 0) << r.err;
  r = vobb_cli("certify " + mesh + " " + tree + " --json --rational --quiet");
  ASSERT_EQ(r.code, 0) << r.err;
  const Rational certified(
      nlohmann::json::parse(r.out).at("weighted_error_rational").get<std::string>());
  EXPECT_TRUE(certified == e[variational_deeper ? 1 : 0]);
  // The text report says why the layers were padded.
  r = vobb_cli("compare " + mesh + flags);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("leaf layer is repeated"), std::string::npos) << r.out;
  std::remove(mesh.c_str());
  std::remove(tree.c_str());
}

// compare's variational build takes --checkpoint as build does, with the same fingerprint: a
// build with the same flags resumes from the state compare saved (nothing left to search) and
// writes the bytes of a build from scratch.
// The progress line names what the search minimises: the library's search_objective, so OMV by
// default and OBV with a collider margin, unless --objective says otherwise.
TEST(Cli, ProgressNamesTheObjectiveTheSearchMinimises) {
  const std::string mesh = test::temp_path("progress_torus.off");
  test::write_off(analytic::polygonal_torus().mesh, mesh);
  const std::string out = test::temp_path("progress_tree.json");
  for (const auto& [args, says] : std::vector<std::pair<std::string, std::string>>{
           {"", "sum OMV "},
           {" --objective obv", "sum OBV "},
           {" --collider-margin 0.05", "sum grown OBV "},
           {" --collider-margin 0.05 --objective omv", "sum grown OMV "}}) {
    const CliRun r =
        vobb_cli("build " + mesh + " -o " + out + " --depth 1 --m 4 --backend cpu" + args);
    ASSERT_EQ(r.code, 0) << args << ": " << r.err;
    EXPECT_NE(r.err.find(says), std::string::npos) << args << ": " << r.err;
  }
  for (const std::string& p : {mesh, out}) std::remove(p.c_str());
}

// compare --tree writes the variational tree it certified: the bytes `build -o` writes with the
// same flags, whose certificate is compare's e to the rational. An output that is the mesh or
// the figure is refused before any work.
TEST(Cli, CompareWritesTheTreeItCertified) {
  const std::string mesh = test::temp_path("cmp_tree_torus.off");
  test::write_off(analytic::polygonal_torus().mesh, mesh);
  const std::string flags = " --depth 3 --m 8 --backend cpu --quiet";
  const std::string from_compare = test::temp_path("cmp_tree.json"),
                    from_build = test::temp_path("cmp_build.json");
  CliRun r = vobb_cli("compare " + mesh + flags + " --json --rational --tree " + from_compare);
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json doc = nlohmann::json::parse(r.out);
  ASSERT_EQ(vobb_cli("build " + mesh + " -o " + from_build + flags).code, 0);
  ASSERT_FALSE(slurp(from_compare).empty());
  EXPECT_EQ(slurp(from_compare), slurp(from_build));
  r = vobb_cli("certify " + mesh + " " + from_compare + " --json --rational --quiet");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(
      Rational(nlohmann::json::parse(r.out).at("weighted_error_rational").get<std::string>()) ==
      Rational(doc.at("e_variational_rational").get<std::string>()));
  const std::string figure = test::temp_path("cmp_tree.png");
  for (const auto& [args, says] : std::vector<std::pair<std::string, std::string>>{
           {" --tree " + mesh, "is the input file"},
           {" --figure " + figure + " --tree " + figure, "is also the file of --figure"}}) {
    r = vobb_cli("compare " + mesh + flags + args);
    EXPECT_EQ(r.code, 2) << args;
    EXPECT_EQ(line_count(r.err), 1u) << args << ": " << r.err;
    EXPECT_NE(r.err.find(says), std::string::npos) << args << ": " << r.err;
  }
  for (const std::string& p : {mesh, from_compare, from_build}) std::remove(p.c_str());
}

TEST(Cli, CompareAndBuildShareACheckpoint) {
  const std::string mesh = write_cube("ck_cube.off", 1);
  const std::string dir = test::temp_path("ck_dir");
  const std::string flags = " --depth 3 --m 8 --backend cpu";
  CliRun r = vobb_cli("compare " + mesh + flags + " --quiet --checkpoint " + dir);
  ASSERT_EQ(r.code, 0) << r.err;
  ASSERT_TRUE(test::exists(dir + "/state.json"));
  // Refused before any work (not after the baseline's build and certification, which print
  // progress lines without --quiet): the folder with other flags, or with a damaged file.
  r = vobb_cli("compare " + mesh + " --depth 3 --m 4 --backend cpu --checkpoint " + dir);
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(line_count(r.err), 1u) << r.err;
  EXPECT_NE(r.err.find("checkpoint of another build"), std::string::npos) << r.err;
  const std::string obv = dir + "/certify-variational/obv.json", obv_bytes = slurp(obv);
  ASSERT_FALSE(obv_bytes.empty());
  { std::ofstream(obv) << obv_bytes.substr(0, obv_bytes.size() / 2); }
  r = vobb_cli("compare " + mesh + flags + " --checkpoint " + dir);
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(line_count(r.err), 1u) << r.err;
  EXPECT_NE(r.err.find("obv.json: damaged certify checkpoint"), std::string::npos) << r.err;
  { std::ofstream(obv) << obv_bytes; }
  const std::string resumed = test::temp_path("ck_resumed.json"),
                    fresh = test::temp_path("ck_fresh.json");
  // The state is the finished search's: nothing is searched again. (The refit runs after the
  // last state, so it runs again where it is on; --no-refit leaves it out, and the states are
  // the same either way.)
  r = vobb_cli("build " + mesh + " -o " + resumed + flags + " --no-refit --checkpoint " + dir);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("resuming from"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("vobb: 0 boxes estimated"), std::string::npos) << r.err;
  r = vobb_cli("build " + mesh + " -o " + resumed + flags + " --checkpoint " + dir);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("resuming from"), std::string::npos) << r.err;
  r = vobb_cli("build " + mesh + " -o " + fresh + flags + " --quiet");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(slurp(resumed), slurp(fresh));
  for (const std::string& p : {mesh, resumed, fresh}) std::remove(p.c_str());
  std::filesystem::remove_all(dir);
}

// File names need not be UTF-8; a JSON report escapes what is not (U+FFFD) instead of failing
// with exit 3.
TEST(Cli, JsonReportsTakeFileNamesThatAreNotUtf8) {
  const std::string name = write_cube("latin\xff_cube.off", 1);
  const CliRun r = vobb_cli("info '" + name + "' --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_NE(r.out.find("latin\xef\xbf\xbd_cube.off"), std::string::npos) << r.out;
  EXPECT_EQ(j.at("faces"), 12);
}

// Progress into a file (not a terminal) is whole lines, each "vobb: ...", never a line
// redrawn with carriage returns; the first progress line comes at once.
TEST(Cli, ProgressIntoAFileIsWholeLines) {
  const std::string mesh = write_cube("progress_cube.off", 1);
  const CliRun r = vobb_cli("build " + mesh + " -o " + test::temp_path("progress_tree.json") +
                            " --depth 2 --backend cpu --m 4");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err.find('\r'), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("vobb: level 1/2  nodes done 0/1  iteration"), std::string::npos) << r.err;
  std::istringstream lines(r.err);
  for (std::string line; std::getline(lines, line);) EXPECT_EQ(line.rfind("vobb: ", 0), 0u) << line;
}

// ODE's tolerances are absolute: at 1e60 (the scale-free scene runs at 1e22) it fails an assertion.
// The run ends with one line naming ODE's message, exit 2, and no report file.
TEST(CliBadInput, PhysicsFailureIsOneLineNotAnAbort) {
  const std::string mesh = write_cube("huge_cube.off", 1e60);
  const std::string tree = test::temp_path("huge_tree.json");
  ASSERT_EQ(vobb_cli("build " + mesh + " -o " + tree + " --method obbtree --depth 2").code, 0);
  const std::string out = test::temp_path("huge_report.json");
  const CliRun r =
      vobb_cli("collide " + mesh + " " + tree + " --colliders 30 --seconds 1 --no-fcl -o " + out);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(line_count(r.err), 1u) << r.err;
  EXPECT_NE(r.err.find("physics engine stopped: ODE"), std::string::npos) << r.err;
  EXPECT_FALSE(test::exists(out));
  // The static scene has no physics and works at this scale.
  EXPECT_EQ(vobb_cli("collide " + mesh + " " + tree + " --static --colliders 30 --no-fcl").code, 0);
}

// Crossing sheets (1,500 triangles through one segment, 1,124,250 meeting pairs): refused
// in one line with exit 2, the count stopped at its limit, and the JSON report says so.
TEST(CliBadInput, CrossingSheetsAreRefusedWithALowerBound) {
  const std::string mesh = test::temp_path("crossing_sheets.off");
  test::write_off(test::pinwheel(1500), mesh);
  const CliRun r = vobb_cli("info " + mesh + " --json");
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(line_count(r.err), 1u) << r.err;
  EXPECT_NE(r.err.find("self-intersecting: at least 1000000 pairs of faces"), std::string::npos)
      << r.err;
  EXPECT_NE(r.out.find("\"count_is_lower_bound\": true"), std::string::npos) << r.out;
  std::remove(mesh.c_str());
}

// Counts are decimal digits: not hex (CLI11 would take 0x10 as 16), not trailing junk, and
// a leading zero is no octal; each refusal names the value.
TEST(CliBadInput, CountsAreDecimalDigits) {
  for (const char* value : {"0x10", "8x", "-1", "''"})
    for (const std::string& args : {std::string("build x.off -o t.json --depth "),
                                    std::string("export t.json -o b.obj --level ")}) {
      const CliRun r = vobb_cli(args + value);
      EXPECT_EQ(r.code, 2) << args << value;
      EXPECT_NE(r.err.find("is not a whole number in decimal digits"), std::string::npos)
          << args << value << ": " << r.err;
    }
  const std::string mesh = write_cube("leading_zero_cube.off", 1);
  const std::string tree = test::temp_path("leading_zero_tree.json");
  EXPECT_EQ(vobb_cli("build " + mesh + " -o " + tree + " --method obbtree --depth 02").code, 0);
  Tree t;
  ASSERT_TRUE(read_tree(tree, &t));
  EXPECT_EQ(t.depth, 2);
  std::remove(tree.c_str());
  std::remove(mesh.c_str());
}

// A report that cannot be written (standard output on a full device) ends with exit 3 and one
// line, not with exit 0 and nothing written.
TEST(CliBadInput, UnwritableStandardOutputIsExitThree) {
  const std::string mesh = write_cube("full_cube.off", 1);
  for (const char* args : {" --json", ""}) {
    const CliRun r = vobb_cli("info " + mesh + args + " >/dev/full");
    EXPECT_EQ(r.code, 3) << args << ": " << r.err;
    EXPECT_EQ(line_count(r.err), 1u) << r.err;
    EXPECT_NE(r.err.find("vobb info: cannot write standard output"), std::string::npos) << r.err;
  }
  EXPECT_EQ(vobb_cli("info " + mesh + " >/dev/null").code, 0);
  // Help and the version too.
  for (const char* args : {"--help", "build --help", "--version"}) {
    const CliRun r = vobb_cli(std::string(args) + " >/dev/full");
    EXPECT_EQ(r.code, 3) << args << ": " << r.err;
    EXPECT_EQ(r.err, "vobb: cannot write standard output\n") << args;
    EXPECT_EQ(vobb_cli(std::string(args) + " >/dev/null").code, 0) << args;
  }
}

// A unit cube written by hand (8 vertices, 12 faces) and its depth-3 baseline tree, shared by
// the tests below (each of them leaves both as they were).
class CliOnCube : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    mesh_ = test::temp_path("cube.off");
    {
      std::ofstream f(mesh_);
      f << "OFF\n8 12 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 0 1\n1 0 1\n0 1 1\n1 1 1\n"
           "3 0 4 6\n3 0 6 2\n3 1 3 7\n3 1 7 5\n3 0 1 5\n3 0 5 4\n3 2 6 7\n3 2 7 3\n3 0 2 3\n3 0 3 "
           "1\n"
           "3 4 5 7\n3 4 7 6\n";
    }
    tree_ = test::temp_path("cube_tree.json");
    built_ = vobb_cli("build " + mesh_ + " -o " + tree_ + " --method obbtree --depth 3");
  }
  static void TearDownTestSuite() {
    std::remove(mesh_.c_str());
    std::remove(tree_.c_str());
  }
  void SetUp() override { ASSERT_EQ(built_.code, 0) << built_.err; }
  // A box file at `path` holding the tree's root box; whether it was written.
  static bool write_root_box(const std::string& path) {
    Tree t;
    return read_tree(tree_, &t) && write_boxes({t.nodes[0].box}, path);
  }
  static std::string mesh_, tree_;
  static CliRun built_;
};
std::string CliOnCube::mesh_, CliOnCube::tree_;
CliRun CliOnCube::built_;

TEST_F(CliOnCube, InfoAndBuild) {
  const std::string& mesh = mesh_;
  const std::string& tree = tree_;
  CliRun r = vobb_cli("info " + mesh + " --json --rational");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("\"verdict\": \"solid\""), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"volume_rational\": \"1\""), std::string::npos) << r.out;
  Tree t;
  ASSERT_TRUE(read_tree(tree, &t));
  EXPECT_EQ(t.mesh_triangles, 12u);
  EXPECT_EQ(t.mesh_sha256.size(), 64u);
  // A collider margin beyond the cube's diagonal (sqrt 3) is refused, and no tree is written.
  const std::string margin_tree = test::temp_path("margin_tree.json");
  r = vobb_cli("build " + mesh + " -o " + margin_tree +
               " --collider-margin 1.8 --backend cpu --depth 1");
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(line_count(r.err), 1u) << r.err;
  EXPECT_NE(r.err.find("bounding-box diagonal"), std::string::npos) << r.err;
  EXPECT_FALSE(test::exists(margin_tree));
  // Within the diagonal it builds, and the margin reaches the builder: the tree differs from
  // the margin-0 build of the same flags (the same difference the builder test pins down).
  const std::string plain_tree = test::temp_path("plain_tree.json");
  r = vobb_cli("build " + mesh + " -o " + margin_tree +
               " --collider-margin 0.5 --backend cpu --depth 2 --m 8 --quiet");
  ASSERT_EQ(r.code, 0) << r.err;
  r = vobb_cli("build " + mesh + " -o " + plain_tree + " --backend cpu --depth 2 --m 8 --quiet");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(slurp(margin_tree), slurp(plain_tree));
  for (const std::string& p : {margin_tree, plain_tree}) std::remove(p.c_str());
}

TEST_F(CliOnCube, ExportWritesEachBoxOfTheLayer) {
  const std::string& tree = tree_;
  CliRun r;
  Tree t;
  ASSERT_TRUE(read_tree(tree, &t));
  const std::string boxes = test::temp_path("layer.obj");
  r = vobb_cli("export " + tree + " --level 2 -o " + boxes);
  ASSERT_EQ(r.code, 0) << r.err;
  {
    // The layer's boxes, each as one object of 8 corners and 6 quads (box_export.h); each
    // corner is the box's centre plus or minus its three half axes.
    const std::vector<int32_t> ids = layer(t, 2);
    ASSERT_FALSE(ids.empty());
    std::istringstream obj(slurp(boxes));
    std::vector<Vec3> corners;
    size_t objects = 0, quads = 0;
    for (std::string line; std::getline(obj, line);) {
      std::istringstream words(line);
      std::string tag;
      words >> tag;
      if (tag == "o") ++objects;
      if (tag == "f")
        quads += std::distance(std::istream_iterator<std::string>(words),
                               std::istream_iterator<std::string>()) == 4;
      if (tag == "v") {
        Vec3 v;
        words >> v[0] >> v[1] >> v[2];
        corners.push_back(v);
      }
    }
    EXPECT_EQ(objects, ids.size());
    EXPECT_EQ(quads, 6 * ids.size());
    ASSERT_EQ(corners.size(), 8 * ids.size());
    for (size_t b = 0; b < ids.size(); ++b) {
      const Obb& box = t.nodes[ids[b]].box;
      for (size_t k = 0; k < 8; ++k) {
        // Local coordinates of the corner, each +-1. The file prints doubles exactly (shortest
        // round trip), so the error is that of computing the corner (3 sums of terms up to
        // |c| + sum h) and of projecting it back (3 products, 2 sums): under 16 roundings of
        // at most eps / 2 of that size, 8 eps of it; the quotient by the half extent adds one
        // rounding of eps / 2 relative to the result, 1: within 16 eps of the size over h.
        const Vec3 d = corners[8 * b + k] - box.center;
        const double size = box.center.norm() + box.half.sum();
        for (int a = 0; a < 3; ++a)
          EXPECT_NEAR(std::abs(d.dot(box.axes[a])) / box.half[a], 1.0,
                      16 * std::numeric_limits<double>::epsilon() * size / box.half[a])
              << b << " " << k;
      }
    }
  }
  r = vobb_cli("export " + tree + " --level 9 -o " + boxes);
  EXPECT_EQ(r.code, 2);
  std::remove(boxes.c_str());
}

TEST_F(CliOnCube, CertifyPassesFailsAndRefuses) {
  const std::string& mesh = mesh_;
  const std::string& tree = tree_;
  CliRun r;
  // certify: a good tree passes (exit 0) with JSON per DESIGN §7; a shrunken box fails
  // (exit 1); a tree for another mesh is bad input (exit 2).
  r = vobb_cli("certify " + mesh + " " + tree + " --json --quiet");
  ASSERT_EQ(r.code, 0) << r.err;
  for (const char* key :
       {"\"levels\"", "\"omv\"", "\"sum_obv\"", "\"overlap\"", "\"upper_bound_holds\": true",
        "\"weighted_error\"", "\"containment\"", "\"seconds\""})
    EXPECT_NE(r.out.find(key), std::string::npos) << key;
  {
    Tree shrunk;
    ASSERT_TRUE(read_tree(tree, &shrunk));
    shrunk.nodes.back().box.half *= 0.5;
    const std::string bad = test::temp_path("shrunk.json");
    ASSERT_TRUE(write_tree(shrunk, bad));
    r = vobb_cli("certify " + mesh + " " + bad + " --quiet");
    EXPECT_EQ(r.code, 1) << r.out << r.err;
    EXPECT_NE(r.out.find("containment: FAILED"), std::string::npos) << r.out;
    std::remove(bad.c_str());
  }
  r = vobb_cli("certify " + test::data_dir() + "/bad/open_cube.off " + tree + " --quiet");
  EXPECT_EQ(r.code, 2);
  const std::string tet = test::temp_path("tet.off");
  {
    std::ofstream f(tet);
    f << "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
  }
  r = vobb_cli("certify " + tet + " " + tree + " --quiet");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("but the mesh has 4"), std::string::npos) << r.err;
  std::remove(tet.c_str());
}

// Flags that would change nothing for what was asked are refused in one line, exit 2, not
// ignored.
TEST_F(CliOnCube, FlagsThatWouldChangeNothingAreRefused) {
  const std::string boxes = test::temp_path("refused_flags_boxes.json");
  ASSERT_TRUE(write_root_box(boxes));
  const std::string obv = "obv " + mesh_ + " --boxes " + boxes;
  struct Case {
    std::string args, says;
  };
  for (const Case& c :
       {Case{obv + " --backend poly --m 8", "--m: the poly backend has no resolution"},
        Case{obv + " --backend exact --m 8", "--m: the exact backend has no resolution"},
        Case{obv + " --backend poly --r-bound", "--r-bound: the poly backend has no R(m)"},
        Case{obv + " --backend cpu --rational", "--rational: the exact values come with"},
        Case{"compare " + mesh_ + " --depth 1 --figure-up z", "--figure-up requires --figure"},
        Case{"compare " + mesh_ + " --depth 1 --figure " + test::temp_path("fig.jpg"),
             "the figure is a PNG; name a .png file"},
        Case{"collide " + mesh_ + " " + tree_ + " --static --seconds 5",
             "--seconds excludes --static"}}) {
    const CliRun r = vobb_cli(c.args);
    EXPECT_EQ(r.code, 2) << c.args << ": " << r.err;
    EXPECT_EQ(line_count(r.err), 1u) << r.err;
    EXPECT_NE(r.err.find(c.says), std::string::npos) << c.args << ": " << r.err;
  }
  // The same flags where they do something run.
  EXPECT_EQ(vobb_cli(obv + " --backend cpu --m 8 --r-bound").code, 0);
  EXPECT_EQ(vobb_cli(obv + " --backend exact --rational").code, 0);
  std::remove(boxes.c_str());
}

// obv's list of resolutions: one list, every element a count in [1, 4096]; an empty element
// is refused, not skipped, as are a count listed twice and a second --m; a leading zero is
// decimal.
TEST_F(CliOnCube, ResolutionListsHaveNoEmptyElements) {
  const std::string boxes = test::temp_path("resolution_list_boxes.json");
  ASSERT_TRUE(write_root_box(boxes));
  const std::string obv = "obv " + mesh_ + " --boxes " + boxes + " --backend cpu --m ";
  for (const char* value :
       {"8,,16", ",8", "8,", "''", "8,0", "8,4097", "8,0x10", "8 --m 16", "8,16,8", "8,08"}) {
    const CliRun r = vobb_cli(obv + value);
    EXPECT_EQ(r.code, 2) << value;
    EXPECT_EQ(line_count(r.err), 1u) << r.err;
    EXPECT_NE(r.err.find("--m: "), std::string::npos) << value << ": " << r.err;
  }
  const CliRun r = vobb_cli(obv + "4,08 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  std::vector<int> ms;
  for (const auto& e : j.at("boxes").at(0).at("estimates")) ms.push_back(e.at("m").get<int>());
  EXPECT_EQ(ms, (std::vector<int>{4, 8}));
  std::remove(boxes.c_str());
}

TEST_F(CliOnCube, ObvEstimatesWithinTheirCertifiedBounds) {
  const std::string& mesh = mesh_;
  const std::string& tree = tree_;
  CliRun r;
  // obv: the cube's root box estimated and computed exactly; JSON per DESIGN §7.
  {
    Tree t;
    ASSERT_TRUE(read_tree(tree, &t));
    const std::string boxes = test::temp_path("boxes.json");
    ASSERT_TRUE(write_boxes({t.nodes[0].box}, boxes));
    r = vobb_cli("obv " + mesh + " --boxes " + boxes + " --m 4,8 --backend all --json --rational");
    ASSERT_EQ(r.code, 0) << r.err;
    for (const char* key :
         {"\"index\"", "\"box_volume\"", "\"interval\"", "\"exact\"", "\"estimates\"",
          "\"backend\": \"cpu\"", "\"backend\": \"gl\"", "\"backend\": \"poly\"", "\"m\": 8",
          "\"obv\"", "\"seconds\"", "\"renderer\""})
      EXPECT_NE(r.out.find(key), std::string::npos) << key << r.out;
    // The exact OBV as a rational too, whose nearest double is "exact"; the interval holds it,
    // and every estimate lies within its certified bound of it (compared as rationals).
    // The root box holds the unit cube, so its exact OBV is its exact volume less 1.
    const nlohmann::json doc = nlohmann::json::parse(r.out);
    ASSERT_EQ(doc["boxes"].size(), 1u);
    EXPECT_EQ(Rational(doc["boxes"][0]["exact_rational"].get<std::string>()),
              exact_volume(t.nodes[0].box) - 1);
    for (const auto& box : doc["boxes"]) {
      const Rational q(box["exact_rational"].get<std::string>());
      EXPECT_EQ(to_double_nearest(q), box["exact"].get<double>());
      EXPECT_LE(Rational(box["interval"][0].get<double>()), q);
      EXPECT_LE(q, Rational(box["interval"][1].get<double>()));
      ASSERT_EQ(box["estimates"].size(), 5u);  // poly, then cpu and gl at m = 4 and 8
      for (const auto& e : box["estimates"]) {
        EXPECT_LE(abs(Rational(e["obv"].get<double>()) - q), Rational(e["bound"].get<double>()))
            << e;
        EXPECT_FALSE(e.contains("r_bound")) << e;  // R(m) only when asked for
      }
    }
    // The rationals only when asked for (they run to thousands of digits); in text, one line
    // per box after the table, the same value.
    r = vobb_cli("obv " + mesh + " --boxes " + boxes + " --backend exact --json");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_FALSE(nlohmann::json::parse(r.out)["boxes"][0].contains("exact_rational")) << r.out;
    r = vobb_cli("obv " + mesh + " --boxes " + boxes + " --backend exact --rational");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("box 0 exact (rational): " +
                         doc["boxes"][0]["exact_rational"].get<std::string>() + "\n"),
              std::string::npos)
        << r.out;
    // Without a GL context: gl is refused in one line, auto falls back to the CPU twin and warns.
    ::setenv("VOBB_GL", "off", 1);
    r = vobb_cli("obv " + mesh + " --boxes " + boxes + " --backend gl");
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(line_count(r.err), 1u) << r.err;
    EXPECT_NE(r.err.find("VOBB_GL=off"), std::string::npos) << r.err;
    r = vobb_cli("obv " + mesh + " --boxes " + boxes + " --m 8 --backend auto --json");
    ::unsetenv("VOBB_GL");
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.err.find("warning"), std::string::npos) << r.err;
    EXPECT_NE(r.out.find("\"backend\": \"cpu\""), std::string::npos) << r.out;
    EXPECT_EQ(r.out.find("\"backend\": \"gl\""), std::string::npos) << r.out;
    std::remove(boxes.c_str());
  }
}

// --rational in text prints every exact value that --json --rational gives: per level OMV, sum
// of OBV and overlap, and e (certify); per layer both trees' OMV, and both e (compare).
TEST_F(CliOnCube, RationalTextGivesEveryRationalOfTheJson) {
  const CliRun text = vobb_cli("certify " + mesh_ + " " + tree_ + " --rational --quiet");
  ASSERT_EQ(text.code, 0) << text.err;
  const CliRun json = vobb_cli("certify " + mesh_ + " " + tree_ + " --rational --json --quiet");
  ASSERT_EQ(json.code, 0) << json.err;
  const nlohmann::json j = nlohmann::json::parse(json.out);
  ASSERT_EQ(j.at("levels").size(), 4u);  // the depth-3 tree
  for (const nlohmann::json& l : j["levels"]) {
    const std::string level = "level " + std::to_string(l.at("level").get<int>());
    for (const auto& [name, key] : {std::pair{" OMV", "omv_rational"},
                                    {" sum OBV", "sum_obv_rational"},
                                    {" overlap", "overlap_rational"}})
      EXPECT_NE(text.out.find(level + name + " (rational): " + l.at(key).get<std::string>() + "\n"),
                std::string::npos)
          << level << name << "\n"
          << text.out;
  }
  EXPECT_NE(text.out.find("e (rational): " + j.at("weighted_error_rational").get<std::string>()),
            std::string::npos)
      << text.out;

  const std::string flags = " --depth 2 --m 8 --backend cpu --lloyd 1 --sweeps 1 --rational";
  const CliRun ctext = vobb_cli("compare " + mesh_ + flags + " --quiet");
  ASSERT_EQ(ctext.code, 0) << ctext.err;
  const CliRun cjson = vobb_cli("compare " + mesh_ + flags + " --json --quiet");
  ASSERT_EQ(cjson.code, 0) << cjson.err;
  const nlohmann::json c = nlohmann::json::parse(cjson.out);
  ASSERT_EQ(c.at("levels").size(), 3u);
  for (const nlohmann::json& l : c["levels"]) {
    const std::string layer = "layer " + std::to_string(l.at("level").get<int>());
    for (const auto& [name, key] : {std::pair{" OMV obbtree", "omv_baseline_rational"},
                                    {" OMV variational", "omv_variational_rational"}})
      EXPECT_NE(
          ctext.out.find(layer + name + " (rational): " + l.at(key).get<std::string>() + "\n"),
          std::string::npos)
          << layer << name << "\n"
          << ctext.out;
  }
  for (const auto& [name, key] :
       {std::pair{"e obbtree", "e_baseline_rational"}, {"e variational", "e_variational_rational"}})
    EXPECT_NE(ctext.out.find(name + std::string(" (rational): ") + c.at(key).get<std::string>()),
              std::string::npos)
        << ctext.out;
}

// compare --figure where no GL context can be made is refused before the run: one line, exit 2,
// nothing printed and no --tree written.
TEST_F(CliOnCube, CompareFigureWithoutGlIsRefusedBeforeTheRun) {
  const std::string figure = test::temp_path("nogl.png"), tree = test::temp_path("nogl.json");
  ::setenv("VOBB_GL", "off", 1);
  const CliRun r = vobb_cli("compare " + mesh_ + " --depth 2 --m 4 --backend cpu --tree " + tree +
                            " --figure " + figure);
  ::unsetenv("VOBB_GL");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(line_count(r.err), 1u) << r.err;
  EXPECT_NE(r.err.find("cannot draw the figure"), std::string::npos) << r.err;
  EXPECT_EQ(r.out, "");
  EXPECT_FALSE(test::exists(tree));
  EXPECT_FALSE(test::exists(figure));
}

TEST_F(CliOnCube, VariationalTreeCertifies) {
  const std::string& mesh = mesh_;
  const std::string tree = test::temp_path("cube_variational.json");
  CliRun r;
  // The variational builder (CPU twin in its loop) writes a tree that certifies.
  r = vobb_cli("build " + mesh + " -o " + tree +
               " --method variational --depth 3 --m 8 --backend cpu --quiet");
  ASSERT_EQ(r.code, 0) << r.err;
  r = vobb_cli("certify " + mesh + " " + tree + " --quiet");
  EXPECT_EQ(r.code, 0) << r.out << r.err;
  std::remove(tree.c_str());
}

// R(m), the cubemap's texel bound (--r-bound), never exceeds the box: the exact OBV lies
// between 0 and the box's volume. At m = 1 on the unit cube, R(m) of a box over the cube's top
// face is 0.18 (CPU) and 0.32 (GL) of a box of volume 0.216 before the range clips it; obv
// reports at most max(E, vol - E) plus its derived round-off (fast/cubemap_bound.h,
// range_bound), and it still holds against the exact value. The round-off, relative to
// max(E, vol - E) >= vol / 2: range_bound's volume U is at most vol (1 + 32 eps)(1 + 12 eps),
// so U - E exceeds vol - E by 44 eps vol, 88 eps of the maximum; the reported box volume is
// the exact one rounded to nearest, off by at most eps / 2 of it, eps of the maximum; and the
// final factor 1 + 4 eps: under 94 eps in all, taken as 128 eps. The certified bound (from the
// polyhedral solver's interval) holds too, and is far below R(m).
TEST(Cli, ObvBoundIsNeverAboveTheBoxVolume) {
  const std::string mesh = write_cube("range_cube.off", 1);
  Obb b;
  b.center = Vec3(0.5, 0.5, 0.9);
  b.half = Vec3(0.3, 0.3, 0.3);
  const std::string boxes = test::temp_path("range_boxes.json");
  ASSERT_TRUE(write_boxes({b}, boxes));
  const CliRun r = vobb_cli("obv " + mesh + " --boxes " + boxes +
                            " --m 1,2 --backend all --json --r-bound --rational");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json doc = nlohmann::json::parse(r.out);
  ASSERT_EQ(doc["boxes"].size(), 1u);
  const auto& box = doc["boxes"][0];
  const double vol = box["box_volume"].get<double>(), exact = box["exact"].get<double>();
  const Rational q(box["exact_rational"].get<std::string>());
  EXPECT_EQ(exact, to_double_nearest(q));            // the exact value, rounded once
  const Rational h(0.3);                             // the stored half extent, exactly
  EXPECT_EQ(vol, to_double_nearest(8 * h * h * h));  // the certified solid's, rounded once
  ASSERT_EQ(box["estimates"].size(), 5u);
  int cubemap = 0;
  for (const auto& e : box["estimates"]) {
    const double obv = e["obv"].get<double>(), bound = e["bound"].get<double>();
    EXPECT_LE(abs(Rational(obv) - q), Rational(bound)) << e;
    if (e["backend"] == "poly") {
      EXPECT_FALSE(e.contains("r_bound")) << e;
      continue;
    }
    ++cubemap;
    const double rb = e["r_bound"].get<double>();
    EXPECT_LE(abs(Rational(obv) - q), Rational(rb)) << e;  // R(m) bounds the exact error
    EXPECT_LE(rb, std::max(obv, vol - obv) * (1 + 128 * std::numeric_limits<double>::epsilon()))
        << e;
    EXPECT_LT(rb, vol) << e;
  }
  EXPECT_EQ(cubemap, 4);
  std::remove(boxes.c_str());
  std::remove(mesh.c_str());
}

// The polyhedral solver through the command line: obv --backend poly prints each estimate with
// its certified interval, which holds the exact rational; build --backend poly (which takes no
// --m) writes a tree that certifies on both exact paths.
TEST(Cli, PolyBackendEstimatesAndBuilds) {
  const std::string mesh = write_cube("poly_cube.off", 1);
  Obb b;
  b.center = Vec3(0.4, 0.55, 0.9);
  b.half = Vec3(0.3, 0.2, 0.25);
  b.axes = {Vec3(0.6, 0.8, 0), Vec3(-0.8, 0.6, 0), Vec3(0, 0, 1)};
  const std::string boxes = test::temp_path("poly_boxes.json");
  ASSERT_TRUE(write_boxes({b}, boxes));
  CliRun r = vobb_cli("obv " + mesh + " --boxes " + boxes + " --backend poly --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json doc = nlohmann::json::parse(r.out);
  const auto& box = doc["boxes"][0];
  ASSERT_EQ(box["estimates"].size(), 1u);
  EXPECT_EQ(box["estimates"][0]["backend"], "poly");
  EXPECT_TRUE(box["estimates"][0]["m"].is_null());  // every estimate has "m"; poly has no m
  EXPECT_FALSE(doc.contains("renderer"));           // no GL context for poly
  r = vobb_cli("obv " + mesh + " --boxes " + boxes + " --backend exact --json --rational");
  ASSERT_EQ(r.code, 0) << r.err;
  const Rational exact(
      nlohmann::json::parse(r.out)["boxes"][0]["exact_rational"].get<std::string>());
  EXPECT_LE(Rational(box["interval"][0].get<double>()), exact);
  EXPECT_LE(exact, Rational(box["interval"][1].get<double>()));
  r = vobb_cli("obv " + mesh + " --boxes " + boxes + " --backend poly");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("certified interval"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("poly"), std::string::npos) << r.out;
  // build: no --m with poly, refused in one line with exit 2 and nothing written.
  const std::string tree = test::temp_path("poly_tree.json");
  r = vobb_cli("build " + mesh + " -o " + tree + " --backend poly --m 8");
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(line_count(r.err), 1u) << r.err;
  EXPECT_FALSE(test::exists(tree));
  const std::string torus_path = test::temp_path("poly_torus.off");
  test::write_off(analytic::polygonal_torus().mesh, torus_path);
  r = vobb_cli("build " + torus_path + " -o " + tree + " --depth 4 --backend poly --quiet");
  ASSERT_EQ(r.code, 0) << r.err;
  r = vobb_cli("certify " + torus_path + " " + tree + " --path both --quiet");
  EXPECT_EQ(r.code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("containment: ok"), std::string::npos) << r.out;
  for (const std::string& p : {mesh, boxes, tree, torus_path}) std::remove(p.c_str());
}

// The swaps applied, from the build's line "vobb: subtree swaps: N pairs scored, S swaps ...";
// 0 where there is no such line.
size_t swaps_reported(const std::string& err) {
  const size_t at = err.find("subtree swaps: ");
  if (at == std::string::npos) return 0;
  const size_t n = err.find("scored, ", at);
  EXPECT_NE(n, std::string::npos) << "no count of swaps in: " << err;
  return n == std::string::npos ? 0 : std::stoul(err.substr(n + 8));
}

// --subtree-swaps after the search: it says what it did, and on this torus it swaps, so the tree
// certifies with an exact e strictly lower than without it (each round kept lowers the
// estimated e by min_drop, 1e-4, of it, far above the polyhedral solver's round-off).
TEST(Cli, SubtreeSwapsLowerTheCertifiedError) {
  const std::string mesh = test::temp_path("swaps_torus.off");
  test::write_off(analytic::polygonal_torus().mesh, mesh);
  const std::string plain = test::temp_path("swaps_plain.json");
  const std::string swapped = test::temp_path("swaps_swapped.json");
  CliRun r = vobb_cli("build " + mesh + " -o " + plain + " --depth 4 --backend poly --quiet");
  ASSERT_EQ(r.code, 0) << r.err;
  r = vobb_cli("build " + mesh + " -o " + swapped + " --depth 4 --backend poly --subtree-swaps");
  ASSERT_EQ(r.code, 0) << r.err;
  const size_t swaps = swaps_reported(r.err);
  // e's enclosure from certify's filter holds the exact value: the swapped tree's upper end
  // below the plain tree's lower end proves the drop.
  auto e_of = [&](const std::string& tree) {
    const CliRun c = vobb_cli("certify " + mesh + " " + tree + " --json --quiet");
    EXPECT_EQ(c.code, 0) << c.err;
    return nlohmann::json::parse(c.out)["weighted_error_enclosure"].get<std::array<double, 2>>();
  };
  ASSERT_GT(swaps, 0u) << r.err;
  EXPECT_LT(e_of(swapped)[1], e_of(plain)[0]);
  // A search for colliders minimises grown OBV or recorded queries, not e: the swaps are
  // refused with either.
  std::remove(swapped.c_str());
  const std::string queries = test::temp_path("swaps_queries.json");
  { std::ofstream(queries) << "{}"; }  // refused before the file is read
  for (const std::string& flag : {std::string("--collider-margin 0.1"), "--queries " + queries}) {
    r = vobb_cli("build " + mesh + " -o " + swapped + " --subtree-swaps " + flag);
    EXPECT_EQ(r.code, 2) << flag;
    EXPECT_EQ(line_count(r.err), 1u) << r.err;
    EXPECT_NE(r.err.find("--subtree-swaps lowers e"), std::string::npos) << r.err;
    EXPECT_FALSE(test::exists(swapped)) << flag;
  }
  std::remove(queries.c_str());
  for (const std::string& p : {mesh, plain, swapped}) std::remove(p.c_str());
}

// The library prints nothing about GL; the command line names the renderer once on stderr,
// and --quiet leaves it out (the build's closing summary line stays).
TEST(Cli, GlRendererIsNamedByTheCommandLineOnlyWhenNotQuiet) {
  const std::string mesh = write_cube("gl_cube.off", 1);
  const std::string tree = test::temp_path("gl_cube_tree.json");
  const std::string flags = " -o " + tree + " --method variational --depth 1 --m 4 --backend gl";
  CliRun r = vobb_cli("build " + mesh + flags);
  ASSERT_EQ(r.code, 0) << r.err;
  const size_t at = r.err.find("vobb: GL renderer: ");
  ASSERT_NE(at, std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("GL renderer", at + 19), std::string::npos) << "named twice: " << r.err;
  r = vobb_cli("build " + mesh + flags + " --quiet");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err.find("GL renderer"), std::string::npos) << r.err;
  EXPECT_EQ(line_count(r.err), 1u) << r.err;  // the summary line only
  std::remove(mesh.c_str());
  std::remove(tree.c_str());
}

// Runs `command` (a shell line) that a test hook kills with SIGKILL; true when it was killed.
// The shell reports the killed child as 128 + 9, or, where it ran the command in its own
// process (exec), the shell is the one killed.
bool killed_by_its_hook(const std::string& command) {
  const int status = std::system((command + " >/dev/null 2>&1").c_str());
  return (WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL) ||
         (WIFEXITED(status) && WEXITSTATUS(status) == 128 + SIGKILL);
}

// The swaps run after the search, whose checkpoint they do not change: a build with
// --subtree-swaps killed once two levels are split, then started again with the same folder,
// writes the same bytes as an uninterrupted one, and so does a third start, which resumes from
// the search's last saved state.
TEST(Cli, SubtreeSwapsAfterAResumedSearchGiveTheSameTree) {
  const std::string mesh = test::temp_path("swaps_resume_torus.off");
  test::write_off(analytic::polygonal_torus().mesh, mesh);
  const std::string dir = test::temp_path("swaps_ckpt");
  const std::string whole = test::temp_path("swaps_whole.json"),
                    resumed = test::temp_path("swaps_resumed.json");
  std::system(("rm -rf " + dir).c_str());
  const std::string args = " --depth 4 --backend poly --subtree-swaps";
  const CliRun first = vobb_cli("build " + mesh + " -o " + whole + args);
  ASSERT_EQ(first.code, 0) << first.err;
  ASSERT_GT(swaps_reported(first.err), 0u) << first.err;
  EXPECT_TRUE(killed_by_its_hook("VOBB_TEST_KILL_AT_SPLIT_LEVELS=2 " + std::string(VOBB_CLI) +
                                 " build " + mesh + " -o " + resumed + args + " --checkpoint " +
                                 dir))
      << "the build was not killed at its level-2 checkpoint";
  EXPECT_FALSE(test::exists(resumed)) << "the killed build wrote its tree";
  EXPECT_NE(slurp(dir + "/state.json").find("\"split_levels\":2"), std::string::npos);
  for (int start : {2, 3}) {
    const CliRun r = vobb_cli("build " + mesh + " -o " + resumed + args + " --checkpoint " + dir);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.err.find("resuming from"), std::string::npos) << "start " << start << ": " << r.err;
    EXPECT_EQ(swaps_reported(r.err), swaps_reported(first.err)) << "start " << start;
    EXPECT_EQ(slurp(resumed), slurp(whole)) << "start " << start;
    std::remove(resumed.c_str());
  }
  std::system(("rm -rf " + dir).c_str());
  for (const std::string& p : {mesh, whole}) std::remove(p.c_str());
}

// A variational build killed (SIGKILL) once its checkpoint holds two split levels, then started
// again with the same folder, writes the same bytes as an uninterrupted build; a build with
// other options refuses that folder with exit 2.
TEST(Cli, KilledBuildResumesToTheSameTree) {
  const std::string mesh = test::real_mesh("dino");
  VOBB_REQUIRE_REAL_MESH("dino");
  const std::string dir = test::temp_path("ckpt"), state = dir + "/state.json";
  const std::string whole = test::temp_path("whole.json"),
                    resumed = test::temp_path("resumed.json");
  std::system(("rm -rf " + dir).c_str());
  // Small settings: the test is about resuming, not about quality (about 15 s a build here).
  const std::string args = " --depth 3 --m 8 --lloyd 1 --backend cpu --quiet";
  ASSERT_EQ(vobb_cli("build " + mesh + " -o " + whole + args).code, 0);
  // Killed (SIGKILL, by the build itself through a test hook) right after the state with two
  // levels split is saved: a known point, not a race with a poller.
  EXPECT_TRUE(killed_by_its_hook("VOBB_TEST_KILL_AT_SPLIT_LEVELS=2 " + std::string(VOBB_CLI) +
                                 " build " + mesh + " -o " + resumed + args + " --checkpoint " +
                                 dir))
      << "the build was not killed at its level-2 checkpoint";
  EXPECT_NE(slurp(state).find("\"split_levels\":2"), std::string::npos);
  EXPECT_FALSE(test::exists(resumed)) << "the killed build wrote its tree";
  // What a build killed while writing its state leaves: the resumed build clears it.
  // (Unlocked, and written longer ago than remove_stray_temporaries waits.)
  const std::string stray = dir + "/.vobb-12345-0.tmp";
  { std::ofstream(stray) << "{\"half"; }
  std::filesystem::last_write_time(
      stray, std::filesystem::file_time_type::clock::now() - std::chrono::minutes(5));
  ASSERT_TRUE(test::exists(stray));
  // Resumed under --quiet, which still says so.
  const CliRun again = vobb_cli("build " + mesh + " -o " + resumed + args + " --checkpoint " + dir);
  ASSERT_EQ(again.code, 0) << again.err;
  EXPECT_NE(again.err.find("resuming from"), std::string::npos) << again.err;
  EXPECT_EQ(slurp(resumed), slurp(whole));
  EXPECT_FALSE(test::exists(stray)) << "a killed run's temporary file was left in the checkpoint";
  const CliRun other =
      vobb_cli("build " + mesh + " -o " + resumed + args + " --seed 2 --checkpoint " + dir);
  EXPECT_EQ(other.code, 2);
  EXPECT_NE(other.err.find("checkpoint of another build"), std::string::npos) << other.err;
  // A margin is part of what the checkpoint names: the margin-0 state is refused.
  const CliRun margin = vobb_cli("build " + mesh + " -o " + resumed + args +
                                 " --collider-margin 0.1 --checkpoint " + dir);
  EXPECT_EQ(margin.code, 2);
  EXPECT_NE(margin.err.find("checkpoint of another build"), std::string::npos) << margin.err;
  // So is the objective: the default's (omv) state is refused by an obv build.
  const CliRun objective =
      vobb_cli("build " + mesh + " -o " + resumed + args + " --objective obv --checkpoint " + dir);
  EXPECT_EQ(objective.code, 2);
  EXPECT_NE(objective.err.find("checkpoint of another build"), std::string::npos) << objective.err;
  std::system(("rm -rf " + dir).c_str());
  for (const std::string& p : {whole, resumed}) std::remove(p.c_str());
}

// The JSON report without its timings (fields named "seconds" or "..._seconds": a resumed
// run keeps those of its resumed layers, not the whole run's).
nlohmann::json without_seconds(nlohmann::json j) {
  if (j.is_object()) {
    for (auto it = j.begin(); it != j.end();)
      it = it.key().find("seconds") != std::string::npos ? j.erase(it) : std::next(it);
    for (auto& item : j.items()) item.value() = without_seconds(item.value());
  } else if (j.is_array()) {
    for (auto& v : j) v = without_seconds(v);
  }
  return j;
}

// A certification killed (SIGKILL, through a test hook) once its checkpoint holds two finished
// layers, then started again with the same folder, prints the uninterrupted certificate, the
// rationals included, certifying only the layers left; another --path refuses that folder.
TEST(Cli, KilledCertifyResumesToTheSameCertificate) {
  const std::string mesh = test::real_mesh("dino");
  VOBB_REQUIRE_REAL_MESH("dino");
  const std::string dir = test::temp_path("cert_ckpt"), state = dir + "/layers.json";
  const std::string tree = test::temp_path("cert_tree.json");
  std::system(("rm -rf " + dir).c_str());
  ASSERT_EQ(vobb_cli("build " + mesh + " -o " + tree + " --method obbtree --depth 4 --quiet").code,
            0);
  const CliRun whole = vobb_cli("certify " + mesh + " " + tree + " --json --rational --quiet");
  ASSERT_EQ(whole.code, 0) << whole.err;
  EXPECT_TRUE(killed_by_its_hook("VOBB_TEST_KILL_AFTER_CERTIFIED_LAYERS=2 " +
                                 std::string(VOBB_CLI) + " certify " + mesh + " " + tree +
                                 " --json --rational --quiet --checkpoint " + dir))
      << "certify was not killed at its two-layer checkpoint";
  const nlohmann::json saved = nlohmann::json::parse(slurp(state), nullptr, false);
  ASSERT_TRUE(saved.is_object()) << "no checkpoint was saved";
  EXPECT_EQ(saved.at("layers").size(), 2u);
  const std::string stray = dir + "/.vobb-12345-4.tmp";
  { std::ofstream(stray) << "{\"half"; }
  std::filesystem::last_write_time(
      stray, std::filesystem::file_time_type::clock::now() - std::chrono::minutes(5));
  const CliRun again =
      vobb_cli("certify " + mesh + " " + tree + " --json --rational --checkpoint " + dir);
  ASSERT_EQ(again.code, 0) << again.err;
  EXPECT_NE(again.err.find("resuming from"), std::string::npos) << again.err;
  EXPECT_NE(again.err.find("2 of 5 layers done"), std::string::npos) << again.err;
  EXPECT_NE(again.err.find("OBV of 31 boxes: from the checkpoint"), std::string::npos) << again.err;
  size_t layer_lines = 0;
  for (size_t at = 0; (at = again.err.find("certify: layer ", at)) != std::string::npos; ++at)
    ++layer_lines;
  EXPECT_EQ(layer_lines, 3u) << again.err;
  EXPECT_FALSE(test::exists(stray)) << "a killed run's temporary file was left in the checkpoint";
  EXPECT_EQ(without_seconds(nlohmann::json::parse(again.out)),
            without_seconds(nlohmann::json::parse(whole.out)));
  const CliRun other =
      vobb_cli("certify " + mesh + " " + tree + " --path clip --quiet --checkpoint " + dir);
  EXPECT_EQ(other.code, 2);
  EXPECT_NE(other.err.find("checkpoint of another certification"), std::string::npos) << other.err;
  std::system(("rm -rf " + dir).c_str());
  std::remove(tree.c_str());
}

// certify --json says, per layer, the enclosure of each value and how its double and its bound
// were decided; the doubles lie in their enclosures, and with --rational each rational rounds
// to the double printed and lies in its enclosure. A checkpoint folder of the format before
// enclosures (version 1) is refused in one line, exit 2.
TEST(Cli, CertifyJsonGivesEnclosuresAndHowEachValueWasDecided) {
  const std::string mesh = test::real_mesh("dino");
  VOBB_REQUIRE_REAL_MESH("dino");
  const std::string tree = test::temp_path("encl_tree.json"), dir = test::temp_path("encl_ckpt");
  std::system(("rm -rf " + dir).c_str());
  ASSERT_EQ(vobb_cli("build " + mesh + " -o " + tree + " --method obbtree --depth 5 --quiet").code,
            0);
  const CliRun r = vobb_cli("certify " + mesh + " " + tree + " --json --rational");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j.at("levels").size(), 6u);
  for (const nlohmann::json& l : j["levels"]) {
    // The progress line of the layer gives the same counts of values refined and sent to
    // rationals as the JSON.
    const std::string line = "certify: layer " + std::to_string(l.at("level").get<int>()) + "/5:";
    const size_t at = r.err.find(line);
    ASSERT_NE(at, std::string::npos) << line << "\n" << r.err;
    const std::string text = r.err.substr(at, r.err.find('\n', at) - at);
    EXPECT_NE(
        text.find("in 256 bits: " + std::to_string(l.at("refined_obv").get<int>()) + " OBV, " +
                  std::to_string(l.at("refined_overlap").get<int>()) + " overlap terms"),
        std::string::npos)
        << text;
    EXPECT_NE(text.find("in rationals: " + std::to_string(l.at("exact_obv").get<int>()) + " OBV, " +
                        std::to_string(l.at("exact_overlap").get<int>()) + " overlap terms"),
              std::string::npos)
        << text;
    EXPECT_LE(l.at("exact_obv").get<size_t>(), l.at("boxes").get<size_t>());
    for (const char* v : {"omv", "sum_obv", "overlap"}) {
      const double d = l.at(v).get<double>();
      const nlohmann::json& e = l.at(std::string(v) + "_enclosure");
      EXPECT_LE(e.at(0).get<double>(), d) << v;
      EXPECT_LE(d, e.at(1).get<double>()) << v;
      const Rational q(l.at(std::string(v) + "_rational").get<std::string>());
      EXPECT_EQ(to_double_nearest(q), d) << v;
      EXPECT_LE(Rational(e.at(0).get<double>()), q) << v;
      EXPECT_LE(q, Rational(e.at(1).get<double>())) << v;
    }
    for (const char* by : {"omv_rounded_by", "sum_obv_rounded_by", "overlap_rounded_by"})
      EXPECT_EQ(l.at(by), "exact")
          << by << ": with --rational every value is the rationals' rounded";
    EXPECT_TRUE(l.at("bound_by") == "filter" || l.at("bound_by") == "exact");
  }
  const Rational e(j.at("weighted_error_rational").get<std::string>());
  EXPECT_EQ(to_double_nearest(e), j.at("weighted_error").get<double>());
  EXPECT_LE(Rational(j.at("weighted_error_enclosure").at(0).get<double>()), e);
  EXPECT_LE(e, Rational(j.at("weighted_error_enclosure").at(1).get<double>()));
  // The default run prints the same doubles without computing the rationals.
  const CliRun plain = vobb_cli("certify " + mesh + " " + tree + " --json --quiet");
  ASSERT_EQ(plain.code, 0) << plain.err;
  const nlohmann::json p = nlohmann::json::parse(plain.out);
  EXPECT_EQ(p.at("weighted_error"), j.at("weighted_error"));
  size_t filtered = 0;
  for (size_t i = 0; i < 6; ++i) {
    const nlohmann::json& l = p["levels"][i];
    for (const char* v : {"omv", "sum_obv", "overlap"}) {
      EXPECT_EQ(l.at(v), j["levels"][i].at(v)) << i << " " << v;
      EXPECT_FALSE(l.contains(std::string(v) + "_rational")) << i << " " << v;
      const std::string by = l.at(std::string(v) + "_rounded_by");
      EXPECT_TRUE(by == "filter" || by == "exact") << i << " " << v << ": " << by;
      filtered += by == "filter";
    }
  }
  // The filter rounds every value whose enclosure holds one nearest double; rationals only
  // break the rare ties, so a generic tree has some of its 18 values rounded by the filter.
  EXPECT_GT(filtered, 0u);
  const std::string e_by = p.at("weighted_error_rounded_by");
  EXPECT_TRUE(e_by == "filter" || e_by == "exact") << e_by;
  EXPECT_EQ(j.at("weighted_error_rounded_by"), "exact");
  // A format-1 folder: refused before any work.
  ASSERT_EQ(vobb_cli("certify " + mesh + " " + tree + " --quiet --checkpoint " + dir).code, 0);
  nlohmann::json obv = nlohmann::json::parse(slurp(dir + "/obv.json"));
  obv["version"] = 1;
  obv.erase("sha256");
  const std::string body = obv.dump();
  obv["sha256"] = sha256_hex(body.data(), body.size());
  std::ofstream(dir + "/obv.json", std::ios::binary) << obv.dump();
  const CliRun old = vobb_cli("certify " + mesh + " " + tree + " --quiet --checkpoint " + dir);
  EXPECT_EQ(old.code, 2);
  EXPECT_NE(old.err.find("older vobb (format 1"), std::string::npos) << old.err;
  EXPECT_EQ(std::count(old.err.begin(), old.err.end(), '\n'), 1) << old.err;
  std::system(("rm -rf " + dir).c_str());
  std::remove(tree.c_str());
}

// compare --checkpoint keeps each tree's certification beside the build's state: killed during
// the baseline's certification, after two of its layers, and started again, it resumes that
// certification and prints the uninterrupted report.
TEST(Cli, KilledCompareResumesItsCertification) {
  const std::string mesh = test::real_mesh("dino");
  VOBB_REQUIRE_REAL_MESH("dino");
  const std::string dir = test::temp_path("cmp_ckpt");
  std::system(("rm -rf " + dir).c_str());
  const std::string args = " --depth 3 --m 8 --lloyd 1 --backend cpu --json --quiet";
  const CliRun whole = vobb_cli("compare " + mesh + args);
  ASSERT_EQ(whole.code, 0) << whole.err;
  EXPECT_TRUE(killed_by_its_hook("VOBB_TEST_KILL_AFTER_CERTIFIED_LAYERS=2 " +
                                 std::string(VOBB_CLI) + " compare " + mesh + args +
                                 " --checkpoint " + dir))
      << "compare was not killed at its two-layer checkpoint";
  EXPECT_TRUE(test::exists(dir + "/certify-obbtree/layers.json"));
  // Killed in the baseline's certification: the variational one's folder (made, and checked,
  // at the start) holds nothing yet.
  EXPECT_FALSE(test::exists(dir + "/certify-variational/obv.json"))
      << "killed in the baseline's certification";
  const CliRun again = vobb_cli(
      "compare " + mesh + " --depth 3 --m 8 --lloyd 1 --backend cpu --json --checkpoint " + dir);
  ASSERT_EQ(again.code, 0) << again.err;
  EXPECT_NE(again.err.find("resuming from " + dir +
                           "/certify-obbtree (the boxes' OBV, 2 of 4 layers done)"),
            std::string::npos)
      << again.err;
  // The saved layers were used, not certified again: two of the baseline's four layers.
  EXPECT_NE(again.err.find("vobb: 2 of 4 layers: from the checkpoint\n"), std::string::npos)
      << again.err;
  EXPECT_EQ(without_seconds(nlohmann::json::parse(again.out)),
            without_seconds(nlohmann::json::parse(whole.out)));
  EXPECT_TRUE(test::exists(dir + "/certify-variational/layers.json"));
  std::system(("rm -rf " + dir).c_str());
}

}  // namespace
}  // namespace vobb
