// OpenGL helpers shared by the camera renderer and the sonar renderer (private to the package).
#pragma once

#include <epoxy/gl.h>

#include <Eigen/Core>
#include <initializer_list>
#include <string>
#include <unordered_map>
#include <vector>

#include "unav_renderer/errors.hpp"
#include "unav_scene/camera.hpp"

namespace unav::renderer::gl {

using unav::scene::CameraModel;

inline void check_gl(const char* where) {
  const GLenum e = glGetError();
  if (e != GL_NO_ERROR) throw GlError(std::string("OpenGL error 0x") + std::to_string(e) + " in " + where);
}

inline GLuint compile(GLenum type, const char* src, const char* name) {
  GLuint s = glCreateShader(type);
  glShaderSource(s, 1, &src, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[4096];
    glGetShaderInfoLog(s, sizeof(log), nullptr, log);
    glDeleteShader(s);
    throw GlError(std::string("shader '") + name + "' does not compile: " + log);
  }
  return s;
}

class Program {
 public:
  Program() = default;
  /// `defines` ("#define X 1\n...") go after both shaders' #version lines: shader variants
  /// specialised at compile time (llvmpipe runs both sides of a branch on a uniform).
  Program(const char* vs, const char* fs, const char* name, const std::string& defines = "") {
    const auto with_defines = [&defines](const char* src) {
      std::string text = src;
      if (!defines.empty()) {
        const std::size_t eol = text.find('\n', text.find("#version"));
        text.insert(eol == std::string::npos ? text.size() : eol + 1, defines);
      }
      return text;
    };
    const std::string vs_text = with_defines(vs), fs_text = with_defines(fs);
    const GLuint v = compile(GL_VERTEX_SHADER, vs_text.c_str(), name),
                 f = compile(GL_FRAGMENT_SHADER, fs_text.c_str(), name);
    id_ = glCreateProgram();
    glAttachShader(id_, v);
    glAttachShader(id_, f);
    glLinkProgram(id_);
    glDeleteShader(v);
    glDeleteShader(f);
    GLint ok = 0;
    glGetProgramiv(id_, GL_LINK_STATUS, &ok);
    if (!ok) {
      char log[4096];
      glGetProgramInfoLog(id_, sizeof(log), nullptr, log);
      throw GlError(std::string("program '") + name + "' does not link: " + log);
    }
  }
  GLint operator[](const std::string& n) {
    auto it = loc_.find(n);
    if (it != loc_.end()) return it->second;
    return loc_[n] = glGetUniformLocation(id_, n.c_str());
  }
  GLuint id() const { return id_; }
  void use() const { glUseProgram(id_); }

 private:
  GLuint id_ = 0;
  std::unordered_map<std::string, GLint> loc_;
};

inline void set3(GLint loc, const Eigen::Vector3d& v) {
  glUniform3f(loc, static_cast<float>(v.x()), static_cast<float>(v.y()), static_cast<float>(v.z()));
}

inline Eigen::Matrix4f projection_from_K(const CameraModel& c) {
  const double w = c.width, h = c.height, n = c.near_m, f = c.far_m;
  Eigen::Matrix4d P = Eigen::Matrix4d::Zero();
  // Optical frame (x right, y down, z forward) straight to clip space; image row 0 lands in
  // framebuffer row 0, so glReadPixels returns the image top row first.
  P(0, 0) = 2.0 * c.fx / w;
  P(0, 2) = 2.0 * (c.cx + 0.5) / w - 1.0;
  P(1, 1) = 2.0 * c.fy / h;
  P(1, 2) = 2.0 * (c.cy + 0.5) / h - 1.0;
  P(2, 2) = (f + n) / (f - n);
  P(2, 3) = -2.0 * f * n / (f - n);
  P(3, 2) = 1.0;
  return P.cast<float>();
}

inline GLuint make_tex(GLenum internal, int w, int h, GLenum format, GLenum type, GLenum filter) {
  GLuint t = 0;
  glGenTextures(1, &t);
  glBindTexture(GL_TEXTURE_2D, t);
  glTexImage2D(GL_TEXTURE_2D, 0, static_cast<GLint>(internal), w, h, 0, format, type, nullptr);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, static_cast<GLint>(filter));
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, static_cast<GLint>(filter));
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  return t;
}

/// A tiling, mipmapped texture from tightly packed `data` (trilinear, repeating): surface maps.
inline GLuint make_tiled_tex(GLenum internal, int w, int h, GLenum format, GLenum type, const void* data) {
  GLuint t = 0;
  glGenTextures(1, &t);
  glBindTexture(GL_TEXTURE_2D, t);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTexImage2D(GL_TEXTURE_2D, 0, static_cast<GLint>(internal), w, h, 0, format, type, data);
  glGenerateMipmap(GL_TEXTURE_2D);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_REPEAT);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_REPEAT);
  return t;
}

inline void check_fbo(const char* what) {
  const GLenum st = glCheckFramebufferStatus(GL_FRAMEBUFFER);
  if (st != GL_FRAMEBUFFER_COMPLETE)
    throw GlError(std::string(what) + " framebuffer incomplete (status 0x" + std::to_string(st) + ")");
}

/// A framebuffer drawing into `colors` (colour attachments 0, 1, ... in that order) with `depth`
/// (a depth texture; 0: none), left bound. Throws GlError naming `what` when it is incomplete.
inline GLuint make_fbo(std::initializer_list<GLuint> colors, GLuint depth, const char* what) {
  GLuint fbo = 0;
  glGenFramebuffers(1, &fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  std::vector<GLenum> bufs;
  for (const GLuint tex : colors) {
    const auto attachment = static_cast<GLenum>(GL_COLOR_ATTACHMENT0 + bufs.size());
    glFramebufferTexture2D(GL_FRAMEBUFFER, attachment, GL_TEXTURE_2D, tex, 0);
    bufs.push_back(attachment);
  }
  if (depth != 0) glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, depth, 0);
  glDrawBuffers(static_cast<GLsizei>(bufs.size()), bufs.data());
  check_fbo(what);
  return fbo;
}

/// The state of an opaque, depth-tested pass into the bound framebuffer (the camera's scene pass,
/// the sonar's): colour attachment 0 cleared to `clear0`, depth to 1 (far), depth test LESS, both
/// faces drawn (passes that cull enable it per mesh), no blending.
inline void begin_opaque_pass(const float clear0[4]) {
  const float far = 1.0f;
  glColorMaski(0, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  glDepthMask(GL_TRUE);
  glClearBufferfv(GL_COLOR, 0, clear0);
  glClearBufferfv(GL_DEPTH, 0, &far);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDisable(GL_CULL_FACE);
  glDisable(GL_BLEND);
}

}  // namespace unav::renderer::gl
