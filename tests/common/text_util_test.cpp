#include "common/text_util.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>

#include "test_common.h"

namespace vobb {
namespace {

TEST(TextUtil, FileNameParts) {
  EXPECT_EQ(basename_of("dir/sub/dino.off"), "dino.off");
  EXPECT_EQ(basename_of("dino.off"), "dino.off");
  EXPECT_EQ(extension_of("dir/Dino.OFF"), "off");
  EXPECT_EQ(extension_of("dir.v2/mesh"), "");
  EXPECT_EQ(extension_of("a/b.tar.gz"), "gz");
}

// The shortest form must read back as the same double, bit for bit, over the whole range:
// subnormals, the extremes, both zeros and random bit patterns.
TEST(TextUtil, FormatDoubleReadsBackExactly) {
  std::vector<double> values = {0.0,
                                -0.0,
                                0.1,
                                1.0 / 3,
                                -2.5e-300,
                                1e300,
                                std::numeric_limits<double>::denorm_min(),
                                std::numeric_limits<double>::min(),
                                std::numeric_limits<double>::max(),
                                -std::numeric_limits<double>::max()};
  std::mt19937_64 rng(7);
  while (values.size() < 20000) {
    const uint64_t bits = rng();
    double v;
    std::memcpy(&v, &bits, sizeof v);
    if (std::isfinite(v)) values.push_back(v);
  }
  for (double v : values) {
    const std::string s = format_double(v);
    const double back = std::strtod(s.c_str(), nullptr);
    EXPECT_EQ(std::memcmp(&back, &v, sizeof v), 0) << s;
    std::string appended = "x ";
    append_double(&appended, v);
    EXPECT_EQ(appended, "x " + s);
  }
  // Shortest: one decimal digit where one suffices.
  EXPECT_EQ(format_double(0.1), "0.1");
  std::string xyz;
  append_xyz(&xyz, Vec3(1, -0.5, 0.1));
  EXPECT_EQ(xyz, "1 -0.5 0.1");
}

// What would block (a FIFO), never end (/dev/zero) or fail late (a folder) is refused before
// it is opened, each in one line naming the file; a regular file is read whole, NUL bytes
// included.
TEST(TextUtil, OnlyRegularFilesAreRead) {
  const std::string file = test::temp_path("tu_file.bin");
  const std::string bytes("ab\0cd\n", 6);
  {
    std::ofstream f(file, std::ios::binary);
    f << bytes;
  }
  uint64_t size = 0;
  ASSERT_TRUE(check_regular_file(file, "tu_file.bin", "mesh", &size));
  EXPECT_EQ(size, bytes.size());
  std::string content;
  ASSERT_TRUE(read_regular_file(file, "tu_file.bin", "mesh", &content));
  EXPECT_EQ(content, bytes);

  const std::string fifo = test::temp_path("tu_fifo");
  std::remove(fifo.c_str());
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  struct Case {
    std::string path, says;
  };
  for (const Case& c :
       {Case{fifo, "x: not a regular file"}, Case{"/dev/zero", "x: not a regular file"},
        Case{::testing::TempDir(), "x: is a directory, not a mesh"},
        Case{test::temp_path("tu_missing"), "x: cannot open: No such file or directory"}}) {
    const Status s = check_regular_file(c.path, "x", "mesh", &size);
    EXPECT_FALSE(s) << c.path;
    EXPECT_EQ(s.message(), c.says) << c.path;
    EXPECT_FALSE(read_regular_file(c.path, "x", "mesh", &content)) << c.path;
  }
  std::remove(fifo.c_str());
  std::remove(file.c_str());
}

// A file that must be text is refused on a NUL byte among its first kTextProbeBytes, before
// the rest is read: a sparse gigabyte of zeros comes back as its first bytes only. A NUL
// further in is the caller's to find (the file is read whole).
TEST(TextUtil, BinaryTextFileIsRefusedFromItsFirstBytes) {
  const std::string file = test::temp_path("tu_sparse.json");
  { std::ofstream f(file, std::ios::binary); }
  std::filesystem::resize_file(file, uint64_t{1} << 30);
  std::string content;
  Status s = read_regular_file(file, "tu_sparse.json", "tree file", &content, true);
  EXPECT_FALSE(s);
  EXPECT_EQ(s.message(), "tu_sparse.json: binary data in a text format");
  EXPECT_EQ(content.size(), kTextProbeBytes);
  std::string late(kTextProbeBytes, ' ');
  late += '\0';
  {
    std::ofstream f(file, std::ios::binary | std::ios::trunc);
    f << late;
  }
  ASSERT_TRUE(read_regular_file(file, "x", "tree file", &content, true));
  EXPECT_EQ(content, late);
  std::remove(file.c_str());
}

// Absent: nothing there, or a path through a file (ENOTDIR). A file, a folder, a FIFO is there,
// so that reading it says what is wrong with it.
TEST(TextUtil, PathAbsentOnlyWhereNothingIs) {
  const std::string file = test::temp_path("tu_absent.txt");
  std::ofstream(file) << "x";
  EXPECT_FALSE(path_absent(file));
  EXPECT_FALSE(path_absent(::testing::TempDir()));
  EXPECT_FALSE(path_absent("/dev/zero"));
  EXPECT_TRUE(path_absent(test::temp_path("tu_nothing_here")));
  EXPECT_TRUE(path_absent(file + "/below_a_file"));
  std::remove(file.c_str());
  EXPECT_TRUE(path_absent(file));
}

}  // namespace
}  // namespace vobb
