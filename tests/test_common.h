// Shared helpers for the test suite: data locations (passed through the build) and the
// named lists of real meshes.
#pragma once

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "common/mesh.h"

namespace vobb::test {

// How far from orthonormal the axes orthonormalize() (common/obb.cpp) makes are, as a test
// measures them. A normalised vector's norm is 1 to about 3 eps, and the test's norm() adds 2.
// a0 . a1 is what the second projection pass leaves (about 3 eps) plus the test's dot product
// (3 eps); a2 = a0 x a1 carries the cross product's rounding (2 eps a component, 3.5 eps in
// direction), plus the second pass's move of a1 (2 eps) after a2 was made, plus the dot
// product's 3 eps: under 9 eps, taken as 12.
inline constexpr double kOrthonormalTol = 12 * std::numeric_limits<double>::epsilon();
// (a0 x a1) . a2 against 1: the three norms' 9 eps, plus the test's cross product and dot
// product (5 eps): under 14 eps, taken as 16.
inline constexpr double kRightHandedTol = 16 * std::numeric_limits<double>::epsilon();

inline std::string data_dir() { return VOBB_TEST_DATA_DIR; }
inline std::string real_mesh(const std::string& name) {
  return std::string(VOBB_REAL_MESH_DIR) + "/" + name + ".off";
}
inline bool exists(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0;
}

// Real meshes a prototype found clean, and ones it found broken (DESIGN §8).
inline const std::vector<std::string>& clean_real_meshes() {
  static const std::vector<std::string> k = {"dino",    "elephant",    "knot1", "armadillo",
                                             "bunny00", "triceratops", "homer", "fandisk"};
  return k;
}

// CI sets VOBB_REQUIRE_REAL_MESHES=1 (.ci/run): there a missing real mesh fails the test
// instead of skipping it, so a failed fetch cannot turn the suite quietly green.
inline bool real_meshes_required() {
  const char* v = std::getenv("VOBB_REQUIRE_REAL_MESHES");
  return v != nullptr && std::string(v) == "1";
}

// CI also sets VOBB_REQUIRE_EVERY_CHECK=1: there a check that this machine cannot run (one that
// needs a second CPU, or gnuplot) fails the test instead of being left out.
inline bool every_check_required() {
  const char* v = std::getenv("VOBB_REQUIRE_EVERY_CHECK");
  return v != nullptr && std::string(v) == "1";
}

// Whether a check that needs `what` runs here: true where it is `available`; otherwise the
// test fails where every check is required, and says on stdout that the check is left out.
inline bool check_runs(bool available, const std::string& what) {
  if (available) return true;
  if (every_check_required())
    ADD_FAILURE() << "a check needs " << what << " (VOBB_REQUIRE_EVERY_CHECK=1)";
  else
    std::printf("left out here: a check that needs %s\n", what.c_str());
  return false;
}

// Skips the current test, saying why, when real meshes are not there (offline machine); fails
// it where they are required.
#define VOBB_SKIP_WITHOUT_REAL_MESHES(why)                                                        \
  do {                                                                                            \
    if (::vobb::test::real_meshes_required()) FAIL() << (why) << " (VOBB_REQUIRE_REAL_MESHES=1)"; \
    GTEST_SKIP() << (why) << ": run data/fetch_meshes.sh";                                        \
  } while (0)

#define VOBB_REQUIRE_REAL_MESH(name)                                                    \
  do {                                                                                  \
    if (!::vobb::test::exists(::vobb::test::real_mesh(name)))                           \
      VOBB_SKIP_WITHOUT_REAL_MESHES(std::string("real mesh ") + (name) + " is absent"); \
  } while (0)

// The whole file's bytes ("" when it cannot be read).
inline std::string slurp(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

// The number of triangles an OFF file's faces make (a k-gon gives k - 2), read here from the
// file with nothing of vobb's reader: the header's counts, then the first number of each face
// line. Lines that are blank or start with '#' are skipped. -1 when the file does not read so.
inline long off_triangle_count(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  auto next = [&]() -> bool {
    while (std::getline(in, line)) {
      const size_t at = line.find_first_not_of(" \t\r");
      if (at != std::string::npos && line[at] != '#') return true;
    }
    return false;
  };
  if (!next() || line.find("OFF") == std::string::npos) return -1;
  long vertices = 0, faces = 0;
  if (!next() || !(std::istringstream(line) >> vertices >> faces)) return -1;
  for (long i = 0; i < vertices; ++i)
    if (!next()) return -1;
  long triangles = 0;
  for (long i = 0; i < faces; ++i) {
    long k = 0;
    if (!next() || !(std::istringstream(line) >> k) || k < 3) return -1;
    triangles += k - 2;
  }
  return triangles;
}

inline std::string temp_dir() {
  const char* dir = std::getenv("TMPDIR");
  return dir ? dir : "/tmp";
}
inline std::string temp_prefix() { return "vobb_test_" + std::to_string(::getpid()) + "_"; }
inline std::string temp_path(const std::string& name) {
  return temp_dir() + "/" + temp_prefix() + name;
}

// What a test process leaves under its temp_path names (a test that stops at a failed ASSERT,
// or one that does not remove its files) goes when the process exits: every entry of the temp
// folder that begins with this process's prefix, files and folders alike.
struct TempCleaner {
  ~TempCleaner() {
    // Never throws (a destructor at exit): every step takes an error code.
    std::error_code ec;
    const std::string prefix = temp_prefix();
    std::vector<std::filesystem::path> mine;
    for (std::filesystem::directory_iterator it(temp_dir(), ec), end; !ec && it != end;
         it.increment(ec))
      if (it->path().filename().string().rfind(prefix, 0) == 0) mine.push_back(it->path());
    for (const auto& p : mine) std::filesystem::remove_all(p, ec);
  }
};
inline TempCleaner temp_cleaner;

// Runs the `vobb` command line with `args` (a shell word list): exit code, stdout, stderr.
struct CliRun {
  int code;
  std::string out, err;
};
// `prefix` goes before the command in the shell line (such as "cd DIR && ").
inline CliRun vobb_cli_in(const std::string& prefix, const std::string& args) {
  const std::string err_path = temp_path("stderr.txt");
  const std::string cmd = prefix + std::string(VOBB_CLI) + " " + args + " 2>" + err_path;
  CliRun r;
  FILE* p = ::popen(cmd.c_str(), "r");
  char buf[4096];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) r.out.append(buf, n);
  const int status = ::pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream e(err_path);
  std::stringstream ss;
  ss << e.rdbuf();
  r.err = ss.str();
  std::remove(err_path.c_str());
  return r;
}
inline CliRun vobb_cli(const std::string& args) { return vobb_cli_in("", args); }

// Crossing sheets: k triangles, each with vertices of its own, in the planes through the z
// axis at angles pi i / k. Each holds the segment from (0, 0, -1) to (0, 0, 1), so every pair
// meets there: k (k - 1) / 2 meeting pairs, none sharing a vertex index (a reader that welds
// equal vertices makes them all share (0, 0, 1)). Open, so not a solid either way.
inline Mesh pinwheel(int k) {
  Mesh m;
  for (int i = 0; i < k; ++i) {
    const double a = M_PI * i / k;
    const int32_t b = static_cast<int32_t>(m.vertices.size());
    m.vertices.push_back(Vec3(-std::cos(a), -std::sin(a), -1));
    m.vertices.push_back(Vec3(std::cos(a), std::sin(a), -1));
    m.vertices.push_back(Vec3(0, 0, 1));
    m.faces.push_back({b, b + 1, b + 2});
  }
  return m;
}

// `m` as an OFF file at `path`, coordinates to 17 significant digits.
inline void write_off(const Mesh& m, const std::string& path) {
  std::ofstream f(path);
  f.precision(17);
  f << "OFF\n" << m.vertices.size() << " " << m.faces.size() << " 0\n";
  for (const Vec3& v : m.vertices) f << v.x() << " " << v.y() << " " << v.z() << "\n";
  for (const Face& t : m.faces) f << "3 " << t[0] << " " << t[1] << " " << t[2] << "\n";
}

// Sets (or, with nullptr, unsets) an environment variable for the scope, and puts back what
// was there before.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const char* value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old, had_ = true;
    if (value != nullptr)
      ::setenv(name, value, 1);
    else
      ::unsetenv(name);
  }
  ~ScopedEnv() {
    if (had_)
      ::setenv(name_.c_str(), old_.c_str(), 1);
    else
      ::unsetenv(name_.c_str());
  }
  ScopedEnv(const ScopedEnv&) = delete;
  ScopedEnv& operator=(const ScopedEnv&) = delete;

 private:
  std::string name_, old_;
  bool had_ = false;
};

}  // namespace vobb::test
