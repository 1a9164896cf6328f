// Render targets per camera: the internal (margin-enlarged) pinhole image, the scene, post,
// in-scatter and blur buffers, the distortion / port remap.
#include "renderer_impl.hpp"

#include <algorithm>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

namespace unav::renderer {

namespace {

// The internal image's margin on each side of the output frame [px] for a field that reaches
// `over` pixels beyond the frame (negative: stays inside it), with 2 px to spare for the bilinear
// read. A field inside the frame (behind a flat port, whose magnification narrows the view) gives a
// negative margin: the internal image is cropped to what the post pass reads, in steps of 4 px, so
// that the pixels kept lie at the same place relative to the principal point, and the in-scatter's
// low-resolution texels (4 x 4 by default) and the forward-scatter blur's 4 x 4 means group the same
// pixels as without the crop (its 16 x 16 means may not; demo front camera, measured before those
// replaced a mip chain: mean difference 0.03 of 255, at most 9 levels).
int internal_margin(float over, int size) {
  const int need = static_cast<int>(std::ceil(std::max(over, -0.5f * size))) + 2;
  if (need >= 2) return std::min(need, size / 2);
  const int crop = 4 * ((2 - need) / 4);
  return 2 - std::min(crop, 4 * ((size / 2 - 16) / 4));
}

}  // namespace

Targets& Renderer::Impl::targets_for(const CameraModel& c) {
  auto it = targets.find(c.name);
  if (it != targets.end()) return it->second;
  Targets t;
  t.out_width = c.width;
  t.out_height = c.height;
  t.out_K[0] = c.fx;
  t.out_K[1] = c.fy;
  t.out_K[2] = c.cx;
  t.out_K[3] = c.cy;
  std::vector<cv::Point2f> dst;
  // Behind a refracting port the scene is rendered with the water-side paraxial focal length
  // (1:1 sampling at the image centre); each output pixel's ray is undistorted in air, then
  // refracted by the port, then projected into that pinhole.
  t.seen = c.water_equivalent();  // a least-squares fit behind a port: once per camera
  const double magnification = t.seen.fx / c.fx;
  // Lateral colour resamples red and blue in the remap (a pinhole's map is the identity).
  if (c.has_distortion() || c.port.refracts() || c.lens.lateral_chromatic != 0.0) {
    // For every output (distorted) pixel, the undistorted pixel it sees.
    std::vector<cv::Point2f> src(static_cast<std::size_t>(c.width) * c.height);
    for (int v = 0; v < c.height; ++v)
      for (int u = 0; u < c.width; ++u) src[static_cast<std::size_t>(v) * c.width + u] = cv::Point2f(u, v);
    cv::Mat K(3, 3, CV_64F), D(1, 5, CV_64F);
    for (int r = 0; r < 3; ++r)
      for (int q = 0; q < 3; ++q) K.at<double>(r, q) = c.K()(r, q);
    for (int k = 0; k < 5; ++k) D.at<double>(0, k) = c.distortion[k];
    cv::undistortPoints(src, dst, K, D, cv::noArray(), c.port.refracts() ? cv::Mat::eye(3, 3, CV_64F) : K,
                        cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 30, 1e-6));
    if (c.port.refracts())
      for (auto& p : dst) {  // normalized air ray -> water ray -> pixel of the water pinhole
        const Eigen::Vector3d w = c.port.to_water({p.x, p.y, 1.0});
        p = cv::Point2f(static_cast<float>(c.fx * magnification * w.x() / w.z() + c.cx),
                        static_cast<float>(c.fy * magnification * w.y() / w.z() + c.cy));
      }
    // How far the undistorted field reaches beyond the output frame (negative: how far inside it
    // stays), on the worse side of the principal point.
    float over_x = -1e9f, over_y = -1e9f;
    for (const auto& p : dst) {
      if (!std::isfinite(p.x) || !std::isfinite(p.y)) continue;
      over_x = std::max({over_x, -p.x, p.x - (c.width - 1)});
      over_y = std::max({over_y, -p.y, p.y - (c.height - 1)});
    }
    // The lateral colour reads red and blue up to |k| x the radius farther out.
    const float chroma_px = static_cast<float>(std::abs(c.lens.lateral_chromatic) * std::hypot(c.width, c.height));
    over_x += chroma_px;
    over_y += chroma_px;
    t.margin_x = internal_margin(over_x, c.width);
    t.margin_y = internal_margin(over_y, c.height);
    for (auto& p : dst) p += cv::Point2f(static_cast<float>(t.margin_x), static_cast<float>(t.margin_y));
  }
  t.internal = c;
  t.internal.fx *= magnification;
  t.internal.fy *= magnification;
  t.internal.width = c.width + 2 * t.margin_x;
  t.internal.height = c.height + 2 * t.margin_y;
  t.internal.cx += t.margin_x;
  t.internal.cy += t.margin_y;
  t.width = t.internal.width;
  t.height = t.internal.height;

  t.scene_color = make_tex(GL_RGBA16F, t.width, t.height, GL_RGBA, GL_FLOAT, GL_LINEAR);
  t.scene_zc = make_tex(GL_R32F, t.width, t.height, GL_RED, GL_FLOAT, GL_NEAREST);
  t.scene_depth = make_tex(GL_DEPTH_COMPONENT32F, t.width, t.height, GL_DEPTH_COMPONENT, GL_FLOAT, GL_NEAREST);
  t.scene_fbo = gl::make_fbo({t.scene_color, t.scene_zc}, t.scene_depth, "scene");

  t.is_scale = std::max(1, options.lamp_scatter_downsample);
  t.is_width = (t.width + t.is_scale - 1) / t.is_scale;
  t.is_height = (t.height + t.is_scale - 1) / t.is_scale;
  // 32-bit floats: llvmpipe reads them without a half-float conversion per texel (the post pass
  // reads four a pixel), and they are small (1/16 of the image).
  t.is_tex = make_tex(GL_RGBA32F, t.is_width, t.is_height, GL_RGBA, GL_FLOAT, GL_NEAREST);
  t.is_water_tex = make_tex(GL_RGBA32F, t.is_width, t.is_height, GL_RGBA, GL_FLOAT, GL_LINEAR);
  t.is_fbo = gl::make_fbo({t.is_tex, t.is_water_tex}, 0, "in-scatter");

  // 32-bit floats: the post pass reads two a pixel, without a half-float conversion each.
  for (int k = 0; k < 2; ++k) {
    const int step = k == 0 ? 4 : 16;
    t.blur_width[k] = (t.width + step - 1) / step;
    t.blur_height[k] = (t.height + step - 1) / step;
    t.blur_tex[k] = make_tex(GL_RGBA32F, t.blur_width[k], t.blur_height[k], GL_RGBA, GL_FLOAT, GL_LINEAR);
    t.blur_fbo[k] = gl::make_fbo({t.blur_tex[k]}, 0, "forward-scatter blur");
  }

  t.post_rgba = make_tex(GL_RGBA8, c.width, c.height, GL_RGBA, GL_UNSIGNED_BYTE, GL_NEAREST);
  t.post_zc = make_tex(GL_R32F, c.width, c.height, GL_RED, GL_FLOAT, GL_NEAREST);
  // The post pass draws geometry and water apart, by a depth test against scene_depth: attached
  // to post_fbo where it reads pixel for pixel, else to the radiance target it remaps from.
  t.post_fbo = gl::make_fbo({t.post_rgba, t.post_zc}, dst.empty() ? t.scene_depth : 0, "post");
  if (!dst.empty()) {
    t.distmap = make_tex(GL_RG32F, c.width, c.height, GL_RG, GL_FLOAT, GL_NEAREST);
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, c.width, c.height, GL_RG, GL_FLOAT, dst.data());
    // 32-bit floats: the remap reads them without a half-float conversion, and seg exactly.
    t.lin_tex = make_tex(GL_RGBA32F, t.width, t.height, GL_RGBA, GL_FLOAT, GL_LINEAR);
    t.lin_fbo = gl::make_fbo({t.lin_tex}, t.scene_depth, "post radiance");
  }
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  check_gl("render targets");
  return targets.emplace(c.name, t).first->second;
}

}  // namespace unav::renderer
