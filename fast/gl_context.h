// vobb::GlContext — a headless OpenGL 4.3 core context through EGL, made only when a GL backend
// is asked for (no context where none is used).
//
// Order of attempts: an EGL device that is a real GPU (EGL_EXT_device_enumeration; Mesa's
// software device is skipped), then Mesa's surfaceless platform (llvmpipe on a machine without
// a GPU). The library prints nothing: renderer(), platform() and version() are for the caller
// to report.
// The environment variable VOBB_GL=off refuses to make any context (to run without GL, or to
// exercise the fallback); VOBB_EGL_PLATFORM=device|surfaceless tries only that platform.
#pragma once

#include <initializer_list>
#include <memory>
#include <string>
#include <utility>

#include "common/status.h"

namespace vobb {

class GlContext {
 public:
  // On failure `out` stays empty and the Status says why, in one line. `device_only` skips
  // the surfaceless (software) platform: for callers that only want GL on a GPU.
  static Status create(std::unique_ptr<GlContext>* out, bool device_only = false);
  // Whether VOBB_GL=off is set: every create() then refuses.
  static bool switched_off();
  ~GlContext();
  GlContext(const GlContext&) = delete;
  GlContext& operator=(const GlContext&) = delete;

  // A context is current on at most one thread at a time (EGL): make_current() binds it to the
  // calling thread, and fails (an assertion) while another thread holds it; release() unbinds
  // whatever context the calling thread holds. create() returns with the context current on the
  // calling thread.
  void make_current() const;
  void release() const;
  // Binds the context to the calling thread for the guard's lifetime.
  class Current {
   public:
    explicit Current(const GlContext& c) : c_(c) { c_.make_current(); }
    ~Current() { c_.release(); }
    Current(const Current&) = delete;
    Current& operator=(const Current&) = delete;

   private:
    const GlContext& c_;
  };
  const std::string& renderer() const { return renderer_; }
  const std::string& platform() const { return platform_; }  // "device" or "surfaceless"
  const std::string& version() const { return version_; }    // GL_VERSION

 private:
  GlContext() = default;
  void* display_ = nullptr;
  void* context_ = nullptr;
  std::string renderer_, platform_, version_;
};

// Builds a GL program from (stage type, GLSL source) pairs, e.g. {{GL_VERTEX_SHADER, vs},
// {GL_FRAGMENT_SHADER, fs}}, in the current context: compiles each stage, links, and deletes the
// shaders whatever the outcome. 0 on failure, with the compiler's or linker's log on one line
// in `log`.
unsigned gl_program(std::initializer_list<std::pair<unsigned, const char*>> stages,
                    std::string* log);

}  // namespace vobb
