// Shared helpers for the test suite: data locations (passed through the build) and the
// named lists of real meshes.
#pragma once

#include <gtest/gtest.h>

#include <string>
#include <sys/stat.h>
#include <vector>

namespace vobb::test {

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
  static const std::vector<std::string> k = {"dino", "elephant", "knot1", "armadillo", "bunny00",
                                             "triceratops", "homer", "fandisk"};
  return k;
}

// Skips the current test, saying why, when a real mesh is not there (offline machine).
#define VOBB_REQUIRE_REAL_MESH(name)                                                         \
  do {                                                                                       \
    if (!::vobb::test::exists(::vobb::test::real_mesh(name)))                                \
      GTEST_SKIP() << "real mesh " << (name) << " is absent: run data/fetch_meshes.sh";      \
  } while (0)

inline std::string temp_path(const std::string& name) {
  const char* dir = std::getenv("TMPDIR");
  return std::string(dir ? dir : "/tmp") + "/vobb_test_" + std::to_string(::getpid()) + "_" + name;
}

}  // namespace vobb::test
