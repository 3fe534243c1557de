// vobb::RgbaImage — an 8-bit RGBA image in memory, rows top-down. Header only: the renderer
// that fills it (render/tree_figure.h) and the PNG writer (png_io.h) share it without linking
// each other.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace vobb {

struct RgbaImage {
  int width = 0, height = 0;
  std::vector<uint8_t> rgba;  // width * height * 4 bytes, row 0 is the top row
  const uint8_t* pixel(int x, int y) const {
    return rgba.data() + (static_cast<size_t>(y) * width + x) * 4;
  }
};

}  // namespace vobb
