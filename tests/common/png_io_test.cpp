// PNG I/O (common/png_io.h): pixels survive a round trip, opaque images are stored as RGB and
// translucent ones as RGBA, 8-bit grey files (with and without alpha) from another writer are
// expanded to RGBA, and bad images, files and paths are refused in one line naming the file,
// leaving nothing half-written.
#include "common/png_io.h"

#include <gtest/gtest.h>
#include <png.h>

#include <cstdio>
#include <filesystem>

#include "test_common.h"

namespace vobb {
namespace {

RgbaImage pattern(int width, int height, bool opaque) {
  RgbaImage img;
  img.width = width;
  img.height = height;
  for (int i = 0; i < width * height * 4; ++i)
    img.rgba.push_back(opaque && i % 4 == 3 ? 255 : static_cast<uint8_t>(i * 53 + 7));
  return img;
}

// The colour type of a PNG (byte 25: the 8-byte signature, the IHDR chunk's length and type,
// width, height and bit depth come first; PNG specification §11.2.2): 2 is RGB, 6 is RGBA.
int colour_type(const std::string& png) {
  return png.size() > 25 ? static_cast<uint8_t>(png[25]) : -1;
}

void expect_one_line_naming(const Status& s, const std::string& name) {
  EXPECT_FALSE(s);
  EXPECT_EQ(s.message().rfind(name + ": ", 0), 0u) << s.message();
  EXPECT_EQ(s.message().find('\n'), std::string::npos) << s.message();
}

TEST(PngIo, TranslucentImageRoundTripsAsRgba) {
  const RgbaImage img = pattern(5, 3, false);
  std::string bytes;
  ASSERT_TRUE(encode_png(img, &bytes, "mem"));
  EXPECT_EQ(colour_type(bytes), 6);
  const std::string path = test::temp_path("translucent.png");
  ASSERT_TRUE(write_png(path, img));
  EXPECT_EQ(test::slurp(path), bytes);  // write_png writes what encode_png encodes
  RgbaImage back;
  const Status r = read_png(path, &back);
  std::remove(path.c_str());
  ASSERT_TRUE(r) << r.message();
  EXPECT_EQ(back.width, 5);
  EXPECT_EQ(back.height, 3);
  EXPECT_TRUE(back.rgba == img.rgba);
}

// Every alpha 255: stored as RGB (a quarter fewer bytes to compress), read back with alpha 255,
// so the pixels are the same.
TEST(PngIo, OpaqueImageIsStoredAsRgbAndReadBackWhole) {
  const RgbaImage img = pattern(7, 4, true);
  std::string bytes;
  ASSERT_TRUE(encode_png(img, &bytes, "mem"));
  EXPECT_EQ(colour_type(bytes), 2);
  const std::string path = test::temp_path("opaque.png");
  ASSERT_TRUE(write_png(path, img));
  RgbaImage back;
  const Status r = read_png(path, &back);
  std::remove(path.c_str());
  ASSERT_TRUE(r) << r.message();
  EXPECT_EQ(back.width, 7);
  EXPECT_EQ(back.height, 4);
  EXPECT_TRUE(back.rgba == img.rgba);
}

// Files vobb does not write itself: 8-bit grey (each grey g becomes g, g, g, 255) and grey with
// alpha, written here with libpng's simplified API.
TEST(PngIo, ReadsGreyFilesOfOtherWritersAsRgba) {
  const std::string path = test::temp_path("grey.png");
  const uint8_t grey[6] = {0, 40, 80, 120, 200, 255};  // 3 x 2
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  image.width = 3;
  image.height = 2;
  image.format = PNG_FORMAT_GRAY;
  ASSERT_NE(png_image_write_to_file(&image, path.c_str(), 0, grey, 0, nullptr), 0) << image.message;
  RgbaImage back;
  Status r = read_png(path, &back);
  ASSERT_TRUE(r) << r.message();
  ASSERT_EQ(back.width, 3);
  ASSERT_EQ(back.height, 2);
  ASSERT_EQ(back.rgba.size(), 24u);
  for (int i = 0; i < 6; ++i) {
    SCOPED_TRACE(i);
    const uint8_t* p = back.pixel(i % 3, i / 3);
    EXPECT_EQ(p[0], grey[i]);
    EXPECT_EQ(p[1], grey[i]);
    EXPECT_EQ(p[2], grey[i]);
    EXPECT_EQ(p[3], 255);
  }
  const uint8_t grey_alpha[4] = {10, 20, 30, 40};  // 2 x 1, (grey, alpha) pairs
  image = png_image{};
  image.version = PNG_IMAGE_VERSION;
  image.width = 2;
  image.height = 1;
  image.format = PNG_FORMAT_GA;
  ASSERT_NE(png_image_write_to_file(&image, path.c_str(), 0, grey_alpha, 0, nullptr), 0)
      << image.message;
  r = read_png(path, &back);
  std::remove(path.c_str());
  ASSERT_TRUE(r) << r.message();
  const std::vector<uint8_t> want = {10, 10, 10, 20, 30, 30, 30, 40};
  EXPECT_EQ(back.rgba, want);
}

TEST(PngIo, RejectsMalformedImagesAndFiles) {
  RgbaImage bad;
  bad.width = 3;
  bad.height = 2;
  bad.rgba.assign(5, 0);
  const std::string path = test::temp_path("bad.png");
  std::remove(path.c_str());
  expect_one_line_naming(write_png(path, bad), path);
  EXPECT_FALSE(test::exists(path));  // nothing half-written
  RgbaImage empty;
  std::string bytes;
  expect_one_line_naming(encode_png(empty, &bytes, "mem"), "mem");
  EXPECT_TRUE(bytes.empty());
  RgbaImage back;
  expect_one_line_naming(read_png(path, &back), path);  // absent
  // Not a PNG at all.
  {
    FILE* out = std::fopen(path.c_str(), "wb");
    ASSERT_NE(out, nullptr);
    std::fputs("P6 1 1 255 xyz", out);
    std::fclose(out);
  }
  Status s = read_png(path, &back);
  expect_one_line_naming(s, path);
  EXPECT_NE(s.message().find("not a PNG"), std::string::npos) << s.message();
  // A truncated PNG: the first half of a valid one.
  ASSERT_TRUE(encode_png(pattern(17, 9, false), &bytes, "mem"));
  FILE* out = std::fopen(path.c_str(), "wb");
  ASSERT_NE(out, nullptr);
  std::fwrite(bytes.data(), 1, bytes.size() / 2, out);
  std::fclose(out);
  s = read_png(path, &back);
  std::remove(path.c_str());
  expect_one_line_naming(s, path);
  EXPECT_TRUE(back.rgba.empty());
  EXPECT_EQ(back.width, 0);
}

// A folder in place of the file: refused, and the folder left as it was.
TEST(PngIo, RefusesToWriteOverAFolder) {
  const std::filesystem::path dir = test::temp_path("png_dir");
  std::filesystem::remove_all(dir);
  std::filesystem::create_directory(dir);
  EXPECT_FALSE(write_png(dir.string(), pattern(2, 2, true)));
  EXPECT_TRUE(std::filesystem::is_directory(dir));
  EXPECT_TRUE(std::filesystem::is_empty(dir));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace vobb
