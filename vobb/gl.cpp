#include "vobb/gl.h"

#include <memory>

#include "common/tree.h"
#include "fast/gl_context.h"
#include "fast/gl_estimator.h"
#include "render/tree_figure.h"
#include "vobb/gl_backend.h"

namespace vobb {

namespace {

std::string describe(const GlContext& gl) {
  return "GL renderer: " + gl.renderer() + " (EGL " + gl.platform() + ", OpenGL " + gl.version() +
         ")";
}

class GlBackend final : public detail::GlEstimate {
 public:
  explicit GlBackend(std::unique_ptr<GlObvEstimator> gl) : gl_(std::move(gl)) {}
  std::vector<double> estimate(const std::vector<Obb>& boxes, int m) override {
    return gl_->estimate(boxes, m);
  }
  int max_m() const override { return gl_->max_m(); }
  const std::string& renderer() const override { return gl_->renderer(); }
  std::string description() const override { return describe(gl_->context()); }

 private:
  std::unique_ptr<GlObvEstimator> gl_;
};

Status make_gl_backend(const Mesh& mesh, bool device_only,
                       std::unique_ptr<detail::GlEstimate>* out) {
  std::unique_ptr<GlObvEstimator> gl;
  const Status s = GlObvEstimator::create(mesh, &gl, device_only);
  if (!s) return s;
  *out = std::make_unique<GlBackend>(std::move(gl));
  return Status::ok();
}

}  // namespace

void enable_gl() { detail::set_gl_factory(&make_gl_backend); }

FigureContext::FigureContext(std::unique_ptr<GlContext> gl) : gl_(std::move(gl)) {}
FigureContext::~FigureContext() = default;

Status FigureContext::create(std::unique_ptr<FigureContext>* out) {
  std::unique_ptr<GlContext> gl;
  const Status s = GlContext::create(&gl);
  if (!s) return Status::error("cannot draw the figure: " + s.message());
  gl->release();  // made current on this thread; bound again for each draw
  out->reset(new FigureContext(std::move(gl)));
  return Status::ok();
}

Status draw_compare_figure(const Mesh& mesh, const CompareResult& result, const std::string& up,
                           const std::function<void(const std::string&)>& note, RgbaImage* image,
                           CompareFigure* figure, const FigureContext* context) {
  FigureOptions fo;
  Status s = set_figure_up(up, &fo);
  if (!s) return s;
  // The trees as certify takes them: a broken one (a result edited, or of another mesh) is an
  // error here, not a crash in the drawing.
  for (int k = 0; k < 2; ++k) {
    s = check_tree_fits(mesh, result.trees[k],
                        k == 0 ? "the obbtree tree" : "the variational tree");
    if (!s) return s;
  }
  std::unique_ptr<FigureContext> own;
  if (context == nullptr) {
    s = FigureContext::create(&own);
    if (!s) return s;
    context = own.get();
  }
  const GlContext& gl = context->gl();
  if (note) note(describe(gl));
  const std::vector<FigureRow> rows = {{"obbtree", &result.trees[0]},
                                       {"variational", &result.trees[1]}};
  fo.levels = default_figure_levels(rows);
  s = render_tree_figure(gl, mesh, rows, fo, image);
  if (!s) return s;
  *figure = {image->width, image->height, fo.levels.front(), fo.levels.back()};
  return Status::ok();
}

}  // namespace vobb
