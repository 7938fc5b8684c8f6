#include "egl_context.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <cstdlib>
#include <cstring>
#include <map>
#include <mutex>
#include <vector>

#include "hameritt/render/renderer.h"

namespace hameritt::render {

namespace {

std::string eglErrorName(EGLint e) {
  switch (e) {
    case EGL_SUCCESS:
      return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED:
      return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS:
      return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC:
      return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE:
      return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONFIG:
      return "EGL_BAD_CONFIG";
    case EGL_BAD_CONTEXT:
      return "EGL_BAD_CONTEXT";
    case EGL_BAD_CURRENT_SURFACE:
      return "EGL_BAD_CURRENT_SURFACE";
    case EGL_BAD_DISPLAY:
      return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH:
      return "EGL_BAD_MATCH";
    case EGL_BAD_PARAMETER:
      return "EGL_BAD_PARAMETER";
    case EGL_BAD_SURFACE:
      return "EGL_BAD_SURFACE";
    default: {
      char buf[32];
      std::snprintf(buf, sizeof(buf), "EGL error 0x%04x", static_cast<unsigned>(e));
      return buf;
    }
  }
}

[[noreturn]] void fail(const std::string& what) {
  throw RenderError("EGL: " + what + " failed (" + eglErrorName(eglGetError()) + ")");
}

bool hasExtension(const char* list, const char* name) {
  if (list == nullptr) return false;
  const std::size_t n = std::strlen(name);
  for (const char* p = list; (p = std::strstr(p, name)) != nullptr; p += n) {
    if ((p == list || p[-1] == ' ') && (p[n] == '\0' || p[n] == ' ')) return true;
  }
  return false;
}

template <typename F>
F proc(const char* name) {
  return reinterpret_cast<F>(eglGetProcAddress(name));
}

// EGL displays are per process: eglTerminate would pull the display from under another
// Renderer, so initialisations are counted and the last user terminates it.
std::mutex g_display_mutex;
std::map<EGLDisplay, int> g_display_users;

bool initializeDisplay(EGLDisplay d) {
  std::lock_guard<std::mutex> lock(g_display_mutex);
  EGLint major = 0, minor = 0;
  if (g_display_users[d] == 0 && !eglInitialize(d, &major, &minor)) {
    g_display_users.erase(d);
    return false;
  }
  ++g_display_users[d];
  return true;
}

void releaseDisplay(EGLDisplay d) {
  std::lock_guard<std::mutex> lock(g_display_mutex);
  auto it = g_display_users.find(d);
  if (it == g_display_users.end()) return;
  if (--it->second == 0) {
    g_display_users.erase(it);
    eglTerminate(d);
  }
}

// A hardware EGL device (not llvmpipe/softpipe), initialised, or EGL_NO_DISPLAY.
EGLDisplay hardwareDeviceDisplay() {
  const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  if (!hasExtension(client, "EGL_EXT_device_enumeration") &&
      !hasExtension(client, "EGL_EXT_device_base")) {
    return EGL_NO_DISPLAY;
  }
  auto query_devices = proc<PFNEGLQUERYDEVICESEXTPROC>("eglQueryDevicesEXT");
  auto device_string = proc<PFNEGLQUERYDEVICESTRINGEXTPROC>("eglQueryDeviceStringEXT");
  auto platform_display = proc<PFNEGLGETPLATFORMDISPLAYEXTPROC>("eglGetPlatformDisplayEXT");
  if (!query_devices || !device_string || !platform_display) return EGL_NO_DISPLAY;
  EGLint n = 0;
  if (!query_devices(0, nullptr, &n) || n <= 0) return EGL_NO_DISPLAY;
  std::vector<EGLDeviceEXT> devices(static_cast<std::size_t>(n));
  if (!query_devices(n, devices.data(), &n)) return EGL_NO_DISPLAY;
  for (EGLint i = 0; i < n; ++i) {
    const char* ext = device_string(devices[static_cast<std::size_t>(i)], EGL_EXTENSIONS);
    if (hasExtension(ext, "EGL_MESA_device_software")) continue;
    EGLDisplay d =
        platform_display(EGL_PLATFORM_DEVICE_EXT, devices[static_cast<std::size_t>(i)], nullptr);
    if (d != EGL_NO_DISPLAY && initializeDisplay(d)) return d;
  }
  return EGL_NO_DISPLAY;
}

EGLDisplay surfacelessDisplay() {
  const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  if (!hasExtension(client, "EGL_MESA_platform_surfaceless")) {
    throw RenderError(
        "EGL: the surfaceless platform (EGL_MESA_platform_surfaceless) is not "
        "available; install libegl-mesa0");
  }
  auto platform_display = proc<PFNEGLGETPLATFORMDISPLAYEXTPROC>("eglGetPlatformDisplayEXT");
  if (!platform_display) fail("eglGetProcAddress(eglGetPlatformDisplayEXT)");
  EGLDisplay d = platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
  if (d == EGL_NO_DISPLAY) fail("eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA)");
  if (!initializeDisplay(d)) fail("eglInitialize (surfaceless)");
  return d;
}

}  // namespace

EglContext::EglContext(const std::string& requested) {
  std::string backend = requested;
  if (const char* env = std::getenv("HAMERITT_EGL_BACKEND"); env != nullptr && *env != '\0') {
    backend = env;
  }
  if (backend != "auto" && backend != "surfaceless" && backend != "device") {
    throw RenderError("backend: expected auto, surfaceless or device, got '" + backend + "'" +
                      (requested != backend ? " (from HAMERITT_EGL_BACKEND)" : ""));
  }
  EGLDisplay d = EGL_NO_DISPLAY;
  if (backend != "surfaceless") {
    d = hardwareDeviceDisplay();
    if (d == EGL_NO_DISPLAY && backend == "device") {
      throw RenderError(
          "EGL: backend 'device' requested but no hardware EGL device could be "
          "initialised (EGL_EXT_device_enumeration, a non-software device)");
    }
    if (d != EGL_NO_DISPLAY) platform_ = "device";
  }
  if (d == EGL_NO_DISPLAY) {
    d = surfacelessDisplay();
    platform_ = "surfaceless";
  }
  display_ = d;
  try {
    if (!eglBindAPI(EGL_OPENGL_API)) fail("eglBindAPI(EGL_OPENGL_API)");
    const char* ext = eglQueryString(d, EGL_EXTENSIONS);
    EGLConfig config = EGL_NO_CONFIG_KHR;
    if (!hasExtension(ext, "EGL_KHR_no_config_context") ||
        !hasExtension(ext, "EGL_KHR_surfaceless_context")) {
      const EGLint attribs[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE,
                                EGL_OPENGL_BIT, EGL_NONE};
      EGLint n = 0;
      if (!eglChooseConfig(d, attribs, &config, 1, &n) || n < 1) fail("eglChooseConfig");
    }
    const EGLint ctx_attribs[] = {EGL_CONTEXT_MAJOR_VERSION,
                                  4,
                                  EGL_CONTEXT_MINOR_VERSION,
                                  5,
                                  EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                  EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                  EGL_NONE};
    context_ = eglCreateContext(d, config, EGL_NO_CONTEXT, ctx_attribs);
    if (context_ == EGL_NO_CONTEXT) {
      fail("eglCreateContext (OpenGL 4.5 core on the " + platform_ + " platform)");
    }
    if (!hasExtension(ext, "EGL_KHR_surfaceless_context")) {
      const EGLint pb[] = {EGL_WIDTH, 1, EGL_HEIGHT, 1, EGL_NONE};
      surface_ = eglCreatePbufferSurface(d, config, pb);
      if (surface_ == EGL_NO_SURFACE) fail("eglCreatePbufferSurface");
    }
    makeCurrent();
  } catch (...) {
    if (context_ != nullptr) eglDestroyContext(d, context_);
    if (surface_ != nullptr) eglDestroySurface(d, surface_);
    releaseDisplay(d);
    throw;
  }
}

EglContext::~EglContext() {
  if (isCurrent()) eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  eglDestroyContext(display_, context_);
  if (surface_ != nullptr) eglDestroySurface(display_, surface_);
  releaseDisplay(display_);
}

void EglContext::makeCurrent() {
  if (isCurrent()) return;
  if (!eglMakeCurrent(display_, surface_, surface_, context_)) {
    const EGLint e = eglGetError();
    if (e == EGL_BAD_ACCESS) {
      throw RenderError(
          "EGL: eglMakeCurrent failed (EGL_BAD_ACCESS): the renderer's context is "
          "current on another thread; call Renderer::releaseCurrent() there first");
    }
    throw RenderError("EGL: eglMakeCurrent failed (" + eglErrorName(e) + ")");
  }
}

void EglContext::releaseCurrent() {
  if (!isCurrent()) return;
  if (!eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT)) {
    fail("eglMakeCurrent(EGL_NO_CONTEXT)");
  }
}

bool EglContext::isCurrent() const { return eglGetCurrentContext() == context_; }

}  // namespace hameritt::render
