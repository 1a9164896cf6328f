// Headless EGL + OpenGL (core 3.3 .. 4.5) context through libepoxy.
// Order: EGL device platform (eglQueryDevicesEXT + eglGetPlatformDisplayEXT(
// EGL_PLATFORM_DEVICE_EXT)), the NVIDIA headless path that Mesa also offers (llvmpipe shows up
// as a software device); then Mesa's EGL_PLATFORM_SURFACELESS_MESA. No X, no window.
#pragma once

#include <memory>
#include <string>

namespace unav::renderer {

struct EglOptions {
  enum class Platform { kAuto, kDevice, kSurfaceless };
  Platform platform = Platform::kAuto;
  /// Index into eglQueryDevicesEXT; -1 = first device that gives a context. The environment
  /// variable UNAV_EGL_DEVICE overrides -1.
  int device_index = -1;
};

/// Owns an EGL display + context with no surface. Not thread-safe: use it from one thread.
class EglContext {
 public:
  /// Throws EglError with the cause ("no EGL device ...", "device 3 requested but 1 found",
  /// "OpenGL 3.3 core not available: ...") and never returns a context that renders black.
  static std::unique_ptr<EglContext> create(const EglOptions& options = {});
  ~EglContext();
  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;

  void make_current();
  const std::string& platform() const { return platform_; }  ///< "device[0]" or "surfaceless"
  const std::string& gl_vendor() const { return vendor_; }
  const std::string& gl_renderer() const { return renderer_; }
  /// Whether GL_RENDERER names a software rasterizer (llvmpipe, softpipe, swrast): fragments cost
  /// CPU time there, and work that trades CPU for fragments pays.
  bool software() const { return is_software_renderer(renderer_); }
  static bool is_software_renderer(const std::string& gl_renderer);
  const std::string& gl_version() const { return version_; }

 private:
  EglContext() = default;
  void* display_ = nullptr;
  void* context_ = nullptr;
  std::string platform_, vendor_, renderer_, version_;
};

}  // namespace unav::renderer
