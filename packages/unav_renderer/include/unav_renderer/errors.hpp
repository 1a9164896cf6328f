// Exceptions thrown at configure time (STYLE.md rule 7). Messages name the file and the key.
#pragma once

#include <stdexcept>
#include <string>

#include "unav_scene/errors.hpp"

namespace unav::renderer {

/// Bad configuration: world/water/camera YAML, missing or unreadable mesh, bad value.
using unav::scene::ConfigError;

/// No usable EGL display/device or OpenGL context.
class EglError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// OpenGL failure (shader compilation, incomplete framebuffer, GL error).
class GlError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace unav::renderer
