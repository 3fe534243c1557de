// Making a GL context or estimator in the GL tests (fast_gl_tests). Every machine here has
// Mesa's llvmpipe, so a missing context is a failure, unless GL was switched off on purpose
// (VOBB_GL=off), which skips the test.
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <memory>
#include <string>

#include "common/status.h"
#include "fast/gl_context.h"
#include "fast/gl_estimator.h"

namespace vobb::test {

inline bool gl_switched_off() {
  const char* env = std::getenv("VOBB_GL");
  return env != nullptr && std::string(env) == "off";
}

}  // namespace vobb::test

// Declares `made_status` from `make` (a Status expression), then skips or fails as above.
#define VOBB_GL_OR_SKIP(make)                                                                   \
  do {                                                                                          \
    const ::vobb::Status made_status = (make);                                                  \
    if (!made_status && ::vobb::test::gl_switched_off()) GTEST_SKIP() << made_status.message(); \
    ASSERT_TRUE(made_status) << made_status.message();                                          \
  } while (0)

// std::unique_ptr<GlContext> ctx, made current on this thread.
#define VOBB_MAKE_CONTEXT(ctx)            \
  std::unique_ptr<::vobb::GlContext> ctx; \
  VOBB_GL_OR_SKIP(::vobb::GlContext::create(&ctx))

// std::unique_ptr<GlObvEstimator> est over `mesh`.
#define VOBB_MAKE_GL(est, mesh)                \
  std::unique_ptr<::vobb::GlObvEstimator> est; \
  VOBB_GL_OR_SKIP(::vobb::GlObvEstimator::create((mesh), &est))
