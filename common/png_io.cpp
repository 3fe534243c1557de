#include "common/png_io.h"

#include <png.h>

#include <cerrno>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <memory>

#include "common/atomic_file.h"

namespace vobb {

namespace {

// libpng reports errors through a callback that must not return; it longjmps back to the
// setjmp in the caller. The message goes to this buffer so the caller can report it.
struct PngErrorSink {
  char message[256] = "unknown libpng error";
};

void on_png_error(png_structp png, png_const_charp msg) {
  auto* sink = static_cast<PngErrorSink*>(png_get_error_ptr(png));
  std::snprintf(sink->message, sizeof sink->message, "%s", msg != nullptr ? msg : "libpng error");
  png_longjmp(png, 1);
}

void on_png_warning(png_structp, png_const_charp) {}

void append_to_string(png_structp png, png_bytep data, png_size_t n) {
  static_cast<std::string*>(png_get_io_ptr(png))->append(reinterpret_cast<const char*>(data), n);
}

void flush_nothing(png_structp) {}

}  // namespace

Status encode_png(const RgbaImage& image, std::string* out, const std::string& display) {
  out->clear();
  if (image.width < 1 || image.height < 1 ||
      image.rgba.size() != static_cast<size_t>(image.width) * image.height * 4)
    return Status::error(display + ": cannot encode PNG: image is " + std::to_string(image.width) +
                         "x" + std::to_string(image.height) + " with " +
                         std::to_string(image.rgba.size()) + " bytes");
  PngErrorSink sink;
  png_structp png =
      png_create_write_struct(PNG_LIBPNG_VER_STRING, &sink, on_png_error, on_png_warning);
  if (png == nullptr) return Status::error(display + ": cannot encode PNG: out of memory");
  png_infop info = png_create_info_struct(png);
  // An opaque image is written as RGB: a quarter fewer bytes to compress, same pixels on
  // reading back (read_png restores alpha 255).
  bool opaque = true;
  for (size_t i = 3; i < image.rgba.size() && opaque; i += 4) opaque = image.rgba[i] == 255;
  std::vector<uint8_t> rgb;
  if (opaque) {
    rgb.reserve(image.rgba.size() / 4 * 3);
    for (size_t i = 0; i < image.rgba.size(); i += 4)
      rgb.insert(rgb.end(), &image.rgba[i], &image.rgba[i] + 3);
  }
  const size_t channels = opaque ? 3 : 4;
  std::vector<png_const_bytep> rows(image.height);
  for (int y = 0; y < image.height; ++y)
    rows[y] =
        opaque ? rgb.data() + static_cast<size_t>(y) * image.width * channels : image.pixel(0, y);
  if (info == nullptr || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    out->clear();
    return Status::error(display + ": cannot encode PNG: " + sink.message);
  }
  png_set_write_fn(png, out, append_to_string, flush_nothing);
  png_set_IHDR(png, info, image.width, image.height, 8,
               opaque ? PNG_COLOR_TYPE_RGB : PNG_COLOR_TYPE_RGBA, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_set_compression_level(png, 9);
  png_write_info(png, info);
  png_write_image(png, const_cast<png_bytepp>(rows.data()));
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return Status::ok();
}

Status write_png(const std::string& path, const RgbaImage& image) {
  std::string bytes;
  Status s = encode_png(image, &bytes, path);
  if (!s) return s;
  return write_file_atomic(path, bytes);
}

Status read_png(const std::string& path, RgbaImage* image) {
  *image = RgbaImage();
  std::unique_ptr<FILE, int (*)(FILE*)> file(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!file) return Status::error(path + ": cannot open: " + std::strerror(errno));
  png_byte signature[8];
  if (std::fread(signature, 1, 8, file.get()) != 8 || png_sig_cmp(signature, 0, 8) != 0)
    return Status::error(path + ": not a PNG file");
  PngErrorSink sink;
  png_structp png =
      png_create_read_struct(PNG_LIBPNG_VER_STRING, &sink, on_png_error, on_png_warning);
  if (png == nullptr) return Status::error(path + ": cannot read PNG: out of memory");
  png_infop info = png_create_info_struct(png);
  RgbaImage result;
  std::vector<png_bytep> rows;
  if (info == nullptr || setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, nullptr);
    return Status::error(path + ": cannot read PNG: " + sink.message);
  }
  png_init_io(png, file.get());
  png_set_sig_bytes(png, 8);
  png_read_info(png, info);
  png_set_strip_16(png);
  png_set_packing(png);
  png_set_expand(png);  // palette to RGB, grey below 8 bits to 8, tRNS to alpha
  png_set_gray_to_rgb(png);
  png_set_add_alpha(png, 0xff, PNG_FILLER_AFTER);
  png_read_update_info(png, info);
  result.width = static_cast<int>(png_get_image_width(png, info));
  result.height = static_cast<int>(png_get_image_height(png, info));
  if (png_get_rowbytes(png, info) != static_cast<size_t>(result.width) * 4)
    png_error(png, "unexpected row size after expansion to RGBA");
  result.rgba.resize(static_cast<size_t>(result.width) * result.height * 4);
  rows.resize(result.height);
  for (int y = 0; y < result.height; ++y)
    rows[y] = result.rgba.data() + static_cast<size_t>(y) * result.width * 4;
  png_read_image(png, rows.data());
  png_read_end(png, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);
  *image = std::move(result);
  return Status::ok();
}

}  // namespace vobb
