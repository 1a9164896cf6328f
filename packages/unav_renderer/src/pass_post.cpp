// The post pass: water attenuation and ambient scatter, the forward-scatter blur, the in-scatter
// upsampling, Snell's window, motion blur, exposure and the sensor's noise, the distortion /
// port remap.
#include "renderer_impl.hpp"

#include <algorithm>

#include "shaders.hpp"
#include "unav_scene/noise.hpp"

namespace unav::renderer {

namespace {

// kPostFS's pcg() on the CPU: the frame's seed is hashed once here, not once per pixel.
GLuint pcg_seed(std::uint32_t v) {
  const std::uint32_t state = v * 747796405u + 2891336453u;
  const std::uint32_t word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
  return (word >> 22u) ^ word;
}

// The defocus disc's taps (kPostFS's u_disc): 16 for radii of 2 px and more, then 8 for smaller
// discs, each set a Vogel spiral over the unit disc (equal areas, golden-angle turns) shifted so
// that its mean is the pixel (no shift of a blurred image).
const std::array<Eigen::Vector2f, 24> kDefocusTaps = [] {
  std::array<Eigen::Vector2f, 24> taps;
  auto spiral = [&](std::size_t first, std::size_t n) {
    Eigen::Vector2f mean = Eigen::Vector2f::Zero();
    for (std::size_t k = 0; k < n; ++k) {
      const double r = std::sqrt((static_cast<double>(k) + 0.5) / static_cast<double>(n));
      const double a = 2.399963229728653 * static_cast<double>(k);  // pi (3 - sqrt 5)
      taps[first + k] = Eigen::Vector2f(static_cast<float>(r * std::cos(a)), static_cast<float>(r * std::sin(a)));
      mean += taps[first + k];
    }
    for (std::size_t k = 0; k < n; ++k) taps[first + k] -= mean / static_cast<float>(n);
  };
  spiral(0, 16);
  spiral(16, 8);
  return taps;
}();

// Largest upward component (-z in world_ned) of the unit view rays of a pinhole camera with
// rotation R_WC: 1 when the zenith is in view, else the maximum along the image border (sampled
// every few pixels; the function is smooth there).
double max_up_component(const CameraModel& c, const Eigen::Matrix3d& R_WC) {
  const Eigen::Vector3d zenith_C = R_WC.transpose() * Eigen::Vector3d(0.0, 0.0, -1.0);
  if (zenith_C.z() > 0.0) {
    const double u = c.fx * zenith_C.x() / zenith_C.z() + c.cx, v = c.fy * zenith_C.y() / zenith_C.z() + c.cy;
    if (u >= -0.5 && v >= -0.5 && u <= c.width - 0.5 && v <= c.height - 0.5) return 1.0;
  }
  double best = -1.0;
  auto up = [&](double u, double v) {
    const Eigen::Vector3d d((u - c.cx) / c.fx, (v - c.cy) / c.fy, 1.0);
    best = std::max(best, -(R_WC * d.normalized()).z());
  };
  const double w = c.width - 0.5, h = c.height - 0.5;
  for (int k = 0; k <= 128; ++k) {
    const double s = k / 128.0;
    up(-0.5 + s * (w + 0.5), -0.5);
    up(-0.5 + s * (w + 0.5), h);
    up(-0.5, -0.5 + s * (h + 0.5));
    up(w, -0.5 + s * (h + 0.5));
  }
  return best;
}

}  // namespace

// The forward-scatter blur's levels: scene_color -> its 4 x 4 means -> their 4 x 4 means.
void Renderer::Impl::blur_levels(const Targets& t) {
  blur_down.use();
  glUniform1i(blur_down["u_src"], 0);
  glActiveTexture(GL_TEXTURE0);
  glBindVertexArray(empty_vao);
  for (int k = 0; k < 2; ++k) {
    const GLuint src = k == 0 ? t.scene_color : t.blur_tex[0];
    const int sw = k == 0 ? t.width : t.blur_width[0], sh = k == 0 ? t.height : t.blur_height[0];
    glBindFramebuffer(GL_FRAMEBUFFER, t.blur_fbo[k]);
    glViewport(0, 0, t.blur_width[k], t.blur_height[k]);
    glBindTexture(GL_TEXTURE_2D, src);
    glUniform2f(blur_down["u_src_texel"], 1.0f / static_cast<float>(sw), 1.0f / static_cast<float>(sh));
    glDrawArrays(GL_TRIANGLES, 0, 3);
  }
}

// The post program with these features compiled in (compiled on first use).
// pixels: 0 every pixel, 1 those with geometry, 2 the water (see PIXELS in kPostFS).
Program& Renderer::Impl::post_program(const PostFeatures& features, int pixels) {
  static constexpr std::array<const char*, kPostFeatures> kNames = {"REMAP",    "FWD",        "INSCATTER", "VIGNETTING",
                                                                    "SHOT",     "READ_NOISE", "SNELL",     "MOTION",
                                                                    "RADIANCE", "DEFOCUS",    "CHROMA"};
  unsigned key = 0;
  for (std::size_t i = 0; i < features.size(); ++i) key |= (features[i] ? 1u : 0u) << i;
  key |= static_cast<unsigned>(pixels) << features.size();
  return program_variant(post_variants, key, detail::kPostVS, detail::kPostFS, "post", [&] {
    std::string defines = "#define PIXELS " + std::to_string(pixels) + "\n";
    for (std::size_t i = 0; i < features.size(); ++i)
      defines += std::string("#define ") + kNames[i] + (features[i] ? " 1\n" : " 0\n");
    return defines;
  });
}

// Post pass: forward scatter, backscatter, + in-scatter, distortion, noise, encoding.
void Renderer::Impl::post_pass(const Targets& t, const FrameSetup& f, const CameraModel& c, std::uint64_t seq,
                               bool do_inscatter, float march_max_m) {
  const bool shot = options.noise && c.shot_noise > 0.0, read_noise = options.noise && c.noise_stddev > 0.0;
  // Motion over the exposure (ending at the stamp), in the optical frame: a world point P (camera
  // coordinates now) was at P + w x P + v when the shutter opened.
  const Eigen::Matrix3d R_CB = c.X_BC.linear().transpose();
  const Eigen::Vector3d v_C =
      c.exposure_time_s * (R_CB * (velocity.linear + velocity.angular.cross(c.X_BC.translation())));
  const Eigen::Vector3d w_C = c.exposure_time_s * (R_CB * velocity.angular);
  const bool motion = c.exposure_time_s > 0.0 && (v_C.norm() > 1e-9 || w_C.norm() > 1e-9);
  // Snell's window costs every pixel once compiled in (llvmpipe): only when a ray can reach it.
  const double critical_up = std::sqrt(1.0 - 1.0 / (water.refractive_index * water.refractive_index));
  const bool window =
      options.snell_window && f.cam_W.z() > 0.0 && max_up_component(c, f.X_WC.linear()) > critical_up - 1e-3;
  const bool remap = t.lin_fbo != 0;
  // REMAP, FWD, INSCATTER, VIGNETTING, SHOT, READ_NOISE, SNELL, MOTION, RADIANCE, DEFOCUS, CHROMA
  // (kPostFS). With a remap, the sensor's stage (vignetting, noise) and the lateral colour run
  // there, per output pixel (a camera with lateral colour always has one: targets_for()).
  const bool vignetting = c.vignetting > 0.0;
  const PostFeatures features{false,          options.forward_scatter, do_inscatter, vignetting && !remap,
                              shot && !remap, read_noise && !remap,    window,       motion,
                              remap,          c.lens.defocus(),        false};
  glBindFramebuffer(GL_FRAMEBUFFER, remap ? t.lin_fbo : t.post_fbo);
  glViewport(0, 0, t.width, t.height);  // the internal size (the output's without a remap)
  // Geometry and water apart: the water's pixels (depth still at its clear value 1) skip the
  // forward scatter and the depth read, the geometry's skip Snell's window; llvmpipe shades only
  // the blocks whose depth test passes. Every pixel is drawn by exactly one of the two.
  glEnable(GL_DEPTH_TEST);
  glDepthMask(GL_FALSE);
  PostFeatures geometry = features, water_only = features;
  geometry[6] = false;      // no Snell's window
  water_only[1] = false;    // no forward scatter
  water_only[9] = false;    // no defocus (the water's pixels have no depth)
  glDepthFunc(GL_GREATER);  // the triangle lies at depth 1: passes where the scene drew
  post_draw(post_program(geometry, 1), t, t.scene_color, f, c, seq, march_max_m, false, motion, v_C, w_C);
  glDepthFunc(GL_EQUAL);  // where it did not
  post_draw(post_program(water_only, 2), t, t.scene_color, f, c, seq, march_max_m, window, motion, v_C, w_C);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  glDisable(GL_DEPTH_TEST);
  if (remap) {  // each output pixel resamples the radiance through the distortion map, + the sensor
    glBindFramebuffer(GL_FRAMEBUFFER, t.post_fbo);
    glViewport(0, 0, t.out_width, t.out_height);
    const PostFeatures sensor{
        true, false, false, vignetting, shot, read_noise, false, false, false, false, c.lens.lateral_chromatic != 0.0};
    post_draw(post_program(sensor), t, t.lin_tex, f, c, seq, march_max_m, false, false, v_C, w_C);
  }
}

// One draw of the post pass with program `post` (post_pass()).
void Renderer::Impl::post_draw(Program& post, const Targets& t, GLuint color, const FrameSetup& f, const CameraModel& c,
                               std::uint64_t seq, float march_max_m, bool window, bool motion,
                               const Eigen::Vector3d& v_C, const Eigen::Vector3d& w_C) {
  post.use();
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, color);
  glActiveTexture(GL_TEXTURE1);
  glBindTexture(GL_TEXTURE_2D, t.scene_zc);
  glActiveTexture(GL_TEXTURE2);
  glBindTexture(GL_TEXTURE_2D, t.distmap);
  glActiveTexture(GL_TEXTURE3);
  glBindTexture(GL_TEXTURE_2D, t.is_tex);
  glActiveTexture(GL_TEXTURE4);
  glBindTexture(GL_TEXTURE_2D, t.is_water_tex);
  glActiveTexture(GL_TEXTURE7);
  glBindTexture(GL_TEXTURE_2D, color);
  glBindSampler(7, nearest);
  glActiveTexture(GL_TEXTURE8);
  glBindTexture(GL_TEXTURE_2D, t.blur_tex[0]);
  glActiveTexture(GL_TEXTURE9);
  glBindTexture(GL_TEXTURE_2D, t.blur_tex[1]);
  glActiveTexture(GL_TEXTURE0);
  glUniform1i(post["u_blur4"], 8);
  glUniform1i(post["u_blur16"], 9);
  glUniform4f(post["u_blur_uv"], 1.0f / static_cast<float>(4 * t.blur_width[0]),
              1.0f / static_cast<float>(4 * t.blur_height[0]), 1.0f / static_cast<float>(16 * t.blur_width[1]),
              1.0f / static_cast<float>(16 * t.blur_height[1]));
  glUniform1i(post["u_color"], 0);
  glUniform1i(post["u_color_px"], 7);
  glUniform1i(post["u_depth"], 1);
  glUniform1i(post["u_distmap"], 2);
  glUniform1i(post["u_inscatter"], 3);
  glUniform1i(post["u_inscatter_water"], 4);
  glUniform1f(post["u_march_max_m"], march_max_m);
  glUniform4f(post["u_K"], static_cast<float>(c.fx), static_cast<float>(c.fy), static_cast<float>(c.cx),
              static_cast<float>(c.cy));
  glUniform2i(post["u_size"], t.width, t.height);
  set3(post["u_betaD"], water.beta_D);
  set3(post["u_betaB"], water.beta_B);
  set3(post["u_Binf"], water.veiling_light_at(f.cam_W.z(), world.sun.surface_irradiance));
  glUniform1f(post["u_veil_gradient"], static_cast<float>(water.veiling_light_gradient));
  const Eigen::Matrix3f R_WC = f.X_WC.linear().cast<float>();
  glUniformMatrix3fv(post["u_R_WC"], 1, GL_FALSE, R_WC.data());
  glUniform1f(post["u_fwd_per_m"], static_cast<float>(water.forward_scatter_per_m));
  glUniform1f(post["u_blur_px_per_m"], static_cast<float>(water.forward_blur_rad_per_m * c.fx));
  // The downwelling irradiance at the camera: the auto exposure's and the auto white balance's meter.
  const Eigen::Vector3d Ed_cam =
      (world.sun.surface_irradiance.array() * (-water.K_d.array() * std::max(0.0, f.cam_W.z())).exp()).matrix();
  double gain = c.exposure;
  if (options.auto_exposure) gain *= std::clamp(0.45 / std::max(luminance(Ed_cam), 1e-6), 0.25, 5.0);
  set3(post["u_gain"], gain * c.white_balance.gains_for(Ed_cam));
  if (c.lens.defocus()) {
    // Blur diameter [px] = fx A |1 / z_f - 1 / z| (CameraLens::blur_diameter_px).
    glUniform2f(post["u_coc"], static_cast<float>(c.fx * 1e-3 * c.lens.focal_length_mm / c.lens.f_number),
                static_cast<float>(1.0 / c.lens.focus_distance_m));
    glUniform2fv(post["u_disc"], static_cast<GLsizei>(kDefocusTaps.size()), kDefocusTaps.front().data());
  }
  if (c.lens.lateral_chromatic != 0.0)
    glUniform2f(post["u_chroma"], static_cast<float>(1.0 / (1.0 + c.lens.lateral_chromatic)),
                static_cast<float>(1.0 / (1.0 - c.lens.lateral_chromatic)));
  glUniform1f(post["u_noise_std"], options.noise ? static_cast<float>(c.noise_stddev) : 0.0f);
  glUniform1f(post["u_shot"], options.noise ? static_cast<float>(c.shot_noise) : 0.0f);
  glUniform1f(post["u_vignetting"], static_cast<float>(c.vignetting));
  // The output (in-air) camera's pinhole for the field angle of the vignetting.
  glUniform4f(post["u_Kout"], static_cast<float>(t.out_K[0]), static_cast<float>(t.out_K[1]),
              static_cast<float>(t.out_K[2]), static_cast<float>(t.out_K[3]));
  glUniform1ui(post["u_seed"], pcg_seed(noise::hash32(static_cast<std::uint32_t>(options.seed) ^
                                                      static_cast<std::uint32_t>(seq * 2654435761ULL))));
  glUniform1i(post["u_srgb"], options.srgb_output ? 1 : 0);
  if (motion) {
    set3(post["u_motion_v"], v_C);
    set3(post["u_motion_w"], w_C);
  }
  if (window) {
    const double n = water.refractive_index;
    const double t0 = 1.0 - std::pow((n - 1.0) / (n + 1.0), 2);  // Fresnel transmittance at normal incidence
    const Eigen::Vector3d& E0 = world.sun.surface_irradiance;
    const double amb = world.sun.ambient_fraction;
    glUniform1f(post["u_cam_depth"], static_cast<float>(f.cam_W.z()));
    glUniform1f(post["u_n_water"], static_cast<float>(n));
    set3(post["u_sky"], n * n * amb / t0 * E0);
    set3(post["u_sun_glow"], M_PI * (1.0 - amb) / t0 * E0);
    set3(post["u_sun_dir_W"], world.sun.direction_W);
  }
  glBindVertexArray(empty_vao);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glBindSampler(7, 0);
}

}  // namespace unav::renderer
