// vobb::GlContext: headless EGL contexts, and which thread they are current on.
#include "fast/gl_context.h"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <memory>
#include <string>
#include <thread>

#include "fast/gl_test_util.h"

namespace vobb {
namespace {

// What the renderer calls itself, through whichever context is current on this thread ("" with
// none).
std::string current_renderer() {
  const GLubyte* r = glGetString(GL_RENDERER);
  return r != nullptr ? reinterpret_cast<const char*>(r) : "";
}

TEST(GlContext, ReportsItsRendererPlatformAndVersion) {
  VOBB_MAKE_CONTEXT(ctx);
  EXPECT_FALSE(ctx->renderer().empty());
  EXPECT_TRUE(ctx->platform() == "device" || ctx->platform() == "surfaceless") << ctx->platform();
  EXPECT_EQ(ctx->version().rfind("4.", 0), 0u) << "an OpenGL 4.x context: " << ctx->version();
  EXPECT_EQ(current_renderer(), ctx->renderer())
      << "create() leaves the context current on this thread";
}

// A context released on one thread can be bound on another (the GL estimator's drawing thread
// takes it after create(), a figure takes it between estimates), and back again; release()
// leaves the thread without a current context.
TEST(GlContext, ReleasedContextMovesBetweenThreads) {
  VOBB_MAKE_CONTEXT(ctx);
  ctx->release();
  EXPECT_EQ(current_renderer(), "");
  std::string there;
  std::thread([&] {
    GlContext::Current bound(*ctx);
    there = current_renderer();
  }).join();
  EXPECT_EQ(there, ctx->renderer());
  {
    GlContext::Current bound(*ctx);
    EXPECT_EQ(current_renderer(), ctx->renderer());
  }
  EXPECT_EQ(current_renderer(), "") << "the guard released it";
}

// Binding a context that another thread holds is a programming error, and a loud one: the
// process ends naming EGL's error, instead of drawing through no context.
TEST(GlContextDeathTest, BindingAContextAnotherThreadHoldsAborts) {
  VOBB_MAKE_CONTEXT(ctx);  // current on this thread
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_DEATH(std::thread([&] { ctx->make_current(); }).join(),
               "eglMakeCurrent failed, EGL error 12290");
}

TEST(GlContext, SwitchedOffGivesAClearOneLineError) {
  const char* old = std::getenv("VOBB_GL");
  const std::string saved = old ? old : "";
  ::setenv("VOBB_GL", "off", 1);
  std::unique_ptr<GlContext> ctx;
  const Status s = GlContext::create(&ctx);
  if (old)
    ::setenv("VOBB_GL", saved.c_str(), 1);
  else
    ::unsetenv("VOBB_GL");
  EXPECT_FALSE(s);
  EXPECT_EQ(ctx, nullptr);
  EXPECT_NE(s.message().find("VOBB_GL=off"), std::string::npos) << s.message();
  EXPECT_EQ(s.message().find('\n'), std::string::npos);
}

}  // namespace
}  // namespace vobb
