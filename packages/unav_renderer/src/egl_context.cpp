#include "unav_renderer/egl_context.hpp"

#include <epoxy/egl.h>
#include <epoxy/gl.h>

#include <cstdlib>
#include <cstring>
#include <map>
#include <mutex>
#include <vector>

#include "unav_renderer/errors.hpp"

namespace unav::renderer {
namespace {

std::string egl_error_name(EGLint e) {
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
    case EGL_BAD_DISPLAY:
      return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH:
      return "EGL_BAD_MATCH";
    case EGL_BAD_PARAMETER:
      return "EGL_BAD_PARAMETER";
    default:
      return "EGL error 0x" + std::to_string(e);
  }
}

bool has_ext(const char* list, const char* name) {
  if (!list) return false;
  const std::size_t n = std::strlen(name);
  for (const char* p = list; (p = std::strstr(p, name)); p += n)
    if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
  return false;
}

// EGL displays are per-device singletons: two contexts on one device share the display, so
// eglTerminate may only run when the last context on it is gone.
std::mutex g_display_mutex;
std::map<EGLDisplay, int> g_display_users;

void release_display(EGLDisplay dpy) {
  std::lock_guard<std::mutex> lock(g_display_mutex);
  if (--g_display_users[dpy] <= 0) {
    g_display_users.erase(dpy);
    eglTerminate(dpy);
  }
}

struct Attempt {
  EGLDisplay display = EGL_NO_DISPLAY;
  EGLContext context = EGL_NO_CONTEXT;
};

// Initialise a display and create a surfaceless core context (4.5 down to 3.3).
bool try_display(EGLDisplay dpy, const std::string& label, Attempt* out, std::string* why) {
  if (dpy == EGL_NO_DISPLAY) {
    *why += label + ": no display (" + egl_error_name(eglGetError()) + "); ";
    return false;
  }
  EGLint major = 0, minor = 0;
  if (!eglInitialize(dpy, &major, &minor)) {
    *why += label + ": eglInitialize failed (" + egl_error_name(eglGetError()) + "); ";
    return false;
  }
  {
    std::lock_guard<std::mutex> lock(g_display_mutex);
    ++g_display_users[dpy];
  }
  const char* dext = eglQueryString(dpy, EGL_EXTENSIONS);
  if (!has_ext(dext, "EGL_KHR_surfaceless_context")) {
    *why += label + ": no EGL_KHR_surfaceless_context; ";
    release_display(dpy);
    return false;
  }
  if (!eglBindAPI(EGL_OPENGL_API)) {
    *why += label + ": desktop OpenGL API not available; ";
    release_display(dpy);
    return false;
  }
  EGLConfig cfg = nullptr;
  EGLint ncfg = 0;
  const EGLint cfg_attr[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
  if (!has_ext(dext, "EGL_KHR_no_config_context") && (!eglChooseConfig(dpy, cfg_attr, &cfg, 1, &ncfg) || ncfg < 1)) {
    *why += label + ": no OpenGL-renderable EGL config; ";
    release_display(dpy);
    return false;
  }
  const int versions[][2] = {{4, 5}, {4, 3}, {4, 1}, {3, 3}};
  for (const auto& v : versions) {
    const EGLint ctx_attr[] = {
        EGL_CONTEXT_MAJOR_VERSION,           v[0],    EGL_CONTEXT_MINOR_VERSION, v[1], EGL_CONTEXT_OPENGL_PROFILE_MASK,
        EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
    EGLContext ctx = eglCreateContext(dpy, ncfg ? cfg : EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, ctx_attr);
    if (ctx == EGL_NO_CONTEXT) continue;
    if (!eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx)) {
      eglDestroyContext(dpy, ctx);
      continue;
    }
    out->display = dpy;
    out->context = ctx;
    return true;
  }
  *why += label + ": cannot create an OpenGL 3.3+ core context (" + egl_error_name(eglGetError()) + "); ";
  release_display(dpy);
  return false;
}

}  // namespace

std::unique_ptr<EglContext> EglContext::create(const EglOptions& options) {
  int device_index = options.device_index;
  if (device_index < 0) {
    if (const char* env = std::getenv("UNAV_EGL_DEVICE"); env && *env) device_index = std::atoi(env);
  }
  const char* client_ext = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  std::string why;
  Attempt a;
  std::string platform;
  const bool want_device = options.platform != EglOptions::Platform::kSurfaceless;
  const bool want_surfaceless = options.platform != EglOptions::Platform::kDevice;

  if (want_device) {
    if (!has_ext(client_ext, "EGL_EXT_device_enumeration") && !has_ext(client_ext, "EGL_EXT_device_base")) {
      why += "device platform: EGL_EXT_device_enumeration not supported by libEGL; ";
    } else if (!has_ext(client_ext, "EGL_EXT_platform_device")) {
      why += "device platform: EGL_EXT_platform_device not supported by libEGL; ";
    } else {
      EGLint n = 0;
      std::vector<EGLDeviceEXT> devs(16);
      if (!eglQueryDevicesEXT(static_cast<EGLint>(devs.size()), devs.data(), &n)) n = 0;
      if (device_index >= 0 && device_index >= n)
        throw EglError("EGL device " + std::to_string(device_index) +
                       " requested (EglOptions::device_index or UNAV_EGL_DEVICE) but "
                       "eglQueryDevicesEXT found " +
                       std::to_string(n) + " device(s)");
      if (n == 0) why += "device platform: eglQueryDevicesEXT found no EGL device; ";
      for (EGLint i = 0; i < n && !a.context; ++i) {
        if (device_index >= 0 && i != device_index) continue;
        const std::string label = "EGL device " + std::to_string(i);
        EGLDisplay dpy = eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, devs[i], nullptr);
        if (try_display(dpy, label, &a, &why)) platform = "device[" + std::to_string(i) + "]";
      }
    }
  }
  if (!a.context && want_surfaceless && device_index < 0) {
    if (!has_ext(client_ext, "EGL_MESA_platform_surfaceless")) {
      why += "surfaceless: EGL_MESA_platform_surfaceless not supported; ";
    } else {
      EGLDisplay dpy = eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
      if (try_display(dpy, "Mesa surfaceless", &a, &why)) platform = "surfaceless";
    }
  }
  if (!a.context)
    throw EglError("no EGL device usable for headless OpenGL: " + why +
                   "install an EGL driver (NVIDIA: libnvidia-egl / libegl-nvidia0; CPU: libegl-mesa0 "
                   "for Mesa llvmpipe) and make sure /dev/dri or the NVIDIA device is accessible");

  std::unique_ptr<EglContext> ctx(new EglContext());
  ctx->display_ = a.display;
  ctx->context_ = a.context;
  ctx->platform_ = platform;
  auto str = [](GLenum e) {
    const auto* s = glGetString(e);
    return s ? std::string(reinterpret_cast<const char*>(s)) : std::string("?");
  };
  ctx->vendor_ = str(GL_VENDOR);
  ctx->renderer_ = str(GL_RENDERER);
  ctx->version_ = str(GL_VERSION);
  if (epoxy_gl_version() < 33)
    throw EglError("OpenGL " + ctx->version_ + " on " + ctx->renderer_ + " (" + platform + "): need 3.3 core or newer");
  return ctx;
}

EglContext::~EglContext() {
  if (display_) {
    eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    if (context_) eglDestroyContext(display_, context_);
    release_display(display_);
  }
}

void EglContext::make_current() {
  if (eglGetCurrentContext() == context_) return;
  if (!eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_))
    throw EglError("eglMakeCurrent failed (" + egl_error_name(eglGetError()) + ")");
}

bool EglContext::is_software_renderer(const std::string& gl_renderer) {
  for (const char* name : {"llvmpipe", "softpipe", "swrast", "Software Rasterizer"})
    if (gl_renderer.find(name) != std::string::npos) return true;
  return false;
}

}  // namespace unav::renderer
