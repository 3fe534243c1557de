#include "fast/gl_context.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <cstdlib>
#include <cstring>
#include <vector>

namespace vobb {

namespace {

bool has_extension(const char* list, const char* name) {
  if (list == nullptr) return false;
  const size_t n = std::strlen(name);
  for (const char* p = list; (p = std::strstr(p, name)) != nullptr; p += n)
    if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
  return false;
}

// Initializes `display` and makes a GL 4.3 core context current on it without a surface.
// Returns the context, or EGL_NO_CONTEXT with `why` set.
EGLContext make_context(EGLDisplay display, std::string* why) {
  EGLint major = 0, minor = 0;
  if (!eglInitialize(display, &major, &minor)) {
    *why = "eglInitialize failed";
    return EGL_NO_CONTEXT;
  }
  const char* exts = eglQueryString(display, EGL_EXTENSIONS);
  if (!has_extension(exts, "EGL_KHR_surfaceless_context")) {
    *why = "no EGL_KHR_surfaceless_context";
    eglTerminate(display);
    return EGL_NO_CONTEXT;
  }
  if (!eglBindAPI(EGL_OPENGL_API)) {
    *why = "eglBindAPI(EGL_OPENGL_API) failed";
    eglTerminate(display);
    return EGL_NO_CONTEXT;
  }
  EGLConfig config = nullptr;
  if (!has_extension(exts, "EGL_KHR_no_config_context")) {
    const EGLint attribs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
    EGLint n = 0;
    if (!eglChooseConfig(display, attribs, &config, 1, &n) || n < 1) {
      *why = "no EGL config for desktop OpenGL";
      eglTerminate(display);
      return EGL_NO_CONTEXT;
    }
  }
  const EGLint ctx_attribs[] = {EGL_CONTEXT_MAJOR_VERSION,
                                4,
                                EGL_CONTEXT_MINOR_VERSION,
                                3,
                                EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                EGL_NONE};
  EGLContext ctx = eglCreateContext(display, config, EGL_NO_CONTEXT, ctx_attribs);
  if (ctx == EGL_NO_CONTEXT) {
    *why = "no OpenGL 4.3 core context";
    eglTerminate(display);
    return EGL_NO_CONTEXT;
  }
  if (!eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx)) {
    *why = "eglMakeCurrent failed";
    eglDestroyContext(display, ctx);
    eglTerminate(display);
    return EGL_NO_CONTEXT;
  }
  return ctx;
}

}  // namespace

bool GlContext::switched_off() {
  const char* gl_env = std::getenv("VOBB_GL");
  return gl_env != nullptr && std::strcmp(gl_env, "off") == 0;
}

Status GlContext::create(std::unique_ptr<GlContext>* out, bool device_only) {
  out->reset();
  if (switched_off()) return Status::error("no OpenGL context: disabled by VOBB_GL=off");
  const char* only = std::getenv("VOBB_EGL_PLATFORM");
  const bool try_device = only == nullptr || std::strcmp(only, "device") == 0;
  const bool try_surfaceless =
      !device_only && (only == nullptr || std::strcmp(only, "surfaceless") == 0);

  const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  auto get_platform_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
      eglGetProcAddress("eglGetPlatformDisplayEXT"));
  if (client == nullptr || get_platform_display == nullptr)
    return Status::error("no OpenGL context: EGL has no platform displays (EGL_EXT_platform_base)");

  std::unique_ptr<GlContext> g(new GlContext());
  std::string why = "no EGL platform to try";
  EGLDisplay display = EGL_NO_DISPLAY;
  EGLContext ctx = EGL_NO_CONTEXT;

  if (try_device && has_extension(client, "EGL_EXT_platform_device")) {
    auto query_devices =
        reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
    auto query_device_string = reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(
        eglGetProcAddress("eglQueryDeviceStringEXT"));
    EGLint n = 0;
    if (query_devices != nullptr && query_device_string != nullptr &&
        query_devices(0, nullptr, &n) && n > 0) {
      std::vector<EGLDeviceEXT> devices(n);
      query_devices(n, devices.data(), &n);
      for (EGLint i = 0; i < n && ctx == EGL_NO_CONTEXT; ++i) {
        if (has_extension(query_device_string(devices[i], EGL_EXTENSIONS),
                          "EGL_MESA_device_software"))
          continue;
        display = get_platform_display(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr);
        if (display == EGL_NO_DISPLAY) continue;
        ctx = make_context(display, &why);
        if (ctx != EGL_NO_CONTEXT) g->platform_ = "device";
      }
    }
  }
  if (ctx == EGL_NO_CONTEXT && try_surfaceless &&
      has_extension(client, "EGL_MESA_platform_surfaceless")) {
    display = get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    if (display != EGL_NO_DISPLAY) {
      ctx = make_context(display, &why);
      if (ctx != EGL_NO_CONTEXT) g->platform_ = "surfaceless";
    }
  }
  if (ctx == EGL_NO_CONTEXT) return Status::error("no OpenGL 4.3 context through EGL: " + why);
  g->display_ = display;
  g->context_ = ctx;
  const GLubyte* renderer = glGetString(GL_RENDERER);
  const GLubyte* version = glGetString(GL_VERSION);
  g->renderer_ = renderer != nullptr ? reinterpret_cast<const char*>(renderer) : "unknown";
  g->version_ = version != nullptr ? reinterpret_cast<const char*>(version) : "unknown";
  *out = std::move(g);
  return Status::ok();
}

GlContext::~GlContext() {
  if (display_ == nullptr) return;
  eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  eglDestroyContext(display_, context_);
  // The display stays initialized: EGL hands every caller in the process the same display
  // handle, and terminating it would pull it from under another live context.
}

void GlContext::make_current() const {
  if (eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_) == EGL_TRUE) return;
  const std::string why = "eglMakeCurrent failed, EGL error " + std::to_string(eglGetError()) +
                          " (12290 = EGL_BAD_ACCESS: the context is current on another thread)";
  VOBB_ASSERT(false, why.c_str());
}

void GlContext::release() const {
  eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
}

unsigned gl_program(std::initializer_list<std::pair<unsigned, const char*>> stages,
                    std::string* log) {
  auto one_line = [](std::string text) {
    for (char& c : text)
      if (c == '\n' || c == '\r') c = ' ';
    while (!text.empty() && text.back() == ' ') text.pop_back();
    return text;
  };
  char buf[2048] = {0};
  std::vector<GLuint> shaders;
  bool ok = true;
  for (const auto& [type, source] : stages) {
    const GLuint s = glCreateShader(type);
    shaders.push_back(s);
    glShaderSource(s, 1, &source, nullptr);
    glCompileShader(s);
    GLint compiled = 0;
    glGetShaderiv(s, GL_COMPILE_STATUS, &compiled);
    if (!compiled) {
      glGetShaderInfoLog(s, sizeof buf - 1, nullptr, buf);
      *log = one_line(buf);
      ok = false;
      break;
    }
  }
  GLuint p = 0;
  if (ok) {
    p = glCreateProgram();
    for (GLuint s : shaders) glAttachShader(p, s);
    glLinkProgram(p);
    GLint linked = 0;
    glGetProgramiv(p, GL_LINK_STATUS, &linked);
    if (!linked) {
      glGetProgramInfoLog(p, sizeof buf - 1, nullptr, buf);
      *log = one_line(buf);
      glDeleteProgram(p);
      p = 0;
    }
  }
  for (GLuint s : shaders) glDeleteShader(s);
  return p;
}

}  // namespace vobb
