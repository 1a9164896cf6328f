// The water between camera and scene: marine snow in the lamps' light and the lamps'
// in-scattering, ray-marched through their shadow maps at a lower resolution.
#include "renderer_impl.hpp"

#include <algorithm>

#include "shaders.hpp"

namespace unav::renderer {

Program& Renderer::Impl::snow_program(int nlamps) {
  return program_variant(snow_variants, static_cast<unsigned>(nlamps), detail::kSnowVS, detail::kSnowFS, "marine_snow",
                         [nlamps] { return "#define NLAMPS " + std::to_string(nlamps) + "\n"; });
}

Program& Renderer::Impl::inscatter_program(int nlamps, int nsamples, bool shadows) {
  const auto key = (static_cast<unsigned>(nlamps) << 16) | (static_cast<unsigned>(nsamples) << 1) | (shadows ? 1u : 0u);
  return program_variant(inscatter_variants, key, detail::kPostVS, detail::kInscatterFS, "lamp_inscatter", [&] {
    return "#define NLAMPS " + std::to_string(nlamps) + "\n#define NSAMPLES " + std::to_string(nsamples) +
           "\n#define SHADOWS " + (shadows ? "1" : "0") + "\n";
  });
}

// Marine snow: additive into the colour only (depth and segmentation untouched).
void Renderer::Impl::snow_pass(const FrameSetup& f, const CameraModel& c, double stamp_s) {
  if (options.marine_snow && snow_count > 0) {
    Program& snow = snow_program(f.nl);
    snow.use();
    glUniformMatrix4fv(snow["u_view"], 1, GL_FALSE, f.view.data());
    glUniformMatrix4fv(snow["u_proj"], 1, GL_FALSE, f.proj.data());
    set3(snow["u_cam_W"], f.cam_W);
    glUniform1f(snow["u_box"], static_cast<float>(world.marine_snow.box_m));
    glUniform1f(snow["u_time"], static_cast<float>(std::fmod(stamp_s, 1.0e4)));
    glUniform1f(snow["u_size_m"], static_cast<float>(world.marine_snow.size_m));
    glUniform1f(snow["u_fx"], static_cast<float>(c.fx));
    set3(snow["u_E0"], world.sun.surface_irradiance);
    set3(snow["u_Kd"], water.K_d);
    set3(snow["u_betaD"], water.beta_D);
    set_lamps_W(snow, f);
    glEnable(GL_PROGRAM_POINT_SIZE);
    glDepthMask(GL_FALSE);
    glEnablei(GL_BLEND, 0);
    glBlendFunc(GL_ONE, GL_ONE);
    glColorMaski(0, GL_TRUE, GL_TRUE, GL_TRUE, GL_FALSE);
    glColorMaski(1, GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    glBindVertexArray(snow_vao);
    glDrawArrays(GL_POINTS, 0, snow_count);
    glDisablei(GL_BLEND, 0);
    glColorMaski(0, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    glColorMaski(1, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    glDepthMask(GL_TRUE);
  }
}

// Lamp in-scattering at low resolution (and the forward-scatter mip chain). Returns whether
// in-scattering was drawn; *march_max_m: the march length the post pass must use too.
bool Renderer::Impl::inscatter_pass(const Targets& t, const FrameSetup& f, const CameraModel& c, float* march_max_out) {
  const int nsamples = std::max(0, options.lamp_scatter_samples);
  const bool do_inscatter = f.nl > 0 && nsamples > 0;
  // March until the lamp light has dropped to ~3% (3.5 attenuation lengths).
  const auto march_max_m = static_cast<float>(std::min(30.0, 3.5 / std::max(1e-3, water.beta_D.minCoeff())));
  glDisable(GL_DEPTH_TEST);
  if (do_inscatter) {
    glBindFramebuffer(GL_FRAMEBUFFER, t.is_fbo);
    glViewport(0, 0, t.is_width, t.is_height);
    Program& inscatter = inscatter_program(f.nl, nsamples, f.shadows);
    inscatter.use();
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, t.scene_color);
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D, t.scene_zc);
    glActiveTexture(GL_TEXTURE0);
    glUniform1i(inscatter["u_color"], 0);
    glUniform1i(inscatter["u_depth"], 1);
    glUniform4f(inscatter["u_K"], static_cast<float>(c.fx), static_cast<float>(c.fy), static_cast<float>(c.cx),
                static_cast<float>(c.cy));
    glUniform2i(inscatter["u_size"], t.width, t.height);
    glUniform1f(inscatter["u_scale"], static_cast<float>(t.is_scale));
    set3(inscatter["u_betaD"], water.beta_D);
    glUniform3fv(inscatter["u_lamp_pos_C[0]"], f.nl, f.lamp_pos_C);
    glUniform3fv(inscatter["u_lamp_dir_C[0]"], f.nl, f.lamp_dir_C);
    glUniform3fv(inscatter["u_lamp_I[0]"], f.nl, f.lamp_I);
    glUniform2fv(inscatter["u_lamp_cos[0]"], f.nl, f.lamp_cos);
    glUniform1i(inscatter["u_shadow"], 5);
    glActiveTexture(GL_TEXTURE5);
    glBindTexture(GL_TEXTURE_2D_ARRAY, f.shadows ? shadow_tex : 0);
    glActiveTexture(GL_TEXTURE0);
    if (f.shadows) glUniformMatrix4fv(inscatter["u_shadow_vp_C[0]"], f.nl, GL_FALSE, f.shadow_vp_C);
    // The march's samples lie centimetres to metres apart and the result is upsampled: nearest
    // depth tests instead of 2x2 PCF (a quarter of the cost of the pass's costliest lookup).
    glBindSampler(5, shadow_nearest);
    glBindSampler(0, nearest);  // u_color: the segmentation of one pixel
    set3(inscatter["u_b_scatter"], water.b_scatter);
    glUniform1f(inscatter["u_schlick_k"], static_cast<float>(water.schlick_k()));
    glUniform1f(inscatter["u_back_frac"], static_cast<float>(water.phase_backscatter_fraction));
    glUniform1f(inscatter["u_march_max_m"], march_max_m);
    glBindVertexArray(empty_vao);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glBindSampler(5, 0);
    glBindSampler(0, 0);
  }

  if (options.forward_scatter) blur_levels(t);
  *march_max_out = march_max_m;
  return do_inscatter;
}

}  // namespace unav::renderer
