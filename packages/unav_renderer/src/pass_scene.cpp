// The scene pass: every mesh in its material variant, lit by sun and lamps through their shadow
// maps, with receiver culling and levels of detail.
#include "renderer_impl.hpp"

#include <algorithm>

#include "shaders.hpp"

namespace unav::renderer {

namespace {

// Scene variant bits: triplanar 1, macro 2, sections 4, bump 8, specular 16, sediment 32, sun shadow 64,
// lamp shadows 128, normal map 256, ORM map 512, lamps << 10. The shadow bits come per chunk
// (shadow receiver culling).
constexpr unsigned kSunShadowBit = 64, kLampShadowBit = 128, kShadowShift = 6, kNormalMapBit = 256, kOrmBit = 512,
                   kLampShift = 10;

}  // namespace

std::string scene_defines(unsigned v) {
  const auto bit = [v](unsigned b) { return (v & b) ? "1" : "0"; };
  return std::string("#define TRIPLANAR ") + bit(1) + "\n#define MACRO " + bit(2) + "\n#define SECTIONS " + bit(4) +
         "\n#define BUMP " + bit(8) + "\n#define SPECULAR " + bit(16) + "\n#define SEDIMENT " + bit(32) +
         "\n#define SUN_SHADOW " + bit(kSunShadowBit) + "\n#define LAMP_SHADOWS " + bit(kLampShadowBit) +
         "\n#define NORMAL_MAP " + bit(kNormalMapBit) + "\n#define ORM_MAP " + bit(kOrmBit) + "\n#define NLAMPS " +
         std::to_string(v >> kLampShift) + "\n";
}

Program& Renderer::Impl::scene_program(const GpuMesh& m, unsigned shadow_bits, const FrameSetup& f, double stamp_s,
                                       std::set<unsigned>* set_up) {
  const Look k = look(m);
  const unsigned v = (m.triplanar ? 1u : 0u) | (m.macro ? 2u : 0u) | (m.sections ? 4u : 0u) | (k.bump ? 8u : 0u) |
                     (k.specular ? 16u : 0u) | (k.sediment ? 32u : 0u) | (shadow_bits << kShadowShift) |
                     (k.normal_map ? kNormalMapBit : 0u) | (k.orm_map ? kOrmBit : 0u) |
                     (static_cast<unsigned>(f.nl) << kLampShift);
  Program& p =
      program_variant(scene_variants, v, detail::kSceneVS, detail::kSceneFS, "scene", [v] { return scene_defines(v); });
  p.use();
  if (!set_up->insert(v).second) return p;
  glUniformMatrix4fv(p["u_view"], 1, GL_FALSE, f.view.data());
  glUniformMatrix4fv(p["u_proj"], 1, GL_FALSE, f.proj.data());
  set3(p["u_cam_W"], f.cam_W);
  set3(p["u_sun_dir_W"], world.sun.direction_W);
  set3(p["u_E0"], world.sun.surface_irradiance);
  glUniform1f(p["u_ambient"], static_cast<float>(world.sun.ambient_fraction));
  glUniform1f(p["u_caustics"], options.caustics ? static_cast<float>(options.caustic_strength) : 0.0f);
  glUniform1f(p["u_time"], static_cast<float>(std::fmod(stamp_s, 1.0e4)));
  set3(p["u_Kd"], water.K_d);
  set3(p["u_betaD"], water.beta_D);
  set_lamps_W(p, f);
  if (v & kSunShadowBit) {
    glUniformMatrix4fv(p["u_sun_vp"], 1, GL_FALSE, f.sun_vp);
    glUniform1i(p["u_sun_map"], 6);
  }
  if (v & kLampShadowBit) {
    glUniformMatrix4fv(p["u_shadow_vp[0]"], f.nl, GL_FALSE, f.shadow_vp_W);
    glUniform1i(p["u_shadow"], 5);
  }
  glUniform1i(p["u_tex"], 0);
  if (v & 2u) glUniform1i(p["u_tex_macro"], 4);
  if (v & 8u) glUniform1i(p["u_grad"], 1);
  if (v & kNormalMapBit) glUniform1i(p["u_normal_map"], 2);
  if (v & kOrmBit) glUniform1i(p["u_orm"], 3);
  if (v & 32u) {
    set3(p["u_sediment_albedo"], sediment_albedo);
    // No seabed: nothing is buried.
    glUniform1f(p["u_seabed_z"], world.seabed.enabled ? static_cast<float>(world.seabed.depth_m) : 1e9f);
  }
  return p;
}

// The lamps' world-frame uniforms (position, beam axis, intensity, cone) of the scene and the
// marine snow programs.
void Renderer::Impl::set_lamps_W(Program& p, const FrameSetup& f) const {
  if (f.nl == 0) return;
  glUniform3fv(p["u_lamp_pos_W[0]"], f.nl, f.lamp_pos_W);
  glUniform3fv(p["u_lamp_dir_W[0]"], f.nl, f.lamp_dir_W);
  glUniform3fv(p["u_lamp_I[0]"], f.nl, f.lamp_I);
  glUniform2fv(p["u_lamp_cos[0]"], f.nl, f.lamp_cos);
}

// Shadow receiver culling for the lamps (per frame): bit 2 when some lamp's shadow map can darken
// the terrain chunk ch of meshes[mesh]: it lies in the lamp's shadow frustum, and either the
// terrain itself can cut the lamp's rays to it (the flattest ray from the lamp to the chunk is not
// steeper than the terrain's steepest slope), or a caster box of another mesh overlaps it as seen
// from the lamp, in azimuth and in depression angle (a ray through both needs both).
unsigned Renderer::Impl::lamp_shadow_bits(std::size_t mesh, const Chunk& ch, const FrameSetup& f,
                                          const std::vector<LampCasters>& casters) const {
  const GpuMesh& m = meshes[mesh];
  for (int i = 0; i < f.nl; ++i) {
    const Eigen::Map<const Eigen::Matrix4f> vp(f.shadow_vp_W + std::ptrdiff_t{16} * i);
    if (!in_frustum(vp, ch)) continue;
    const Eigen::Vector3f L = Eigen::Map<const Eigen::Vector3f>(f.lamp_pos_W + 3 * static_cast<std::ptrdiff_t>(i));
    const LampCaster r = seen_from(L, mesh, ch.lo, ch.hi);
    if (!(std::tan(r.dep_lo) > m.tan_slope)) return 2u;
    if (casters[static_cast<std::size_t>(i)].any_may_shadow(r, mesh)) return 2u;
  }
  return 0u;
}

// Scene geometry into colour (direct signal), camera-space depth and segmentation.
void Renderer::Impl::scene_pass(const Targets& t, const FrameSetup& f, double stamp_s) {
  glBindFramebuffer(GL_FRAMEBUFFER, t.scene_fbo);
  glViewport(0, 0, t.width, t.height);
  const float zero[4] = {0, 0, 0, 0};
  const float inf = std::numeric_limits<float>::infinity();
  const float inf4[4] = {inf, inf, inf, inf};
  glColorMaski(1, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  glClearBufferfv(GL_COLOR, 1, inf4);
  gl::begin_opaque_pass(zero);
  glActiveTexture(GL_TEXTURE6);
  glBindTexture(GL_TEXTURE_2D, f.sun_shadow ? sun_tex : 0);
  glActiveTexture(GL_TEXTURE5);
  glBindTexture(GL_TEXTURE_2D_ARRAY, f.shadows ? shadow_tex : 0);
  glActiveTexture(GL_TEXTURE0);
  glBindSampler(1, mip_nearest);  // u_grad
  glBindSampler(4, mip_nearest);  // u_tex_macro
  const Eigen::Matrix4f vp = f.proj * f.view;
  const Eigen::Vector3f cam = f.cam_W.cast<float>();
  std::set<unsigned> set_up;  // variants whose frame uniforms are set
  const unsigned all_shadows = (f.sun_shadow ? 1u : 0u) | (f.shadows ? 2u : 0u);
  // Shadow receiver culling: the terrain's visible chunks by the shadow lookups they need (llvmpipe
  // pays for a lookup on every pixel of a draw that compiles it, lit or not).
  const bool cull = receiver_culling() && all_shadows != 0;
  std::vector<LampCasters> casters;  // per lamp: the caster boxes in its frustum, seen from it
  if (cull && f.shadows) {
    casters.resize(static_cast<std::size_t>(f.nl));
    for (int i = 0; i < f.nl; ++i) {
      const Eigen::Map<const Eigen::Matrix4f> lvp(f.shadow_vp_W + std::ptrdiff_t{16} * i);
      const Eigen::Vector3f L = Eigen::Map<const Eigen::Vector3f>(f.lamp_pos_W + 3 * static_cast<std::ptrdiff_t>(i));
      for (const CasterBox& c : caster_boxes) {
        if (!in_frustum(lvp, c.lo, c.hi)) continue;
        if (hidden_under(c.under, L)) continue;  // under a terrain mesh the lamp stands over: never in its map
        const float pad = pcf_pad(f.lamp_texel_per_m[i], L, c.lo, c.hi);
        casters[static_cast<std::size_t>(i)].add(seen_from(L, c.mesh, c.lo.array() - pad, c.hi.array() + pad));
      }
    }
  }
  // What to draw by level of detail (the shadow lift; non-terrain and full meshes: 0), then by
  // the shadow lookups needed.
  std::array<std::array<std::vector<const Chunk*>, 4>, std::size_t{2} * kLodLevels> bins;  // skirts: kLodLevels + level
  const float fx = f.lod_fx;
  std::vector<int> levels;
  for (std::size_t& n : timings.terrain_tiles) n = 0;
  for (std::size_t& n : timings.object_parts) n = 0;
  timings.shadow_lookups_drawn = timings.shadow_lookups_skipped = 0;
  timings.scene_fragments = timings.sun_lookup_fragments = timings.lamp_lookup_fragments = 0;
  timings.scene_invocations = 0;
  if (options.profile_passes && fragment_query == 0) {
    glGenQueries(1, &fragment_query);
    if (epoxy_gl_version() >= 46 || epoxy_has_gl_extension("GL_ARB_pipeline_statistics_query"))
      glGenQueries(1, &invocation_query);
  }
  // The terrain last: what stands on it hides part of it, and llvmpipe skips the shading of
  // blocks whose depth test fails (the image is the same in any order).
  std::vector<std::size_t> order;
  order.reserve(meshes.size());
  for (const bool terrain : {false, true})
    for (std::size_t mi = 0; mi < meshes.size(); ++mi)
      if (meshes[mi].terrain == terrain) order.push_back(mi);
  for (const std::size_t mi : order) {
    const GpuMesh& m = meshes[mi];
    for (auto& level : bins)
      for (auto& b : level) b.clear();
    // Chunk `draw` at `level` (a skirt: kLodLevels + level), its shadow lookups decided by `box`
    // (the chunk, or its tile).
    const auto add = [&](const Chunk& draw, const Chunk& box, int level) {
      unsigned bits = all_shadows;
      if (cull && m.terrain) {
        bits = (f.sun_shadow && !box.sun_free ? 1u : 0u) | (f.shadows ? lamp_shadow_bits(mi, box, f, casters) : 0u);
        for (unsigned b : {1u, 2u}) {
          if (!(all_shadows & b)) continue;
          ++((bits & b) ? timings.shadow_lookups_drawn : timings.shadow_lookups_skipped);
        }
      }
      bins[static_cast<std::size_t>(level)][bits].push_back(&draw);
    };
    const auto seen = [&](const Chunk& ch) {
      return in_frustum(vp, ch) && !(options.occlusion_culling && hidden_under(ch.under, cam));
    };
    if (!m.lod.empty()) {
      for (std::size_t ci = 0; ci < m.chunks.size(); ++ci) {
        if (!seen(m.chunks[ci])) continue;
        const std::size_t k = lod_level(m.lod[ci], cam, fx, options.terrain_lod_px);
        ++timings.object_parts[k];
        add(m.lod[ci].level[k], m.chunks[ci], static_cast<int>(k));
      }
    } else if (m.tiles.empty()) {
      for (const Chunk& ch : m.chunks)
        if (seen(ch)) add(ch, ch, 0);
    } else {
      levels.resize(m.tiles.size());
      for (std::size_t ti = 0; ti < m.tiles.size(); ++ti)
        levels[ti] = lod_level(m.tiles[ti], cam, fx, options.terrain_lod_px);
      const auto tc = static_cast<std::size_t>(m.tile_cols);
      for (std::size_t ti = 0; ti < m.tiles.size(); ++ti) {
        const TerrainTile& tile = m.tiles[ti];
        if (!seen(tile.box)) continue;
        const int k = levels[ti];
        const auto kk = static_cast<std::size_t>(k);
        ++timings.terrain_tiles[kk];
        if (k == 0) {
          for (std::size_t c = tile.chunk_begin; c < tile.chunk_end; ++c)
            if (seen(m.chunks[c])) add(m.chunks[c], m.chunks[c], 0);
        } else {
          add(tile.level[kk], tile.box, k);
        }
        // Skirts towards the neighbours (-x, +x, -y, +y) drawn at another level. After all the
        // surfaces: they lie under them but where the seam between two levels opens, and llvmpipe
        // skips the shading of blocks whose depth test fails.
        const std::size_t r = ti / tc, c = ti % tc;
        const bool has[4] = {r > 0, (r + 1) * tc<m.tiles.size(), c> 0, c + 1 < tc};
        const std::size_t nb[4] = {ti - tc, ti + tc, ti - 1, ti + 1};
        for (std::size_t side = 0; side < 4; ++side)
          if (has[side] && levels[nb[side]] != k) add(tile.skirt[kk][side], tile.box, kLodLevels + k);
      }
    }
    for (std::size_t b = 0; b < bins.size() * 4; ++b) {
      const std::size_t level = b / 4;
      const unsigned bits = b % 4;
      const auto& bin = bins[level][bits];
      if (bin.empty()) continue;
      Program& scene = scene_program(m, bits, f, stamp_s, &set_up);
      glUniform2f(scene["u_shadow_lift"], m.lift[level % kLodLevels], m.lamp_lift[level % kLodLevels]);
      set3(scene["u_albedo"], m.material.albedo);
      glUniform1f(scene["u_uv_scale"], static_cast<float>(m.material.uv_scale_m));
      const Look k = look(m);
      if (k.bump) glUniform1f(scene["u_relief"], m.relief_m);
      if (k.specular) {
        glUniform1f(scene["u_roughness"], m.roughness);
        glUniform1f(scene["u_metallic"], m.metallic);
      }
      if (k.sediment) glUniform1f(scene["u_sediment"], m.sediment_cover);
      glUniform1f(scene["u_seg"], static_cast<float>(m.seg_class));
      if (k.bump) {
        glActiveTexture(GL_TEXTURE1);
        glBindTexture(GL_TEXTURE_2D, m.gradient);
      }
      if (k.normal_map) {
        glActiveTexture(GL_TEXTURE2);
        glBindTexture(GL_TEXTURE_2D, m.normal_map);
      }
      if (k.orm_map) {
        glActiveTexture(GL_TEXTURE3);
        glBindTexture(GL_TEXTURE_2D, m.orm_map);
      }
      glActiveTexture(GL_TEXTURE0);
      glBindTexture(GL_TEXTURE_2D, m.texture);
      if (m.macro) {  // the same texture at a larger scale, through mip_nearest
        glActiveTexture(GL_TEXTURE4);
        glBindTexture(GL_TEXTURE_2D, m.texture);
        glActiveTexture(GL_TEXTURE0);
      }
      glBindVertexArray(m.vao);
      cull_back_faces(m, vp);
      if (options.profile_passes) {
        glBeginQuery(GL_SAMPLES_PASSED, fragment_query);
        if (invocation_query) glBeginQuery(GL_FRAGMENT_SHADER_INVOCATIONS_ARB, invocation_query);
      }
      draw_chunks(bin);
      if (options.profile_passes) {  // fragments shaded (the depth test passed) with and without lookups
        glEndQuery(GL_SAMPLES_PASSED);
        GLuint n = 0, inv = 0;
        glGetQueryObjectuiv(fragment_query, GL_QUERY_RESULT, &n);
        if (invocation_query) {
          glEndQuery(GL_FRAGMENT_SHADER_INVOCATIONS_ARB);
          glGetQueryObjectuiv(invocation_query, GL_QUERY_RESULT, &inv);
        }
        timings.scene_invocations += inv;
        timings.scene_fragments += n;
        if (bits & 1u) timings.sun_lookup_fragments += n;
        if (bits & 2u) timings.lamp_lookup_fragments += n;
      }
    }
  }
  glDisable(GL_CULL_FACE);
  glBindSampler(1, 0);
  glBindSampler(4, 0);
}

}  // namespace unav::renderer
