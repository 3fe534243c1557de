// PNG I/O through libpng for vobb::RgbaImage (rgba_image.h): 8-bit RGBA, rows top-down.
//
// write_png encodes in memory and writes through write_file_atomic (atomic_file.h): a failure
// never leaves a half-written file at `path`. read_png reads what write_png wrote (and any
// 8-bit RGB/RGBA/grey PNG, expanded to RGBA) — for tests and for checking a figure.
// Errors are one-line Statuses naming the file.
#pragma once

#include <string>
#include <vector>

#include "common/rgba_image.h"
#include "common/status.h"

namespace vobb {

// Encodes `image` as a PNG in memory: RGB when every alpha is 255, else RGBA.
// Precondition: width, height >= 1 and rgba.size() == width * height * 4 (checked: an error,
// not an abort).
Status encode_png(const RgbaImage& image, std::string* png, const std::string& display);

// encode_png, then write_file_atomic to `path`.
Status write_png(const std::string& path, const RgbaImage& image);

// Decodes the PNG file at `path` into 8-bit RGBA (16-bit is stripped, palette and grey expanded,
// a missing alpha channel filled with 255).
Status read_png(const std::string& path, RgbaImage* image);

}  // namespace vobb
