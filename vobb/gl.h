// vobb's GL component (target vobb::gl): the cubemap estimator on the GPU through headless EGL,
// and figures of trees. Needs OpenGL, EGL and libpng beside the core's dependencies.
#pragma once

#include <functional>
#include <string>

#include "common/png_io.h"
#include "common/rgba_image.h"
#include "common/status.h"
#include "vobb/vobb.h"

namespace vobb {

// Lets build_tree, compare and estimate_obv make GL estimators: Backend::kGl, and kAuto on a GPU
// from m = kAutoGlFromM. Call it once, before them; it makes no context by itself.
void enable_gl();

struct CompareFigure {
  int width = 0, height = 0;            // pixels
  int first_level = 0, last_level = 0;  // the columns' levels
};
// Draws both trees of a comparison over the mesh, levels 1..8 (paper Fig. 6: row 1 the
// baseline, row 2 the variational tree), with the mesh's up axis `up` ("x", "y", "z", "-x",
// "-y", "-z"), into `image` (write_png, common/png_io.h, writes it). Makes a GL context of its
// own (on llvmpipe where there is no GPU); `note` gets the renderer.
Status draw_compare_figure(const Mesh& mesh, const CompareResult& result, const std::string& up,
                           const std::function<void(const std::string&)>& note, RgbaImage* image,
                           CompareFigure* figure);

// Whether draw_compare_figure can make its GL context here: makes one and lets it go, so that
// a run whose last step is the figure can be refused before its work.
Status check_figure_context();

}  // namespace vobb
