#include "common/io/assimp_reader.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
#include <filesystem>
#include <fstream>

#include "common/io/mesh_io.h"
#include "test_common.h"
#include "vobb/config.h"

namespace vobb {
namespace {

#if VOBB_HAVE_ASSIMP
void write_text(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

// A LightWave scene names its object file, which assimp opens itself. A pipe there blocked it
// until the wall-clock deadline (50 s by default), which then blamed CPU time: assimp is given
// regular files only, so the scene is refused at once, in one line.
TEST(AssimpReader, ASceneNamingAPipeIsRefusedAtOnce) {
  const std::string dir = test::temp_path("lws_dir");
  std::filesystem::remove_all(dir);
  std::filesystem::create_directory(dir);
  const std::string fifo = dir + "/object.lwo", scene = dir + "/scene.lws";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  write_text(scene, "LWSC\n3\n\nFirstFrame 1\nLastFrame 60\nLoadObjectLayer 1 " + fifo + "\n");
  LoadedMesh lm;
  const auto t0 = std::chrono::steady_clock::now();
  const Status s = load_mesh(scene, &lm);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_FALSE(s);
  EXPECT_EQ(s.message().rfind("scene.lws: cannot read: assimp made an incomplete scene", 0), 0u)
      << s.message();
  EXPECT_EQ(s.message().find('\n'), std::string::npos) << s.message();
  // Far below the wall-clock deadline, 2 x 20 s + 10 s: nothing waited.
  EXPECT_LT(seconds, 10.0) << s.message();
  std::filesystem::remove_all(dir);
}

// Each of these few bytes crashes assimp 5.2's importer (found by mutating small files): an
// ASE mesh whose face list is empty makes it dereference a null pointer, and an NFF file that
// ends in a bare "p" fails an assertion in its triangulation (abort). Each read must come back
// as a one-line refusal, and the process must go on.
TEST(AssimpReader, ImporterCrashesBecomeOneLineRefusals) {
  const struct {
    const char* name;
    const char* text;
  } cases[] = {
      {"crash.ase", "*GEOMOBJECT *MESH {*MESH_NUMFACES 1{}*MESH_FACE_LIST {}}"},
      {"crash.nff",
       "p 3\n0 0 0\n0 0 1\n0 1 1\np 3\n0 0 0\n0 1 1\n0 1 0\np 3\n1 0 0\n1 1 0\n1 1 1\np"},
  };
  for (const auto& c : cases) {
    const std::string path = test::temp_path(c.name);
    write_text(path, c.text);
    LoadedMesh lm;
    const Status s = load_mesh(path, &lm);
    EXPECT_FALSE(s) << c.name;
    std::string said = ": cannot read: assimp's importer crashed";
#if defined(__SANITIZE_ADDRESS__)
    // AddressSanitizer's SIGSEGV handler reports the null dereference and exits with status 1,
    // so the child does not die by the signal: the parent sees an importer that ended without a
    // result. Its handler leaves SIGABRT alone (NFF's failed assertion still dies by it).
    if (std::string(c.name) == "crash.ase") said = ": cannot read: assimp's importer ended";
#endif
    EXPECT_NE(s.message().find(std::string(c.name) + said), std::string::npos) << s.message();
    EXPECT_EQ(s.message().find('\n'), std::string::npos);
    std::remove(path.c_str());
  }
}

// These 20 bytes of SMD make assimp 5.2 loop forever. With a 1 s CPU limit the read is
// refused once the limit is spent: the wall time is bounded by the limit plus the second that
// SIGKILL follows SIGXCPU by, plus start-up; 30 s leaves room for a machine that is busy.
TEST(AssimpReader, ALoopingImportStopsAtTheCpuLimit) {
  const std::string path = test::temp_path("loop.smd");
  write_text(path, "version 1\nnodes\n0 \"r");
  LoadedMesh lm;
  const auto t0 = std::chrono::steady_clock::now();
  const Status s = load_with_assimp(path, "loop.smd", &lm, 1.0);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_FALSE(s);
  EXPECT_NE(s.message().find("loop.smd: cannot read: assimp did not finish within 1 s of CPU time"),
            std::string::npos)
      << s.message();
  EXPECT_LT(wall, 30.0);
  std::remove(path.c_str());
}

// A good file comes back through the child process unchanged: every vertex and face.
TEST(AssimpReader, AGoodFileComesBackWhole) {
  const std::string path = test::temp_path("tetra.raw");
  write_text(path, "0 0 0 0 1 0 1 0 0\n0 0 0 1 0 0 0 0 1\n0 0 0 0 0 1 0 1 0\n1 0 0 0 1 0 0 0 1\n");
  LoadedMesh lm;
  const Status s = load_with_assimp(path, "tetra.raw", &lm, assimp_cpu_seconds(100));
  ASSERT_TRUE(s) << s.message();
  ASSERT_EQ(lm.mesh.faces.size(), 4u);
  ASSERT_EQ(lm.mesh.vertices.size(), 12u);  // RAW repeats each corner; load_mesh welds them
  EXPECT_TRUE(lm.single_precision);
  EXPECT_EQ(lm.format, "raw");
  for (size_t f = 0; f < 4; ++f)
    for (int k = 0; k < 3; ++k) EXPECT_EQ(lm.mesh.faces[f][k], static_cast<int32_t>(3 * f + k));
  EXPECT_EQ(lm.mesh.vertices[3], Vec3(0, 0, 0));
  EXPECT_EQ(lm.mesh.vertices[4], Vec3(1, 0, 0));
  EXPECT_EQ(lm.mesh.vertices[11], Vec3(0, 0, 1));
  std::remove(path.c_str());
}
#else
TEST(AssimpReader, NotBuilt) { GTEST_SKIP() << "this build has no assimp"; }
#endif

}  // namespace
}  // namespace vobb
