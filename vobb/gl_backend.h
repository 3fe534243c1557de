// Internal: how the public face reaches the GL component without linking it. The GL component
// (vobb/gl.cpp) registers a factory through enable_gl(); without one, no GL is made.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "common/mesh.h"
#include "common/obb.h"
#include "common/status.h"

namespace vobb::detail {

// A GL estimator as the face uses it (fast/gl_estimator.h). estimate() may be called from
// several threads at once.
class GlEstimate {
 public:
  virtual ~GlEstimate() = default;
  virtual std::vector<double> estimate(const std::vector<Obb>& boxes, int m) = 0;
  virtual int max_m() const = 0;
  virtual const std::string& renderer() const = 0;
  // "GL renderer: R (EGL P, OpenGL V)", for a note.
  virtual std::string description() const = 0;
};

// Makes a GL estimator for `mesh` (kept by reference); `device_only`: only on a GPU.
using GlFactory = Status (*)(const Mesh& mesh, bool device_only, std::unique_ptr<GlEstimate>* out);

void set_gl_factory(GlFactory factory);
GlFactory gl_factory();  // null until the GL component is enabled

}  // namespace vobb::detail
