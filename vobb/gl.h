// vobb's GL component (target vobb::gl): the cubemap estimator on the GPU through headless EGL,
// and figures of trees. Needs OpenGL, EGL and libpng beside the core's dependencies.
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "common/png_io.h"
#include "common/rgba_image.h"
#include "common/status.h"
#include "vobb/vobb.h"

namespace vobb {

class GlContext;

// Lets build_tree, compare and estimate_obv make GL estimators: Backend::kGl, and kAuto on a GPU
// from m = kAutoGlFromM. Call it once, before them; it makes no context by itself.
void enable_gl();

struct CompareFigure {
  int width = 0, height = 0;            // pixels
  int first_level = 0, last_level = 0;  // the columns' levels
};
// A GL context for figures (on llvmpipe where there is no GPU), made ahead of a run whose last
// step is a figure, so that a run that could not draw it is refused before its work. It is
// current on no thread between draws.
class FigureContext {
 public:
  // On failure `out` stays empty and the Status says why, in one line.
  static Status create(std::unique_ptr<FigureContext>* out);
  ~FigureContext();
  FigureContext(const FigureContext&) = delete;
  FigureContext& operator=(const FigureContext&) = delete;
  const GlContext& gl() const { return *gl_; }

 private:
  explicit FigureContext(std::unique_ptr<GlContext> gl);
  std::unique_ptr<GlContext> gl_;
};

// Draws both trees of a comparison over the mesh, levels 1..8 (paper Fig. 6: row 1 the
// baseline, row 2 the variational tree), with the mesh's up axis `up` ("x", "y", "z", "-x",
// "-y", "-z"), into `image` (write_png, common/png_io.h, writes it). Draws in `context`, or
// without one in a FigureContext of its own; `note` gets the renderer.
Status draw_compare_figure(const Mesh& mesh, const CompareResult& result, const std::string& up,
                           const std::function<void(const std::string&)>& note, RgbaImage* image,
                           CompareFigure* figure, const FigureContext* context = nullptr);

}  // namespace vobb
